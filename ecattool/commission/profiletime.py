"""How long a profile-position move must at least take: the trapezoid of the profile velocity 6081h, profile
acceleration 6083h and profile deceleration 6084h (6083h where the drive has no 6084h, as Technosoft), from rest
to rest. A move that ends sooner did not follow the profile (a wrong 6081h/6083h/6084h, a scaling that converts
them wrongly, a drive that jumps). The commissioning run checks the move against it, within one cycle and
:data:`SLACK`; a jerk-limited profile only takes longer.

The values are converted with the project's factor group (internal units per position unit, per velocity unit
and per acceleration unit, as ``scaling`` reports them); without a scaling section the check is left out (the
drive's own units are not known here)."""

from __future__ import annotations

from fractions import Fraction
from math import sqrt
from typing import TYPE_CHECKING, Protocol

from ecattool.errors import EcatToolError

if TYPE_CHECKING:
    from ecattool.commission.trace import DriveTrace
    from ecattool.project.slave import Slave


#: how much shorter than the profile's time a move may seem: the run counts the master's cycles, which on a real
#: bus are not exactly the drive's clock (a served HDT move of 587 drive cycles counts 581), and takes the longer
#: of that count and the master's own clock; a drive that does not ramp is far shorter (the jump the report
#: showed: 1 mm in 20 ms against 89 ms). The same on a bus: a drive runs on its own clock there, a real one as
#: well as one `sim serve` serves (its cycle time or SYNC0, not the master's frames, paces its motion), so a
#: late master or frames back to back neither stretch nor shorten its move
SLACK = 0.05


class _Io(Protocol):
    def has(self, index: int, sub: int = 0) -> bool: ...

    def read(self, index: int, sub: int) -> int: ...


def trapezoid_time(distance: float, velocity: float, acceleration: float, deceleration: float) -> float:
    """Seconds of a rest-to-rest move of ``distance`` at most ``velocity``, speeding up at ``acceleration`` and
    slowing down at ``deceleration`` (one unit throughout); 0 for no distance, inf where a value is 0."""
    d = abs(distance)
    if d == 0:
        return 0.0
    if velocity <= 0 or acceleration <= 0 or deceleration <= 0:
        return float("inf")
    ramps = velocity * velocity / 2 * (1 / acceleration + 1 / deceleration)
    if d >= ramps:
        return velocity / acceleration + velocity / deceleration + (d - ramps) / velocity
    peak = sqrt(2 * d * acceleration * deceleration / (acceleration + deceleration))
    return peak / acceleration + peak / deceleration


def _ratio(summary: dict[str, object], key: str) -> Fraction | None:
    """An exact ``internal units … per <unit>`` entry of the factor group's summary (None where irrational)."""
    unit = summary.get(key.split(" per ")[-1])
    text = summary.get(key.split(" per ")[0] + f" per {unit}") if unit is not None else None
    try:
        return Fraction(str(text)) if text is not None else None
    except (ValueError, ZeroDivisionError):
        return None


def check_move_time(io: _Io, rd: Slave, trace: DriveTrace, mode: str, distance: Fraction) -> tuple[bool, str]:
    """(ok, text for the move step): whether the PP move took at least the profile's time, less one cycle."""
    group = rd.factor_group
    if mode != "pp" or group is None or trace.move_cycles is None or rd.counts_per_unit is None:
        return True, ""
    summary = dict(getattr(group, "summary", {}))
    per_velocity = _ratio(summary, "internal units/s per velocity unit")
    per_acceleration = _ratio(summary, "internal units/s² per acceleration unit")
    if not per_velocity or not per_acceleration:
        return True, ""
    try:
        velocity = io.read(0x6081, 0)
        acceleration = io.read(0x6083, 0)
        has_6084 = io.has(0x6084, 0)
        deceleration = io.read(0x6084, 0) if has_6084 else acceleration
    except EcatToolError:
        return True, ""
    if min(velocity, acceleration, deceleration) <= 0:
        return True, ""  # a 0 ramp: no profile time to hold the move to (the drive reports it, EMCY 6320h)
    need = trapezoid_time(float(distance * rd.counts_per_unit), float(velocity * per_velocity),
                          float(acceleration * per_acceleration), float(deceleration * per_acceleration))
    start, end = trace.move_cycles
    # the drive's cycles as the master counted them; on a real bus a late master counts fewer than the drive
    # ran, and then its own clock is the longer (and true) measure: the longer of the two is never too short
    took = max((end - start) * trace.cycle_s, trace.move_wall_s or 0.0)
    ramps = f"6083h {acceleration}, 6084h {deceleration}" if has_6084 else f"6083h {acceleration} both ways"
    text = f"; took {took:.4g} s, the profile (6081h {velocity}, {ramps}) allows {need:.4g} s at the least"
    if took < need * (1 - SLACK) - trace.cycle_s:
        return False, "move ended sooner than its profile allows" + text + ": the drive did not follow " \
                      "6081h/6083h/6084h (or the scaling converts them wrongly)"
    return True, text
