"""Issue 33 N18: HDT's EMCY carries the bitmap of the alarms present in its bytes 3..6 (§2.04.1), also for the
following error the supervision finds (8611h, alarm FA_13 "Position error" = bit 12), not only for an alarm a test
injects by its number."""

from __future__ import annotations

from ecattool.sim.cia402 import State
from tests.sim.sim_helpers import OP, at, r, w
from tests.profiles.test_families_manuals import HDT_TEXT, manual_says
from tests.sim.test_sim_stop_reactions import REV, _hdt_move_into_an_obstacle


def _bitmap(emcy_bytes: bytes) -> int:
    return int.from_bytes(emcy_bytes[3:7], "little")


def test_hdt_following_error_emcy_carries_alarm_fa13():
    manual_says(HDT_TEXT, 96, "3.7 Manufacturer specific Error Field: 4 of these 5 Bytes are used to")
    manual_says(HDT_TEXT, 116, "12 FA_13 Position error")
    manual_says(HDT_TEXT, 403, "Y 8611h Following Error Position error Y")
    d = _hdt_move_into_an_obstacle(0)  # the profile runs on against the obstacle: following error
    n = 0
    while d.cia402_state is State.OPERATION_ENABLED and n < 2000:
        d.step(1)
        n += 1
    assert d.cia402_state is State.FAULT and r(d, 0x603F) == 0x8611
    emcy = [e for e in d.emergencies if e.code == 0x8611][-1].to_bytes()
    assert emcy[:2] == bytes.fromhex("1186") and _bitmap(emcy) == 1 << 12, emcy.hex()
    assert emcy[7] == 0


def test_hdt_bitmap_reports_every_alarm_present_until_a_fault_reset():
    manual_says(HDT_TEXT, 97, "report all the current alarms of the Drive")
    manual_says(HDT_TEXT, 115, "11 FA_12 Under voltage DC Bus")
    d = at("hdt", OP)
    d.inject_fault(0x3220)  # DC bus under-voltage, FA_12
    assert _bitmap(d.emergencies[-1].to_bytes()) == 1 << 11
    d.inject_fault(0x8611)  # a second alarm while the first is present: both bits
    assert _bitmap(d.emergencies[-1].to_bytes()) == (1 << 11) | (1 << 12)
    w(d, 0x6040, 0, 0x80, 2)  # fault reset: no alarm present any more
    assert d.cia402_state is State.SWITCH_ON_DISABLED
    d.inject_fault(0x8611)
    assert _bitmap(d.emergencies[-1].to_bytes()) == 1 << 12


def test_other_families_send_no_bitmap():
    d = at("technosoft-ipos", OP)
    d.inject_fault(0x8611)
    assert d.emergencies[-1].to_bytes()[3:] == bytes(5)
    assert REV == 65536
