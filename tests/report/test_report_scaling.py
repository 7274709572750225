"""The scaling page (issue 15 item 2): what `scale compute/explain --html` shows, read back from the page.

The chain encoder → gear → transmission → user unit must carry the values the factor group was computed
from, name the objects each link comes from and the mechanical part, and the cross-check 608Fh × 6091h ÷ 6092h
against 6093h must say when the objects disagree.
"""

from __future__ import annotations

import html
import re
from pathlib import Path

import pytest

from tests.conftest import ROOT, run

pytest.importorskip("jinja2")

LINK = re.compile(r'<div class="link (?P<kind>[a-z]+)" data-link="(?P<title>[^"]+)">\s*<h4>[^<]*</h4>\s*'
                  r'<div class="value">(?P<value>[^<]*)</div>\s*<div class="muted">(?P<objects>[^<]*)</div>'
                  r'(?:\s*<div>(?P<part>[^<]*)</div>)?')
CHECK = re.compile(r'<p class="(ok|bad)">([^<]*)</p>')


def _page(capsys: pytest.CaptureFixture[str], tmp_path: Path, *args: str) -> tuple[list[dict[str, str]], list[tuple[str, str]]]:
    out = tmp_path / "scaling.html"
    code, _, err = run(capsys, "scale", *args, "--html", str(out))
    assert code == 0, err
    text = out.read_text(encoding="utf-8")
    links = [{k: html.unescape(v or "") for k, v in m.groupdict().items()} for m in LINK.finditer(text)]
    return links, [(k, html.unescape(v)) for k, v in CHECK.findall(text)]


def test_ball_screw_chain_from_the_mechanics(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    # 500-line quadrature encoder = 2000 counts/rev, 3:1 gear, 5 mm lead: 2000 × 3 / 5 = 1200 counts per mm
    links, checks = _page(capsys, tmp_path, "compute", str(ROOT / "samples" / "scaling" / "ballscrew.yaml"))
    assert [(x["title"], x["kind"]) for x in links] == [
        ("Encoder", "known"), ("Gear", "known"), ("Transmission", "known"), ("User unit", "result")]
    enc, gear, feed, unit = links
    assert (enc["value"], enc["objects"]) == ("2000 counts / motor rev", "608Fh")
    assert "500-line" in enc["part"]
    assert (gear["value"], gear["objects"], gear["part"]) == ("3 motor rev : 1 shaft rev", "6091h", "3:1")
    assert (feed["value"], feed["objects"]) == ("5 mm / shaft rev", "6092h")
    assert "ball screw" in feed["part"]
    assert (unit["value"], unit["objects"]) == ("1 mm = 1200 counts", "6093h")
    assert checks == [("ok", "608Fh × 6091h ÷ 6092h = 1200 counts per unit: agrees with the position factor 1200")]


def test_hdt_chain_derives_gear_and_transmission_from_6093(capsys: pytest.CaptureFixture[str],
                                                           tmp_path: Path) -> None:
    # HDT: 65536 counts per motor rev always; 6093h = 16384/25 counts per unit → 1 motor rev = 100 units
    links, checks = _page(capsys, tmp_path, "explain", "--family", "hdt", "6093:01=16384", "6093:02=25")
    assert [(x["title"], x["kind"]) for x in links] == [
        ("Encoder", "known"), ("Gear × transmission", "derived"), ("User unit", "result")]
    assert links[0]["value"] == "65536 counts / motor rev"
    assert links[1]["value"] == "1 motor rev = 100 position unit"
    assert links[2]["value"] == "1 position unit = 655.36 (16384/25) counts"
    assert checks == []  # no 608Fh/6091h/6092h to cross-check


def test_inconsistent_objects_are_shown_as_differing(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    links, checks = _page(capsys, tmp_path, "explain", "--family", "technosoft-ipos",
                          "608F:01=2000", "608F:02=1", "6091:01=3", "6091:02=1", "6092:01=5", "6092:02=1",
                          "6093:01=1201", "6093:02=1")
    assert (links[-1]["value"], links[-1]["objects"]) == ("1 position unit = 1201 counts", "6093h")
    assert checks == [("bad", "608Fh × 6091h ÷ 6092h = 1200 counts per unit: DIFFERS from the position factor 1201")]
