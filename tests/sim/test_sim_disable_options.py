"""Issue 33 N13: the shutdown (605Bh) and disable-operation (605Ch) option codes. Option code 1 "slow down with
slow down ramp; disable the drive function": the axis decelerates over several cycles with the slow-down ramp,
still OPERATION ENABLED, and only at standstill the drive makes the transition the controlword asked for; 0 disables
at once. The defaults and ranges are the families' profile data (Technosoft §4.4.8/§4.4.9: 605Bh 0, 605Ch 1;
Control Techniques Tables 7.10/7.12: 0 to 1; HDT has neither object)."""

from __future__ import annotations

from ecattool.sim import Drive
from ecattool.sim.cia402 import State
from tests.sim.sim_helpers import OP, SAFE, at, code_of, r, w
from tests.profiles.test_families_manuals import CT_TEXT, TS_TEXT, manual_says
from tests.sim.test_sim_stop_reactions import _moving

#: the controlword that leaves OPERATION ENABLED, by the state it asks for
SHUTDOWN, DISABLE_OPERATION, DISABLE_VOLTAGE = 0x06, 0x07, 0x00


def _leave(d: Drive, cw: int) -> tuple[int, list[int]]:
    """Write ``cw`` to a moving axis; the cycles it stays OPERATION ENABLED (bounded) and their velocities."""
    w(d, 0x6040, 0, cw, 2)
    seen = []
    n = 0
    while d.cia402_state is State.OPERATION_ENABLED and n < 5000:
        assert r(d, 0x6041) & 0x6F == 0x27  # still OPERATION ENABLED while it slows down
        seen.append(abs(d.internal_velocity))
        d.step(1)
        n += 1
    return n, seen


def test_technosoft_605c_default_1_ramps_with_6083h_then_switched_on():
    manual_says(TS_TEXT, 2017, "The drive will execute the instructions from Object 605Ch: Disable operation option "
                               "code and finally transition into <i>Switched On</i> state.")
    manual_says(TS_TEXT, 2539, "The slowdown ramp is a deceleration value set by the Profile acceleration object, "
                               "index 6083_h.")
    manual_says(TS_TEXT, 2560, "1\tSlow down on slow down ramp and disable the drive function")
    d = _moving("technosoft-ipos", 2)
    assert r(d, 0x605C) == 1  # the default of §4.4.9 (profile data), not written by the test
    n, seen = _leave(d, DISABLE_OPERATION)
    # 5 counts per sample down at 6083h = 6553 / 65536 counts per sample² (just under 0.1): 50 samples and the
    # last partial one (the quick-stop ramp 6085h is twice as steep: 26 in test_sim_stop_reactions)
    assert n == 51, n
    assert seen == sorted(seen, reverse=True) and seen[0] > seen[-1] > 0
    assert d.cia402_state is State.SWITCHED_ON and d.internal_velocity == 0 and r(d, 0x6041) & 0x6F == 0x23
    assert any(e.kind == "cia402" and e.data.get("reason") == "slow down completed, 605Ch = 1 (disable operation)"
               for e in d.events)


def test_technosoft_605b_default_0_disables_at_once_and_1_ramps():
    manual_says(TS_TEXT, 2020, "The drive will execute the instructions from Object 605Bh: Shutdown option code and "
                               "finally transition into <i>Ready to switch on</i> state.")
    manual_says(TS_TEXT, 2533, "0\tDisable drive function (switch-off the drive power stage)")
    d = _moving("technosoft-ipos", 2)
    assert r(d, 0x605B) == 0
    assert _leave(d, SHUTDOWN)[0] == 0
    assert d.cia402_state is State.READY and d.internal_velocity == 0
    d = _moving("technosoft-ipos", 2)
    w(d, 0x605B, 0, 1, 2)
    assert _leave(d, SHUTDOWN)[0] == 51
    assert d.cia402_state is State.READY


def test_technosoft_disable_voltage_follows_605c():
    """Technosoft's transition 9 reads 605Ch too (CiA-402's switches the power stage off at once)."""
    manual_says(TS_TEXT, 2021, "Bit 1 is cancelled in Controlword (Disable Voltage command)\tThe drive will execute "
                               "the instructions from Object 605Ch: Disable operation option code and finally "
                               "transition into <i>Switch on disabled</i> state.")
    d = _moving("technosoft-ipos", 2)
    assert _leave(d, DISABLE_VOLTAGE)[0] == 51
    assert d.cia402_state is State.SWITCH_ON_DISABLED
    d = _moving("technosoft-ipos", 2)
    w(d, 0x605C, 0, 0, 2)
    assert _leave(d, DISABLE_VOLTAGE)[0] == 0 and d.cia402_state is State.SWITCH_ON_DISABLED


def test_controltechniques_option_1_ramps_with_6084h_in_csp():
    manual_says(CT_TEXT, 1531, "This object is used to control what action is performed if there is a transition "
                               "from the Operation Enabled state to the Ready To Switch On state.")
    manual_says(CT_TEXT, 1546, "| 1     | Slow down with slow down ramp; disable the drive function |")
    manual_says(CT_TEXT, 1567, "| 1     | Slow down with slow down ramp; disable the drive function |")
    manual_says(CT_TEXT, 1494, "The slow down ramp is the deceleration value of the used mode of operations.")
    for index, cw, end in ((0x605B, SHUTDOWN, State.READY), (0x605C, DISABLE_OPERATION, State.SWITCHED_ON)):
        d = _moving("controltechniques", 2)
        assert r(d, index) == 0 and _leave(d, cw)[0] == 0 and d.cia402_state is end  # 0: at once
        d = _moving("controltechniques", 2)
        w(d, index, 0, 1, 2)
        n, seen = _leave(d, cw)
        assert n > 2 and d.cia402_state is end and d.internal_velocity == 0
        # Disable Voltage is CiA-402's transition 9 on this family: at once, whatever 605Ch says
        d = _moving("controltechniques", 2)
        w(d, index, 0, 1, 2)
        assert _leave(d, DISABLE_VOLTAGE)[0] == 0 and d.cia402_state is State.SWITCH_ON_DISABLED
    assert code_of(w, at("controltechniques", OP), 0x605B, 0, 2, 2) == 0x06090031  # Table 7.10: 0 to 1


def test_enable_operation_during_the_slow_down_takes_the_axis_back():
    d = _moving("technosoft-ipos", 2)
    w(d, 0x6040, 0, DISABLE_OPERATION, 2)
    d.step(10)
    assert d.cia402_state is State.OPERATION_ENABLED
    w(d, 0x6040, 0, 0x0F, 2)
    d.step(200)
    assert d.cia402_state is State.OPERATION_ENABLED and d.internal_velocity == 5 * 65536  # back at 60FFh


def test_quick_stop_during_the_slow_down_takes_over():
    d = _moving("technosoft-ipos", 2)
    w(d, 0x6040, 0, DISABLE_OPERATION, 2)
    d.step(10)
    w(d, 0x6040, 0, 0x0B, 2)  # quick stop: its own ramp, then SWITCH ON DISABLED (605Ah = 2)
    n = 0
    while d.cia402_state is State.QUICK_STOP and n < 100:
        d.step(1)
        n += 1
    assert 0 < n < 26 and d.cia402_state is State.SWITCH_ON_DISABLED


def test_hdt_has_no_605b_605c_and_disables_at_once():
    d = _moving("hdt", 2)
    assert code_of(d.sdo_upload, 0x605C, 0) == 0x06020000
    assert _leave(d, DISABLE_OPERATION)[0] == 0 and d.cia402_state is State.SWITCHED_ON


def test_the_slow_down_runs_through_the_plant():
    """On the family's default plant (not the ideal tracker) the slow-down takes as many cycles."""
    d = at("technosoft-ipos", OP, plant=None)
    w(d, 0x6060, 0, 3, 1)
    w(d, 0x6083, 0, 65536 // 10, 4)
    for cw in (0x06, 0x07, 0x0F):
        w(d, 0x6040, 0, cw, 2)
    w(d, 0x60FF, 0, 5 * 65536, 4)
    d.step(200)
    before = r(d, 0x606C, signed=True)
    assert before > 0
    n, _ = _leave(d, DISABLE_OPERATION)
    assert n >= 49 and d.cia402_state is State.SWITCHED_ON


# --- 605Dh halt in the cyclic modes ------------------------------------------------------------------------------
def test_technosoft_halt_in_csv_ramps_with_605dh_and_ignores_the_target():
    """A halt in CSV ramps down with the slow-down ramp 605Dh = 1 names (6083h), the target ignored (bit 12 = 0)
    and bit 10 = 0 while the drive decelerates, 1 at standstill; it stopped within the cycle before."""
    manual_says(TS_TEXT, 2565, "This object determines what action is taken if when the halt command is executed. "
                               "The slowdown ramp is a deceleration value set by [Object 6083_h: Profile "
                               "acceleration](#).")
    manual_says(TS_TEXT, 8907, "Target velocity ignored. When 6040h.8 Halt is set to 1.")
    d = at("technosoft-ipos", OP)
    w(d, 0x6060, 0, 9, 1)
    w(d, 0x6083, 0, 65536 // 10, 4)
    for cw in (0x06, 0x07, 0x0F):
        w(d, 0x6040, 0, cw, 2)
    w(d, 0x60FF, 0, 5 * 65536, 4)
    d.step(3)
    assert d.internal_velocity == 5 * 65536 and r(d, 0x605D) == 1
    w(d, 0x6040, 0, 0x10F, 2)
    n = 0
    while d.internal_velocity and n < 200:
        sw = r(d, 0x6041)
        assert not sw & 0x1000 and not sw & 0x0400 and sw & 0x6F == 0x27
        d.step(1)
        n += 1
    assert n == 51, n
    assert r(d, 0x6041) & 0x0400 and d.cia402_state is State.OPERATION_ENABLED
    w(d, 0x6040, 0, 0x0F, 2)  # halt cleared: the target velocity again
    d.step(1)
    assert d.internal_velocity == 5 * 65536


def test_controltechniques_halt_in_csp_ramps_with_6084h():
    """605Dh (no default: 0, as 1) in CSP (Control Techniques: "the deceleration value of the used mode of operations",
    6084h): the axis slows down over several cycles, holding still afterwards while the target runs on."""
    manual_says(CT_TEXT, 1494, "The slow down ramp is the deceleration value of the used mode of operations.")
    d = at("controltechniques", SAFE)
    d.configure_dc(0x0300, 1_000_000)
    d.request_state(OP)
    w(d, 0x6060, 0, 8, 1)
    w(d, 0x6084, 0, 100 * 65536, 4)  # 10 units a 250 us cycle stop in about 25 cycles
    for cw in (0x06, 0x07, 0x0F):
        w(d, 0x6040, 0, cw, 2)
    for position in range(1, 21):
        w(d, 0x607A, 0, position * 10, 4)
        d.step(1)
    assert d.internal_velocity
    w(d, 0x6040, 0, 0x10F, 2)
    n = 0
    while d.internal_velocity and n < 1000:
        w(d, 0x607A, 0, 300 + n * 10, 4)  # the master's set-points run on: ignored while halted
        d.step(1)
        n += 1
    assert 2 < n < 1000
    held = r(d, 0x6064, signed=True)
    d.step(5)
    assert r(d, 0x6064, signed=True) == held and d.cia402_state is State.OPERATION_ENABLED
