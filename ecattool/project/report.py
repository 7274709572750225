"""Rendering lint findings: JSON, SARIF 2.1.0 (code-scanning dashboards) and GitHub annotations.

(The rich text rendering is done by the CLI; these formats are library functions so that CI tools and
master software can produce them too.)
"""

from __future__ import annotations

import os
from typing import Any

from ecattool import __version__
from ecattool.findings import Finding, Severity

_SARIF_LEVEL = {Severity.ERROR: "error", Severity.WARNING: "warning", Severity.INFO: "note"}


def to_json(findings: list[Finding], files: list[str]) -> dict[str, Any]:
    counts = {s.value: sum(1 for f in findings if f.severity is s) for s in Severity}
    return {"files": files, "summary": counts, "findings": [f.to_json() for f in findings]}


def _uri(path: str | None) -> str:
    if not path:
        return ""
    try:
        rel = os.path.relpath(path)
    except ValueError:
        rel = path
    return rel.replace(os.sep, "/")


def to_sarif(findings: list[Finding], rule_help: dict[str, str] | None = None) -> dict[str, Any]:
    """A SARIF 2.1.0 log with one run; rules are the rule ids that occur."""
    rule_ids = sorted({f.rule for f in findings})
    rules = [
        {
            "id": rid,
            "shortDescription": {"text": (rule_help or {}).get(rid, rid)},
        }
        for rid in rule_ids
    ]
    results = []
    for f in findings:
        result: dict[str, Any] = {
            "ruleId": f.rule,
            "ruleIndex": rule_ids.index(f.rule),
            "level": _SARIF_LEVEL[f.severity],
            "message": {"text": f.message},
        }
        if f.location and f.location.file:
            region: dict[str, int] = {}
            if f.location.line:
                region["startLine"] = f.location.line
                if f.location.column:
                    region["startColumn"] = f.location.column
            phys: dict[str, Any] = {"artifactLocation": {"uri": _uri(f.location.file)}}
            if region:
                phys["region"] = region
            result["locations"] = [{"physicalLocation": phys}]
        results.append(result)
    return {
        "$schema": "https://json.schemastore.org/sarif-2.1.0.json",
        "version": "2.1.0",
        "runs": [
            {
                "tool": {"driver": {"name": "ecattool", "version": __version__, "rules": rules}},
                "results": results,
            }
        ],
    }


def _gh_escape(text: str, prop: bool = False) -> str:
    text = text.replace("%", "%25").replace("\r", "%0D").replace("\n", "%0A")
    if prop:
        text = text.replace(":", "%3A").replace(",", "%2C")
    return text


def to_github(findings: list[Finding]) -> str:
    """GitHub Actions workflow commands (``::error file=…,line=…::message``), one per finding."""
    lines = []
    for f in findings:
        kind = {Severity.ERROR: "error", Severity.WARNING: "warning", Severity.INFO: "notice"}[f.severity]
        props = [f"title={_gh_escape(f.rule, True)}"]
        if f.location and f.location.file:
            props.insert(0, f"file={_gh_escape(_uri(f.location.file), True)}")
            if f.location.line:
                props.insert(1, f"line={f.location.line}")
                if f.location.column:
                    props.insert(2, f"col={f.location.column}")
        lines.append(f"::{kind} {','.join(props)}::{_gh_escape(f.message)}")
    return "\n".join(lines) + ("\n" if lines else "")
