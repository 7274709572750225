"""Issue 24, remaining gaps: the quick stop (605Ah) and the fault reaction (605Eh) as each family's manual defines
them. 1/2 (and the CiA-402 3/4) ramp down in QUICK STOP ACTIVE and then make the automatic transition 12 to
SWITCH ON DISABLED; 0 disables the drive function at once; 5/6 ramp and stay. A fault the family's manual gives a
reaction ramps in FAULT REACTION ACTIVE before FAULT. Each test quotes the manual line it follows."""

from __future__ import annotations

import pytest

from ecattool.sim import Drive
from ecattool.sim.cia402 import State
from tests.sim.sim_helpers import OP, SAFE, at, code_of, r, w
from tests.profiles.test_families_manuals import CT_TEXT, HDT_TEXT, TS_TEXT, manual_says

#: per family: the writes that set up a moving axis with a slow-down ramp half as steep as the quick-stop ramp
#: (the objects the manual names), and the profile velocity set-point (None: cyclic synchronous position)
SETUP = {
    # §4.4.7: slow-down ramp 6083h, quick-stop ramp 6085h (counts per sample² x 65536); 5 counts per sample
    "technosoft-ipos": ([(0x6083, 65536 // 10, 4), (0x6085, 65536 // 5, 4)], 5 * 65536),
    # §4.03.6: 604Eh (3000 rpm) over 6050h (1000 ms) / 6051h (500 ms); 6083h 6000 rpm/s up to 600 rpm
    "hdt": ([(0x6083, 6000, 4), (0x6050, 1000, 4), (0x6051, 500, 4)], 600),
    # 7.3.2 "the deceleration value of the used mode of operations" (6084h, "the deceleration ramp for the
    # positioning modes", 7.3.8) and 7.3.9 6085h; CSP (the family has no profile velocity mode) at 1 unit/cycle
    "controltechniques": ([(0x6084, 65536, 4), (0x6085, 131072, 4)], None),
}


def _moving(family: str, option: int) -> Drive:
    d = at(family, SAFE)
    d.configure_dc(0x0300, 1_000_000)  # CT 1857: the positioning modes need distributed clocks in OP
    d.request_state(OP)
    writes, target = SETUP[family]
    w(d, 0x6060, 0, 3 if target is not None else 8, 1)
    for index, value, size in writes:
        w(d, index, 0, value, size)
    w(d, 0x605A, 0, option, 2)
    for cw in (0x06, 0x07, 0x0F):
        w(d, 0x6040, 0, cw, 2)
    if target is None:
        for position in range(1, 21):
            w(d, 0x607A, 0, position, 4)
            d.step(1)
    else:
        w(d, 0x60FF, 0, target, 4)
        for _ in range(2000):
            d.step(1)
            if r(d, 0x6041) & 0x0400:  # target reached: at the set-point velocity
                break
    assert d.internal_velocity and d.cia402_state is State.OPERATION_ENABLED
    return d


def _quick_stop(d: Drive) -> int:
    """Quick stop (controlword 0x000B); the cycles the axis ramps in QUICK STOP ACTIVE until it stands."""
    w(d, 0x6040, 0, 0x0B, 2)
    n = 0
    while d.internal_velocity and n < 5000:
        assert d.cia402_state is State.QUICK_STOP and r(d, 0x6041) & 0x6F == 0x07
        d.step(1)
        n += 1
    return n


@pytest.mark.parametrize("family", sorted(SETUP))
def test_quick_stop_1_and_2_ramp_and_then_switch_on_disabled(family):
    manual_says(TS_TEXT, 2503, "1\tSlow down on slow down ramp and transit into Switch On Disabled")
    manual_says(TS_TEXT, 2482, "The slow down ramp is a deceleration value set by the Profile acceleration object, "
                               "index 6083_h. The quick stop ramp is a deceleration value set by the Quick stop "
                               "deceleration object, index 6085_h.")
    manual_says(HDT_TEXT, 2039, "in “Switch On Disabled” state (power is disabled).")
    manual_says(CT_TEXT, 1463, "Automatic transition when the quick stop function is completed and quick stop "
                               "option code 1, 2, 3 or 4")
    manual_says(CT_TEXT, 1494, "The slow down ramp is the deceleration value of the used mode of operations.")
    cycles = {}
    for option in (1, 2):
        d = _moving(family, option)
        cycles[option] = _quick_stop(d)
        assert cycles[option] > 2
        # the ramp done, the drive leaves QUICK STOP ACTIVE by itself (transition 12)
        assert d.cia402_state is State.SWITCH_ON_DISABLED and r(d, 0x6041) & 0x4F == 0x40
        assert any(e.kind == "cia402" and e.data.get("reason") == f"quick stop completed, 605Ah = {option}"
                   and e.data["state"] == "SWITCH_ON_DISABLED" for e in d.events)
        w(d, 0x6040, 0, 0x0F, 2)  # enable operation is no way back from there (transition 16 needs 5..8)
        assert d.cia402_state is State.SWITCH_ON_DISABLED
    # the slow-down ramp is half as steep as the quick-stop ramp: it takes twice the cycles
    assert abs(cycles[1] - 2 * cycles[2]) <= 2, cycles


def test_technosoft_quick_stop_2_ramp_is_6085h_exactly():
    """5 counts per sample down at 6085h = 0.2 counts per sample²: 25 samples and the last partial one."""
    d = _moving("technosoft-ipos", 2)
    assert _quick_stop(d) == 26


@pytest.mark.parametrize("family", sorted(SETUP))
def test_quick_stop_5_and_6_ramp_as_1_and_2_and_stay(family):
    manual_says(HDT_TEXT, 2049, "in “Quick Stop Active” state (power is still supplied).")
    for stay, leave in ((5, 1), (6, 2)):
        d = _moving(family, stay)
        n = _quick_stop(d)
        assert d.cia402_state is State.QUICK_STOP
        d.step(5)
        assert d.cia402_state is State.QUICK_STOP
        assert n == _quick_stop(_moving(family, leave))


@pytest.mark.parametrize("family", sorted(SETUP))
def test_quick_stop_0_disables_the_drive_function_at_once(family):
    manual_says(HDT_TEXT, 2034, "0 disable Drive Power is disabled and the motor is free to move.")
    d = _moving(family, 0)
    assert r(d, 0x605A) == 0  # 0 is kept as 0, not read as the default 2
    w(d, 0x6040, 0, 0x0B, 2)
    assert d.cia402_state is State.SWITCH_ON_DISABLED and d.internal_velocity == 0


def test_technosoft_reserved_3_and_4_act_as_cia402_current_and_voltage_limit():
    """§4.4.7 lists 3 and 4 as reserved in a value range of the whole INTEGER16, so the drive stores them; they act
    as CiA-402 defines them (stop at the current/voltage limit, then SWITCH ON DISABLED) with the quick-stop ramp
    6085h standing in for the limit (the model has no torque; docs/decisions.md). Manufacturer-specific values
    act as the default 2."""
    manual_says(TS_TEXT, 2505, "3\tReserved")
    quick = _quick_stop(_moving("technosoft-ipos", 2))
    for option in (3, 4, -5):
        d = _moving("technosoft-ipos", option)
        assert _quick_stop(d) == quick
        assert d.cia402_state is State.SWITCH_ON_DISABLED


def test_ct_and_hdt_refuse_3_and_4():
    manual_says(CT_TEXT, 1504, "**Table 7.9 Quick stop value definitions**")
    for family in ("controltechniques", "hdt"):
        d = at(family, OP)
        for bad in (3, 4):
            assert code_of(w, d, 0x605A, 0, bad, 2) == 0x06090030


def test_quick_stop_with_the_axis_standing_ends_at_once():
    d = at("technosoft-ipos", OP)
    for cw in (0x06, 0x07, 0x0F, 0x0B):
        w(d, 0x6040, 0, cw, 2)
    assert d.cia402_state is State.SWITCH_ON_DISABLED


# --- fault reaction 605Eh ---------------------------------------------------------------------------------
def _fault_cycles(d: Drive, code: int) -> int:
    d.inject_fault(code)
    n = 0
    while d.cia402_state is State.FAULT_REACTION and n < 5000:
        assert r(d, 0x6041) & 0x4F == 0x0F and d.internal_velocity
        d.step(1)
        n += 1
    assert d.cia402_state is State.FAULT and d.internal_velocity == 0 and r(d, 0x603F) == code
    return n


def test_hdt_fault_reaction_ramps_in_fault_reaction_active_for_its_alarms():
    manual_says(HDT_TEXT, 2171, "these cases the Drive remains in“Fault reaction” state while it's executing this "
                                "action, and when it's completed the")
    manual_says(HDT_TEXT, 2206, "3220h DC link Under Voltage DC BUS under the voltage limit")
    cycles = {}
    for option in (0, 1, 2):
        d = _moving("hdt", 5)
        w(d, 0x605E, 0, option, 2)
        cycles[option] = _fault_cycles(d, 0x8611)
    assert cycles[0] == 0 and cycles[1] > 2 and abs(cycles[1] - 2 * cycles[2]) <= 2, cycles
    d = _moving("hdt", 5)
    w(d, 0x605E, 0, 1, 2)
    assert _fault_cycles(d, 0x2310) == 0  # not in the table: FAULT at once
    assert any(e.kind == "cia402" and e.data.get("reason") == "fault reaction completed" for e in d.events) is False


def test_technosoft_fault_reaction_2_uses_6085h_for_non_fatal_errors():
    manual_says(TS_TEXT, 2629, "2\tSlow down with quick stop ramp")
    d = _moving("technosoft-ipos", 5)
    assert r(d, 0x605E) == 2  # the default
    assert _fault_cycles(d, 0x3220) == 26  # under-voltage, a non-fatal error: 6085h as the quick stop
    assert any(e.kind == "cia402" and e.data.get("reason") == "fault reaction completed" for e in d.events)
    d = _moving("technosoft-ipos", 5)
    assert _fault_cycles(d, 0x2340) == 0  # short-circuit is not one of §4.4.11's non-fatal errors
    d = _moving("technosoft-ipos", 5)
    w(d, 0x605E, 0, 0, 2)
    assert _fault_cycles(d, 0x3220) == 0  # 0: "Disable drive, motor is free to rotate"


def test_ct_fault_reaction_is_ignored_for_trips():
    manual_says(CT_TEXT, 1571, "This object is ignored if the drive is tripped.")
    d = _moving("controltechniques", 5)
    w(d, 0x605E, 0, 2, 2)
    d.inject_trip(31)
    assert d.cia402_state is State.FAULT and d.internal_velocity == 0


# --- HDT profile type -1: linear ramp with torque limit ---------------------------------------------------------
REV = 65536  # HDT: 65536 pulses per motor revolution with the default factors


def _hdt_move_into_an_obstacle(profile_type: int) -> Drive:
    """10 revolutions at 600 rpm, 6000 rpm/s both ways, with an obstacle 3 revolutions out."""
    d = at("hdt", OP)
    w(d, 0x6060, 0, 1, 1)
    for index, value, size in ((0x6086, profile_type, 2), (0x6081, 600, 4), (0x6083, 6000, 4), (0x6084, 6000, 4)):
        w(d, index, 0, value, size)
    for cw in (0x06, 0x07, 0x0F):
        w(d, 0x6040, 0, cw, 2)
    d.set_obstacle(3 * REV)
    w(d, 0x607A, 0, 10 * REV, 4)
    w(d, 0x6040, 0, 0x1F, 2)
    return d


def test_hdt_profile_type_minus_1_stops_at_an_obstacle_and_resumes():
    manual_says(HDT_TEXT, 4188, "a trapezoidal shape. However, if the positioning is blocked by an obstacle, the "
                                "algorithm")
    manual_says(HDT_TEXT, 4191, "When the torque falls below its limit, the positioning is resumed to reach the "
                                "chosen")
    manual_says(HDT_TEXT, 4194, "In this mode the position error may not be detected since the position profile "
                                "adapts to the")
    d = _hdt_move_into_an_obstacle(-1)
    d.step(1000)  # 2 s, far longer than the move takes
    assert r(d, 0x6064, signed=True) == 3 * REV  # held at the obstacle
    assert r(d, 0x60F4, signed=True) == 0 and r(d, 0x6062, signed=True) == 3 * REV  # the profile adapts
    sw = r(d, 0x6041)
    assert sw & 0x6F == 0x27 and not sw & 0x0400 and not sw & 0x2000  # enabled, target not reached, no error
    d.set_obstacle(None)
    n = 0
    while not r(d, 0x6041) & 0x0400 and n < 2000:
        d.step(1)
        n += 1
    assert r(d, 0x6064, signed=True) == 10 * REV
    # resumed from standstill: 7 revolutions at 10 rev/s with 0.1 s ramps = 0.7 + 0.1 s = 400 cycles of 2 ms
    assert abs(n - 400) <= 1, n


def test_hdt_linear_ramp_at_an_obstacle_runs_into_the_following_error():
    """Profile type 0 against the same obstacle: the profile runs on, the position error 60F4h passes the window
    6065h (910 pulses) and after 6066h (200 ms) the drive faults with bit 13 (§4.06.5) and 8611h."""
    manual_says(HDT_TEXT, 3725, "error window\" (index 6065h). If this period is surpassed the bit 13 of the "
                                "statusword is set to 1 and the Drive")
    d = _hdt_move_into_an_obstacle(0)
    n = 0
    while d.cia402_state is State.OPERATION_ENABLED and n < 2000:
        d.step(1)
        n += 1
        if d.cia402_state is State.OPERATION_ENABLED and r(d, 0x6064, signed=True) == 3 * REV:
            assert r(d, 0x6062, signed=True) - 3 * REV == r(d, 0x60F4, signed=True) >= 0
    assert d.cia402_state is State.FAULT and r(d, 0x603F) == 0x8611
    assert r(d, 0x6041) & 0x2000
    assert r(d, 0x6064, signed=True) == 3 * REV
    w(d, 0x6040, 0, 0x80, 2)
    assert not r(d, 0x6041) & 0x2000


def test_hdt_profile_type_0_without_an_obstacle_moves_as_minus_1():
    times = {}
    for kind in (0, -1):
        d = _hdt_move_into_an_obstacle(kind)
        d.set_obstacle(None)
        n = 0
        while not r(d, 0x6041) & 0x0400 and n < 2000:
            d.step(1)
            n += 1
        times[kind] = n
    assert times[0] == times[-1] and abs(times[0] - 550) <= 1  # 10 rev: 1.0 + 0.1 s


def test_communication_lost_with_quick_stop_ramps_to_its_end_without_cycles():
    """Technosoft 6007h = 3 "Quick stop command" (TS line ~2650) with 605Ah = 2: out of OP no cycle comes, yet
    the drive ramps down by itself and ends in SWITCH ON DISABLED; with 6007h = 1 the fault 8100h (a non-fatal
    error, §4.4.11) ramps in FAULT REACTION ACTIVE and ends in FAULT."""
    manual_says(TS_TEXT, 2650, "+3\tQuick stop command")
    d = _moving("technosoft-ipos", 2)
    w(d, 0x6007, 0, 3, 2)
    d.lose_communication()
    assert d.cia402_state is State.SWITCH_ON_DISABLED and d.internal_velocity == 0
    d = _moving("technosoft-ipos", 2)
    w(d, 0x6007, 0, 1, 2)
    d.lose_communication()
    assert d.cia402_state is State.FAULT and d.internal_velocity == 0 and r(d, 0x603F) == 0x8100
    assert any(e.data.get("reason") == "fault reaction completed" for e in d.events if e.kind == "cia402")
