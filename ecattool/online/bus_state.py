"""Never stop a running machine by surprise (issue 35 item 4): before a master resets the bus (SOEM's
``config_init`` and KickCAT's bus init take every slave to INIT), each slave's AL state is read with one raw
frame, built by the frame code the simulator's bus uses (``ecattool.sim.bus.frame``): a BRD of the AL status
register (0x0130) counts the slaves, one APRD per slave reads its state. Where a slave is in SAFE-OP or OP the
command is refused in one line naming them, unless the user passed ``--reset-bus``; when the command ends, each
slave is put back in the state it was found in where ecattool can (INIT and PRE-OP), and what it could not is
said (:func:`restore`).

The read needs what the master needs (a raw socket: root or CAP_NET_RAW); where it cannot be made, or nothing
answers, nothing is known and the master goes on as before (it says itself why it cannot open the interface).
"""

from __future__ import annotations

import socket
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

from ecattool.errors import TargetError
from ecattool.od.model import EcState
from ecattool.sim.bus.frame import Cmd, Datagram, FrameError, make_frame, parse_frame
from ecattool.sim.bus import raw
from ecattool.target.base import Unsupported

#: the AL status register (ETG.1000.4, 0x0130): bits 0-3 the state, bit 4 the error indication
AL_STATUS = 0x0130
#: how long one raw read waits for its frame to come back, and how often it is sent
REPLY_S = 0.05
ATTEMPTS = 3
#: slaves read in one frame at most (12 octets of datagram head and data each: a frame holds ~120)
MAX_SLAVES = 100
#: the DC registers read per slave before the reset (SOEM's config_init clears 0x0981): the activation word
#: (0x0980-0x0981) and the SYNC0 and SYNC1 cycle times (0x09A0-0x09A7)
DC_ACTIVATION = 0x0980
DC_SYNC_CYCLES = 0x09A0
#: slaves whose DC registers one frame reads (2 datagrams, 34 octets, each: 40 fit an Ethernet frame)
DC_SLAVES_PER_FRAME = 40
_SRC = b"\x02\x00\x00\x00\xec\x01"
_STATES = {0x01: EcState.INIT, 0x02: EcState.PREOP, 0x03: EcState.BOOT, 0x04: EcState.SAFEOP, 0x08: EcState.OP}
RUNNING = (EcState.SAFEOP, EcState.OP)


@dataclass(frozen=True)
class Found:
    """A slave's AL state as found before the bus was reset (``state`` None: an AL status that names none), and
    its AL status code (0x0134)."""

    position: int
    al_status: int
    al_status_code: int = 0
    #: the slave's DC activation as found (ESC 0x0980-0x0981: the ESI's AssignActivate word; 0: no SYNC
    #: signal) and its SYNC0/SYNC1 cycle times (0x09A0, 0x09A4, ns); None where they were not read
    assign_activate: int | None = None
    sync0_cycle_ns: int | None = None
    sync1_cycle_ns: int | None = None

    @property
    def error(self) -> bool:
        """The AL status's error indication (bit 4): the slave refused a state change or left a state by itself."""
        return bool(self.al_status & 0x10)

    @property
    def state(self) -> EcState | None:
        return _STATES.get(self.al_status & 0x0F)

    def __str__(self) -> str:
        name = self.state.value if self.state is not None else f"AL status 0x{self.al_status:02X}"
        return f"slave {self.position} ({name}{', error' if self.al_status & 0x10 else ''})"


def _exchange(sock: socket.socket, frame: bytes, index: int, resent: list[bool] | None = None) -> bytes | None:
    """``frame`` sent; the frame that comes back processed (bit 1 of the source MAC set by the first slave).
    ``resent``: set to [True] where the frame was sent again (a late answer to the first may still come)."""
    for attempt in range(ATTEMPTS):
        if attempt and resent is not None:
            resent[:] = [True]
        sock.send(frame)
        deadline = time.monotonic() + REPLY_S
        while (left := deadline - time.monotonic()) > 0:
            sock.settimeout(left)
            try:
                got, addr = sock.recvfrom(2048)
            except (socket.timeout, BlockingIOError):
                break
            if len(addr) > 2 and addr[2] == socket.PACKET_OUTGOING:
                continue
            parsed = parse_frame(got)
            if parsed is not None and got[6:12] == bytes([_SRC[0] | 0x02]) + _SRC[1:] and parsed.datagrams \
                    and parsed.datagrams[0].index == index:
                return got
    return None


#: sends a frame and returns the frame that comes back with the datagram index given (None: no answer)
Exchange = Callable[[bytes, int], bytes | None]


def read_states(ifname: str) -> list[Found] | None:
    """Each slave's AL status (and DC activation, :func:`read_found`) on ``ifname``, in bus order; None where it
    cannot be read (no raw socket, no answer)."""
    try:
        sock = raw.open_raw(ifname)
    except TargetError:
        return None  # no raw socket here, or no such interface: the master's own open says why
    resent: list[bool] = []
    try:
        return read_found(lambda frame, index: _exchange(sock, frame, index, resent))
    except OSError:
        return None
    finally:
        if resent:
            _drain(sock)
        _close_aside(sock)


#: the threads closing state-read sockets (:func:`_close_aside`), until :func:`settle` has waited for them
_closing: list[threading.Thread] = []


def _close_aside(sock: socket.socket) -> None:
    """Close ``sock`` in a thread of its own: Linux releases a packet socket only after every CPU has let go of
    its receive hook (an RCU grace period, 10-15 ms on this project's virtual machines), a wait the command need
    not sit through while it loads the master (:func:`settle` before the master's process is forked)."""
    closing = threading.Thread(target=sock.close, name="ecattool-raw-close", daemon=True)
    closing.start()
    _closing.append(closing)


def settle(timeout_s: float = 1.0) -> None:
    """Wait (``timeout_s`` at most each) for the sockets :func:`_close_aside` is closing: a process forked before
    would hold the socket open (and a fork beside a running thread is what Python 3.12 warns about)."""
    while _closing:
        _closing.pop().join(timeout_s)


def _drain(sock: socket.socket) -> None:
    """Take the late answers to frames sent again off the wire before the master opens its own socket (which
    would read them as answers to its frames), until none comes for :data:`REPLY_S` (at most ``ATTEMPTS``)."""
    for _ in range(ATTEMPTS):
        sock.settimeout(REPLY_S)
        try:
            sock.recvfrom(2048)
        except (OSError, socket.timeout):
            return


def read_found(exchange: Exchange) -> list[Found] | None:
    """Each slave's AL status and DC registers, read through ``exchange``: a BRD of the AL status counts the
    slaves, one APRD per slave reads its state (:func:`_with_dc` its DC activation)."""
    try:
        got = exchange(make_frame([Datagram.make(Cmd.BRD, 0, AL_STATUS, 2, index=0x51)], _SRC), 0x51)
        if got is None:
            return None
        count = min(parse_frame(got).datagrams[0].wkc, MAX_SLAVES)  # type: ignore[union-attr]
        if count <= 0:
            return []
        # 0x0130-0x0135: the AL status and the AL status code (0x0134)
        reads = [Datagram.make(Cmd.APRD, -p, AL_STATUS, 6, index=0x52) for p in range(count)]
        got = exchange(make_frame(reads, _SRC), 0x52)
        if got is None:
            return None
        frame = parse_frame(got)
        assert frame is not None
        found = [Found(p, int.from_bytes(d.data[:2], "little"), int.from_bytes(d.data[4:6], "little"))
                 for p, d in enumerate(frame.datagrams) if d.wkc]
        return _with_dc(exchange, found)
    except FrameError:
        return None


def _with_dc(exchange: Exchange, found: list[Found]) -> list[Found]:
    """``found`` with each slave's DC activation and SYNC0/SYNC1 cycle times (:attr:`Found.assign_activate`),
    read before the master resets the bus (SOEM's ``config_init`` writes 0x0981 := 0): what a commissioned bus
    runs with, for ``project new --from-bus``. A slave that does not answer the read (no DC unit) keeps None."""
    out = list(found)
    for start in range(0, len(found), DC_SLAVES_PER_FRAME):
        part = found[start:start + DC_SLAVES_PER_FRAME]
        reads = []
        for f in part:
            reads.append(Datagram.make(Cmd.APRD, -f.position, DC_ACTIVATION, 2, index=0x53))
            reads.append(Datagram.make(Cmd.APRD, -f.position, DC_SYNC_CYCLES, 8, index=0x53))
        got = exchange(make_frame(reads, _SRC), 0x53)
        frame = parse_frame(got) if got is not None else None
        if frame is None or len(frame.datagrams) != 2 * len(part):
            continue
        for k, f in enumerate(part):
            act, cycles = frame.datagrams[2 * k], frame.datagrams[2 * k + 1]
            if act.wkc and cycles.wkc:
                out[start + k] = replace(f, assign_activate=int.from_bytes(act.data[:2], "little"),
                                         sync0_cycle_ns=int.from_bytes(cycles.data[:4], "little"),
                                         sync1_cycle_ns=int.from_bytes(cycles.data[4:8], "little"))
    return out


def guard(ifname: str, reset_bus: bool) -> list[Found]:
    """The slaves' states before the bus is reset; a TargetError naming the slaves in SAFE-OP or OP unless
    ``reset_bus``."""
    found = read_states(ifname) or []
    running = [f for f in found if f.state in RUNNING]
    if running and not reset_bus:
        raise TargetError(f"{', '.join(str(f) for f in running)} on {ifname!r} "
                          f"{'is' if len(running) == 1 else 'are'} running: opening the bus resets every slave to "
                          "INIT and would stop the machine; pass --reset-bus to do it anyway")
    return found


def restore(slaves: Sequence[object], found: Sequence[Found]) -> list[str]:
    """Put each slave back in the state it was found in where ecattool can (INIT; PRE-OP is where the bus commands
    leave it); returns what it could not, one line per slave."""
    notes = []
    by_position = {int(getattr(s, "position", i)): s for i, s in enumerate(slaves)}
    for f in found:
        slave = by_position.get(f.position)
        if slave is None or f.state in (None, EcState.PREOP):
            continue
        if f.state in RUNNING or f.state is EcState.BOOT:
            notes.append(f"{f} was left in PRE-OP: ecattool has no configuration to take it back to {f.state.value}")
            continue
        try:
            slave.request_state(EcState.INIT)  # type: ignore[attr-defined]
        except Unsupported as exc:
            notes.append(f"{f} was left in PRE-OP: {exc}")
        except (TargetError, AttributeError) as exc:
            notes.append(f"{f} could not be put back in INIT: {exc}")
    return notes
