"""The live bus through pysoem (SOEM): the commissioning adapter (:mod:`ecattool.target.pysoem`) for identity,
state and SDO, plus what SOEM offers besides: the SII EEPROM (``eeprom_read``/``eeprom_write``, word addressed),
the AL status code and the SDO Information service (``slave.od``: SOEM's OD list and descriptions)."""

from __future__ import annotations

from types import ModuleType
from typing import TYPE_CHECKING, Any

from ecattool.errors import TargetError
from ecattool.esi.model import Identity
from ecattool.od.model import Access, EcState, Entry, ObjectCode, ObjectDictionary, OdObject
from ecattool.od.types import lookup
from ecattool.online.live import LiveBus, read_sii

if TYPE_CHECKING:
    from ecattool.target.timeouts import BusLimits

#: SOEM's EEPROM access timeout per word, in microseconds (pysoem's default is 20 ms)
EEPROM_TIMEOUT_US = 20_000
_CODES = {7: ObjectCode.VAR, 8: ObjectCode.ARRAY, 9: ObjectCode.RECORD}
_STATES = (EcState.PREOP, EcState.SAFEOP, EcState.OP)


def access_of(word: int) -> Access:
    """The per-state access of an ObjectAccess word (bits 0-2 read, 3-5 write in PRE-OP, SAFE-OP, OP)."""
    return Access(frozenset(s for i, s in enumerate(_STATES) if word & (1 << i)),
                  frozenset(s for i, s in enumerate(_STATES) if word & (8 << i)))


def _text(value: Any) -> str:
    """pysoem gives names as bytes (the slave's VISIBLE_STRING)."""
    return value.decode("latin-1") if isinstance(value, (bytes, bytearray)) else str(value)


def _entry(sub: int, name: str, data_type: int, bits: int | None, access: int | None) -> Entry:
    dt = lookup(int(data_type))
    if bits is None:
        bits = dt.bits if dt is not None and dt.bits is not None else 0
    if access is None:  # SOEM reads no entry description of a VAR: its access is not known, PRE-OP..OP assumed
        return Entry(sub, name, dt, int(bits))
    mapping = ("R" if access & 0x40 else "") + ("T" if access & 0x80 else "")
    return Entry(sub, name, dt, int(bits), access=access_of(int(access)), pdo_mapping=mapping)


def dictionary_from_soem(objects: Any) -> ObjectDictionary:
    """pysoem's ``slave.od`` as an ecattool dictionary: objects with index, name, object code and data type, and
    for an ARRAY/RECORD its entries (name, data type, bit length, access word; SOEM lists every sub-index up to
    the highest, a gap with an empty name and no bits). A VAR comes without entries: its size is its type's."""
    od = ObjectDictionary()
    for o in objects:
        code = _CODES.get(int(o.object_code), ObjectCode.VAR)
        name = _text(o.name)
        entries: dict[int, Entry] = {}
        subs = list(o.entries or [])
        if code is ObjectCode.VAR or not subs:
            bits, access = getattr(o, "bit_length", None), getattr(o, "obj_access", None)
            entries[0] = _entry(0, name, int(o.data_type), bits or None, access if bits else None)
        else:
            for sub, e in enumerate(subs):
                if not e.name and not e.bit_length:
                    continue
                entries[sub] = _entry(sub, _text(e.name), int(e.data_type), int(e.bit_length), int(e.obj_access))
        od.add(OdObject(int(o.index), name, code, entries))
    return od


class PysoemLiveSlave:
    def __init__(self, slave: Any, module: ModuleType) -> None:
        self._t = slave  # ecattool.target.pysoem.PysoemSlave
        self._raw = slave.raw
        self._mod = module
        self.position = int(slave.position)

    def identity(self) -> Identity:
        ident: Identity = self._t.identity()
        return ident

    def sdo_upload(self, index: int, subindex: int, complete_access: bool = False, size: int | None = None) -> bytes:
        data: bytes = self._t.sdo_upload(index, subindex, complete_access, size=size)
        return data

    def sdo_download(self, index: int, subindex: int, data: bytes, complete_access: bool = False,
                     expect_reply: bool = True) -> None:
        self._t.sdo_download(index, subindex, data, complete_access, expect_reply)

    def state(self) -> EcState:
        state: EcState = self._t.state()
        return state

    def request_state(self, state: EcState) -> None:
        self._t.request_state(state)

    def al_status_code(self) -> int | None:
        self._t.state()  # reads the AL status of the bus
        return int(self._raw.al_status or 0)

    def _eeprom(self, fn: Any, word: int) -> Any:
        try:
            return fn()
        except self._mod.EepromError as exc:
            raise TargetError(f"slave {self.position}: SII word 0x{word:04X}: {exc}") from None

    def sii_read(self) -> bytes:
        return read_sii(lambda w: self._eeprom(lambda: bytes(self._raw.eeprom_read(w, EEPROM_TIMEOUT_US)), w))

    def sii_write(self, image: bytes) -> None:
        from ecattool.online.sii_access import write_sequence

        for w, word in write_sequence(image, self.sii_read()):
            self.sii_write_word(w, word)

    def sii_write_word(self, word: int, data: bytes) -> None:
        self._eeprom(lambda: self._raw.eeprom_write(word, data, EEPROM_TIMEOUT_US), word)

    def sdo_info(self) -> ObjectDictionary:
        try:
            objects = self._raw.od
        except (self._mod.SdoInfoError, self._mod.MailboxError, self._mod.WkcError) as exc:
            # tried once: what the refusal left in SOEM's error list must not fail the requests that follow
            self._t._master.drain_errors()
            raise TargetError(f"slave {self.position} offers no SDO Information ({exc})") from None
        return dictionary_from_soem(objects)


def open_pysoem(ifname: str, module: ModuleType | None = None, limits: BusLimits | None = None) -> LiveBus:
    """A pysoem master on ``ifname`` with every slave in PRE-OP, as a live bus. No process data is set up: the
    commands that read a bus never take a slave past PRE-OP. ``limits``: the slaves' timeouts."""
    from ecattool.target.pysoem import PysoemTarget

    target = PysoemTarget(ifname, pysoem_module=module, keep_cycling=False, limits=limits)
    slaves = [PysoemLiveSlave(s, target.pysoem) for s in target.slaves()]
    return LiveBus(f"pysoem:{ifname}", slaves, closer=target.close)
