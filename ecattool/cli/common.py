"""Helpers shared by the CLI command modules: options, JSON output, rich rendering, number parsing."""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

import click

from ecattool.errors import InputError
from ecattool.record import Record

if TYPE_CHECKING:
    from rich.console import Console
    from rich.table import Table

#: a click command function (or command) that an option decorator returns as it came, with the option added
Decorated = TypeVar("Decorated", bound=Callable[..., object])


def json_option(f: Decorated) -> Decorated:
    return click.option("--json", "as_json", is_flag=True, help="Print machine-readable JSON instead of tables.")(f)


#: revision selection policies of an ESI device selector (``ecattool.esi.select``)
POLICIES = ("exact", "newest-not-newer", "newest")


def policy_option(f: Decorated) -> Decorated:
    """``--policy``: how an ESI device selector picks a revision when several devices match it."""
    return click.option("--policy", type=click.Choice(POLICIES), default="exact", show_default=True,
                        help="How the device selector picks a revision when several match: exact, "
                             "newest-not-newer (the newest not newer than the one named) or newest.")(f)


#: where the shared ``--force`` flag leaves its value for :func:`write_output` (click's per-invocation meta)
_FORCE_KEY = "ecattool.force"

FORCE_HELP = "Overwrite an existing output file (never an input)."


def store_force(ctx: click.Context, param: click.Parameter, value: bool) -> bool:
    """The callback of every ``--force`` that allows overwriting an existing output (also a command's own
    ``--force`` with a wider meaning, such as ``map sdo``'s)."""
    if value:
        ctx.meta[_FORCE_KEY] = True
    return value


def force_requested() -> bool:
    """Whether this invocation was given ``--force`` (an existing output file may be replaced)."""
    ctx = click.get_current_context(silent=True)
    return bool(ctx is not None and ctx.meta.get(_FORCE_KEY))


def _with_force(f: Decorated) -> Decorated:
    """Add the shared ``--force`` to a command that writes files, once (a command with ``-o`` and ``--html`` gets
    one flag for both)."""
    params = getattr(f, "__click_params__", [])
    if any("--force" in getattr(p, "opts", ()) for p in params):
        return f
    return click.option("--force", is_flag=True, expose_value=False, callback=store_force, help=FORCE_HELP)(f)


def _output_path(ctx: click.Context, param: click.Parameter, value: str | None) -> str | None:
    if value == "":
        raise click.BadParameter("the file name is empty (use '-' for standard output)")
    return value


def output_option(required: bool = False, help: str = "Write to FILE (atomically; never over an input; an existing "
                  "file only with --force). '-' = stdout.", force: bool = True) -> Callable[[Decorated], Decorated]:
    """``-o/--output FILE`` plus the shared ``--force`` (unless ``force=False``: the command has its own flag that
    calls :func:`store_force`)."""
    option = click.option("-o", "--output", "output", type=click.Path(dir_okay=False, allow_dash=True),
                          required=required, callback=_output_path, help=help)

    def decorate(f: Decorated) -> Decorated:
        f = option(f)
        return _with_force(f) if force else f

    return decorate


def file_output_option(flag: str, name: str, help: str) -> Callable[[Decorated], Decorated]:
    """An option naming a file to write besides the main output (``--svg``, ``--report``, ``--html``): written
    atomically, never over an input, an existing file only with ``--force``, like ``-o``; '-' is stdout."""
    option = click.option(flag, name, type=click.Path(dir_okay=False, allow_dash=True), metavar="FILE",
                          callback=_output_path, help=help)

    def decorate(f: Decorated) -> Decorated:
        return _with_force(option(f))

    return decorate


def _plain(v: Any) -> Any:
    """``dataclasses.asdict`` for JSON, for trees that mix dataclasses and records: both become dicts of their
    fields, nested ones too (a record's ``to_json`` is used only where the encoder meets it, as before)."""
    if isinstance(v, Record):
        return {n: _plain(getattr(v, n)) for n in v._fields}
    if hasattr(v, "__dataclass_fields__") and not isinstance(v, type):
        import dataclasses

        return {f.name: _plain(getattr(v, f.name)) for f in dataclasses.fields(v)}
    if isinstance(v, (list, tuple)):
        return [_plain(x) for x in v]
    if isinstance(v, dict):
        return {k: _plain(x) for k, x in v.items()}
    return v


def _default(o: Any) -> Any:
    if isinstance(o, (bytes, bytearray)):
        return o.hex()
    if isinstance(o, Path):
        return str(o)
    if hasattr(o, "to_json"):
        return o.to_json()
    if hasattr(o, "model_dump"):
        return o.model_dump(mode="json")
    if isinstance(o, Record) or hasattr(o, "__dataclass_fields__"):
        return _plain(o)
    if hasattr(o, "value"):
        return o.value
    if hasattr(o, "numerator") and hasattr(o, "denominator"):
        return f"{o.numerator}/{o.denominator}"
    return str(o)


def dump_json(data: Any) -> str:
    import json  # on first use: most commands print no JSON (json costs ~2 ms to import)

    return json.dumps(data, indent=2, default=_default, ensure_ascii=False)


def print_json(data: Any) -> None:
    click.echo(dump_json(data))


def console(stderr: bool = False) -> Console:
    """A rich console; plain (no colour, no decoration) when not writing to a terminal."""
    from rich.console import Console

    stream = sys.stderr if stderr else sys.stdout
    is_tty = stream.isatty()
    return Console(file=stream, highlight=False, color_system="auto" if is_tty else None, soft_wrap=not is_tty,
                   width=None if is_tty else 200)


#: columns that hold identifiers a person types back (``--device 0x00030924``, an object address, a value): never
#: cut or broken on a narrow terminal; the other columns wrap (or fold) to make room
IDENTIFIER_COLUMNS = frozenset({
    "#", "type", "product", "productcode", "product code", "revision", "vendor", "index", "sub", "object", "address",
    "offset", "PDO", "hex", "value", "start", "end", "SM", "tr", "transition", "data", "default", "profile",
})


#: below this terminal width a table leaves out the columns its command marks as optional
NARROW = 120


def table(title: str | None, columns: list[str], optional: tuple[str, ...] = ()) -> Table:
    """A rich table. At any width (80 columns too) identifier columns stay whole and the others wrap; on a
    terminal narrower than :data:`NARROW` the ``optional`` columns are left out (rows are given in full)."""
    from rich import box
    from rich.console import RenderableType
    from rich.table import Table

    narrow = sys.stdout.isatty() and console().width < NARROW
    keep = [i for i, c in enumerate(columns) if not (narrow and c in optional)]

    class _Table(Table):
        def add_row(self, *cells: RenderableType | None, **kwargs: Any) -> None:
            super().add_row(*(cells[i] for i in keep if i < len(cells)), **kwargs)

    t = _Table(title=title, box=box.SIMPLE_HEAD if sys.stdout.isatty() else box.ASCII2, title_justify="left")
    for i in keep:
        t.add_column(columns[i], no_wrap=columns[i] in IDENTIFIER_COLUMNS, overflow="fold")
    return t


def write_output(output: str | None, data: bytes | str, inputs: tuple[str, ...] | list[str] = ()) -> None:
    """Write to ``-o FILE`` (see :func:`ecattool.fileio.write_atomic`: atomically, through devices and FIFOs,
    never over an input, over an existing file only with ``--force``), or to stdout when output is None or '-'."""
    if output in (None, "-"):
        if isinstance(data, bytes):
            sys.stdout.buffer.write(data)
            sys.stdout.buffer.flush()
        else:
            click.echo(data, nl=not data.endswith("\n"))
        return
    from ecattool.fileio import write_atomic

    write_atomic(output, data, inputs, overwrite=force_requested())


def check_output(output: str | None, inputs: tuple[str, ...] | list[str] = ()) -> None:
    """Refuse an output :func:`write_output` would refuse, before long work (commission, sim runs)."""
    if output in (None, "-"):
        return
    from ecattool.fileio import check_output as check

    check(output, inputs, overwrite=force_requested())


def parse_int_arg(text: str, what: str = "number") -> int:
    from ecattool.od.numbers import parse_int

    try:
        return parse_int(text, what=what)
    except InputError as exc:
        raise click.BadParameter(exc.message) from None


def hex32(v: int | None) -> str:
    return "" if v is None else f"0x{v:08X}"
