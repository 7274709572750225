"""The device model → an ESI document (ETG.2000 ``EtherCATInfo``), e.g. for a built-in drive family.

``device_to_esi(device)`` writes one ``Device`` with its identity, sync managers, FMMUs, PDOs, mailbox (CoE
details and init commands), DC op modes, EEPROM settings where the model has them, and the whole object
dictionary (data types declared, objects with defaults, limits, access and PDO mapping). The document validates
against the ETG.2000 schemas v1.14 and v1.17 and reads back (``ecattool.esi.load``) to the same model, up to
what ESI cannot say (docs/esi.md, "Writing an ESI"):

- an ARRAY object whose elements differ in type or flags, or whose sub-indices have gaps (``ArrayInfo`` states
  one element type and one ``Flags`` for sub-indices 1..n), becomes a RECORD;
- entry comments and units, ``Entry.category`` values other than ``m``/``o``/``c`` (the Control Techniques
  "slow" mark: the family rules carry it by vendor id), per-object source locations and ``Device.extra`` are
  not written; access ``const`` is written ``ro``; bit offsets inside records are laid out here; a limit
  outside the entry's type is not written;
- a VAR object's entry takes the object's name; a device without ``Physics`` (which the schema requires) is
  written ``YY``, one without a group in the group ``Devices``; characters XML cannot hold are dropped from
  texts (a string default holding them is written as ``DefaultData``).
"""

from __future__ import annotations

import re
from typing import Any

from lxml import etree

from ecattool.errors import EncodeError
from ecattool.esi.model import Device, Pdo
from ecattool.od.model import MAILBOX_STATES, EcState, Entry, ObjectCode, OdObject
from ecattool.od.types import BY_CODE, Kind, lookup

#: per-state access → the ESI Read/WriteRestrictions value
_RESTRICTIONS = {
    frozenset({EcState.PREOP}): "PreOP",
    frozenset({EcState.SAFEOP}): "SafeOP",
    frozenset({EcState.OP}): "OP",
    frozenset({EcState.PREOP, EcState.SAFEOP}): "PreOP_SafeOP",
    frozenset({EcState.PREOP, EcState.OP}): "PreOP_OP",
    frozenset({EcState.SAFEOP, EcState.OP}): "SafeOP_OP",
}
#: the order of the mailbox protocol elements in the schema
_PROTOCOL_ORDER = ("AoE", "EoE", "CoE", "FoE", "SoE", "VoE")


def _hexdec(value: int) -> str:
    """ESI HexDecValue: ``#x`` hex for non-negative numbers, decimal for negative ones."""
    return f"#x{value:X}" if value >= 0 else str(value)


def _bool(value: bool) -> str:
    return "true" if value else "false"


#: characters XML 1.0 cannot hold (a vendor name with a control character, read from another ESI)
_NOT_XML = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ufffe\uffff]")


def _sub(parent: Any, tag: str, text: str | None = None, **attrs: str) -> Any:
    el = etree.SubElement(parent, tag, {k: _NOT_XML.sub("", v) for k, v in attrs.items()})
    if text is not None:
        el.text = _NOT_XML.sub("", text)
    return el


_UNIT_BITS = {Kind.STRING: 8, Kind.UNICODE: 16, Kind.OCTETS: 8}
_SIZED = {Kind.STRING: "STRING", Kind.UNICODE: "UNICODE_STRING", Kind.OCTETS: "OCTET_STRING"}


def _type_name(entry: Entry) -> str:
    """A type name the reader resolves to the entry's type: the entry's own name where it is a standard one
    (``UDINT``, ``UNSIGNED32``, ``BIT2``), ``STRING(n)``/``OCTET_STRING(n)`` for sized strings and octet
    blobs, else the standard name of its type (a vendor alias such as ``DT0800`` says nothing by itself here);
    an entry of unknown type keeps its name."""
    dt = entry.datatype
    name = entry.type_name or (dt.name if dt is not None else f"BIT{entry.bit_size}")
    if dt is None:
        return name
    if dt.kind in _SIZED and dt.code != 0x000F:  # DOMAIN keeps its name: its size is the object's
        return f"{_SIZED[dt.kind]}({entry.bit_size // _UNIT_BITS[dt.kind]})"
    own = lookup(name)
    if own is not None and (own.code, own.kind, own.bits) == (dt.code, dt.kind, dt.bits):
        return name
    return BY_CODE[dt.code].name if dt.code in BY_CODE else name


class _Types:
    """The ``DataTypes`` of the document: each name declared once, in first-use order."""

    def __init__(self) -> None:
        self.declared: dict[str, Any] = {}
        self.parent = etree.Element("DataTypes")

    def base(self, entry: Entry) -> str:
        """The declared type of one entry (see :func:`_type_name`), declared on first use."""
        name = _type_name(entry)
        if name not in self.declared:
            el = _sub(self.parent, "DataType")
            _sub(el, "Name", name)
            _sub(el, "BitSize", str(entry.bit_size))
            self.declared[name] = el
        return name

    def enum(self, entry: Entry, owner: str) -> str:
        name = f"{owner}EN{entry.bit_size}"
        el = self.add(name, self.base(entry))
        _sub(el, "BitSize", str(entry.bit_size))
        for value, text in sorted(entry.enum.items()):
            info = _sub(el, "EnumInfo")
            _sub(info, "Text", text)
            _sub(info, "Enum", str(value))
        self.declared[name] = el
        return name

    def of(self, entry: Entry, owner: str) -> str:
        return self.enum(entry, owner) if entry.enum else self.base(entry)

    def add(self, name: str, base: str | None = None) -> Any:
        el = _sub(self.parent, "DataType")
        _sub(el, "Name", name)
        if base is not None:
            _sub(el, "BaseType", base)
        self.declared[name] = el
        return el


def _flags(parent: Any, entry: Entry) -> None:
    flags = _sub(parent, "Flags")
    access = entry.access
    text = "rw" if access.writable() and access.readable() else "wo" if access.writable() else "ro"
    attrs = {}
    for key, states in (("ReadRestrictions", access.read), ("WriteRestrictions", access.write)):
        if states and states != MAILBOX_STATES and frozenset(states) in _RESTRICTIONS:
            attrs[key] = _RESTRICTIONS[frozenset(states)]
    _sub(flags, "Access", text, **attrs)
    if entry.category in ("m", "o", "c"):
        _sub(flags, "Category", entry.category)
    if entry.pdo_mapping:
        _sub(flags, "PdoMapping", entry.pdo_mapping)
    if entry.backup:
        _sub(flags, "Backup", "1")
    if entry.setting:
        _sub(flags, "Setting", "1")


def _values(parent: Any, entry: Entry) -> None:
    """``Info`` content of one entry: DefaultString, or MinData/MaxData/DefaultData (encoded as on the wire,
    so floats and every integer size read back exactly)."""
    dt = entry.datatype
    if dt is not None and dt.kind is Kind.STRING and entry.default is not None:
        text = entry.default.decode("latin-1")
        if not _NOT_XML.search(text):  # else (NUL padding …) as DefaultData, byte-exact
            _sub(parent, "DefaultString", text)
            return
    for tag, value in (("MinData", entry.minimum), ("MaxData", entry.maximum)):
        if value is None or dt is None or not dt.is_numeric:
            continue
        try:
            raw = entry.encode(value)
        except Exception:  # a limit outside the type is not written (the reader would not take it either)
            continue
        _sub(parent, tag, raw.hex().upper())
    if entry.default is not None:
        _sub(parent, "DefaultData", entry.default.hex().upper())


def _uniform_array(obj: OdObject) -> bool:
    """An ARRAY in CiA 301's sense: elements 1..n of one type, size and flags (ESI ``ArrayInfo``)."""
    if obj.object_code is not ObjectCode.ARRAY or 0 not in obj.entries:
        return False
    elements = [e for e in obj if e.subindex > 0]
    if [e.subindex for e in elements] != list(range(1, len(elements) + 1)):
        return False
    if not elements:
        return True  # sub-index 0 only (an SM assignment with no PDO): ArrayInfo with no elements
    first = elements[0]
    key = (first.type_name, first.datatype, first.bit_size, first.access, first.pdo_mapping, first.enum,
           first.category, first.backup, first.setting)
    return all((e.type_name, e.datatype, e.bit_size, e.access, e.pdo_mapping, e.enum, e.category, e.backup,
                e.setting) == key for e in elements)


def _align(offset: int, bits: int) -> int:
    step = 16 if bits >= 16 else 8 if bits % 8 == 0 else 1
    return -(-offset // step) * step


def _sub_names(entries: list[Entry]) -> dict[int, str]:
    """Sub-item names unique within the object, as ETG.2000's SubItemKey requires (a DataType's SubItem names
    are its key): a later sub-item that repeats a name (EDS files name several "Reserved") gets its sub-index,
    ``Reserved_03``. The object's Info/SubItem names use the same names, so the two still match."""
    out: dict[int, str] = {}
    used: set[str] = set()
    for e in entries:
        name = e.name or f"SubIndex {e.subindex:03d}"
        if name in used:
            name = f"{name}_{e.subindex:02X}"
            while name in used:
                name += "_"
        used.add(name)
        out[e.subindex] = name
    return out


def _record_type(types: _Types, obj: OdObject) -> tuple[str, int]:
    """The DataType of a RECORD/ARRAY object; returns (name, bit size)."""
    name = f"DT{obj.index:04X}"
    el = types.add(name)
    bits_el = _sub(el, "BitSize", "0")
    offset = 0
    entries = list(obj)
    if _uniform_array(obj):
        sub0, elements = entries[0], entries[1:]
        first = elements[0] if elements else sub0  # no elements: any type, none is used
        arr = f"{name}ARR"
        arr_el = types.add(arr, types.of(first, f"{name}E"))
        _sub(arr_el, "BitSize", str(first.bit_size * len(elements)))
        info = _sub(arr_el, "ArrayInfo")
        _sub(info, "LBound", "1")
        _sub(info, "Elements", str(len(elements)))
        layout: list[tuple[Entry, str, str | None]] = [(sub0, types.of(sub0, f"{name}S00"), "0"),
                                                        (first, arr, None)]
    else:
        layout = [(e, types.of(e, f"{name}S{e.subindex:02X}"), str(e.subindex)) for e in entries]
    names = _sub_names(entries)
    for e, type_name, subidx in layout:
        size = e.bit_size if subidx is not None else e.bit_size * (len(entries) - 1)
        offset = _align(offset, e.bit_size)
        si = _sub(el, "SubItem")
        if subidx is not None:
            _sub(si, "SubIdx", subidx)
        _sub(si, "Name", names[e.subindex] if subidx is not None else "Elements")
        _sub(si, "Type", type_name)
        _sub(si, "BitSize", str(size))
        _sub(si, "BitOffs", str(offset))
        _flags(si, e)
        offset += size
    bits_el.text = str(offset)
    return name, offset


def _object(objects: Any, types: _Types, obj: OdObject) -> None:
    el = _sub(objects, "Object")
    _sub(el, "Index", _hexdec(obj.index))
    _sub(el, "Name", obj.name)
    entries = list(obj)
    if obj.object_code is ObjectCode.VAR and len(entries) == 1 and entries[0].subindex == 0:
        e = entries[0]
        _sub(el, "Type", types.of(e, f"DT{obj.index:04X}"))
        _sub(el, "BitSize", str(e.bit_size))
        info = _sub(el, "Info")
        _values(info, e)
        if not len(info):
            el.remove(info)
        _flags(el, e)
        return
    type_name, bits = _record_type(types, obj)
    _sub(el, "Type", type_name)
    _sub(el, "BitSize", str(bits))
    info = _sub(el, "Info")
    # the names the DataType lists its SubItems by (an ArrayInfo array lists one, "Elements": names may repeat)
    names = {e.subindex: e.name for e in entries} if _uniform_array(obj) else _sub_names(entries)
    for e in entries:  # one per sub-index, in order: the reader matches them by name, else by position
        si = _sub(info, "SubItem")
        _sub(si, "Name", names[e.subindex])
        _values(_sub(si, "Info"), e)


def _pdo(parent: Any, tag: str, pdo: Pdo) -> None:
    attrs = {}
    if pdo.fixed:
        attrs["Fixed"] = "true"
    if pdo.mandatory:
        attrs["Mandatory"] = "true"
    if pdo.sm is not None:
        attrs["Sm"] = str(pdo.sm)
    el = _sub(parent, tag, **attrs)
    _sub(el, "Index", _hexdec(pdo.index))
    _sub(el, "Name", pdo.name)
    for x in pdo.excludes:
        _sub(el, "Exclude", _hexdec(x))
    for e in pdo.entries:
        entry = _sub(el, "Entry")
        _sub(entry, "Index", _hexdec(e.index))
        if not e.is_gap:
            _sub(entry, "SubIndex", str(e.subindex))
        _sub(entry, "BitLen", str(e.bit_len))
        if not e.is_gap:
            if e.name:
                _sub(entry, "Name", e.name)
            if e.data_type:
                _sub(entry, "DataType", e.data_type)


def _mailbox(parent: Any, device: Device) -> None:
    mbx = device.mailbox
    if mbx is None:
        return
    el = _sub(parent, "Mailbox", **({"DataLinkLayer": "true"} if mbx.data_link_layer else {}))
    for proto in sorted(set(mbx.protocols), key=lambda p: _PROTOCOL_ORDER.index(p) if p in _PROTOCOL_ORDER else 9):
        if proto not in _PROTOCOL_ORDER:
            continue
        p = _sub(el, proto)
        if proto == "CoE" and mbx.coe is not None:
            c = mbx.coe
            for key, on in (("SdoInfo", c.sdo_info), ("PdoAssign", c.pdo_assign), ("PdoConfig", c.pdo_config),
                            ("PdoUpload", c.pdo_upload), ("CompleteAccess", c.complete_access)):
                p.set(key, _bool(on))
            if c.eds_file:
                p.set("EdsFile", c.eds_file)
            p.set("SegmentedSdo", _bool(c.segmented_sdo))
        if proto in ("CoE", "SoE"):
            for cmd in mbx.init_cmds:
                if cmd.protocol == proto:
                    _init_cmd(p, cmd)


def _init_cmd(parent: Any, cmd: Any) -> None:
    attrs = {}
    if cmd.fixed:
        attrs["Fixed"] = "true"
    if cmd.complete_access:
        attrs["CompleteAccess"] = "true"
    el = _sub(parent, "InitCmd", **attrs)
    for t in cmd.transitions:
        _sub(el, "Transition", t)
    if cmd.protocol == "SoE":
        _sub(el, "IDN", str(cmd.index))
    else:
        _sub(el, "Index", _hexdec(cmd.index))
        _sub(el, "SubIndex", str(cmd.subindex))
    _sub(el, "Data", cmd.data.hex().upper())
    if cmd.comment:
        _sub(el, "Comment", cmd.comment)


def _dc(parent: Any, device: Device) -> None:
    if not device.dc_opmodes:
        return
    dc = _sub(parent, "Dc")
    for m in device.dc_opmodes:
        om = _sub(dc, "OpMode")
        _sub(om, "Name", m.name)
        if m.desc:
            _sub(om, "Desc", m.desc)
        _sub(om, "AssignActivate", _hexdec(m.assign_activate))
        for tag, value, factor in (("CycleTimeSync0", m.cycle_time_sync0, m.cycle_time_sync0_factor),
                                   ("ShiftTimeSync0", m.shift_time_sync0, m.shift_time_sync0_factor),
                                   ("CycleTimeSync1", m.cycle_time_sync1, m.cycle_time_sync1_factor),
                                   ("ShiftTimeSync1", m.shift_time_sync1, m.shift_time_sync1_factor)):
            if value is not None:
                _sub(om, tag, str(value), **({"Factor": str(factor)} if factor is not None else {}))


def _eeprom(parent: Any, device: Device) -> None:
    ee = device.eeprom
    if ee is None:
        return
    el = _sub(parent, "Eeprom")
    if ee.data:
        _sub(el, "Data", ee.data.hex().upper())
        return
    _sub(el, "ByteSize", str(ee.byte_size or 2048))
    _sub(el, "ConfigData", (ee.config_data or bytes(14)).hex().upper())
    if ee.bootstrap:
        _sub(el, "BootStrap", ee.bootstrap.hex().upper())
    for cat in ee.categories:
        c = _sub(el, "Category")
        _sub(c, "CatNo", str(cat.cat_no))
        _sub(c, "Data", cat.data.hex().upper())


def device_to_esi(device: Device, *, vendor_name: str = "") -> bytes:
    """An ETG.2000 ESI document (UTF-8 bytes) describing ``device``; ``vendor_name`` names the vendor."""
    root = etree.Element("EtherCATInfo", {"Version": "1.14"})
    vendor = _sub(root, "Vendor")
    _sub(vendor, "Id", _hexdec(device.vendor_id))
    _sub(vendor, "Name", vendor_name or f"Vendor {device.vendor_id:#010x}")
    desc = _sub(root, "Descriptions")
    groups = _sub(desc, "Groups")
    group_type = device.group_type or "Devices"
    g = _sub(groups, "Group")
    _sub(g, "Type", group_type)
    _sub(g, "Name", device.group_name or group_type)
    # Physics is required; a device without one (an IgH-made ESI) gets the usual two EBUS/MII ports
    dev = _sub(_sub(desc, "Devices"), "Device", Physics=device.physics or "YY")
    _sub(dev, "Type", device.type_name, ProductCode=_hexdec(device.product_code),
         RevisionNo=_hexdec(device.revision))
    _sub(dev, "Name", device.name or device.type_name, LcId="1033")
    if device.url:
        _sub(dev, "URL", device.url)
    if device.ebus_current_ma is not None:
        _sub(_sub(_sub(dev, "Info"), "Electrical"), "EBusCurrent", str(device.ebus_current_ma))
    _sub(dev, "GroupType", group_type)
    profile = _sub(dev, "Profile")
    if device.profile_no is not None:
        _sub(profile, "ProfileNo", str(device.profile_no))
    if len(device.dictionary):
        types = _Types()
        dictionary = _sub(profile, "Dictionary")
        dictionary.append(types.parent)
        objects = _sub(dictionary, "Objects")
        for obj in device.dictionary:
            _object(objects, types, obj)
    if not len(profile):
        dev.remove(profile)
    for f in device.fmmus:
        attrs = {k: str(v) for k, v in (("Sm", f.sm), ("Su", f.su)) if v is not None}
        _sub(dev, "Fmmu", f.kind, **attrs)
    for sm in sorted(device.sync_managers, key=lambda s: s.number):
        attrs = {"StartAddress": _hexdec(sm.start_address), "ControlByte": _hexdec(sm.control_byte),
                 "Enable": str(int(sm.enable))}
        for key, value in (("DefaultSize", sm.default_size), ("MinSize", sm.min_size), ("MaxSize", sm.max_size)):
            if value is not None:
                attrs[key] = str(value)
        if sm.virtual:
            attrs["Virtual"] = "true"
        if sm.op_only:
            attrs["OpOnly"] = "true"
        _sub(dev, "Sm", sm.kind, **attrs)
    for p in device.rx_pdos:
        _pdo(dev, "RxPdo", p)
    for p in device.tx_pdos:
        _pdo(dev, "TxPdo", p)
    _mailbox(dev, device)
    _dc(dev, device)
    _eeprom(dev, device)
    etree.indent(root, space="  ")
    out: bytes = etree.tostring(root, xml_declaration=True, encoding="UTF-8", pretty_print=True)
    check_own_output(root, device)
    return out


def check_own_output(root: Any, device: Device) -> None:
    """The identity constraints ETG.2000's schema states for a dictionary (the XSDs are not shipped, so these are
    checked here, and every ``esi export`` is checked): DataType names unique (DataTypeKey), SubItem names
    unique within a DataType (SubItemKey), and every DataType a BaseType, SubItem or Object names defined
    (BaseTypeRef, SubItemTypeRef, ObjectTypesRef). An ESI that breaks one is never returned: EncodeError."""
    label = device.type_name or device.name or "device"
    for dictionary in root.iter("Dictionary"):
        defined: set[str] = set()
        for dt in dictionary.iterfind("DataTypes/DataType"):
            name = dt.findtext("Name") or ""
            if name in defined:
                raise EncodeError(f"{label}: the ESI would define DataType {name!r} twice (ETG.2000 DataTypeKey)")
            defined.add(name)
            subs = [si.findtext("Name") or "" for si in dt.iterfind("SubItem")]
            dup = sorted({n for n in subs if subs.count(n) > 1})
            if dup:
                raise EncodeError(f"{label}: DataType {name!r} would have SubItems sharing the name(s) "
                                  f"{', '.join(repr(d) for d in dup)} (ETG.2000 SubItemKey)")
        refs = [(dt.findtext("BaseType"), "BaseType") for dt in dictionary.iterfind("DataTypes/DataType")]
        refs += [(si.findtext("Type"), "SubItem Type") for si in dictionary.iterfind("DataTypes/DataType/SubItem")]
        refs += [(o.findtext("Type"), "Object Type") for o in dictionary.iterfind("Objects/Object")]
        for ref, what in refs:
            if ref is not None and ref not in defined:
                raise EncodeError(f"{label}: {what} {ref!r} names no DataType of the ESI (ETG.2000 key reference)")


__all__ = ["check_own_output", "device_to_esi"]
