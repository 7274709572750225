"""A small CiA-402 client: statusword decoding and the enable sequence, over process data or SDO."""

from __future__ import annotations

from collections.abc import Callable

from ecattool.errors import TargetError

SHUTDOWN = 0x0006
SWITCH_ON = 0x0007
ENABLE_OPERATION = 0x000F
DISABLE_VOLTAGE = 0x0000
FAULT_RESET = 0x0080
NEW_SETPOINT = 0x0010  # PP: bit 4


def state_of(statusword: int) -> str:
    """The CiA-402 state named by a statusword (bits 0-3, 5, 6)."""
    s = statusword
    if s & 0x4F == 0x00:
        return "not ready to switch on"
    if s & 0x4F == 0x40:
        return "switch on disabled"
    if s & 0x6F == 0x21:
        return "ready to switch on"
    if s & 0x6F == 0x23:
        return "switched on"
    if s & 0x6F == 0x27:
        return "operation enabled"
    if s & 0x6F == 0x07:
        return "quick stop active"
    if s & 0x4F == 0x0F:
        return "fault reaction active"
    if s & 0x4F == 0x08:
        return "fault"
    return f"unknown (0x{s:04X})"


def enable(read_sw: Callable[[], int], write_cw: Callable[[int], None], cycle: Callable[[], None], max_cycles: int = 200) -> list[str]:
    """Drive the state machine to OPERATION ENABLED; returns the states passed through."""
    seen: list[str] = []
    for _ in range(max_cycles):
        cycle()
        sw = read_sw()
        st = state_of(sw)
        if not seen or seen[-1] != st:
            seen.append(st)
        if st == "operation enabled":
            return seen
        if st == "fault":
            if seen.count("fault") > 1 and "fault reset sent" in seen:
                raise TargetError(f"drive stays in FAULT after a fault reset (statusword 0x{sw:04X})")
            write_cw(FAULT_RESET)
            seen.append("fault reset sent")
            cycle()
            write_cw(DISABLE_VOLTAGE)
        elif st in ("switch on disabled", "not ready to switch on"):
            write_cw(SHUTDOWN)
        elif st == "ready to switch on":
            write_cw(SWITCH_ON)
        elif st == "switched on":
            write_cw(ENABLE_OPERATION)
        elif st == "quick stop active":
            write_cw(DISABLE_VOLTAGE)
    raise TargetError(f"drive did not reach OPERATION ENABLED in {max_cycles} cycles (passed: {', '.join(seen)})")
