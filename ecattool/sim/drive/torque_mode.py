"""The torque demand side of the drive: profile torque (6060h = 4) and cyclic synchronous torque (10).

* Profile torque (CT §7.6, CiA-402): the target torque 6071h (per thousand of rated torque) is reached along the
  torque slope 6087h (per thousand of rated torque per second). A slope of 0 (the Control Techniques default,
  7.6.4) is a step: decision "Simulator: torque slope 0" in docs/decisions.md.
* Cyclic synchronous torque: the target (plus the torque offset 60B2h where the drive has it) is the demand
  of the cycle, without a slope.
* Both are limited to the maximum torque 6072h (per thousand, where the drive has it and it is not 0).
* The torque actual value 6077h (and the torque demand 6074h where the drive has it) report the demand.

On a plant (the default) the plant's motor makes the demand torque (:meth:`.plant.Plant.apply_torque`): the
project's inertia and friction, a load torque and the torque limits 6072h/60E0h/60E1h act, and the demand position
follows the axis. On the ideal plant the torque moves the axis through a :class:`TorqueLoad` (acceleration of the
axis for a torque at a speed): :class:`FreeInertia` turns the torque into acceleration through one inertia and no
friction, ``a = T / J``.
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING, Protocol

from ecattool.sim.cia402 import HALT, State
from ecattool.sim.drive.velocity_mode import counts_per_rev

if TYPE_CHECKING:
    from ecattool.sim.drive.app import DriveApp

_ZERO = Fraction(0)
PROFILE_TORQUE, CST = 4, 10
TORQUE_MODES = frozenset({PROFILE_TORQUE, CST})


class TorqueLoad(Protocol):
    """What a torque does to the axis: its acceleration in increments/s² for ``torque`` (per thousand of the
    rated torque) at ``velocity`` (increments/s)."""

    def acceleration(self, torque: Fraction, velocity: Fraction) -> Fraction: ...


class FreeInertia:
    """A rigid inertia without friction: the rated torque accelerates it by ``rated_acceleration`` revolutions/s²
    (default 1000 rev/s², a servo motor with little load), ``counts_per_rev`` increments per revolution."""

    __slots__ = ("rated_acceleration", "counts_per_rev")

    def __init__(self, counts_per_rev: Fraction, rated_acceleration: Fraction = Fraction(1000)) -> None:
        self.counts_per_rev = counts_per_rev
        self.rated_acceleration = rated_acceleration

    def acceleration(self, torque: Fraction, velocity: Fraction) -> Fraction:
        return torque / 1000 * self.rated_acceleration * self.counts_per_rev


class TorqueMode:
    """The torque demand of one axis (per thousand of rated torque) and the load it drives."""

    __slots__ = ("demand", "load")

    def __init__(self, load: TorqueLoad | None = None) -> None:
        self.demand = _ZERO
        #: the load the torque moves (None: :class:`FreeInertia` with the drive's counts per revolution)
        self.load = load

    def snapshot(self) -> tuple[object, ...]:
        return (self.demand, self.load)

    @staticmethod
    def target(drive: DriveApp, mode: int) -> Fraction:
        """The torque the mode asks for: 6071h (+ 60B2h in CST), limited by 6072h."""
        read = drive._read_int
        target = Fraction(read(0x6071, 0) or 0)
        if mode == CST and (0x60B2, 0) in drive.objects.entries:
            target += read(0x60B2, 0) or 0
        limit = read(0x6072, 0) if (0x6072, 0) in drive.objects.entries else None
        if limit:
            target = max(-Fraction(limit), min(Fraction(limit), target))
        return target

    def step(self, drive: DriveApp, mode: int, dt: Fraction) -> None:
        """One cycle in OPERATION ENABLED without halt: the demand towards the target, the axis accelerated."""
        goal = self.target(drive, mode)
        slope = drive._read_int(0x6087, 0) if mode == PROFILE_TORQUE and (0x6087, 0) in drive.objects.entries else 0
        if not slope or abs(goal - self.demand) <= slope * dt:
            self.demand = goal
        else:
            self.demand += slope * dt if goal > self.demand else -slope * dt
        cia = drive.cia
        if drive.plant is not None:
            # the plant's motor makes the torque (:func:`.plant_step.cycle`): its inertia, friction, load and the
            # torque limits 6072h/60E0h/60E1h move the axis, the demand position follows it
            cia.target_reached = self.demand == goal
            return
        load = self.load
        if load is None:
            cpr = counts_per_rev(drive)
            load = self.load = FreeInertia(cpr if cpr is not None else Fraction(1))
        units = drive.units
        v0 = units.increments_per_second(cia.velocity)
        a = load.acceleration(self.demand, v0)
        v1 = v0 + a * dt
        cia.position += (v0 + v1) / 2 * dt
        cia.velocity = units.velocity_from_increments_per_second(v1)
        # profile torque: bit 10 "target reached" once the demand is the target (CiA-402)
        cia.target_reached = self.demand == goal

    def newton_metres(self, rated_torque: float) -> float:
        """The demand in N·m (per thousand of the rated torque ``rated_torque``, 6076h)."""
        demand = self.demand
        return demand.numerator / demand.denominator / 1000 * rated_torque

    def report(self, drive: DriveApp) -> None:
        """6077h (and 6074h) from the demand; outside OPERATION ENABLED or in a halt the demand is 0."""
        cia = drive.cia
        if cia.state is not State.OPERATION_ENABLED or cia.controlword & HALT:
            self.demand = _ZERO
        value = int(self.demand)
        drive._put(0x6077, 0, value)
        drive._put(0x6074, 0, value)
