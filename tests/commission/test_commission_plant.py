"""Issue 33 item 6: commission on the plant. Each move reports its following error, settling time, overshoot, peak
speed and torque; a project whose following-error window 6065h is too tight for its move fails, and widening it
(the fix docs/simulator.md shows) makes it pass."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from ecattool.commission import commission
from tests.conftest import ROOT

GENERIC = ROOT / "samples" / "generic_esi"


def _project(tmp_path: Path, window: int, plant: str = "") -> Path:
    shutil.copy(GENERIC / "inovance_SV660_EOE_1Axis_V9.12.xml", tmp_path)
    text = (GENERIC / "project.yaml").read_text().replace(
        "    move: {distance: 10000, mode: csp}",
        "    parameters:\n"
        f"      - {{object: \"0x6065:00\", value: {window}, comment: following error window}}\n"
        "      - {object: \"0x6066:00\", value: 10, comment: following error time out 10 ms}\n"
        f"{plant}"
        "    move: {distance: 10000, mode: csp}")
    assert "0x6065:00" in text
    path = tmp_path / "project.yaml"
    path.write_text(text)
    return path


def test_a_window_too_tight_for_the_move_fails_and_a_wider_one_passes(tmp_path: Path):
    tight = commission(_project(tmp_path, 100))
    assert not tight.ok
    move = next(s for s in tight.drives[0].steps if s.name == "move")
    assert "faulted" in move.detail and "6065h window 100" in move.detail
    wide = commission(_project(tmp_path, 1000))
    assert wide.ok, [s.detail for s in wide.drives[0].steps if not s.ok]
    figures = wide.drives[0].trace.figures
    assert figures is not None and 100 < figures.following_error <= 1000 and figures.window == 1000


def test_the_ideal_plant_has_no_following_error(tmp_path: Path):
    """``plant: ideal`` keeps the exact tracker: the tight window passes (the axis is where the master says)."""
    report = commission(_project(tmp_path, 100, "    plant: ideal\n"))
    assert report.ok
    assert report.drives[0].trace.figures is not None and report.drives[0].trace.figures.following_error <= 100


def test_a_heavier_load_lags_more(tmp_path: Path):
    """The project's plant: a 50x load inertia (reflected through no gear) needs more torque for the same move."""
    light = commission(_project(tmp_path, 100000)).drives[0].trace.figures
    heavy = commission(_project(tmp_path, 100000, "    plant: {load_inertia: 1.5e-3}\n")).drives[0].trace.figures
    assert light is not None and heavy is not None
    assert heavy.peak_torque is not None and light.peak_torque is not None
    assert heavy.peak_torque > 10 * light.peak_torque


@pytest.mark.parametrize("sample", ["hdt", "technosoft_ipos", "controltechniques", "generic_esi"])
def test_the_samples_commission_with_figures(sample: str):
    report = commission(ROOT / "samples" / sample / "project.yaml")
    assert report.ok, [s.detail for d in report.drives for s in d.steps if not s.ok]
    drive = report.drives[0]
    assert drive.trace.figures is not None
    out = drive.to_json()
    assert set(out["move"]) >= {"following_error_max", "settling_time_s", "overshoot", "peak_speed",
                                "peak_torque_per_mille"}
    assert "following error up to" in next(s.detail for s in drive.steps if s.name == "move")
    json.dumps(out)


def test_the_html_report_plots_the_following_error_with_its_window_and_the_torque(tmp_path: Path):
    from ecattool.report import commission_html

    html = commission_html([commission(_project(tmp_path, 1000))])
    assert "Following error and torque" in html
    assert "6065h following error window ±1000" in html
    assert "6077h torque actual" in html
