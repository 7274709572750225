"""The CLI contract, swept over the whole command tree (docs/cli.md, "Exit codes and errors").

The tree is walked from the click group, so a new command is covered without editing a list here:

* every group and leaf command has ``--help`` with an example line for itself, and every leaf has ``--json``
  unless it is in :data:`NO_JSON` (commands that only write a file or a format of their own); with ``--json``
  stdout is JSON and nothing else;
* every file a command reads (a ``click.Path`` parameter, found from the parameters) is swapped, one at a
  time, for bad input of every kind in :data:`BAD_KINDS` in an otherwise valid invocation from
  :data:`HAPPY` (which must exit 0). Each must end with exit status 1, exactly one non-empty line on stderr
  naming the file, no traceback, and no output file (a pre-existing one is left byte-identical). The same on
  standard input where a command accepts '-', for files named inside projects and build specs, for an -o that
  cannot be written, and for unknown keys in YAML inputs.

Deliberate exceptions are data here, each with its reason: :data:`REPORTERS` (checkers that report bad input
as a finding), :data:`UNDETECTABLE` (what a format cannot show).
Commands run in-process through the real entry point (``tests.conftest.run``).
"""

from __future__ import annotations

import random
import re
import shutil
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import click
import pytest

from ecattool.cli import cli
from tests.conftest import CORPUS, ROOT, corpus_path, have_corpus, need_corpus, run, sample_sw_spec


def _leaves(group: click.Group, path: tuple[str, ...] = ()) -> Iterator[tuple[tuple[str, ...], click.Command]]:
    ctx = click.Context(group)
    for name in group.list_commands(ctx):
        cmd = group.get_command(ctx, name)
        assert cmd is not None, f"{' '.join((*path, name))}: listed but cannot be loaded"
        if isinstance(cmd, click.Group):
            yield from _leaves(cmd, (*path, name))
        else:
            yield (*path, name), cmd


LEAVES: dict[tuple[str, ...], click.Command] = dict(_leaves(cli))


def _name(cmd: tuple[str, ...]) -> str:
    return " ".join(cmd)


# ------------------------------------------------------------------------------------------- --help, --json
#: Commands that print no data of their own, so have no --json (each says why). Everything else must.
NO_JSON: dict[tuple[str, ...], str] = {
    ("esi", "export"): "writes an ESI file (-o required; '-' = stdout)",
    ("project", "new"): "writes a project skeleton (YAML) to -o or stdout",
    ("project", "schema"): "prints the JSON Schema itself (JSON already) or checks a checked-in copy",
    ("scale", "startup"): "writes a startup list in the master format chosen with --format (json is one)",
    ("sii", "build"): "writes an SII image (-o required)",
    ("sii", "fix-crc"): "writes the repaired image (-o required)",
    ("sii", "set-alias"): "writes the changed image (-o required)",
    ("startup", "convert"): "writes the startup list in --format (json is one) to -o",
    ("startup", "export"): "writes the startup list in --format (json is one)",
    ("sw", "build"): "writes a .sw image (-o required)",
    ("sdo", "dump"): "writes a JSON dictionary snapshot (JSON is its only form)",
    ("sii", "read"): "writes a binary SII image (-o required)",
    ("backup",): "writes a folder (-o required) of images and JSON snapshots; prints the names of its files",
    ("sii", "write"): "writes to a slave's EEPROM; prints one line (a refusal is an error)",
    ("sw", "foe"): "writes a FoE file (-o required)",
    ("sw", "from-foe"): "writes .sw text",
    ("sw", "patch"): "writes the patched .sw image (-o required)",
}


def test_tree_is_walked_and_the_allowlist_names_real_commands() -> None:
    assert len(LEAVES) >= 35 and ("sw", "info") in LEAVES and ("lint",) in LEAVES
    assert set(NO_JSON) <= set(LEAVES), set(NO_JSON) - set(LEAVES)


@pytest.mark.parametrize("cmd", sorted(LEAVES), ids=_name)
def test_help_has_an_example_of_the_command(capsys: pytest.CaptureFixture[str], cmd: tuple[str, ...]) -> None:
    code, out, err = run(capsys, *cmd, "--help")
    assert code == 0 and not err
    assert re.search(rf"^\s+ecattool {re.escape(_name(cmd))}\b", out, re.MULTILINE), f"no example line in:\n{out}"


def _groups(group: click.Group, path: tuple[str, ...] = ()) -> Iterator[tuple[str, ...]]:
    ctx = click.Context(group)
    for name in group.list_commands(ctx):
        cmd = group.get_command(ctx, name)
        if isinstance(cmd, click.Group):
            yield (*path, name)
            yield from _groups(cmd, (*path, name))


GROUPS = sorted(_groups(cli))


@pytest.mark.parametrize("group", GROUPS, ids=_name)
def test_group_help_has_examples(capsys: pytest.CaptureFixture[str], group: tuple[str, ...]) -> None:
    code, out, err = run(capsys, *group, "-h")
    assert code == 0 and not err
    assert re.search(rf"^\s+ecattool {re.escape(_name(group))} ", out, re.MULTILINE), f"no example in:\n{out}"


def _command_table() -> set[tuple[str, ...]]:
    """The commands docs/cli.md's table lists: `group` | `a`, `b` | page, or `cmd` | (one command) | page."""
    text = (ROOT / "docs" / "cli.md").read_text(encoding="utf-8")
    listed: set[tuple[str, ...]] = set()
    for group, commands in re.findall(r"^\| `([a-z-]+)` \| ([^|]+) \|", text, re.MULTILINE):
        names = re.findall(r"`([a-z-]+)`", commands)
        listed |= {(group, n) for n in names} if names else {(group,)}
    return listed


def test_docs_cli_lists_every_command() -> None:
    """docs/cli.md's table is the list of commands a reader trusts: every command is there, and nothing else."""
    assert _command_table() == set(LEAVES)


@pytest.mark.parametrize("cmd", sorted(LEAVES), ids=_name)
def test_json_where_data_is_printed(cmd: tuple[str, ...]) -> None:
    has_json = any("--json" in p.opts for p in LEAVES[cmd].params if isinstance(p, click.Option))
    # in NO_JSON exactly when it has no --json: the allowlist cannot go stale either way
    assert has_json != (cmd in NO_JSON), NO_JSON.get(cmd, "prints data but has no --json")


# --------------------------------------------------------------------------------------- valid invocations
@dataclass(frozen=True)
class In:
    """An input file of a valid invocation. ``where``: 'samples/...' (repository), 'corpus:...' or 'gen:...'
    (written by the ``gen`` fixture); ``kind`` chooses the truncated corpus file and the wrong-command file."""

    kind: str
    where: str


@dataclass(frozen=True)
class Out:
    """The -o file of a valid invocation (created in the test's tmp_path)."""

    name: str


ESI = In("esi", "samples/esi/etg2001_cia402.xml")
SW = In("sw", "corpus:sw/ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.sw")
PARAMS = In("params", "corpus:sw/ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.ems_parameters.cfg")
FOE = In("foe", "corpus:sw/ecmc_ipos8020BX_FOESW_8020.bin")
SII = In("sii", "corpus:sii/ni9144.bin")
SII_ESI = In("esi", "corpus:sii/ni9144.xml")
STARTUP = In("startup", "corpus:configs/ros2_technosoft_ipos3604.yaml")
PROJECT = In("project", "samples/hdt/project.yaml")
SPEC = In("spec", "samples/scaling/ballscrew.yaml")
COPLEY = In("esi", "corpus:esi/copley_XE2_4.60.xml")  # a dictionary with the factor group
TS = ("--profile", "technosoft-ipos")

#: One or more valid invocations per command that reads or writes files; together they name every file
#: parameter (checked by test_every_file_parameter_is_swept).
HAPPY: dict[tuple[str, ...], list[tuple[object, ...]]] = {
    ("commission",): [(PROJECT, "-o", Out("report.json"), "--report", Out("report.html"))],
    ("lint",): [(PROJECT, "-o", Out("lint.txt"))],
    ("esi", "devices"): [(ESI,)],
    ("esi", "show"): [(ESI, "--pdos"), (In("eds", "corpus:eds/technosoft_iPOS.D.v1.04.eds"), "--pdos")],
    ("esi", "export"): [("technosoft-ipos", "--revision", "F515I", "-o", Out("drive.xml"))],
    ("esi", "validate"): [(ESI,)],
    ("map", "check"): [(*TS, "--mapping", In("mapping", "gen:mapping.yaml")),
                       ("--esi", ESI),
                       (*TS, "--product", "ipos4808-bx-cat", "--startup", In("startup", "corpus:configs/ecmc_ecmciPOSXXXX.cmd"))],
    ("map", "layout"): [(*TS, "--mapping", In("mapping", "gen:mapping.yaml"), "-o", Out("layout.json")),
                        ("--esi", ESI, "-o", Out("layout.json"), "--svg", Out("layout.svg")),
                        (*TS, "--product", "ipos4808-bx-cat", "--startup", In("startup", "corpus:configs/ecmc_ecmciPOSXXXX.cmd"))],
    ("map", "sdo"): [(*TS, "--mapping", In("mapping", "gen:mapping.yaml"), "-o", Out("sdo.json")),
                     ("--esi", ESI, "-o", Out("sdo.json")),
                     (*TS, "--product", "ipos4808-bx-cat", "--startup", In("startup", "corpus:configs/ecmc_ecmciPOSXXXX.cmd"))],
    ("project", "new"): [(*TS, "-o", Out("machine.yaml"))],
    ("project", "schema"): [("-o", Out("schema.json")), ("--check", In("schema", "schemas/project.schema.json"))],
    ("scale", "compute"): [(SPEC, "-o", Out("factors.json"), "--html", Out("scaling.html")),
                           (In("spec", "samples/scaling/rotary_table.yaml"), "--esi", COPLEY, "-o", Out("factors.json"))],
    ("scale", "startup"): [(SPEC, "--format", "json", "-o", Out("startup.json")),
                           (In("spec", "samples/scaling/rotary_table.yaml"), "--esi", COPLEY, "-o", Out("startup.txt"))],
    ("scale", "explain"): [("--from", In("startup", "gen:factors.csv"), "--html", Out("scaling.html")),
                           ("--project", PROJECT)],
    ("sim", "run"): [("technosoft-ipos", In("script", "gen:steps.yaml"), "-o", Out("transcript.txt")),
                     (In("esi", "corpus:esi/elmo_Elmo_ECAT_00010420_V11.xml"), In("script", "gen:steps.yaml"), "--device", "2")],
    ("sii", "info"): [(SII,)],
    ("sii", "check"): [(SII,), (SII_ESI, SII)],
    ("sii", "fix-crc"): [(SII, "-o", Out("fixed.bin"))],
    ("sii", "set-alias"): [(SII, "7", "-o", Out("alias.bin"))],
    ("sii", "build"): [(SII_ESI, "--device", "#x23B8:2", "-o", Out("built.bin"))],
    ("sii", "diff"): [(SII, SII)],
    ("startup", "import"): [(STARTUP,)],
    ("startup", "convert"): [(STARTUP, "--format", "json", "-o", Out("startup.json"))],
    ("startup", "export"): [("--from", STARTUP, "--format", "json", "-o", Out("startup.json")),
                            ("--project", In("project", "samples/technosoft_ipos/project.yaml"), "--format", "json",
                             "-o", Out("startup.json"))],
    ("sw", "info"): [(SW,)],
    ("sw", "show"): [(SW, "-p", PARAMS)],
    ("sw", "foe"): [(SW, "-o", Out("FOESW_AXIS.bin"))],
    ("sw", "from-foe"): [(FOE, "-o", Out("back.sw"))],
    ("sw", "verify"): [(SW, "--preload", SW), ("--project", In("project", "gen:machine.yaml"), "--preload", SW)],
    ("sw", "download"): [(SW, "--preload", SW, "--json"), ("--project", In("project", "gen:machine.yaml"))],
    ("sw", "patch"): [(SW, "-p", PARAMS, "--set", "PWMPER=2251", "-o", Out("patched.sw"))],
    ("sw", "diff"): [(SW, SW, "-p", PARAMS)],
    ("sw", "build"): [(In("swspec", "samples/sw/build.yaml"), "-o", Out("built.sw"))],
    ("bus", "scan"): [("--target", "sim:hdt,technosoft-ipos", "--library", "samples/generic_esi")],
    ("sdo", "read"): [("0x1018:01", "--target", "sim:hdt")],
    ("sdo", "write"): [("0x6060:00", "1", "--target", "sim:technosoft-ipos", "--device", "technosoft-ipos")],
    ("sdo", "info"): [("--target", "sim:hdt")],
    ("sdo", "diff"): [(In("snapshot", "gen:hdt.dict.json"), In("snapshot", "gen:hdt.dict.json"))],
    ("sdo", "dump"): [("--target", "sim:hdt", "-o", Out("dict.json"))],
    ("sii", "read"): [("--target", "sim:hdt", "-o", Out("slave.bin"))],
    ("sii", "write"): [(In("sii", "gen:hdt.sii.bin"), "--target", "sim:hdt", "--backup", Out("old.bin"))],
    ("audit",): [(In("project", "gen:plain.yaml"), "--target", "sim", "-o", Out("audit.txt"), "--html",
                  Out("audit.html"))],
    ("backup",): [(In("project", "gen:plain.yaml"), "--target", "sim", "-o", Out("backup-folder"))],
    ("sw", "upload"): [("--like", SW, "--target", "sim", "--preload", SW, "-o", Out("back.sw")),
                       ("--project", In("project", "gen:machine.yaml"), "--preload", SW, "-o", Out("back.sw"))],
}

#: One real file of every input kind the valid invocations use (the first In of that kind): the "other:KIND"
#: bad inputs give each input slot every kind of file but its own (an SII image as a project, a script as an ESI).
KIND_FILES: dict[str, str] = {}
for _invs in HAPPY.values():
    for _inv in _invs:
        for _a in _inv:
            if isinstance(_a, In):
                KIND_FILES.setdefault(_a.kind, _a.where)

STEPS = "- state: PREOP\n- read: '1018:01'\n- state: SAFEOP\n- state: OP\n"
MAPPING = "rx:\n  - index: 0x1600\n    entries: [controlword, 0x607A:00/32]\n"


@pytest.fixture(scope="session")
def gen(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Inputs that no sample holds as such: a mapping file, a simulator script, a project with a .sw, the CSV
    startup list of a factor group."""
    d = tmp_path_factory.mktemp("gen")
    (d / "mapping.yaml").write_text(MAPPING)
    (d / "steps.yaml").write_text(STEPS)
    (d / "plain.yaml").write_text("ecattool: 1\nname: m\ndrives:\n  - name: y\n    device: {profile: hdt}\n")
    if have_corpus():  # else the tests that use it (and machine.yaml, which names it) skip in resolve()
        (d / "axis.sw").write_bytes(corpus_path("sw", "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.sw").read_bytes())
    (d / "machine.yaml").write_text("ecattool: 1\nname: m\ndrives:\n  - name: y\n    device: {profile: technosoft-ipos}\n"
                                    "    sw: axis.sw\n")
    cli.main(["sdo", "dump", "--target", "sim:hdt", "-o", str(d / "hdt.dict.json")], standalone_mode=False)
    cli.main(["sii", "read", "--target", "sim:hdt", "-o", str(d / "hdt.sii.bin")], standalone_mode=False)
    cli.main(["scale", "startup", str(ROOT / SPEC.where), "--format", "csv", "-o", str(d / "factors.csv")],
             standalone_mode=False)
    return d


@pytest.fixture(autouse=True)
def _own_cache(monkeypatch: pytest.MonkeyPatch, tmp_path_factory: pytest.TempPathFactory) -> None:
    """lint/commission cache parsed ESI files: in a directory of this run, not the user's cache."""
    monkeypatch.setenv("ECATTOOL_CACHE_DIR", str(tmp_path_factory.getbasetemp() / "cache"))


def resolve(where: str, gen: Path) -> Path:
    if where.startswith("corpus:"):
        return corpus_path(*where[len("corpus:"):].split("/"))
    if where.startswith("gen:"):
        if where in ("gen:axis.sw", "gen:machine.yaml"):
            need_corpus()
        return gen / where[len("gen:"):]
    if where == "samples/sw/build.yaml":  # it names corpus files: a copy that finds the corpus in use
        return sample_sw_spec(gen)
    return ROOT / where


def argv(inv: tuple[object, ...], gen: Path, out_dir: Path, swap: dict[int, Path | str] | None = None) -> list[str]:
    args = []
    for i, a in enumerate(inv):
        if swap and i in swap:
            args.append(str(swap[i]))
        elif isinstance(a, In):
            args.append(str(resolve(a.where, gen)))
        elif isinstance(a, Out):
            args.append(str(out_dir / a.name))
        else:
            args.append(str(a))
    return args


#: parameters naming a file a command writes (besides -o): written atomically and swept like -o
OUTPUT_PARAMS = {"output", "svg", "report", "html", "backup"}


def _is_read_path(p: click.Parameter) -> bool:
    return isinstance(p.type, click.Path) and bool(p.type.file_okay) and p.name not in OUTPUT_PARAMS


def params_at(cmd: tuple[str, ...], inv: tuple[object, ...]) -> dict[int, click.Parameter]:
    """The click parameter that takes each In/Out of ``inv`` (parsed as click parses it; no file is opened)."""
    command = LEAVES[cmd]
    args = [f"@{i}" if isinstance(a, (In, Out)) else str(a) for i, a in enumerate(inv)]  # distinct, so found once
    ctx = command.make_context(_name(cmd), list(args), resilient_parsing=True)
    by_name = {p.name: p for p in command.params}
    found = {}
    for i, a in enumerate(inv):
        if isinstance(a, (In, Out)):
            for name, value in ctx.params.items():
                if args[i] in (value if isinstance(value, tuple) else (value,)):
                    found[i] = by_name[name]
    return found


def test_every_file_parameter_is_swept() -> None:
    """Every file a command reads and every -o appears in some valid invocation, so the matrix covers it."""
    assert set(HAPPY) <= set(LEAVES), set(HAPPY) - set(LEAVES)
    for cmd, command in LEAVES.items():
        wanted = {p.name for p in command.params if _is_read_path(p) or p.name in OUTPUT_PARAMS}
        covered = {p.name for inv in HAPPY.get(cmd, []) for p in params_at(cmd, inv).values()}
        assert wanted <= covered, f"{_name(cmd)}: no valid invocation gives {sorted(wanted - covered)}"


HAPPY_CASES = [(cmd, n) for cmd, invs in HAPPY.items() for n in range(len(invs))]


@pytest.mark.parametrize(("cmd", "n"), HAPPY_CASES, ids=[f"{_name(c)}#{n}" for c, n in HAPPY_CASES])
def test_valid_invocation_succeeds(capsys: pytest.CaptureFixture[str], gen: Path, tmp_path: Path,
                                   cmd: tuple[str, ...], n: int) -> None:
    inv = HAPPY[cmd][n]
    code, out, err = run(capsys, *cmd, *argv(inv, gen, tmp_path))
    assert code == 0, err or out
    for a in inv:
        if isinstance(a, Out):
            assert (tmp_path / a.name).stat().st_size > 0


# ---------------------------------------------------------------------------------------------- bad input
BAD_KINDS = ("missing", "empty", "directory", "binary", "other", "truncated", "bad-utf8", "doctype")

#: A real file of each input kind, cut short (the corpus where it has that kind of file).
TRUNCATED = {
    "esi": "corpus:esi/smc_EX260-SECx_V11.xml",
    "sii": "corpus:sii/ni9144.bin",
    "sw": "corpus:sw/ecmc_TMLCode.sw",
    "foe": "corpus:sw/ecmc_ipos8020_FOESW_DC48V_TRQ.bin",
    "params": "corpus:sw/ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.ems_parameters.cfg",
    "startup": "corpus:configs/eni_kpierczy_test_eni.xml",
}
#: Input kinds that are binary: "invalid UTF-8" means nothing there (random bytes are covered by 'binary').
BINARY_KINDS = {"sii", "foe"}

DOCTYPE = (b'<?xml version="1.0" encoding="UTF-8"?>\n<!DOCTYPE EtherCATInfo [\n  <!ENTITY boom "boom">\n]>\n'
           b"<EtherCATInfo><Vendor><Id>&boom;</Id></Vendor></EtherCATInfo>\n")


def bad_file(kind: str, inp: In, gen: Path, tmp_path: Path) -> Path:
    real = resolve(inp.where, gen)
    path = tmp_path / f"bad-{kind.replace(':', '-')}{real.suffix}"  # the expected suffix: the content decides
    if kind == "missing":
        return path
    if kind == "directory":
        path.mkdir()
        return path
    if kind == "empty":
        data = b""
    elif kind == "binary":
        data = random.Random(1).randbytes(700)
    elif kind == "other":  # valid for another command: a .sw where XML is expected, else an ESI
        data = resolve((SW if inp.kind == "esi" else ESI).where, gen).read_bytes()
    elif kind.startswith("other:"):  # a real file of that kind
        data = resolve(KIND_FILES[kind.split(":", 1)[1]], gen).read_bytes()
    elif kind == "truncated":  # cut inside the data (an SII image's 0xFF fill is not data)
        src = resolve(TRUNCATED.get(inp.kind, inp.where), gen).read_bytes()
        data = src[: len(src.rstrip(b"\xff")) * 3 // 5]
    elif kind == "bad-utf8":  # a line of bytes that are not UTF-8, in a file that says it is UTF-8
        src = re.sub(rb"^<\?xml[^>]*\?>", b'<?xml version="1.0" encoding="UTF-8"?>', real.read_bytes())
        cut = src.index(b"\n", len(src) // 2) + 1
        data = src[:cut] + b"\xff\xfe\xc3\x28 \x80\n" + src[cut:]
    elif kind == "doctype":
        data = DOCTYPE
    else:  # pragma: no cover
        raise AssertionError(kind)
    path.write_bytes(data)
    return path


def _bad_cases() -> list[tuple[tuple[str, ...], int, int, str]]:
    cases = []
    for cmd, invs in HAPPY.items():
        for n, inv in enumerate(invs):
            for i, a in enumerate(inv):
                if not isinstance(a, In):
                    continue
                for kind in BAD_KINDS:
                    if kind == "bad-utf8" and a.kind in BINARY_KINDS:
                        continue
                    if kind == "other":
                        cases += [(cmd, n, i, f"other:{k}") for k in sorted(KIND_FILES)
                                  if k != a.kind and frozenset({k, a.kind}) not in INTERCHANGEABLE]
                    else:
                        cases.append((cmd, n, i, kind))
    return cases


#: Input kinds each command that takes one also takes as the other (not "bad" there): a CANopen EDS is accepted
#: wherever an ESI is (docs/esi.md, "CANopen EDS and DCF files").
INTERCHANGEABLE = {frozenset({"esi", "eds"})}
BAD_CASES = _bad_cases()


#: Checkers whose report is their output: the input they check (of this kind), when bad, is a finding in the
#: report (stdout, or the -o file, which is written), named with its file; exit status 1 as for any error finding.
REPORTERS: dict[tuple[str, ...], tuple[str, str]] = {
    ("lint",): ("project", "a CI linter reports every project, readable or not, in its text/JSON/SARIF report"),
    ("sii", "check"): ("sii", ("an unreadable image is an error finding (rule sii.parse), in --json too; a bad "
                               "ESI to compare with is an ordinary error")),
}

#: (input kind, bad kind) pairs that cannot be detected, by design of the format (docs/cli.md).
UNDETECTABLE: dict[tuple[str, str], str] = {
    ("sw", "truncated"): "a .sw image has no length, end marker or file checksum: a prefix cut at a line is a "
                         "shorter valid image; 'sw info' integrity words and 'sw verify' are the checks",
}


@pytest.mark.parametrize(("cmd", "n", "i", "kind"), BAD_CASES,
                         ids=[f"{_name(c)}#{n}.{i}-{k}" for c, n, i, k in BAD_CASES])
def test_bad_input_is_one_line_and_exit_1(capsys: pytest.CaptureFixture[str], gen: Path, tmp_path: Path,
                                          cmd: tuple[str, ...], n: int, i: int, kind: str) -> None:
    inv = HAPPY[cmd][n]
    inp = inv[i]
    assert isinstance(inp, In)
    bad = bad_file(kind, inp, gen, tmp_path)
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    outs = [out_dir / a.name for a in inv if isinstance(a, Out)]
    previous = b"an earlier result\n"
    keep = kind == "binary"  # once per input: a pre-existing output must survive the failure untouched
    for o in outs:
        if keep:
            o.write_bytes(previous)
    force = ("--force",) if keep and outs else ()  # allowed to replace it: the bad input is what must stop it
    code, out, err = run(capsys, *cmd, *argv(inv, gen, out_dir, {i: bad}), *force)
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert "Traceback" not in out + err
    if (inp.kind, kind) in UNDETECTABLE:
        assert code in (0, 1)
        return
    if cmd in REPORTERS and REPORTERS[cmd][0] == inp.kind:
        report = out + "".join(o.read_text() for o in outs)
        assert code == 1 and not lines and f"{bad}" in report, f"exit {code}\nstdout: {out}\nstderr: {err}"
        assert sorted(out_dir.iterdir()) == sorted(outs), "stray files"
        return
    assert code == 1, f"exit {code}\nstdout: {out}\nstderr: {err}"
    assert len(lines) == 1, f"stderr is not one line:\n{err}"
    assert bad.name in lines[0], f"the error does not name {bad.name}: {lines[0]}"
    for o in outs:
        if keep:
            assert o.read_bytes() == previous
        else:
            assert not o.exists(), f"{o.name} written although the command failed"
    assert sorted(p.name for p in out_dir.iterdir()) == sorted(o.name for o in outs if keep), "stray files"


# ------------------------------------------------------------------------------------- stdin and the output
def _stdin_cases() -> list[tuple[tuple[str, ...], int, int, str]]:
    cases = []
    for cmd, invs in HAPPY.items():
        for n, inv in enumerate(invs):
            for i, p in params_at(cmd, inv).items():
                a = inv[i]
                if isinstance(a, In) and getattr(p.type, "allow_dash", False):
                    cases += [(cmd, n, i, kind) for kind in ("empty", "binary", "bad-utf8", "doctype")
                              if not (kind == "bad-utf8" and a.kind in BINARY_KINDS)]
    return cases


STDIN_CASES = _stdin_cases()


def test_stdin_is_swept_where_a_command_reads_it() -> None:
    assert {c[0] for c in STDIN_CASES} >= {("esi", "devices"), ("map", "check"), ("startup", "import"), ("sii", "info")}


@pytest.mark.parametrize(("cmd", "n", "i", "kind"), STDIN_CASES,
                         ids=[f"{_name(c)}#{n}.{i}-{k}" for c, n, i, k in STDIN_CASES])
def test_bad_stdin_is_one_line_and_exit_1(capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch,
                                          gen: Path, tmp_path: Path, cmd: tuple[str, ...], n: int, i: int,
                                          kind: str) -> None:
    """'-' reads standard input: the same bad input there is named as <stdin> (or '-')."""
    import io
    import sys

    inv = HAPPY[cmd][n]
    inp = inv[i]
    assert isinstance(inp, In)
    data = bad_file(kind, inp, gen, tmp_path).read_bytes()
    monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(io.BytesIO(data), encoding="utf-8"))
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    code, out, err = run(capsys, *cmd, *argv(inv, gen, out_dir, {i: "-"}))
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert "Traceback" not in out + err
    assert code == 1 and len(lines) == 1, f"exit {code}\nstdout: {out}\nstderr: {err}"
    assert re.match(r"ecattool: error: (<stdin>|-)[:\s]", lines[0]), lines[0]
    assert not list(out_dir.iterdir())


OUT_CASES = [(cmd, n) for cmd, n in HAPPY_CASES if any(isinstance(a, Out) for a in HAPPY[cmd][n])]


@pytest.mark.parametrize(("cmd", "n"), OUT_CASES, ids=[f"{_name(c)}#{n}" for c, n in OUT_CASES])
def test_output_that_cannot_be_written_is_one_line_and_exit_1(capsys: pytest.CaptureFixture[str], gen: Path,
                                                              tmp_path: Path, cmd: tuple[str, ...], n: int) -> None:
    """-o into a directory that does not exist: the command does its work, then cannot write; one line, exit 1."""
    code, out, err = run(capsys, *cmd, *argv(HAPPY[cmd][n], gen, tmp_path / "no-such-dir"))
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert "Traceback" not in out + err
    assert code == 1 and len(lines) == 1 and "no-such-dir" in lines[0], f"exit {code}\nstdout: {out}\nstderr: {err}"
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(("cmd", "n"), OUT_CASES, ids=[f"{_name(c)}#{n}" for c, n in OUT_CASES])
def test_existing_output_is_replaced_only_with_force(capsys: pytest.CaptureFixture[str], gen: Path, tmp_path: Path,
                                                     cmd: tuple[str, ...], n: int) -> None:
    """Every command that writes a file: an existing one is refused in one line that names --force, and left as it
    was; with --force it is replaced (docs/cli.md, "Output files")."""
    inv = HAPPY[cmd][n]
    outs = [tmp_path / a.name for a in inv if isinstance(a, Out)]
    assert any("--force" in p.opts for p in LEAVES[cmd].params if isinstance(p, click.Option))
    earlier = b"an earlier result\n"
    for o in outs:
        if cmd == ("backup",):  # --force replaces only an earlier back-up (its manifest; issue 37.2)
            o.mkdir()
            (o / "ecattool-backup.json").write_text('{"format": "ecattool-backup", "version": 1}\n')
            (o / "earlier.bin").write_bytes(earlier)
        else:
            o.write_bytes(earlier)

    def kept(o: Path) -> bool:
        return (o / "earlier.bin").is_file() if o.is_dir() else o.read_bytes() == earlier

    code, out, err = run(capsys, *cmd, *argv(inv, gen, tmp_path))
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert code == 1 and len(lines) == 1 and "file exists; use --force" in lines[0], f"exit {code}\n{out}\n{err}"
    assert all(kept(o) for o in outs)
    code, out, err = run(capsys, *cmd, *argv(inv, gen, tmp_path), "--force")
    assert code == 0, err or out
    assert not any(kept(o) for o in outs)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(o.name for o in outs), "stray files"


# ------------------------------------------------------------------------------------ files named in files
#: An input that names another file: (the file it names, the text naming it, with {ref} for that file's path).
NESTED: dict[str, tuple[In, str]] = {
    "project-esi": (In("esi", "samples/generic_esi/inovance_SV660_EOE_1Axis_V9.12.xml"),
                    ("ecattool: 1\nname: m\ndrives:\n  - name: joint1\n    device:\n      esi: {ref}\n"
                     "      select: InoSV660N\n    move: {{distance: 10000, mode: csp}}\n")),
    "project-sw": (SW, ("ecattool: 1\nname: m\ndrives:\n  - name: y\n    device: {{profile: technosoft-ipos}}\n"
                        "    sw: {ref}\n")),
    "swspec-base": (SW, "base: {ref}\nsetup:\n  parameters: " + str(CORPUS / "sw" / PARAMS.where.split("/")[-1])
                        + "\n  values: {{SLPER: 10}}\n"),
}
#: The commands that read each nested file; {top} is the naming file, {out} an output, {sw} a good .sw image.
NESTED_COMMANDS: dict[str, list[tuple[str, ...]]] = {
    "project-esi": [("commission", "{top}"), ("lint", "{top}"),
                    ("startup", "export", "--project", "{top}", "--format", "json", "-o", "{out}")],
    "project-sw": [("commission", "{top}"), ("lint", "{top}"), ("sw", "verify", "--project", "{top}", "--preload", "{sw}"),
                   ("sw", "download", "--project", "{top}")],
    "swspec-base": [("sw", "build", "{top}", "-o", "{out}")],
}
#: Commands that report a bad file named in a project as a finding or a failed drive, in their report.
NESTED_REPORTERS: dict[tuple[str, ...], str] = {
    ("lint",): REPORTERS[("lint",)][1],
    ("commission",): "a drive that cannot be commissioned is a FAILED drive in the report, the others still run "
                     "(a project whose simulated target cannot even be built is one error line)",
}
NESTED_CASES = [(name, n, kind) for name, cmds in NESTED_COMMANDS.items() for n in range(len(cmds))
                for kind in ("ok", *BAD_KINDS) if not (kind == "bad-utf8" and NESTED[name][0].kind in BINARY_KINDS)]


@pytest.mark.parametrize(("name", "n", "kind"), NESTED_CASES,
                         ids=[f"{nm}:{' '.join(NESTED_COMMANDS[nm][n][:2])}-{k}" for nm, n, k in NESTED_CASES])
def test_bad_file_named_in_an_input(capsys: pytest.CaptureFixture[str], gen: Path, tmp_path: Path, name: str,
                                    n: int, kind: str) -> None:
    """A bad file named inside a project or a build spec is reported with its own name, like a bad argument."""
    inp, text = NESTED[name]
    ref = resolve(inp.where, gen) if kind == "ok" else bad_file(kind, inp, gen, tmp_path)
    top = tmp_path / "top.yaml"
    top.write_text(text.format(ref=ref))
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    cmd = NESTED_COMMANDS[name][n]
    code, out, err = run(capsys, *(a.format(top=top, out=out_dir / "result", sw=resolve(SW.where, gen)) for a in cmd))
    assert "Traceback" not in out + err
    if kind == "ok":
        assert code == 0, err or out
        return
    if (inp.kind, kind) in UNDETECTABLE:
        assert code in (0, 1)
        return
    lines = [ln for ln in err.splitlines() if ln.strip()]
    if cmd[:1] in NESTED_REPORTERS:
        assert code == 1 and len(lines) <= 1 and ref.name in out + err, f"exit {code}\nstdout: {out}\nstderr: {err}"
        return
    assert code == 1 and len(lines) == 1, f"exit {code}\nstdout: {out}\nstderr: {err}"
    assert ref.name in lines[0], f"the error does not name {ref.name}: {lines[0]}"
    assert not list(out_dir.iterdir())


# ------------------------------------------------------------------------------------------ unknown fields
#: YAML inputs: a key the reader does not know must be refused (file:line), never silently ignored. The
#: startup kind is absent on purpose: ethercat_driver_ros2 files keep keys of their own (auto_fault_reset …),
#: which ecattool carries through to the ros2 writer (ecattool/startup/formats/ros2.py, cfg.extra).
YAML_KINDS = {"project", "spec", "swspec", "mapping", "script"}
UNKNOWN_KEY_CASES = [(cmd, n, i) for cmd, n, i, kind in BAD_CASES  # one case per YAML input slot
                     if kind == "empty" and getattr(HAPPY[cmd][n][i], "kind", None) in YAML_KINDS]


def with_unknown_key(data: bytes) -> bytes:
    if data.lstrip().startswith(b"- "):  # a list of mappings (a script): into the first item
        first = data.index(b"\n") + 1
        return data[:first] + b"  bogus_key: 1\n" + data[first:]
    return data.rstrip(b"\n") + b"\nbogus_key: 1\n"


@pytest.mark.parametrize(
    ("cmd", "n", "i"),
    UNKNOWN_KEY_CASES,
    ids=[f"{_name(c)}#{n}.{i}" for c, n, i in UNKNOWN_KEY_CASES])
def test_unknown_yaml_key_is_refused(capsys: pytest.CaptureFixture[str], gen: Path, tmp_path: Path,
                                     cmd: tuple[str, ...], n: int, i: int) -> None:
    inv = HAPPY[cmd][n]
    inp = inv[i]
    assert isinstance(inp, In)
    real = resolve(inp.where, gen)
    bad = tmp_path / f"unknown-key{real.suffix}"
    # the sample build spec names corpus files relative to itself
    bad.write_bytes(with_unknown_key(real.read_bytes()).replace(b"../../../shared/corpus", str(CORPUS).encode()))
    (tmp_path / "out").mkdir()
    code, out, err = run(capsys, *cmd, *argv(inv, gen, tmp_path / "out", {i: bad}))
    lines = [ln for ln in err.splitlines() if ln.strip()]
    outs = [tmp_path / "out" / a.name for a in inv if isinstance(a, Out)]
    report = out + "".join(o.read_text() for o in outs if o.exists()) if cmd in REPORTERS else \
        (lines[0] if len(lines) == 1 else "")
    assert code == 1 and "bogus_key" in report and re.search(rf"{re.escape(bad.name)}:\d+", report), \
        f"exit {code}\nstdout: {out}\nstderr: {err}"


# ------------------------------------------------------------------------------------------------- --json
def _has_json(cmd: tuple[str, ...]) -> bool:
    return any("--json" in p.opts for p in LEAVES[cmd].params if isinstance(p, click.Option))


def as_json(inv: tuple[object, ...]) -> tuple[object, ...]:
    """``inv`` printing JSON on stdout: without its -o file, with --json."""
    out: list[object] = []
    for a in inv:
        if isinstance(a, Out):
            out.pop()  # its -o
        else:
            out.append(a)
    return (*out, "--json") if "--json" not in out else tuple(out)


JSON_CASES = [(cmd, n, i) for cmd, n in HAPPY_CASES if _has_json(cmd)
              for i in (None, *(j for j, a in enumerate(as_json(HAPPY[cmd][n])) if isinstance(a, In)))]


@pytest.mark.parametrize(("cmd", "n", "i"), JSON_CASES,
                         ids=[f"{_name(c)}#{n}" + ("" if i is None else f".{i}-binary") for c, n, i in JSON_CASES])
def test_json_stdout_is_json_only(capsys: pytest.CaptureFixture[str], gen: Path, tmp_path: Path,
                                  cmd: tuple[str, ...], n: int, i: int | None) -> None:
    """With --json, stdout is one JSON document (exit 0), or, for bad input, JSON (a checker's report) or nothing."""
    import json

    inv = as_json(HAPPY[cmd][n])
    swap: dict[int, Path | str] = {}
    if i is not None:
        bad = inv[i]
        assert isinstance(bad, In)
        swap[i] = bad_file("binary", bad, gen, tmp_path)
    code, out, err = run(capsys, *cmd, *argv(inv, gen, tmp_path, swap))
    assert code == (0 if i is None else 1), err or out
    if i is None or out.strip():
        json.loads(out)


# ------------------------------------------------------------------------------------ -o never over an input
CLOBBER_CASES = [(cmd, n, i) for cmd, n in OUT_CASES for i, a in enumerate(HAPPY[cmd][n]) if isinstance(a, In)]


@pytest.mark.parametrize(("cmd", "n", "i"), CLOBBER_CASES, ids=[f"{_name(c)}#{n}.{i}" for c, n, i in CLOBBER_CASES])
def test_output_over_an_input_is_refused(capsys: pytest.CaptureFixture[str], gen: Path, tmp_path: Path,
                                         cmd: tuple[str, ...], n: int, i: int) -> None:
    """-o naming one of the command's own inputs: refused in one line, the input keeps its bytes."""
    inv = HAPPY[cmd][n]
    inp = inv[i]
    assert isinstance(inp, In)
    real = resolve(inp.where, gen)
    if inp.kind == "project":  # with the files it names beside it
        shutil.copytree(real.parent, tmp_path / "in")
    copy = tmp_path / "in" / real.name  # a copy: the sample or corpus file itself is never at risk
    copy.parent.mkdir(exist_ok=True)
    copy.write_bytes(real.read_bytes().replace(b"../../../shared/corpus", str(CORPUS).encode()))
    before = copy.read_bytes()
    args = argv(inv, gen, tmp_path, {i: copy})
    args = [str(copy) if isinstance(a, Out) else args[j] for j, a in enumerate(inv)]
    code, out, err = run(capsys, *cmd, *args)
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert copy.read_bytes() == before, "an input was overwritten"
    # refused as an input, or earlier for a reason of its own (a FoE file must be named .bin)
    assert code == 1 and len(lines) == 1 and copy.name in lines[0], f"exit {code}\nstdout: {out}\nstderr: {err}"


def test_scale_startup_without_factor_objects_says_so(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    """Found by the sweep: an ESI without the factor group gave an empty startup list and exit 0."""
    esi = ROOT / ESI.where
    out = tmp_path / "startup.txt"
    code, _, err = run(capsys, "scale", "startup", str(ROOT / SPEC.where), "--esi", str(esi), "-o", str(out))
    assert code == 1 and err.startswith(f"ecattool: error: {esi}: the device has none of the scaling objects")
    assert not out.exists()


@pytest.mark.parametrize("cmd", [("commission", "{p}"), ("lint", "{p}"),
                                 ("startup", "export", "--project", "{p}", "--format", "json")], ids=lambda c: c[0])
@pytest.mark.parametrize("named", ["setup.sw", "../generic_esi/inovance_SV660_EOE_1Axis_V9.12.xml"])
def test_output_over_a_file_a_project_names_is_refused(capsys: pytest.CaptureFixture[str], tmp_path: Path,
                                                       cmd: tuple[str, ...], named: str) -> None:
    """Found by the sweep: -o naming the project's .sw image (or ESI) replaced it with the report."""
    shutil.copytree(ROOT / "samples", tmp_path / "samples")
    project = tmp_path / "samples" / "technosoft_ipos" / "project.yaml"
    if named.endswith(".xml"):  # the same project on an ESI device
        project = project.with_name("esi.yaml")
        project.write_text(f"ecattool: 1\nname: m\ndrives:\n  - name: a\n    device: {{esi: {named}, select: InoSV660N}}\n")
    target = project.parent / named
    before = target.read_bytes()
    code, _, err = run(capsys, *(a.format(p=project) for a in cmd), "-o", str(target))
    assert target.read_bytes() == before
    assert code == 1 and err.startswith(f"ecattool: error: {target}: refusing to overwrite an input file")


def test_sw_build_output_over_its_base_image_is_refused(capsys: pytest.CaptureFixture[str], gen: Path,
                                                        tmp_path: Path) -> None:
    """Found by the sweep: 'sw build -o' over the base image its spec names replaced that image."""
    base = tmp_path / "base.sw"
    base.write_bytes(resolve(SW.where, gen).read_bytes())
    spec = tmp_path / "build.yaml"
    spec.write_text(NESTED["swspec-base"][1].format(ref=base))
    code, _, err = run(capsys, "sw", "build", str(spec), "-o", str(base))
    assert base.read_bytes() == resolve(SW.where, gen).read_bytes()
    assert code == 1 and err.startswith(f"ecattool: error: {base}: refusing to overwrite an input file")


# ------------------------------------------------------------------------------------------ option values
#: A valid invocation of the commands that read no file (the others use their first HAPPY one).
BASE: dict[tuple[str, ...], tuple[object, ...]] = {
    ("sim", "profiles"): (),
    ("sim", "show"): ("technosoft-ipos",),
    ("sim", "serve"): ("hdt", "--list"),  # --list: no interface is opened (tests never touch the host's network)
    ("scale", "si"): ("mm", "rpm"),
    # never a real master here (tests never touch the host's network): a simulator is not held, exit 1; nothing
    # holds a name of this test's own, exit 1
    ("bus", "hold"): ("--target", "sim:hdt", "--for", "1"),
    ("bus", "release"): ("--target", "pysoem:contract-nothing-holds-this"),
}
#: Odd values for every option that takes text or a number (not a file, not a choice: click checks those).
ODD_VALUES = ("", "-1", "99999999999999999999999", "0x", "nonsense", "1:2:3", "\u00e9\u00ff", "6060:00=abc")


def _value_options(cmd: tuple[str, ...]) -> list[str]:
    return [p.opts[-1] for p in LEAVES[cmd].params if isinstance(p, click.Option) and not p.is_flag
            and not isinstance(p.type, (click.Path, click.Choice)) and p.name != "output"]


def test_every_command_has_a_base_invocation() -> None:
    assert set(BASE).isdisjoint(HAPPY) and set(BASE) <= set(LEAVES)
    assert set(LEAVES) == set(HAPPY) | set(BASE), set(LEAVES) - set(HAPPY) - set(BASE)


OPTION_CASES = [(cmd, opt) for cmd in sorted(LEAVES) for opt in _value_options(cmd)]


@pytest.mark.parametrize(("cmd", "opt"), OPTION_CASES, ids=[f"{_name(c)} {o}" for c, o in OPTION_CASES])
def test_odd_option_values_never_trace_back(capsys: pytest.CaptureFixture[str], gen: Path, tmp_path: Path,
                                           cmd: tuple[str, ...], opt: str) -> None:
    """Accepted, a usage error (2), or one line with exit 1: never a traceback."""
    inv = HAPPY[cmd][0] if cmd in HAPPY else BASE[cmd]
    for value in ODD_VALUES:
        code, out, err = run(capsys, *cmd, *argv(inv, gen, tmp_path), opt, value)
        lines = [ln for ln in err.splitlines() if ln.strip()]
        assert "Traceback" not in out + err and code in (0, 1, 2), f"{opt} {value!r}: exit {code}\n{err}"
        if code == 1 and cmd not in REPORTERS:
            assert len(lines) == 1 and lines[0].startswith("ecattool: error: "), f"{opt} {value!r}:\n{out}\n{err}"


def test_startup_format_choices_are_what_the_registry_reads_and_writes() -> None:
    """--from-format offered igh and pysoem, which cannot be read (exit 1 after parsing); now click refuses them."""
    from ecattool.startup.formats import FORMATS

    for cmd in (("startup", "import"), ("startup", "convert"), ("startup", "export")):
        params = {p.name: p.type for p in LEAVES[cmd].params}
        from_format = params["from_format"]
        assert isinstance(from_format, click.Choice)
        assert sorted(from_format.choices) == sorted(n for n, f in FORMATS.items() if f.can_import)
        if "fmt" in params:
            fmt = params["fmt"]
            assert isinstance(fmt, click.Choice)
            assert sorted(fmt.choices) == sorted(n for n, f in FORMATS.items() if f.can_export)


@pytest.mark.parametrize("fmt", ["eni", "twincat", "ros2", "ecmc", "json", "csv", "lcec"])
def test_a_startup_file_forced_into_another_format_is_refused(capsys: pytest.CaptureFixture[str], gen: Path,
                                                              tmp_path: Path, fmt: str) -> None:
    """--from-format FMT on a file of every other format: one line, exit 1 (ecmc read anything as an empty slave)."""
    files = {"eni": corpus_path("configs", "eni_kpierczy_test_eni.xml"),
             "ros2": corpus_path("configs", "ros2_elmo_gold.yaml"),
             "ecmc": corpus_path("configs", "ecmc_ecmciPOSXXXX.cmd"),
             "lcec": corpus_path("configs", "lcec_initcmds_ethercat-conf.xml")}
    for written in ("twincat", "json", "csv", "igh", "pysoem"):
        files[written] = tmp_path / f"startup.{written}"
        assert run(capsys, "startup", "convert", str(resolve(STARTUP.where, gen)), "--format", written, "--lossy",
                   "-o", str(files[written]))[0] == 0
    for other, path in files.items():
        code, _, err = run(capsys, "startup", "import", str(path), "--from-format", fmt)
        lines = [ln for ln in err.splitlines() if ln.strip()]
        if other == fmt:
            assert code == 0, err
        else:
            assert code == 1 and len(lines) == 1 and path.name in lines[0], f"{fmt} <- {other}: exit {code}\n{err}"
