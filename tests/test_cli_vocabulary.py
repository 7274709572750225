"""One vocabulary across the CLI: every command's --help against the table of shared options in docs/cli.md.

The table says which option carries which idea and which old spellings are still accepted (hidden). Here every
command of the CLI is walked: no --help shows an old spelling, every old spelling still parses, the shared
options are spelt as the table says, and the errors an option would fix name it.
"""

from __future__ import annotations

import re

import click
import pytest

from ecattool.cli import cli
from ecattool.cli.vocab import ALIASES, AliasedOption
from tests.conftest import ROOT, corpus_path, run


def _shared_table() -> list[tuple[list[str], list[str]]]:
    """(options, old spellings) per row of docs/cli.md "Shared options"."""
    text = (ROOT / "docs" / "cli.md").read_text(encoding="utf-8")
    section = text[text.index("## Shared options"):]
    section = section[:section.index("\n## ", 3)]
    rows = []
    for line in section.splitlines():
        cells = [c.strip() for c in re.split(r"(?<!\\)\|", line)[1:-1]]
        if len(cells) != 3 or cells[1] in ("option", "---"):
            continue
        options = re.findall(r"(?<![\w-])(--?[a-z][a-z-]*)", cells[1])
        aliases = re.findall(r"(--[a-z][a-z-]*)", cells[2])
        rows.append((options, aliases))
    return rows


TABLE = _shared_table()


def _commands() -> list[tuple[tuple[str, ...], click.Command]]:
    ctx = click.Context(cli)
    out: list[tuple[tuple[str, ...], click.Command]] = []

    def walk(cmd: click.Command, path: tuple[str, ...]) -> None:
        if isinstance(cmd, click.Group):
            for name in cmd.list_commands(ctx):
                sub = cmd.get_command(ctx, name)
                assert sub is not None, name
                walk(sub, (*path, name))
        else:
            out.append((path, cmd))

    walk(cli, ())
    return out


COMMANDS = _commands()


def test_the_table_is_read_and_matches_the_aliases_the_cli_keeps() -> None:
    assert len(TABLE) >= 10
    assert {a: tuple(als) for opts, als in TABLE for a in opts[:1] if als} == ALIASES


@pytest.mark.parametrize("path", [p for p, _ in COMMANDS], ids=" ".join)
def test_help_shows_only_the_shared_spelling(capsys: pytest.CaptureFixture[str], path: tuple[str, ...]) -> None:
    code, out, _ = run(capsys, *path, "--help")
    assert code == 0
    hidden = [a for als in ALIASES.values() for a in als]
    for alias in hidden:
        assert not re.search(rf"(?<![\w-]){re.escape(alias)}(?![\w-])", out), f"{' '.join(path)} --help shows {alias}"
    command = dict(COMMANDS)[path]
    for param in command.params:
        opts = set(getattr(param, "opts", ()))
        # an old spelling parses, hidden, beside the shared one
        for canonical, als in ALIASES.items():
            if opts & set(als):
                assert isinstance(param, AliasedOption) and canonical in opts, (path, param.name)
        if "--output" in opts:
            assert "-o" in opts, f"{' '.join(path)}: --output without -o"
        if isinstance(param, click.Argument):
            assert param.name != "target", f"{' '.join(path)}: a positional TARGET (a --target is sim|pysoem:IF)"
        if "--target" in opts:
            assert "sim" in (param.help or "") and "pysoem" in (param.help or ""), path


def test_every_option_of_the_table_is_used() -> None:
    used = {o for _, cmd in COMMANDS for p in cmd.params for o in getattr(p, "opts", ())}
    for options, _ in TABLE:
        assert set(options) <= used, options


@pytest.mark.parametrize("argv", [
    ["scale", "compute", "--family", "hdt", "--counts", "2000", "--transmission", "ballscrew pitch=5mm", "--json"],
    ["scale", "explain", "--family", "hdt", "6093:01=65536", "6093:02=360", "--json"],
])
def test_old_spellings_still_work(capsys: pytest.CaptureFixture[str], argv: list[str]) -> None:
    code, out, err = run(capsys, *argv)
    new = [{"--family": "--profile", "--counts": "--counts-per-rev"}.get(a, a) for a in argv]
    code2, out2, _ = run(capsys, *new)
    assert code == code2 == 0 and out == out2, err


def test_map_sdo_lists_only_the_formats_it_writes(capsys: pytest.CaptureFixture[str], tmp_path) -> None:
    command = dict(COMMANDS)[("map", "sdo")]
    fmt = next(p for p in command.params if p.name == "fmt")
    assert isinstance(fmt.type, click.Choice) and "lcec" not in fmt.type.choices
    for name in fmt.type.choices:
        code, _, err = run(capsys, "map", "sdo", "--profile", "hdt", "--rx", "0x1600=controlword,0x607A:00/32",
                           "--format", name, "-o", str(tmp_path / f"out.{name}"))
        assert code == 0, (name, err)
    code, _, err = run(capsys, "map", "sdo", "--profile", "hdt", "--format", "lcec")
    assert code == 2 and "'lcec' is not one of" in err


def test_errors_name_the_option_that_fixes_them(capsys: pytest.CaptureFixture[str], tmp_path) -> None:
    # a mapping with errors: map sdo says --force prints it anyway
    code, _, err = run(capsys, "map", "sdo", "--profile", "technosoft-ipos", "--rx", "0x1600=statusword")
    assert code == 1 and "--force" in err.splitlines()[-1]
    # an ESI with several devices: the selector error names --device
    esi = corpus_path("esi", "elmo_Elmo_ECAT_00010420_V11.xml")
    for argv in (["esi", "show", str(esi)], ["scale", "compute", "--counts-per-rev", "2000", "--esi", str(esi)],
                 ["project", "new", "--esi", str(esi), "-o", str(tmp_path / "p.yaml")]):
        code, _, err = run(capsys, *argv)
        assert code == 1 and "choose one with --device SEL" in err, (argv, err)
    # a startup file of several slaves into a one-slave format: --drive, which convert has
    eni = corpus_path("configs", "eni_kpierczy_test_eni.xml")
    code, _, err = run(capsys, "startup", "convert", str(eni), "--format", "twincat", "--lossy")  # (no DC in TwinCAT)
    assert code == 1 and "--drive" in err.splitlines()[-1]
    code, out, err = run(capsys, "startup", "convert", str(eni), "--format", "twincat", "--lossy", "--drive", "1")
    assert code == 0 and out, err
