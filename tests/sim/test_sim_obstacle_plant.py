"""Issue 33 item 5: an obstacle blocks the plant's load, not the demand. The demand (the master's CSP set-points,
the profile, the interpolator) runs on, the actual position stands at the obstacle, the following error grows
through the plant, and supervision faults the drive with 8611h in every position mode, not only PP."""

from __future__ import annotations

from ecattool.sim.cia402 import State
from tests.sim.sim_helpers import OP, SAFE, at, r, w
from tests.profiles.test_families_manuals import HDT_TEXT, manual_says
from tests.sim.test_sim_stop_reactions import REV

OBSTACLE = 2000


def _hdt(mode: int):
    d = at("hdt", OP, plant=None)
    assert d.plant is not None
    w(d, 0x6060, 0, mode, 1)
    w(d, 0x6065, 0, 500, 4)
    w(d, 0x6066, 0, 20, 2)  # ms
    for cw in (0x06, 0x07, 0x0F):
        w(d, 0x6040, 0, cw, 2)
    d.set_obstacle(OBSTACLE)
    return d


def _run(d, cycles: int, target=None) -> tuple[int, int]:
    """Cycles until the drive leaves OPERATION ENABLED (bounded), and the largest actual position seen."""
    top = 0
    for k in range(1, cycles + 1):
        if target is not None:
            w(d, 0x607A, 0, target(k), 4)
        d.step(1)
        if d.cia402_state is not State.OPERATION_ENABLED:
            return k, top
        top = max(top, r(d, 0x6064, signed=True))
    return cycles, top


def test_csp_against_an_obstacle_lags_through_the_plant_and_faults():
    manual_says(HDT_TEXT, 3725, "error window\" (index 6065h). If this period is surpassed the bit 13 of the "
                                "statusword is set to 1 and the Drive")
    d = _hdt(8)
    n, top = _run(d, 500, lambda k: 20 * k)  # 10,000 counts/s: the master's set-points run on past 2000
    assert n < 500 and d.cia402_state in (State.FAULT, State.FAULT_REACTION)
    assert r(d, 0x603F) == 0x8611
    assert top == OBSTACLE  # the load stood at the obstacle
    assert r(d, 0x6062, signed=True) > OBSTACLE + 500  # the demand ran on past the window


def test_pp_on_the_plant_runs_its_profile_on_and_faults():
    d = _hdt(1)
    for index, value, size in ((0x6081, 600, 4), (0x6083, 6000, 4), (0x6084, 6000, 4)):
        w(d, index, 0, value, size)
    w(d, 0x607A, 0, 10 * REV, 4)
    w(d, 0x6040, 0, 0x1F, 2)
    lag = []
    for _ in range(400):
        d.step(1)
        if d.cia402_state is not State.OPERATION_ENABLED:
            break
        lag.append(r(d, 0x60F4, signed=True))
        assert r(d, 0x6064, signed=True) <= OBSTACLE
    assert d.cia402_state is not State.OPERATION_ENABLED and r(d, 0x603F) == 0x8611
    assert lag[-1] > 500 and d.cia.obstacle is not None and not d.cia.following_error  # the plant's lag


def test_taking_the_obstacle_away_lets_the_loop_pull_the_load_to_the_demand():
    d = _hdt(8)
    w(d, 0x6065, 0, 0xFFFFFFFF, 4)  # supervision off
    _run(d, 200, lambda k: min(20 * k, 3000))
    assert r(d, 0x6064, signed=True) == OBSTACLE and r(d, 0x6062, signed=True) == 3000
    d.set_obstacle(None)
    d.step(1)
    assert OBSTACLE < r(d, 0x6064, signed=True) < 3000  # the loop's dynamics, not a jump
    d.step(200)
    assert r(d, 0x6064, signed=True) == 3000 and r(d, 0x60F4, signed=True) == 0


def test_interpolated_position_against_an_obstacle_faults():
    d = at("hdt", SAFE, plant=None)
    d.request_state(OP)
    w(d, 0x6060, 0, 7, 1)
    w(d, 0x6065, 0, 500, 4)
    w(d, 0x6066, 0, 20, 2)
    for cw in (0x06, 0x07, 0x0F, 0x1F):  # bit 4: enable ip mode (HDT §4.09.1)
        w(d, 0x6040, 0, cw, 2)
    d.set_obstacle(OBSTACLE)
    n = 0
    for k in range(1, 500):
        w(d, 0x60C1, 1, 20 * k, 4)
        d.step(1)
        n = k
        if d.cia402_state is not State.OPERATION_ENABLED:
            break
        assert r(d, 0x6064, signed=True) <= OBSTACLE
    assert n < 499 and r(d, 0x603F) == 0x8611


def test_hdt_torque_limited_profile_still_stops_at_the_obstacle_on_the_plant():
    manual_says(HDT_TEXT, 4194, "In this mode the position error may not be detected since the position profile "
                                "adapts to the")
    d = _hdt(1)
    for index, value, size in ((0x6086, -1, 2), (0x6081, 600, 4), (0x6083, 6000, 4), (0x6084, 6000, 4)):
        w(d, index, 0, value, size)
    w(d, 0x607A, 0, 10 * REV, 4)
    w(d, 0x6040, 0, 0x1F, 2)
    d.step(1000)
    assert d.cia402_state is State.OPERATION_ENABLED
    assert r(d, 0x6064, signed=True) == OBSTACLE and abs(r(d, 0x60F4, signed=True)) <= 1
