"""The pictures (issue 15): the process-image SVG, the HTML commissioning report and the scaling page.

Structural tests that run everywhere (no browser): the diagram has one box per mapped entry at the entry's
byte.bit offset, gaps and padding are drawn, text from files is escaped, outputs are written atomically,
and without the ``report`` extra every picture option is refused in one line before any work is done.
The browser test is tests/report/test_report_browser.py.
"""

from __future__ import annotations

import sys
import xml.etree.ElementTree as ET
from fractions import Fraction
from pathlib import Path
from typing import Any

import pytest

from ecattool import pdo, profiles
from ecattool.esi.model import Direction
from ecattool.pdo.layout import ImageEntry, Layout, SmImage
from ecattool.project.machine import load_machine
from ecattool.report import diagram, process_image_svg
from tests.conftest import ROOT
from tests.project.project_helpers import run

SVG = "{http://www.w3.org/2000/svg}"
SAMPLES = sorted((ROOT / "samples").glob("*/project.yaml"))
TS = ["--profile", "technosoft-ipos"]


def _classes(el: ET.Element) -> set[str]:
    return set((el.get("class") or "").split())


def _boxes(svg: str) -> list[tuple[str, list[dict[str, str]]]]:
    """Per sync-manager image: its entry/gap/padding groups, each with its bit offset read back from the
    drawing (first rectangle's column and row) and its drawn width in bits."""
    root = ET.fromstring(svg)
    out = []
    for sec in root.iter(f"{SVG}g"):
        if "sm-image" not in _classes(sec):
            continue
        rows = sorted(float(r.get("y", 0)) for r in sec.findall(f"{SVG}rect")
                      if float(r.get("width", 0)) == diagram.BITS_PER_ROW * diagram.BIT_WIDTH)
        boxes = []
        for g in sec.findall(f"{SVG}g"):
            rects = g.findall(f"{SVG}rect")
            first = rects[0]
            col = (float(first.get("x", 0)) - diagram.X0) / diagram.BIT_WIDTH
            row = rows.index(float(first.get("y", 0)))
            drawn = sum(float(r.get("width", 0)) for r in rects) / diagram.BIT_WIDTH
            boxes.append({**g.attrib, "kind": g.get("class", ""), "drawn_bit": str(int(row * diagram.BITS_PER_ROW + col)),
                          "drawn_bits": str(int(drawn)),
                          "text": " ".join(t.text or "" for t in g.findall(f"{SVG}text")),
                          "title": (g.findtext(f"{SVG}title") or "")})
        out.append((sec.get("data-title", ""), boxes))
    return out


@pytest.mark.parametrize("project", SAMPLES, ids=lambda p: p.parent.name)
def test_diagram_has_one_box_per_mapped_entry_at_its_offset(project: Path) -> None:
    result = load_machine(project)
    for rd in result.slaves:
        assert rd.device is not None and rd.mapping is not None
        lay = pdo.layout(rd.device, rd.mapping)
        sections = _boxes(process_image_svg(lay, rd.drive.name))
        assert [t.split(" ")[0] for t, _ in sections] == [f"SM{lay.outputs.sm}", f"SM{lay.inputs.sm}"]
        for img, (_, boxes) in zip((lay.outputs, lay.inputs), sections):
            mapped = [e for e in img.entries if not e.is_gap]
            drawn = [b for b in boxes if b["kind"] == "entry"]
            assert len(drawn) == len(mapped) > 0
            for e, b in zip(mapped, drawn):
                assert b["data-object"] == f"0x{e.index:04X}:{e.subindex:02X}" and b["data-offset"] == e.offset
                assert int(b["drawn_bit"]) == e.bit_offset and int(b["drawn_bits"]) == e.bit_len, (e, b)
                # labelled with object, name and byte.bit (long names are cut to the box, whole in the tooltip)
                assert b["data-object"] in b["text"] and e.offset in b["text"]
                assert e.name in b["title"] and e.offset in b["title"]


def test_gaps_and_padding_are_drawn() -> None:
    device = profiles.load("technosoft-ipos")
    mapping = pdo.Mapping.from_text(rx="0x1600=controlword,gap/8,0x6060:00/8", tx="0x1A00=statusword,gap/3",
                                    device=device)
    (_, outs), (_, ins) = _boxes(process_image_svg(pdo.layout(device, mapping)))
    assert [(b["kind"], b["data-offset"], b["drawn_bits"]) for b in outs] == [
        ("entry", "0.0", "16"), ("gap", "2.0", "8"), ("entry", "3.0", "8")]
    # 19 bits: a 3-bit gap, then 5 unused bits of the third byte
    assert [(b["kind"], b["data-offset"], b["drawn_bits"]) for b in ins] == [
        ("entry", "0.0", "16"), ("gap", "2.0", "3"), ("padding", "2.3", "5")]


def test_entries_across_rows_and_text_from_files_is_escaped() -> None:
    hostile = 'Pos <script>alert("x")</script> & more'
    rx = SmImage(Direction.RX, 2, 0x1000, [0x1600],
                 [ImageEntry(0x1600, 0x6040, 0, 0, 16, "Controlword", "UINT"),
                  ImageEntry(0x1600, 0x607A, 0, 16, 64, hostile, "DINT")])
    tx = SmImage(Direction.TX, 3, 0x1400)
    svg = process_image_svg(Layout(rx, tx))
    assert "<script>" not in svg
    (_, outs), (_, ins) = _boxes(svg)
    assert [(b["drawn_bit"], b["drawn_bits"]) for b in outs] == [("0", "16"), ("16", "64")]
    assert outs[1]["data-name"] == hostile and "(cont.)" in outs[1]["text"]
    assert ins == []


def test_map_layout_svg_cli(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    out = tmp_path / "layout.svg"
    code, stdout, err = run(capsys, "map", "layout", *TS, "--rx", "0x1600=controlword,0x607A:00/32", "--svg", str(out))
    assert code == 0 and "0x607A:00" in stdout and not err  # the table as usual, the picture in the file
    (_, outs), _ = _boxes(out.read_text())
    assert [b["data-object"] for b in outs] == ["0x6040:00", "0x607A:00"]
    code, _, err = run(capsys, "map", "layout", *TS, "--svg", "-", "--json")
    assert code == 2 and "stdout" in err


def test_outputs_are_written_atomically(capsys: pytest.CaptureFixture[str], tmp_path: Path,
                                        monkeypatch: pytest.MonkeyPatch) -> None:
    """A write that fails half-way leaves the previous file and no temporary file behind."""
    import os

    out = tmp_path / "layout.svg"
    out.write_text("previous")

    def broken(*_: object) -> None:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "fsync", broken)
    code, _, err = run(capsys, "map", "layout", *TS, "--svg", str(out), "--force")
    assert code == 1 and err.startswith(f"ecattool: error: {out}: cannot write file: No space left on device")
    assert out.read_text() == "previous" and [p.name for p in tmp_path.iterdir()] == ["layout.svg"]


@pytest.mark.parametrize("argv", [
    ["map", "layout", *TS, "--svg", "{out}"],
    ["commission", str(ROOT / "samples" / "hdt" / "project.yaml"), "--report", "{out}"],
    ["scale", "explain", "--family", "hdt", "6093:01=16384", "6093:02=25", "--html", "{out}"],
    ["scale", "compute", str(ROOT / "samples" / "scaling" / "ballscrew.yaml"), "--html", "{out}"],
], ids=["map-layout-svg", "commission-report", "scale-explain-html", "scale-compute-html"])
def test_missing_extra_is_refused_in_one_line(capsys: pytest.CaptureFixture[str], tmp_path: Path,
                                              monkeypatch: pytest.MonkeyPatch, argv: list[str]) -> None:
    for name in ("jinja2", "matplotlib"):
        monkeypatch.setitem(sys.modules, name, None)  # import raises ImportError, as where it is not installed
    out = tmp_path / "out.file"
    code, stdout, err = run(capsys, *(a.format(out=out) for a in argv))
    lines = err.splitlines()
    assert code == 1 and len(lines) == 1 and "pip install 'ecattool[report]'" in lines[0], err
    assert not out.exists() and not stdout


# ------------------------------------------------------------------------------------------ the run's trace
def test_trace_records_the_startup_list_as_the_drive_received_it() -> None:
    from ecattool.commission import commission
    from ecattool.commission.runner import open_target
    from ecattool.target.sim import SimTarget

    path = ROOT / "samples" / "technosoft_ipos" / "project.yaml"
    drives = open_target("sim", load_machine(path).slaves)[0].slaves()
    (dr,) = commission(path, target=SimTarget(drives)).drives
    trace = dr.trace
    # every write the drive received, in order: the .sw download's writes, then the startup list
    received = [(e.data["index"], e.data["subindex"]) for e in drives[0].events  # type: ignore[attr-defined]
                if e.kind == "sdo_download"]
    sent = [(int(w.address[2:6], 16), int(w.address[7:], 16)) for w in trace.startup]
    assert len(sent) == 50 and received[-len(sent):] == sent
    assert all(w.ok and w.result == "ok" for w in trace.startup)
    assert all(w.verified and w.read_back == w.data for w in trace.startup if w.read_back is not None)
    assert trace.startup[0].source == "" and trace.startup[-1].source.startswith(f"{path}:")
    # the three .sw blocks, written because the fresh drive held none of them
    assert len(trace.sw_blocks) == 3 and all(b.written and b.ok and b.after == b.expected for b in trace.sw_blocks)
    # EtherCAT states in order, then the CiA-402 enable sequence with the controlwords that caused it
    assert [e.state for e in trace.events if e.layer == "ethercat"] == ["INIT", "PREOP", "INIT", "PREOP", "SAFEOP", "OP"]
    cia = [(e.state, e.controlword) for e in trace.events if e.layer == "cia402"]
    assert cia[-3:] == [("ready to switch on", 0x0006), ("switched on", 0x0007), ("operation enabled", 0x000F)]
    # the move: 1000 um = 1200 counts, sampled from start to end in user and internal units
    first, last = trace.samples[0].values, trace.samples[-1].values
    assert (first["actual"], last["actual"], last["target"]) == (0, 1000, 1000)
    assert (first["internal"], last["internal"]) == (0, 1200)
    assert trace.units == {"position": "um", "velocity": "mm/s"} and trace.counts_per_unit == Fraction(6, 5)


def test_a_failed_write_is_in_the_trace_and_the_report(tmp_path: Path) -> None:
    from ecattool.commission import commission
    from ecattool.commission.runner import open_target
    from ecattool.report import commission_html
    from ecattool.target.sim import SimTarget

    path = ROOT / "samples" / "hdt" / "project.yaml"
    drives = open_target("sim", load_machine(path).slaves)[0].slaves()
    drives[0].faults.abort_sdo(4, 0x06090030)  # type: ignore[attr-defined]  # the first startup write
    report = commission(path, target=SimTarget(drives))
    (dr,) = report.drives
    assert not dr.ok and [(w.address, w.ok) for w in dr.trace.startup] == [("0x6093:01", False)]
    assert "0x06090030" in dr.trace.startup[0].result
    page = _page(commission_html([report]))
    row = page.xpath("//table[@class='startup']//tr[td]")[0]
    assert "0x6093:01" in row.text_content() and row.xpath("td[@class='bad']") and "FAILED" in page.text_content()
    assert page.xpath("//*[@class='move']/following-sibling::p[1]")[0].text_content().startswith("No move was made")


def test_trace_through_the_pysoem_target() -> None:
    """The same runner on the pysoem target (a fake pysoem over simulated drives) fills the same trace."""
    from ecattool.commission import commission
    from ecattool.commission.runner import open_target
    from tests.commission.test_commission_pysoem import pysoem_on

    path = ROOT / "samples" / "controltechniques" / "project.yaml"
    drives = open_target("sim", load_machine(path).slaves)[0].slaves()
    target, _ = pysoem_on(drives)
    (dr,) = commission(path, target=target).drives
    assert dr.ok and dr.trace.startup and dr.trace.events[-1].state == "operation enabled"
    assert dr.trace.samples[-1].values["actual"] == 5000 and dr.trace.cycle_s == 0.001  # 60C2h as the project sets it


def test_long_moves_are_thinned_not_cut() -> None:
    from ecattool.commission import trace as tr

    t = tr.DriveTrace()

    class Io:  # the two things a sample reads
        in_pos = {(0x6064, 0): None}
        out_pos: dict[object, object] = {}

        def has(self, index: int, sub: int) -> bool:
            return index == 0x6064

        def read(self, index: int, sub: int) -> int:
            return t.cycles

    io = Io()
    t.begin_move(io, "test")  # type: ignore[arg-type]
    for _ in range(10_000):
        t.cycles += 1
        if t._sampling and (t.cycles - t._move_start) % t._every == 0:
            t._sample(io)  # type: ignore[arg-type]
    t.end_move(io)  # type: ignore[arg-type]
    cycles = [s.cycle for s in t.samples]
    assert len(cycles) < tr.MAX_SAMPLES and cycles[0] == 0 and cycles[-1] == 10_000
    assert all(s.values["actual"] == s.cycle for s in t.samples)
    steps = {b - a for a, b in zip(cycles, cycles[1:-1])}
    assert len(steps) == 1  # evenly spaced


# ------------------------------------------------------------------------------------------ the HTML report
def _page(html: str) -> Any:
    import lxml.html

    return lxml.html.fromstring(html)


@pytest.fixture(scope="module")
def sample_report(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    """``commission --report`` over the four samples, once for the module."""
    from ecattool.cli import main

    out = tmp_path_factory.mktemp("report") / "report.html"
    try:
        main(["commission", *map(str, SAMPLES), "--report", str(out), "--json"])
    except SystemExit as exc:
        assert exc.code == 0
    return out, out.read_text(encoding="utf-8")


def test_report_of_the_four_samples_has_every_section(sample_report: tuple[Path, str]) -> None:
    _, html = sample_report
    page = _page(html)
    assert "http://" not in html.replace('xmlns="http://www.w3.org/2000/svg"', "").replace(
        'xmlns:xlink="http://www.w3.org/1999/xlink"', "").replace("http://www.w3.org/1999/02/22-rdf", "").replace(
        "http://purl.org/dc", "").replace("http://creativecommons.org", "") and "https://" not in html
    assert not page.xpath("//script|//link|//img|//iframe")  # self-contained: nothing fetched, nothing run
    projects = page.xpath("//h2[@class='project']")
    assert [p.text.split()[1] for p in projects] == [str(s) for s in SAMPLES]
    assert len(page.xpath("//h3[@class='findings']")) == 4
    for project in SAMPLES:
        result = load_machine(project)
        for rd in result.slaves:
            (sec,) = [s for s in page.xpath("//section[@class='drive']") if rd.drive.name in s.findtext("h3")]
            assert "OK" in sec.findtext("h3/span") and "vendor 0x" in sec.xpath(".//table[@class='identity']")[0].text_content()
            # the diagram: one box per mapped entry
            lay = pdo.layout(rd.device, rd.mapping)
            mapped = [e for e in (*lay.outputs.entries, *lay.inputs.entries) if not e.is_gap]
            boxes = sec.xpath(".//div[contains(@class,'diagram')]//*[local-name()='g'][@class='entry']")
            assert [(b.get("data-object"), b.get("data-offset")) for b in boxes] == [
                (f"0x{e.index:04X}:{e.subindex:02X}", e.offset) for e in mapped]
            # the startup list as sent: every command of the project, each with its data, result and read-back
            rows = sec.xpath(".//table[@class='startup']//tr[td]")
            assert len(rows) == len(rd.startup)
            for row, cmd in zip(rows, rd.startup):
                cells = [c.text_content().strip() for c in row.xpath("td")]
                assert cells[2].startswith(cmd.address) and cells[3] == cmd.data.hex(" ") and cells[6] == "ok"
            assert bool(sec.xpath(".//table[@class='sw']//td[text()='verified']")) == (rd.sw_image is not None)
            # the state timeline and the plots of the move, with their labels (text, not paths)
            assert sec.xpath(".//div[contains(@class,'timeline')]//*[local-name()='svg']")
            assert "operation enabled" in sec.xpath(".//table[@class='events']")[0].text_content()
            plots = sec.xpath(".//div[contains(@class,'plot')]")
            titles = [p.get("data-title") for p in plots]
            assert titles[0].startswith("Position (user units") and titles[1].startswith("Velocity (user units")
            assert ("Internal units (counts)" in titles) == (rd.device.dictionary.entry(0x6063, 0) is not None)
            for p in plots:
                assert p.get("data-title") in " ".join(t.text_content() for t in p.xpath(".//*[local-name()='text']"))


def test_report_ids_are_unique(sample_report: tuple[Path, str]) -> None:
    import re
    from collections import Counter

    ids = Counter(re.findall(r'\bid="([^"]+)"', sample_report[1]))
    assert ids and not [i for i, n in ids.items() if n > 1]


def test_time_base_is_the_drives_interpolation_period() -> None:
    """The HDT TomCat's default 60C2h is 2 ms: its 90 deg at 90 deg/s, ramped up at 360 deg/s² (6083h) and down
    at 1000 deg/s² (6084h default), take 0.25 + 0.83 + 0.09 s = 585 cycles, plus the jerk-limited rounding
    (6086h = 3: 2011h = 100000 deg/s³ limits the jerk, a / 2J + d / 2J = 1.8 + 5 ms; issue 33)."""
    from fractions import Fraction

    from ecattool.commission import commission
    from ecattool.sim.ramp import profile_time

    (dr,) = commission(ROOT / "samples" / "hdt" / "project.yaml").drives
    t = dr.trace
    seconds = profile_time(Fraction(90), Fraction(90), Fraction(360), Fraction(1000)) + Fraction(68, 10_000)
    assert t.cycle_s == 0.002
    # the move's cycles until it reached its target (the samples go on while the plant settles)
    assert t.move_cycles is not None and t.samples[0].cycle == t.move_cycles[0]
    assert abs(t.move_cycles[1] - t.move_cycles[0] - seconds / Fraction(2, 1000)) <= 2
    speeds = {s.values["velocity"] for s in t.samples}
    assert {0, 90} <= speeds and len(speeds) > 10  # the ramps: every speed between 0 and 90 deg/s


def test_velocity_from_integer_positions_is_steady() -> None:
    """One unit every 11 cycles (HDT's whole degrees at 90 deg/s, 1 ms) is a steady 90.9 units/s, not spikes."""
    from ecattool.report.plots import derivative

    cycles = list(range(1000))
    positions = [c // 11 for c in cycles]
    v, window = derivative(cycles, positions, 0.001)
    assert window > 11 and all(abs(x - 1000 / 11) < 1000 / 11 * 0.05 for x in v[window:-window])
    assert derivative([0, 1, 2], [0, 5, 10], 0.5)[0] == [10.0, 10.0, 10.0]
