"""Issue 33 item 2/N7 on the plant: profile torque (4) and cyclic synchronous torque (10) drive the plant's motor,
so the project's inertia, friction, a load torque and the torque limits 6072h/60E0h/60E1h act. The done-when of
issue 33: CST acceleration = (torque - friction) / inertia on the real plant."""

from __future__ import annotations

import math

import pytest

from ecattool.sim.cia402 import State
from ecattool.sim.drive.plant import PlantParams
from tests.sim.sim_helpers import OP, PRE, SAFE, at, r, w
from tests.profiles.test_families_manuals import CT_TEXT, TS_TEXT, manual_says

#: a motor of 1e-4 kg·m² with as much load, 0.1 N·m of Coulomb friction and no viscous friction
PLANT = PlantParams(motor_inertia=1e-4, load_inertia=1e-4, coulomb=0.1, viscous=0.0, rated_torque=1.27,
                    peak_torque=3.8)


def _cst(plant: PlantParams | None = PLANT, mode: int = 10):
    d = at("technosoft-ipos", PRE, plant=plant)
    w(d, 0x6060, 0, mode, 1)
    d.request_state(SAFE)
    d.request_state(OP)
    for cw in (0x06, 0x07, 0x0F):
        w(d, 0x6040, 0, cw, 2)
    return d


def _rad_per_s(d, increments_per_s: float) -> float:
    return increments_per_s * 2 * math.pi / d.plant.counts_per_rev


def test_cst_acceleration_is_torque_minus_friction_over_inertia():
    manual_says(CT_TEXT, 2233, "The value of this object is given per thousand of rated torque.")
    d = _cst()
    assert d.cia402_state is State.OPERATION_ENABLED and d.plant is not None
    dt = float(d.cycle_time())
    w(d, 0x6071, 0, 500, 2)  # 50 % of the rated 1.27 N·m
    n = 200
    d.step(n)
    torque = 0.5 * 1.27
    alpha = (torque - PLANT.coulomb) / PLANT.inertia  # rad/s²
    assert _rad_per_s(d, d.plant.velocity) == pytest.approx(alpha * n * dt, rel=1e-9)
    assert r(d, 0x6077, signed=True) == 500  # the torque the motor makes, per mille of rated
    # the position is the plant's: x = alpha t² / 2 (in increments, as 6063h counts them)
    expected = alpha * (n * dt) ** 2 / 2 * d.plant.counts_per_rev / (2 * math.pi)
    assert d.internal_position == pytest.approx(expected, abs=2)
    # the ideal plant's free inertia knows no friction: another speed
    ideal = _cst(plant="ideal")
    w(ideal, 0x6071, 0, 500, 2)
    ideal.step(n)
    assert ideal.internal_velocity != d.internal_velocity


def test_cst_torque_below_the_friction_does_not_move():
    d = _cst()
    w(d, 0x6071, 0, 50, 2)  # 0.0635 N·m < 0.1 N·m static friction
    d.step(100)
    assert d.plant.velocity == 0 and d.internal_position == 0


@pytest.mark.parametrize("index", [0x6072, 0x60E0])
def test_6072h_and_60e0h_limit_the_cst_torque_on_the_plant(index: int):
    """A generic ESI drive with the torque limits (Inovance SV660N): 6071h = 90 % made at the 20 % 6072h max
    torque (or 60E0h positive torque limit) allows; the plant accelerates with what the limit leaves."""
    from ecattool.sim.drive import Drive as SimDrive
    from tests.conftest import ROOT

    d = SimDrive.from_esi(ROOT / "samples" / "generic_esi" / "inovance_SV660_EOE_1Axis_V9.12.xml", "InoSV660N",
                          plant=PLANT)
    for s in (PRE, SAFE, OP):
        d.request_state(s)
    assert 10 in d.rules.supported_modes and (index, 0) in d._entries
    w(d, 0x6060, 0, 10, 1)
    w(d, index, 0, 200, 2)  # 20 % of rated
    for cw in (0x06, 0x07, 0x0F):
        w(d, 0x6040, 0, cw, 2)
    w(d, 0x6071, 0, 900, 2)
    dt = float(d.cycle_time())
    d.step(100)
    alpha = (0.2 * 1.27 - PLANT.coulomb) / PLANT.inertia
    assert _rad_per_s(d, d.plant.velocity) == pytest.approx(alpha * 100 * dt, rel=1e-9)
    assert r(d, 0x6077, signed=True) == 200


def test_a_load_torque_works_against_the_cst_torque():
    d = _cst()
    d.set_load_torque(0.3)
    w(d, 0x6071, 0, 500, 2)
    dt = float(d.cycle_time())
    d.step(100)
    alpha = (0.5 * 1.27 - 0.3 - PLANT.coulomb) / PLANT.inertia
    assert _rad_per_s(d, d.plant.velocity) == pytest.approx(alpha * 100 * dt, rel=1e-9)


def test_technosoft_6080h_caps_the_speed_in_cst():
    manual_says(TS_TEXT, 9075, "This object indicates the configured maximal allowed speed of the motor, taken from "
                               "the motor specifications, when the mode of operation is CST or External Torque value.")
    d = _cst()
    limit = 2 * 65536  # 2 counts per sample (velocity units)
    w(d, 0x6080, 0, limit, 4)
    w(d, 0x6071, 0, 500, 2)
    d.step(2000)
    expected = d.units.increments_per_second(d.units.velocity_to_internal(limit))
    assert d.plant.velocity == pytest.approx(float(expected), rel=1e-12)
    d.step(10)
    assert d.plant.velocity == pytest.approx(float(expected), rel=1e-12)


def test_a_halt_in_cst_stops_the_axis_from_its_speed():
    d = _cst()
    w(d, 0x6071, 0, 500, 2)
    d.step(100)
    speed = d.plant.velocity
    assert speed > 0
    w(d, 0x6040, 0, 0x10F, 2)  # halt
    d.step(2000)
    assert abs(d.plant.velocity) < 1e-6 * speed and d.cia402_state is State.OPERATION_ENABLED
