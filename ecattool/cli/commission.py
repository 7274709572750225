"""ecattool commission: the main job."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import click

from ecattool.cli.common import (
    check_output,
    console,
    dump_json,
    file_output_option,
    output_option,
    write_output,
)
from ecattool.cli.online import reset_bus_given, reset_bus_option
from ecattool.cli.paths import InputFile

if TYPE_CHECKING:
    from rich.console import Console

    from ecattool.commission.runner import CommissionReport, DriveReport


@click.command(
    "commission",
    epilog="""\b
Examples:
  ecattool commission samples/technosoft_ipos/project.yaml          # on the embedded simulator
  ecattool commission --json machine.yaml > report.json
  ecattool commission --target pysoem:eth0 machine.yaml             # a real bus (pip install 'ecattool[pysoem]')
  ecattool commission samples/hdt/project.yaml --report report.html  # + an HTML report (pip install 'ecattool[report]')
\b
Exit codes: 0 every drive commissioned, 1 a drive failed or the project is invalid, 2 usage error.""",
)
@click.argument("projects", nargs=-1, required=True, type=InputFile())
@click.option("--target", default=None, help="'sim' (default: the project's target) or 'pysoem:<interface>'.")
@reset_bus_option
@click.option("--json", "as_json", is_flag=True, help="Print the report as JSON.")
@click.option("--allow-errors", is_flag=True, help="Commission drives even when lint reports errors for them (by "
              "default such a drive is not touched and its report names the first error).")
@output_option(help="Also write the JSON report to FILE.")
@file_output_option("--report", "report", help="Also write a self-contained HTML report to FILE: per drive the result, "
                    "the process image, the startup list as sent and read back, the .sw blocks, the state timeline "
                    "and plots of the move, and the lint findings (docs/report.md). Needs "
                    "pip install 'ecattool[report]'.")
def commission(projects: tuple[str, ...], target: str | None, as_json: bool, allow_errors: bool,
               output: str | None, report: str | None) -> None:
    """Commission the drives and I/O slaves of project files.

    For each slave: INIT -> PRE-OP, identity check, .sw verify/download, the startup list with every write
    read back, SAFE-OP, OP. A CiA-402 axis is then enabled through the state machine and makes a short move in
    user units checked in internal units; an I/O slave exchanges one cycle of process data (outputs written,
    inputs read). A failing slave is stopped safely and the failing command and abort code are named.
    """
    from ecattool.commission import commission as run

    _report_prerequisites(report, as_json or output == "-")
    inputs = _checked_outputs(projects, output, report)
    con = None if as_json or report == "-" else console()
    reports = [run(path, target=target, on_drive=_drive_printer(con, path), allow_errors=allow_errors,
                   reset_bus=reset_bus_given()) for path in projects]
    data = {"ok": all(r.ok for r in reports), "projects": [r.to_json() for r in reports]}
    if as_json:
        click.echo(dump_json(data))
    elif con is not None:
        _render_summary(con, reports)
    if output:
        write_output(output, dump_json(data) + "\n", inputs)
    if report:
        from ecattool.report import commission_html

        write_output(report, commission_html(reports), inputs)
    raise SystemExit(0 if data["ok"] else 1)


def _report_prerequisites(report: str | None, json_to_stdout: bool) -> None:
    """Before any drive is touched: the report extra is there, and the page and the JSON do not both go to stdout."""
    if report:
        from ecattool.report import require

        require()  # a missing extra is one line before any drive is touched
        if report == "-" and json_to_stdout:
            raise click.UsageError("--report - and the JSON report cannot both go to stdout")


def _checked_outputs(projects: tuple[str, ...], *outputs: str | None) -> list[str]:
    """The projects and the ESI/.sw files they name, where an output goes to a file: each output is refused
    before the drives are touched, not after, when it would replace one of them."""
    inputs: list[str] = []
    for out in outputs:
        if out not in (None, "-"):
            from ecattool.project.loader import project_inputs

            inputs = inputs or project_inputs(projects)
            check_output(out, inputs)
    return inputs


def _drive_printer(con: Console | None, path: str) -> Callable[[DriveReport], None]:
    """What is printed as each drive of ``path`` is done: OK or FAILED, and its steps (nothing without ``con``)."""
    def show(dr: DriveReport) -> None:
        if con is None:
            return
        mark = "[green]OK[/green]" if dr.ok else "[red]FAILED[/red]"
        con.print(f"{path}: drive {dr.name!s} (position {dr.position}): {mark}")
        for s in dr.steps:
            con.print(f"    {'ok ' if s.ok else 'ERR'} {s.name}: {s.detail}", markup=False,
                      style=None if s.ok else "red")

    return show


def _render_summary(con: Console, reports: list[CommissionReport]) -> None:
    n = sum(len(r.drives) for r in reports)
    bad = sum(1 for r in reports for d in r.drives if not d.ok)
    con.print(f"{n - bad} of {n} drive(s) commissioned" + (f", {bad} failed" if bad else ""),
              style="green" if not bad else "red")
