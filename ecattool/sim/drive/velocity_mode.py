"""The velocity demand side of the drive: vl velocity mode (6060h = 2) and the status bits of profile velocity
(6060h = 3) that depend on windows and times.

* vl velocity mode, the default mode of Control Techniques and HDT (CT §7.5, HDT §4.11): the target 6042h
  (rpm times the dimension factor 604Ch, and the set-point factor 604Bh where the drive has it) is limited by
  6046h/6047h, ramped with 6048h (acceleration) and 6049h (deceleration, "delta speed / delta time", a delta
  time of 0 follows at once: HDT §4.11.7), and reported in 6043h (ramp output) and 6044h (actual speed) in the
  units of 6042h. Where the family reads controlword bits 4-6 in vl (HDT §4.11.1: enable ramp, ramp unlock,
  enable reference; ``Behaviour.vl_ramp_bits``) they block the ramp as the manual says.
* profile velocity: statusword bit 10 is set once |60FFh - 606Ch| has stayed within the velocity window 606Dh
  for the window time 606Eh (HDT §4.10.7, Technosoft §10.2.4); bit 12 "speed = 0" follows |606Ch| <= the
  velocity threshold 606Fh, changing only after the new condition has held for the threshold time 6070h
  (HDT §4.10.8; Technosoft §10.1.2 Remark). A drive without those objects keeps the exact comparison.
* Technosoft §10.1 Remark 2: a 60FFh written before profile velocity is entered does not start a motion until
  60FFh is written again (``Behaviour.pv_needs_new_target``; an RxPDO that maps 60FFh writes it every cycle).

The axis is an ideal tracker here: the actual speed is the ramp's output (the plant, where there is one, sits
between them).
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING

from ecattool.esi.model import Direction
from ecattool.od.model import EcState
from ecattool.sim.cia402 import HALT, State
from ecattool.sim.drive import polarity

if TYPE_CHECKING:
    from ecattool.sim.drive.app import DriveApp

_ZERO = Fraction(0)
VL = 2


def counts_per_rev(drive: DriveApp) -> Fraction | None:
    """Increments per motor revolution: 608Fh (encoder increments / motor revolutions) where both are set, else
    the family's fixed resolution (HDT 65536), else None (the speed in rpm cannot move the position)."""
    inc, rev = drive._read_int(0x608F, 1), drive._read_int(0x608F, 2)
    if inc and rev:
        return Fraction(inc, rev)
    cpr = drive.rules.counts_per_rev
    return Fraction(cpr) if cpr else None


def _ratio(drive: DriveApp, index: int) -> Fraction:
    """A numerator/denominator pair (sub 1 / sub 2); 1 where the drive has no such object or a part is 0."""
    num, den = drive._read_int(index, 1), drive._read_int(index, 2)
    return Fraction(num, den) if num and den else Fraction(1)


class VlVelocity:
    """vl velocity mode of one axis: the ramp function generator and its output (rpm)."""

    __slots__ = ("rpm",)

    def __init__(self) -> None:
        #: the ramp output, rpm (exact)
        self.rpm = _ZERO

    def snapshot(self) -> tuple[object, ...]:
        return (self.rpm,)

    # --- the objects, as the drive reads them ------------------------------------------------------------
    @staticmethod
    def limited(drive: DriveApp, target: int) -> int:
        """6042h limited by the minimum and maximum speeds: 6047h (sub 1/2 positive min/max, 3/4 negative) where
        the drive has it, else the amounts 6046h (sub 1 min, sub 2 max) both ways (HDT §4.11.6: "if the reference
        speed is positive, its minimum achievable value is '+ min velocity amount'"). 0 stays 0 (it has no
        sign)."""
        read = drive._read_int
        if target == 0:
            return 0
        if (0x6047, 1) in drive.objects.entries:
            lo, hi = (read(0x6047, 1), read(0x6047, 2)) if target > 0 else (read(0x6047, 3), read(0x6047, 4))
        elif (0x6046, 1) in drive.objects.entries:
            lo, hi = read(0x6046, 1), read(0x6046, 2)
        else:
            return target
        size = abs(target)
        if lo is not None:
            size = max(size, lo)
        if hi is not None:
            size = min(size, hi)
        return size if target > 0 else -size

    @staticmethod
    def _slope(drive: DriveApp, index: int) -> Fraction | None:
        """6048h/6049h/604Ah as a slope in 6042h units per second (delta speed / delta time); None: a delta time
        of 0, the reference is followed at once (HDT §4.11.7/4.11.8)."""
        speed, time = drive._read_int(index, 1), drive._read_int(index, 2)
        if not time:
            return None
        return Fraction(speed or 0, time)

    @staticmethod
    def rpm_per_unit(drive: DriveApp) -> Fraction:
        """rpm per unit of 6042h/6043h/6044h: the dimension factor 604Ch times the set-point factor 604Bh."""
        return _ratio(drive, 0x604C) * _ratio(drive, 0x604B)

    # --- one cycle ---------------------------------------------------------------------------------------
    def step(self, drive: DriveApp, dt: Fraction) -> None:
        """One cycle of vl in OPERATION ENABLED without halt: ramp towards the (limited) target and move."""
        cia = drive.cia
        cpr = counts_per_rev(drive)
        if cpr is not None:
            self.rpm = drive.units.increments_per_second(cia.velocity) * 60 / cpr  # after a halt or a quick stop
        cw = cia.controlword
        per_unit = self.rpm_per_unit(drive)
        goal: Fraction | None = self.limited(drive, drive._read_int(0x6042, 0) or 0) * per_unit
        dimension = _ratio(drive, 0x604C)  # 604Bh "does not influence ... the ramp function" (CT 7.5.9)
        if drive.behaviour.vl_ramp_bits:
            if not cw & 0x10:  # bit 4 = 0: "The motor is stopped with the power on"
                self.rpm = _ZERO
                goal = None
            elif not cw & 0x20:  # bit 5 = 0: "The output of the speed ramp is blocked to the actual value"
                goal = None
            elif not cw & 0x40:  # bit 6 = 0: "The input of the speed ramp function is set to 0"
                goal = _ZERO
        if goal is not None and goal != self.rpm:
            up = abs(goal) > abs(self.rpm) and goal * self.rpm >= 0
            slope = self._slope(drive, 0x6048 if up else 0x6049)
            if slope is None:
                self.rpm = goal
            else:
                change = slope * dimension * dt
                if abs(goal - self.rpm) <= change:
                    self.rpm = goal
                else:
                    self.rpm += change if goal > self.rpm else -change
        if cpr is not None:
            inc_per_s = self.rpm * cpr / 60
            cia.velocity = drive.units.velocity_from_increments_per_second(inc_per_s)
            cia.position += inc_per_s * dt
        cia.target_reached = goal is None or self.rpm == goal

    def report(self, drive: DriveApp) -> None:
        """6043h (ramp output) and 6044h (actual speed) in the units of 6042h, truncated towards 0. Outside
        OPERATION ENABLED, in a halt or a quick stop, they follow the axis."""
        cia = drive.cia
        cpr = counts_per_rev(drive)
        if cia.state is not State.OPERATION_ENABLED or cia.controlword & HALT:
            self.rpm = drive.units.increments_per_second(cia.velocity) * 60 / cpr if cpr is not None else _ZERO
        value = int(self.rpm / self.rpm_per_unit(drive))
        drive._put(0x6043, 0, value)
        drive._put(0x6044, 0, value)


class PvStatus:
    """Statusword bits 10 and 12 of profile velocity from the windows and times of the drive (see the module)."""

    __slots__ = ("in_window_s", "speed_zero", "changing_s", "armed")

    def __init__(self) -> None:
        #: how long |60FFh - 606Ch| has been within 606Dh, s (None: outside)
        self.in_window_s: Fraction | None = None
        #: statusword bit 12 in profile velocity: the axis stands still (it does at power-on)
        self.speed_zero = True
        #: how long the speed condition has differed from :attr:`speed_zero`, s
        self.changing_s = _ZERO
        #: 60FFh was written since profile velocity was entered (Technosoft §10.1 Remark 2)
        self.armed = False

    def snapshot(self) -> tuple[object, ...]:
        return (self.in_window_s, self.speed_zero, self.changing_s, self.armed)

    def update(self, drive: DriveApp, dt: Fraction) -> None:
        """After a profile velocity cycle: the window of bit 10 and the threshold of bit 12."""
        read, entries = drive._read_int, drive.objects.entries
        cia = drive.cia
        actual = drive.units.velocity_to_user(cia.velocity)
        if (0x606D, 0) in entries and cia.state is State.OPERATION_ENABLED and not cia.controlword & HALT:
            sign = polarity.target_signs(drive, 3)[1]  # 607Eh: compared as the drive turns
            target = Fraction(sign * (read(0x60FF, 0) or 0)) if self.target_live(drive) else _ZERO
            if abs(target - actual) <= (read(0x606D, 0) or 0):
                self.in_window_s = _ZERO if self.in_window_s is None else self.in_window_s + dt
            else:
                self.in_window_s = None
            time_ms = read(0x606E, 0) if (0x606E, 0) in entries else 0
            cia.target_reached = self.in_window_s is not None and self.in_window_s * 1000 >= (time_ms or 0)
        if (0x606F, 0) in entries:
            still = abs(actual) <= (read(0x606F, 0) or 0)
            if still == self.speed_zero:
                self.changing_s = _ZERO
            else:
                time_ms = read(0x6070, 0) if (0x6070, 0) in entries else 0
                if self.changing_s * 1000 >= (time_ms or 0):
                    self.speed_zero = still
                    self.changing_s = _ZERO
                else:
                    self.changing_s += dt
        else:
            self.speed_zero = cia.vel_n == 0

    def target_live(self, drive: DriveApp) -> bool:
        """Whether 60FFh drives the motion (Technosoft: not until it is written in profile velocity; an RxPDO
        that maps it writes it every cycle)."""
        if not drive.behaviour.pv_needs_new_target or self.armed:
            return True
        return drive.esm is EcState.OP and any(index == 0x60FF for index, _, _, _ in drive.layout[Direction.RX].entries)
