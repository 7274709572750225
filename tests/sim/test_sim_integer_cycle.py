"""The process data cycle computes in integers (issue 26): CSP and CSV move, and the actual values are
converted, on exact rationals carried as integer numerator and denominator instead of ``Fraction`` objects.
These tests hold it to the ``Fraction`` computation it replaced, kept here as the reference:

* the integer pieces (:func:`floor_ratio`, :func:`reduced`, :meth:`Units.ratios`, :meth:`Cia402.follow_position`,
  :meth:`Cia402.follow_velocity`, :meth:`Trapezoid.at`) against ``Fraction`` arithmetic on random values: negative, zero, huge, and
  values on, just below and just above every integer a floor can land on;
* whole drives of the three families, with the factor groups of the sample projects and random ones: a drive as
  shipped and one whose cycle and actual values are the ``Fraction`` code of before, run through the same random
  outputs (controlwords, modes, targets), compared after every cycle: inputs, store, position, velocity, events.
"""

from __future__ import annotations

import struct
from fractions import Fraction
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ecattool.errors import SdoAbort
from ecattool.esi.model import Direction
from ecattool.od.model import EcState
from ecattool.project.export import slave_configs
from ecattool.sim.drive.mode_parts import MOVED, PARTS
from ecattool.sim import Drive
from ecattool.sim.cia402 import CSP, CSV, HALT, PP, PV, Cia402, State
from ecattool.sim.drive import halt_homing as hh
from ecattool.sim.ramp import Trapezoid
from ecattool.sim.units import (FACTOR_OBJECTS, HdtUnits, Reader, TechnosoftUnits, Units, floor_ratio, reduced,
                                to_int)

#: the integer cycle against the reference Fraction cycle, exact traces: the ideal plant (issue 33)
pytestmark = pytest.mark.usefixtures("ideal_plant")

ROOT = Path(__file__).resolve().parents[2]
FAMILIES = ("hdt", "technosoft-ipos", "controltechniques")
SAMPLES = {"hdt": "hdt", "technosoft-ipos": "technosoft_ipos", "controltechniques": "controltechniques"}

# --- the integer pieces against Fraction arithmetic -------------------------------------------------------

#: integers a drive meets: small, around the 32-bit bounds, beyond them, both signs
INTS = st.one_of(st.integers(-1000, 1000), st.integers(-(2**33), 2**33), st.integers(-(2**70), 2**70),
                 st.sampled_from((0, 1, -1, 2**31 - 1, -(2**31), 2**32 - 1, 65536, 3221225472, 2684354560)))
DENS = st.one_of(st.integers(1, 1000), st.integers(1, 2**40), st.sampled_from((1, 9, 60, 1000, 65536, 2684354560)))


@st.composite
def rationals(draw: st.DrawFn) -> Fraction:
    """A rational anywhere, or on / one part in its denominator below / above an integer (the floor's edges)."""
    den = draw(DENS)
    if draw(st.booleans()):
        return Fraction(draw(INTS), den)
    return Fraction(draw(INTS) * den + draw(st.sampled_from((-1, 0, 1))), den)


FACTOR = st.tuples(INTS, INTS)  # a factor object's two parts as a reader returns them (0 and negative included)


def _reader(parts: dict[tuple[int, int], int]) -> Reader:
    return lambda index, sub: parts.get((index, sub))


@st.composite
def units(draw: st.DrawFn) -> Units:
    parts: dict[tuple[int, int], int] = {}
    for index in sorted(FACTOR_OBJECTS - {0x60C2}):
        if draw(st.booleans()):
            parts[(index, 1)], parts[(index, 2)] = draw(FACTOR)
        if index in (0x608A, 0x608C, 0x608E):
            parts[(index, 0)] = draw(st.integers(0, 3))
    kind = draw(st.sampled_from(("generic", "hdt", "technosoft", "technosoft-old")))
    read = _reader(parts)
    if kind == "generic":
        return Units(read)
    if kind == "hdt":
        return HdtUnits(read)
    return TechnosoftUnits(read, cia402_2=kind == "technosoft", slow_loop_s=draw(st.sampled_from(
        (Fraction(1, 1000), Fraction(1, 4000), Fraction(1, 3)))))


@settings(max_examples=150, deadline=None)
@given(u=units(), value=rationals(), x=rationals())
def test_integer_conversions_are_the_fraction_ones(u: Units, value: Fraction, x: Fraction) -> None:
    pn, pd, vn, vd, sn, sd = u.ratios()
    assert pd > 0 and vd > 0 and sd > 0 and sn > 0
    assert Fraction(pn, pd) == u.position_factor() and Fraction(vn, vd) == u.velocity_factor()
    # every family's internal velocity is increments/s times a constant, and back by dividing by it
    assert u.increments_per_second(x) == x * Fraction(sn, sd)
    assert u.velocity_from_increments_per_second(x) == x * Fraction(sd, sn)
    n, d = value.numerator, value.denominator
    assert floor_ratio(n, d, pn, pd) == to_int(u.position_to_user(value)) == u.position_to_user_int(value)
    assert floor_ratio(n, d, vn, vd) == to_int(u.velocity_to_user(value)) == u.velocity_to_user_int(value)
    assert n // d == to_int(value)


@settings(max_examples=100, deadline=None)
@given(num=INTS, den=INTS.filter(bool))
def test_reduced_is_what_a_fraction_holds(num: int, den: int) -> None:
    f = Fraction(num, den)
    assert reduced(num, den) == (f.numerator, f.denominator)


DT = st.sampled_from((Fraction(1, 1000), Fraction(1, 4000), Fraction(1, 250), Fraction(0), Fraction(3, 7)))


@settings(max_examples=150, deadline=None)
@given(start=rationals(), target=rationals(), dt=DT, ratio=rationals().filter(lambda r: r > 0),
       velocity=rationals())
def test_csp_and_csv_in_integers_are_the_fraction_steps(start: Fraction, target: Fraction, dt: Fraction,
                                                        ratio: Fraction, velocity: Fraction) -> None:
    """The CSP and CSV cycle of before: velocity = vel_from_inc((target - position) / dt), position = target;
    velocity = target velocity, position += inc(velocity) * dt (``ratio``: increments/s per velocity unit)."""
    cia = Cia402()
    cia.position = start
    cia.follow_position(target.numerator, target.denominator, dt, ratio.denominator, ratio.numerator)
    assert cia.position == target and cia.target_reached
    assert cia.velocity == ((target - start) / dt / ratio if dt else 0)
    assert (cia.pos_n, cia.pos_d, cia.vel_n, cia.vel_d) == (target.numerator, target.denominator,
                                                            cia.velocity.numerator, cia.velocity.denominator)
    cia.follow_velocity(velocity.numerator, velocity.denominator, dt, ratio.numerator, ratio.denominator)
    assert cia.velocity == velocity and cia.position == target + velocity * ratio * dt
    assert (cia.pos_n, cia.pos_d) == (cia.position.numerator, cia.position.denominator)
    cia.velocity = velocity  # the Fraction way in still works, and reads back as set
    assert (cia.vel_n, cia.vel_d) == (velocity.numerator, velocity.denominator) and cia.velocity is velocity


def _fraction_at(ramp: Trapezoid, time: Fraction) -> tuple[Fraction, Fraction]:
    """``Trapezoid.at`` as it was, in Fractions."""
    if time >= ramp.duration or not ramp.segments:
        return ramp.target, Fraction(0)
    seg = ramp.segments[0]
    for s in ramp.segments:
        if s[0] > time:
            break
        seg = s
    t0, p0, v0, a = seg
    tau = time - t0
    return p0 + v0 * tau + a * tau * tau / 2, v0 + a * tau


POSITIVE = rationals().filter(lambda r: r > 0)


@settings(max_examples=100, deadline=None)
@given(start=rationals(), v0=rationals(), target=rationals(), vmax=POSITIVE, acc=POSITIVE, dec=POSITIVE,
       times=st.lists(st.one_of(rationals().map(abs), st.integers(0, 50).map(lambda k: Fraction(k, 1000))),
                      min_size=1, max_size=8))
def test_a_trapezoid_in_integers_is_the_fraction_one(start: Fraction, v0: Fraction, target: Fraction,
                                                     vmax: Fraction, acc: Fraction, dec: Fraction,
                                                     times: list[Fraction]) -> None:
    ramp = Trapezoid(start, v0, target, vmax, acc, dec)
    for time in times + [t for t, _, _, _ in ramp.segments] + [ramp.duration]:  # every segment's edges too
        got = ramp.at(time)
        assert got == _fraction_at(ramp, time)
        assert all(isinstance(x, Fraction) for x in got)


# --- whole drives: the shipped cycle against the Fraction cycle of before ------------------------------------

class FractionDrive(Drive):
    """The motion step and the actual values as they were computed before the integer cycle: ``Fraction``
    conversions (``Units.position_to_internal`` & co.), CSP and CSV on ``Fraction`` positions, ``to_int``, and
    the profile of PP and PV made afresh every cycle (the shipped drive keeps it while nothing it reads changes)."""

    def step(self, cycles: int = 1) -> None:
        if not self.has_cia402:
            return
        dt = self.cycle_time()
        u, cia = self.units, self.cia
        mode: int | None = None
        for _ in range(cycles):
            mode = self.mode()
            homing_before = cia.homing
            moving = cia.state is State.OPERATION_ENABLED and not cia.controlword & HALT
            if moving and mode == CSP:
                target = u.position_to_internal((self._read_int(0x607A, 0) or 0) - self._home_offset())
                delta = target - cia.position
                cia.velocity = u.velocity_from_increments_per_second(delta / dt) if dt else Fraction(0)
                cia.position = target
                cia.target_reached = True
            elif moving and mode == CSV:
                cia.velocity = u.velocity_to_internal(self._read_int(0x60FF, 0) or 0)
                cia.position = cia.position + u.increments_per_second(cia.velocity) * dt
            elif moving and mode in MOVED:  # the parts of vl, torque and IP (no integer path of their own)
                self.modes.step(self, mode, dt)
            else:
                cia.step(mode, dt, target_position=Fraction(0),
                         target_velocity=u.velocity_to_internal(self._read_int(0x60FF, 0) or 0)
                         if moving and mode == PV and self.modes.pv.target_live(self) else Fraction(0),
                         profile_velocity=Fraction(0), acceleration=Fraction(0),
                         inc_per_s=u.increments_per_second, vel_from_inc_per_s=u.velocity_from_increments_per_second,
                         inc_per_s2=u.increments_per_second2, halt_deceleration=hh.halt_decel_for_step(self, mode),
                         profile=(self._make_profile(mode) if mode == PV
                                  else self.modes.pp.profile(self, self._make_profile(mode)))
                         if moving and mode in (PP, PV) else None)
            if homing_before is not cia.homing:
                hh.after_step(self, homing_before)
            if mode == PP and cia.target is None and self.modes.pp.after_step(self, dt):
                self._report_blocked_motion()
            if mode in PARTS:
                self.modes.after(self, mode, dt)
            self._after_step(dt)  # following error, automatic transitions: no arithmetic of the cycle's own
        self._refresh_inputs(mode)

    def _refresh_inputs(self, mode: int | None = None) -> None:
        if not getattr(self, "has_cia402", False):
            return
        if mode is None:
            mode = self.mode()
        cia, u = self.cia, self.units
        sw = cia.statusword(mode=mode) | (0x0800 if self.limit_active else 0)
        if mode in PARTS:
            sw |= self.modes.status_bits(self, mode)
        if self.family == "technosoft-ipos" and mode == 6 and cia.homing.name == "IN_PROGRESS":
            sw |= 0x0100 | (0x0080 if self.homing_warning else 0)
        if self.family == "technosoft-ipos" and cia.state in (State.OPERATION_ENABLED, State.QUICK_STOP,
                                                             State.FAULT_REACTION):
            sw |= 0x8000
        if self.family == "technosoft-ipos":
            self._put(0x2000, 0, self.motion_errors())
        user_position = to_int(u.position_to_user(cia.position)) + self._home_offset()
        error = to_int(u.position_to_user(cia.following_error)) if cia.following_error else 0
        self._put_all(((0x6041, 0), (0x6063, 0), (0x6064, 0), (0x6062, 0), (0x606C, 0), (0x603F, 0), (0x60F4, 0)),
                      (sw, to_int(cia.position), user_position, user_position + error,
                       to_int(u.velocity_to_user(cia.velocity)), cia.fault_code, error))


def _sample_factors() -> dict[str, list[tuple[int, int, int]]]:
    """The factor objects (and 60C2h) each sample project's startup list writes, per family."""
    out = {}
    for family, sample in SAMPLES.items():
        (cfg,) = slave_configs(ROOT / "samples" / sample / "project.yaml")
        out[family] = [(s.index, s.subindex, int(s.value)) for s in cfg.startup
                       if s.index in FACTOR_OBJECTS and isinstance(s.value, int)]
    return out


SAMPLE_FACTORS = _sample_factors()


def _write(d: Drive, index: int, sub: int, value: int) -> int | None:
    e = d._entries.get((index, sub))
    if e is None:
        return -1
    try:
        d.sdo_download(index, sub, (value & ((1 << e.bit_size) - 1)).to_bytes((e.bit_size + 7) // 8, "little"))
    except SdoAbort as abort:
        return abort.code
    return None


def _pair(family: str, writes: list[tuple[int, int, int]]) -> tuple[Drive, Drive]:
    drives = (Drive.from_profile(family), FractionDrive.from_profile(family))
    for d in drives:
        d.request_state(EcState.PREOP)
    for index, sub, value in writes:
        assert _write(drives[0], index, sub, value) == _write(drives[1], index, sub, value)
    for d in drives:
        d.configure_dc(0x0300, 1_000_000)  # SYNC0 1 ms: CT's positioning modes need DC in OP (CT 1857)
        d.request_state(EcState.SAFEOP)
        d.request_state(EcState.OP)
    return drives


def _outputs(d: Drive, controlword: int, position: int, velocity: int, home: int = 0,
             profile: tuple[int, int] = (0, 0)) -> bytes:
    """The output image with these values where the mapping has them; those it lacks (Control Techniques maps
    no target, Technosoft no 60FFh) are written by SDO, as a master does it. ``profile``: the profile velocity
    and acceleration (6081h, 6083h, 6084h), left alone where (0, 0) and not mapped."""
    out = bytearray(d.process_image_sizes()[0])
    values = {0x607A: position, 0x60FF: velocity, 0x607C: home, 0x6081: profile[0], 0x6083: profile[1],
              0x6084: profile[1]}
    if profile == (0, 0):
        mapped = {e[0] for e in d.layout[Direction.RX].entries}
        values = {i: v for i, v in values.items() if i < 0x6081 or i > 0x6084 or i in mapped}
    for index, _sub, offset, bits in d.layout[Direction.RX].entries:
        at = offset // 8
        if index == 0x6040 and bits == 16:
            out[at:at + 2] = struct.pack("<H", controlword)
        elif index in values and bits == 32:
            out[at:at + 4] = struct.pack("<i", values.pop(index))
    for index, value in values.items():
        _write(d, index, 0, value)
    return bytes(out)


def _observed(d: Drive) -> tuple[object, ...]:
    return (dict(d._store), d.cia.position, d.cia.velocity, d.cia.following_error, d.cia402_state,
            [(e.kind, e.data) for e in d.events], [m.to_bytes() for m in d.emergencies])


#: random factor groups written in PRE-OP (each family refuses what its manual refuses, both drives alike)
FACTOR_WRITES = st.lists(st.tuples(st.sampled_from((0x6093, 0x6094, 0x6097, 0x608F, 0x6091, 0x6092, 0x6096,
                                                    0x210F)), st.integers(1, 2),
                                   st.one_of(st.integers(0, 70_000), st.integers(0, 2**32 - 1))), max_size=6)
#: controlwords: enable, enable + halt, enable + new set-point (PP), quick stop, shutdown, fault reset
CONTROLWORDS = (0x0F, 0x0F, 0x0F, 0x10F, 0x1F, 0x02, 0x06, 0x80)
TARGETS = st.one_of(st.integers(-1000, 1000), st.integers(-(2**31), 2**31 - 1))
#: (controlword, target position, target velocity, cycles, mode written before, home offset written before,
#: profile velocity and acceleration)
STEP = st.tuples(st.sampled_from(CONTROLWORDS), TARGETS, TARGETS, st.integers(1, 5),
                 st.one_of(st.none(), st.sampled_from((CSP, CSP, CSV, PP, PV))),
                 st.one_of(st.none(), st.integers(-5000, 5000)),
                 st.one_of(st.just((0, 0)), st.tuples(st.sampled_from((1000, 50_000, 7)),
                                                       st.sampled_from((10_000, 2_000_000, 3)))))


@settings(max_examples=40, deadline=None)
@given(family=st.sampled_from(FAMILIES), sample=st.booleans(), writes=FACTOR_WRITES,
       steps=st.lists(STEP, min_size=1, max_size=10))
def test_a_drive_cycle_in_integers_is_the_fraction_cycle(family: str, sample: bool,
                                                         writes: list[tuple[int, int, int]],
                                                         steps: list[tuple[int, int, int, int, int | None,
                                                                           int | None, tuple[int, int]]]) -> None:
    fast, ref = _pair(family, (SAMPLE_FACTORS[family] if sample else []) + writes)
    for d in (fast, ref):
        for cw in (0x06, 0x07, 0x0F):
            d.exchange(_outputs(d, cw, 0, 0))
    for controlword, position, velocity, cycles, mode, home, profile in steps:
        if mode is not None:
            assert _write(fast, 0x6060, 0, mode) == _write(ref, 0x6060, 0, mode)
        outputs = _outputs(fast, controlword, position, velocity, home or 0, profile)
        assert _outputs(ref, controlword, position, velocity, home or 0, profile) == outputs
        for _ in range(cycles):
            assert fast.exchange(outputs) == ref.exchange(outputs)
            assert _observed(fast) == _observed(ref)


@settings(max_examples=10, deadline=None)
@given(family=st.sampled_from(FAMILIES), speed=st.integers(-(2**20), 2**20).filter(bool),
       mode=st.sampled_from((CSP, CSV)))
def test_moving_with_the_sample_factors_for_many_cycles(family: str, speed: int, mode: int) -> None:
    """A target moving at a constant speed for 200 cycles with the sample project's factor group: every cycle
    moves, so every one runs the integer path."""
    fast, ref = _pair(family, SAMPLE_FACTORS[family])
    if mode not in fast.rules.supported_modes:
        mode = CSP  # Control Techniques has no CSV
    for d in (fast, ref):
        assert _write(d, 0x6060, 0, mode) is None
        for cw in (0x06, 0x07, 0x0F):
            d.exchange(_outputs(d, cw, 0, 0))
        assert d.cia402_state is State.OPERATION_ENABLED
    for k in range(200):
        outputs = _outputs(fast, 0x0F, (k * speed) % 2**31, speed)
        assert _outputs(ref, 0x0F, (k * speed) % 2**31, speed) == outputs
        assert fast.exchange(outputs) == ref.exchange(outputs)
        assert _observed(fast) == _observed(ref)
    assert fast.cia.position != 0 and fast.cia.velocity != 0


@settings(max_examples=12, deadline=None)
@given(family=st.sampled_from(("hdt", "technosoft-ipos")), mode=st.sampled_from((PP, PV)),  # CT has neither
       changes=st.lists(st.tuples(st.sampled_from((1000, 200_000)), st.integers(1, 5_000_000),
                                  st.sampled_from((0, 5000, -(10**6))), st.integers(1, 25)), min_size=1, max_size=4))
def test_profile_moves_see_every_change_of_their_profile(family: str, mode: int,
                                                         changes: list[tuple[int, int, int, int]]) -> None:
    """PP and PV with the profile velocity, acceleration and target changed during the motion (PP: a new
    set-point with each change): the drive that keeps its profile between changes moves as the one that makes
    it every cycle."""
    fast, ref = _pair(family, SAMPLE_FACTORS[family])
    for d in (fast, ref):
        assert _write(d, 0x6060, 0, mode) is None
        for cw in (0x06, 0x07, 0x0F):
            d.exchange(_outputs(d, cw, 0, 0))
    moved = False
    for velocity, acceleration, target, cycles in changes:
        for k in range(cycles):
            cw = 0x1F if mode == PP and k == 1 else 0x0F  # a rising set-point bit on the second cycle
            outputs = _outputs(fast, cw, target, target, 0, (velocity, acceleration))
            assert _outputs(ref, cw, target, target, 0, (velocity, acceleration)) == outputs
            assert fast.exchange(outputs) == ref.exchange(outputs)
            assert _observed(fast) == _observed(ref)
            moved = moved or fast.cia.velocity != 0
    assert moved or all(t == 0 for _, _, t, _ in changes) or fast.cia402_state is not State.OPERATION_ENABLED
