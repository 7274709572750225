"""A small CiA-402 client: statusword decoding and the enable sequence, over process data or SDO."""

from __future__ import annotations

import time
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


#: how long a fault reset is held (bit 7 set) at most while the statusword still says FAULT, in seconds
FAULT_RESET_S = 2.0
#: the most cycles one fault reset is held, whatever the clock says (a bound on the loop itself)
FAULT_RESET_CYCLES = 5000
#: fault resets tried before the drive counts as staying in FAULT
FAULT_RESETS = 2


def fault_reset(read_sw: Callable[[], int], write_cw: Callable[[int], None], cycle: Callable[[], None],
                clock: Callable[[], float] = time.monotonic, hold_s: float = FAULT_RESET_S) -> int:
    """A fault reset as CiA-402 defines it: bit 7 of the controlword low for one cycle, then set (the rising edge
    starts transition 15) and held until the statusword leaves FAULT or ``hold_s`` passes; the caller clears
    bit 7 with its next command (Technosoft iPOS manual, seeds/000_a0ab57c0bda88c2c.txt line 2027: "After leaving
    the state Fault bit 7, Fault Reset of the Controlword has to be cleared by the host"; line 2085: "the fault
    reset: The transition is only started by a bit transition from 0 to 1"). Returns the last statusword read."""
    write_cw(DISABLE_VOLTAGE)  # bit 7 low first: a controlword left at 0x0080 would give no edge
    cycle()
    write_cw(FAULT_RESET)
    deadline = clock() + hold_s
    sw = read_sw()
    for _ in range(FAULT_RESET_CYCLES):
        cycle()
        sw = read_sw()
        if state_of(sw) != "fault" or clock() >= deadline:
            break
    return sw


def enable(read_sw: Callable[[], int], write_cw: Callable[[int], None], cycle: Callable[[], None],
           max_cycles: int = 200, clock: Callable[[], float] = time.monotonic,
           reset_hold_s: float = FAULT_RESET_S) -> list[str]:
    """Drive the state machine to OPERATION ENABLED; returns the states passed through. A drive in FAULT gets a
    :func:`fault_reset` (at most FAULT_RESETS); one in FAULT REACTION ACTIVE is waited for (it ends in FAULT)."""
    seen: list[str] = []
    resets = 0
    for _ in range(max_cycles):
        cycle()
        sw = read_sw()
        st = state_of(sw)
        if not seen or seen[-1] != st:
            seen.append(st)
        if st == "operation enabled":
            return seen
        if st == "fault":
            if resets >= FAULT_RESETS:
                raise TargetError(f"drive stays in FAULT after {resets} fault resets, each held up to "
                                  f"{reset_hold_s:g} s (statusword 0x{sw:04X})")
            resets += 1
            seen.append("fault reset sent")
            sw = fault_reset(read_sw, write_cw, cycle, clock, reset_hold_s)
            if state_of(sw) != "fault":
                seen.append(state_of(sw))
                write_cw(SHUTDOWN)  # bit 7 cleared, on to READY TO SWITCH ON
        elif st in ("switch on disabled", "not ready to switch on"):
            write_cw(SHUTDOWN)
        elif st == "ready to switch on":
            write_cw(SWITCH_ON)
        elif st == "switched on":
            write_cw(ENABLE_OPERATION)
        elif st == "quick stop active":
            write_cw(DISABLE_VOLTAGE)
    raise TargetError(f"drive did not reach OPERATION ENABLED in {max_cycles} cycles (passed: {', '.join(seen)})")
