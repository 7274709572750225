"""Issue 24: the built-in profiles against the manuals' own object tables.

The tables are read from the seed texts themselves (tests/manual_tables.py; the digests in
../shared/reference/<family>/objects.csv are not used here) and compared, entry by entry, with the generated data
files: data type, access, PDO mapping, default value and value range (kind included: interval, single value,
value list). Every difference must be named in :data:`EXPLAINED` with the decision of docs/decisions.md that
makes it; the test prints the counts per family and fails on any other difference (and on an explanation that
no longer matches a difference, so the list cannot rot).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from ecattool.profiles._build_data import clean_spec, fit_default, norm_type, parse_default, parse_range_spec
from ecattool.profiles._common import load_data
from manual_tables import Row, controltechniques, hdt, technosoft

DECISIONS = Path(__file__).resolve().parents[1] / "docs" / "decisions.md"

READERS = {"technosoft": technosoft, "hdt": hdt, "controltechniques": controltechniques}

#: (family, index, sub, field) -> the decision (docs/decisions.md) that departs from the printed cell
EXPLAINED: dict[tuple[str, int, int, str], str] = {}


def _explain(family: str, decision: str, *keys: tuple[int, int, str]) -> None:
    for index, sub, field in keys:
        EXPLAINED[(family, index, sub, field)] = decision


# --- Technosoft --------------------------------------------------------------------------------------------
_explain("technosoft", "TS-2", (0x1C00, 4, "default"))
_explain("technosoft", "TS-3", (0x1C12, 0, "access"), (0x1C13, 0, "access"))
_explain("technosoft", "TS-6", (0x2001, 0, "access"))
_explain("technosoft", "TS-7", (0x20A0, 0, "pdo"))
_explain("technosoft", "TS-1", (0x1018, 0, "default"))
_explain("technosoft", "607Eh max 255 (54)", (0x607E, 0, "range"))
_explain("technosoft", "Printed ranges that contradict the\n  type are dropped", (0x2012, 0, "range"))


_explain("technosoft", "TS-7", (0x2108, 3, "range"))

# --- HDT ---------------------------------------------------------------------------------------------------
_explain("hdt", "HDT-9", (0x2024, 0, "absent"), (0x2088, 0, "range"), (0x2415, 0, "type"), (0x2416, 0, "type"),
         (0x2417, 0, "type"))
_explain("hdt", "Profiles-2", (0x605A, 0, "range"))

# --- Control Techniques ------------------------------------------------------------------------------------
_explain("controltechniques", "CT-2", (0x1605, 2, "default"))
_explain("controltechniques", "CT-3", (0x1615, 0, "range"), (0x1A15, 0, "range"), (0x1C12, 0, "range"),
         (0x1C13, 0, "range"))
_explain("controltechniques", "CT-4", (0x6041, 0, "access"), (0x6099, 0, "type"))
_explain("controltechniques", "Profiles-2", (0x605A, 0, "range"))


def _profile(family: str) -> dict[tuple[int, int], dict[str, Any]]:
    data = load_data(family if family != "technosoft" else "technosoft")
    return {(o["index"], e["sub"]): e for o in data["objects"] for e in o["entries"]}


def _cells(row: Row, typ: str, bits: int) -> dict[str, Any]:
    """The comparable cells of one printed row, in the profile's terms (a cell the row does not give: absent)."""
    out: dict[str, Any] = {}
    nt = norm_type(row.type) if row.type else None
    if nt is not None:
        out["type"] = nt[0]
    if row.access:
        out["access"] = {"w": "wo"}.get(row.access, row.access)
    if row.pdo:
        out["pdo"] = row.pdo.strip().lower().startswith(("yes", "possible"))
    if typ != "STRING":
        default = parse_default(row.default)
        if default is not None:
            out["default"] = fit_default(typ, bits, default)
        spec = parse_range_spec(row.range)
        if spec.kind != "none":
            out["range"] = clean_spec(typ, bits, spec)
    return out


def _differences(family: str) -> tuple[list[tuple[int, int, str, Row, Any, Any]], dict[str, int]]:
    """Entry by entry and cell by cell: a cell differs when no printing of the entry gives the profile's value."""
    manual = READERS[family]()
    profile = _profile(family)
    diffs: list[tuple[int, int, str, Row, Any, Any]] = []
    counts = {"entries": len(manual), "compared": 0, "cells": 0, "absent": 0}
    for (index, sub), rows in sorted(manual.items()):
        p = profile.get((index, sub))
        if p is None:
            counts["absent"] += 1
            diffs.append((index, sub, "absent", rows[0], "", None))
            continue
        counts["compared"] += 1
        ours = {"type": p["type"], "access": p["access"], "pdo": bool(p.get("pdo")), "default": p.get("default"),
                "range": (p.get("min"), p.get("max"), p.get("values"))}
        printed = [(row, _cells(row, p["type"], p["bits"])) for row in rows]
        for field, value in ours.items():
            given = [(row, cells[field]) for row, cells in printed if field in cells]
            if not given:
                continue
            counts["cells"] += 1
            if all(v != value for _, v in given):
                row, v = given[0]
                diffs.append((index, sub, field, row, v, value))
    return diffs, counts


@pytest.mark.parametrize("family", sorted(READERS))
def test_profiles_agree_with_the_manuals_tables(family, capsys):
    diffs, counts = _differences(family)
    unexplained = [d for d in diffs if (family, d[0], d[1], d[2]) not in EXPLAINED]
    found = {(family, d[0], d[1], d[2]) for d in diffs}
    stale = [k for k in EXPLAINED if k[0] == family and k not in found]
    with capsys.disabled():
        print(f"\n{family}: {counts['entries']} entries read from the manual, {counts['compared']} in the profile "
              f"({counts['cells']} cells compared), {len(diffs)} differences, "
              f"{len(diffs) - len(unexplained)} explained by decisions")
    text = DECISIONS.read_text(encoding="utf-8")
    for key in EXPLAINED:
        if key[0] == family:
            assert EXPLAINED[key] in text, f"{key}: decision {EXPLAINED[key]!r} is not in docs/decisions.md"
    lines = [f"0x{i:04X}:{s:02X} {field}: manual line {row.line} prints {m!r}, profile has {p!r}"
             for i, s, field, row, m, p in unexplained]
    assert not unexplained, f"{len(lines)} unexplained differences:\n" + "\n".join(lines)
    assert not stale, f"explanations without a difference: {stale}"
