"""A held bus (issue 35 item 5: ``sdo read`` at the cost of a bare pysoem script; ``ecattool bus hold``), in
process: the holder serves a simulated bus from its master's child process, as it serves a real master's, under a
``pysoem:`` name of its own; the commands run through the real entry point and find it by that name. No master
library is loaded and no bus state is read by a command that goes through the holder (both are made to fail here).
On the wire, with SOEM: tests/wire/test_wire_online.py."""

from __future__ import annotations

import itertools
import json
import os
import signal
import threading
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from ecattool.errors import TargetError
from ecattool.online import bus_state, held
from ecattool.online.live import LiveBus
from ecattool.online.targets import isolated_bus, open_guarded, sim_bus
from ecattool.target import pysoem as pysoem_adapter
from ecattool.target.isolated import MasterGone
from tests.conftest import run

_COUNT = itertools.count()


@dataclass
class Holding:
    name: str
    thread: threading.Thread
    done: list[held.Hold]
    opened: list[LiveBus]

    def wait(self, timeout_s: float = 30.0) -> held.Hold:
        self.thread.join(timeout_s)
        assert not self.thread.is_alive(), "the hold did not end"
        return self.done[0]


def _sim_opener(opened: list[LiveBus]) -> Any:
    from ecattool.sim.bus.serve import device_source
    from ecattool.sim.slave import drive_for_device

    def opener() -> LiveBus:
        bus = isolated_bus("sim:hdt", lambda: sim_bus([drive_for_device(device_source("hdt")[1])]))
        opened.append(bus)
        return bus

    return opener


def _start(seconds: float = 60.0) -> Holding:
    name = f"pysoem:held{os.getpid()}x{next(_COUNT)}"  # a name of this test's own: xdist workers share the netns
    ready = threading.Event()
    done: list[held.Hold] = []
    opened: list[LiveBus] = []

    def run_hold() -> None:
        done.append(held.hold(name, _sim_opener(opened), seconds, ready=lambda h: ready.set()))

    thread = threading.Thread(target=run_hold, daemon=True)
    thread.start()
    assert ready.wait(30), "the holder did not get ready"
    return Holding(name, thread, done, opened)


@pytest.fixture
def holding(monkeypatch: pytest.MonkeyPatch) -> Iterator[Holding]:
    def no_master() -> None:
        raise AssertionError("a command through a held bus loaded a master of its own")

    def no_state_read(*a: object, **k: object) -> None:
        raise AssertionError("a command through a held bus read the bus state")

    monkeypatch.setattr(pysoem_adapter, "_import_pysoem", no_master)
    monkeypatch.setattr(bus_state, "guard", no_state_read)
    h = _start()
    yield h
    if h.thread.is_alive():
        held.release(h.name)
        h.wait()


def test_commands_read_and_write_through_the_held_master(holding: Holding, capsys: pytest.CaptureFixture[str]) -> None:
    target = ["--target", holding.name]
    code, out, err = run(capsys, "sdo", "read", "0x1018:01", *target, "--json")
    assert code == 0, err
    assert json.loads(out)["value"] == 0x289  # HDT's vendor ID, as the simulated drive answers it
    # one master for all: what one command writes, the next reads (a master of its own would have reset it)
    code, out, err = run(capsys, "sdo", "write", "0x6081:00", "12345", *target, "--device", "hdt")
    assert code == 0, err
    code, out, err = run(capsys, "sdo", "read", "profile velocity", *target, "--device", "hdt", "--json")
    assert code == 0, err
    assert json.loads(out)["value"] == 12345
    code, out, err = run(capsys, "bus", "scan", *target, "--json")
    assert code == 0, err
    assert [s["coe_identity"]["vendor_id"] for s in json.loads(out)["slaves"]] == [0x289]
    # an abort comes back as itself: one line naming the object and the abort
    code, out, err = run(capsys, "sdo", "read", "0x7777:00", *target)
    assert code == 1 and err.startswith("ecattool: error: ") and "7777" in err and "0x06020000" in err, err
    code, out, err = run(capsys, "bus", "release", *target, "--json")
    assert code == 0, err
    summary = json.loads(out)
    assert (summary["target"], summary["pid"], summary["commands"]) == (holding.name, os.getpid(), 5)
    assert summary["requests"] >= 5
    record = holding.wait()
    assert (record.ended, record.commands) == ("released", 5)
    assert held.holder(holding.name) is None
    assert holding.opened[0].master.gone  # the master was closed when the hold ended


def test_commands_that_reset_the_bus_are_refused_while_it_is_held(holding: Holding, tmp_path: Path,
                                                                  capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(TargetError) as refused:
        open_guarded(holding.name)
    assert str(refused.value) == (f"{holding.name} is held by ecattool bus hold (pid {os.getpid()}), and this command "
                                  "takes every slave through INIT with a master of its own: end the hold first "
                                  f"(ecattool bus release --target {holding.name})")
    code, out, err = run(capsys, "sw", "upload", "--target", holding.name, "--range", "0x5638-0x5A37",
                         "-o", str(tmp_path / "up.sw"))
    assert code == 1 and f"is held by ecattool bus hold (pid {os.getpid()})" in err, err
    with pytest.raises(TargetError, match="it is held once at a time"):
        held.hold(holding.name, lambda: pytest.fail("a second hold opened the bus"), 5)


def test_the_hold_ends_by_itself_and_puts_the_bus_back() -> None:
    h = _start(seconds=0.3)
    record = h.wait()
    assert record.ended == "time is up" and record.commands == 0
    assert h.opened[0].master.gone
    assert held.connect(h.name) is None


def test_only_the_holders_user_and_root_are_served(holding: Holding, monkeypatch: pytest.MonkeyPatch) -> None:
    assert held._allowed(os.getuid()) and held._allowed(0)
    assert not held._allowed(os.getuid() + 12345)
    with monkeypatch.context() as m, \
            pytest.raises(MasterGone, match=r"ended before it took this command \(it serves its own user and root "
                                            r"only\)"):
        # the holder (its thread) sees this process as another user's; the command still trusts the holder
        m.setattr(held, "_allowed", lambda uid: threading.current_thread() is threading.main_thread())
        held.connect(holding.name)


def test_a_socket_of_another_user_is_never_trusted(monkeypatch: pytest.MonkeyPatch) -> None:
    """Anyone may bind an abstract name: a command unpickles the replies of a holder of its own user or root only."""
    import socket

    name = f"pysoem:squat{os.getpid()}"
    squatter = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    squatter.bind(held.address(name))
    squatter.listen(1)
    try:
        monkeypatch.setattr(held, "_allowed", lambda uid: False)  # this process as another user's
        with pytest.raises(TargetError, match=rf"the socket that says it holds {name} \(@ecattool/held/{name}, pid "
                                              rf"{os.getpid()}\) belongs to user {os.getuid()}, neither this user nor "
                                              r"root: not used"):
            held.connect(name)
    finally:
        squatter.close()


def test_one_command_at_a_time_and_the_next_is_told_why_it_waits(holding: Holding,
                                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    first = held.connect(holding.name)
    assert first is not None and first.positions == [0]
    with monkeypatch.context() as m, \
            pytest.raises(MasterGone, match=rf"the holder of {holding.name} \(ecattool bus hold, pid "
                                            rf"{os.getpid()}\) is serving another command, 0.3 s already"):
        m.setattr(held, "HELLO_S", 0.3)
        held.connect(holding.name)
    first.close()
    second = held.connect(holding.name)  # taken once the first hung up (the usual wait, HELLO_S)
    assert second is not None
    second.close()


def test_a_master_that_dies_ends_the_hold_and_the_command_is_told(holding: Holding) -> None:
    master = holding.opened[0].master
    os.kill(master._proc.pid, signal.SIGKILL)
    bus = held.held_bus(holding.name, holding.name)
    assert bus is not None
    with pytest.raises(MasterGone, match=r"the master crashed (before )?reading 1018h:01 of slave 0 \(sim:hdt: "
                                         r"signal SIGKILL\)"):
        bus.slave(0).sdo_upload(0x1018, 1)
    bus.close()
    assert holding.wait().ended == "the master is gone"


def test_a_command_stopped_in_the_middle_of_a_message_is_let_go(holding: Holding,
                                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    """Every wait of the holder is bounded: a peer that sends the start of a message and no more is dropped after
    STALL_S, and the next command is served."""
    import socket

    monkeypatch.setattr(held, "STALL_S", 0.3)
    stuck = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    stuck.connect(held.address(holding.name))
    stuck.recv(1 << 16)  # the hello
    stuck.sendall(b"\xff\x00")  # two of a length's four octets, then nothing
    try:
        bus = held.held_bus(holding.name, holding.name)  # waits for the holder to let the stuck one go
        assert bus is not None
        assert bus.slave(0).sdo_upload(0x1018, 1) == (0x289).to_bytes(4, "little")
        bus.close()
    finally:
        stuck.close()


def test_sigterm_ends_a_hold_as_ctrl_c_does() -> None:
    """The handler the hold installs for SIGTERM, called as the interpreter calls it (no real signal is sent to the
    test runner's worker: one that arrives while a GC callback runs would be raised there instead), and the one
    before it back afterwards."""
    before = signal.getsignal(signal.SIGTERM)
    with pytest.raises(KeyboardInterrupt):
        with held._terminated_as_interrupt():
            handler = signal.getsignal(signal.SIGTERM)
            assert callable(handler) and handler is not before
            handler(signal.SIGTERM, None)
    assert signal.getsignal(signal.SIGTERM) is before


def test_only_a_real_masters_bus_is_held(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run(capsys, "bus", "hold", "--target", "sim:hdt")
    assert (code, out) == (1, "")
    assert err == "ecattool: error: target 'sim': only a real master's bus can be held (pysoem:IF or kickcat:IF)\n"
    code, out, err = run(capsys, "bus", "release", "--target", "pysoem:nothing-holds-this")
    assert code == 1 and err == ("ecattool: error: nothing holds pysoem:nothing-holds-this (ecattool bus hold "
                                 "--target pysoem:nothing-holds-this holds it)\n")


def test_the_cli_and_the_library_agree_on_how_long_a_hold_may_be() -> None:
    from ecattool.cli import bus

    assert (bus.MAX_HOLD_S, bus.DEFAULT_HOLD_S) == (held.MAX_HOLD_S, held.DEFAULT_HOLD_S)
