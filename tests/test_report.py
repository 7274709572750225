"""The pictures (issue 15): the process-image SVG, the HTML commissioning report and the scaling page.

Structural tests that run everywhere (no browser): the diagram has one box per mapped entry at the entry's
byte.bit offset, gaps and padding are drawn, text from files is escaped, outputs are written atomically,
and without the ``report`` extra every picture option is refused in one line before any work is done.
The browser test is tests/test_report_browser.py.
"""

from __future__ import annotations

import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from ecattool import pdo, profiles
from ecattool.esi.model import Direction
from ecattool.pdo.layout import ImageEntry, Layout, SmImage
from ecattool.project.lint import lint_project
from ecattool.report import diagram, process_image_svg
from tests.conftest import ROOT
from tests.project_helpers import run

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
    result = lint_project(project)
    for rd in result.drives:
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
    assert code == 0 and not stdout and not err
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
    code, _, err = run(capsys, "map", "layout", *TS, "--svg", str(out))
    assert code == 1 and err.startswith(f"ecattool: error: {out}: cannot write file: No space left on device")
    assert out.read_text() == "previous" and [p.name for p in tmp_path.iterdir()] == ["layout.svg"]


@pytest.mark.parametrize("argv", [["map", "layout", *TS, "--svg", "{out}"]], ids=["map-layout-svg"])
def test_missing_extra_is_refused_in_one_line(capsys: pytest.CaptureFixture[str], tmp_path: Path,
                                              monkeypatch: pytest.MonkeyPatch, argv: list[str]) -> None:
    for name in ("jinja2", "matplotlib"):
        monkeypatch.setitem(sys.modules, name, None)  # import raises ImportError, as where it is not installed
    out = tmp_path / "out.file"
    code, stdout, err = run(capsys, *(a.format(out=out) for a in argv))
    lines = err.splitlines()
    assert code == 1 and len(lines) == 1 and "pip install 'ecattool[report]'" in lines[0], err
    assert not out.exists() and not stdout
