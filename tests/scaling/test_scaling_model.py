"""Mechanics model, family choices, explain checks, and a real ESI (Copley XE2) for the generic family."""

from __future__ import annotations

from fractions import Fraction

import pytest

from ecattool.errors import InputError, SelectionError
from ecattool.scaling import (
    Axis, Exact, Feedback, Gear, Transmission, axis_from_dict, compute, explain, technosoft_factor_set,
)
from ecattool.scaling.spec import load_spec
from tests.conftest import corpus_path

MM = Fraction(1, 1000)


def test_load_side_encoder_is_referred_to_the_motor() -> None:
    axis = Axis(Feedback.encoder(10000, on="load"), Transmission.rotary(), Gear(Fraction(5)), position="deg")
    assert axis.counts_per_motor_rev == Exact(Fraction(2000))
    g = compute(axis, "generic")
    assert g.pair(0x608F) == (2000, 1) and g.ratio(0x6093) == Fraction(10000, 360)


def test_linear_scale_on_a_screw() -> None:
    axis = axis_from_dict({"feedback": {"resolution": "1 um"}, "transmission": {"type": "ballscrew", "pitch": "5 mm"},
                           "units": {"position": "mm"}})
    g = compute(axis, "generic")
    assert g.pair(0x608F) == (5000, 1) and g.ratio(0x6093) == 1000


def test_linear_motor_counts_per_pole_pitch() -> None:
    axis = Axis(Feedback.encoder(4096), Transmission.linear_motor(Exact(32 * MM)), position="mm")
    assert compute(axis, "generic").ratio(0x6093) == 128
    assert compute(axis, "hdt").ratio(0x6093) == 2048  # 65536 per pole pitch (inferred, decisions.md)


def test_rack_by_module_keeps_pi_symbolic() -> None:
    axis = axis_from_dict({"feedback": {"counts_per_rev": 4096},
                           "transmission": {"type": "rack", "teeth": 20, "module": "2 mm"}, "units": {"position": "mm"}})
    assert axis.travel_per_motor_rev == Exact(Fraction(40, 1000), 1)  # 40π mm
    a = compute(axis, "generic").get(0x6093, 1).approximation
    assert not a.exact and a.exact_value == Exact(Fraction(4096, 40), -1)


def test_rotary_pulley_stage_by_teeth() -> None:
    axis = axis_from_dict({"feedback": {"lines": 500}, "transmission": {"type": "rotary", "driving_teeth": 20,
                                                                         "driven_teeth": 60}, "units": {"position": "deg"}})
    assert compute(axis, "generic").ratio(0x6093) == Fraction(2000 * 3, 360)


def test_hollow_shaft_with_gear_is_warned() -> None:
    g = compute(Axis(Feedback.encoder(4096), Transmission.hollow_shaft(Exact(5 * MM)), Gear(Fraction(2)), position="mm"), "hdt")
    assert any(f.rule == "scaling.gear-ignored" for f in g.findings)


@pytest.mark.parametrize("firmware,expected", [
    ("F515K", "cia402-2"), ("F515I", "obsolete"), ("F515F", "obsolete"), ("FA00C", "cia402-2"), ("F510A", "obsolete"),
    ("0x3531354B", "cia402-2"), ("0x35313549", "obsolete"), ("892417353", "obsolete"), (None, "cia402-2"),
])
def test_technosoft_factor_set_by_firmware(firmware: str | None, expected: str) -> None:
    assert technosoft_factor_set(firmware) == expected


def test_polarity() -> None:
    rev = Axis(Feedback.lines(500), reverse=True)
    assert compute(rev, "technosoft-ipos").get(0x607E, 0).value == 0xC0
    assert compute(Axis(Feedback.lines(500)), "generic").get(0x607E, 0) is None
    assert compute(rev, "generic").get(0x607E, 0).value == 0xC0


def test_inch_has_no_si_word_and_says_so() -> None:
    g = compute(Axis(Feedback.lines(500), Transmission.ballscrew(Exact(Fraction(254, 10000) / 5)), position="inch"),
                "technosoft-ipos")
    assert g.get(0x60A8, 0) is None and any("0x60A8" in n for n in g.notes)
    assert g.ratio(0x6093) == 10000  # 5 turns per inch x 2000 counts, exact


def test_explain_flags_inconsistent_encoder_factor() -> None:
    g = compute(Axis(Feedback.lines(500), position="rev", velocity="rpm"), "technosoft-ipos")
    values = g.values
    values[(0x6094, 2)] += 1000
    e = explain(values, "technosoft-ipos")
    assert any(f.rule == "scaling.inconsistent" for f in e.findings)
    assert not explain(g.values, "technosoft-ipos").findings


def test_explain_obsolete_factor_inactive_without_dimension_index() -> None:
    e = explain({(0x6093, 1): 0x20000, (0x6093, 2): 0x10000, (0x608A, 0): 0, (0x6089, 0): 0}, "technosoft-ipos",
                firmware="F515I")
    assert any("INACTIVE" in m for _, m in e.lines)


def test_explain_decodes_si_units() -> None:
    e = explain({(0x6093, 1): 1200, (0x6093, 2): 1, (0x60A8, 0): 0xFD010100}, "technosoft-ipos")
    assert e.lines[0][1].startswith("1 mm = 1200 counts")


def test_unknown_family_and_units() -> None:
    with pytest.raises(SelectionError):
        compute(Axis(Feedback.lines(500)), "yaskawa")
    with pytest.raises(InputError, match="not a velocity unit"):
        Axis(Feedback.lines(500), velocity="deg").unit(1)


def test_spec_errors_have_lines(tmp_path) -> None:
    spec = tmp_path / "s.yaml"
    spec.write_text("feedback: {lines: 500}\ntransmission: {type: screw}\n")
    with pytest.raises(InputError) as exc:
        load_spec(spec)
    assert exc.value.location.line == 2 and "pitch" in exc.value.message
    spec.write_text("feedback: {lines: 500}\ncolour: red\n")
    with pytest.raises(InputError) as exc:
        load_spec(spec)
    assert exc.value.location.line == 2


def test_generic_family_on_a_real_esi_copley_xe2() -> None:
    from ecattool.esi import load

    device = load(corpus_path("esi", "copley_XE2_4.60.xml")).devices[0]
    axis = Axis(Feedback.encoder(8192), Transmission.ballscrew(Exact(10 * MM)), Gear(Fraction(2)), position="um",
                reverse=True)
    g = compute(axis, "generic", device=device)
    written = {o.index for o in g.objects}
    assert {0x608F, 0x6091, 0x6092, 0x6096, 0x6097, 0x60A2, 0x607E} <= written
    assert 0x6093 not in written and 0x60A8 not in written  # the XE2 has neither: left out, with notes
    assert any("0x6093" in n for n in g.notes)
    assert g.pair(0x6092) == (10000, 1)
    for c in g.startup():
        entry = device.dictionary.entry(c.index, c.subindex)
        assert entry is not None and len(c.data) * 8 == entry.bit_size


def test_read_values_from_the_simulator_hdt_defaults() -> None:
    """HDT oracle 32: the drive's defaults read back mean counts (65536/rev), rpm and rpm/s."""
    from ecattool.od.model import EcState
    from ecattool.scaling.explain import read_values
    from ecattool.sim import Drive

    d = Drive.from_profile("hdt")
    d.request_state(EcState.PREOP)
    values = read_values(d)
    assert (0x6093, 1) in values and (0x210F, 1) not in values
    e = explain(values, "hdt")
    assert e.data["counts per position unit"] == 1
    assert e.data["counts/s per velocity unit"] == Fraction(65536, 60)
    assert any("1 rpm" in m or "= 1 motor rpm" in m for _, m in e.lines)


def test_hdt_vl_dimension_factor_is_int32() -> None:
    g = compute(Axis(Feedback.encoder(4096), position="rev", velocity="rev/s"), "hdt", vl=True)
    assert g.pair(0x604C) == (60, 1) and g.get(0x604C, 1).type_name == "DINT"


def test_ct_negative_setpoint_allowed_and_no_polarity_object() -> None:
    g = compute(Axis(Feedback.encoder(4096), reverse=True), "controltechniques", vl_setpoint=(-1, 1))
    assert g.pair(0x604B) == (-1, 1) and g.get(0x604B, 1).hex == "0xFFFF"
    assert g.get(0x607E, 0) is None and any(f.rule == "scaling.no-polarity" for f in g.findings)


def test_command_line_options_build_the_spec_a_file_would() -> None:
    """The flags of ``scale compute`` are a typed object of the library (AxisOptions), turned into the same Spec a
    spec file gives: alone, or over a file where each option said replaces that key only."""
    from ecattool.scaling.spec import AxisOptions, spec_from_dict, spec_with
    from tests.conftest import ROOT

    alone = spec_with(None, AxisOptions(lines="500", gear="3:1", transmission="ballscrew pitch=5mm", position="mm",
                                        velocity="mm/s", slow_loop="1ms"))
    assert alone == spec_from_dict({"feedback": {"lines": "500"}, "gear": "3:1",
                                    "transmission": "ballscrew pitch=5mm", "units": {"position": "mm",
                                    "velocity": "mm/s"}, "slow_loop": "1ms", "reverse": False})
    base = load_spec(ROOT / "samples" / "scaling" / "ballscrew.yaml")
    over = spec_with(base, AxisOptions(gear="5:1", steps=("200", "256"), reverse=True))
    assert over.axis.gear != base.axis.gear and over.axis.reverse and not base.axis.reverse
    assert over.axis.feedback != base.axis.feedback and over.axis.transmission == base.axis.transmission
    assert over.axis.position == base.axis.position and over.family == base.family
    assert spec_with(base, AxisOptions(feedback_on="load")).axis.feedback.on == "load"
    with pytest.raises(InputError, match="give a SPEC file or the feedback"):
        spec_with(None, AxisOptions(position="mm"))
