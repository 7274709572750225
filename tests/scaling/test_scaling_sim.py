"""Round trips on the embedded simulator (an independent witness: ecattool.sim reads the manuals itself).

The computed factor group is written to a simulated drive as its startup list; then values in user units
are converted by the drive and compared with internal units worked out here by hand from the mechanics
(not from the factor group).
"""

from __future__ import annotations

from fractions import Fraction

import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from ecattool.errors import EncodeError, InputError
from ecattool.od.model import EcState
from ecattool.scaling import Axis, Exact, Feedback, Gear, Transmission, compute
from ecattool.sim import Drive

MM = Fraction(1, 1000)
T = Fraction(1, 1000)


def _drive(family: str, revision: str | None = None) -> Drive:
    d = Drive.from_profile(family, revision=revision) if revision else Drive.from_profile(family)
    d.request_state(EcState.PREOP)
    return d


def _apply(d: Drive, group) -> None:
    for c in group.startup():
        d.sdo_download(c.index, c.subindex, c.data)


def _read(d: Drive, index: int, sub: int) -> int:
    return int.from_bytes(d.sdo_upload(index, sub), "little")


# axes: (name, axis, counts per user unit computed by hand)
SCREW = Axis(Feedback.lines(500), Transmission.ballscrew(Exact(5 * MM)), Gear(Fraction(3)), position="mm",
             velocity="mm/s", acceleration="mm/s^2")
SCREW_CPU = Fraction(2000 * 3, 5)  # 2000 counts x 3 motor revs per 5 mm
BELT = Axis(Feedback.encoder(4096), Transmission.belt_teeth(24, Exact(5 * MM)), Gear(Fraction(5)), position="mm",
            velocity="mm/s", acceleration="mm/s^2")
BELT_CPU = Fraction(4096 * 5, 24 * 5)
TABLE = Axis(Feedback.lines(2500), Transmission.rotary(), Gear(Fraction(100)), position="deg", velocity="deg/s",
             acceleration="deg/s^2")
TABLE_CPU = Fraction(10000 * 100, 360)
AXES = [("ballscrew", SCREW, SCREW_CPU), ("belt", BELT, BELT_CPU), ("rotary", TABLE, TABLE_CPU)]


@pytest.mark.parametrize("name,axis,cpu", AXES, ids=[a[0] for a in AXES])
def test_technosoft_cia402_2_round_trip(name: str, axis: Axis, cpu: Fraction) -> None:
    d = _drive("technosoft-ipos", "F515K")
    group = compute(axis, "technosoft-ipos", firmware="F515K")
    _apply(d, group)
    u = d.units
    assert u.position_to_internal(10) == 10 * cpu
    assert u.increments_per_second(u.velocity_to_internal(100)) == 100 * cpu
    assert u.increments_per_second2(u.acceleration_to_internal(1000)) == 1000 * cpu
    # the simulator's own reading of §5.2 derives the same encoder factors from 608F/6091/6092/6096/6097
    derived = u.derived_factors()
    assert derived["position"] == group.ratio(0x6093)
    assert derived["velocity"] == group.ratio(0x6094)
    assert derived["acceleration"] == group.ratio(0x210F)


def test_technosoft_obsolete_radians_round_trip() -> None:
    d = _drive("technosoft-ipos", "F515I")
    group = compute(Axis(Feedback.lines(500), position="rad", velocity="rad/s", acceleration="rad/s^2"),
                    "technosoft-ipos", firmware="F515I")
    _apply(d, group)  # writes the dimension indices too, which activate the factors
    assert _read(d, 0x608A, 0) != 0
    exact = Fraction(2000) / (2 * Fraction(314159265358979323846, 10**20))
    assert abs(d.units.position_to_internal(1) - exact) / exact < Fraction(1, 10**7)
    assert int(d.units.position_to_internal(2)) == 636
    v = d.units.increments_per_second(d.units.velocity_to_internal(1))
    a = group.get(0x6094, 1).approximation  # manual's method: numerator 0xFFFFFFFF, divisor rounded
    assert a.method == "max-scale" and a.numerator == 0xFFFFFFFF
    assert abs((v / exact - 1) * 10**6 - a.ppm) < Fraction(1, 10**6)  # the drive drifts exactly as reported
    assert abs(a.ppm) < 5


def test_technosoft_profile_position_move_in_millimetres() -> None:
    """PP mode: 10 mm at 20 mm/s with 200 mm/s² ends at 12000 counts (3:1 gear, 5 mm lead, 2000 counts)."""
    d = _drive("technosoft-ipos", "F515K")
    _apply(d, compute(SCREW, "technosoft-ipos"))
    for index, size, value in ((0x6060, 1, 1), (0x607A, 4, 10), (0x6081, 4, 20), (0x6083, 4, 200)):
        d.sdo_download(index, 0, value.to_bytes(size, "little"))
    d.request_state(EcState.SAFEOP)
    d.request_state(EcState.OP)
    for cw in (0x06, 0x07, 0x0F, 0x1F):
        d.sdo_download(0x6040, 0, cw.to_bytes(2, "little"))
    d.step(2000)
    assert d.internal_position == 12000
    assert int.from_bytes(d.sdo_upload(0x6064, 0), "little", signed=True) == 10


@pytest.mark.parametrize("name,axis,cpu", AXES, ids=[a[0] for a in AXES])
def test_hdt_round_trip(name: str, axis: Axis, cpu: Fraction) -> None:
    d = _drive("hdt")
    _apply(d, compute(axis, "hdt"))
    internal_cpu = cpu / axis.counts_per_motor_rev.rational * 65536  # HDT: 65536 pulses per motor revolution
    u = d.units
    assert u.position_to_internal(10) == 10 * internal_cpu
    assert u.increments_per_second(u.velocity_to_internal(100)) == 100 * internal_cpu
    assert u.increments_per_second2(u.acceleration_to_internal(1000)) == 1000 * internal_cpu


@pytest.mark.parametrize("name,axis,cpu", AXES, ids=[a[0] for a in AXES])
def test_controltechniques_round_trip_with_608f_read_from_drive(name: str, axis: Axis, cpu: Fraction) -> None:
    d = _drive("controltechniques")
    d._put(0x608F, 1, int(axis.counts_per_motor_rev.rational))  # the encoder configuration sets 608Fh
    resolution = Fraction(_read(d, 0x608F, 1), _read(d, 0x608F, 2))
    ax = axis.with_(feedback=Feedback.encoder(resolution))
    group = compute(ax, "controltechniques")
    _apply(d, group)  # never writes the read-only 608Fh
    assert d.units.position_to_internal(10) == 10 * cpu


def test_hdt_belt_by_diameter_drift_matches_report() -> None:
    """pi on a flat-belt roller: the drive's counts after 10^6 mm differ from the exact ones by the reported drift."""
    axis = Axis(Feedback.encoder(4096), Transmission.belt_diameter(Exact(60 * MM)), Gear(Fraction(10)), position="mm")
    group = compute(axis, "hdt")
    a = group.get(0x6093, 1).approximation
    d = _drive("hdt")
    _apply(d, group)
    drift = d.units.position_to_internal(10**6) - 10**6 * a.exact_value.rational
    assert drift == a.drift
    assert abs(drift) <= a.bound * 10**6


@settings(max_examples=25)
@given(pitch_um=st.integers(100, 50_000), counts=st.integers(16, 1 << 20), motor=st.integers(1, 200),
       load=st.integers(1, 50), unit=st.sampled_from(["mm", "um", "inch"]))
def test_technosoft_random_screws_on_the_simulator(pitch_um: int, counts: int, motor: int, load: int, unit: str) -> None:
    axis = Axis(Feedback.encoder(counts), Transmission.ballscrew(Exact(Fraction(pitch_um, 10**6))),
                Gear(Fraction(motor), Fraction(load)), position=unit)
    try:
        group = compute(axis, "technosoft-ipos", firmware="F515K")
    except EncodeError:  # a factor beyond 32 bits (e.g. jerk IU per inch/s³ on a 0.1 mm screw): refused cleanly
        assume(False)
        return
    d = _drive("technosoft-ipos", "F515K")
    _apply(d, group)
    size = {"mm": MM, "um": MM / 1000, "inch": Fraction(254, 10000)}[unit]
    exact = Fraction(counts * motor, load) * size / Fraction(pitch_um, 10**6)
    got = d.units.position_to_internal(1)
    a = group.get(0x6093, 1).approximation
    assert got - exact == a.error
    assert abs(got - exact) <= a.bound


#: corpus drive ESIs (file, device index): Copley has 608Fh/6091h/6092h; the Inovance SV660N has 6091h only,
#: so 6091h must carry the encoder resolution and the feed (else the drive moves by the gear ratio alone)
GENERIC_ESIS = [("copley_XE2_4.60.xml", 0), ("inovance_SV660_EOE_1Axis_V9.12.xml", 0),
                ("elmo_Elmo_ECAT_00010420_V11.xml", 2)]


@pytest.mark.parametrize("esi,index", GENERIC_ESIS, ids=[e[0].split("_")[0] for e in GENERIC_ESIS])
@pytest.mark.parametrize("name,axis,cpu", AXES, ids=[a[0] for a in AXES])
def test_generic_round_trip_on_a_real_esi(name: str, axis: Axis, cpu: Fraction, esi: str, index: int) -> None:
    """Corpus ESI drives simulated as generic CiA-402 drives: 608Fh x 6091h / 6092h per user unit, whichever
    of them the ESI has."""
    from ecattool.esi import load
    from tests.conftest import corpus_path

    device = load(corpus_path("esi", esi)).devices[index]
    d = Drive.from_device(device)
    d.request_state(EcState.PREOP)
    _apply(d, compute(axis, "generic", device=device))
    assert d.units.position_to_internal(10) == 10 * cpu
    assert d.units.increments_per_second(d.units.velocity_to_internal(100)) == 100 * cpu


@pytest.mark.parametrize("esi", ["etg_ETG2001_ModulesSlots_CiA402.xml", "ingenia_eve-xcr-e_esi.xml"])
def test_a_drive_without_factor_objects_cannot_take_user_units(esi: str) -> None:
    """The ETG.2001 example drive and the Ingenia Everest ESI have none of 608Fh/6091h/6092h/6093h: the scaling
    is an error, not a table of factors nobody writes (lint refused nothing and the move was not checked)."""
    from ecattool.esi import load
    from tests.conftest import corpus_path

    device = load(corpus_path("esi", esi)).devices[0]
    with pytest.raises(InputError, match="none of the scaling objects that set user units"):
        compute(SCREW, "generic", device=device)


@pytest.mark.parametrize("name,axis,cpu", AXES, ids=[a[0] for a in AXES])
def test_generic_drive_without_gear_ratio_object_keeps_the_gear(name: str, axis: Axis, cpu: Fraction) -> None:
    """A generic drive with 608Fh and 6092h but no 6091h (and no 6093h) takes the gear ratio as 1: the gear
    must go into 608Fh, else the drive moves by the factor without the gear."""
    from ecattool.esi import load
    from ecattool.od.model import ObjectDictionary
    from tests.conftest import corpus_path

    device = load(corpus_path("esi", "copley_XE2_4.60.xml")).devices[0]
    assert device.dictionary.get(0x6093) is None and device.dictionary.get(0x608F) is not None
    device.dictionary = ObjectDictionary({o.index: o for o in device.dictionary if o.index != 0x6091})
    d = Drive.from_device(device)
    d.request_state(EcState.PREOP)
    _apply(d, compute(axis, "generic", device=device))
    assert d.units.position_to_internal(10) == 10 * cpu


@pytest.mark.parametrize("esi", ["etg_ETG2001_ModulesSlots_CiA402.xml", "ingenia_eve-xcr-e_esi.xml"])
def test_a_drive_without_factor_objects_takes_its_own_increments(esi: str) -> None:
    """Position unit = the drive's increment (counts) needs no factor object: it was refused with
    '1 counts = 1 increments cannot be set' on the drives that have none."""
    from ecattool.esi import load
    from tests.conftest import corpus_path

    device = load(corpus_path("esi", esi)).devices[0]
    group = compute(Axis(Feedback.encoder(8388608), position="counts"), "generic", device=device)
    assert group.objects == []
    d = Drive.from_device(device)
    assert d.units.position_to_internal(10) == 10


def test_generic_velocity_and_acceleration_units_go_through_6096_and_6097() -> None:
    """Copley has 6096h/6097h: um positions with mm/s and mm/s^2 write 6096h = 1/1000; the simulated drive ignored
    6096h/6097h, so the witness agreed with a group whatever those objects said."""
    from ecattool.esi import load
    from tests.conftest import corpus_path

    device = load(corpus_path("esi", "copley_XE2_4.60.xml")).devices[0]
    axis = Axis(Feedback.encoder(1 << 20), Transmission.ballscrew(Exact(5 * MM)), Gear(Fraction(3)), position="um",
                velocity="mm/s", acceleration="m/s^2")
    cpu = Fraction((1 << 20) * 3, 5000)  # increments per um
    d = Drive.from_device(device)
    d.request_state(EcState.PREOP)
    _apply(d, compute(axis, "generic", device=device))
    assert d.units.position_to_internal(10) == 10 * cpu
    assert d.units.increments_per_second(d.units.velocity_to_internal(2)) == 2000 * cpu          # 2 mm/s
    assert d.units.increments_per_second2(d.units.acceleration_to_internal(3)) == 3_000_000 * cpu  # 3 m/s^2


@pytest.mark.parametrize("velocity,acceleration,missing", [("rpm", None, "6096h"), ("mm/s", "m/s^2", "6097h")])
def test_a_drive_without_6096_or_6097_refuses_other_units(velocity: str, acceleration: str | None,
                                                          missing: str) -> None:
    """The Inovance SV660N ESI has 6091h only: rpm was accepted with a note and the drive then took 100 'rpm' as
    100 mm/s (12x too fast on a 5 mm screw)."""
    from ecattool.esi import load
    from tests.conftest import corpus_path

    device = load(corpus_path("esi", "inovance_SV660_EOE_1Axis_V9.12.xml")).devices[0]
    axis = Axis(Feedback.encoder(8388608), Transmission.ballscrew(Exact(5 * MM)), Gear(Fraction(1)), position="mm",
                velocity=velocity, **({"acceleration": acceleration} if acceleration else {}))
    with pytest.raises(InputError, match=f"the device has no {missing}"):
        compute(axis, "generic", device=device)
    ok = Axis(Feedback.encoder(8388608), Transmission.ballscrew(Exact(5 * MM)), Gear(Fraction(1)), position="mm",
              velocity="mm/s", acceleration="mm/s^2")
    d = Drive.from_device(device)
    d.request_state(EcState.PREOP)
    _apply(d, compute(ok, "generic", device=device))
    assert d.units.increments_per_second(d.units.velocity_to_internal(100)) == 100 * Fraction(8388608, 5)
