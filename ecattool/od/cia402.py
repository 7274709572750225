"""CiA-402 device control as definitions: the drive states, the statusword bits and masks that show them, the
controlword commands and the masks that recognise them (CiA-402-2 / IEC 61800-7-201 §6.2, as the three manuals
print them: Technosoft Table 4.1.1, HDT §4.03.1, Control Techniques Table 7.2).

The one place of these numbers: the commissioning client (:mod:`ecattool.commission.cia402`) decodes a
statusword and writes commands by them, the simulator (:mod:`ecattool.sim.cia402`) makes its statusword and
reads the master's controlword by them (tests/test_fitness.py holds both to it).
"""

from __future__ import annotations

from enum import Enum


class State(str, Enum):
    """A state of the CiA-402 power drive state machine."""

    NOT_READY = "NOT_READY_TO_SWITCH_ON"
    SWITCH_ON_DISABLED = "SWITCH_ON_DISABLED"
    READY = "READY_TO_SWITCH_ON"
    SWITCHED_ON = "SWITCHED_ON"
    OPERATION_ENABLED = "OPERATION_ENABLED"
    QUICK_STOP = "QUICK_STOP_ACTIVE"
    FAULT_REACTION = "FAULT_REACTION_ACTIVE"
    FAULT = "FAULT"

    @property
    def text(self) -> str:
        """The state as the manuals write it in prose (``switch on disabled``)."""
        return _TEXTS[self]


_TEXTS = {
    State.NOT_READY: "not ready to switch on",
    State.SWITCH_ON_DISABLED: "switch on disabled",
    State.READY: "ready to switch on",
    State.SWITCHED_ON: "switched on",
    State.OPERATION_ENABLED: "operation enabled",
    State.QUICK_STOP: "quick stop active",
    State.FAULT_REACTION: "fault reaction active",
    State.FAULT: "fault",
}

#: statusword bits 0-3 and 6 (ready to switch on, switched on, operation enabled, fault, switch on disabled)
STATE_MASK = 0x004F
#: the same and bit 5 (quick stop), which tells the states where the drive is switched on
STATE_MASK_QS = 0x006F

#: statusword low bits per state, under the state's mask (:data:`MASK_OF`)
STATUS_BITS = {
    State.NOT_READY: 0x0000,
    State.SWITCH_ON_DISABLED: 0x0040,
    State.READY: 0x0021,
    State.SWITCHED_ON: 0x0023,
    State.OPERATION_ENABLED: 0x0027,
    State.QUICK_STOP: 0x0007,
    State.FAULT_REACTION: 0x000F,
    State.FAULT: 0x0008,
}
#: the mask under which a statusword shows each state
MASK_OF = {s: STATE_MASK_QS if s in (State.READY, State.SWITCHED_ON, State.OPERATION_ENABLED, State.QUICK_STOP)
           else STATE_MASK for s in State}

#: other statusword bits
SW_VOLTAGE_ENABLED = 0x0010  # bit 4
SW_FAULT = 0x0008  # bit 3
SW_REMOTE = 0x0200  # bit 9
SW_TARGET_REACHED = 0x0400  # bit 10
SW_OP_SPECIFIC_12 = 0x1000  # bit 12: set-point acknowledge (PP), homing attained, drive follows (CSP/CSV)
SW_OP_SPECIFIC_13 = 0x2000  # bit 13: following error (PP), homing error

#: controlword commands (the bits a master writes)
DISABLE_VOLTAGE = 0x0000
QUICK_STOP = 0x0002
SHUTDOWN = 0x0006
SWITCH_ON = 0x0007
ENABLE_OPERATION = 0x000F
FAULT_RESET = 0x0080  # bit 7, on its rising edge
NEW_SETPOINT = 0x0010  # bit 4 in profile position
HALT = 0x0100  # bit 8

#: (mask, value) that recognise a command in a controlword (bit 7, fault reset, is checked first)
CMD_SHUTDOWN = (0x0007, 0x0006)
CMD_SWITCH_ON = (0x000F, 0x0007)
CMD_ENABLE_OPERATION = (0x000F, 0x000F)
CMD_QUICK_STOP = (0x0006, 0x0002)
#: bit 1 (enable voltage) clear: the disable voltage command
CW_ENABLE_VOLTAGE = 0x0002


def state_of(statusword: int) -> State | None:
    """The state a statusword shows (bits 0-3, 5, 6 under :data:`MASK_OF`); None when it shows none."""
    for state, bits in STATUS_BITS.items():
        if statusword & MASK_OF[state] == bits:
            return state
    return None


def decode_statusword(statusword: int) -> State:
    """The state a statusword shows; NOT READY TO SWITCH ON for a statusword that shows none (the drive's
    reading of a word it cannot place)."""
    return state_of(statusword) or State.NOT_READY
