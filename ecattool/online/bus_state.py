"""Never stop a running machine by surprise (issue 35 item 4): before a master resets the bus (SOEM's
``config_init`` and KickCAT's bus init take every slave to INIT), each slave's AL state is read with one raw
frame, built by the frame code the simulator's bus uses (``ecattool.sim.bus.frame``): a BRD of the AL status
register (0x0130) counts the slaves, one APRD per slave reads its state. Where a slave is in SAFE-OP or OP the
command is refused in one line naming them, unless the user passed ``--reset-bus``; when the command ends, each
slave is put back in the state it was found in where ecattool can (INIT and PRE-OP; SAFE-OP and OP where the
command has a project that configures the slave), and what it could not is said (:func:`restore`).

The read needs what the master needs (a raw socket: root or CAP_NET_RAW); where it cannot be made, or nothing
answers, nothing is known and the master goes on as before (it says itself why it cannot open the interface).
"""

from __future__ import annotations

import socket
import threading
import time
from collections.abc import Callable, Sequence
from typing import Any

from ecattool.errors import TargetError
from ecattool.od.model import EcState
from ecattool.online.found import RUNNING as RUNNING
from ecattool.online.found import Found as Found
from ecattool.sim.bus import raw
from ecattool.sim.bus.frame import Cmd, Datagram, FrameError, make_frame, parse_frame
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


def read_states(ifname: str, sii: bool = False) -> list[Found] | None:
    """Each slave's AL status (and DC activation, :func:`read_found`) on ``ifname``, in bus order; with ``sii``
    each slave's SII image too (:func:`with_sii`); None where it cannot be read (no raw socket, no answer)."""
    try:
        sock = raw.open_raw(ifname)
    except TargetError:
        return None  # no raw socket here, or no such interface: the master's own open says why
    resent: list[bool] = []
    try:
        def exchange(frame: bytes, index: int) -> bytes | None:
            return _exchange(sock, frame, index, resent)

        found = read_found(exchange)
        return with_sii(exchange, found) if sii and found else found
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
                out[start + k] = f.replace(assign_activate=int.from_bytes(act.data[:2], "little"),
                                        sync0_cycle_ns=int.from_bytes(cycles.data[:4], "little"),
                                        sync1_cycle_ns=int.from_bytes(cycles.data[4:8], "little"))
    return out


#: the ESC's SII EEPROM interface (ETG.1000.4, 0x0500-0x050F): the configuration (0: the master, not the PDI,
#: drives the EEPROM), control/status with the word address behind it (one write starts a read), the data
EEPROM_CONFIG = 0x0500
EEPROM_CONTROL = 0x0502
EEPROM_DATA = 0x0508
#: control/status bits: read command, 8 octets per read (else 4), the error bits, busy
EE_CMD_READ = 0x0100
EE_READ_8 = 0x0040
EE_ERRORS = 0x7800
EE_BUSY = 0x8000
#: status reads one SII read waits for the EEPROM at most (each a frame of up to REPLY_S)
EE_POLLS = 20


def sii_words(exchange: Exchange, position: int) -> Callable[[int], bytes]:
    """``read_words(word) -> bytes`` of the slave at bus ``position`` through its ESC's EEPROM interface, with
    raw frames (auto-increment addressing: before the master assigns station addresses): the read command with
    the word address in one write of 0x0502-0x0507, then the status and the data read together until the
    EEPROM is not busy; 8 octets where the status says the ESC reads 8, else 4 (as SOEM's ``ec_readeeprom``)."""
    def read_words(word: int) -> bytes:
        start = EE_CMD_READ.to_bytes(2, "little") + word.to_bytes(4, "little")
        got = exchange(make_frame([Datagram.make(Cmd.APWR, -position, EEPROM_CONTROL, start, index=0x54)],
                                  _SRC), 0x54)
        frame = parse_frame(got) if got is not None else None
        if frame is None or not frame.datagrams[0].wkc:
            raise TargetError(f"slave {position}: the SII read command at word 0x{word:04X} got no answer")
        for _ in range(EE_POLLS):
            reads = [Datagram.make(Cmd.APRD, -position, EEPROM_CONTROL, 2, index=0x55),
                     Datagram.make(Cmd.APRD, -position, EEPROM_DATA, 8, index=0x55)]
            got = exchange(make_frame(reads, _SRC), 0x55)
            frame = parse_frame(got) if got is not None else None
            if frame is None or len(frame.datagrams) != 2 or not frame.datagrams[0].wkc:
                raise TargetError(f"slave {position}: the SII status at word 0x{word:04X} got no answer")
            status = int.from_bytes(frame.datagrams[0].data[:2], "little")
            if status & EE_BUSY:
                continue
            if status & EE_ERRORS:
                raise TargetError(f"slave {position}: the SII read at word 0x{word:04X} failed (EEPROM status "
                                  f"0x{status:04X})")
            return bytes(frame.datagrams[1].data[:8 if status & EE_READ_8 else 4])
        raise TargetError(f"slave {position}: the EEPROM stayed busy reading word 0x{word:04X}")

    return read_words


def with_sii(exchange: Exchange, found: list[Found]) -> list[Found]:
    """``found`` with each slave's SII image (:attr:`Found.sii`), read through its ESC's EEPROM interface
    (:func:`sii_words`, :func:`ecattool.sii.eeprom.read_sii`: the fixed area, then the categories to the end
    marker) before a master whose binding reads no SII (KickCAT's) opens the bus. The master is given the EEPROM
    first (0x0500 := 0); a slave whose EEPROM does not answer keeps None."""
    from ecattool.sii.eeprom import read_sii

    out = list(found)
    for k, f in enumerate(found):
        try:
            exchange(make_frame([Datagram.make(Cmd.APWR, -f.position, EEPROM_CONFIG, b"\x00", index=0x56)],
                                _SRC), 0x56)
            out[k] = f.replace(sii=read_sii(sii_words(exchange, f.position)))
        except TargetError:
            continue
    return out


def guard(ifname: str, reset_bus: bool, sii: bool = False) -> list[Found]:
    """The slaves' states before the bus is reset (with ``sii`` their SII images, :func:`with_sii`); a
    TargetError naming the slaves in SAFE-OP or OP unless ``reset_bus``."""
    found = read_states(ifname, sii) or []
    running = [f for f in found if f.state in RUNNING]
    if running and not reset_bus:
        raise TargetError(f"{', '.join(str(f) for f in running)} on {ifname!r} "
                          f"{'is' if len(running) == 1 else 'are'} running: opening the bus resets every slave to "
                          "INIT and would stop the machine; pass --reset-bus to do it anyway")
    return found


#: takes slaves (each with the state it was found in: SAFE-OP or OP) back to that state as a project configures
#: them, and returns one line per slave (what was done, or why not): ``ecattool.commission.runner.put_back``
#: with the project's slaves, given by the commands that have a project (``audit``, ``backup``)
PutBack = Callable[[Sequence[tuple[Any, EcState]]], list[str]]


def restore(slaves: Sequence[object], found: Sequence[Found], put_back: PutBack | None = None) -> list[str]:
    """Put each slave back in the state it was found in where ecattool can: INIT; PRE-OP (where the bus commands
    leave it); SAFE-OP and OP where the command has the slaves' configuration (``put_back``: a project). Returns
    one line per slave put back in SAFE-OP/OP, and per slave it could not put back."""
    notes: list[str] = []
    by_position = {int(getattr(s, "position", i)): s for i, s in enumerate(slaves)}
    running: list[tuple[Any, EcState]] = []
    init: list[tuple[object, Found]] = []
    for f in found:
        slave = by_position.get(f.position)
        if slave is None or f.state in (None, EcState.PREOP):
            continue
        if f.state in RUNNING and put_back is not None:
            running.append((slave, f.state))
        elif f.state in RUNNING or f.state is EcState.BOOT:
            notes.append(f"{f} was left in PRE-OP: ecattool has no configuration to take it back to {f.state.value}"
                         + (" (give the command a project)" if f.state in RUNNING else ""))
        else:
            init.append((slave, f))
    if running and put_back is not None:
        # before any slave goes back to INIT: a master maps the whole bus on the first SAFE-OP request (SOEM's
        # config_map reads every slave's PDO assignment over its mailbox, which a slave in INIT has not)
        notes.extend(put_back(running))
    for slave, f in init:
        try:
            slave.request_state(EcState.INIT)  # type: ignore[attr-defined]
        except Unsupported as exc:
            notes.append(f"{f} was left in PRE-OP: {exc}")
        except (TargetError, AttributeError) as exc:
            notes.append(f"{f} could not be put back in INIT: {exc}")
    return notes
