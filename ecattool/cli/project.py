"""ecattool project: the project file's JSON Schema and a skeleton for new projects."""

from __future__ import annotations

from pathlib import Path

import click

from ecattool.cli.common import dump_json, output_option, policy_option, write_output
from ecattool.cli.online import open_live, reset_bus_option
from ecattool.cli.paths import InputFile
from ecattool.cli.vocab import shared_option


@click.group("project", epilog="""\b
Examples:
  ecattool project new --profile technosoft-ipos -o machine.yaml
  ecattool project schema -o schemas/project.schema.json""")
def project() -> None:
    """Project files: JSON Schema for editors, new project skeletons."""


@project.command(
    "schema",
    epilog="""\b
Examples:
  ecattool project schema -o schemas/project.schema.json --force   # regenerate
  ecattool project schema --check schemas/project.schema.json   # CI drift check""",
)
@output_option()
@click.option("--check", "check", type=InputFile(),
              help="Compare with a checked-in schema file; exit 1 if it differs.")
def schema(output: str | None, check: str | None) -> None:
    """Print the JSON Schema of the project file (for editor completion and validation)."""
    from ecattool.project.model import json_schema

    text = dump_json(json_schema()) + "\n"
    if check:
        from ecattool.fileio import read_bytes

        if read_bytes(check) != text.encode("utf-8"):  # bytes: a file that is not even UTF-8 is simply out of date
            click.echo(f"ecattool: error: {check}: out of date; regenerate with "
                       f"'ecattool project schema -o {check} --force'", err=True)
            raise SystemExit(1)
        click.echo(f"{check}: up to date")
        return
    write_output(output, text)


@project.command(
    "new",
    epilog="""\b
Examples:
  ecattool project new --profile technosoft-ipos -o machine.yaml
  ecattool project new --esi drives/elmo.xml --device 0x00030924:1 -o machine.yaml
  ecattool project new --esi beckhoff_EL1xxx.xml --device EL1008 --policy newest -o io.ecattool.yaml
  ecattool project new --from-bus pysoem:eth0 --library esi/ -o machine.yaml""",
)
@click.option("--profile", help="Built-in drive family (technosoft-ipos, hdt, controltechniques).")
@click.option("--product", help="Product of the family.")
@click.option("--esi", "esi_path", help="ESI file of the drive (relative to where the project will be).")
@shared_option("--device", "select", metavar="SEL", help="Device in the ESI (type name, product[:revision] or list index).")
@policy_option
@click.option("--name", default=None, help="Name of the first drive (default: axis1, or io1 for an I/O slave).")
@click.option("--from-bus", "from_bus", metavar="TARGET",
              help="Every slave of a live bus (pysoem:IF, kickcat:IF, sim:PROFILE,…): devices, PDO mappings and the "
                   "current values of the usual objects, as read from the drives.")
@click.option("--library", type=click.Path(file_okay=False), metavar="DIR",
              help="With --from-bus: a folder of ESI/EDS files to match the slaves against.")
@output_option()
@reset_bus_option
def new(profile: str | None, product: str | None, esi_path: str | None, select: str | None, policy: str,
        name: str | None, from_bus: str | None, library: str | None, output: str | None) -> None:
    """Write a minimal project file for one drive that lints clean (a vendor ESI's own flaws aside, which it
    points out with a commented-out disable_rules): the device is resolved first (unknown
    profile, product, ESI or selector: exit 1), and the PP move is only proposed where the drive has mode 1."""
    if from_bus is not None:
        if profile is not None or esi_path is not None:
            raise click.UsageError("give --from-bus, or --profile/--esi, not both")
        _new_from_bus(from_bus, library, output)
        return
    if (profile is None) == (esi_path is None):
        raise click.UsageError("give --profile or --esi (or --from-bus)")

    from ecattool.project.skeleton import esi_flaws, new_project, resolve

    base = Path(output).parent if output not in (None, "-") else Path(".")
    if profile is not None and policy != "exact":
        raise click.UsageError("--policy selects among the revisions of an ESI device: give it with --esi")
    device = resolve(profile, product, esi_path, select, base, policy)
    findings = esi_flaws(esi_path, select, base, policy) if esi_path is not None else []
    write_output(output, new_project(device, name=name, profile=profile, product=product, esi=esi_path,
                                     select=select, policy=policy, findings=findings),
                 (str(base / esi_path),) if esi_path is not None else ())


def _new_from_bus(target: str, library: str | None, output: str | None) -> None:
    """``project new --from-bus``: the project of every slave of the live bus, and a warning per slave that did
    not answer (the project holds the others)."""
    from ecattool.online.from_bus import project_from_bus
    from ecattool.online.library import Library

    problems: list[str] = []
    with open_live(target, read_sii=True) as live:  # KickCAT gives no SII: read it through the ESCs
        text = project_from_bus(live, Library(library) if library else None, output, problems=problems)
    write_output(output, text)
    for p in problems:
        click.echo(f"ecattool: warning: {p}", err=True)
