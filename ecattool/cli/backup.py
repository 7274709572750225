"""``ecattool backup``: what the drives hold, into one folder."""

from __future__ import annotations

import click

from ecattool.cli.common import console
from ecattool.cli.online import allow_errors_option, project_bus, project_machine, target_option
from ecattool.cli.paths import InputFile


@click.command(epilog="""\b
Examples:
  ecattool backup machine.yaml --target pysoem:eth0 -o backup-2026-11-26
  ecattool backup machine.yaml --target sim -o /tmp/sim-backup
  ecattool backup machine.yaml --target pysoem:eth0 -o backup --allow-errors   # despite lint errors""")
@click.argument("project", type=InputFile())
@target_option()
@click.option("-o", "--output", "folder", required=True, type=click.Path(), metavar="DIR",
              help="A new folder (it appears complete or not at all); never an input, the project's folder or a "
              "folder holding them; an existing back-up only with --force.")
@click.option("--force", is_flag=True, help="Replace an existing back-up folder (one with an ecattool-backup.json "
              "manifest; after the new one is complete). Any other folder or file is never replaced.")
@allow_errors_option
def backup(project: str, target: str, folder: str, force: bool, allow_errors: bool) -> None:
    """Per drive of the project: its SII image, a snapshot of its dictionary and (Technosoft, where the project
    has a .sw) its EEPROM setup read back into a .sw, all in one new folder."""
    from ecattool.online.backup import backup as do_backup
    from ecattool.online.backup import check_folder

    machine = project_machine(project, "back up", allow_errors)
    check_folder(folder, machine, force)  # refused before the bus is opened
    with project_bus(machine, target) as live:
        report = do_backup(machine, live, folder, overwrite=force, allow_errors=allow_errors)
    c = console()
    c.print(f"{report.folder}: {len(report.files)} files")
    for f in report.files:
        c.print(f"  {f}")
    for s in report.skipped:
        c.print(f"  skipped: {s}")

