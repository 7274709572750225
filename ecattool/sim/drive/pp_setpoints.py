"""How profile position takes its set-points (controlword bits 4, 5, 6, 11; statusword bit 12).

* Change set immediately (bit 5 = 1): a rising bit 4 re-plans the move at once; set-point acknowledge falls
  with bit 4 (HDT §4.07.3 "When bit 4 of the controlword returns to 0 bit 12 of the statusword returns to 0
  too"). This is what every family does here.
* Single set-point (bit 5 = 0), where the family's manual describes it (``Behaviour.pp_single_setpoint``):
  a set-point given while a move runs is not taken until that move has ended (Technosoft §7.1 "Finish the
  actual positioning and then start the next positioning"; HDT §4.07.3 "the new target position is acquired
  only at the end of the current positioning"). Technosoft keeps the set-point of the rising edge and starts
  it then; HDT acquires 607Ah at the end, if bit 4 is still 1 ("acquired and executed only when bit 4 ... is
  set to 1 and bit 12 ... is set to 0": ``Behaviour.pp_acquire_at_end``). Set-point acknowledge stays 1 until
  the generator has reached the demand position: Technosoft then waits for bit 4 = 0 (§7.1.1 "after that, the
  master has to reset bit new set-point ... the drive will signalize ... by resetting set-point acknowledge
  bit ... after the reference generator has reached the designated demand position"); HDT clears it at the
  end of the positioning ("When a positioning is terminated the bit 12 of the statusword is set again to 0").
* Technosoft bit 11 with a relative set-point: additive, the increment is added to the previous position to
  reach instead of the position at the time of the command (§7.1; ``Behaviour.pp_additive_bit11``).
* Technosoft §7.1.2 Remark: with 6086h = 3 (S-curve) bit 5 must be 0, "else a command error is issued":
  the set-point is not taken, EMCY 9000h (command error) and Motion Error Register 2000h bit 14
  (``Behaviour.scurve_single_setpoint_only``; docs/decisions.md).
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING

from ecattool.sim.cia402 import Profile, State
from ecattool.sim.drive import polarity

if TYPE_CHECKING:
    from ecattool.sim.drive.app import DriveApp

NEW_SETPOINT, IMMEDIATE, RELATIVE, ADDITIVE = 0x0010, 0x0020, 0x0040, 0x0800
COMMAND_ERROR = 0x9000


class PpSetpoints:
    """The set-point handshake of one axis: a set-point waiting for the running move, the last target taken."""

    __slots__ = ("pending", "last_target", "ramps", "planned_velocity", "settle_s")

    def __init__(self) -> None:
        #: (controlword, 607Ah) of a set-point given while a single set-point move runs
        self.pending: tuple[int, int] | None = None
        #: the last position to reach (internal units), for an additive relative move
        self.last_target: Fraction | None = None
        #: (acceleration, deceleration, jerk time) of the positioning that started from standstill
        self.ramps: tuple[Fraction, Fraction, Fraction] | None = None
        #: the profile velocity the running move was planned with
        self.planned_velocity: Fraction | None = None
        #: how long the axis has been in the position window 6067h since the generator ended, s
        self.settle_s: Fraction | None = None

    def snapshot(self) -> tuple[object, ...]:
        return (self.pending, self.last_target, self.ramps, self.planned_velocity, self.settle_s)

    def profile(self, drive: DriveApp, fresh: Profile) -> Profile:
        """The profile a PP cycle moves by. HDT §4.07.3 (``Behaviour.pp_ramps_at_standstill``): "The acceleration
        ramps ..., deceleration ramps ... and the 'rounding values' ... are adjusted when the motor is standstill
        and a new positioning is starting. The speed instead (profile velocity - index 6081h) is immediately
        adjusted to the set value": the ramps of the positioning that started from standstill, the velocity of
        now (a new one re-plans the running move)."""
        if not drive.behaviour.pp_ramps_at_standstill:
            return fresh
        cia = drive.cia
        if self.ramps is None or (cia.move is None and cia.vel_n == 0):
            self.ramps = (fresh.acceleration, fresh.deceleration, fresh.jerk_time)
        if cia.move is not None and self.planned_velocity != fresh.velocity:
            cia.move = None  # planned again from where the axis is, at the speed it has
        self.planned_velocity = fresh.velocity
        acc, dec, jerk = self.ramps
        if (acc, dec, jerk) == (fresh.acceleration, fresh.deceleration, fresh.jerk_time):
            return fresh
        return Profile(fresh.velocity, acc, dec, jerk, fresh.torque_limited)

    def on_controlword(self, drive: DriveApp, cw: int, prev: int) -> bool:
        """A controlword in profile position, OPERATION ENABLED; True when a set-point was taken."""
        cia = drive.cia
        behaviour = drive.behaviour
        single = behaviour.pp_single_setpoint and not cw & IMMEDIATE
        if cw & NEW_SETPOINT and not prev & NEW_SETPOINT:
            if cw & IMMEDIATE and behaviour.scurve_single_setpoint_only and (drive._read_int(0x6086, 0) or 0) == 3:
                drive._log("command_error", reason="6086h = 3 (S-curve) needs controlword bit 5 = 0")
                drive.motion_error(14)
                drive.emcy(COMMAND_ERROR)
                return False
            if single and cia.target is not None:
                self.pending = (cw, drive._read_int(0x607A, 0) or 0)
                return False
            self.take(drive, cw, drive._read_int(0x607A, 0) or 0)
            return True
        if not cw & NEW_SETPOINT and (not single or (cia.target is None and self.pending is None)):
            cia.setpoint_ack = False
        return False

    def _settle(self, drive: DriveApp, dt: Fraction) -> None:
        """Technosoft §7.2.12 (TS 6125): "If the position actual value is within the position window for a time
        period defined inside the position window time object, this target position is regarded as reached";
        6067h = 2^32 - 1 switches the window off ("reached when the position reference is reached"). 6068h counts
        slow-loop samples (1 ms by default: docs/decisions.md)."""
        read, cia = drive._read_int, drive.cia
        window = read(0x6067, 0)
        if window is None or window == 0xFFFFFFFF:
            return
        assert self.last_target is not None
        inside = abs(drive.units.position_to_user(cia.position - self.last_target)) <= window
        if not inside:
            self.settle_s = None
        else:
            self.settle_s = Fraction(0) if self.settle_s is None else self.settle_s + dt
        cia.target_reached = inside and self.settle_s is not None and \
            self.settle_s * 1000 >= (read(0x6068, 0) or 0)

    def take(self, drive: DriveApp, cw: int, target: int) -> None:
        cia = drive.cia
        relative = bool(cw & RELATIVE)
        target *= polarity.target_signs(drive, 1)[0]  # 607Eh bit 7
        position = drive.units.position_to_internal(target - (0 if relative else drive._home_offset()))
        if relative and cw & ADDITIVE and drive.behaviour.pp_additive_bit11:
            base = self.last_target if self.last_target is not None else cia.position
            cia.new_setpoint(base + position, relative=False)
        else:
            cia.new_setpoint(position, relative=relative)
        self.last_target = cia.target
        self.settle_s = None

    def after_step(self, drive: DriveApp, dt: Fraction) -> bool:
        """After a profile position cycle: the end of a single set-point move starts the waiting set-point and
        ends the handshake; the position window holds bit 10. True when a set-point was taken."""
        cia = drive.cia
        if cia.target is not None or cia.state is not State.OPERATION_ENABLED:
            return False
        if drive.behaviour.pp_position_window and self.last_target is not None:
            self._settle(drive, dt)
        cw = cia.controlword
        if self.pending is not None:
            pending, self.pending = self.pending, None
            if drive.behaviour.pp_acquire_at_end:
                if cw & NEW_SETPOINT:
                    self.take(drive, cw, drive._read_int(0x607A, 0) or 0)
                    return True
            else:
                self.take(drive, *pending)
                return True
        if cia.setpoint_ack and drive.behaviour.pp_single_setpoint and not cw & IMMEDIATE \
                and (not cw & NEW_SETPOINT or drive.behaviour.pp_acquire_at_end):
            cia.setpoint_ack = False
        return False
