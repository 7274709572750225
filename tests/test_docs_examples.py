"""The examples in README.md and docs/ work as written.

* every ```python block of README.md and docs/*.md runs (blocks of one page in order, in one namespace), in a
  directory where the file names the docs use exist: the corpus files by their own names, ``samples/``, and
  the few placeholder names of the docs (``drive.xml``, ``axis1.sw`` …) standing for a corpus or sample file;
* the README "Library" snippet gives the results its comments promise;
* the format examples of docs/startup.md are what the exporters write for the slave the page describes;
* the project file of docs/project.md and the ``sim run`` script of docs/simulator.md pass as shown.

A renamed function, a changed signature or exporter output that drifts from its page fails here.
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterator
from pathlib import Path

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


def test_readme_library_snippet_does_what_its_comments_say(docs_dir: Path) -> None:
    (code,) = [b for b in blocks("README.md", "python") if "commission(" in b]
    ns: dict[str, object] = {}
    exec(compile(code, "README.md Library", "exec"), ns)
    from ecattool.commission import CommissionReport
    from ecattool.esi.model import Device
    from ecattool.startup import StartupList

    device, findings, startup, report = ns["device"], ns["findings"], ns["startup"], ns["report"]
    assert isinstance(device, Device) and device.revision == 0x00010420
    assert findings == []
    assert isinstance(startup, StartupList)
    assert {c.index for c in startup.commands} >= {0x1C12, 0x1C13, 0x1607, 0x1A07}
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

    assert export(startup_example(), fmt).rstrip("\n") == section_block("docs/startup.md", FULL_EXAMPLES[fmt]).rstrip("\n")


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
