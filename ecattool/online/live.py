"""A live bus: the slaves behind a master as ecattool reads them (identity, state, AL status, SDO, SDO
Information, SII), on every target: the embedded simulator, SOEM through pysoem, KickCAT.

Every target implements the same :class:`LiveSlave`; what a master's binding cannot do raises
:class:`Unsupported` naming the target and what is missing (docs/at-the-machine.md, "What each target can do").
"""

from __future__ import annotations

import weakref
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

from ecattool.errors import InputError, TargetError
from ecattool.esi.model import Device, Identity
from ecattool.od.model import EcState, ObjectDictionary

#: the SII EEPROM is read up to this many bytes at most (a 32 kbit EEPROM; IgH reads to the end marker too)
SII_MAX_BYTES = 4096
#: the fixed area of the SII (words 0x00-0x3F)
SII_HEADER_BYTES = 128


class Unsupported(TargetError):
    """The target's master binding cannot do what was asked (e.g. SII access through KickCAT's Python module)."""


@runtime_checkable
class LiveSlave(Protocol):
    """One slave on a live bus."""

    position: int

    def identity(self) -> Identity:
        """The identity the master read from the slave's SII (KickCAT: from 1018h, it gives no SII access)."""
        ...

    def sdo_upload(self, index: int, subindex: int, complete_access: bool = False, size: int | None = None) -> bytes:
        """As :meth:`ecattool.target.base.SlaveTarget.sdo_upload`: ``size`` bounds the reply."""
        ...

    def sdo_download(self, index: int, subindex: int, data: bytes, complete_access: bool = False,
                     expect_reply: bool = True) -> None: ...

    def state(self) -> EcState: ...

    def al_status_code(self) -> int | None:
        """The AL status code register (0x0134), or None where the master does not give it."""
        ...

    def sii_read(self) -> bytes:
        """The SII image, from word 0 to the end of the category list."""
        ...

    def sii_write(self, image: bytes) -> None:
        """Write ``image`` to the SII EEPROM word by word (the caller has checked it), in the order of
        :func:`ecattool.online.sii_access.write_sequence` (the header and its CRC last)."""
        ...

    def sii_write_word(self, word: int, data: bytes) -> None:
        """Write one 16-bit word (2 bytes, little-endian) at word address ``word`` of the SII EEPROM."""
        ...

    def sdo_info(self) -> ObjectDictionary:
        """The dictionary the slave describes through the SDO Information service (raises SdoAbort/Unsupported
        where it offers none)."""
        ...


@dataclass
class LiveBus:
    """The slaves of one target, in bus order. ``spec`` names the target (``sim``, ``pysoem:eth0``…)."""

    spec: str
    slaves: list[Any]
    closer: Any = None
    #: the simulator's log of writes (SDO downloads, SII writes) since the bus was opened; None on a real master
    write_log: list[str] | None = None
    #: the devices a simulator bus was made of (its own dictionaries), by position
    devices: list[Device] = field(default_factory=list)
    #: what closing the bus could not do (a slave found in OP and left in PRE-OP), one line each
    notes: list[str] = field(default_factory=list)
    #: each slave's AL state as found before the master reset the bus (``bus_state.Found``; empty: not known)
    found: list[Any] = field(default_factory=list)
    #: whether the ``with`` block that used the bus ended with an exception (its error is what a user reads then)
    failed: bool = False

    def slave(self, position: int) -> Any:
        if not 0 <= position < len(self.slaves):
            raise InputError(f"no slave at position {position}: the bus on {self.spec} has {len(self.slaves)}")
        return self.slaves[position]

    def close(self) -> None:
        if self.closer is not None:
            self.closer()
            self.closer = None

    def __enter__(self) -> "LiveBus":
        return self

    def __exit__(self, *exc: object) -> None:
        self.failed = exc[0] is not None
        self.close()


def read_sii(read_words: Any, max_bytes: int = SII_MAX_BYTES) -> bytes:
    """An SII image read through ``read_words(word_address) -> bytes`` (4 or 8 bytes per read, as the ESC
    gives them): the fixed area, then category headers until the end marker 0xFFFF (IgH's ``sii_read`` reads
    the same range). A chain that runs past ``max_bytes`` ends there."""
    data = bytearray()

    def fill(upto: int) -> None:
        while len(data) < upto:
            chunk = bytes(read_words(len(data) // 2))
            if not chunk or len(chunk) % 2:
                raise TargetError(f"the SII read at word 0x{len(data) // 2:04X} returned {len(chunk)} bytes")
            data.extend(chunk)

    fill(SII_HEADER_BYTES)
    offset = SII_HEADER_BYTES
    while offset + 4 <= max_bytes:
        fill(offset + 2)  # the type first: nothing is read past an end marker
        cat_type = int.from_bytes(data[offset:offset + 2], "little")
        if cat_type == 0xFFFF:
            offset += 2
            break
        fill(offset + 4)
        size_words = int.from_bytes(data[offset + 2:offset + 4], "little")
        offset += 4 + 2 * size_words
        fill(min(offset, max_bytes))
    return bytes(data[:min(max(offset, SII_HEADER_BYTES), max_bytes)])


# --------------------------------------------------------------------------------------------- as found
#: the mailbox protocol bit of CoE in SII word 0x1C (ETG.2010)
MBX_COE = 0x0004


@dataclass(frozen=True)
class SiiFacts:
    """What a slave's SII says about how to talk to it: its mailbox protocols (SII word 0x1C; 0 where its
    standard receive mailbox, word 0x19, has no size: the slave has no mailbox) and its name (the general
    category's); ``protocols`` None where the target gives no SII (KickCAT's binding)."""

    protocols: int | None
    name: str = ""

    @property
    def coe(self) -> bool | None:
        """Whether SDOs can reach the slave: True, False (no CoE mailbox: never send it one), None (unknown)."""
        return None if self.protocols is None else bool(self.protocols & MBX_COE)


_FACTS: "weakref.WeakKeyDictionary[Any, SiiFacts]" = weakref.WeakKeyDictionary()


def sii_facts(slave: Any, sii: bytes | None = None) -> SiiFacts:
    """The :class:`SiiFacts` of ``slave``, read from its SII once (kept for as long as the slave object lives);
    ``sii``: its SII image where the caller has read it already."""
    try:
        return _FACTS[slave]
    except (KeyError, TypeError):
        pass
    from ecattool.sii.image import parse

    try:
        image = parse(slave.sii_read() if sii is None else sii, source=f"slave {slave.position} SII")
    except TargetError:  # Unsupported (no SII through this master), or the read failed: not known
        facts = SiiFacts(None)
    except InputError:  # an SII that does not parse: the header words are still the slave's
        facts = SiiFacts(None)
    else:
        h = image.header
        g = image.general
        name = image.strings[g.name_idx - 1] if g is not None and 0 < g.name_idx <= len(image.strings) else ""
        has_mailbox = h.std_rx_size not in (0, 0xFFFF) and h.mailbox_protocols != 0xFFFF
        facts = SiiFacts(h.mailbox_protocols if has_mailbox else 0, name)
    try:
        _FACTS[slave] = facts
    except TypeError:
        pass  # an object that takes no weak reference: read again next time
    return facts


def describe_slave(slave: Any) -> str:
    """"slave N (NAME, vendor 0x…, product 0x…, revision 0x…)": a slave named as a user finds it on the bus
    (what is not known is left out)."""
    parts = []
    try:
        known = _FACTS.get(slave)
    except TypeError:
        known = None
    name = known.name if known is not None else ""  # never a new SII read for a slave that may not answer
    if name:
        parts.append(name)
    try:
        ident = slave.identity()
    except Exception:  # noqa: BLE001 - naming a slave that does not answer must not fail in turn
        ident = None
    if ident is not None:
        parts.append(f"vendor 0x{ident.vendor_id:08X}, product 0x{ident.product_code:08X}, "
                     f"revision 0x{ident.revision:08X}")
    return f"slave {slave.position}" + (f" ({', '.join(parts)})" if parts else "")


# --------------------------------------------------------------------------------------------- simulator
class SimLiveSlave:
    """A simulated drive (:class:`ecattool.sim.Drive`) with its SII, as the virtual bus serves them."""

    def __init__(self, drive: Any, sii: bytes, log: list[str]) -> None:
        self.drive = drive
        self.position = int(drive.position)
        self.sii = bytes(sii)
        self._log = log
        self._seen = len(drive.events)

    def _note_writes(self) -> None:
        for e in self.drive.events[self._seen:]:
            # a write the drive refused was still sent: it counts
            if e.kind in ("sdo_download", "foe", "eeprom") or (e.kind == "sdo_abort" and e.data.get("op") != "upload"):
                self._log.append(f"slave {self.position}: {e.kind} {e.data}")
        self._seen = len(self.drive.events)

    def identity(self) -> Identity:
        from ecattool.sii.image import parse_header

        h = parse_header(self.sii)
        return Identity(h.vendor_id, h.product_code, h.revision, h.serial)

    def sdo_upload(self, index: int, subindex: int, complete_access: bool = False, size: int | None = None) -> bytes:
        try:
            return bytes(self.drive.sdo_upload(index, subindex, complete_access, size=size))
        finally:
            self._note_writes()

    def sdo_download(self, index: int, subindex: int, data: bytes, complete_access: bool = False,
                     expect_reply: bool = True) -> None:
        try:
            self.drive.sdo_download(index, subindex, data, complete_access, expect_reply)
        finally:
            self._note_writes()

    def state(self) -> EcState:
        state: EcState = self.drive.state()
        return state

    def request_state(self, state: EcState) -> None:
        self.drive.request_state(state)

    def dc_activation(self) -> tuple[int, int, int]:
        """The drive's DC as a master configured it (the ESC's 0x0980-0x0981 word, SYNC0 and SYNC1 cycle in ns)."""
        act, cycle = getattr(self.drive, "dc", (0, 0))
        return int(act), int(cycle), 0

    def al_status_code(self) -> int | None:
        for e in reversed(self.drive.events):
            if e.kind in ("state", "state_refused"):
                return int(e.data.get("al_status", 0))
        return 0

    def sii_read(self) -> bytes:
        return read_sii(lambda word: self.sii[2 * word:2 * word + 8].ljust(8, b"\xff"))

    def sii_write(self, image: bytes) -> None:
        from ecattool.online.sii_access import write_sequence

        self._log.append(f"slave {self.position}: SII write of {len(image)} bytes")
        for word, data in write_sequence(image, self.sii):
            self.sii_write_word(word, data)

    def sii_write_word(self, word: int, data: bytes) -> None:
        if len(data) != 2 or word < 0:
            raise TargetError(f"slave {self.position}: SII word 0x{word:04X}: a write is one word (2 bytes)")
        sii = bytearray(self.sii.ljust(2 * word + 2, b"\xff"))
        sii[2 * word:2 * word + 2] = data
        self.sii = bytes(sii)

    def sdo_info(self) -> ObjectDictionary:
        dictionary: ObjectDictionary = self.drive.device.dictionary
        return dictionary


def sim_bus(drives: Iterable[Any], spec: str = "sim") -> LiveBus:
    """A live bus of simulated drives (e.g. those of a ``SimTarget`` a test commissioned), each with the SII
    ``ecattool sii build`` makes of its device (as ``sim serve`` gives it)."""
    from ecattool.sii.builder import build

    log: list[str] = []
    slaves = []
    for i, d in enumerate(drives):
        d.position = i
        if d.state() is EcState.INIT:  # as a master's bus init does: the mailbox works from PRE-OP
            d.request_state(EcState.PREOP)
        slaves.append(SimLiveSlave(d, build(d.device).to_bytes(), log))
    return LiveBus(spec, slaves, write_log=log, devices=[s.drive.device for s in slaves])

