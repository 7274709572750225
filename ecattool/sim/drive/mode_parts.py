"""The demand side of the modes beyond PP, PV, CSP, CSV and homing, one composed part per mode family:
:class:`~.velocity_mode.VlVelocity` (vl, 2), :class:`~.velocity_mode.PvStatus` (the window bits of profile
velocity, 3), :class:`~.torque_mode.TorqueMode` (profile torque 4, CST 10) and
:class:`~.interpolated.Interpolated` (interpolated position, 7). :class:`ModeParts` holds them for one axis and
steps the one the mode of operation selects."""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING

from ecattool.sim.cia402 import HALT, State
from ecattool.sim.drive.interpolated import IP, Interpolated
from ecattool.sim.drive.pp_setpoints import PpSetpoints
from ecattool.sim.drive.torque_mode import CST, PROFILE_TORQUE, TorqueMode
from ecattool.sim.drive.velocity_mode import VL, PvStatus, VlVelocity

if TYPE_CHECKING:
    from ecattool.sim.drive.app import DriveApp

PV = 3
#: the modes a part moves (in OPERATION ENABLED without halt)
MOVED = frozenset({VL, PROFILE_TORQUE, IP, CST})
#: the modes a part reports in (every cycle, moved or not)
PARTS = MOVED | {PV}


class ModeParts:
    """The parts of one axis (made again with the drive application)."""

    __slots__ = ("vl", "pv", "torque", "ip", "pp")

    def __init__(self) -> None:
        self.vl = VlVelocity()
        self.pv = PvStatus()
        self.torque = TorqueMode()
        self.ip = Interpolated()
        self.pp = PpSetpoints()

    def snapshot(self) -> tuple[object, ...]:
        """The parts' state, for the quiet-cycle comparison of the process data."""
        return (self.vl.snapshot(), self.pv.snapshot(), self.torque.snapshot(), self.ip.snapshot(),
                self.pp.snapshot())

    def mode_changed(self) -> None:
        """6060h was written: the interpolator starts afresh, the PV window timers too, the torque demand is the
        new mode's."""
        self.ip.stop()
        self.pv.in_window_s = None
        self.pv.changing_s = Fraction(0)
        self.torque.demand = Fraction(0)

    def step(self, drive: DriveApp, mode: int, dt: Fraction) -> None:
        """One cycle of ``mode`` (one of :data:`MOVED`) in OPERATION ENABLED without halt."""
        if mode == VL:
            self.vl.step(drive, dt)
        elif mode == IP:
            self.ip.step(drive, dt)
        else:
            self.torque.step(drive, mode, dt)

    def after(self, drive: DriveApp, mode: int, dt: Fraction) -> None:
        """After every cycle of ``mode``, moved or not: the values and bits the parts report."""
        if mode == VL:
            self.vl.report(drive)
        elif mode == PV:
            self.pv.update(drive, dt)
        elif mode == PROFILE_TORQUE or mode == CST:
            self.torque.report(drive)
        if self.ip.active and (mode != IP or not _moving(drive)):
            self.ip.stop()

    def status_bits(self, drive: DriveApp, mode: int) -> int:
        """Statusword bits the parts own: 12 "speed = 0" in PV, 12 "ip mode active" in IP, 12 "target torque
        followed" in CST (as CSP/CSV)."""
        if mode == PV:
            return 0x1000 if self.pv.speed_zero else 0
        if mode == IP:
            return 0x1000 if self.ip.active else 0
        if mode == CST:
            return 0x1000 if _moving(drive) else 0
        return 0


def _moving(drive: DriveApp) -> bool:
    """OPERATION ENABLED without halt: the mode's demand drives the axis."""
    cia = drive.cia
    return cia.state is State.OPERATION_ENABLED and not cia.controlword & HALT
