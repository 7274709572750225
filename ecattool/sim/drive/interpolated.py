"""Interpolated position mode (6060h = 7) on the drive: linear interpolation (60C0h = 0) of the positions the
master writes to 60C1h sub 1, one per interpolation period 60C2h (the simulator's cycle).

* HDT §4.09.1: controlword bit 4 "Enable ip mode" (0 disables the interpolator), statusword bit 12 "Ip mode
  active" (§4.09.2); ``Behaviour.ip_enable_bit``. Control Techniques' controlword has no such bit (Table 7.1:
  bit 4 is "hos" only): its interpolator runs whenever the mode is enabled (docs/decisions.md).
* Control Techniques 7.4.3: "Only linear interpolation is currently supported, this type inserts a delay of
  one interpolation time period" (``Behaviour.ip_delay_periods``): the position demand reaches a record one
  period after the period it was written in.
* Statusword bit 10: the demand is at the last record (HDT §4.09.2 "Target position reached").

The demand moves the axis as CSP does (an ideal tracker: the plant, where there is one, follows it).
"""

from __future__ import annotations

from collections import deque
from fractions import Fraction
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ecattool.sim.drive.app import DriveApp

IP = 7
ENABLE_IP = 0x0010  # controlword bit 4 in interpolated position mode


class Interpolated:
    """The interpolator of one axis: the records on their way to the demand (the delay line)."""

    __slots__ = ("pending", "active")

    def __init__(self) -> None:
        #: records written but not yet reached (internal units), oldest first
        self.pending: deque[Fraction] = deque()
        #: the interpolator runs (statusword bit 12)
        self.active = False

    def snapshot(self) -> tuple[object, ...]:
        return (tuple(self.pending), self.active)

    def enabled(self, drive: DriveApp) -> bool:
        return not drive.behaviour.ip_enable_bit or bool(drive.cia.controlword & ENABLE_IP)

    def step(self, drive: DriveApp, dt: Fraction) -> None:
        """One interpolation period in OPERATION ENABLED without halt."""
        cia = drive.cia
        if not self.enabled(drive):
            self.stop()
            cia.velocity = Fraction(0)
            cia.target_reached = True
            return
        record = drive._read_int(0x60C1, 1) or 0
        if record >= 1 << 31:  # Control Techniques types it UNSIGNED32 (Table 7.34): a position, two's complement
            record -= 1 << 32
        record -= drive._home_offset()
        target = drive.units.position_to_internal(record)
        if not self.active:  # the interpolator starts from where the axis is: no jump
            self.active = True
            self.pending = deque([cia.position] * drive.behaviour.ip_delay_periods)
        self.pending.append(target)
        demand = self.pending.popleft()
        per_inc = drive.units.velocity_from_increments_per_second(Fraction(1))
        cia.follow_position(demand.numerator, demand.denominator, dt, per_inc.numerator, per_inc.denominator)
        cia.target_reached = demand == target

    def stop(self) -> None:
        self.active = False
        self.pending.clear()
