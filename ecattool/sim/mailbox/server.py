"""The mailbox of one virtual slave: takes the frames the master writes to SM0, dispatches them by mailbox
type to CoE (SDO, SDO information), FoE, and queues the replies (and the drive's emergencies) for SM1."""

from __future__ import annotations

from collections import deque
from typing import TYPE_CHECKING

from ecattool.od.model import MAILBOX_STATES, EcState
from ecattool.sim.mailbox import coe, foe, sdoinfo
from ecattool.sim.mailbox.header import (
    HEADER_SIZE,
    PROTOCOL_TYPES,
    MailboxError,
    MailboxHeader,
    MailboxRefused,
    MailboxType,
    error_data,
    frame,
    next_counter,
)

if TYPE_CHECKING:
    from ecattool.sim.drive import Drive


#: replies (and emergencies) a mailbox keeps for SM1 at most
MAX_QUEUED_REPLIES = 64


class MailboxServer:
    """Mailbox protocols of one drive over SM0 (``out_size``, master → slave) and SM1 (``in_size``).

    ``handle`` takes one frame as the master wrote it (header + data, may be padded to the SM length);
    ``pending`` pops the next reply for SM1 (at most ``in_size`` octets) and turns the drive's new emergencies
    into CoE Emergency frames; ``repeat`` gives the last frame again (the master's mailbox repeat request).
    A request whose counter equals the previous request's (not 0) is a repeated write of the same request and
    is not executed twice. ``resize`` (the master configured SM0/SM1) restarts the mailbox: queued replies,
    transfers in progress and the counters are dropped, as on a slave whose mailbox is set up again.
    """

    def __init__(self, drive: "Drive", out_size: int, in_size: int) -> None:
        self.drive = drive
        self.out_size = out_size
        self.in_size = in_size
        self.sdo = coe.SdoServer(drive, out_size, in_size)
        self.info = sdoinfo.SdoInfoServer(drive, in_size)
        self.foe = foe.FoeServer(drive, out_size, in_size)
        #: replies not yet read through SM1, bounded: a master that writes requests and never reads the answers
        #: loses the oldest (a legitimate master reads each answer before its next request)
        self._replies: deque[bytes] = deque(maxlen=MAX_QUEUED_REPLIES)
        self._last: bytes | None = None
        self._rx_counter = 0
        self._tx_counter = 0
        self._emcy_seen = len(drive.emergencies)
        mb = drive.device.mailbox
        self.protocols = frozenset(PROTOCOL_TYPES[p] for p in (mb.protocols if mb is not None else ["CoE"])
                                   if p in PROTOCOL_TYPES)

    # ------------------------------------------------------------------------------------------
    def resize(self, out_size: int, in_size: int) -> None:
        """The master (re)configured SM0/SM1: new sizes, and the mailbox starts afresh."""
        self.out_size = self.sdo.out_size = self.foe.out_size = out_size
        self.in_size = self.sdo.in_size = self.info.in_size = self.foe.in_size = in_size
        self.reset()

    def reset(self) -> None:
        self._replies.clear()
        self._last = None
        self._rx_counter = 0
        self._tx_counter = 0
        self.sdo.reset()
        self.foe.reset()

    def handle(self, frame_bytes: bytes) -> None:
        if len(frame_bytes) < HEADER_SIZE:
            self._queue(MailboxType.ERROR, error_data(MailboxError.INVALID_HEADER))
            return
        header = MailboxHeader.parse(frame_bytes)
        if header.length > len(frame_bytes) - HEADER_SIZE:
            self._queue(MailboxType.ERROR, error_data(MailboxError.INVALID_SIZE))
            return
        if header.counter and header.counter == self._rx_counter:
            return  # the same request written again: it was executed once already
        self._rx_counter = header.counter
        data = bytes(frame_bytes[HEADER_SIZE:HEADER_SIZE + header.length])
        try:
            replies = self._dispatch(header.type, data)
        except MailboxRefused as refused:
            self._queue(MailboxType.ERROR, error_data(refused.code))
            return
        for mtype, payload in replies:
            self._queue(mtype, payload)

    def pending(self) -> bytes | None:
        self._drain_emergencies()
        if not self._replies:
            return None
        self._last = self._replies.popleft()
        return self._last

    def repeat(self) -> bytes | None:
        return self._last

    # ------------------------------------------------------------------------------------------
    def _dispatch(self, mtype: int, data: bytes) -> list[tuple[MailboxType, bytes]]:
        if mtype not in self.protocols:
            raise MailboxRefused(MailboxError.UNSUPPORTED_PROTOCOL)
        state = self.drive.state()
        if mtype == MailboxType.FOE:
            return [(MailboxType.FOE, r) for r in self.foe.handle(data)]
        if state is EcState.BOOT:  # only FoE lives in BOOT (firmware download)
            raise MailboxRefused(MailboxError.UNSUPPORTED_PROTOCOL)
        if mtype != MailboxType.COE:  # EoE, SoE, ...: named by the device, not simulated
            raise MailboxRefused(MailboxError.UNSUPPORTED_PROTOCOL)
        if len(data) < 2:
            raise MailboxRefused(MailboxError.SIZE_TOO_SHORT)
        service = data[1] >> 4
        if service == coe.SERVICE_SDO_REQUEST:
            return [(MailboxType.COE, r) for r in self.sdo.handle(data)]
        if service == coe.SERVICE_SDO_INFO:
            return [(MailboxType.COE, r) for r in self.info.handle(data)]
        raise MailboxRefused(MailboxError.SERVICE_NOT_SUPPORTED)

    def _queue(self, mtype: int, payload: bytes) -> None:
        self._tx_counter = next_counter(self._tx_counter)
        self._replies.append(frame(mtype, payload, self._tx_counter))

    def _drain_emergencies(self) -> None:
        emergencies = self.drive.emergencies
        if len(emergencies) == self._emcy_seen:
            return  # nothing new (every frame asks)
        new = emergencies[self._emcy_seen:]
        self._emcy_seen = len(emergencies)
        if MailboxType.COE not in self.protocols or self.drive.state() not in MAILBOX_STATES:
            return  # no CoE mailbox running: the message is lost, as on the bus
        for m in new:
            self._queue(MailboxType.COE, coe.emergency_data(m))
