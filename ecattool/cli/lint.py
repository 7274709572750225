"""ecattool lint: run every check over project files (for CI)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import click

from ecattool.cli.common import console, dump_json, output_option, write_output
from ecattool.cli.paths import InputFile

if TYPE_CHECKING:
    from ecattool.project.machine import Machine


@click.command(
    "lint",
    epilog="""\b
Examples:
  ecattool lint samples/*/project.yaml
  ecattool lint --format sarif -o ecattool.sarif machine.yaml
  ecattool lint --format github --strict machine.yaml   # annotations in a GitHub Actions log
\b
Exit codes: 0 no errors (no warnings either with --strict), 1 findings or invalid input, 2 usage error.""",
)
@click.argument("projects", nargs=-1, required=True, type=InputFile())
@click.option("--format", "fmt", type=click.Choice(["text", "json", "sarif", "github"]), default="text",
              show_default=True, help="Output format.")
@click.option("--json", "as_json", is_flag=True, help="Same as --format json.")
@click.option("--strict", is_flag=True, help="Warnings fail the lint too.")
@output_option()
def lint(projects: tuple[str, ...], fmt: str, as_json: bool, strict: bool, output: str | None) -> None:
    """Lint ecattool project files: schema, ESI, PDO mapping, scaling, parameters, .sw images, identity.

    Every finding has a rule id and names the file, line and column at fault. Rules can be disabled per
    project or per drive with `disable_rules: [{rule: PDO011, reason: "…"}]`.
    """
    from ecattool.project.lint import lint as run_lint

    results, failed = run_lint(list(projects), strict=strict)
    inputs = projects
    if output not in (None, "-"):  # the report never replaces a project, nor an ESI/.sw one names
        from ecattool.project.loader import project_inputs

        inputs = tuple(project_inputs(projects))
    if as_json or fmt != "text":
        write_output(output, _report_text("json" if as_json else fmt, results, projects), inputs)
    else:
        _text(results, output, inputs)
    raise SystemExit(1 if failed else 0)


def _report_text(fmt: str, results: list[Machine], projects: tuple[str, ...]) -> str:
    """Every finding as a JSON, SARIF or GitHub-annotation report."""
    from ecattool.project import report

    findings = [f for r in results for f in r.findings]
    if fmt == "json":
        return dump_json(report.to_json(findings, list(projects))) + "\n"
    if fmt == "sarif":
        from ecattool.project.lint import rule_descriptions

        return dump_json(report.to_sarif(findings, rule_descriptions())) + "\n"
    return report.to_github(findings)


def _text(results: list[Machine], output: str | None, inputs: tuple[str, ...]) -> None:
    lines = []
    for r in results:
        for f in r.findings:
            lines.append(str(f))
        n_err = sum(1 for f in r.findings if f.severity.value == "error")
        n_warn = sum(1 for f in r.findings if f.severity.value == "warning")
        drives = len(r.slaves)
        lines.append(f"{r.path}: {drives} drive(s), {n_err} error(s), {n_warn} warning(s)")
    text = "\n".join(lines) + "\n"
    if output not in (None, "-"):
        write_output(output, text, inputs)
        return
    con = console()
    for line in lines:
        style = "red" if ": error:" in line else "yellow" if ": warning:" in line else None
        con.print(line, style=style, markup=False)
