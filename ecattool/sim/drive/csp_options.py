"""Technosoft's options of cyclic synchronous position (``Behaviour.csp_options``):

* controlword bit 6 "Abs / rel" (§13.1.1): "In Relative position mode, the drive will add to its current
  position the value received in object 607Ah" — each cycle (TS 8736: "By sending this value periodically ...
  it will be like working in Cyclic Synchronous Velocity mode");
* 2086h = 1 (§13.2): "During CSP mode, the maximum velocity will be the one defined in object 6081h"; with
  6081h = 0 "the motor will not move when it receives new position commands". "During CSV mode, the maximum
  acceleration will be the one defined in object 6083h" (6083h = 0: no motion either).
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING

from ecattool.sim.drive import polarity

if TYPE_CHECKING:
    from ecattool.sim.drive.app import DriveApp

RELATIVE = 0x0040


def applies(drive: DriveApp) -> bool:
    """Whether this cycle's CSP target needs the options (else the plain integer path runs)."""
    return drive.behaviour.csp_options and (bool(drive.cia.controlword & RELATIVE)
                                            or drive._read_int(0x2086, 0) == 1)


def csv_limited(drive: DriveApp) -> bool:
    return drive.behaviour.csp_options and drive._read_int(0x2086, 0) == 1


def csv_step(drive: DriveApp, dt: Fraction) -> None:
    """One CSV cycle with 2086h = 1: the velocity towards 60FFh at most 6083h per second."""
    cia, units, read = drive.cia, drive.units, drive._read_int
    goal = units.velocity_to_internal(polarity.target_signs(drive, 9)[1] * (read(0x60FF, 0) or 0))
    acc = abs(units.increments_per_second2(units.acceleration_to_internal(read(0x6083, 0) or 0)))
    now = units.increments_per_second(cia.velocity)
    want = units.increments_per_second(goal)
    change = acc * dt
    if abs(want - now) <= change:
        cia.velocity = goal
    else:
        cia.velocity = units.velocity_from_increments_per_second(now + (change if want > now else -change))
    cia.position += (now + units.increments_per_second(cia.velocity)) / 2 * dt


def target(drive: DriveApp, dt: Fraction) -> Fraction:
    """The position (internal units) CSP goes to this cycle."""
    cia, units, read = drive.cia, drive.units, drive._read_int
    value = (read(0x607A, 0) or 0) * polarity.target_signs(drive, 8)[0]
    if cia.controlword & RELATIVE:
        goal = cia.position + units.position_to_internal(value)
    else:
        goal = units.position_to_internal(value - drive._home_offset())
    if read(0x2086, 0) == 1:
        limit = abs(units.increments_per_second(units.velocity_to_internal(read(0x6081, 0) or 0))) * dt
        step = goal - cia.position
        if abs(step) > limit:
            goal = cia.position + (limit if step > 0 else -limit)
    return goal
