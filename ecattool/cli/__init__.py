"""The ``ecattool`` command line. Thin: parse arguments, call the library, render.

Subcommand groups live in their own modules and are imported only when used, so that
``ecattool --version`` stays close to the cost of starting Python.
"""

from __future__ import annotations

import importlib
import os
import sys
from typing import Any

import click

from ecattool import __version__
from ecattool.errors import EcatToolError

#: command name -> (module, attribute, one-line help)
COMMANDS: dict[str, tuple[str, str, str]] = {
    "esi": ("ecattool.cli.esi", "esi", "Read, show and validate ESI device description files."),
    "sim": ("ecattool.cli.sim", "sim", "Built-in drive profiles and the embedded drive simulator."),
    "map": ("ecattool.cli.map", "map_", "Check, lay out and program PDO mappings."),
    "scale": ("ecattool.cli.scale", "scale", "Compute CiA-402 factor groups from mechanics and units."),
    "sw": ("ecattool.cli.sw", "sw", "Technosoft .sw EEPROM setup images."),
    "sii": ("ecattool.cli.sii", "sii", "SII EEPROM images: inspect, check, build from ESI."),
    "startup": ("ecattool.cli.startup", "startup", "Export and import startup lists for EtherCAT masters."),
    "lint": ("ecattool.cli.lint", "lint", "Lint project files (for CI)."),
    "commission": ("ecattool.cli.commission", "commission", "Commission the drives of a project (simulator by default)."),
    "project": ("ecattool.cli.project", "project", "Project files: schema, new project skeletons."),
    "bus": ("ecattool.cli.bus", "bus", "Look at a live bus: scan the slaves (read only); hold it open for the other commands."),
    "sdo": ("ecattool.cli.sdo", "sdo", "Read and write a live slave's objects, typed by its dictionary."),
    "audit": ("ecattool.cli.audit", "audit", "Compare what the drives on a bus hold with a project (drift)."),
    "backup": ("ecattool.cli.backup", "backup", "Back up what the drives of a project hold (SII, dictionary, .sw)."),
}


class LazyGroup(click.Group):
    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted(COMMANDS)

    def get_command(self, ctx: click.Context, name: str) -> click.Command | None:
        spec = COMMANDS.get(name)
        if spec is None:
            return None
        module, attr, _ = spec
        try:
            command: click.Command = getattr(importlib.import_module(module), attr)
            return command
        except ModuleNotFoundError as exc:
            if exc.name == module:
                return None
            raise

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        rows = [(name, COMMANDS[name][2]) for name in self.list_commands(ctx)]
        with formatter.section("Commands"):
            formatter.write_dl(rows)


@click.group(
    cls=LazyGroup,
    context_settings={"help_option_names": ["-h", "--help"], "max_content_width": 110},
    epilog="""\b
Examples:
  ecattool esi devices beckhoff_EL1xxx.xml
  ecattool map check --profile technosoft-ipos --rx "0x6040:00/16,0x607A:00/32"
  ecattool commission samples/technosoft_ipos/project.yaml

Shell completion (bash): eval "$(_ECATTOOL_COMPLETE=bash_source ecattool)"
(zsh: zsh_source, fish: fish_source). See docs/cli.md.""",
)
@click.version_option(__version__, "-V", "--version", prog_name="ecattool")
@click.option("--debug", is_flag=True, envvar="ECATTOOL_DEBUG", help="Show Python tracebacks for errors.")
@click.pass_context
def cli(ctx: click.Context, debug: bool) -> None:
    """ecattool: commissioning toolchain for EtherCAT CoE servo drives.

    Reads ESI files, checks PDO mappings, computes CiA-402 factor groups, handles Technosoft .sw
    setup images and SII EEPROM images, writes startup lists for every master, lints projects in CI,
    and commissions drives against an embedded simulator or a real master.
    """
    ctx.ensure_object(dict)
    ctx.obj["debug"] = debug


def _command_of(argv: list[str]) -> click.Command:
    """The (sub)command ``argv`` runs, as far as its words name one."""
    command: click.Command = cli
    ctx = click.Context(cli)
    for word in argv:
        if not isinstance(command, click.Group):
            break
        sub = command.get_command(ctx, word) if not word.startswith("-") else None
        if sub is not None:
            command = sub
    return command


def _name_the_flag(message: str, argv: list[str]) -> str:
    """An error the library words for every caller ("choose one with a selector") names the option of the
    command that was run where that option would fix it."""
    if "with a selector" in message:
        opts = {o for p in _command_of(argv).params for o in getattr(p, "opts", ())}
        if "--device" in opts:
            return message.replace("with a selector", "with --device SEL")
    return message


def main(argv: list[str] | None = None) -> Any:
    """Entry point: run the CLI, turning ecattool errors into one-line messages and exit code 1."""
    debug = "--debug" in (argv if argv is not None else sys.argv[1:]) or bool(os.environ.get("ECATTOOL_DEBUG"))
    try:
        return cli.main(args=argv, prog_name="ecattool", standalone_mode=False)
    except click.exceptions.Exit as exc:
        sys.exit(exc.exit_code)
    except click.exceptions.Abort:
        click.echo("Aborted.", err=True)
        sys.exit(1)
    except click.ClickException as exc:
        exc.show()
        sys.exit(exc.exit_code)
    except EcatToolError as exc:
        if debug:
            raise
        text = " ".join(_name_the_flag(str(exc), argv if argv is not None else sys.argv[1:]).split())  # one line
        click.echo(f"ecattool: error: {text if len(text) <= 600 else text[:400] + ' … ' + text[-150:]}", err=True)
        sys.exit(1)
    except BrokenPipeError:
        sys.exit(0)
    except KeyboardInterrupt:
        click.echo("Interrupted.", err=True)
        sys.exit(130)
