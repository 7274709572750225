"""Commissioning through the pysoem target: a fake pysoem module (pysoem's API surface) whose slaves are
simulated drives, so the runner, the pysoem adapter and the drive are exercised together, faults included."""

from __future__ import annotations

import types

import pytest

from ecattool.commission import commission
from ecattool.commission.runner import open_target
from ecattool.errors import SdoAbort, SdoTimeout, StateChangeError
from ecattool.od.model import EcState
from ecattool.project.lint import lint_project
from ecattool.target.pysoem import PysoemTarget
from tests.project_helpers import SAMPLES, sample
from tests.test_target_pysoem import SdoError, WkcError

CODES = {EcState.INIT: 1, EcState.PREOP: 2, EcState.BOOT: 3, EcState.SAFEOP: 4, EcState.OP: 8}
STATES = {v: k for k, v in CODES.items()}


class SoemSlave:
    """pysoem.CdefSlave as far as ecattool uses it, backed by a simulated drive."""

    def __init__(self, position, drive):
        self.position, self.drive = position, drive
        ident = drive.identity()
        self.man, self.id, self.rev = ident.vendor_id, ident.product_code, ident.revision
        self.state = CODES[drive.state()]
        self.al_status = 0
        self.output, self.input = b"", b""
        self.dc = None

    def _call(self, fn, index, subindex, *args):
        try:
            return fn(index, subindex, *args)
        except SdoAbort as exc:
            raise SdoError(self.position, index, subindex, exc.code, str(exc)) from None
        except SdoTimeout:
            raise WkcError() from None

    def sdo_read(self, index, subindex, ca=False):
        return self._call(self.drive.sdo_upload, index, subindex, ca)

    def sdo_write(self, index, subindex, data, ca=False):
        self._call(self.drive.sdo_download, index, subindex, data, ca)

    def write_state(self):
        self.requested = self.state

    def state_check(self, expected, timeout_us):
        try:
            self.drive.request_state(STATES[self.requested])
            self.al_status = 0
        except StateChangeError as exc:
            self.al_status = exc.al_status
            return CODES[self.drive.state()] | 0x10
        self.state = CODES[self.drive.state()]
        return self.state

    def dc_sync(self, act, sync0_cycle_time):
        self.dc = (act, sync0_cycle_time)
        self.drive.configure_dc(0x0300 if act else 0, sync0_cycle_time)


class SoemMaster:
    def __init__(self, drives):
        self.drives = drives
        self.slaves: list[SoemSlave] = []
        self.opened = self.closed = False

    def open(self, ifname):
        self.opened = ifname

    def config_init(self):
        self.slaves = [SoemSlave(i, d) for i, d in enumerate(self.drives)]
        return len(self.slaves)

    def config_map(self):
        return sum(len(s.output) for s in self.slaves)

    def read_state(self):
        for s in self.slaves:
            s.state = CODES[s.drive.state()]

    def send_processdata(self):
        for s in self.slaves:
            s.input = s.drive.exchange(s.output) if s.drive.state() in (EcState.SAFEOP, EcState.OP) else s.input

    def receive_processdata(self, timeout):
        return 1

    def close(self):
        self.closed = True


def pysoem_on(drives):
    master = SoemMaster(drives)
    module = types.SimpleNamespace(Master=lambda: master, SdoError=SdoError, WkcError=WkcError)
    return PysoemTarget("eth-test", pysoem_module=module), master


def sim_drives(path):
    return open_target("sim", lint_project(path).drives)[0].slaves()


@pytest.mark.parametrize("name", SAMPLES)
def test_samples_commission_through_pysoem(name):
    path = sample(name)
    drives = sim_drives(path)
    target, master = pysoem_on(drives)
    report = commission(path, target=target)
    assert report.ok, report.drives[0].error
    assert master.opened == "eth-test" and not master.closed  # the caller's target stays open
    assert drives[0].state() is EcState.OP
    expected = {"technosoft_ipos": 1200, "hdt": 81920, "controltechniques": 98304, "generic_esi": 10000}[name]
    assert drives[0].internal_position == expected


def test_dc_reaches_the_slave_through_pysoem():
    path = sample("controltechniques")
    drives = sim_drives(path)
    target, master = pysoem_on(drives)
    assert commission(path, target=target).ok
    assert master.slaves[0].dc == (True, 1_000_000)


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
