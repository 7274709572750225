"""A held bus: one real master kept open by ``ecattool bus hold``, that the other commands read the bus through
(issue 35 item 5), as IgH's master owns its bus and ``ethercat upload`` answers without a bus init.

Every command that reads a live bus opens a master of its own, and a master's bus init (SOEM's ``config_init``,
KickCAT's bus init) costs what a whole bare pysoem script costs, and resets every slave. ``ecattool bus hold
--target pysoem:eth0`` opens the bus once (the guarded open of every command: a bus with slaves in SAFE-OP or OP
is refused without ``--reset-bus``; the master in its child process, ``ecattool.target.isolated``) and keeps it
for a bounded time. Meanwhile each command that reads a live bus with the same ``--target`` (``sdo``, ``bus
scan``, ``audit``, ``backup``, ``project new --from-bus``, ``sii read/write``) sends its requests to the holder
instead: no bus init, no state change, no master library loaded. The commands that take slaves through INIT
(``commission``, ``sw``, ``scale explain --target``) are refused while the bus is held, naming the holder.

The holder listens on a Unix socket in the abstract namespace, ``@ecattool/held/KIND:IF``. An abstract socket
belongs to its network namespace, as the interface does: a command finds the holder of the interface it names
there, and nothing is left on disk. A connection is served only for the holder's own user or root
(``SO_PEERCRED``), because requests are pickled as between ecattool and its master's child. One command is
served at a time; another waits for it, :data:`HELLO_S` at the most. A request is the isolated master's request
with its time limit; the reply is the master's, errors come back as themselves (an SdoAbort stays one).
"""

from __future__ import annotations

import os
import select
import socket
import struct
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any

from ecattool.errors import SelectionError, TargetError
from ecattool.online.live import LiveBus
from ecattool.record import Record
from ecattool.target.remote import (
    CALL_TIMEOUT_S,
    Channel,
    MasterGone,
    RemoteSlave,
    cap,
    describe,
    error_reply,
    outcome,
)
from ecattool.target.timeouts import BusLimits

if TYPE_CHECKING:
    from ecattool.target.isolated import MasterProcess

#: how long a command waits for the holder to take it (it serves one command at a time)
HELLO_S = 10.0
#: what a request through the holder may take beyond its own time limit (which the holder applies to the master)
HOP_S = 2.0
#: how long the rest of a message may take once its first octets came (a peer stopped mid-message is let go)
STALL_S = 10.0
#: how long ``bus release`` waits for the holder to put the slaves back and close its master
RELEASE_S = 60.0
#: the longest and the default hold (``bus hold --for``), in seconds
MAX_HOLD_S = 24 * 3600.0
DEFAULT_HOLD_S = 3600.0
#: the requests a holder serves: what a live slave answers through a master in another process (the public
#: methods of ``target.remote.RemoteSlave``, the one list of them)
REQUESTS = frozenset(n for n, v in vars(RemoteSlave).items() if callable(v) and not n.startswith("_"))
#: struct ucred of SO_PEERCRED: pid, uid, gid
_UCRED = struct.Struct("3i")


def address(name: str) -> bytes:
    """The holder's socket address of a master ``name`` (``pysoem:eth0``): abstract, of the network namespace."""
    return b"\0ecattool/held/" + name.encode()


def _peer(sock: socket.socket) -> tuple[int, int]:
    """The pid and uid of the process at the other end of a Unix socket."""
    pid, uid, _gid = _UCRED.unpack(sock.getsockopt(socket.SOL_SOCKET, socket.SO_PEERCRED, _UCRED.size))
    return pid, uid


def _dial(name: str) -> socket.socket | None:
    """A connection to the holder of ``name``, or None where nothing holds it."""
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    sock.settimeout(STALL_S)
    try:
        sock.connect(address(name))
    except (ConnectionRefusedError, FileNotFoundError):
        sock.close()
        return None
    except OSError as exc:  # EAGAIN: its backlog is full (it exists, and is busy)
        sock.close()
        raise TargetError(f"the holder of {name} (ecattool bus hold) cannot be reached: {exc.strerror or exc}") from None
    return sock


def holder(name: str) -> int | None:
    """The pid of the process that holds ``name``, or None."""
    sock = _dial(name)
    if sock is None:
        return None
    try:
        return _peer(sock)[0]
    finally:
        sock.close()


def refuse_if_held(name: str, why: str) -> None:
    """A TargetError naming the holder of ``name`` where it is held: ``why`` the command cannot go through it."""
    pid = holder(name)
    if pid is not None:
        raise TargetError(f"{name} is held by ecattool bus hold (pid {pid}), and {why}: end the hold first "
                          f"(ecattool bus release --target {name})")


# ------------------------------------------------------------------------------------------------ a command's side
class HeldMaster:
    """The master a holder keeps, seen by one command (a :class:`~ecattool.target.isolated.Master`): ``call``
    sends one request, ``close`` hangs up (the bus stays held). ``found``: the slaves' states as the holder found
    them before its master opened the bus."""

    def __init__(self, name: str, sock: socket.socket, limits: BusLimits | None = None) -> None:
        self.name = name
        self.limits = limits or BusLimits()
        self.pid, uid = _peer(sock)
        if not _allowed(uid):  # anyone may bind an abstract name: a reply is unpickled only from a trusted holder
            sock.close()
            raise TargetError(f"the socket that says it holds {name} (@ecattool/held/{name}, pid {self.pid}) belongs "
                              f"to user {uid}, neither this user nor root: not used")
        self._conn = Channel(sock)
        self._dead: MasterGone | None = None
        hello = self._answer("", HELLO_S, busy=True)
        self.positions: list[int] = list(hello["positions"])
        self.found: list[Any] = list(hello["found"])

    def _gone(self, text: str) -> MasterGone:
        self._dead = MasterGone(text)
        self._conn.close()
        return self._dead

    def _answer(self, what: str, timeout_s: float, busy: bool = False) -> Any:
        who = f"the holder of {self.name} (ecattool bus hold, pid {self.pid})"
        try:
            reply = self._conn.recv() if self._conn.poll(timeout_s) else None
        except (EOFError, OSError):
            raise self._gone(f"{who} ended" + (f" {what}" if what else " before it took this command") +
                             (" (it serves its own user and root only)" if busy else "")) from None
        if reply is None:
            if busy:
                raise self._gone(f"{who} is serving another command, {timeout_s:g} s already: try again when it ends")
            raise self._gone(f"{who} did not answer within {timeout_s:g} s {what}")
        return outcome(reply, what)

    def call(self, position: int | None, method: str, *args: Any, timeout_s: float = CALL_TIMEOUT_S,
             **kwargs: Any) -> Any:
        what = describe(method, position, args)
        if self._dead is not None:
            raise MasterGone(f"{what}: {self._dead.message}")
        limit = cap(timeout_s)
        try:
            self._conn.send((position, method, args, kwargs, limit))
        except OSError:
            raise self._gone(f"the holder of {self.name} (pid {self.pid}) ended before {what}") from None
        return self._answer(what, limit + HOP_S)

    def release(self) -> dict[str, Any]:
        """Ask the holder to put the slaves back, close its master and end; what it says of it."""
        self._conn.send(("release",))
        summary: dict[str, Any] = self._answer("releasing the bus", RELEASE_S)
        return summary

    def close(self) -> None:
        self._conn.close()


def connect(name: str, limits: BusLimits | None = None) -> HeldMaster | None:
    """The master that holds ``name`` (``pysoem:eth0``), taken for this command; None where nothing holds it."""
    sock = _dial(name)
    return None if sock is None else HeldMaster(name, sock, limits)


def held_bus(name: str, spec: str, limits: BusLimits | None = None) -> LiveBus | None:
    """The live bus ``spec`` through the holder of ``name``, or None where nothing holds it. Closing it hangs up:
    the slaves stay as the holder keeps them (nothing to put back, the command reset nothing)."""
    master = connect(name, limits)
    if master is None:
        return None
    return LiveBus(spec, [RemoteSlave(master, p) for p in master.positions], closer=master.close,
                   found=master.found)


def release(name: str) -> dict[str, Any]:
    """End the hold on ``name`` (``bus release``): the holder puts the slaves back and closes its master first.
    Returns its summary (:meth:`Hold.to_json`: ``target``, ``pid``, ``ended``, ``commands``, ``requests``,
    ``notes`` …)."""
    master = connect(name)
    if master is None:
        raise TargetError(f"nothing holds {name} (ecattool bus hold --target {name} holds it)")
    try:
        return master.release()
    finally:
        master.close()


# ------------------------------------------------------------------------------------------------ the holder
class Hold(Record):
    """A hold as it went: the master ``name``, the slaves held, why it ended, the commands and requests served,
    and what putting the slaves back said (``notes``)."""

    __slots__ = ("name", "pid", "slaves", "until", "ended", "commands", "requests", "notes")
    name: str
    pid: int
    slaves: int
    until: float
    ended: str
    commands: int
    requests: int
    notes: list[str]

    def __init__(self, name: str, pid: int, slaves: int, until: float, ended: str = "", commands: int = 0,
                 requests: int = 0, notes: list[str] | None = None) -> None:
        self.name = name
        self.pid = pid
        self.slaves = slaves
        self.until = until
        self.ended = ended
        self.commands = commands
        self.requests = requests
        self.notes = [] if notes is None else notes

    def to_json(self) -> dict[str, Any]:
        return {"target": self.name, "pid": self.pid, "slaves": self.slaves, "until": self.until,
                "ended": self.ended, "commands": self.commands, "requests": self.requests, "notes": self.notes}


def hold_name(kind: str, interface: str) -> str:
    """The name a master is held under (``pysoem:eth0``): the spec as read, whatever its spelling."""
    if not interface:
        raise SelectionError(f"target {kind!r}: only a real master's bus can be held (pysoem:IF or kickcat:IF)")
    return f"{kind}:{interface}"


@contextmanager
def _terminated_as_interrupt() -> Iterator[None]:
    """SIGTERM ends a hold as Ctrl-C does (the slaves put back, the master closed), in the main thread."""
    import signal  # the holder's alone: a command that reads through it loads neither
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def stop(signum: int, frame: Any) -> None:
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, stop)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def hold(name: str, opener: Callable[[], LiveBus], seconds: float,
         ready: Callable[[Hold], None] = lambda h: None) -> Hold:
    """Open the bus (``opener``: a real master's guarded open) and serve it to other commands under ``name`` for
    ``seconds`` at the most, or until ``bus release``, Ctrl-C or SIGTERM, or until its master is gone; then put the
    slaves back and close it. ``ready`` is called once the bus is open and the socket listens."""
    refuse_if_held(name, "it is held once at a time")
    seconds = min(max(seconds, 0.0), MAX_HOLD_S)
    listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        listener.bind(address(name))  # before the bus opens: two holds started at once, one of them refused
    except OSError:
        listener.close()
        raise TargetError(f"{name} is held already (ecattool bus hold, pid {holder(name)})") from None
    released: Channel | None = None
    try:
        bus = opener()
        master: MasterProcess | None = bus.master
        if master is None:
            bus.close()
            raise SelectionError(f"{name}: only a real master's bus can be held (pysoem:IF or kickcat:IF)")
        record = Hold(name, os.getpid(), len(bus.slaves), time.time() + seconds)
        try:
            listener.listen(8)
            ready(record)
            with _terminated_as_interrupt():
                released = _serve(listener, bus, master, record, time.monotonic() + seconds)
        except KeyboardInterrupt:
            record.ended = "interrupted"
        finally:
            bus.close()  # the slaves put back as found, the master closed
            record.notes = list(bus.notes)
    finally:
        listener.close()
        if released is not None:
            try:
                released.send(("ok", record.to_json()))
            except OSError:
                pass
            released.close()
    return record


def _allowed(uid: int) -> bool:
    """Whether a process of ``uid`` may send the holder requests: its own user, or root."""
    return uid in (os.getuid(), 0)


def _serve(listener: socket.socket, bus: LiveBus, master: MasterProcess, record: Hold,
           deadline: float) -> Channel | None:
    """Take one command at a time until the deadline, a release (its channel returned, answered once the bus is
    closed) or the master's end."""
    hello = ("ok", {"positions": list(master.positions), "found": list(bus.found), "pid": record.pid})
    while (left := deadline - time.monotonic()) > 0:
        ready, _, _ = select.select([listener], [], [], left)
        if not ready:
            break
        sock, _ = listener.accept()
        sock.settimeout(STALL_S)  # a command stopped in the middle of a message never holds the holder past it
        conn = Channel(sock)
        if not _allowed(_peer(sock)[1]):
            conn.close()
            continue
        ended = _session(conn, master, hello, record, deadline)
        if ended == "release":
            record.ended = "released"
            return conn
        conn.close()
        if master.gone:
            record.ended = "the master is gone"
            return None
    record.ended = record.ended or "time is up"
    return None


def _session(conn: Channel, master: MasterProcess, hello: tuple[str, Any], record: Hold, deadline: float) -> str:
    """Serve one command's requests until it hangs up ("done"), asks for the release ("release"), the master is
    gone or the deadline passes. A command is counted once it sends a request (not one that only looked whether
    the bus is held)."""
    try:
        conn.send(hello)
    except OSError:
        return "done"
    first = True
    while (left := deadline - time.monotonic()) > 0 and not master.gone:
        try:
            request = conn.recv() if conn.poll(left) else None
        except (EOFError, OSError):
            return "done"
        if request is None:
            return "done"
        if request == ("release",):
            return "release"
        reply = _answer(master, request)
        record.requests += 1
        if first:
            record.commands += 1
            first = False
        try:
            conn.send(reply)
        except OSError:
            return "done"
    return "done"


def _answer(master: MasterProcess, request: Any) -> tuple[Any, ...]:
    """The master's reply to one request (``(position, method, args, kwargs, timeout_s)``)."""
    try:
        position, method, args, kwargs, timeout_s = request
        if method not in REQUESTS or position not in master.positions:
            return ("failed", f"{method!r} of slave {position!r} is not a request a held bus serves")
        return ("ok", master.call(position, method, *args, timeout_s=float(timeout_s), **kwargs))
    except Exception as exc:  # noqa: BLE001 - every failure goes back to the command as its reply (Ctrl-C ends the hold)
        return error_reply(exc)
