"""Advice ecattool prints is advice it accepts (issue 14, item 5).

* every ``--option`` named in ecattool's messages and help texts (every string of its source but the
  docstrings of modules, classes and functions that are not commands) is an option of an ecattool command,
  and every option an error of a command suggests is an option of *that* command (the ambiguous-selector
  advice ``--policy newest`` is given by each command that takes a device selector, and each accepts it);
* in a project file the same advice reads ``policy: newest``, and the project file accepts it;
* the ``disable_rules`` entries ``project new`` proposes (commented out) lint clean once uncommented: no PRJ003
  for an ``esi-…`` rule id, and the rule is really disabled.
"""

from __future__ import annotations

import ast
import re
import shutil
from pathlib import Path

import click
import pytest

from ecattool.cli import cli
from ecattool.findings import Severity
from ecattool.project.machine import load_machine
from tests.conftest import ROOT, corpus_path, run
from tests.test_cli_contract import LEAVES

_FLAG = re.compile(r"(?<![\w-])--[a-z][a-z0-9]*(?:-[a-z0-9]+)*")
#: flags of other programs that ecattool's texts quote (each with where)
FOREIGN = {
    "--help": "click's own option, on every command",
}


def _options(cmd: click.Command) -> set[str]:
    return {o for p in cmd.params for o in (*p.opts, *p.secondary_opts) if o.startswith("--")}


def _tree(cmd: click.Command) -> list[click.Command]:
    """A command and, for a group, every command under it (the root's --version and --debug too)."""
    if not isinstance(cmd, click.Group):
        return [cmd]
    ctx = click.Context(cmd)
    return [cmd, *(c for n in cmd.list_commands(ctx) for c in _tree(cmd.get_command(ctx, n)))]  # type: ignore[arg-type]


ALL_OPTIONS = set().union(*(_options(c) for c in _tree(cli))) | set(FOREIGN)


def _is_command(node: ast.AST) -> bool:
    """A click command or group callback: its docstring is the help text users read."""
    decorators = getattr(node, "decorator_list", [])
    return any(w in ast.unparse(d) for d in decorators for w in (".command", ".group", "click.group"))


def _strings(path: Path) -> list[tuple[int, str]]:
    """Every string constant of a module (f-string parts too) with its line, except the docstrings of modules,
    classes and functions other than click commands (those are for programmers, not printed)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    private = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and not _is_command(node):
            body = node.body
            if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
                private.add(id(body[0].value))
    return [(n.lineno, n.value) for n in ast.walk(tree)
            if isinstance(n, ast.Constant) and isinstance(n.value, str) and id(n) not in private]


def test_every_option_ecattool_mentions_exists() -> None:
    unknown = []
    for path in sorted((ROOT / "ecattool").rglob("*.py")):
        for line, text in _strings(path):
            for flag in _FLAG.findall(text):
                if flag not in ALL_OPTIONS:
                    unknown.append(f"{path.relative_to(ROOT)}:{line}: {flag}")
    assert not unknown, unknown


#: "ecattool <command words> <the rest of the sentence>": the options in the rest are that command's
_COMMAND_TEXT = re.compile(r"ecattool((?: [a-z{][a-z0-9{}-]*)+)([^`;\n]*)")


def _named_command(words: list[str]) -> tuple[click.Command, list[str]]:
    """The command the longest run of leading words names, with those words."""
    cmd: click.Command = cli
    used: list[str] = []
    for word in words:
        sub = cmd.get_command(click.Context(cmd), word) if isinstance(cmd, click.Group) else None
        if sub is None:
            break
        cmd, used = sub, [*used, word]
    return cmd, used


def test_every_option_a_text_gives_to_a_command_is_an_option_of_that_command() -> None:
    """An example or advice that reads "ecattool sim serve --device …" names an option ``sim serve`` has (the
    first test only asks that some command has it). ``ecattool map {cmd} …`` (a help text made for each
    command of a group) is checked against every command of the group; prose ("the ecattool project file")
    names a group, not a command, and is not advice."""
    wrong, checked = [], 0
    for path in sorted((ROOT / "ecattool").rglob("*.py")):
        for line, text in _strings(path):
            for m in _COMMAND_TEXT.finditer(text):
                words = m.group(1).split()
                cmd, used = _named_command(words)
                rest = words[len(used):]
                if isinstance(cmd, click.Group):
                    if not rest or not rest[0].startswith("{"):
                        continue  # prose naming a group
                    accepted = set().union(*(_options(c) for c in _tree(cmd)[1:]))
                else:
                    accepted = _options(cmd)
                flags = set(_FLAG.findall(" ".join(rest) + m.group(2))) - set(FOREIGN)
                checked += bool(flags)
                if flags - accepted:
                    wrong.append(f"{path.relative_to(ROOT)}:{line}: ecattool {' '.join(used)}: "
                                 f"{sorted(flags - accepted)}")
    assert checked > 50 and not wrong, (checked, wrong)


def _ambiguous(tmp_path: Path) -> Path:
    esi = tmp_path / "el1xxx.xml"  # EL1008 has three revisions
    shutil.copy(corpus_path("esi", "beckhoff_EL1xxx.xml"), esi)
    return esi


def _commands(tmp: Path, esi: Path) -> list[list[str]]:
    script = tmp / "steps.yaml"
    script.write_text("- state: PREOP\n")
    return [
        ["project", "new", "--esi", esi.name, "--select", "EL1008", "-o", str(tmp / "p.yaml")],
        ["esi", "show", str(esi), "--device", "EL1008", "--json"],
        ["map", "check", "--esi", str(esi), "--device", "EL1008", "--json"],
        ["sim", "run", str(esi), str(script), "--device", "EL1008", "--json"],
        ["scale", "compute", "--esi", str(esi), "--device", "EL1008", "--lines", "500", "--json"],
        ["sii", "build", str(esi), "--device", "EL1008", "-o", str(tmp / "x.bin")],
    ]


def test_the_selector_advice_names_an_option_of_the_command_that_gives_it(capsys, tmp_path) -> None:
    esi = _ambiguous(tmp_path)
    for args in _commands(tmp_path, esi):
        code, _, err = run(capsys, *args)
        assert code == 1 and "matches 3 devices" in err, (args, err)
        leaf = next(LEAVES[k] for k in LEAVES if list(k) == args[:len(k)])
        suggested = set(_FLAG.findall(err))
        assert suggested and suggested <= _options(leaf), (args, suggested - _options(leaf))
        # and following the advice gets past the selection
        code, _, err = run(capsys, *args, "--policy", "newest")
        assert "matches 3 devices" not in err and "no such option" not in err, (args, err)


def test_the_selector_advice_in_a_project_file_is_accepted(tmp_path) -> None:
    esi = _ambiguous(tmp_path)
    project = tmp_path / "p.yaml"
    project.write_text(f"ecattool: 1\ndrives:\n  - name: a\n    device: {{esi: {esi.name}, select: EL1008}}\n")
    found = [f for f in load_machine(project).findings if f.rule == "PRJ005"]
    assert len(found) == 1 and "policy: newest under device:" in found[0].message
    project.write_text(project.read_text().replace("select: EL1008", "select: EL1008, policy: newest"))
    assert [str(f) for f in load_machine(project).findings] == []


@pytest.mark.parametrize("name", ["synapticon_Somanet_CiA402-single.xml", "beckhoff_AX2xxx.xml"])
def test_proposed_disable_rules_are_accepted(capsys, tmp_path, name) -> None:
    shutil.copy(corpus_path("esi", name), tmp_path / name)
    out = tmp_path / "m.yaml"
    assert run(capsys, "project", "new", "--esi", name, "-o", str(out))[0] == 0
    text = out.read_text()
    proposed = re.findall(r"#\s+- \{rule: ([\w.-]+)", text)
    assert proposed, text
    before = {f.rule for f in load_machine(out).findings if f.severity is Severity.ERROR}
    assert set(proposed) <= before  # each proposal answers an error lint reports
    out.write_text(text.replace("    # disable_rules:", "    disable_rules:").replace("    #   - {rule", "      - {rule"))
    after = load_machine(out).findings
    assert not [str(f) for f in after if f.rule in ("PRJ003", "PRJ004") or f.rule in proposed]


@pytest.mark.parametrize(("rule", "flagged"), [("esi-pdo-object-missing", False), ("scaling.small-pair", False),
                                               ("PDO011", False), ("PRJ019", False), ("PRJ999", True),
                                               ("PDO999", True), ("no-such-rule", True), ("not a rule", True)])
def test_prj003_flags_only_what_is_not_a_rule(tmp_path, rule, flagged) -> None:
    project = tmp_path / "p.yaml"
    project.write_text("ecattool: 1\ndisable_rules:\n  - {rule: \"%s\", reason: testing}\n"
                       "drives:\n  - name: a\n    device: {profile: hdt}\n" % rule)
    found = [f for f in load_machine(project).findings if f.rule == "PRJ003"]
    assert bool(found) is flagged, found
    if found:
        assert found[0].location is not None and found[0].location.line == 3
