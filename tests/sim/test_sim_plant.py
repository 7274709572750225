"""Issue 33: the drive on a physical plant. The plant's responses against their closed forms, the plant on by
default between demand and actual values, following-error supervision in CSP, the torque and the delay."""

from __future__ import annotations

import math

import pytest

from ecattool.sim import Drive
from ecattool.sim.cia402 import State
from ecattool.sim.drive.plant import Plant, PlantParams, reflected_inertia
from tests.sim.sim_helpers import OP, PRE, SAFE, at, r, w
from tests.conftest import ROOT

CPR = 65536.0
#: a stiff, unsaturated plant: the linear loop alone
LINEAR = PlantParams(peak_torque=1e6, max_speed=1e9, coulomb=0.0, viscous=0.0, velocity_feedforward=0.0)


def test_position_loop_step_response_is_the_critically_damped_closed_form():
    """A step of 1000 increments at zeta = 1 (KickCAT's wn = 80 rad/s): the axis starts 1000 behind a demand that
    stands, x(t) = 1000 (1 - (1 + wn t) e^(-wn t))."""
    wn, dt = 80.0, 0.001
    plant = Plant(LINEAR.with_(position_bandwidth=wn, damping=1.0), CPR, dt)
    plant.error = -1000.0
    for k in range(1, 200):
        plant.follow_position(0.0)
        t = k * dt
        expected = -1000.0 * (1 + wn * t) * math.exp(-wn * t)
        assert plant.error == pytest.approx(expected, abs=1e-6), k


def test_underdamped_step_overshoots_as_the_closed_form_says():
    """zeta = 0.5: overshoot e^(-pi zeta / sqrt(1 - zeta²)) = 16.3 % at t = pi / (wn sqrt(1 - zeta²))."""
    wn, zeta, dt = 100.0, 0.5, 0.0001
    plant = Plant(LINEAR.with_(position_bandwidth=wn, damping=zeta), CPR, dt)
    plant.error = -1000.0
    peak = -1000.0
    for _ in range(2000):
        plant.follow_position(0.0)
        peak = max(peak, plant.error)
    assert peak == pytest.approx(1000.0 * math.exp(-math.pi * zeta / math.sqrt(1 - zeta * zeta)), rel=1e-3)


@pytest.mark.parametrize("zeta,wn", [(1.0, 80.0), (0.7, 200.0), (1.5, 50.0)])
def test_steady_following_error_on_a_ramp_is_2_zeta_v_over_wn(zeta: float, wn: float):
    """Issue 33 done-when: the steady following error of the second-order loop on a ramp is 2 zeta v / wn."""
    dt, v = 0.001, 100_000.0  # increments/s
    plant = Plant(LINEAR.with_(position_bandwidth=wn, damping=zeta), CPR, dt)
    for _ in range(3000):
        plant.follow_position(v * dt)
    assert -plant.error == pytest.approx(2 * zeta * v / wn, rel=1e-6)
    assert plant.velocity == pytest.approx(v, rel=1e-9)


def test_velocity_feedforward_takes_the_steady_ramp_error_away():
    dt, v = 0.001, 100_000.0
    plant = Plant(LINEAR.with_(velocity_feedforward=1.0), CPR, dt)
    for _ in range(3000):
        plant.follow_position(v * dt)
    assert abs(plant.error) < 1e-6


def test_torque_accelerates_the_inertia_against_friction():
    """Issue 33 done-when: acceleration = (torque - friction) / inertia (Coulomb 0.05 N·m, no viscous)."""
    params = PlantParams(motor_inertia=1e-4, load_inertia=1e-4, coulomb=0.05, viscous=0.0, peak_torque=10.0)
    dt = 0.001
    plant = Plant(params, CPR, dt)
    plant.apply_torque(0.5)  # from standstill: static friction is overcome (0.5 > 0.05)
    plant.apply_torque(0.5)
    accel_inc = (0.5 - 0.05) / 2e-4 * CPR / (2 * math.pi)  # rad/s² -> increments/s²
    assert plant.velocity == pytest.approx(2 * accel_inc * dt, rel=1e-9)
    # below the Coulomb friction the axis at rest does not move
    still = Plant(params, CPR, dt)
    still.apply_torque(0.04)
    assert still.velocity == 0.0


def test_torque_limit_makes_the_axis_lag():
    """A step the loop cannot make within the peak torque: the axis accelerates at (T_peak - friction) / J."""
    params = PlantParams(peak_torque=0.3, coulomb=0.0, viscous=0.0, velocity_feedforward=0.0)
    dt = 0.001
    plant = Plant(params, CPR, dt)
    plant.error = -1_000_000.0
    plant.follow_position(0.0)
    assert plant.torque == pytest.approx(0.3)
    assert plant.velocity == pytest.approx(0.3 / params.inertia * CPR / (2 * math.pi) * dt, rel=1e-9)


def test_reflected_inertia_through_a_gear_and_a_screw():
    """A 10 kg slide on a 5 mm lead screw behind a 3:1 gear: m (lead / 2 pi)² / 3² = 7.04e-6 kg·m²."""
    j = reflected_inertia(gear_ratio=3.0, load_mass=10.0, travel_per_load_rev_m=0.005)
    assert j == pytest.approx(10 * (0.005 / (2 * math.pi)) ** 2 / 9)
    assert reflected_inertia(gear_ratio=5.0, load_inertia=0.25) == pytest.approx(0.01)


def _csp(drive: Drive) -> Drive:
    w(drive, 0x6060, 0, 8, 1)
    for cw in (0x06, 0x07, 0x0F):
        w(drive, 0x6040, 0, cw, 2)
    return drive


def test_the_plant_is_on_by_default_and_a_csp_step_lags():
    """Issue 33, N3: with the plant a CSP step of 1000 counts is not reached in the same cycle (CT 2550: one
    interpolation period of delay; HDT here, no delay, the loop's lag)."""
    d = _csp(at("hdt", OP, plant=None))
    assert d.plant is not None and Drive.from_profile("hdt").plant is not None  # the default
    ideal = _csp(at("hdt", OP))
    assert ideal.plant is None
    for drive in (d, ideal):
        w(drive, 0x607A, 0, 1000, 4)
        drive.step(1)
    assert r(ideal, 0x6064, signed=True) == 1000
    assert 0 < r(d, 0x6064, signed=True) < 1000
    assert r(d, 0x60F4, signed=True) == 1000 - r(d, 0x6064, signed=True)
    d.step(100)
    assert r(d, 0x6064, signed=True) == 1000 and r(d, 0x60F4, signed=True) == 0


def test_csp_step_beyond_the_following_error_window_faults_8611():
    """Issue 33, N4: a CSP jump of 1,000,000 counts with 6065h = 1 count faults with 8611h and bit 13 instead of
    reading 606Ch = 500,000,000 counts/s (HDT §4.06.5, seeds/003_8679b1dde0e37523.txt line 3725)."""
    d = at("hdt", OP, plant=None)
    assert d.plant is not None
    _csp(d)
    w(d, 0x6065, 0, 1, 4)
    w(d, 0x6066, 0, 1, 2)
    w(d, 0x607A, 0, 1_000_000, 4)
    d.step(1)
    assert d.cia402_state in (State.FAULT, State.FAULT_REACTION)
    assert any(e.code == 0x8611 for e in d.emergencies)
    assert r(d, 0x606C, signed=True) < 500_000_000
    # and the ideal plant runs on, as before (the exact tracker)
    ideal = _csp(at("hdt", OP))
    w(ideal, 0x6065, 0, 1, 4)
    w(ideal, 0x6066, 0, 1, 2)
    w(ideal, 0x607A, 0, 1_000_000, 4)
    ideal.step(1)
    assert ideal.cia402_state is State.OPERATION_ENABLED


def test_csp_ramp_reports_a_following_error_in_60f4h():
    """Issue 33, N4: a CSP ramp reports its lag in 60F4h (the bare loop, 2 zeta v / wn)."""
    d = _csp(at("hdt", OP, plant=PlantParams(velocity_feedforward=0.0, position_bandwidth=100.0)))
    w(d, 0x6065, 0, 0xFFFFFFFF, 4)
    v_per_cycle = 200  # counts per 2 ms cycle = 100,000 counts/s
    for k in range(1, 400):
        w(d, 0x607A, 0, k * v_per_cycle, 4)
        d.step(1)
    assert r(d, 0x60F4, signed=True) == pytest.approx(2 * 1.0 * 100_000 / 100.0, abs=1)
    assert r(d, 0x6062, signed=True) - r(d, 0x6064, signed=True) == pytest.approx(2000, abs=1)


def test_hdt_caps_the_following_error_window_at_32768_pulses():
    """HDT §4.06.5 (seeds/003_8679b1dde0e37523.txt line 3706): the window is at most 32,768 pulses; 6065h =
    100,000 still faults at a lag of 40,000."""
    d = _csp(at("hdt", OP, plant=PlantParams(velocity_feedforward=0.0, position_bandwidth=50.0)))
    w(d, 0x6065, 0, 100_000, 4)
    w(d, 0x6066, 0, 1, 2)
    for k in range(1, 400):  # 1,000,000 counts/s: steady lag 2 v / wn = 40,000
        w(d, 0x607A, 0, k * 2000, 4)
        d.step(1)
        if d.cia402_state is not State.OPERATION_ENABLED:
            break
    assert any(e.code == 0x8611 for e in d.emergencies)


def test_a_script_sets_the_plant_and_the_inputs():
    """Issue 33 item 6: ``sim run`` scripts set plant parameters, a load torque and limit switches."""
    from ecattool.errors import InputError, Location
    from ecattool.sim.script import parse_steps, run_script

    d = at("hdt", OP, plant=None)
    steps = [{"plant": {"position_bandwidth": 50, "velocity_feedforward": 0}}, {"inputs": {"load_torque": 0.5}},
             {"inputs": {"limit_positive": True}}, {"cycles": 1}]
    parsed, locs = parse_steps(steps, [Location("s.yaml", i + 1) for i in range(len(steps))])
    transcript = run_script(d, parsed, locs)
    assert transcript.ok
    assert d.plant is not None and d.plant.params.position_bandwidth == 50 and d.plant.load_torque == 0.5
    assert d.limit_switches == (False, True)
    with pytest.raises(InputError, match="unknown parameter 'bandwith'"):
        run_script(d, [{"plant": {"bandwith": 5}}], [Location("s.yaml", 1)])
    run_script(d, [{"plant": "ideal"}], [Location("s.yaml", 1)])
    assert d.plant is None


def _ts_pp(writes: tuple[tuple[int, int, int], ...] = ()) -> Drive:
    d = at("technosoft-ipos", OP)
    w(d, 0x6060, 0, 1, 1)
    w(d, 0x6081, 0, 10 * 65536, 4)  # 10 counts per sample
    w(d, 0x6083, 0, 65536, 4)  # 1 count per sample²
    w(d, 0x6085, 0, 2 * 65536, 4)  # quick-stop deceleration: 2 counts per sample²
    for index, sub, value in writes:
        w(d, index, sub, value, 4)
    for cw in (0x06, 0x07, 0x0F):
        w(d, 0x6040, 0, cw, 2)
    return d


def _go(d: Drive, target: int) -> None:
    w(d, 0x607A, 0, target, 4)
    w(d, 0x6040, 0, 0x1F, 2)
    w(d, 0x6040, 0, 0x0F, 2)


def test_a_limit_switch_stops_the_move_with_6085h_and_holds():
    """Issue 33, N11: Technosoft §4.3.1 (seeds/000_a0ab57c0bda88c2c.txt line 2235): a limit switch during a motion
    stops the axis with 6085h, the drive stays OPERATION ENABLED and takes only a motion away from the switch."""
    d = _ts_pp()
    _go(d, 100_000)
    d.step(20)  # at 10 counts/sample
    assert d.internal_velocity == 10 * 65536
    d.set_limit_switches(positive=True)
    d.step(2)
    assert d.internal_velocity == 6 * 65536  # 2 counts/sample² down
    d.step(10)
    assert d.internal_velocity == 0 and d.cia402_state is State.OPERATION_ENABLED
    stopped = d.internal_position
    d.step(50)
    assert d.internal_position == stopped  # held: the set-point beyond the switch is dropped
    _go(d, 100_000)  # still towards the switch: refused
    d.step(10)
    assert d.internal_position == stopped
    _go(d, 0)  # away from it: taken
    d.step(10)
    assert d.internal_position < stopped


def test_software_limits_607dh_stop_the_move():
    """Issue 33, N12: Technosoft §4.3.2 (line 2276): the software limits "work just like the hardware limit
    switches": a move to 10,000 with 607Dh:02 = 5000 stops just beyond 5000 (the 6085h ramp)."""
    d = _ts_pp(((0x607D, 2, 5000),))
    _go(d, 10_000)
    d.step(2000)
    assert 5000 <= d.internal_position < 5000 + 40
    assert d.cia402_state is State.OPERATION_ENABLED


def test_6072h_limits_the_plants_torque():
    """Issue 33 item 3: 6072h max torque (per mille of rated) is the plant's torque limit: a CSP jump the loop
    would make at several times the rated torque is made at 10 % of it, the axis lags behind (Inovance SV660N)."""
    from ecattool.sim.drive import Drive as SimDrive

    esi = ROOT / "samples" / "generic_esi" / "inovance_SV660_EOE_1Axis_V9.12.xml"
    peaks = {}
    for limit in (0, 100):
        d = SimDrive.from_esi(esi, "InoSV660N")
        for s in (PRE, SAFE, OP):
            d.request_state(s)
        assert (0x6072, 0) in d._entries
        w(d, 0x6065, 0, 0xFFFFFFFF, 4)
        w(d, 0x6072, 0, limit, 2)
        _csp(d)
        w(d, 0x607A, 0, 100_000, 4)
        peak = 0
        for _ in range(20):
            d.step(1)
            peak = max(peak, abs(r(d, 0x6077, signed=True)))
        peaks[limit] = (peak, r(d, 0x6064, signed=True))
    assert peaks[100][0] == 100 and peaks[0][0] > 1000
    assert peaks[100][1] < peaks[0][1]


@pytest.mark.parametrize("family,delayed", [("controltechniques", True), ("technosoft-ipos", True), ("hdt", False)])
def test_one_sample_of_delay_where_the_manual_says_so(family: str, delayed: bool):
    """Issue 33 item 2 / N3: Control Techniques CSP inserts one interpolation period (CT 2550); Technosoft samples
    the actual position before the new reference (§3.2.2, TS 1855); HDT's loop answers in the same cycle."""
    d = at(family, SAFE, plant=None)
    d.configure_dc(0x0300, 1_000_000)  # CT 1857: the positioning modes need distributed clocks in OP
    d.request_state(OP)
    d = _csp(d)
    if (0x6065, 0) in d._entries:
        w(d, 0x6065, 0, 0xFFFFFFFF, 4)
    w(d, 0x607A, 0, 1, 4)  # 1 user unit: 1 count (HDT, Technosoft), 65536 counts (Control Techniques)

    def actual() -> float:  # increments, as the drive measures them this cycle
        assert d.plant is not None
        return d.cia.pos_n / d.cia.pos_d + d.plant.reported()[0]

    d.step(1)
    assert (actual() == 0) is delayed, actual()
    d.step(1)
    assert actual() > 0
