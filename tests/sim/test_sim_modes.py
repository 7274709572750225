"""Issue 33 item 3: every mode a family accepts does what its manual says (N5 vl velocity, N6 interpolated
position, N7 profile torque and CST, N8-N10 profile velocity status, N31 6061h at power-on). Each test quotes
the manual line it follows (TS = 000_…, HDT = 003_…, CT = 004_… seed text)."""

from __future__ import annotations

from fractions import Fraction

from ecattool.od.model import EcState
from ecattool.sim import Drive
from ecattool.sim.cia402 import State
from tests.sim.sim_helpers import OP, PRE, SAFE, at, in_mode, r, w
from tests.conftest import seeds_path

TS_TEXT, HDT_TEXT, CT_TEXT = "000_a0ab57c0bda88c2c.txt", "003_8679b1dde0e37523.txt", "004_b59360cba58a7982.txt"


def manual_says(seed: str, line: int, text: str) -> None:
    """The quoted text is on (or within 40 lines of) the seed line cited: the test follows the manual."""
    lines = seeds_path(seed).read_text(encoding="utf-8").splitlines()
    window = "\n".join(lines[max(0, line - 41):line + 40])
    assert text in window, f"{seed}:{line} does not say {text!r}"


def enable(d: Drive, last: int = 0x0F) -> None:
    for cw in (0x06, 0x07, last):
        w(d, 0x6040, 0, cw, 2)
    assert d.cia.state is State.OPERATION_ENABLED


def ct_with_dc(mode: int, plant: object = "ideal") -> Drive:
    """A Control Techniques drive in OP with SYNC0 at 250 us (its positioning modes need DC, CT 1857); on the
    ideal plant unless ``plant`` is given (the manuals' traces are the demand's)."""
    d = Drive.from_profile("controltechniques", plant=plant)  # type: ignore[arg-type]
    d.request_state(PRE)
    w(d, 0x6060, 0, mode, 1)
    d.configure_dc(0x0300, 250_000)
    d.request_state(SAFE)
    d.request_state(OP)
    return d


# N31 -----------------------------------------------------------------------------------------------------
def test_n31_mode_display_follows_the_default_mode_from_power_on():
    manual_says(HDT_TEXT, 2211, "6060h Modes of INT8 -2.10 2 Yes rw")
    manual_says(CT_TEXT, 1599, "| Default:      | 2   |")
    for family in ("hdt", "controltechniques"):
        d = Drive.from_profile(family)
        assert (d.value(0x6060), d.value(0x6061)) == (2, 2), family
    # Technosoft shows the mode only once OPERATION ENABLED is reached (§4.2.3): unchanged
    assert Drive.from_profile("technosoft-ipos").value(0x6061) == 0


# N5 ------------------------------------------------------------------------------------------------------
def test_n5_ct_vl_ramps_to_the_target_with_the_manual_example_ramp():
    manual_says(CT_TEXT, 2057, "Example: To ramp to 1000 rpm in 5s, possible values for delta speed and delta time "
                               "are 10000 and 50 respectively.")
    manual_says(CT_TEXT, 2193, "The vl\\_target\\_velocity object is re-read every new profile cycle.")
    d = at("controltechniques", OP)  # vl is the default mode (6060h = 2)
    w(d, 0x6048, 1, 10000, 4)
    w(d, 0x6048, 2, 50, 2)
    enable(d)
    w(d, 0x6042, 0, 1000, 2)
    cycles_per_s = int(1 / d.cycle_time())
    d.step(cycles_per_s * 5 // 2)
    assert (r(d, 0x6043, 0, True), r(d, 0x6044, 0, True)) == (500, 500)  # half way after 2.5 s
    assert not r(d, 0x6041) & 0x0400
    d.step(cycles_per_s * 5 // 2)
    assert (r(d, 0x6043, 0, True), r(d, 0x6044, 0, True)) == (1000, 1000)
    before = d.value(0x6064)
    d.step(cycles_per_s)
    assert d.value(0x6064) > before  # the axis turns
    # the default deceleration 6049h = 1000 rpm / 2 s: from 1000 rpm to 0 in 2 s
    w(d, 0x6042, 0, 0, 2)
    d.step(cycles_per_s)
    assert r(d, 0x6044, 0, True) == 500
    d.step(cycles_per_s)
    assert r(d, 0x6044, 0, True) == 0


def test_n5_ct_vl_target_is_limited_by_6047():
    manual_says(CT_TEXT, 2195, "The vl\\_target\\_velocity is limited according to the values set in the object "
                               "vl\\_velocity\\_min\\_max")
    d = at("controltechniques", OP)
    w(d, 0x6047, 2, 300, 4)  # max positive
    w(d, 0x6047, 3, 50, 4)  # min negative
    w(d, 0x6048, 2, 0, 2)
    w(d, 0x6049, 2, 0, 2)
    enable(d)
    w(d, 0x6042, 0, 1000, 2)
    d.step(2)
    assert r(d, 0x6043, 0, True) == 300
    w(d, 0x6042, 0, -10, 2)
    d.step(2)
    assert r(d, 0x6043, 0, True) == -50


def test_n5_hdt_vl_controlword_bits_and_instant_ramp():
    manual_says(HDT_TEXT, 5329, "0 The motor is stopped with the power on")
    manual_says(HDT_TEXT, 5489, "If “Delta time\" is set to 0 the reference speed is followed instantly")
    manual_says(HDT_TEXT, 5435, "This parameter corresponds to the measured speed of the motor")
    d = at("hdt", OP)
    enable(d)  # 0x0F: bits 4-6 = 0, the ramp is not enabled
    w(d, 0x6042, 0, 1000, 2)
    d.step(600)
    assert r(d, 0x6044, 0, True) == 0
    w(d, 0x6040, 0, 0x7F, 2)  # enable ramp, unlock, use the reference
    d.step(250)  # 6048h default 1000 rpm / 1 s, 2 ms cycle: 500 rpm after 0.5 s
    assert r(d, 0x6043, 0, True) == 500
    w(d, 0x6040, 0, 0x5F, 2)  # bit 5 = 0: the ramp output is held
    d.step(100)
    assert r(d, 0x6043, 0, True) == 500
    w(d, 0x6048, 2, 0, 2)  # delta time 0: the reference at once
    w(d, 0x6040, 0, 0x7F, 2)
    d.step(1)
    assert r(d, 0x6044, 0, True) == 1000
    w(d, 0x6040, 0, 0x6F, 2)  # bit 4 = 0: stopped
    d.step(1)
    assert r(d, 0x6044, 0, True) == 0


def test_n5_hdt_vl_min_amount():
    manual_says(HDT_TEXT, 5451, "its minimum achievable value is “+ min velocity amount’")
    d = at("hdt", OP)
    w(d, 0x6046, 1, 200, 4)
    w(d, 0x6048, 2, 0, 2)
    enable(d, 0x7F)
    w(d, 0x6042, 0, 20, 2)
    d.step(1)
    assert r(d, 0x6043, 0, True) == 200


# N7 ------------------------------------------------------------------------------------------------------
def test_n7_ct_profile_torque_follows_the_slope_and_moves_the_axis():
    manual_says(CT_TEXT, 2233, "The value of this object is given per thousand of rated torque.")
    manual_says(CT_TEXT, 2271, "The value of this object is given in units of per thousand of rated torque per second.")
    d = in_mode("controltechniques", 4)
    w(d, 0x6087, 0, 1000, 4)  # 100 % of rated torque per second
    enable(d)
    w(d, 0x6071, 0, 500, 2)  # 50 %
    cycles_per_s = int(1 / d.cycle_time())
    d.step(cycles_per_s // 4)
    assert r(d, 0x6077, 0, True) == 250
    assert not r(d, 0x6041) & 0x0400
    d.step(cycles_per_s // 4)
    assert r(d, 0x6077, 0, True) == 500
    assert r(d, 0x6041) & 0x0400  # target torque reached
    assert d.value(0x6064) != 0 and d.cia.velocity > 0


def test_n7_technosoft_cst_torque_is_the_cycle_demand_and_accelerates_by_torque_over_inertia():
    manual_says(CT_TEXT, 2233, "per thousand of rated torque")
    d = in_mode("technosoft-ipos", 10)
    enable(d)
    from ecattool.sim.drive.torque_mode import FreeInertia

    d.modes.torque.load = FreeInertia(Fraction(2000), Fraction(100))  # rated torque: 100 rev/s²
    w(d, 0x6071, 0, 250, 2)
    d.step(1)
    assert r(d, 0x6077, 0, True) == 250
    assert r(d, 0x6041) & 0x1000  # CST: the drive follows the command value
    d.step(999)  # one second at 25 % of rated torque: 25 rev/s = 50,000 increments/s
    assert d.units.increments_per_second(d.cia.velocity) == 50_000
    assert d.cia.position == Fraction(50_000, 2)  # a = const: x = a t² / 2
    w(d, 0x6040, 0, 0x10F, 2)  # halt: no torque
    d.step(1)
    assert r(d, 0x6077, 0, True) == 0


# N6 ------------------------------------------------------------------------------------------------------
def test_n6_ct_interpolated_position_follows_60c1_one_period_late():
    manual_says(CT_TEXT, 1871, "Linear interpolation is used to generate position demand values every 250µs.")
    manual_says(CT_TEXT, 1921, "this type inserts a delay of one interpolation time period")
    d = ct_with_dc(7)
    enable(d)
    for record in (100, 200, 300):
        w(d, 0x60C1, 1, record, 4)
        d.step(1)
        assert d.value(0x6064) == record - 100  # the record of the period before
    d.step(1)
    assert d.value(0x6064) == 300
    assert r(d, 0x6041) & 0x0400


def test_n6_ct_interpolated_position_is_delayed_once_on_the_plant():
    """The one period of CT 1921 is the interpolator's: the plant's own reference delay (CT CSP, 2550) does not
    add a second one in mode 7, so the axis on the family's plant tracks the same demand as on a plant without
    that delay."""
    from dataclasses import replace

    from ecattool.sim.drive.plant import plant_for

    params = plant_for("controltechniques")
    assert params is not None and params.delay == "reference"
    traces = []
    for p in (params, replace(params, delay="none")):
        d = ct_with_dc(7, plant=p)
        enable(d)
        trace = []
        for cycle in range(800):  # 0.2 s at 250 us: one revolution (1 unit, 65536 increments) per 80 periods
            w(d, 0x60C1, 1, min(cycle // 80, 5), 4)
            d.step(1)
            assert d.plant is not None
            trace.append(round(d.cia.pos_n / d.cia.pos_d + d.plant.reported()[0]))  # increments, as measured
        traces.append(trace)
    assert traces[0] == traces[1] and 0 < traces[0][100] < traces[0][-1] <= 5 * 65536


def test_n6_hdt_interpolated_position_needs_bit4_and_reports_bit12():
    manual_says(HDT_TEXT, 4792, "1 Enables the Interpolator mode")
    manual_says(HDT_TEXT, 4860, "1 Interpolator enabled")
    d = in_mode("hdt", 7)
    enable(d)
    w(d, 0x60C1, 1, 5000, 4)
    d.step(3)
    assert d.value(0x6064) == 0 and not r(d, 0x6041) & 0x1000
    w(d, 0x6040, 0, 0x1F, 2)
    d.step(1)
    assert d.value(0x6064) == 5000 and r(d, 0x6041) & 0x1000
    w(d, 0x60C1, 1, 5500, 4)
    d.step(1)
    assert d.value(0x6064) == 5500


# N8 N9 ---------------------------------------------------------------------------------------------------
def _hdt_pv() -> Drive:
    d = in_mode("hdt", 3)
    enable(d)
    return d


def test_n8_hdt_pv_bit10_waits_for_the_velocity_window_time():
    manual_says(HDT_TEXT, 5172, "for a longer period than the one set here, then the")
    d = _hdt_pv()
    w(d, 0x606D, 0, 20, 2)
    w(d, 0x606E, 0, 100, 2)  # ms
    w(d, 0x60FF, 0, 1000, 4)
    reached_at = None
    window_at = None
    for cycle in range(1, 1000):
        d.step(1)
        if window_at is None and abs(1000 - r(d, 0x606C, 0, True)) <= 20:
            window_at = cycle
        if r(d, 0x6041) & 0x0400:
            reached_at = cycle
            break
    assert window_at is not None and reached_at is not None
    # in the window at 1000 - 20, 100 ms (50 cycles of 2 ms) later bit 10
    assert (reached_at - window_at) * 2 == 100


def test_n9_hdt_pv_bit12_speed_zero_with_threshold_time():
    manual_says(HDT_TEXT, 5181, "longer than the one set on “Velocity threshold time\" (index 6070h), then bit 12 of "
                                "the statusword is set to 0")
    d = _hdt_pv()
    d.step(1)
    assert r(d, 0x6041) & 0x1000  # standing still
    w(d, 0x606F, 0, 20, 2)
    w(d, 0x6070, 0, 10, 2)  # ms
    w(d, 0x60FF, 0, 1000, 4)
    above = None
    for cycle in range(1, 100):
        d.step(1)
        if above is None and r(d, 0x606C, 0, True) > 20:
            above = cycle
        if not r(d, 0x6041) & 0x1000:
            assert above is not None and (cycle - above) * 2 == 10
            break
    else:
        raise AssertionError("bit 12 never fell")


def test_n9_technosoft_pv_bit12_below_threshold():
    manual_says(TS_TEXT, 7675, "If the actual velocity of the drive / motor is below the velocity threshold, then bit "
                               "12 will be set, else it will be reset.")
    d = in_mode("technosoft-ipos", 3)
    w(d, 0x606F, 0, 5, 2)
    w(d, 0x6083, 0, 1, 4)
    enable(d)
    d.step(1)
    assert r(d, 0x6041) & 0x1000
    w(d, 0x60FF, 0, 1 << 16, 4)  # 1 increment/sample (15.16 fixed point)
    d.step(20)
    assert not r(d, 0x6041) & 0x1000


def test_n8_technosoft_pv_bit10_in_the_window():
    manual_says(TS_TEXT, 7744, "is in the velocity window for longer than the velocity window time (606E_h), the "
                               "*Target reached bit* (Statusword) is set")
    d = in_mode("technosoft-ipos", 3)
    w(d, 0x6083, 0, 1 << 15, 4)  # 0.5 increment/sample² (15.16 fixed point)
    enable(d)
    w(d, 0x606D, 0, 40000, 2)  # 0.61 increment/sample
    w(d, 0x606E, 0, 0, 2)
    w(d, 0x60FF, 0, 100 << 16, 4)
    d.step(198)  # 99 increments/sample: outside the window
    assert not r(d, 0x6041) & 0x0400
    d.step(1)  # 99.5: inside, window time 0: reached although the ramp goes on
    assert r(d, 0x6041) & 0x0400
    w(d, 0x606E, 0, 5, 2)  # 5 ms = 5 samples in the window before bit 10
    w(d, 0x60FF, 0, 200 << 16, 4)
    d.step(1)
    assert not r(d, 0x6041) & 0x0400
    steps = 0
    while not r(d, 0x6041) & 0x0400:
        d.step(1)
        steps += 1
        assert steps < 1000
    assert r(d, 0x606C, 0, True) == 200 << 16
    assert d.modes.pv.in_window_s == Fraction(5, 1000)


# N10 -----------------------------------------------------------------------------------------------------
def test_n10_technosoft_pv_target_written_before_entering_does_not_start():
    manual_says(TS_TEXT, 7645, "Remark2: If the velocity is already set when entering velocity mode, the motion will "
                               "not start until a value (even if it is the same) will be set again in Target "
                               "Velocity 60FF_h.")
    d = at("technosoft-ipos", OP)
    w(d, 0x60FF, 0, 1 << 16, 4)
    w(d, 0x6083, 0, 1 << 16, 4)
    w(d, 0x6060, 0, 3, 1)
    enable(d)
    d.step(10)
    assert d.cia.velocity == 0
    w(d, 0x60FF, 0, 1 << 16, 4)  # the same value again
    d.step(10)
    assert d.cia.velocity != 0
    # HDT has no such rule: a target set before moves at once
    h = at("hdt", OP)
    w(h, 0x60FF, 0, 100, 4)
    w(h, 0x6060, 0, 3, 1)
    enable(h)
    h.step(10)
    assert h.cia.velocity != 0
    assert h.esm is EcState.OP


# N1 N2 N21 N22 (profile position set-points) ---------------------------------------------------------------
def _pp(family: str, velocity: int, acceleration: int) -> Drive:
    d = at(family, PRE)
    w(d, 0x6060, 0, 1, 1)
    d.request_state(SAFE)
    d.request_state(OP)
    w(d, 0x6081, 0, velocity, 4)
    w(d, 0x6083, 0, acceleration, 4)
    if (0x6084, 0) in d._entries:
        w(d, 0x6084, 0, acceleration, 4)
    enable(d)
    return d


def _until_reached(d: Drive, limit: int = 100_000) -> int:
    for n in range(1, limit):
        d.step(1)
        if r(d, 0x6041) & 0x0400:
            return n
    raise AssertionError("target never reached")


def test_n1_n2_technosoft_single_setpoint_waits_for_the_running_move():
    manual_says(TS_TEXT, 5836, "Finish the actual positioning and then start the next positioning")
    manual_says(TS_TEXT, 5806, "the drive will signalize that it can accept a new set-point by resetting *set-point "
                               "acknowledge* bit in *Statusword* after the reference generator has reached the "
                               "designated demand position")
    d = _pp("technosoft-ipos", 10 << 16, 1 << 16)  # 10 increments/ms, 1 increment/ms²
    w(d, 0x607A, 0, 20000, 4)
    w(d, 0x6040, 0, 0x1F, 2)
    d.step(100)
    w(d, 0x6040, 0, 0x0F, 2)  # bit 4 falls during the move: acknowledge stays (N2)
    assert r(d, 0x6041) & 0x1000
    w(d, 0x607A, 0, 0, 4)
    w(d, 0x6040, 0, 0x1F, 2)  # a second set-point while the first runs (N1)
    w(d, 0x6040, 0, 0x0F, 2)
    before = d.value(0x6064)
    d.step(10)
    assert d.value(0x6064) > before  # still on the way to 20000
    peak = before
    for _ in range(5000):
        d.step(1)
        peak = max(peak, d.value(0x6064))
        if d.value(0x6064) < peak:
            break
    assert peak == 20000  # the first move ended at its target, then the second started
    assert r(d, 0x6041) & 0x1000  # acknowledged: the second set-point runs
    _until_reached(d)
    assert d.value(0x6064) == 0 and not r(d, 0x6041) & 0x1000


def test_n2_hdt_single_setpoint_acknowledge_until_the_end_of_the_positioning():
    manual_says(HDT_TEXT, 4026, "When a positioning is terminated the bit 12 of the statusword is set")
    d = _pp("hdt", 1000, 10000)
    w(d, 0x607A, 0, 20000, 4)
    w(d, 0x6040, 0, 0x1F, 2)
    d.step(10)
    w(d, 0x6040, 0, 0x0F, 2)
    assert r(d, 0x6041) & 0x1000  # bit 4 fell, the positioning runs: still acknowledged
    _until_reached(d)
    assert not r(d, 0x6041) & 0x1000
    # change set immediately: acknowledge follows bit 4 (HDT 4056)
    manual_says(HDT_TEXT, 4056, "When bit 4 of the controlword returns to 0 bit 12 of the statusword returns to 0 too")
    w(d, 0x607A, 0, 0, 4)
    w(d, 0x6040, 0, 0x3F, 2)
    d.step(5)
    w(d, 0x6040, 0, 0x2F, 2)
    assert not r(d, 0x6041) & 0x1000


def test_n21_technosoft_additive_relative_move():
    manual_says(TS_TEXT, 5797, "In the additive relative mode, the position to reach is computed by adding the "
                               "position increment to the previous position to reach")
    d = _pp("technosoft-ipos", 10 << 16, 1 << 16)
    w(d, 0x607A, 0, 5000, 4)
    w(d, 0x6040, 0, 0x3F, 2)  # absolute 5000, change set immediately
    d.step(50)
    w(d, 0x6040, 0, 0x2F, 2)
    w(d, 0x607A, 0, 1000, 4)
    w(d, 0x6040, 0, 0x087F, 2)  # relative (bit 6), additive (bit 11), immediately (bit 5)
    _until_reached(d)
    assert d.value(0x6064) == 6000  # 5000 + 1000, not the position at the command + 1000


def test_n22_technosoft_s_curve_with_change_set_immediately_is_a_command_error():
    manual_says(TS_TEXT, 5818, "then *change set immediately* bit must be 0, else a command error is issued")
    manual_says(TS_TEXT, 1804, "9000\tCommand error")
    d = _pp("technosoft-ipos", 10 << 16, 1 << 16)
    w(d, 0x6086, 0, 3, 2)
    w(d, 0x607A, 0, 5000, 4)
    w(d, 0x6040, 0, 0x3F, 2)
    assert [m.code for m in d.emergencies][-1] == 0x9000
    assert r(d, 0x2000) & (1 << 14)  # Motion Error Register: command error
    d.step(100)
    assert d.value(0x6064) == 0  # not taken


# N19 N26 N27 ---------------------------------------------------------------------------------------------
def test_n19_technosoft_statusword_bit15_axis_on():
    manual_says(TS_TEXT, 2124, "1	Axis on. Power stage is enabled. Motor control is performed")
    d = at("technosoft-ipos", OP)
    for cw in (0x06, 0x07):
        w(d, 0x6040, 0, cw, 2)
        assert not r(d, 0x6041) & 0x8000
    w(d, 0x6040, 0, 0x0F, 2)
    assert r(d, 0x6041) & 0x8000
    w(d, 0x6040, 0, 0x07, 2)
    assert not r(d, 0x6041) & 0x8000


def test_n26_n27_motion_error_register_and_fault_reset():
    manual_says(TS_TEXT, 2359, "3	Control error (position/speed error too big). <u>Set</u> when protection is "
                               "triggered. <u>Reset</u> by a Reset Fault command")
    manual_says(TS_TEXT, 1781, "00xx	Error Reset or No Error")
    manual_says(CT_TEXT, 3128, "| 0x0000     | Error reset / No error ")
    d = at("technosoft-ipos", OP)
    enable(d)
    d.inject_fault(0x8611)
    assert r(d, 0x2000) & (1 << 3) and r(d, 0x1001) != 0
    d.set_limit_switches(negative=True)
    assert r(d, 0x2000) & (1 << 7)
    d.set_limit_switches()
    w(d, 0x6040, 0, 0x80, 2)
    assert d.cia.state is State.SWITCH_ON_DISABLED
    assert (r(d, 0x2000), r(d, 0x1001)) == (0, 0)
    assert d.emergencies[-1].code == 0x0000
    c = at("controltechniques", OP)
    enable(c)
    c.inject_trip(1)
    w(c, 0x6040, 0, 0x80, 2)
    assert (r(c, 0x1001), c.emergencies[-1].code) == (0, 0x0000)


# N23 N24 (Technosoft CSP) ----------------------------------------------------------------------------------
def _ts_csp() -> Drive:
    d = in_mode("technosoft-ipos", 8)
    enable(d)
    return d


def test_n23_technosoft_csp_relative_adds_607a_each_cycle():
    manual_says(TS_TEXT, 8736, "In Relative position mode, the drive will add to its current position the value "
                               "received in object 607A_h.")
    d = _ts_csp()
    w(d, 0x6040, 0, 0x4F, 2)  # bit 6: relative
    w(d, 0x607A, 0, 10, 4)
    d.step(5)
    assert d.value(0x6064) == 50
    w(d, 0x6040, 0, 0x0F, 2)  # absolute again
    d.step(1)
    assert d.value(0x6064) == 10


def test_n24_technosoft_csp_speed_limit_2086():
    manual_says(TS_TEXT, 8817, "If 2086_h = 1, the limit is active. During CSP mode, the maximum velocity will be the "
                               "one defined in object 6081_h.")
    manual_says(TS_TEXT, 8819, "If 6081_h = 0 and 2086_h = 1, during CSP mode, the motor will not move")
    d = _ts_csp()
    w(d, 0x2086, 0, 1, 2)
    w(d, 0x6081, 0, 0, 4)
    w(d, 0x607A, 0, 1000, 4)
    d.step(3)
    assert d.value(0x6064) == 0
    w(d, 0x6081, 0, 100 << 16, 4)  # 100 increments per sample (1 ms)
    d.step(3)
    assert d.value(0x6064) == 300
    d.step(10)
    assert d.value(0x6064) == 1000


# N28 N29 N30 (Control Techniques) --------------------------------------------------------------------------
def test_n28_ct_trips_map_to_the_codes_of_table_9_17():
    manual_says(CT_TEXT, 3133, "| 0x3130     | Phase failure                           | 32 – PH<br>107 – PH.P   |")
    manual_says(CT_TEXT, 3136, "| 0x4200     | Temperature device ")
    manual_says(CT_TEXT, 3157, "| 0x7112 | Brake Chopper (Over current brake chopper) | 4 – Ol.br")
    expected = {32: 0x3130, 107: 0x3130, 2: 0x3200, 21: 0x4200, 105: 0x4200, 36: 0x5530, 4: 0x7112, 176: 0x7300,
                190: 0x7300, 177: 0x7600, 8: 0x3000, 109: 0x2200, 20: 0x2300, 215: 0x5000, 150: 0x6200, 11: 0x1000}
    for trip, code in expected.items():
        d = at("controltechniques", OP)
        d.inject_trip(trip)
        assert d.value(0x603F) == code, trip


def test_n29_ct_positioning_mode_selected_in_op_without_dc_leaves_op():
    manual_says(CT_TEXT, 1857, "When using one of the DSP-402 positioning modes, Distributed Clocks must be enabled. "
                               "Failure to do so may result in the SM-EtherCAT module going into the SAFE-OPERATIONAL "
                               "state (Pr **MM.04** = 4).")
    d = at("controltechniques", OP)  # free run, vl
    w(d, 0x6060, 0, 8, 1)
    assert d.esm is EcState.SAFEOP
    assert d.value(0x200F, 4) == 4
    assert any(e.kind == "state" and e.data.get("al_status") == 0x0030 for e in d.events)
    # with DC it stays in OP; vl without DC as well
    c = ct_with_dc(2)
    w(c, 0x6060, 0, 8, 1)
    assert c.esm is EcState.OP


def test_n30_ct_6080_is_pr_1_06():
    manual_says(CT_TEXT, 1808, "changing the value of this object will also change Pr 1.06")
    d = at("controltechniques", PRE)
    assert d.value(0x2001, 6) == d.value(0x6080) == 3000
    w(d, 0x6080, 0, 1500, 4)
    assert d.value(0x2001, 6) == 1500
    w(d, 0x2001, 6, 2500, 4)
    assert d.value(0x6080) == 2500


def test_no_family_name_compares_left_in_the_simulator():
    """Issue 33 item 1: the family is chosen once, as data (``Behaviour``, ``FamilyRules``); the simulator's code
    compares no family names."""
    import re
    from pathlib import Path

    root = Path(__file__).resolve().parents[2] / "ecattool" / "sim"
    found = [f"{p.relative_to(root)}:{n}" for p in root.rglob("*.py")
             for n, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1)
             if re.search(r"family\s*(==|!=|in\s*\()", line)]
    assert not found, found


# N25 -----------------------------------------------------------------------------------------------------
def test_n25_technosoft_polarity_reverses_targets_and_actual_values():
    manual_says(TS_TEXT, 4222, "This object is used to multiply by 1 or -1 position and velocity objects. The object "
                               "applies only to position profile, velocity profile, CSP and CSV in modes of operation.")
    d = _ts_csp()
    w(d, 0x607E, 0, 0xC0, 1)
    w(d, 0x607A, 0, 1000, 4)
    d.step(1)
    assert d.internal_position == -1000  # the motor turns the other way
    assert d.value(0x6064) == 1000  # and the position object is multiplied by -1 too
    w(d, 0x607E, 0, 0, 1)
    d.step(1)
    assert d.internal_position == 1000 and d.value(0x6064) == 1000


def test_n25_technosoft_polarity_reverses_the_actual_values_on_the_plant_too():
    """The same on the family's default plant (issue 33 item 2): 6064h, 6062h, 606Ch and 60F4h reversed, as the
    ideal plant reports them (they were the unreversed plant values)."""
    manual_says(TS_TEXT, 4222, "This object is used to multiply by 1 or -1 position and velocity objects.")
    d = at("technosoft-ipos", OP, plant=None)
    assert d.plant is not None
    w(d, 0x607E, 0, 0xC0, 1)
    w(d, 0x6060, 0, 8, 1)
    for cw in (0x06, 0x07, 0x0F):
        w(d, 0x6040, 0, cw, 2)
    for k in range(1, 50):
        w(d, 0x607A, 0, 10 * k, 4)
        d.step(1)
    assert d.internal_position == -490
    assert d.value(0x6062) == 490 and 0 < d.value(0x6064) <= 490  # the sample of §3.2.2 lags one cycle
    assert d.value(0x60F4) == d.value(0x6062) - d.value(0x6064) and d.value(0x606C) > 0


def test_n25_hdt_polarity_reverses_the_targets():
    manual_says(HDT_TEXT, 3418, "if the bit is equal to 1, the value’s sign is reversed.")
    d = in_mode("hdt", 9)  # CSV
    w(d, 0x607E, 0, 0x40, 1)  # velocity polarity
    enable(d)
    w(d, 0x60FF, 0, 1000, 4)
    d.step(10)
    assert d.internal_velocity < 0 and r(d, 0x606C, 0, True) < 0  # HDT: the target only
    h = at("hdt", PRE)
    w(h, 0x6060, 0, 8, 1)  # CSP
    h.request_state(SAFE)
    h.request_state(OP)
    w(h, 0x607E, 0, 0x80, 1)
    enable(h)
    w(h, 0x607A, 0, 5000, 4)
    h.step(1)
    assert h.value(0x6064) == -5000


# N14 N15 (HDT profile position on the fly) -------------------------------------------------------------------
def test_n14_hdt_new_profile_velocity_applies_during_the_move():
    manual_says(HDT_TEXT, 4164, "speed instead (profile velocity - index 6081h) is immediately adjusted to the set value.")
    d = _pp("hdt", 1000, 10000)
    w(d, 0x607A, 0, 10_000_000, 4)
    w(d, 0x6040, 0, 0x3F, 2)
    d.step(300)  # at cruise (the S-curve's jerk limit 2011h included)
    cruise = r(d, 0x606C, 0, True)
    w(d, 0x6081, 0, 2000, 4)
    d.step(300)
    assert cruise > 0 and r(d, 0x606C, 0, True) == 2 * cruise


def test_n15_hdt_ramps_changed_during_a_move_wait_for_standstill():
    manual_says(HDT_TEXT, 4163, "are adjusted when the motor is standstill and a new positioning is starting.")
    d = _pp("hdt", 1000, 10000)  # 1000 rpm in 0.1 s = 50 cycles
    w(d, 0x6086, 0, 0, 2)  # linear ramp (trapezoid)
    w(d, 0x607A, 0, 10_000_000, 4)
    w(d, 0x6040, 0, 0x3F, 2)
    d.step(10)
    w(d, 0x6083, 0, 100, 4)  # a ramp 100 times flatter
    w(d, 0x6084, 0, 100, 4)
    w(d, 0x6040, 0, 0x2F, 2)
    w(d, 0x607A, 0, 20_000_000, 4)
    w(d, 0x6040, 0, 0x3F, 2)  # a new set-point taken while moving: the ramps of the running positioning
    d.step(45)
    cruise = r(d, 0x606C, 0, True)
    d.step(10)
    assert r(d, 0x606C, 0, True) == cruise  # at full speed after 55 cycles, as the old ramp runs


def test_n17_hdt_201a_bit1_torque_limit_makes_the_profile_adapt():
    manual_says(HDT_TEXT, 3816, "1 Torque limit enabled: when the Drive torque reaches the limit (because there is an "
                                "obstacle on")
    rev = 65536
    d = at("hdt", OP)
    w(d, 0x6060, 0, 1, 1)
    for index, value, size in ((0x6086, 0, 2), (0x6081, 600, 4), (0x6083, 6000, 4), (0x6084, 6000, 4),
                               (0x201A, 0x2, 1)):
        w(d, index, 0, value, size)
    enable(d)
    d.set_obstacle(3 * rev)
    w(d, 0x607A, 0, 10 * rev, 4)
    w(d, 0x6040, 0, 0x1F, 2)
    d.step(1000)
    assert r(d, 0x6064, signed=True) == 3 * rev and r(d, 0x60F4, signed=True) == 0  # adapted, no error
    assert d.cia402_state is State.OPERATION_ENABLED
    d.set_obstacle(None)
    d.step(1000)
    assert r(d, 0x6064, signed=True) == 10 * rev  # resumed to the target


def test_ct_quick_stop_in_vl_ramps_along_604a():
    manual_says(CT_TEXT, 2107, "This object is used to configure the delta speed and delta time of the slope of the "
                               "deceleration ramp for quick stop.")
    d = at("controltechniques", OP)
    w(d, 0x6048, 2, 0, 2)  # at speed at once
    w(d, 0x604A, 1, 1000, 4)  # 1000 rpm per 1 s
    w(d, 0x604A, 2, 1, 2)
    w(d, 0x605A, 0, 2, 2)
    enable(d)
    w(d, 0x6042, 0, 1000, 2)
    d.step(1)
    assert r(d, 0x6044, 0, True) == 1000
    w(d, 0x6040, 0, 0x0B, 2)  # quick stop
    cycles_per_s = int(1 / d.cycle_time())
    d.step(cycles_per_s // 2)
    assert d.cia402_state is State.QUICK_STOP and r(d, 0x6044, 0, True) == 500
    d.step(cycles_per_s // 2)
    assert d.cia402_state is State.SWITCH_ON_DISABLED


def test_n24_technosoft_csv_acceleration_limit_2086():
    manual_says(TS_TEXT, 8817, "During CSV mode, the maximum acceleration will be the one defined in object 6083_h.")
    d = in_mode("technosoft-ipos", 9)
    enable(d)
    w(d, 0x2086, 0, 1, 2)
    w(d, 0x6083, 0, 1 << 16, 4)  # 1 increment/sample²
    w(d, 0x60FF, 0, 10 << 16, 4)
    d.step(5)
    assert r(d, 0x606C, 0, True) == 5 << 16
    d.step(10)
    assert r(d, 0x606C, 0, True) == 10 << 16


def test_n20_technosoft_pp_bit10_waits_for_the_position_window_time():
    manual_says(TS_TEXT, 6125, "If the *position actual value* is within the *position window* for a time period "
                               "defined inside the *position window time* object, this *target position* is regarded "
                               "as reached.")
    d = _pp("technosoft-ipos", 10 << 16, 1 << 16)
    w(d, 0x6067, 0, 5, 4)
    w(d, 0x6068, 0, 20, 2)  # 20 samples of 1 ms
    w(d, 0x607A, 0, 1000, 4)
    w(d, 0x6040, 0, 0x1F, 2)
    n = 0
    while d.internal_position != 1000:
        d.step(1)
        n += 1
        assert n < 1000
    assert not r(d, 0x6041) & 0x0400  # at the target, not yet 20 ms in the window
    d.step(19)
    assert not r(d, 0x6041) & 0x0400
    d.step(1)
    assert r(d, 0x6041) & 0x0400
