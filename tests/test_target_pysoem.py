"""The pysoem target, tested against a fake pysoem module that behaves like pysoem's API."""

import types

import pytest

from ecattool.errors import SdoAbort, SdoTimeout, StateChangeError, TargetError
from ecattool.od.model import EcState
from ecattool.target.pysoem import PysoemTarget


class SdoError(Exception):
    def __init__(self, slave_pos, index, subindex, abort_code, desc):
        super().__init__(desc)
        self.abort_code = abort_code


class WkcError(Exception):
    pass


class FakeSlave:
    man, id, rev = 0x1A3, 0x019F418D, 0x0200
    al_status = 0x001D

    def __init__(self):
        self.od = {(0x6060, 0): b"\x01"}
        self.state = 1
        self.refuse = set()
        self.output = b""
        self.input = b"\x27\x02"

    def sdo_read(self, index, subindex, ca=False):
        if (index, subindex) not in self.od:
            raise SdoError(1, index, subindex, 0x06020000, "no object")
        return self.od[(index, subindex)]

    def sdo_write(self, index, subindex, data, ca=False):
        if index == 0x2080:
            raise WkcError()
        if index == 0x6041:
            raise SdoError(1, index, subindex, 0x06010002, "read only")
        self.od[(index, subindex)] = data

    def dc_sync(self, act, cycle):
        self.dc = (act, cycle)

    def write_state(self):
        pass

    def state_check(self, expected, timeout):
        if expected in self.refuse:
            self.state = 0x12  # PREOP + error flag
            return self.state
        self.state = expected
        return expected


class FakeMaster:
    def __init__(self):
        self.slaves = [FakeSlave()]
        self.mapped = False

    def open(self, ifname):
        if ifname == "nope":
            raise ConnectionError("no such device")

    def config_init(self):
        return len(self.slaves)

    def config_map(self):
        self.mapped = True

    def read_state(self):
        return 1

    def send_processdata(self):
        pass

    def receive_processdata(self, timeout):
        return 1

    def close(self):
        pass


fake = types.SimpleNamespace(Master=FakeMaster, SdoError=SdoError, WkcError=WkcError)


def test_sdo_and_aborts():
    t = PysoemTarget("eth0", pysoem_module=fake)
    s = t.slaves()[0]
    assert s.identity().vendor_id == 0x1A3
    s.sdo_download(0x6060, 0, b"\x08")
    assert s.sdo_upload(0x6060, 0) == b"\x08"
    with pytest.raises(SdoAbort) as ei:
        s.sdo_upload(0x1234, 0)
    assert ei.value.code == 0x06020000
    with pytest.raises(SdoAbort) as ei:
        s.sdo_download(0x6041, 0, b"\x00\x00")
    assert ei.value.code == 0x06010002
    # the Technosoft reset gets no reply: fine when no reply is expected, a timeout otherwise
    s.sdo_download(0x2080, 0, b"\x00\x00", expect_reply=False)
    with pytest.raises(SdoTimeout):
        s.sdo_download(0x2080, 0, b"\x00\x00")


def test_states_and_refusals():
    t = PysoemTarget("eth0", pysoem_module=fake)
    s = t.slaves()[0]
    s.request_state(EcState.PREOP)
    assert s.state() is EcState.PREOP
    s.request_state(EcState.SAFEOP)
    assert t.mapped and s.state() is EcState.SAFEOP
    s._slave.refuse.add(8)
    with pytest.raises(StateChangeError) as ei:
        s.request_state(EcState.OP)
    assert ei.value.al_status == 0x001D
    assert s.exchange(b"\x0f\x00") == b"\x27\x02" and s._slave.output == b"\x0f\x00"


def test_open_failures_are_target_errors():
    with pytest.raises(TargetError, match="cannot open"):
        PysoemTarget("nope", pysoem_module=fake)
