"""The fault reset of ``commission`` as CiA-402 says (issue 35 item 6): a rising edge of controlword bit 7, held
until the statusword leaves FAULT or a bounded time passes. The manual's words: "The transition is only started by
a bit transition from 0 to 1" (seeds/000_a0ab57c0bda88c2c.txt line 2085) and "After leaving the state Fault bit 7,
Fault Reset of the Controlword has to be cleared by the host" (same file, line 2027).

Before: bit 7 was held for one cycle and the drive given up at the next FAULT read, so a drive that answers the
reset a few cycles late (a loaded machine, a drive clearing its error register) failed the enable."""

from __future__ import annotations

import pytest

from ecattool.commission.cia402 import FAULT_RESET_CYCLES, enable
from ecattool.errors import TargetError

FAULT, SWITCH_ON_DISABLED, READY, SWITCHED_ON, ENABLED = 0x0008, 0x0040, 0x0021, 0x0023, 0x0027


class LateDrive:
    """A CiA-402 drive in FAULT that leaves it ``late`` cycles after a rising edge of bit 7, if bit 7 is still
    held then (a reset released early is lost); ``never``: it stays in FAULT."""

    def __init__(self, late: int, cw: int = 0, never: bool = False) -> None:
        self.late, self.never = late, never
        self.sw = FAULT
        self.cw = self.prev = cw
        self.held = -1  # cycles bit 7 has been held since its rising edge (-1: no edge)
        self.cycles = 0
        self.writes: list[int] = []

    def write(self, cw: int) -> None:
        self.writes.append(cw)
        self.cw = cw

    def read(self) -> int:
        return self.sw

    def cycle(self) -> None:
        self.cycles += 1
        bit7, was = self.cw & 0x80, self.prev & 0x80
        self.prev = self.cw
        if self.sw == FAULT:
            if bit7 and not was:
                self.held = 0
            elif bit7 and self.held >= 0:
                self.held += 1
            else:
                self.held = -1
            if self.held >= self.late and not self.never:
                self.sw = SWITCH_ON_DISABLED
            return
        command = self.cw & 0x8F
        if command == 0x06:
            self.sw = READY
        elif command == 0x07 and self.sw in (READY, SWITCHED_ON):
            self.sw = SWITCHED_ON
        elif command == 0x0F and self.sw in (SWITCHED_ON, ENABLED):
            self.sw = ENABLED


def test_a_reset_answered_late_is_held_until_the_drive_leaves_fault() -> None:
    drive = LateDrive(late=8)
    passed = enable(drive.read, drive.write, drive.cycle)
    assert passed[-1] == "operation enabled" and passed.count("fault reset sent") == 1
    i = drive.writes.index(0x0080)
    assert drive.writes[i - 1] & 0x80 == 0  # bit 7 low before it is set: a rising edge
    assert drive.writes[i + 1] == 0x0006  # cleared by the host once the drive has left FAULT


def test_a_controlword_left_at_0x0080_still_gives_a_rising_edge() -> None:
    drive = LateDrive(late=1, cw=0x0080)  # a previous master left bit 7 set: writing 0x0080 again is no edge
    assert enable(drive.read, drive.write, drive.cycle)[-1] == "operation enabled"


def test_a_drive_that_stays_in_fault_is_given_up_in_bounded_time() -> None:
    drive = LateDrive(late=0, never=True)
    now = [0.0]

    def cycle() -> None:
        drive.cycle()
        now[0] += 0.001  # a 1 ms bus cycle

    with pytest.raises(TargetError, match=r"stays in FAULT after 2 fault resets, each held up to 2 s"):
        enable(drive.read, drive.write, cycle, clock=lambda: now[0])
    assert drive.cycles <= 2 * (2000 + 3) + 10  # two resets of 2 s at 1 ms, and the cycles between
    assert drive.cycles < 2 * FAULT_RESET_CYCLES
