"""``bus scan``: every slave of a live bus with its identity (from the SII and from 1018h, and where the two
differ), state and AL status code, mailbox protocols, DC support, and the library device or built-in family it
matches."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from ecattool.abort import al_status_text
from ecattool.errors import EcatToolError, SdoAbort
from ecattool.esi.model import Identity
from ecattool.online.library import Library, Match, family_device, family_match
from ecattool.online.live import LiveBus, sii_facts
from ecattool.target.base import Unsupported


def _ident_json(i: Identity | None) -> dict[str, int] | None:
    if i is None:
        return None
    return {"vendor_id": i.vendor_id, "product_code": i.product_code, "revision": i.revision, "serial": i.serial}


@dataclass
class ScannedSlave:
    position: int
    sii_identity: Identity | None
    coe_identity: Identity | None
    state: str
    al_status: int | None
    protocols: list[str] | None
    dc: bool | None
    name: str
    match: Match | None
    #: what could not be read, and why
    unknown: list[str] = field(default_factory=list)

    @property
    def identity(self) -> Identity | None:
        return self.sii_identity or self.coe_identity

    @property
    def identity_differs(self) -> list[str]:
        """The identity fields in which the SII and 1018h disagree."""
        a, b = self.sii_identity, self.coe_identity
        if a is None or b is None:
            return []
        return [f for f in ("vendor_id", "product_code", "revision") if getattr(a, f) != getattr(b, f)]

    def to_json(self) -> dict[str, Any]:
        return {"position": self.position, "name": self.name, "sii_identity": _ident_json(self.sii_identity),
                "coe_identity": _ident_json(self.coe_identity), "identity_differs": self.identity_differs,
                "state": self.state, "al_status": self.al_status,
                "al_status_text": None if self.al_status is None else al_status_text(self.al_status),
                "mailbox_protocols": self.protocols, "dc": self.dc,
                "match": None if self.match is None else self.match.to_json(), "unknown": self.unknown}


def _coe_identity(slave: Any) -> Identity:
    # 1018h's entries are UDINTs (CiA-301): no reply of more than 4 octets is taken
    v, p, r = (int.from_bytes(slave.sdo_upload(0x1018, sub, size=4), "little") for sub in (1, 2, 3))
    try:
        serial = int.from_bytes(slave.sdo_upload(0x1018, 4, size=4), "little")
    except SdoAbort:  # the serial number is optional (CiA-301)
        serial = 0
    return Identity(v, p, r, serial)


def scan_slave(slave: Any, library: Library | None = None) -> ScannedSlave:
    from ecattool.sii.image import parse

    unknown: list[str] = []
    sii_ident: Identity | None = None
    protocols: list[str] | None = None
    dc: bool | None = None
    name = ""
    coe_mailbox: bool | None = None  # unknown until the SII says
    try:
        sii = slave.sii_read()
        sii_facts(slave, sii)  # kept for the commands that scan first (the slave's name in a message)
        image = parse(sii, source=f"slave {slave.position} SII")
        h = image.header
        sii_ident = Identity(h.vendor_id, h.product_code, h.revision, h.serial)
        protocols = h.protocols if h.std_rx_size not in (0, 0xFFFF) else []
        coe_mailbox = "CoE" in protocols
        dc = bool(image.dc_opmodes) or None
        g = image.general
        if g is not None and 0 < g.name_idx <= len(image.strings):
            name = image.strings[g.name_idx - 1]
    except Unsupported as exc:
        unknown.append(f"SII: {exc}")
    except EcatToolError as exc:
        unknown.append(f"SII: {exc}")
    coe: Identity | None = None
    if coe_mailbox is not False:  # a slave without a CoE mailbox is never sent an SDO
        try:
            coe = _coe_identity(slave)
        except EcatToolError as exc:
            unknown.append(f"1018h: {exc}")
    if sii_ident is None and coe is None:
        try:
            coe = slave.identity()
        except EcatToolError as exc:
            unknown.append(f"identity: {exc}")
    ident = sii_ident or coe
    match = None
    if ident is not None:
        # among models sharing the identity, the one the SII's name names (as project new --from-bus writes it)
        match = (library.match(ident, name) if library is not None else None) or family_match(ident, name)
        if match is None:
            unknown.append("device: no library file or built-in family has this vendor and product code")
    if dc is None and match is not None:
        dc = _dc_from_match(match, library)
    al = slave.al_status_code()
    if al is None:
        unknown.append("AL status code: not given by this master")
    return ScannedSlave(slave.position, sii_ident, coe, slave.state().value, al, protocols, dc, name, match, unknown)


def _dc_from_match(match: Match, library: Library | None) -> bool | None:
    try:
        dev = library.device(match) if match.kind == "esi" and library is not None else family_device(match)
    except EcatToolError:
        return None
    return bool(dev.dc_opmodes)


def scan(bus: LiveBus, library: Library | None = None) -> list[ScannedSlave]:
    """Read every slave of ``bus`` (reads only: SII, 1018h, state, AL status)."""
    return [scan_slave(s, library) for s in bus.slaves]
