"""A real master in a child process of its own, so that a master that crashes or hangs cannot take ecattool down.

SOEM (through pysoem) and KickCAT are compiled code that trusts what a slave answers: SOEM reads the size an SDO
upload announces as a signed 32-bit number (2^31 octets or more passes its "does it fit the buffer" check and is
copied with ``memcpy``), and copies the segments of a segmented upload without ever checking the end of the buffer;
KickCAT's bus init follows an SII category chain without an end marker for minutes (docs/at-the-machine.md,
"When the master crashes"). In ecattool's own process either ends the command with SIGSEGV (exit 139, no word)
or a wait without end.

So the master runs in a forked child (:class:`MasterProcess`): the child opens the bus and owns the master's
objects; ecattool sends it one request at a time over a pipe (a slave's position, a method, its arguments) and
waits a bounded time for the answer. ecattool's own errors raised in the child (SdoAbort, SdoTimeout, …) come
back as themselves. A child that dies becomes one :class:`MasterCrashed` naming the slave and what was asked
("the master crashed reading 1018h:01 of slave 0"); one that does not answer in time is stopped and named the
same way (:class:`MasterHung`). After either, the master is gone: every later request raises the same error at
once. Every request and the bus init have a time limit (``timeout_s`` of the call; ``ECATTOOL_MASTER_TIMEOUT_S``
caps them all, e.g. for a test that wants a hang found quickly).

The cost is one ``fork`` when the bus is opened and one pipe round trip (some ten microseconds) per request.
"""

from __future__ import annotations

import ctypes
import faulthandler
import os
import select
import signal
import sys
import time
from collections.abc import Callable, Sequence
from typing import Any

from ecattool.target.base import SlaveTarget
from ecattool.target.remote import (
    CALL_TIMEOUT_S,
    Channel,
    MasterCrashed,
    MasterGone,
    MasterHung,
    RemoteSlave,
    cap,
    describe,
    error_reply,
    outcome,
)
from ecattool.target.timeouts import BusLimits

__all__ = ["CALL_TIMEOUT_S", "Channel", "IsolatedTarget", "MasterCrashed", "MasterGone", "MasterHung",
           "MasterProcess", "RemoteSlave", "cap", "describe", "pysoem_target"]

#: how long a closing master may take before it is stopped
CLOSE_TIMEOUT_S = 5.0
#: prctl(2) option: the signal the child gets when its parent dies
_PR_SET_PDEATHSIG = 1


def _signal_name(code: int | None) -> str:
    if code is None:
        return "no exit status"
    if code < 0:
        try:
            return f"signal {signal.Signals(-code).name}"
        except ValueError:
            return f"signal {-code}"
    return f"exit status {code}"


class Child:
    """A forked child process running ``target()`` (exit status 0, or 1 where it raised), as ``multiprocessing``'s
    fork context starts one: ``exitcode`` negative for the signal that ended it."""

    def __init__(self, target: Callable[[], None], before: Callable[[], None] = lambda: None) -> None:
        sys.stdout.flush()
        sys.stderr.flush()
        self.exitcode: int | None = None
        pid = os.fork()
        if pid == 0:  # the child: never returns into the caller's code
            code = 1
            try:
                before()
                target()
                code = 0
            finally:
                os._exit(code)
        self.pid = pid
        self._pidfd = self._open_pidfd()

    def _reap(self, block: bool = False) -> None:
        if self.exitcode is None:
            try:
                pid, status = os.waitpid(self.pid, 0 if block else os.WNOHANG)
            except ChildProcessError:
                self.exitcode = -int(signal.SIGKILL)
                return
            if pid:
                self.exitcode = os.waitstatus_to_exitcode(status)

    def is_alive(self) -> bool:
        self._reap()
        return self.exitcode is None

    def join(self, timeout_s: float) -> None:
        """Wait for the child to end, ``timeout_s`` at the most: woken by its end through a pidfd (Linux 5.3)
        where there is one, else polled every 10 ms (a closing master is waited for by every command: the poll
        alone cost a one-object ``sdo read`` 5 ms on average)."""
        deadline = time.monotonic() + timeout_s
        if self.is_alive() and self._pidfd is not None:
            select.select([self._pidfd], [], [], max(0.0, timeout_s))
        while self.is_alive() and time.monotonic() < deadline:
            time.sleep(0.01)

    def _open_pidfd(self) -> int | None:
        try:
            return os.pidfd_open(self.pid)
        except (AttributeError, OSError):  # not Linux, or a kernel before 5.3
            return None

    def close(self) -> None:
        """Let go of the pidfd (the child itself is reaped by join or kill)."""
        if self._pidfd is not None:
            os.close(self._pidfd)
            self._pidfd = None

    def kill(self) -> None:
        if self.is_alive():
            try:
                os.kill(self.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass


# ------------------------------------------------------------------------------------------------ the child
def _serve(conn: Channel, factory: Callable[[], Any], slaves_of: Callable[[Any], Sequence[Any]]) -> None:
    """The child: open the master (``factory``), tell the parent the slaves' positions, then answer requests
    until the parent says ``None`` (close) or goes away."""
    try:  # the master never outlives ecattool (a killed parent leaves no master on the interface)
        ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGKILL)
    except (OSError, AttributeError):
        pass
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's: it closes the master in order
    faulthandler.disable()  # a crash of the master is the parent's one line, not a Python stack dump
    try:
        root = factory()
        slaves = list(slaves_of(root))
    except BaseException as exc:  # noqa: BLE001 - every failure goes back to the parent as one reply
        conn.send(error_reply(exc))
        return
    conn.send(("ok", [int(getattr(s, "position", i)) for i, s in enumerate(slaves)]))
    while True:
        try:
            request = conn.recv()
        except (EOFError, OSError):
            request = None
        if request is None:
            try:
                root.close()
            finally:
                conn.close()
            return
        position, method, args, kwargs = request
        try:
            target = root if position is None else slaves[position]
            reply: tuple[Any, ...] = ("ok", getattr(target, method)(*args, **kwargs))
        except BaseException as exc:  # noqa: BLE001
            reply = error_reply(exc)
        conn.send(reply)


# ------------------------------------------------------------------------------------------------ the parent
class MasterProcess:
    """A master opened by ``factory`` in a forked child; ``slaves_of(root)`` lists its slaves there.

    ``name`` (``pysoem:eth0``) is used in errors. :attr:`positions` are the slaves' bus positions, in order.
    ``limits``: how long the bus init and each SDO request may take (the slaves' timeouts; ``open_timeout_s``
    overrides the bus init's)."""

    def __init__(self, name: str, factory: Callable[[], Any], slaves_of: Callable[[Any], Sequence[Any]],
                 open_timeout_s: float | None = None, limits: BusLimits | None = None) -> None:
        self.name = name
        self.limits = limits or BusLimits()
        self._dead: MasterGone | None = None
        self._conn, child_end = Channel.pair()
        self._proc = Child(lambda: _serve(child_end, factory, slaves_of), before=self._conn.close)
        child_end.close()
        open_s = self.limits.open_s if open_timeout_s is None else open_timeout_s
        self.positions: list[int] = self._answer(f"opening the bus on {name}", cap(open_s))

    def _answer(self, what: str, timeout_s: float) -> Any:
        """The child's reply to the request just sent (or to its start)."""
        conn = self._conn
        try:
            ready = conn.poll(timeout_s)
            reply = conn.recv() if ready else None
        except (EOFError, OSError):
            self._proc.join(1.0)
            self._dead = MasterCrashed(f"the master crashed {what} ({self.name}: {_signal_name(self._proc.exitcode)})")
            raise self._dead from None
        if reply is None:
            self._stop()
            self._dead = MasterHung(f"the master did not answer within {timeout_s:g} s {what} ({self.name}; stopped; "
                                    f"{self.limits.describe()})")
            raise self._dead
        return outcome(reply, what)

    def call(self, position: int | None, method: str, *args: Any, timeout_s: float = CALL_TIMEOUT_S,
             **kwargs: Any) -> Any:
        """``method(*args, **kwargs)`` of the slave at ``position`` (None: the master itself), in the child."""
        what = describe(method, position, args)
        if self._dead is not None:
            raise MasterGone(f"{what}: {self._dead.message}")
        try:
            self._conn.send((position, method, args, kwargs))
        except (OSError, ValueError):
            self._proc.join(1.0)
            self._dead = MasterCrashed(f"the master crashed before {what} ({self.name}: "
                                       f"{_signal_name(self._proc.exitcode)})")
            raise self._dead from None
        return self._answer(what, cap(timeout_s))

    @property
    def gone(self) -> bool:
        """Whether the master is gone (crashed, hung or closed): every request raises :class:`MasterGone`."""
        return self._dead is not None

    def _stop(self) -> None:
        if self._proc.is_alive():
            self._proc.kill()
        self._proc.join(CLOSE_TIMEOUT_S)

    def close(self) -> None:
        """Close the master (in the child) and end the child; bounded by CLOSE_TIMEOUT_S."""
        if self._dead is None and self._proc.is_alive():
            try:
                self._conn.send(None)
            except (OSError, ValueError):
                pass
            self._proc.join(cap(CLOSE_TIMEOUT_S))
        self._stop()
        self._conn.close()
        self._proc.close()
        if self._dead is None:
            self._dead = MasterGone(f"the master on {self.name} is closed")


class IsolatedTarget:
    """A :class:`~ecattool.target.base.Target` whose master runs in a :class:`MasterProcess`."""

    def __init__(self, master: MasterProcess) -> None:
        self.master = master
        self._slaves = [RemoteSlave(master, p) for p in master.positions]

    def slaves(self) -> list[SlaveTarget]:
        return list(self._slaves)

    def close(self) -> None:
        self.master.close()


def pysoem_target(ifname: str, limits: BusLimits | None = None) -> IsolatedTarget:
    """SOEM through pysoem on ``ifname`` (:class:`ecattool.target.pysoem.PysoemTarget`), in a child process;
    ``limits``: the slaves' timeouts (ecattool.target.timeouts)."""
    from ecattool.target.pysoem import PysoemTarget, _import_pysoem

    _import_pysoem()  # a missing extra is said here, and the child starts with the module loaded
    return IsolatedTarget(MasterProcess(f"pysoem:{ifname}", lambda: PysoemTarget(ifname, limits=limits),
                                        lambda t: t.slaves(), limits=limits))
