"""The physical plant of a simulated drive: what stands between the demand the drive's reference generator makes
(profile, interpolator, the master's CSP/CSV set-points) and the actual values it measures (6063h, 6064h, 606Ch,
6077h, 6078h, 60F4h).

* position modes: a second-order position loop, ``x'' = wn² (r - x) + 2 zeta wn (kff r' - x')`` (natural
  frequency ``wn``, damping ``zeta``, velocity feed-forward ``kff``), run exactly between samples with the demand
  interpolated linearly over the cycle (a ramp is followed with the steady error ``2 zeta (1 - kff) v / wn``; a
  step settles as ``1 - (1 + wn t) e^(-wn t)`` at zeta = 1);
* velocity modes: a first-order velocity loop, ``v' = (v_ref - v) / tau``;
* the torque the motion needs, ``J a + B v + Tc sign(v) + T_load`` (inertia of motor and load reflected to the
  motor, viscous and Coulomb friction, a load torque), limited to the torque limit: beyond it the axis accelerates
  with what the limit leaves, ``(T_max - friction - load) / J``, and lags (following error);
* a speed limit; the motor coasts against its friction while the power stage is off;
* one sample of delay where the manual says so (:attr:`PlantParams.delay`).

Deterministic (floats in a fixed order, no clock). State in increments and increments per second; parameters in
SI units at the motor shaft (:class:`PlantParams`), converted once with the increments per motor revolution.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Literal


#: ``"reference"``: the loop sees the demand one cycle late (Control Techniques CSP/IP insert one interpolation
#: period); ``"sample"``: the actual values are sampled before the new reference is applied (Technosoft §3.2.2)
Delay = Literal["none", "reference", "sample"]


@dataclass(frozen=True, slots=True)
class PlantParams:
    """A motor with its load, at the motor shaft (SI units). Defaults: a 400 W class servo motor with a load of
    the motor's inertia, loops tuned as a commissioning engineer's first stiff setting."""

    #: motor rotor inertia, kg·m²
    motor_inertia: float = 0.3e-4
    #: load inertia reflected to the motor shaft, kg·m² (:func:`reflected_inertia` from the mechanics)
    load_inertia: float = 0.3e-4
    #: viscous friction, N·m per rad/s
    viscous: float = 1.0e-5
    #: Coulomb (dry) friction, N·m
    coulomb: float = 0.02
    #: rated (continuous) torque, N·m: 6076h, the unit of 6077h and 6072h (per mille)
    rated_torque: float = 1.27
    #: peak torque, N·m: what the current limit allows
    peak_torque: float = 3.8
    #: maximum motor speed, rad/s
    max_speed: float = 6000 * 2 * math.pi / 60
    #: position loop natural frequency wn, rad/s
    position_bandwidth: float = 200.0
    #: position loop damping ratio zeta
    damping: float = 1.0
    #: velocity feed-forward of the position loop, 0..1 (1: the demand's velocity is fed to the velocity loop, as
    #: drives are commissioned; 0: the bare loop, whose steady error on a ramp is 2 zeta v / wn)
    velocity_feedforward: float = 1.0
    #: velocity loop time constant, s
    velocity_tau: float = 0.002
    #: one sample of delay (see :data:`Delay`)
    delay: Delay = "none"

    def with_(self, **changes: float | str) -> "PlantParams":
        """A copy with ``changes`` (names of the fields)."""
        return replace(self, **changes)  # type: ignore[arg-type]

    @property
    def inertia(self) -> float:
        return self.motor_inertia + self.load_inertia


#: the families' defaults: the delay their manual names, loops that keep the samples' moves inside their default
#: following-error windows
FAMILY_PLANTS: dict[str, PlantParams] = {
    "technosoft-ipos": PlantParams(delay="sample"),
    "hdt": PlantParams(),
    "controltechniques": PlantParams(delay="reference"),
    "generic": PlantParams(),
}


def plant_for(family: str) -> PlantParams:
    """The default plant of a family (the generic one for any other)."""
    return FAMILY_PLANTS.get(family, FAMILY_PLANTS["generic"])


def reflected_inertia(*, gear_ratio: float = 1.0, load_inertia: float = 0.0, load_mass: float = 0.0,
                      travel_per_load_rev_m: float = 0.0) -> float:
    """The inertia of a load at the motor shaft, kg·m²: a rotary load ``load_inertia`` (kg·m², at the load side of
    a gear of ``gear_ratio`` motor revolutions per load revolution) is divided by the ratio squared; a mass
    ``load_mass`` (kg) moved ``travel_per_load_rev_m`` metres per load revolution (screw lead, belt pulley
    circumference, rack pinion) is ``m (travel / 2 pi)²`` at the load side, divided by the ratio squared too."""
    ratio = gear_ratio or 1.0
    linear = load_mass * (travel_per_load_rev_m / (2 * math.pi)) ** 2
    return (load_inertia + linear) / (ratio * ratio)


def _expm2(a: float, b: float, c: float, d: float, t: float) -> tuple[float, float, float, float]:
    """e^(M t) of the 2x2 matrix M = [[a, b], [c, d]] (scaling and squaring of a Taylor series)."""
    norm = max(abs(a), abs(b), abs(c), abs(d)) * t
    squarings = max(0, int(math.ceil(math.log2(norm))) + 1) if norm > 0.5 else 0
    h = t / (1 << squarings)
    ma, mb, mc, md = a * h, b * h, c * h, d * h
    ra, rb, rc, rd = 1.0, 0.0, 0.0, 1.0  # result
    ta, tb, tc, td = 1.0, 0.0, 0.0, 1.0  # term
    for k in range(1, 20):
        ta, tb, tc, td = ((ta * ma + tb * mc) / k, (ta * mb + tb * md) / k, (tc * ma + td * mc) / k,
                          (tc * mb + td * md) / k)
        ra, rb, rc, rd = ra + ta, rb + tb, rc + tc, rd + td
    for _ in range(squarings):
        ra, rb, rc, rd = ra * ra + rb * rc, ra * rb + rb * rd, rc * ra + rd * rc, rc * rb + rd * rd
    return ra, rb, rc, rd


class Plant:
    """The motor and its load under the drive's loops, in increments (one per drive; see the module doc).

    ``error`` is the actual position minus the demand (increments; negative while the axis lags a move in the
    positive direction), ``velocity`` the actual velocity (increments/s), ``torque`` the torque the motor makes
    (N·m)."""

    __slots__ = ("params", "counts_per_rev", "dt", "error", "velocity", "torque", "load_torque", "torque_limit",
                 "speed_limit", "pending", "sampled", "version", "limits_key", "limits_mode", "samples_first", "_delay_reference", "_ramp_lag", "_fixed", "_phi", "_j", "_b", "_tc", "_vmax", "_decay", "_tau_gain",
                 "_limited")

    def __init__(self, params: PlantParams, counts_per_rev: float, dt: float) -> None:
        self.params = params
        self.counts_per_rev = counts_per_rev
        self.dt = dt
        self.error = 0.0
        self.velocity = 0.0
        self.torque = 0.0
        #: an external torque on the motor shaft, N·m (a load, a spring, an obstacle pushing back)
        self.load_torque = 0.0
        #: the torque limit in force, N·m (the drive sets it from 6072h/60E0h/60E1h; at most the peak torque)
        self.torque_limit = params.peak_torque
        #: the speed limit in force, increments/s (the drive sets it from 6080h; at most the motor's)
        self.speed_limit = 0.0
        #: the demand change the loop has not seen yet (delay "reference"), increments
        self.pending = 0.0
        #: the actual values as sampled before this cycle's reference (delay "sample"): (error, velocity)
        self.sampled = (0.0, 0.0)
        #: the last cycle ran into the torque or the speed limit
        self._limited = False
        #: the drive store's version the geometry was taken at
        self.version = 0
        #: the drive store's version and the mode the speed limit (:attr:`speed_limit`) was made at (0: not yet)
        self.limits_key = 0
        self.limits_mode = 0
        self._derive()

    def _derive(self) -> None:
        p, dt = self.params, self.dt
        rad = 2 * math.pi / self.counts_per_rev  # rad per increment
        self._j = p.inertia * rad  # N·m per increment/s²
        self._b = p.viscous * rad  # N·m per increment/s
        self._tc = p.coulomb
        self._vmax = p.max_speed / rad
        self.speed_limit = self._vmax
        wn, zeta = p.position_bandwidth, p.damping
        self._phi = _expm2(0.0, 1.0, -wn * wn, -2 * zeta * wn, dt)
        #: the steady error of the position loop per increment/s of a ramp, 2 zeta (1 - kff) / wn
        self._ramp_lag = 2 * zeta * (1 - p.velocity_feedforward) / wn
        #: the actual values are sampled before the reference (delay "sample")
        self.samples_first = p.delay == "sample"
        #: the loop sees the demand one cycle late (delay "reference")
        self._delay_reference = p.delay == "reference"
        #: a position-loop cycle that left the plant as it found it: (the demand step, error, velocity, pending,
        #: load torque, torque limit, speed limit) it started from (:meth:`follow_position`), else None
        self._fixed: tuple[float, ...] | None = None
        self._decay = math.exp(-dt / p.velocity_tau) if p.velocity_tau > 0 else 0.0
        self._tau_gain = p.velocity_tau * (1 - self._decay)
        self.torque_limit = min(self.torque_limit, p.peak_torque) if self.torque_limit else p.peak_torque

    def set_params(self, params: PlantParams) -> None:
        """New parameters (a sim script's ``plant`` command); the state is kept."""
        self.params = params
        self.torque_limit = params.peak_torque
        self._derive()
        self.limits_key = 0

    @property
    def max_speed(self) -> float:
        """The motor's own maximum speed, increments/s (:attr:`speed_limit` is at most this)."""
        return self._vmax

    def set_geometry(self, counts_per_rev: float, dt: float) -> None:
        """Increments per motor revolution and the cycle in seconds (derived values made again on a change)."""
        if dt != self.dt or counts_per_rev != self.counts_per_rev:
            self.dt = dt
            self.counts_per_rev = counts_per_rev
            self._derive()
            self.limits_key = 0

    # --- the cycle -----------------------------------------------------------------------------------------
    def follow_position(self, moved: float, reference_delay: bool = True) -> None:
        """One cycle in a position mode: the demand moved by ``moved`` increments over the cycle. Without
        ``reference_delay`` the loop sees the demand at once even where the family delays it (the mode's own
        generator already delayed it: Control Techniques interpolated position); a reference still held back from
        an earlier cycle is then passed on."""
        fixed = self._fixed
        e0, v0, p0 = self.error, self.velocity, self.pending
        if fixed is not None and fixed[0] == moved and fixed == (moved, e0, v0, p0, self.load_torque,
                                                               self.torque_limit, self.speed_limit, reference_delay):
            # the cycle before started here with the same demand step and ended here (a steady ramp or a standstill
            # settled to the float's last bit): this one does the same; only the delayed sample moves on
            if self.samples_first:
                self.sampled = (e0 - moved, v0)
            return
        # the loop's step, inline (every cycle of a position mode): what the loop's reference moved by, its error
        loop_moved, y0 = moved, e0
        if self._delay_reference:
            if reference_delay:
                loop_moved, y0 = p0, e0 + p0
                self.pending = moved
            elif p0:
                loop_moved, y0 = moved + p0, e0 + p0
                self.pending = 0.0
        elif self.samples_first:
            self.sampled = (e0 - moved, v0)  # the previous actual, against the new demand
        s = loop_moved / self.dt
        c = self._ramp_lag * s
        # in (z, w) = (error + c, velocity - s) the loop is autonomous over the cycle: one matrix step
        z0, w0 = y0 + c, v0 - s
        a, b, cc, d = self._phi
        self._finish(v0, cc * z0 + d * w0 + s, a * z0 + b * w0 - c - y0 + loop_moved, moved)
        self._fixed = (moved, e0, v0, p0, self.load_torque, self.torque_limit, self.speed_limit, reference_delay) \
            if e0 == self.error and v0 == self.velocity and p0 == self.pending else None

    def follow_velocity(self, reference: float, moved: float) -> None:
        """One cycle in a velocity mode: the velocity loop towards ``reference`` increments/s; the demand position
        (the reference integrated) moved by ``moved``."""
        self._fixed = None
        if self.params.delay == "sample":
            self.sampled = (self.error - moved, self.velocity)  # the previous actual, against the new demand
        v0 = self.velocity
        v1 = reference + (v0 - reference) * self._decay
        travelled = reference * self.dt + (v0 - reference) * self._tau_gain
        self._finish(v0, v1, travelled, moved)

    def apply_torque(self, torque: float, moved: float = 0.0) -> None:
        """One cycle with the motor making ``torque`` N·m (a torque mode, or 0 with the power stage off: the axis
        coasts against its friction and load); the demand moved by ``moved``."""
        self._fixed = None
        if self.params.delay == "sample":
            self.sampled = (self.error - moved, self.velocity)  # the previous actual, against the new demand
        limit = self.torque_limit
        torque = max(-limit, min(limit, torque))
        self._accelerate(self.velocity, torque, moved)

    def _finish(self, v0: float, v1: float, travelled: float, moved: float) -> None:
        """The torque the step from ``v0`` to ``v1`` needs; within the torque and speed limits it is taken, beyond
        them the axis accelerates with the limit."""
        dt = self.dt
        vm = (v0 + v1) / 2
        friction = self._b * vm + (self._tc if vm > 0 else -self._tc if vm < 0 else 0.0)
        torque = self._j * (v1 - v0) / dt + friction + self.load_torque
        limit = self.torque_limit
        if -limit <= torque <= limit and -self.speed_limit <= v1 <= self.speed_limit:
            self.torque = torque
            self.velocity = v1
            self.error += travelled - moved
            self._limited = False
            if moved == 0.0 and -1e-6 < self.error < 1e-6 and -1e-6 < v1 < 1e-6:
                self.error = self.velocity = 0.0  # settled: the loop holds the axis on the demand
                self.torque = self.load_torque
            return
        self._accelerate(v0, max(-limit, min(limit, torque)), moved)
        self._limited = True

    def _accelerate(self, v0: float, torque: float, moved: float) -> None:
        """The axis under ``torque`` against friction and load for a cycle (speed-limited)."""
        dt = self.dt
        resist = self._b * v0 + self.load_torque
        net = torque - resist
        if v0 > 0 or (v0 == 0 and net > self._tc):
            net -= self._tc
        elif v0 < 0 or (v0 == 0 and net < -self._tc):
            net += self._tc
        else:
            net = 0.0  # static friction holds the axis
        v1 = v0 + net / self._j * dt
        if v0 != 0 and (v1 > 0) != (v0 > 0) and torque == 0 and abs(self.load_torque) <= self._tc:
            v1 = 0.0  # coasting: friction stops the axis, it does not turn it round
        vmax = self.speed_limit
        v1 = max(-vmax, min(vmax, v1))
        self.torque = torque
        self.velocity = v1
        self.error += (v0 + v1) / 2 * dt - moved

    def state(self) -> tuple[object, ...]:
        """Everything a cycle reads and changes (the quiet-cycle comparison of the process data)."""
        return (self.params, self.counts_per_rev, self.dt, self.error, self.velocity, self.torque, self.load_torque,
                self.torque_limit, self.speed_limit, self.pending, self.sampled, self._limited)

    # --- what the drive reports --------------------------------------------------------------------------------
    def reported(self) -> tuple[float, float]:
        """(error, velocity) as the drive measures them this cycle (the sample before the reference where the
        family samples first)."""
        if self.samples_first:
            return self.sampled
        return self.error, self.velocity

    @property
    def limited(self) -> bool:
        """The last cycle ran into the torque or speed limit."""
        return self._limited

    def take_error(self, amount: float) -> None:
        """The drive moved its demand by ``amount`` increments onto the axis (power stage off: the demand follows
        the actual position)."""
        self._fixed = None
        self.error -= amount
        if self.params.delay == "sample":
            self.sampled = (self.sampled[0] - amount, self.sampled[1])
        self.pending = 0.0

    def torque_per_mille(self) -> int:
        """6077h: the torque in thousandths of the rated torque."""
        rated = self.params.rated_torque
        return int(round(self.torque / rated * 1000)) if rated > 0 else 0
