"""A real master in a child process (ecattool/target/isolated.py, issue 37 item 1): a master library that crashes
or hangs on what a slave answers becomes one error naming the slave and the object; ecattool's own errors come back
as themselves; every request is bounded in time. In process, with a stand-in master whose calls really crash
(a NULL read: SIGSEGV, as SOEM's ``sdo_read`` does on an upload that announces 2^31 octets) -- before the
isolation, these tests ended the test process itself."""

from __future__ import annotations

import ctypes
import threading
from typing import Any

import pytest

from ecattool.errors import SdoAbort, SdoTimeout, TargetError
from ecattool.esi.model import Identity
from ecattool.od.model import EcState
from ecattool.online.live import LiveBus
from ecattool.online.targets import isolated_bus
from ecattool.target.isolated import MasterCrashed, MasterGone, MasterHung, MasterProcess, RemoteSlave, describe

#: released when a test ends: a "hanging" master call waits on it, bounded
RELEASE = threading.Event()


class StandIn:
    """A slave of a master library: 1018h:01 crashes it, 2000h hangs it, 6060h aborts, the rest answers."""

    def __init__(self, position: int) -> None:
        self.position = position

    def identity(self) -> Identity:
        return Identity(0x289, 0x1234, 7, 42)

    def sdo_upload(self, index: int, subindex: int, complete_access: bool = False, size: int | None = None) -> bytes:
        if (index, subindex) == (0x1018, 1):
            ctypes.string_at(0)  # SIGSEGV in the master's process
        if index == 0x2000:
            RELEASE.wait(30)
        if index == 0x6060:
            raise SdoAbort(index, subindex, 0x06020000)
        if index == 0x6061:
            raise SdoTimeout(index, subindex, self.position)
        return bytes([index & 0xFF, subindex, int(complete_access)])

    def state(self) -> EcState:
        return EcState.PREOP

    def al_status_code(self) -> int | None:
        return 0

    def sii_read(self) -> bytes:
        raise ValueError("a bug in the binding")


def _bus() -> LiveBus:
    return LiveBus("standin:eth9", [StandIn(0), StandIn(1)])


def test_a_crash_in_the_master_is_one_error_naming_the_slave_and_the_object() -> None:
    bus = isolated_bus("standin:eth9", _bus)
    with bus:
        s0, s1 = bus.slaves
        assert s1.sdo_upload(0x1000, 0, True) == b"\x00\x00\x01"  # the slaves' own answers come through
        with pytest.raises(MasterCrashed) as crashed:
            s0.sdo_upload(0x1018, 1)
        assert str(crashed.value) == ("the master crashed reading 1018h:01 of slave 0 (standin:eth9: "
                                      "signal SIGSEGV)")
        with pytest.raises(MasterGone, match=r"^reading the state of slave 1: the master crashed reading 1018h:01"):
            s1.state()  # the master is gone: every later request says so at once


def test_ecattool_errors_come_back_as_themselves() -> None:
    with isolated_bus("standin:eth9", _bus) as bus:
        s = bus.slaves[1]
        with pytest.raises(SdoAbort) as abort:
            s.sdo_upload(0x6060, 0)
        assert abort.value.code == 0x06020000 and (abort.value.index, abort.value.subindex) == (0x6060, 0)
        with pytest.raises(SdoTimeout, match="SDO timeout on 0x6061:00 of slave 1: no reply"):
            s.sdo_upload(0x6061, 0)
        with pytest.raises(TargetError, match=r"^the master failed reading the SII of slave 1: ValueError: a bug"):
            s.sii_read()
        assert s.identity() == Identity(0x289, 0x1234, 7, 42) and s.state() is EcState.PREOP
        assert s.sdo_upload(0x1001, 0) == b"\x01\x00\x00"  # still serving after the errors


def test_a_hanging_master_is_stopped_after_its_time_limit(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("ECATTOOL_MASTER_TIMEOUT_S", "0.5")
    master = MasterProcess("standin:eth9", _bus, lambda bus: bus.slaves)
    try:
        with pytest.raises(MasterHung, match=r"^the master did not answer within 0.5 s reading 2000h:03 of slave 1"):
            RemoteSlave(master, 1).sdo_upload(0x2000, 3)
        assert not master._proc.is_alive()  # stopped, not left behind
    finally:
        RELEASE.set()
        master.close()


def test_a_master_that_fails_to_open_says_why_and_leaves_no_process() -> None:
    def refuse() -> Any:
        raise TargetError("no EtherCAT slaves found on 'eth9' (asked for 2 s)")

    with pytest.raises(TargetError, match="^no EtherCAT slaves found on 'eth9'"):
        isolated_bus("standin:eth9", refuse)

    def crash() -> Any:
        ctypes.string_at(0)

    with pytest.raises(MasterCrashed, match=r"^the master crashed opening the bus on standin:eth9 "):
        isolated_bus("standin:eth9", crash)


def test_requests_are_described_as_a_manual_names_them() -> None:
    assert describe("sdo_upload", 3, (0x6041, 0)) == "reading 6041h:00 of slave 3"
    assert describe("sdo_download", 0, (0x6060, 0, b"\x01")) == "writing 6060h:00 of slave 0"
    assert describe("request_state", 1, (EcState.SAFEOP,)) == "requesting SAFEOP of slave 1"


def test_a_closing_master_is_waited_for_without_a_poll(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every command waits for its master's child to end; the wait wakes when the child ends (a pidfd), not on a
    10 ms poll that cost a one-object ``sdo read`` 5 ms on average (benchmarks/bench_sdo_read.py). A child still
    running is waited for up to the time given, and no poll either."""
    import os

    from ecattool.target import isolated

    def no_poll(seconds: float) -> None:
        raise AssertionError(f"join polled ({seconds} s)")

    read_end, write_end = os.pipe()
    child = isolated.Child(lambda: os.read(read_end, 1) and None)  # runs until the parent writes
    try:
        monkeypatch.setattr(isolated.time, "sleep", no_poll)
        child.join(0.2)  # still running: waited 0.2 s in select, then given up on
        assert child.is_alive()
        os.write(write_end, b"x")
        child.join(30)  # ends now: woken by its end
        assert child.exitcode == 0
    finally:
        monkeypatch.undo()
        child.kill()
        child.join(5)
        child.close()
        os.close(read_end)
        os.close(write_end)
