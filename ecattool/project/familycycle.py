"""The family's rules on the SYNC0 cycle (PRJ080): Technosoft synchronises its slow control loop on SYNC0, so
SYNC0 must equal or be a multiple of the slow loop (the project's ``scaling.slow_loop``, 1 ms by default), and
its interpolation period 60C2h must equal the sync cycle. The rules are data of the family
(:meth:`ecattool.profiles.FamilyRules.dc_cycle_problems`); this module finds the project's values."""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING

from ecattool.errors import EcatToolError

if TYPE_CHECKING:
    from ecattool.project.loader import LoadedProject
    from ecattool.project.slave import Found, Slave

RULE = "PRJ080"
DESCRIPTION = "the SYNC0 cycle is not a multiple of the drive's slow loop, or 60C2h differs from it (Technosoft)"


def _slow_loop_ns(slave: Slave) -> Fraction:
    """The project's slow loop (``scaling.slow_loop``) in ns; 1 ms where not given or not readable."""
    from ecattool.scaling.units import time_seconds

    raw = slave.drive.scaling.get("slow_loop") if slave.drive.scaling is not None else None
    if raw is None:
        return Fraction(1_000_000)
    try:
        return time_seconds(raw, None) * 1_000_000_000
    except EcatToolError:  # the scaling step reports it (PRJ050)
        return Fraction(1_000_000)


def _ip_period_ns(slave: Slave) -> Fraction | None:
    """60C2h as the startup list leaves it (the dictionary default where not written)."""
    from ecattool.profiles.rules import interpolation_period_ns

    assert slave.device is not None
    state: dict[int, int] = {}
    for sub in (1, 2):
        e = slave.device.dictionary.entry(0x60C2, sub)
        if e is None:
            return None
        state[sub] = e.decode(e.default) if e.default else 0
    for cmd in slave.startup:
        if cmd.index == 0x60C2 and cmd.subindex in (1, 2) and not cmd.complete_access:
            state[cmd.subindex] = int.from_bytes(cmd.data, "little", signed=cmd.subindex == 2)
    return interpolation_period_ns(state[1], state[2])


def check_dc_cycle(lp: LoadedProject, i: int, slave: Slave) -> Found:
    """PRJ080 for a drive whose DC (SYNC0) is active."""
    from ecattool.project.slave import Found

    found = Found()
    dc = slave.dc
    rules = slave.rules
    if dc is None or not dc.active or not dc.cycle_ns or rules is None or slave.device is None:
        return found
    for what, message in rules.dc_cycle_problems(dc.cycle_ns, _ip_period_ns(slave), _slow_loop_ns(slave)):
        if what == "sync0":  # "must be equal or a multiple": the drive's control loop does not synchronise
            found.error(RULE, f"{slave.device.type_name}: {message}", lp.drive_location(i, "dc", "cycle_ns"))
        else:  # the interpolated modes take the set-points at the wrong rate
            where = next((c.source for c in reversed(list(slave.startup)) if c.index == 0x60C2 and c.source), None)
            found.warning(RULE, f"{slave.device.type_name}: {message}; set {_period_hint(dc.cycle_ns)}",
                          where or lp.drive_location(i, "parameters"))
    return found


def _period_hint(cycle_ns: int) -> str:
    """The 60C2h writes for a period of ``cycle_ns`` (value 1..255, the largest unit that divides it)."""
    for exp in range(-3, -10, -1):
        unit = 10 ** (9 + exp)
        if cycle_ns % unit == 0 and 1 <= cycle_ns // unit <= 255:
            return f"60C2:02 = {exp} and 60C2:01 = {cycle_ns // unit}"
    return "60C2h to the sync cycle"
