"""The requests of a master that runs in another process: the side of ecattool that sends them. A request is a
slave's position, a method, its arguments and a time limit; the reply is the method's value or the error it raised,
pickled over a stream socket (:class:`Channel`). The master's side is the child process of
:mod:`ecattool.target.isolated` (``MasterProcess``) or a bus holder (:mod:`ecattool.online.held`); a command that
reads through a holder loads this module only, no master library and no child process code.
"""

from __future__ import annotations

import os
import pickle
import select
import socket
import struct
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, Protocol

from ecattool.errors import EcatToolError, TargetError

if TYPE_CHECKING:
    from ecattool.esi.model import Identity
    from ecattool.od.model import EcState, ObjectDictionary
    from ecattool.target.timeouts import BusLimits

#: how long one state or SII request may take (the bus init and SDO requests are bounded by the slaves' own
#: timeouts instead: ecattool.target.timeouts.BusLimits)
CALL_TIMEOUT_S = 20.0
#: the environment variable that caps every time limit (seconds)
TIMEOUT_ENV = "ECATTOOL_MASTER_TIMEOUT_S"

class MasterGone(TargetError):
    """The master is gone (it crashed or hung earlier): nothing more can be read through it."""


class MasterCrashed(MasterGone):
    """The master's child process ended while it served a request (a crash inside the master library)."""


class MasterHung(MasterGone):
    """The master did not answer a request within its time limit; its child process was stopped."""


def cap(timeout_s: float) -> float:
    """``timeout_s``, or the cap ``ECATTOOL_MASTER_TIMEOUT_S`` sets where it is lower."""
    text = os.environ.get(TIMEOUT_ENV, "")
    try:
        limit = float(text) if text else 0.0
    except ValueError:
        raise TargetError(f"{TIMEOUT_ENV}={text!r} is not a number of seconds") from None
    return min(timeout_s, limit) if limit > 0 else timeout_s


def object_text(index: int, subindex: int) -> str:
    """An object as a manual writes it: ``1018h:01``."""
    return f"{index:04X}h:{subindex:02X}"


def describe(method: str, slave: int | None, args: Sequence[Any]) -> str:
    """What a request does, for an error: ``reading 1018h:01 of slave 0``."""
    of = "" if slave is None else f" of slave {slave}"
    if method == "sdo_upload" and len(args) >= 2:
        return f"reading {object_text(args[0], args[1])}{of}"
    if method == "sdo_download" and len(args) >= 2:
        return f"writing {object_text(args[0], args[1])}{of}"
    if method == "sii_read":
        return f"reading the SII{of}"
    if method == "sii_write":
        return f"writing the SII{of}"
    if method == "sdo_info":
        return f"reading the SDO Information{of}"
    if method in ("state", "al_status_code"):
        return f"reading the state{of}"
    if method == "request_state" and args:
        return f"requesting {getattr(args[0], 'value', args[0])}{of}"
    if method == "identity":
        return f"reading the identity{of}"
    if method == "exchange":
        return f"exchanging process data{of}"
    return f"{method.replace('_', ' ')}{of}"


class Channel:
    """One end of a socket pair carrying pickled messages (a 4-octet length, then the pickle): what
    ``multiprocessing.Pipe`` gives, without importing ``multiprocessing`` (its connection module pulls in
    ``tempfile``, ``shutil`` and the compression modules: a noticeable part of a one-object ``sdo read``)."""

    def __init__(self, sock: socket.socket) -> None:
        self._sock = sock

    @classmethod
    def pair(cls) -> tuple["Channel", "Channel"]:
        a, b = socket.socketpair()
        return cls(a), cls(b)

    def send(self, obj: Any) -> None:
        data = pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL)
        self._sock.sendall(struct.pack("<I", len(data)) + data)

    def _read(self, n: int) -> bytes:
        buf = bytearray()
        while len(buf) < n:
            chunk = self._sock.recv(min(n - len(buf), 1 << 20))
            if not chunk:
                raise EOFError("the other end is closed")
            buf += chunk
        return bytes(buf)

    def recv(self) -> Any:
        (n,) = struct.unpack("<I", self._read(4))
        return pickle.loads(self._read(n))

    def poll(self, timeout_s: float) -> bool:
        """Whether a message (or the other end's close) is there to read within ``timeout_s``."""
        ready, _, _ = select.select([self._sock], [], [], max(0.0, timeout_s))
        return bool(ready)

    def close(self) -> None:
        self._sock.close()


def error_reply(exc: BaseException) -> tuple[Any, ...]:
    if isinstance(exc, EcatToolError):
        return ("error", type(exc), exc.args, dict(exc.__dict__))
    return ("failed", f"{type(exc).__name__}: {exc}")


def rebuild(reply: tuple[Any, ...], what: str) -> Exception:
    """The exception an error reply (:func:`error_reply`: the child's, or a bus holder's) stands for."""
    if reply[0] == "error":
        cls, args, state = reply[1], reply[2], reply[3]
        exc: Exception = cls.__new__(cls)
        exc.args = args
        exc.__dict__.update(state)
        return exc
    return TargetError(f"the master failed {what}: {reply[1]}")


def outcome(reply: tuple[Any, ...], what: str) -> Any:
    """The value a reply carries (``("ok", value)``), or the exception it stands for raised (:func:`rebuild`)."""
    if reply[0] == "ok":
        return reply[1]
    raise rebuild(reply, what)



class Master(Protocol):
    """What a :class:`RemoteSlave` sends its requests through: a :class:`MasterProcess`, or the master a bus
    holder keeps (``ecattool.online.held.HeldMaster``)."""

    name: str
    limits: BusLimits
    positions: list[int]

    def call(self, position: int | None, method: str, *args: Any, timeout_s: float = CALL_TIMEOUT_S,
             **kwargs: Any) -> Any: ...

    def close(self) -> None: ...


class RemoteSlave:
    """A slave of a :class:`MasterProcess` (or of a held bus's master): every method of the slave runs in the
    master's child (a :class:`~ecattool.target.base.LiveSlave`: the core and every capability)."""

    def __init__(self, master: Master, position: int) -> None:
        self._master = master
        self.position = position

    def _call(self, method: str, *args: Any, **kwargs: Any) -> Any:
        return self._master.call(self.position, method, *args, **kwargs)

    def identity(self) -> Identity:
        # pysoem's identity is the SII's (no request); KickCAT's is 1018h:01-03, three SDOs
        ident: Identity = self._call("identity", timeout_s=3 * self._master.limits.sdo_call_s)
        return ident

    def sdo_upload(self, index: int, subindex: int, complete_access: bool = False, size: int | None = None) -> bytes:
        data: bytes = self._call("sdo_upload", index, subindex, complete_access, size=size,
                                 timeout_s=self._master.limits.sdo_call_s)
        return data

    def sdo_download(self, index: int, subindex: int, data: bytes, complete_access: bool = False,
                     expect_reply: bool = True) -> None:
        self._call("sdo_download", index, subindex, bytes(data), complete_access, expect_reply,
                   timeout_s=self._master.limits.sdo_call_s)

    def state(self) -> EcState:
        state: EcState = self._call("state")
        return state

    def request_state(self, state: EcState) -> None:
        # pysoem gives a drive on its way to OP 2 s of paced cycles plus a state check per cycle (~22 s at 1 ms)
        self._call("request_state", state, timeout_s=3 * CALL_TIMEOUT_S)

    def al_status_code(self) -> int | None:
        code: int | None = self._call("al_status_code")
        return code

    def sii_read(self) -> bytes:
        image: bytes = self._call("sii_read")
        return image

    def sii_write(self, image: bytes) -> None:
        # word by word through the EEPROM: a 4 KiB image takes some seconds on a real bus
        self._call("sii_write", bytes(image), timeout_s=max(CALL_TIMEOUT_S, len(image) / 2 * 0.05))

    def sii_write_word(self, word: int, data: bytes) -> None:
        self._call("sii_write_word", word, bytes(data))

    def sdo_info(self) -> ObjectDictionary:
        # the SDO Information service reads every object's and entry's description: minutes on a large dictionary
        dictionary: ObjectDictionary = self._call("sdo_info", timeout_s=10 * CALL_TIMEOUT_S)
        return dictionary

    def exchange(self, outputs: bytes) -> bytes:
        data: bytes = self._call("exchange", bytes(outputs))
        return data

    def configure_dc(self, assign_activate: int, sync0_cycle_ns: int = 0, sync0_shift_ns: int = 0) -> None:
        self._call("configure_dc", assign_activate, sync0_cycle_ns, sync0_shift_ns)
