"""Supervision of the actual values the plant gives (:mod:`.plant`): the following error and its window, the
position window of target reached, and the actual values as the drive reports them.

* following error (6065h window in position user units, 6066h time in ms): in the position modes (PP, IP,
  homing, CSP) an error beyond the window for longer than the time sets statusword bit 13 and faults the drive
  with 8611h — the family's fault reaction and an EMCY (HDT §4.06.5; CiA-402 for the others). A drive without
  both objects does not supervise (Control Techniques has no 6066h); 6065h = FFFFFFFFh switches the supervision
  off; HDT caps the window at 32,768 pulses (§4.06.5, ``Behaviour``);
* target reached in PP (statusword bit 10): the profile has ended and the actual position has stayed within
  the position window 6067h of the target for the window time 6068h (ms; 0 where the drive lacks them);
* 6063h, 6064h, 6062h, 606Ch, 6077h, 6078h and 60F4h from the plant's measurement.
"""

from __future__ import annotations

from fractions import Fraction
from math import floor
from typing import TYPE_CHECKING

from ecattool.sim.cia402 import CSP, HALT, HOMING, PP, State
from ecattool.sim.drive import polarity
from ecattool.sim.drive.supervision_state import Supervision
from ecattool.sim.units import floor_ratio

_ENABLED = State.OPERATION_ENABLED

if TYPE_CHECKING:
    from ecattool.sim.drive.app import DriveApp

#: the modes whose following error is supervised (CiA-402: pp, ip, hm, csp)
POSITION_MODES = frozenset({PP, 7, HOMING, CSP})
#: the actual values :func:`report_actual` refreshes, in its order
_ACTUAL = ((0x6041, 0), (0x6063, 0), (0x6064, 0), (0x6062, 0), (0x606C, 0), (0x603F, 0), (0x60F4, 0), (0x6077, 0),
           (0x6078, 0))


def following_error(drive: "DriveApp") -> float:
    """Position demand minus actual position, increments (the plant's lag and an obstacle's block)."""
    plant = drive.plant
    lag = -plant.error if plant is not None else 0.0
    fe = drive.cia.following_error
    return lag + (fe.numerator / fe.denominator if fe else 0.0)


def _ms(drive: "DriveApp", time: int) -> float:
    """6066h/6068h in ms (the family's unit: ms, or control-loop samples)."""
    if drive.behaviour.window_times_in_samples:
        dt = drive.units.cycle_s
        return time * 1000 * dt.numerator / dt.denominator
    return float(time)


def _window_increments(drive: "DriveApp", window: int) -> float:
    pn, pd = drive.units.ratios()[:2]
    inc = window * pn / pd
    cap = drive.behaviour.following_error_cap
    return min(inc, cap) if cap is not None else inc


def _limits(drive: "DriveApp") -> tuple[float | None, float]:
    """(the following-error window in increments, None: no supervision; the time in ms) from 6065h/6066h."""
    window, timeout = drive._read_int(0x6065, 0), drive._read_int(0x6066, 0)
    if window is None or timeout is None or window == 0xFFFFFFFF or (
            drive.behaviour.following_error_zero_unset and not window and not timeout):
        return None, 0.0
    return _window_increments(drive, window), _ms(drive, timeout)


def supervise(drive: "DriveApp", mode: int) -> None:
    """One cycle of supervision (after the plant's step) in ``mode`` (6061h)."""
    cia = drive.cia
    sup = drive.supervision
    plant = drive.plant
    assert plant is not None
    seconds = plant.dt
    if mode == PP:
        if cia.target_reached and _position_window(drive, _actual_user(drive, plant.reported()[0])):
            sup.inside_s += seconds
        else:
            sup.inside_s = 0.0
    elif sup.inside_s:
        sup.inside_s = 0.0
    if cia.state is not _ENABLED or mode not in POSITION_MODES:
        sup.outside_s = 0.0
        return
    if -0.5 < plant.error < 0.5 and not cia.following_error.numerator:
        sup.outside_s = 0.0  # measured in whole increments: no error, within any window
        return
    get = drive.objects.store.get
    key = (get((0x6065, 0)), get((0x6066, 0)), drive.objects.store.version)
    limits = sup.limits
    if limits is None or limits[0] != key:
        limits = sup.limits = (key, *_limits(drive))
    window_inc = limits[1]
    if window_inc is None:
        sup.outside_s = 0.0
        return
    error = following_error(drive)
    if abs(round(error)) <= window_inc:  # the encoder measures whole increments
        sup.outside_s = 0.0
        return
    sup.outside_s += seconds
    if sup.outside_s * 1000 > limits[2]:
        sup.outside_s = 0.0
        cia.following_error_bit = True
        pn, pd = drive.units.ratios()[:2]
        pn = pn or 1
        drive._log("following_error", window=drive._read_int(0x6065, 0), timeout_ms=drive._read_int(0x6066, 0),
                   error=int(error * pd / pn), mode=mode)
        drive.inject_fault(0x8611)


def _position_window(drive: "DriveApp", actual_user: int) -> bool:
    """PP: the actual position is within 6067h of the target 607Ah."""
    target = drive._read_int(0x607A, 0)
    return target is not None and abs(actual_user - target) <= (drive._read_int(0x6067, 0) or 0)


def _actual_user(drive: "DriveApp", error: float) -> int:
    """6064h for a plant error of ``error`` increments."""
    pn, pd = drive.units.ratios()[:2]
    qn, qd = drive.cia.pos_n, drive.cia.pos_d
    return floor_ratio(qn + round(error) * qd, qd, pn, pd) + drive._home_offset()


def report_actual(drive: "DriveApp", sw: int, mode: int) -> None:
    """The actual values from the plant (see the module doc); ``sw``: the statusword as the state machine makes
    it."""
    cia = drive.cia
    plant = drive.plant
    assert plant is not None
    units = drive.units
    pn, pd, vn, vd, sn, sd = units.ratios()
    error, velocity = plant.sampled if plant.samples_first else (plant.error, plant.velocity)
    k = round(error)
    offset = drive._home_offset()
    qn, qd = cia.pos_n, cia.pos_d
    # floor_ratio, inline (every cycle): floor((q / qd) / (pn / pd)), 0 where the factor is 0
    if pn:
        demand_user = (qn * pd) // (qd * pn) + offset
        actual_user = ((qn + k * qd) * pd) // (qd * pn) + offset if k else demand_user
    else:
        demand_user = actual_user = offset
    fe = cia.following_error
    blocked = units.position_to_user_int(fe) if fe.numerator else 0
    user_velocity = velocity * sd * vd / (sn * vn) if sn and vn else 0.0
    # a velocity that is the demand's up to the float's last bits reads as the demand's (no floor below it)
    user_velocity = floor(user_velocity + 1e-9 * (user_velocity if user_velocity > 1.0 else
                                                  -user_velocity if user_velocity < -1.0 else 1.0))
    if mode == PP and cia.state is _ENABLED and not cia.controlword & HALT and sw & 0x0400 and not (
            _position_window(drive, actual_user)
            and drive.supervision.inside_s * 1000 >= _ms(drive, drive._read_int(0x6068, 0) or 0)):
        sw &= ~0x0400
    if mode == CSP and cia.following_error_bit:
        sw |= 0x2000
    rated = plant.params.rated_torque
    torque = round(plant.torque / rated * 1000) if rated > 0 else 0
    demand_user += blocked
    lag = blocked + (round(-error * pd / pn) if error and pn else 0)
    if drive.behaviour.polarity == "targets+actuals":
        # Technosoft §5.1.1: 607Eh multiplies the actual values too (as on the ideal plant, motion.py)
        ps, vs = polarity.actual_signs(drive, mode)
        actual_user, demand_user, lag, user_velocity = ps * actual_user, ps * demand_user, ps * lag, vs * user_velocity
    drive._put_all(_ACTUAL, (sw, qn // qd + k, actual_user, demand_user, user_velocity, cia.fault_code, lag, torque,
                             torque))


# --- limit switches and software position limits ---------------------------------------------------------------
_FULL_RANGE = (-(2**31), 2**31 - 1)


def _blocked(drive: "DriveApp") -> tuple[bool, bool]:
    """(negative, positive) directions a limit blocks: the hardware limit-switch inputs, and the software position
    limits 607Dh (min, max, position user units) reached by the position demand — Technosoft §4.3.2 ("work just
    like the hardware limit switches"); HDT only with 201Ah bit 0 (§4.06.7). A 607Dh of the whole INTEGER32 range,
    or min >= max, sets none."""
    neg, pos = drive.limit_switches
    low, high = drive._read_int(0x607D, 1), drive._read_int(0x607D, 2)
    if low is None or high is None or (low, high) == _FULL_RANGE or low >= high:
        return neg, pos
    if drive.behaviour.home_offset_continuous and not (drive._read_int(0x201A, 0) or 0) & 1:  # HDT
        return neg, pos
    pn, pd = drive.units.ratios()[:2]
    demand = floor_ratio(drive.cia.pos_n, drive.cia.pos_d, pn, pd) + drive._home_offset()
    return neg or demand <= low, pos or demand >= high


def limit_stop(drive: "DriveApp", mode: int, dt: Fraction) -> bool:
    """A limit switch (or software limit) in the direction the axis moves or is told to move: the axis ramps down
    with the quick-stop deceleration 6085h and holds, still OPERATION ENABLED; only a motion away from the limit
    is taken (Technosoft §4.3.1, seeds/000_a0ab57c0bda88c2c.txt line 2235: "Triggering a limit switch during a
    motion causes the drive to automatically stop using the deceleration value defined in Object 6085h ... wait
    until a new motion command is received in the opposite direction"). True: this cycle's motion was the stop.
    Homing searches for the switches and is left alone."""
    if mode == HOMING:
        return False
    neg, pos = drive.limit_switches
    if not (neg or pos) and (0x607D, 2) not in drive.objects.entries:
        return False
    blocked_neg, blocked_pos = _blocked(drive)
    if not (blocked_neg or blocked_pos):
        return False
    cia = drive.cia
    direction = (cia.vel_n > 0) - (cia.vel_n < 0)
    if not direction:
        if mode == PP and cia.target is not None:
            direction = (cia.target > cia.position) - (cia.target < cia.position)
        elif mode == CSP:
            pn, pd = drive.units.ratios()[:2]
            target = Fraction(((drive._read_int(0x607A, 0) or 0) - drive._home_offset()) * pn, pd)
            direction = (target > cia.position) - (target < cia.position)
        else:
            v = drive._read_int(0x60FF, 0) or 0
            direction = (v > 0) - (v < 0)
    if not ((direction > 0 and blocked_pos) or (direction < 0 and blocked_neg)):
        return False
    units = drive.units
    if cia.vel_n:
        decel = abs(units.increments_per_second2(units.acceleration_to_internal(drive._read_int(0x6085, 0) or 0)))
        if decel:
            cia._slow_down(dt, decel, units.increments_per_second, units.velocity_from_increments_per_second)
        else:
            cia.velocity = Fraction(0)
    if not cia.vel_n:
        if cia.target is not None or cia.move is not None:
            drive._log("limit", event="stopped", direction=direction)
        cia.target = None
        cia.move = None
        cia.target_reached = True
    else:
        cia.move = None
    return True
