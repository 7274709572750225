"""``ecattool audit``: compare what the drives hold with the project."""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING

import click

from ecattool.cli.common import dump_json, file_output_option, output_option, write_output
from ecattool.cli.online import allow_errors_option, project_bus, project_machine, target_option
from ecattool.cli.paths import InputFile

if TYPE_CHECKING:
    from ecattool.online.audit import AuditReport


@click.command(epilog="""\b
Examples:
  ecattool audit machine.yaml --target pysoem:eth0
  ecattool audit machine.yaml --target pysoem:eth0 --format sarif -o audit.sarif
  ecattool audit machine.yaml --target sim --json --html audit.html
  ecattool audit machine.yaml --target pysoem:eth0 --allow-errors   # a project lint reports errors for
  ecattool audit machine.yaml --target pysoem:eth0 --reset-bus   # a running bus, put back in SAFE-OP/OP after""")
@click.argument("project", type=InputFile())
@target_option()
@click.option("--format", "fmt", type=click.Choice(["text", "json", "sarif"]), default="text", show_default=True,
              help="Report format.")
@click.option("--json", "as_json", is_flag=True, help="Same as --format json.")
@click.option("--sw-checksums", is_flag=True,
              help="Also have each Technosoft drive checksum its .sw blocks (writes the request object 2069h; "
                   "without this flag the audit never writes).")
@allow_errors_option
@output_option()
@file_output_option("--html", "html", "Also write the drift report as an HTML page (the report extra).")
def audit(project: str, target: str, fmt: str, as_json: bool, sw_checksums: bool, allow_errors: bool,
          output: str | None, html: str | None) -> None:
    """Read back every object the project's startup list would write, and each drive's identity, and report
    where the drives differ from the project (drift). Reads only. Exit status 1 on drift."""
    from ecattool.online.audit import audit as do_audit

    machine = project_machine(project, "audit", allow_errors)
    with project_bus(machine, target) as live:
        report = do_audit(machine, live, sw_checksums=sw_checksums, allow_errors=allow_errors)
    text = _audit_text(report, "json" if as_json else fmt, f"{project} on {target}")
    write_output(output, text, (project,))
    if html is not None:
        from ecattool.report.audit import audit_html

        write_output(html, audit_html(report), (project,))
    if not report.ok:
        sys.exit(1)


def _audit_text(report: AuditReport, fmt: str, title: str) -> str:
    """The report as JSON, SARIF or text (the drifts, then the process-data objects left uncompared)."""
    if fmt == "json":
        return dump_json(report.to_json()) + "\n"
    if fmt == "sarif":
        from ecattool.project.report import to_sarif

        return dump_json(to_sarif(report.findings())) + "\n"
    lines = [f"{title}: {report.checked} values checked, "
             + ("no drift" if report.ok else f"{len(report.drifts)} drifted")]
    lines += [f"  {d.drive} (slave {d.position}) {d.address}: {d.message}" for d in report.drifts]
    if report.process_data:
        lines.append("process data (objects in the RxPDOs: the master writes them every cycle, not compared):")
        lines += [f"  {p['drive']} (slave {p['position']}) {p['address']}: the project sets {p['project']!r}, "
                  f"read {p['read']!r}" for p in report.process_data]
    return "\n".join(lines) + "\n"
