"""Commissioning through the pysoem target: a fake pysoem module (pysoem's API surface) whose slaves are
simulated drives (tests/target/fake_pysoem.py), so the runner, the pysoem adapter and the drive are exercised
together, faults included."""

from __future__ import annotations


import pytest

from ecattool.commission import commission
from ecattool.commission.runner import open_target
from ecattool.od.model import EcState
from ecattool.project.machine import load_machine
from ecattool.target.pysoem import PysoemTarget
from tests.project.project_helpers import SAMPLES, copy_sample, sample
from tests.target.fake_pysoem import VirtualClock, make_module


def pysoem_on(drives):
    clock = VirtualClock()
    target = PysoemTarget("eth-test", pysoem_module=make_module(drives), clock=clock.now, sleep=clock.sleep,
                          keep_cycling=False)
    target.master.clock = clock
    return target, target.master


def sim_drives(path):
    return open_target("sim", load_machine(path).slaves)[0].slaves()


@pytest.mark.parametrize("name", SAMPLES)
def test_samples_commission_through_pysoem(name):
    path = sample(name)
    drives = sim_drives(path)
    target, master = pysoem_on(drives)
    report = commission(path, target=target)
    assert report.ok, report.drives[0].error
    assert master.opened == "eth-test" and master.context_initialized  # the caller's target stays open
    assert drives[0].state() is EcState.OP
    expected = {"technosoft_ipos": 1200, "hdt": 81920, "controltechniques": 98304, "generic_esi": 10000}[name]
    assert drives[0].internal_position == expected


def test_dc_reaches_the_slave_through_pysoem():
    path = sample("controltechniques")
    drives = sim_drives(path)
    target, master = pysoem_on(drives)
    assert commission(path, target=target).ok
    assert master.dc_configured and master.slaves[0].dc == (0x03, 1_000_000, 0, None)
    # one frame per SYNC0 cycle (1 ms): a CSP set-point is never skipped (times on the virtual clock)
    gaps = [b - a for a, b in zip(master.sent_at, master.sent_at[1:])]
    assert len(gaps) > 100 and min(gaps) >= 0.001 - 1e-12


def test_abort_through_pysoem_keeps_its_code():
    path = sample("hdt")
    drives = sim_drives(path)
    drives[0].faults.abort_sdo(4, 0x06090030)
    target, _ = pysoem_on(drives)
    (dr,) = commission(path, target=target).drives
    assert not dr.ok and dr.steps[-1].name == "write 0x6093:01" and dr.steps[-1].abort_code == 0x06090030
    assert dr.final_state == "PREOP"


def test_refused_state_through_pysoem_keeps_the_al_status():
    path = sample("technosoft_ipos")
    drives = sim_drives(path)
    drives[0].faults.refuse_state(EcState.SAFEOP, 0x001D)
    target, _ = pysoem_on(drives)
    (dr,) = commission(path, target=target).drives
    assert dr.steps[-1].name == "state SAFEOP" and dr.steps[-1].al_status == 0x001D and not dr.ok
    target2, _ = pysoem_on(drives)
    assert commission(path, target=target2).ok  # converges


HDT_TABLE = """  - name: table
    position: 0
    device: {profile: hdt, product: tomcat}
    scaling:
      feedback: {counts_per_rev: 65536}
      gear: "5:1"
      transmission: {type: rotary}
      units: {position: deg, velocity: deg/s, acceleration: deg/s^2}
    parameters:
      - {object: "0x6081:00", value: 90}
      - {object: "0x6083:00", value: 360}
    move: {distance: 90}
    disable_rules:
      - {rule: PDO021, reason: "HDT's default RxPDOs carry 6081h/6083h"}
"""


def test_two_drives_share_one_io_map(tmp_path):
    """SOEM lays out one IO map for the bus from the PDO assignments the slaves report: it must be read after
    every drive's mapping was written (the Technosoft drive at position 1 changes its mapping in PRE-OP)."""
    path = copy_sample("technosoft_ipos", tmp_path)
    text = path.read_text().replace("  - name: z_axis\n", HDT_TABLE + "  - name: z_axis\n    position: 1\n")
    path.write_text(text)
    drives = sim_drives(path)
    target, master = pysoem_on(drives)
    report = commission(path, target=target)
    assert [d.ok for d in report.drives] == [True, True], [d.error for d in report.drives]
    assert master.map_calls == 1
    assert [s._obytes for s in master.slaves][1] == 7  # 1600h (controlword, mode) + 1601h (target position)
    assert drives[0].internal_position == 81920 and drives[1].internal_position == 1200
