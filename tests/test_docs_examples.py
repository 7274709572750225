"""The examples in README.md and docs/ work as written.

* every ```python block of README.md and docs/*.md runs (blocks of one page in order, in one namespace), in a
  directory where the file names the docs use exist: the corpus files by their own names, ``samples/``, and
  the few placeholder names of the docs (``drive.xml``, ``axis1.sw`` …) standing for a corpus or sample file;
* the README "Library" snippet gives the results its comments promise;
* the format examples of docs/startup.md are what the exporters write for the slave the page describes;
* the project file of docs/project.md and the ``sim run`` script of docs/simulator.md pass as shown.
* every shell block (```sh, ```console) of README.md and docs/ runs, page by page in one directory that holds
  the files the docs name: each command exits as the page says (0 unless it shows the failure), except the few
  lines NOT_RUN says why (a real bus, the network, pip); the virtual-bus recipes run as root in their own network
  namespace, exit 0 and leave nothing running;
* the pre-commit hooks' file pattern takes every project file name the docs use.

A renamed function, a changed signature or exporter output that drifts from its page fails here.
"""

from __future__ import annotations

import os
import re
import sys
from collections.abc import Iterator
from pathlib import Path

import click
import pytest

from ecattool.errors import SdoAbort
from tests.conftest import CORPUS, ROOT, corpus_path, need_corpus, run

#: Placeholder names used in the docs -> the file that stands for them (relative to ROOT or the corpus).
PLACEHOLDERS: dict[str, Path] = {
    "drive.xml": CORPUS / "esi" / "elmo_Elmo_ECAT_00010420_V11.xml",
    "axis1.sw": CORPUS / "sw" / "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.sw",
    "custom_slave.xml": ROOT / "samples" / "sii" / "custom_slave.xml",
    "board.bin": ROOT / "samples" / "sii" / "custom_slave.bin",
    "machine.yaml": ROOT / "samples" / "hdt" / "project.yaml",
    "ETG/v1.17": CORPUS / "xsd" / "v1.17",
}

#: What a block needs that its page leaves to the reader (a slave to talk to, bytes of a file).
PREAMBLE: dict[tuple[str, int], str] = {
    ("sw.md", 0): "from ecattool.sim import Drive\nslave = Drive.from_profile('technosoft-ipos')\n",
    ("esi.md", 0): "data = open('drive.xml', 'rb').read()\n",
}

#: Blocks whose last statement is documented to raise.
RAISES: dict[tuple[str, int], type[BaseException]] = {
    ("simulator.md", 1): SdoAbort,  # "SdoAbort 0609 0030h (reserved)"
}

PAGES = ["README.md", *sorted(p.relative_to(ROOT).as_posix() for p in (ROOT / "docs").glob("*.md"))]


def blocks(page: str, lang: str) -> list[str]:
    text = (ROOT / page).read_text(encoding="utf-8")
    return re.findall(rf"^```{lang}\n(.*?)^```", text, re.S | re.M)


def section_block(page: str, heading: str) -> str:
    """The first fenced block after the heading line ``heading`` of ``page``."""
    text = (ROOT / page).read_text(encoding="utf-8")
    start = text.index(heading + "\n")
    m = re.compile(r"^```\w*\n(.*?)^```", re.S | re.M).search(text, start)
    assert m is not None, f"{page}: no code block after {heading!r}"
    return m.group(1)


@pytest.fixture
def docs_dir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    """A working directory holding every file name the docs use."""
    need_corpus()
    for sub in ("esi", "sii", "sw", "configs", "eds"):
        for f in (CORPUS / sub).iterdir():
            (tmp_path / f.name).symlink_to(f)
    (tmp_path / "samples").symlink_to(ROOT / "samples")
    for name, target in PLACEHOLDERS.items():
        dest = tmp_path / name
        dest.parent.mkdir(parents=True, exist_ok=True)
        assert target.exists(), target
        dest.symlink_to(target)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("ECATTOOL_CACHE_DIR", str(tmp_path / ".cache"))
    yield tmp_path


@pytest.mark.parametrize("page", [p for p in PAGES if blocks(p, "python")])
def test_python_blocks_run_as_written(docs_dir: Path, page: str) -> None:
    namespace: dict[str, object] = {"__name__": "docs_example"}
    name = Path(page).name
    for i, code in enumerate(blocks(page, "python")):
        source = PREAMBLE.get((name, i), "") + code
        compiled = compile(source, f"{page} python block {i + 1}", "exec")
        expected = RAISES.get((name, i))
        if expected is None:
            exec(compiled, namespace)
        else:
            with pytest.raises(expected):
                exec(compiled, namespace)


def test_readme_library_snippet_does_what_its_comments_say(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # it names files of the repository only: it runs in a fresh clone as written, with no corpus beside it
    (tmp_path / "samples").symlink_to(ROOT / "samples")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("ECATTOOL_CACHE_DIR", str(tmp_path / ".cache"))
    (code,) = [b for b in blocks("README.md", "python") if "commission(" in b]
    ns: dict[str, object] = {}
    exec(compile(code, "README.md Library", "exec"), ns)
    from ecattool.commission import CommissionReport
    from ecattool.esi.model import Device
    from ecattool.startup import StartupList

    device, findings, startup, report = ns["device"], ns["findings"], ns["startup"], ns["report"]
    assert isinstance(device, Device) and (device.product_code, device.revision) == (0x000C010D, 0x00010000)
    assert findings == []
    assert isinstance(startup, StartupList)
    assert {c.index for c in startup.commands} >= {0x1C12, 0x1C13, 0x1600, 0x1A00}
    assert isinstance(report, CommissionReport) and report.ok


# --------------------------------------------------------------------------------- docs/startup.md formats
def startup_example():
    """The slave of docs/startup.md, "Examples of every format": an iPOS at position 0 with a PDO
    programming sequence, one signed parameter, the assigned PDOs and DC SYNC0 at 1 ms."""
    from ecattool import pdo, profiles
    from ecattool.esi.model import Direction, Identity, Pdo, PdoEntry
    from ecattool.startup import SlaveConfig, StartupCommand, StartupList

    device = profiles.load("technosoft-ipos", product="ipos4808-bx-cat")
    mapping = pdo.Mapping.from_text(rx="0x1600=controlword,0x607A:00/32", device=device)
    commands = [*pdo.program(device, mapping).commands,
                StartupCommand("PS", 0x60C2, 2, b"\xfd", comment="interpolation time index", type_name="SINT", value=-3)]
    rx = [Pdo(Direction.RX, 0x1600, "RxPDO1", [PdoEntry(0x6040, 0, 16, "Controlword", "UINT"),
                                               PdoEntry(0x607A, 0, 32, "Target position", "DINT")])]
    tx = [Pdo(Direction.TX, 0x1A00, "TxPDO1", [PdoEntry(0x6041, 0, 16, "Statusword", "UINT"),
                                               PdoEntry(0x6064, 0, 32, "Position actual value", "DINT")])]
    return SlaveConfig(StartupList(commands, name="Axis1"), name="Axis1", position=0,
                       identity=Identity(0x1A3, 0x019F418D, 0), rx_pdos=rx, tx_pdos=tx,
                       dc_assign_activate=0x0300, dc_cycle_ns=1_000_000, dc_shift_ns=0)


FULL_EXAMPLES = {"twincat": "### TwinCAT startup lines (`twincat`)", "igh": "### IgH C (`igh`)",
                 "pysoem": "### pysoem (`pysoem`)", "ros2": "### ethercat_driver_ros2 (`ros2`)",
                 "ecmc": "### ecmc (`ecmc`)", "csv": "### CSV (`csv`)"}
#: Abbreviated with "…": every other line must appear in the output, in order.
EXCERPTS = {"eni": "### ENI (`eni`)", "json": "### JSON (`json`)"}


@pytest.mark.parametrize("fmt", sorted(FULL_EXAMPLES))
def test_startup_format_example_is_what_the_exporter_writes(fmt: str) -> None:
    from ecattool.startup import export

    # lossy: TwinCAT lines and CSV have no DC (docs/startup.md says so); the other formats carry all of it
    assert export(startup_example(), fmt, lossy=fmt in ("twincat", "csv")).rstrip("\n") == \
        section_block("docs/startup.md", FULL_EXAMPLES[fmt]).rstrip("\n")


@pytest.mark.parametrize("fmt", sorted(EXCERPTS))
def test_startup_format_excerpt_is_in_what_the_exporter_writes(fmt: str) -> None:
    from ecattool.startup import export

    out = iter(line.strip() for line in export(startup_example(), fmt).splitlines())
    shown = [line.strip() for line in section_block("docs/startup.md", EXCERPTS[fmt]).splitlines()]
    for line in shown:
        if "…" in line or not line:
            continue
        assert any(o == line for o in out), f"{fmt}: {line!r} is not written (or not in this order)"


# ------------------------------------------------------------------------ project and sim run examples
def test_project_example_lints_clean(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                     monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("ECATTOOL_CACHE_DIR", str(tmp_path / ".cache"))
    (tmp_path / "esi").mkdir()
    (tmp_path / "esi" / "elmo_Elmo_ECAT_00010420_V11.xml").symlink_to(corpus_path("esi", "elmo_Elmo_ECAT_00010420_V11.xml"))
    (tmp_path / "setups").mkdir()
    (tmp_path / "setups" / "x_axis.sw").symlink_to(corpus_path("sw", "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.sw"))
    project = tmp_path / "machine.yaml"
    project.write_text(blocks("docs/project.md", "yaml")[0], encoding="utf-8")
    code, out, err = run(capsys, "lint", "--strict", str(project))
    assert (code, err) == (0, ""), out
    assert "2 drive(s), 0 error(s), 0 warning(s)" in out


def test_sim_script_example_runs(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    text = section_block("docs/simulator.md", "### Script format (YAML or JSON list)")
    script = tmp_path / "steps.yaml"
    script.write_text(text, encoding="utf-8")
    code, out, _ = run(capsys, "sw", "foe", str(corpus_path("sw", "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.sw")),
                       "-o", str(tmp_path / "FOESW_AXIS01.bin"))
    assert code == 0
    os.replace(tmp_path / "FOESW_AXIS01.bin", tmp_path / "setup.bin")
    code, out, err = run(capsys, "sim", "run", "technosoft-ipos", str(script))
    assert (code, err) == (0, ""), out
    assert len(out.splitlines()) == len(re.findall(r"^- ", text, re.M)) and "ERR" not in out


# ------------------------------------------------------------------------------------ shell blocks run as written
#: Lines of shell blocks that are not run here, and why (each is the only line of its kind in the docs).
NOT_RUN = {
    "python3 scripts/dev.py": "sets up .venv and runs this very suite (its demo is the `commission samples/*` of "
                              "docs/report.md)",
    "pysoem:eth0": "a real bus on eth0",
    "pip install": "installs packages",
    "curl ": "fetches from the network",
    "ethercat sii_": "IgH's tool writing a real EEPROM (readback.bin stands for what it reads back)",
}
#: Commands the docs show failing, by page and a part of the command: the exit status they document.
EXPECTED_STATUS = {
    ("docs/pdo-mapping.md", '0x60FF:00/32"'): 1,  # PDO009 + PDO013, "echo $?" prints 1
    ("docs/sii.md", "sii check edited.bin"): 1,  # the checksum error fix-crc repairs
    ("docs/esi.md", "esi validate copley_XE2_4.60.xml"): 1,  # "exit 1: the vendor's own schema errors"
    ("docs/sii.md", "sii diff factory.bin rebuilt.bin"): 1,  # "1 difference(s)"
}
#: Blocks that need a private network namespace (docs/virtual-bus.md): run by test_virtual_bus_recipes_run.
NETNS_PAGES = {"docs/virtual-bus.md"}
SHELL_FENCE = re.compile(r"^```(?:sh|bash|shell|console)\n(.*?)^```", re.S | re.M)


def shell_blocks(page: str) -> list[str]:
    return SHELL_FENCE.findall((ROOT / page).read_text(encoding="utf-8"))


def shell_commands(block: str) -> list[str]:
    """The commands of a block: with ``$ `` prompts, the prompted lines (the others are output); else every
    line that is not a comment; a line ending in a backslash goes on; a quote left open spans lines."""
    lines = block.splitlines()
    prompted = any(line.startswith("$ ") for line in lines)
    if not prompted and any(line.startswith(("for ", "while ", "if ")) for line in lines):
        return [block.rstrip("\n")]  # one compound command
    out: list[str] = []
    current: str | None = None
    for line in lines:
        if current is not None:
            current += "\n" + line
        elif prompted:
            if not line.startswith("$ "):
                continue
            current = line[2:]
        elif line.strip() and not line.lstrip().startswith("#"):
            current = line
        else:
            continue
        if current.endswith("\\") or current.count("'") % 2:
            continue
        out.append(current)
        current = None
    return out


def _env(work: Path) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "COLUMNS")}
    # the ecattool (and python) of the interpreter running the tests, whatever the shell's PATH says
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    env["ECATTOOL_CACHE_DIR"] = str(work / ".cache")
    return env


def _doc_files(root: Path) -> Path:
    """``root/work``: every file name the shell blocks use (the corpus also as ../shared/corpus, as the docs
    write it), and the files a reader would have made before (a mapping file, a changed EEPROM image …)."""
    need_corpus()
    work = root / "work"
    work.mkdir()
    (root / "shared").mkdir()
    (root / "shared" / "corpus").symlink_to(CORPUS)
    for sub in ("esi", "sii", "sw", "configs", "eds"):
        for f in (CORPUS / sub).iterdir():
            (work / f.name).symlink_to(f)
    for name in ("samples", "tests"):
        (work / name).symlink_to(ROOT / name)
    for name, target in PLACEHOLDERS.items():
        if name != "machine.yaml":
            (work / name).parent.mkdir(parents=True, exist_ok=True)
            (work / name).symlink_to(target)
    # machine.yaml is the project of docs/project.md, with the files it names
    (work / "machine.yaml").write_text(blocks("docs/project.md", "yaml")[0], encoding="utf-8")
    (work / "esi").mkdir()
    (work / "esi" / "elmo_Elmo_ECAT_00010420_V11.xml").symlink_to(CORPUS / "esi" / "elmo_Elmo_ECAT_00010420_V11.xml")
    (work / "setups").mkdir()
    (work / "setups" / "x_axis.sw").symlink_to(CORPUS / "sw" / "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.sw")
    (work / "machines").mkdir()
    (root / "drives").mkdir()
    (root / "drives" / "elmo.xml").symlink_to(CORPUS / "esi" / "elmo_Elmo_ECAT_00010420_V11.xml")
    (work / "drives").symlink_to(root / "drives")
    (work / "mapping.yaml").write_text("rx: [{index: 0x1607, entries: [controlword, '0x607A:00/32']}]\n"
                                       "tx: [{index: 0x1A07, entries: [statusword, '0x6064:00/32']}]\n")
    image = (ROOT / "samples" / "sii" / "custom_slave.bin").read_bytes()
    (work / "readback.bin").write_bytes(image)
    (work / "factory.bin").write_bytes(image)
    (work / "edited.bin").write_bytes(image[:14] + bytes([image[14] ^ 0x55]) + image[15:])  # a wrong checksum
    changed = bytearray(image)
    changed[0x08:0x0A] = b"\x10\x00"  # the station alias (word 4): rebuilt differs from factory in one field
    (work / "rebuilt.bin").write_bytes(bytes(changed))
    code = run_main(["scale", "startup", str(ROOT / "samples/scaling/ballscrew.yaml"), "--format", "eni", "--lossy",
                     "-o", str(work / "drive_startup.xml")])
    assert code == 0
    return work


def run_main(argv: list[str]) -> int:
    from ecattool.cli import main

    try:
        main(argv)
    except SystemExit as exc:
        return exc.code if isinstance(exc.code, int) else 0
    return 0


SHELL_PAGES = [p for p in PAGES if shell_blocks(p) and p not in NETNS_PAGES]


@pytest.mark.parametrize("page", SHELL_PAGES)
def test_shell_blocks_run_as_written(tmp_path: Path, page: str) -> None:
    """Every command of the page's shell blocks, in order, in one directory: it exits as the page says (0 unless
    the page shows it failing), in one line of error at most."""
    import shutil
    import subprocess

    work = _doc_files(tmp_path)
    ran = skipped = 0
    for block in shell_blocks(page):
        for command in shell_commands(block):
            if any(marker in command for marker in NOT_RUN):
                skipped += 1
                continue
            expected = next((s for (pg, part), s in EXPECTED_STATUS.items() if pg == page and part in command), 0)
            if "zsh_source" in command or "fish_source" in command:
                shell = "zsh" if "zsh" in command else "fish"
                if shutil.which(shell) is None:  # the completion script is still made as written
                    command = f"_ECATTOOL_COMPLETE={shell}_source ecattool | grep -q {shell[0]}"
                else:
                    done = subprocess.run([shell, "-c", command], cwd=work, env=_env(work), capture_output=True,
                                          text=True, timeout=60)
                    assert done.returncode == 0, f"{page}: {command}\n{done.stderr}"
                    ran += 1
                    continue
            done = subprocess.run(["bash", "-o", "pipefail", "-c", command], cwd=work, env=_env(work),
                                  capture_output=True, text=True, timeout=120)
            assert done.returncode == expected, f"{page}: `{command}` exited {done.returncode}\n{done.stderr[-2000:]}"
            assert "Traceback" not in done.stderr, done.stderr
            ran += 1
    assert ran or skipped, f"{page}: no command"


def test_every_shell_block_is_run_or_says_why_not() -> None:
    for page in PAGES:
        for block in shell_blocks(page):
            commands = shell_commands(block)
            assert commands, f"{page}: a shell block without a command:\n{block}"
            for command in commands:
                assert command.split()[0] in ("ecattool", "eval", "_ECATTOOL_COMPLETE=fish_source", "unshare", "for",
                                              "python3", "pip", "curl", "ethercat", "echo") or page in NETNS_PAGES, command


def _processes_in(directory: Path) -> list[str]:
    """The command lines of the processes whose working directory is ``directory`` (what a recipe left running)."""
    out = []
    for proc in Path("/proc").iterdir():
        try:
            if proc.name.isdigit() and Path(os.readlink(proc / "cwd")) == directory:
                out.append((proc / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace"))
        except OSError:
            continue
    return out


def _serve_help_recipe() -> str:
    """The recipe `ecattool sim serve --help` prints under "Run it inside a private network namespace", as a user
    would copy it from the terminal (the help's indent removed)."""
    from ecattool.cli import cli

    serve = cli.get_command(click.Context(cli), "sim").get_command(click.Context(cli), "serve")  # type: ignore[union-attr]
    epilog = serve.epilog or ""
    lines = epilog[epilog.index("unshare -n"):].splitlines()
    recipe = [line[2:] if line.startswith("  ") else line for line in lines]
    return "\n".join(line for line in recipe if not line.startswith("(")).strip()


def test_the_serve_help_recipe_is_the_documented_one() -> None:
    """`sim serve --help` shows the recipe docs/virtual-bus.md runs (the old one left the server running)."""
    recipe = _serve_help_recipe()
    assert recipe.startswith("unshare -n sh -c") and "trap" in recipe and "ecattool sim serve" in recipe
    assert "(ecattool sim serve" not in recipe


@pytest.mark.xdist_group("wire")
def test_virtual_bus_recipes_run(tmp_path: Path) -> None:
    """The recipes of docs/virtual-bus.md, pasted as written (each starts its own private network namespace with
    `unshare -n`): they exit 0 and leave nothing running. A bus on a loaded machine can miss a cycle: one rerun."""
    import importlib.util
    import subprocess

    from ecattool.sim.bus import netns

    if os.geteuid() != 0:
        pytest.skip("the recipes are written for root (unshare -n)")
    why = netns.unavailable()
    if why:
        pytest.skip(why)
    work = tmp_path.resolve()
    for name in ("samples", "tests"):
        (work / name).symlink_to(ROOT / name)
    needs = {"wire_kickcat_scenario": "kickcat", "pysoem:": "pysoem"}
    ran = 0
    for block in [*shell_blocks("docs/virtual-bus.md"), _serve_help_recipe()]:
        missing = [m for key, m in needs.items() if key in block and importlib.util.find_spec(m) is None]
        if missing:
            continue  # the wire tests say why (the master is not installed here)
        for attempt in (1, 2):
            done = subprocess.run(["bash", "-c", block], cwd=work, env=_env(work), capture_output=True, text=True,
                                  timeout=180)
            if done.returncode == 0 or attempt == 2:
                break
        assert done.returncode == 0, f"{block}\nexited {done.returncode}\n{done.stdout[-1500:]}\n{done.stderr[-1500:]}"
        assert _processes_in(work) == [], "the recipe left processes running"
        ran += 1
    if not ran:
        pytest.skip("neither pysoem nor kickcat is installed (the 'wire' extra)")


def test_the_pre_commit_hooks_lint_the_project_files_the_docs_name() -> None:
    import yaml

    hooks = yaml.safe_load((ROOT / ".pre-commit-hooks.yaml").read_text(encoding="utf-8"))
    patterns = {h["id"]: re.compile(h["files"]) for h in hooks}
    assert set(patterns) == {"ecattool-lint", "ecattool-lint-strict"}
    # every project file a lint or commission command of the docs names (a glob stands for a file it matches)
    named = set()
    for page in PAGES:
        for block in shell_blocks(page):
            for command in shell_commands(block):
                words = command.split()
                if words[:2] in (["ecattool", "lint"], ["ecattool", "commission"]):
                    named |= {w for w in words if w.endswith((".yaml", ".yml")) and not w.startswith("-")}
    files = {n.replace("*", "line1") for n in named} | {"project.yaml", "x.ecattool.yaml", "a/machines/b.yml"}
    assert {"machine.yaml", "machines/line1.yaml", "samples/technosoft_ipos/project.yaml"} <= files
    for name, pattern in patterns.items():
        for f in sorted(files):
            assert pattern.search(f), f"{name} skips {f}"
        for other in ("samples/scaling/ballscrew.yaml", ".github/workflows/ci.yml", "mapping.yaml", "machines.yaml"):
            assert not pattern.search(other), f"{name} would lint {other}"
