"""A small CiA-402 client: statusword decoding and the enable sequence, over process data or SDO."""

from __future__ import annotations

from collections.abc import Callable

from ecattool.errors import TargetError
# the commands, read by the commissioning run from here too
from ecattool.od.cia402 import DISABLE_VOLTAGE as DISABLE_VOLTAGE
from ecattool.od.cia402 import ENABLE_OPERATION as ENABLE_OPERATION
from ecattool.od.cia402 import FAULT_RESET as FAULT_RESET
from ecattool.od.cia402 import NEW_SETPOINT as NEW_SETPOINT
from ecattool.od.cia402 import SHUTDOWN as SHUTDOWN
from ecattool.od.cia402 import SWITCH_ON as SWITCH_ON
from ecattool.od.cia402 import state_of as _state


def state_of(statusword: int) -> str:
    """The CiA-402 state a statusword shows, as the manuals write it (``switch on disabled``), or
    ``unknown (0x….)`` (:func:`ecattool.od.cia402.state_of`)."""
    state = _state(statusword)
    return state.text if state is not None else f"unknown (0x{statusword:04X})"


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
