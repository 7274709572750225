"""CANopen EDS and DCF files → the device model, read by python-canopen's EDS reader.

A drive without an ESI often has a CANopen EDS (CiA 306): the same object dictionary, but nothing of the
EtherCAT side. :func:`load_eds_bytes` lets ``canopen.objectdictionary.eds.import_eds`` read the file (we keep
no EDS parser of our own) and turns its dictionary into a :class:`~ecattool.esi.model.Device`; what an EDS
lacks compared to an ESI is derived (docs/esi.md, "CANopen EDS and DCF files"):

- PDOs: one per mapping object 1600h–17FFh (RxPDO) and 1A00h–1BFFh (TxPDO), its entries from the EDS's
  default mapping (in a DCF the configured ``ParameterValue``); Fixed when the mapping's sub-index 0 is not
  writable;
- assignment: 1C12h/1C13h's defaults where the EDS has them, else the CANopen meaning of "this PDO is used":
  the COB-ID of its communication parameter (1400h+n / 1800h+n sub-index 1) has bit 31 (invalid) clear and
  it maps at least one object;
- sync managers: the standard layout of the built-in families (SM0/SM1 mailbox, SM2 outputs, SM3 inputs at the
  usual addresses), SM2/SM3 default size = the assigned PDOs, maximum = 8 bytes (a CAN frame) per mapping object;
- mailbox: CoE (PdoAssign/PdoConfig where the mapping objects are writable); DC op modes: free run, and DC
  SYNC0 where the EDS has 1005h (the device consumes SYNC on CANopen).

The file is untrusted input: bounded in size, and every malformed line is a one-line :class:`InputError`
naming the file and line. python-canopen's own complaints and anything it leaves unread become located
warnings on the returned :class:`EsiFile`.
"""

from __future__ import annotations

import configparser
import io
import logging
import re
from pathlib import Path
from types import TracebackType
from typing import Any

from ecattool.errors import InputError, Location
from ecattool.esi.derive import DC_FREERUN, DC_SYNC0, STANDARD_FMMUS, pdos_from_dictionary, standard_sync_managers
from ecattool.esi.model import (
    CoeDetails,
    DcOpMode,
    Device,
    Direction,
    EsiFile,
    Fmmu,
    Identity,
    Mailbox,
    Pdo,
)
from ecattool.findings import Finding, Severity
from ecattool.od.model import Access, Entry, ObjectCode, ObjectDictionary, OdObject
from ecattool.od.types import lookup

#: EDS files are a few kB to a few hundred kB; anything above this is refused before it is read
MAX_EDS_BYTES = 16 * 1024 * 1024

_SECTION = re.compile(r"^\s*\[([^\]]*)\]")
_OPTION = re.compile(r"^\s*([^=:;#\[\s][^=:]*?)\s*[=:]")
_INDEX = re.compile(r"^([0-9A-Fa-f]{4})$")
_SUB = re.compile(r"^([0-9A-Fa-f]{4})[Ss]ub([0-9A-Fa-f]+)$")
_RULE = "eds-read"


def looks_like_eds(data: bytes) -> bool:
    """Whether ``data`` is an INI-style EDS/DCF (first significant line a ``[section]`` or a ``;`` comment)
    rather than XML."""
    head = data[:4096].lstrip(b"\xef\xbb\xbf").lstrip()
    return head.startswith((b"[", b";"))


def load_eds(path: str | Path) -> EsiFile:
    """Read an EDS or DCF file (see :func:`load_eds_bytes`)."""
    from ecattool.fileio import read_bytes

    return load_eds_bytes(read_bytes(path, MAX_EDS_BYTES), str(path))


class _Lines:
    """Where each ``[section]`` and each ``key=`` line of the text is, and its raw value (for located messages
    only; the values themselves are read by python-canopen)."""

    def __init__(self, text: str) -> None:
        self.sections: dict[str, int] = {}
        self.options: dict[tuple[str, str], tuple[int, str]] = {}
        self.order: list[str] = []
        current = ""
        for n, line in enumerate(text.splitlines(), start=1):
            m = _SECTION.match(line)
            if m:
                current = m.group(1).strip()
                self.sections.setdefault(current, n)
                self.order.append(current)
                continue
            o = _OPTION.match(line)
            if o and current:
                value = line.split("=", 1)[1] if "=" in line else ""
                self.options.setdefault((current, o.group(1)), (n, value.split(";", 1)[0].strip()))

    def of(self, section: str, option: str | None = None) -> int | None:
        if option is not None and (section, option) in self.options:
            return self.options[(section, option)][0]
        return self.sections.get(section)

    def value(self, section: str, option: str) -> str | None:
        found = self.options.get((section, option))
        return found[1] if found is not None else None


class _Warnings(logging.Handler):
    """Collects python-canopen's log warnings during one import."""

    def __init__(self) -> None:
        super().__init__(logging.WARNING)
        self.messages: list[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.messages.append(record.getMessage())


def _decode(data: bytes) -> str:
    data = data.removeprefix(b"\xef\xbb\xbf")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:  # CiA 306 says ASCII; vendors write Latin-1 (degree signs, umlauts)
        return data.decode("latin-1")


def _failing_section(tb: TracebackType | None) -> str | None:
    """The EDS section python-canopen was reading when it raised (its ``section`` variable)."""
    found = None
    while tb is not None:
        if tb.tb_frame.f_globals.get("__name__", "").startswith("canopen."):
            value = tb.tb_frame.f_locals.get("section")
            if isinstance(value, str):
                found = value
        tb = tb.tb_next
    return found


def _error(exc: BaseException, lines: _Lines, source: str) -> InputError:
    """A one-line located error for anything python-canopen raised on a malformed file."""
    if isinstance(exc, configparser.MissingSectionHeaderError):
        return InputError(f"not an EDS/DCF file: text before the first [section]: {exc.line.strip()!r}",
                          Location(source, exc.lineno))
    if isinstance(exc, configparser.DuplicateSectionError):
        return InputError(f"section [{exc.section}] appears twice (first at line {lines.of(exc.section)})",
                          Location(source, exc.lineno))
    if isinstance(exc, configparser.DuplicateOptionError):
        return InputError(f"{exc.option}= appears twice in section [{exc.section}]", Location(source, exc.lineno))
    if isinstance(exc, configparser.ParsingError):
        lineno, text = exc.errors[0] if exc.errors else (None, "")
        shown = str(text).strip("'\"").replace("\\n", "").strip()  # configparser keeps the line's repr
        return InputError(f"not an EDS/DCF line (expected [section], key=value or ; comment): {shown!r}",
                          Location(source, lineno))
    if isinstance(exc, configparser.NoOptionError):
        return InputError(f"section [{exc.section}] has no {exc.option}= (CiA 306 requires it)",
                          Location(source, lines.of(exc.section)))
    section = _failing_section(exc.__traceback__)
    if isinstance(exc, ValueError):
        # the key whose value did not convert, where the message quotes that value (its own section first)
        for (sec, option), (n, value) in sorted(lines.options.items(), key=lambda kv: kv[0][0] != section):
            if value and f"'{value}'" in str(exc):
                return InputError(f"[{sec}] {option}={value} is not a number or not a valid choice",
                                  Location(source, n))
    if isinstance(exc, configparser.NoSectionError):
        return InputError(f"refers to a section [{exc.section}] the file does not have",
                          Location(source, lines.of(section) if section else None))
    if section is None:
        return InputError(f"not a readable EDS/DCF file: {exc}", Location(source))
    line = lines.of(section)
    what = str(exc).strip("'\"") or type(exc).__name__
    if isinstance(exc, KeyError):
        m = _SUB.match(section)
        parent = f"[{m.group(1)}]" if m else "its object"
        return InputError(f"section [{section}] is a sub-index of {parent}, which the file does not define",
                          Location(source, line))
    if isinstance(exc, ValueError):
        return InputError(f"section [{section}]: a value is not a number or not a valid choice ({what})",
                          Location(source, line))
    return InputError(f"section [{section}] cannot be read: {what}", Location(source, line))


def _pdo_flags(access: str, mappable: bool) -> str:
    """EDS ``PDOMapping=1`` + ``AccessType`` → ESI-style R/T (rww: RxPDO only, rwr: TxPDO only; decision
    "PDO mapping direction")."""
    if not mappable:
        return ""
    return {"rww": "R", "wo": "R", "rwr": "T", "ro": "T", "const": "T"}.get(access, "RT")


class _Convert:
    """python-canopen's dictionary → ecattool's, with each entry located at its section."""

    def __init__(self, lines: _Lines, source: str, dcf: bool) -> None:
        self.lines = lines
        self.source = source
        self.dcf = dcf
        self.warnings: list[Finding] = []

    def warn(self, message: str, line: int | None) -> None:
        self.warnings.append(Finding(_RULE, Severity.WARNING, message, Location(self.source, line)))

    def section_of(self, index: int, sub: int | None) -> str:
        for name in ((f"{index:04X}", f"{index:04x}") if sub is None else
                     (f"{index:04X}sub{sub:X}", f"{index:04X}sub{sub:x}", f"{index:04x}sub{sub:x}",
                      f"{index:04X}Sub{sub:X}", f"{index:04x}Sub{sub:x}")):
            if name in self.lines.sections:
                return name
        return f"{index:04X}" if sub is None else f"{index:04X}sub{sub:X}"

    def entry(self, var: Any, sub: int, section: str) -> Entry:
        code = var.data_type
        dt = lookup(code) if isinstance(code, int) else None
        line = self.lines.of(section)
        access_text = str(var.access_type or "ro").lower()
        value = var.value if self.dcf and var.value is not None else var.default
        raw: bytes | None = None
        bits = dt.bits if dt is not None and dt.bits is not None else 0
        if value is not None and dt is not None:
            try:
                raw = value if isinstance(value, bytes) else dt.encode(value)
            except Exception as exc:  # out of range for the type: reported, the entry keeps no default
                key = "ParameterValue" if self.dcf and var.value is not None else "DefaultValue"
                self.warn(f"[{section}] {key} {value!r} does not fit {dt.name}: {exc}; no default taken",
                          self.lines.of(section, key))
                raw = None
            if raw is not None and dt.bits is None:
                bits = 8 * len(raw)
        elif dt is not None:
            self._unread_default(var, section)
        return Entry(
            subindex=sub,
            name=str(var.name),
            datatype=dt,
            bit_size=bits,
            type_name=dt.name if dt is not None else f"DT{code:04X}" if isinstance(code, int) else "",
            access=Access.parse(access_text),
            pdo_mapping=_pdo_flags(access_text, bool(var.pdo_mappable)),
            default=raw,
            minimum=var.min,
            maximum=var.max,
            enum={int(k): str(v) for k, v in getattr(var, "value_descriptions", {}).items()},
            unit=str(getattr(var, "unit", "") or ""),
            comment=str(getattr(var, "description", "") or ""),
            location=Location(self.source, line),
        )

    def _unread_default(self, var: Any, section: str) -> None:
        """python-canopen drops a DefaultValue it cannot convert without a word: say so (node-relative COB-IDs
        excepted, which have no value on EtherCAT)."""
        raw = getattr(var, "default_raw", None)
        if raw is None or "$NODEID" in str(raw).upper() or not str(raw).strip():
            return
        self.warn(f"[{section}] DefaultValue {raw!r} is not a value of data type 0x{var.data_type:04X}; "
                  "no default taken", self.lines.of(section, "DefaultValue"))

    def dictionary(self, cod: Any) -> ObjectDictionary:
        from canopen.objectdictionary import ODArray, ODRecord

        od = ObjectDictionary()
        for index in sorted(cod.indices):
            item = cod.indices[index]
            if not isinstance(index, int) or not 0 < index <= 0xFFFF:
                continue
            if index < 0x1000 and not isinstance(item, (ODArray, ODRecord)) and getattr(item, "name", "").startswith("Dummy"):
                continue  # DummyUsage pseudo-objects: the dummies are data types 1-7, known to every family
            section = self.section_of(index, None)
            loc = Location(self.source, self.lines.of(section))
            if isinstance(item, (ODArray, ODRecord)):
                code = ObjectCode.ARRAY if isinstance(item, ODArray) else ObjectCode.RECORD
                obj = OdObject(index, str(item.name), code, location=loc)
                for sub in sorted(item.subindices):
                    obj.entries[sub] = self.entry(item.subindices[sub], sub, self.section_of(index, sub))
                self._compact(obj, section)
            else:
                obj = OdObject(index, str(item.name), ObjectCode.VAR, location=loc)
                obj.entries[0] = self.entry(item, 0, section)
            od.add(obj)
        return od

    def _compact(self, obj: OdObject, section: str) -> None:
        """``CompactSubObj=N``: N sub-indices like sub-index 1 (python-canopen keeps only sub-index 1)."""
        line = self.lines.of(section, "CompactSubObj")
        if line is None or 1 not in obj.entries:
            return
        try:
            n = int(self.lines.value(section, "CompactSubObj") or "0", 0)
        except ValueError:
            return
        template = obj.entries[1]
        for sub in range(2, min(n, 254) + 1):
            if sub not in obj.entries:
                e = Entry(sub, f"{template.name.rstrip('0123456789 ')} {sub}".strip(), template.datatype,
                          template.bit_size, template.type_name, access=template.access,
                          pdo_mapping=template.pdo_mapping, default=template.default, minimum=template.minimum,
                          maximum=template.maximum, location=template.location)
                obj.entries[sub] = e
        if 0 in obj.entries and obj.entries[0].default is None:
            obj.entries[0].default = bytes([min(n, 254)])
            obj.entries[0].bit_size = 8


def _unused_sections(lines: _Lines, od: ObjectDictionary, conv: _Convert) -> None:
    """Object and sub-index sections python-canopen left out of the dictionary (e.g. a sub-index of a VAR)."""
    for name in lines.order:
        m = _SUB.match(name)
        if m:
            index, sub = int(m.group(1), 16), int(m.group(2), 16)
            if od.entry(index, sub) is None:
                conv.warn(f"section [{name}] not used: object {index:04X}h has no sub-index {sub} "
                          f"(is it a VAR?)", lines.of(name))


def _cob_id_valid(cod: Any, index: int) -> bool:
    """CiA 301: a PDO is used when its COB-ID (comm. parameter sub-index 1) has bit 31 (invalid) clear."""
    item = cod.indices.get(index)
    var = item.subindices.get(1) if item is not None and hasattr(item, "subindices") else None
    if var is None:
        return True  # no communication parameter: nothing says the PDO is unused
    raw = str(getattr(var, "value_raw", None) or getattr(var, "default_raw", "") or "").upper().replace(" ", "")
    if not raw:
        return True
    try:
        value = int(re.sub(r"\+?\$NODEID\+?", "", raw) or "0", 0)
    except ValueError:
        return True
    return not value >> 31 & 1


def _assign_valid_pdos(cod: Any, pdos: list[Pdo], direction: Direction, conv: _Convert) -> None:
    """The default assignment of an EDS without 1C12h/1C13h: its valid PDOs (see :func:`_cob_id_valid`) that map
    something, without repeating an object. On CANopen each PDO is a frame of its own and a CiA-402 EDS often
    maps the controlword into every RPDO; on EtherCAT the assigned PDOs share one image, where a repeated
    controlword would take two values each cycle. Longer PDOs are kept first (then lower indices)."""
    comm_base = 0x1400 if direction is Direction.RX else 0x1800
    map_base = 0x1600 if direction is Direction.RX else 0x1A00
    sm = 2 if direction is Direction.RX else 3
    taken: dict[tuple[int, int], int] = {}
    for p in sorted(pdos, key=lambda q: (-q.bit_size, q.index)):
        p.sm = None
        if not p.entries or not _cob_id_valid(cod, comm_base + p.index - map_base):
            continue
        objects = {(e.index, e.subindex) for e in p.entries if not e.is_gap and e.index >= 0x1000}
        clash = sorted(objects & taken.keys())
        if clash:
            index, sub = clash[0]
            conv.warnings.append(Finding(
                _RULE, Severity.INFO,
                f"PDO {p.index:04X}h is valid in the EDS but not assigned by default: it maps {index:04X}:{sub:02X} "
                f"like PDO {taken[clash[0]]:04X}h (on EtherCAT the assigned PDOs share one process image)",
                p.location))
            continue
        p.sm = sm
        taken.update(dict.fromkeys(objects, p.index))


def _device(cod: Any, od: ObjectDictionary, lines: _Lines, source: str, conv: _Convert) -> Device:
    info = cod.device_information
    e1018 = {s: od.entry(0x1018, s) for s in (1, 2, 3)}

    def ident(value: Any, sub: int) -> int:
        if isinstance(value, int):
            return value & 0xFFFFFFFF
        entry = e1018[sub]
        v = entry.default_value if entry is not None else None
        return v if isinstance(v, int) else 0

    identity = Identity(ident(info.vendor_number, 1), ident(info.product_number, 2), ident(info.revision_number, 3))
    devtype = od.entry(0x1000, 0)
    dt_value = devtype.default_value if devtype is not None else None
    profile_no = dt_value & 0xFFFF if isinstance(dt_value, int) and dt_value & 0xFFFF else None

    rx_idx = [i for i in od.indices() if 0x1600 <= i <= 0x17FF]
    tx_idx = [i for i in od.indices() if 0x1A00 <= i <= 0x1BFF]
    rx = pdos_from_dictionary(od, Direction.RX, rx_idx, 2)
    tx = pdos_from_dictionary(od, Direction.TX, tx_idx, 3)
    for pdos, direction in ((rx, Direction.RX), (tx, Direction.TX)):
        for p in pdos:
            sub0 = od.entry(p.index, 0)
            p.fixed = sub0 is not None and not sub0.access.writable()
            obj = od.get(p.index)
            p.location = obj.location if obj is not None else None
        assign = od.entry(direction.assign_index, 0)
        if assign is None or assign.default is None:
            _assign_valid_pdos(cod, pdos, direction, conv)
    writable = any(not p.fixed for p in (*rx, *tx))
    assign_writable = all(e is None or e.access.writable() for e in (od.entry(0x1C12, 0), od.entry(0x1C13, 0)))
    mailbox = Mailbox(protocols=["CoE"], coe=CoeDetails(pdo_assign=writable and assign_writable, pdo_config=writable,
                                                         segmented_sdo=True))
    # SYNC consumer (1005h) on CANopen ~ SYNC0-synchronous operation on EtherCAT
    dc = [DcOpMode(*DC_FREERUN), *([DcOpMode(*DC_SYNC0)] if 0x1005 in od else [])]
    group = ("Drive", "Drives") if profile_no == 402 else ("", "")
    rx_bytes = (sum(p.bit_size for p in rx if p.sm is not None) + 7) // 8
    tx_bytes = (sum(p.bit_size for p in tx if p.sm is not None) + 7) // 8
    # a CANopen PDO is one CAN frame: at most 8 bytes per mapping object
    sms = standard_sync_managers(rx_bytes, tx_bytes, 8 * len(rx), 8 * len(tx))
    file_info = getattr(cod, "__edsFileInfo", {}) or {}
    name = str(info.product_name or file_info.get("Description") or Path(source).stem)
    extra = {k: str(v) for k, v in (("format", "DCF" if conv.dcf else "EDS"),
                                     ("eds_file", file_info.get("FileName")),
                                     ("eds_version", file_info.get("EDSVersion")),
                                     ("eds_file_version", file_info.get("FileVersion")),
                                     ("eds_file_revision", file_info.get("FileRevision")),
                                     ("eds_created_by", file_info.get("CreatedBy")),
                                     ("order_code", info.order_code),
                                     ("node_id", cod.node_id)) if v not in (None, "")}
    return Device(
        identity=identity,
        type_name=str(info.product_name or Path(source).stem),
        name=name,
        group_type=group[0],
        group_name=group[1],
        physics="YY",
        profile_no=profile_no,
        sync_managers=sms,
        fmmus=[Fmmu(kind, sm) for kind, sm in STANDARD_FMMUS],
        rx_pdos=rx,
        tx_pdos=tx,
        dictionary=od,
        mailbox=mailbox,
        dc_opmodes=dc,
        source=source,
        location=Location(source, lines.of("DeviceInfo")),
        extra=extra,
    )


def load_eds_bytes(data: bytes, source: str = "<bytes>") -> EsiFile:
    """Read a CANopen EDS or DCF document: an :class:`EsiFile` with one device (root ``"EDS"`` or ``"DCF"``).

    Raises :class:`InputError` (file and line) for a malformed file or when python-canopen is missing.
    """
    if len(data) > MAX_EDS_BYTES:
        raise InputError(f"EDS document is {len(data)} bytes, larger than the {MAX_EDS_BYTES} byte limit",
                         Location(source))
    try:
        from canopen.objectdictionary import eds as canopen_eds
    except ImportError:
        raise InputError("reading EDS/DCF files needs the 'canopen' package: pip install canopen",
                         Location(source)) from None
    text = _decode(data)
    lines = _Lines(text)
    if "DeviceInfo" not in lines.sections:
        raise InputError("not an EDS/DCF file: it has no [DeviceInfo] section (CiA 306 requires one)",
                         Location(source, 1))
    dcf = "DeviceComissioning" in lines.sections or source.lower().endswith(".dcf")
    stream = io.StringIO(text)
    import_eds: Any = canopen_eds.import_eds  # untyped in python-canopen
    logger = logging.getLogger("canopen.objectdictionary")
    handler = _Warnings()
    logger.addHandler(handler)
    try:
        cod = import_eds(stream, None)
    except RecursionError:
        raise InputError("EDS document cannot be read (nested too deeply)", Location(source)) from None
    except Exception as exc:  # untrusted input: whatever python-canopen raises becomes one located line
        raise _error(exc, lines, source) from None
    finally:
        logger.removeHandler(handler)
    conv = _Convert(lines, source, dcf)
    od = conv.dictionary(cod)
    _unused_sections(lines, od, conv)
    for message in handler.messages:
        conv.warn(f"python-canopen: {message}", None)
    device = _device(cod, od, lines, source, conv)
    return EsiFile(
        source=source,
        root="DCF" if dcf else "EDS",
        vendor_id=device.vendor_id,
        vendor_name=str(cod.device_information.vendor_name or ""),
        groups={device.group_type: device.group_name} if device.group_type else {},
        devices=[device],
        version=str(getattr(cod, "__edsFileInfo", {}).get("EDSVersion", "") or ""),
        warnings=conv.warnings,
    )


__all__ = ["MAX_EDS_BYTES", "load_eds", "load_eds_bytes", "looks_like_eds"]
