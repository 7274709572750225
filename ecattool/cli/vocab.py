"""One vocabulary across the CLI: the options every command spells the same way (docs/cli.md, "Shared options").

An option renamed for that keeps its old spelling as a hidden alias: still accepted, never shown in ``--help``
or in error messages. ``tests/test_cli_vocabulary.py`` walks every command against the table in docs/cli.md.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import click

from ecattool.cli.common import Decorated

#: the startup formats ecattool writes (``--format`` of map sdo, scale startup; lcec is read only)
WRITE_FORMATS = ("eni", "twincat", "igh", "pysoem", "ros2", "ecmc", "json", "csv")

#: canonical option -> the old spellings it still accepts (hidden)
ALIASES: dict[str, tuple[str, ...]] = {
    "--device": ("--select",),
    "--profile": ("--family",),
    "--counts-per-rev": ("--counts",),
}


class AliasedOption(click.Option):
    """A click option whose old spellings (``aliases``) parse but are left out of the help and error hints."""

    def __init__(self, param_decls: list[str], aliases: tuple[str, ...] = (), **kwargs: Any) -> None:
        super().__init__(param_decls, **kwargs)
        self.aliases = aliases

    def _shown(self) -> list[str]:
        return [o for o in self.opts if o not in self.aliases]

    def get_help_record(self, ctx: click.Context) -> tuple[str, str] | None:
        opts = self.opts
        self.opts = self._shown()
        try:
            return super().get_help_record(ctx)
        finally:
            self.opts = opts

    def get_error_hint(self, ctx: click.Context | None) -> str:
        return " / ".join(f"'{o}'" for o in self._shown())


def shared_option(canonical: str, dest: str, **kwargs: Any) -> Callable[[Decorated], Decorated]:
    """``click.option(canonical, *old spellings, dest)`` with the old spellings hidden."""
    aliases = ALIASES.get(canonical, ())
    return click.option(canonical, *aliases, dest, cls=AliasedOption, aliases=aliases, **kwargs)


def device_option(help: str = "Device in the ESI (type name, product[:revision] or list index) when it has "
                  "several.") -> Callable[[Decorated], Decorated]:
    """``--device SEL``: which device of an ESI file (old spelling ``--select``)."""
    return shared_option("--device", "selector", metavar="SEL", help=help)
