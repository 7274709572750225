"""Every scaling oracle of the three reference/<family>/oracles.md files, each as its own test.

Numbers in the test names refer to the oracle items (technosoft D31…F56, hdt 32…D5, controltechniques 30…44).
IU conversions truncate toward minus infinity like the manual's examples (decisions.md, ambiguity 47).
"""

from __future__ import annotations

import math
from fractions import Fraction

import pytest

from ecattool.scaling import (
    Axis, Exact, Feedback, Gear, Transmission, approximate, compute, decode_si_unit, encode_si_unit, explain,
)
from ecattool.scaling.units import describe_dimension
from tests.conftest import reference_path

MM = Fraction(1, 1000)


def _iu(value: Fraction | int, ratio: Fraction) -> int:
    return math.floor(Fraction(value) * ratio)


@pytest.fixture(scope="module")
def ipos() -> object:
    """500-line encoder (2000 counts/rev), T = 1 ms, PU rot, VU rpm, AU rot/s² (oracles D/F55)."""
    return compute(Axis(Feedback.lines(500), position="rev", velocity="rpm", acceleration="rev/s^2"), "technosoft-ipos")


def test_reference_oracles_present() -> None:
    for fam in ("technosoft", "hdt", "controltechniques"):
        assert reference_path(fam, "oracles.md").is_file(), f"reference oracles missing for {fam}"


# --- Technosoft D: internal-unit conversions ---------------------------------------------------------------

def test_ts_33_homing_speeds_600_and_150_rpm(ipos) -> None:
    v = ipos.ratio(0x6094)
    assert _iu(600, v) == 0x00140000
    assert _iu(150, v) == 0x00050000


def test_ts_33_homing_acceleration_5_rot_s2(ipos) -> None:
    assert _iu(5, ipos.ratio(0x210F)) == 0x0000028F  # 655.36 truncated


def test_ts_33_home_offset_1_rev(ipos) -> None:
    assert _iu(1, ipos.ratio(0x6093)) == 0x000007D0


def test_ts_34_relative_trapezoid(ipos) -> None:
    assert _iu(20, ipos.ratio(0x6093)) == 0x00009C40
    assert _iu(200, ipos.ratio(0x6093)) == 0x00061A80
    # 500 rpm: exact 1092266.67; the manual prints 0x10AAAC (rounded 16.6667 first) -> within 2 LSB
    assert abs(_iu(500, ipos.ratio(0x6094)) - 0x0010AAAC) <= 2


def test_ts_35_absolute_trapezoid(ipos) -> None:
    assert _iu(4, ipos.ratio(0x6093)) == 0x00001F40
    assert _iu(16, ipos.ratio(0x6093)) == 0x00007D00


def test_ts_36_37_s_curves(ipos) -> None:
    assert _iu(10, ipos.ratio(0x6093)) == 0x00004E20
    assert _iu(450, ipos.ratio(0x6094)) == 0x000F0000
    assert _iu(5, ipos.ratio(0x6093)) == 0x00002710
    assert _iu(150, ipos.ratio(0x6094)) == 0x00050000


def test_ts_38_profile_velocity_600_rpm(ipos) -> None:
    assert _iu(600, ipos.ratio(0x6094)) == 0x00140000


def test_ts_39_stepper_300_rpm() -> None:
    g = compute(Axis(Feedback.stepper(200, 512), position="rev", velocity="rpm"), "technosoft-ipos")
    assert _iu(300, g.ratio(0x6094)) == 0x02000000


def test_ts_31_40_41_velocity_iu_meaning() -> None:
    e = explain({(0x6094, 1): 0x00090000, (0x6094, 2): 1, (0x608F, 1): 2000, (0x608F, 2): 1}, "technosoft-ipos")
    assert e.data["counts/s per velocity unit"] == 9000  # 9.0 counts/ms
    e = explain({(0x210F, 1): 0x199A, (0x210F, 2): 1}, "technosoft-ipos")
    assert float(e.data["counts/s² per acceleration unit"]) == pytest.approx(100006.1, rel=1e-6)  # 0.1000061 IU


def test_ts_41_default_encoder_resolution(ipos) -> None:
    assert ipos.pair(0x608F) == (2000, 1)


def test_ts_43_step_loss_window_in_degrees() -> None:
    g = compute(Axis(Feedback.stepper(100, 256), position="deg"), "technosoft-ipos")
    assert Fraction(1000) / g.ratio(0x6093) == Fraction(140625, 10000)  # 14.0625 degrees


def test_ts_44_4000_iu_is_one_revolution() -> None:
    g = compute(Axis(Feedback.lines(1000), position="rev"), "technosoft-ipos")
    assert g.ratio(0x6093) == 4000


def test_ts_45_twincat_degrees_per_count() -> None:
    g = compute(Axis(Feedback.lines(500), position="deg"), "technosoft-ipos")
    assert 1 / g.ratio(0x6093) == Fraction(18, 100)
    e = explain(g.values, "technosoft-ipos")
    assert any("1 count = 0.18 (9/50) deg" in m for _, m in e.lines)


# --- Technosoft F: factor group -------------------------------------------------------------------------

def test_ts_49_obsolete_radians_4294967295_over_13493038() -> None:
    g = compute(Axis(Feedback.lines(500), position="rad"), "technosoft-ipos", firmware="F515I")
    assert g.factor_set == "obsolete"
    assert g.pair(0x6093) == (4294967295, 13493038)
    a = g.get(0x6093, 1).approximation
    assert not a.exact and abs(a.ppm) < Fraction(1, 10)  # 318.30988… counts/rad vs exact 2000/2π


def test_ts_50_small_pair_is_written_large_and_warned() -> None:
    a = approximate(Fraction(2), scale_exact=True)
    assert a.value == 2 and a.numerator >= 0x20000 and a.denominator >= 0x10000
    e = explain({(0x6093, 1): 2, (0x6093, 2): 1}, "technosoft-ipos")
    assert any(f.rule == "scaling.small-pair" for f in e.findings)


@pytest.mark.parametrize("unit,word", [
    ("inc", 0x00B50100), ("deg", 0x00410100), ("mm", 0xFD010100), ("rpm", 0x00B44700), ("mm/s", 0xFD010300),
    ("deg/s^2", 0x00415700), ("krad/s²", 0x03105700), ("deg/s^3", 0x0041A000), ("krad/s^3", 0x0310A000),
])
def test_ts_51_si_unit_words(unit: str, word: int) -> None:
    assert encode_si_unit(unit) == word
    assert encode_si_unit(decode_si_unit(word).replace("rot/min", "rpm")) == word


def test_ts_51_si_decode_texts() -> None:
    assert decode_si_unit(0xFD010100) == "mm"
    assert decode_si_unit(0x00B44700) == "rot/min"
    assert decode_si_unit(0x00B50100) == "inc"
    assert decode_si_unit(0x03105700) == "krad/s²"
    assert decode_si_unit(0xFD010000) == "mm"  # denominator 00 = none (canopen-stack style)


def test_ts_52_velocity_factor() -> None:
    g = compute(Axis(Feedback.lines(500), position="rad", velocity="rpm"), "technosoft-ipos")
    a = g.get(0x6096, 1).approximation
    assert a.exact_value == Exact(Fraction(30), -1)  # 60 / 2π
    assert abs(float(g.ratio(0x6096)) - 9.5492966) < 1e-7
    g = compute(Axis(Feedback.lines(500), position="rad", velocity="rad/s"), "technosoft-ipos")
    assert g.ratio(0x6096) == 1


def test_ts_53_acceleration_factor() -> None:
    g = compute(Axis(Feedback.lines(500), position="rad", velocity="rad/s", acceleration="krad/s^2"), "technosoft-ipos")
    assert g.ratio(0x6097) == Fraction(1, 1000)
    g = compute(Axis(Feedback.lines(500), position="rad", velocity="rad/s", acceleration="rad/s^2"), "technosoft-ipos")
    assert g.ratio(0x6097) == 1


def test_ts_54_jerk_factor() -> None:
    base = dict(position="rad", velocity="rad/s", acceleration="rad/s^2")
    g = compute(Axis(Feedback.lines(500), jerk="krad/s^3", **base), "technosoft-ipos")
    assert g.ratio(0x60A2) == Fraction(1, 1000)
    g = compute(Axis(Feedback.lines(500), jerk="rad/s^3", **base), "technosoft-ipos")
    assert g.ratio(0x60A2) == 1


def test_ts_55_encoder_factors_cross_check(ipos) -> None:
    assert ipos.ratio(0x6094) == Fraction(2000, 60) * Fraction(1, 1000) * 65536  # 2184.5333 IU per rpm
    assert ipos.ratio(0x6097) == Fraction(1, 60)  # AU = rot/s², VU = rpm
    assert ipos.ratio(0x210F) * 5 == Fraction(65536, 100)  # 655.36


@pytest.mark.parametrize("dim,notation,text", [
    (1, -6, "µm"), (12, 0, "rad"), (13, -3, "mm/s"), (28, 3, "kHz"), (4, 77, "day"), (12, 76, "minute (angle)"),
])
def test_ts_56_dimension_notation(dim: int, notation: int, text: str) -> None:
    assert describe_dimension(dim, notation) == text


# --- HDT ------------------------------------------------------------------------------------------------------

def test_hdt_32_34_default_factors() -> None:
    g = compute(Axis(Feedback.encoder(4096), position="counts", velocity="rpm", acceleration="rpm/s"), "hdt")
    assert g.ratio(0x6093) == Fraction(65536, 65536)
    assert g.ratio(0x6094) == Fraction(65536, 60)
    assert g.ratio(0x6097) == Fraction(65536, 60)


def test_hdt_35_caliper_reduced_fraction_equal_by_ratio() -> None:
    g = compute(Axis(Feedback.encoder(4096), position="counts", velocity="rpm", acceleration="rpm/s"), "hdt")
    assert g.ratio(0x6094) == Fraction(16384, 15)


def test_hdt_36_910_pulses_is_about_5_degrees() -> None:
    g = compute(Axis(Feedback.encoder(4096), position="deg"), "hdt")
    assert Fraction(910) / g.ratio(0x6093) == Fraction(910 * 360, 65536)
    assert abs(float(Fraction(910) / g.ratio(0x6093)) - 4.99878) < 1e-5


def test_hdt_40_1000_rpm_in_counts_per_second() -> None:
    e = explain({(0x6094, 1): 65536, (0x6094, 2): 60}, "hdt")
    assert e.data["counts/s per velocity unit"] * 1000 == Fraction(3276800, 3)


def test_hdt_41_jerk_uses_acceleration_factor() -> None:
    e = explain({(0x6097, 1): 65536, (0x6097, 2): 60}, "hdt")
    assert any(q == "jerk" and "(16384/15) pulses/s³" in m for q, m in e.lines)


def test_hdt_58_user_position_from_internal() -> None:
    e = explain({(0x6093, 1): 65536, (0x6093, 2): 360}, "hdt")
    assert e.data["counts per position unit"] * 90 == 16384


def test_hdt_d1_degrees_at_motor() -> None:
    g = compute(Axis(Feedback.encoder(4096), position="deg"), "hdt")
    assert g.pair(0x6093) == (8192, 45)
    assert 90 * g.ratio(0x6093) == 16384


def test_hdt_64_1024_pulse_encoder_is_4096_counts_and_hdt_still_counts_65536() -> None:
    # §5.03 feedback screen: 2032h "Impulsi/giro 1024" -> "Risoluzione/giro 4096" (x4 quadrature); the drive's
    # position units stay 65536 per motor revolution whatever the encoder (§4.06.6), so the factor group is
    # the same as for any other encoder
    fb = Feedback.lines(1024)
    assert fb.counts_per_rev == 4096
    assert compute(Axis(fb, position="deg"), "hdt").pair(0x6093) == (8192, 45)


def test_hdt_37_32_bit_positions_reach_32767_motor_turns() -> None:
    # §4.06.6: a 32-bit signed position at 65536 per turn is "up to ±32767 motor turns"
    g = compute(Axis(Feedback.encoder(65536), position="rev"), "hdt")
    per_turn = g.ratio(0x6093)
    assert per_turn == 65536
    assert 32767 * per_turn <= 2**31 - 1 < 32768 * per_turn and -32768 * per_turn >= -(2**31)


def test_hdt_d2_screw_5mm_in_micrometres() -> None:
    for kind in (Transmission.ballscrew, Transmission.hollow_shaft):
        g = compute(Axis(Feedback.encoder(4096), kind(Exact(5 * MM)), position="um"), "hdt")
        assert g.pair(0x6093) == (8192, 625)
        assert 1000 * g.ratio(0x6093) == Fraction(131072, 10)  # 13107.2 pulses


def test_hdt_d3_velocity_rps_and_counts() -> None:
    g = compute(Axis(Feedback.encoder(4096), position="rev", velocity="rps"), "hdt")
    assert g.ratio(0x6094) == 65536
    g = compute(Axis(Feedback.encoder(4096), position="counts", velocity="counts/s"), "hdt")
    assert g.ratio(0x6094) == 1


def test_hdt_d4_gearbox_10_to_1_disk_degrees() -> None:
    g = compute(Axis(Feedback.encoder(4096), Transmission.rotary(), Gear(Fraction(10), Fraction(1)), position="deg"), "hdt")
    assert g.pair(0x6093) == (16384, 9)
    assert g.summary["Caliper application"].startswith("0 - disk axis")


def test_hdt_d5_custom_label() -> None:
    g = compute(Axis(Feedback.encoder(4096), Transmission.custom_label("bottle", 100, 1), position="bottle"), "hdt")
    assert g.pair(0x6093) == (16384, 25)


def test_hdt_polarity_607e() -> None:
    g = compute(Axis(Feedback.encoder(4096), reverse=True), "hdt")
    assert g.get(0x607E, 0).value == 0xC0


# --- Control Techniques -------------------------------------------------------------------------------------------

def test_ct_30_position_factor_1228_8() -> None:
    g = compute(Axis(Feedback.encoder(4096), Transmission.ballscrew(Exact(10 * MM)), Gear(Fraction(3)), position="mm"),
                "controltechniques")
    assert g.pair(0x6091) == (3, 1)
    assert g.pair(0x6092) == (10, 1)
    assert g.summary["position factor (drive computes 608F x 6091 / 6092)"] == Fraction(6144, 5)
    assert not g.get(0x608F, 1).write  # read-only on SM-EtherCAT: never in the startup list
    assert all(c.index != 0x608F for c in g.startup())
    e = explain({(0x608F, 1): 4096, (0x608F, 2): 1, (0x6091, 1): 3, (0x6091, 2): 1, (0x6092, 1): 10, (0x6092, 2): 1},
                "controltechniques")
    assert e.data["counts per position unit"] == Fraction(12288, 10)


def test_ct_30_defaults_position_factor_1() -> None:
    e = explain({(0x608F, 1): 1, (0x608F, 2): 1, (0x6091, 1): 1, (0x6091, 2): 1, (0x6092, 1): 1, (0x6092, 2): 1},
                "controltechniques")
    assert e.data["counts per position unit"] == 1


def test_ct_43_vl_dimension_factor_rev_per_second() -> None:
    g = compute(Axis(Feedback.encoder(4096), position="rev", velocity="rev/s"), "controltechniques")
    assert g.pair(0x604C) == (60, 1)
    assert g.get(0x604C, 1).type_name == "INT"
    e = explain(g.values, "controltechniques")
    assert 25 * e.data["rpm per 6042h unit"] == 1500


def test_ct_44_vl_setpoint_factor_tenths() -> None:
    e = explain({(0x604B, 1): 1, (0x604B, 2): 10, (0x604C, 1): 1, (0x604C, 2): 1}, "controltechniques")
    assert 15000 * e.data["rpm per 6042h unit"] == 1500
    g = compute(Axis(Feedback.encoder(4096), position="rev", velocity="rpm"), "controltechniques", vl_setpoint=(1, 10))
    assert g.pair(0x604B) == (1, 10) and g.pair(0x604C) == (1, 1)


def test_ct_42_vl_factor_zero_rejected() -> None:
    from ecattool.errors import InputError

    with pytest.raises(InputError):
        compute(Axis(Feedback.encoder(4096)), "controltechniques", vl_setpoint=(0, 1))
    with pytest.raises(InputError):
        explain({(0x604C, 1): 0, (0x604C, 2): 1}, "controltechniques")
