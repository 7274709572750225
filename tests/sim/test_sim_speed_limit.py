"""Issue 33 item 3 (N4, N30): the plant's speed limit follows 6080h max motor speed and 607Fh max profile velocity.
A demand faster than the limit leaves the axis behind: the following error grows through the plant, and where the
drive supervises it (6065h/6066h) it faults with 8611h, as a real drive does."""

from __future__ import annotations

from ecattool.sim.cia402 import State
from ecattool.sim.drive import Drive as SimDrive
from tests.sim.sim_helpers import OP, PRE, SAFE, at, r, w
from tests.profiles.test_families_manuals import CT_TEXT, TS_TEXT, manual_says
from tests.conftest import ROOT

INOVANCE = ROOT / "samples" / "generic_esi" / "inovance_SV660_EOE_1Axis_V9.12.xml"


def _csp(d: SimDrive) -> SimDrive:
    w(d, 0x6060, 0, 8, 1)
    for cw in (0x06, 0x07, 0x0F):
        w(d, 0x6040, 0, cw, 2)
    return d


def _ramp(d: SimDrive, per_cycle: int, cycles: int, start: int = 0) -> int:
    """A CSP ramp of ``per_cycle`` user units a cycle (bounded); the cycles run before the drive left OPERATION
    ENABLED."""
    for k in range(1, cycles + 1):
        w(d, 0x607A, 0, start + k * per_cycle, 4)
        d.step(1)
        if d.cia402_state is not State.OPERATION_ENABLED:
            return k
    return cycles


def _inovance() -> SimDrive:
    d = SimDrive.from_esi(INOVANCE, "InoSV660N")
    for s in (PRE, SAFE, OP):
        d.request_state(s)
    w(d, 0x6065, 0, 1000, 4)
    w(d, 0x6066, 0, 10, 2)
    return _csp(d)


def test_607fh_below_the_demand_makes_a_following_error_that_faults():
    """A generic ESI drive (Inovance SV660N): a CSP ramp at 100 counts a cycle follows inside 6065h = 1000; with
    607Fh = half that speed the axis cannot, the error passes the window and the drive faults with 8611h."""
    d = _inovance()
    assert d.plant is not None
    assert _ramp(d, 100, 300) == 300 and abs(r(d, 0x60F4, signed=True)) < 1000
    speed = 100 * 1000  # counts/s at a 1 ms cycle (60C2h default)
    assert d.cycle_time() * 1000 == 1
    d = _inovance()
    w(d, 0x607F, 0, speed // 2, 4)
    n = _ramp(d, 100, 300)
    assert n < 300 and d.cia402_state in (State.FAULT, State.FAULT_REACTION)
    assert r(d, 0x603F) == 0x8611 and any(e.code == 0x8611 for e in d.emergencies)
    # until it faulted the axis ran at the limit, not at the demand
    assert abs(d.plant.velocity) <= speed // 2 + 1e-6


def test_ct_6080h_and_pr_1_06_limit_the_motor():
    manual_says(CT_TEXT, 1808, "It is used to protect the motor and changing the value of this object will also "
                               "change Pr 1.06. The value is given in rotations per minute (rpm).")
    d = at("controltechniques", SAFE, plant=None)
    d.configure_dc(0x0300, 1_000_000)  # CT 1857: CSP needs distributed clocks in OP
    d.request_state(OP)
    _csp(d)
    w(d, 0x6065, 0, 0xFFFFFFFF, 4)
    assert d.plant is not None
    cpr = d.plant.counts_per_rev
    w(d, 0x6080, 0, 1000, 4)
    assert r(d, 0x2001, 6) == 1000  # the link of 7.3.17
    dt = float(d.cycle_time())
    per_cycle = round(2000 * cpr / 60 * dt)  # 2000 rpm in counts a cycle (user units = counts by default)
    _ramp(d, per_cycle, 200)
    assert d.cia402_state is State.OPERATION_ENABLED  # CT has no 6066h: no supervision (7.3.18)
    limit = 1000 * cpr / 60
    assert abs(d.plant.velocity - limit) <= limit * 1e-9
    lag = r(d, 0x60F4, signed=True)
    assert lag > per_cycle * 50  # the demand ran away at twice the speed
    w(d, 0x2001, 6, 3000, 4)  # Pr 1.06 raised: 6080h follows, the axis catches up at up to 3000 rpm
    assert r(d, 0x6080) == 3000
    start = r(d, 0x607A, signed=True)
    _ramp(d, per_cycle, 20, start)
    assert d.plant.velocity > 1.5 * limit


def test_technosoft_6080h_limits_only_in_cst():
    manual_says(TS_TEXT, 9075, "This object indicates the configured maximal allowed speed of the motor, taken from "
                               "the motor specifications, when the mode of operation is CST or External Torque value.")
    lags = []
    for limit in (0, 1):
        d = at("technosoft-ipos", SAFE, plant=None)
        d.configure_dc(0x0300, 1_000_000)
        d.request_state(OP)
        _csp(d)
        w(d, 0x6065, 0, 0xFFFFFFFF, 4)
        assert r(d, 0x6080) == 0  # "activated when setting a value different from zero (default)"
        w(d, 0x6080, 0, limit, 4)  # 1 velocity unit (a count per sample): far below the ramp, yet not in CSP
        _ramp(d, 50, 100)
        assert d.cia402_state is State.OPERATION_ENABLED
        lags.append(r(d, 0x60F4, signed=True))
    assert lags[0] == lags[1] <= 50  # the one sample of §3.2.2, no more
