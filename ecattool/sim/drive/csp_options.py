"""Technosoft's options of cyclic synchronous position (``Behaviour.csp_options``):

* controlword bit 6 "Abs / rel" (§13.1.1): "In Relative position mode, the drive will add to its current
  position the value received in object 607Ah" — each cycle (TS 8736: "By sending this value periodically ...
  it will be like working in Cyclic Synchronous Velocity mode");
* 2086h = 1 (§13.2): "During CSP mode, the maximum velocity will be the one defined in object 6081h"; with
  6081h = 0 "the motor will not move when it receives new position commands".
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING

from ecattool.sim.drive import polarity

if TYPE_CHECKING:
    from ecattool.sim.drive.core import DriveCore

RELATIVE = 0x0040


def applies(drive: DriveCore) -> bool:
    """Whether this cycle's CSP target needs the options (else the plain integer path runs)."""
    return drive.behaviour.csp_options and (bool(drive.cia.controlword & RELATIVE)
                                            or drive._read_int(0x2086, 0) == 1)


def target(drive: DriveCore, dt: Fraction) -> Fraction:
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
