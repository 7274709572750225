"""ENI (EtherCAT Network Information, ETG.2100) slave init commands, and TwinCAT's ``EtherCATMailbox`` export.

Writing: ``EtherCATConfig/Config/Slave`` per slave with ``Info`` (identity and addresses), ``ProcessData``
(when PDO information is given), ``Mailbox`` with ``CoE/InitCmds/InitCmd`` (and ``SoE/InitCmds`` for SoE
commands), an ECAT ``InitCmds`` entry that sets the DC activation register, and ``DC``. CoE InitCmds carry
``Ccs`` 1 for downloads as TwinCAT writes it, Index and SubIndex in decimal, Data as little-endian hex.

Reading: ENI files and TwinCAT-exported ``EtherCATMailbox`` files (``<EtherCATMailbox><CoE|SoE><InitCmds>``).
A CoE InitCmd with data is a download whatever its Ccs says (SOEM 2.0 writes Ccs 2 for writes); a
disagreement is reported as a note. InitCmds without data (uploads) are reported and skipped. An InitCmd
with several Transition elements becomes one command per transition.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from lxml import etree

from ecattool.errors import EncodeError, InputError, Location
from ecattool.esi.model import Direction, Identity, Pdo, PdoEntry, SyncManager
from ecattool.findings import Severity
from ecattool.od.numbers import parse_int
from ecattool.startup.config import SlaveConfig, SoeCommand
from ecattool.startup.formats._common import (
    check_transition,
    dc_losses,
    one_shot_losses,
    one_shot_text,
    parse_hex,
    pdo_sm,
    sync_plan,
    unsigned_type,
)
from ecattool.startup.model import StartupCommand, StartupList

NAME = "eni"
EXTENSIONS = (".xml",)
DESCRIPTION = "ENI EtherCATConfig slave Mailbox/CoE/InitCmds (reads TwinCAT EtherCATMailbox exports too)"

#: element order written for each part (ETG.2100 sequence order, as TwinCAT writes it)
SLAVE_ORDER = ("Info", "ProcessData", "Mailbox", "InitCmds", "DC")
INFO_ORDER = ("Name", "PhysAddr", "AutoIncAddr", "VendorId", "ProductCode", "RevisionNo", "SerialNo")
MAILBOX_ORDER = ("Send", "Recv", "Protocol", "CoE", "SoE")
COE_INITCMD_ORDER = ("Transition", "Comment", "Timeout", "Ccs", "Index", "SubIndex", "Data")
SOE_INITCMD_ORDER = ("Transition", "Comment", "Timeout", "OpCode", "DriveNo", "IDN", "Elements", "Attribute", "Data")
ECAT_INITCMD_ORDER = ("Transition", "Comment", "Requires", "Cmd", "Adp", "Ado", "Data", "Retries")
PDO_ORDER = ("Index", "Name", "Entry")
ENTRY_ORDER = ("Index", "SubIndex", "BitLen", "Name", "DataType")

#: ESC register of the DC cyclic unit activation (AssignActivate)
DC_ACTIVATION_REGISTER = 0x0980
#: SYNC0 cycle time (4 bytes) followed by the SYNC1 cycle time, and the SYNC0 start time (8 bytes)
DC_CYCLE_REGISTER = 0x09A0
DC_START_REGISTER = 0x0990
_FPWR = 5  # configured-address physical write
_FIRST_PHYS_ADDR = 1001


#: characters XML 1.0 cannot hold (C0 controls other than tab and line breaks, surrogates, U+FFFE/U+FFFF)
_NOT_XML = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ud800-\udfff\ufffe\uffff]")


def xml_text(value: str) -> str:
    """Text as XML can hold it: a character XML 1.0 has no place for (a control character in a TwinCAT comment
    or a JSON name) is written as ``\\xNN`` / ``\\uNNNN``, visibly, instead of making the writer fail."""
    return _NOT_XML.sub(lambda m: f"\\x{ord(m.group()):02x}" if ord(m.group()) < 0x100 else
                        f"\\u{ord(m.group()):04x}", value)


def _sub(parent: Any, tag: str, text: object | None = None, cdata: bool = False) -> Any:
    el = etree.SubElement(parent, tag)
    if text is not None:
        value = xml_text(str(text))
        el.text = etree.CDATA(value) if cdata and value and "]]>" not in value else value
    return el


def _pdo_element(parent: Any, tag: str, pdo: Pdo, sm: int) -> None:
    el = _sub(parent, tag)
    el.set("Sm", str(sm))
    _sub(el, "Index", f"#x{pdo.index:04x}")
    _sub(el, "Name", pdo.name or f"0x{pdo.index:04X}", cdata=True)
    for e in pdo.entries:
        en = _sub(el, "Entry")
        _sub(en, "Index", f"#x{e.index:04x}")
        if e.index:
            _sub(en, "SubIndex", e.subindex)
        _sub(en, "BitLen", e.bit_len)
        if e.index:
            if e.name:
                _sub(en, "Name", e.name, cdata=True)
            if e.data_type:
                _sub(en, "DataType", e.data_type)


def _process_data(slave: Any, c: SlaveConfig) -> None:
    pd = _sub(slave, "ProcessData")
    sms = {s.number: s for s in c.sync_managers}
    for plan in sync_plan(c):
        if plan.mailbox or not plan.pdos:
            continue
        direction = Direction.RX if plan.output else Direction.TX
        sm = _sub(pd, f"Sm{plan.number}")
        _sub(sm, "Type", direction.sm_kind)
        known = sms.get(plan.number)
        if known is not None and known.start_address:
            _sub(sm, "StartAddress", known.start_address)
            _sub(sm, "ControlByte", known.control_byte)
        _sub(sm, "Enable", 1)
        for p in plan.pdos:
            _sub(sm, "Pdo", p.index)
    for p in c.tx_pdos:
        _pdo_element(pd, "TxPdo", p, pdo_sm(c, p))
    for p in c.rx_pdos:
        _pdo_element(pd, "RxPdo", p, pdo_sm(c, p))


def _mailbox_cmd(parent: Any, attrs: dict[str, str], transition: str, comment: str,
                 fields: tuple[tuple[str, object], ...]) -> None:
    ic = _sub(parent, "InitCmd")
    for key, value in attrs.items():
        ic.set(key, value)
    _sub(ic, "Transition", transition)
    _sub(ic, "Comment", comment, cdata=True)
    for tag, field_value in fields:
        _sub(ic, tag, field_value)


def _mailbox(slave: Any, c: SlaveConfig) -> None:
    mb = _sub(slave, "Mailbox")
    for kind, tag in (("MBoxOut", "Send"), ("MBoxIn", "Recv")):
        sm = next((s for s in c.sync_managers if s.kind == kind), None)
        if sm is not None and sm.start_address and sm.default_size:
            box = _sub(mb, tag)
            _sub(box, "Start", sm.start_address)
            _sub(box, "Length", sm.default_size)
    _sub(mb, "Protocol", "CoE")
    if c.soe_commands:
        _sub(mb, "Protocol", "SoE")
    cmds = _sub(_sub(mb, "CoE"), "InitCmds")
    for cmd in c.commands:
        if cmd.kind == "reset":  # a master re-sends InitCmds at every transition: a reset is not one of them
            cmds.append(etree.Comment(xml_text(f" not an InitCmd: {one_shot_text(cmd).replace('--', '- -')} ")))
            continue
        _mailbox_cmd(cmds, {"CompleteAccess": "true"} if cmd.complete_access else {}, cmd.transition, cmd.comment,
                     (("Timeout", cmd.timeout_ms), ("Ccs", 1), ("Index", cmd.index), ("SubIndex", cmd.subindex),
                      ("Data", cmd.data.hex())))
    if c.soe_commands:
        soe = _sub(_sub(mb, "SoE"), "InitCmds")
        for s in c.soe_commands:
            _mailbox_cmd(soe, {"Fixed": "1"} if s.fixed else {}, s.transition, s.comment,
                         (("Timeout", s.timeout_ms), ("OpCode", s.op_code), ("DriveNo", s.drive_no), ("IDN", s.idn),
                          ("Elements", s.elements), ("Attribute", s.attribute), ("Data", s.data.hex())))


def _ecat_cmd(cmds: Any, transitions: tuple[str, ...], comment: str, phys_addr: int, ado: int, data: bytes) -> None:
    ic = _sub(cmds, "InitCmd")
    for t in transitions:
        _sub(ic, "Transition", t)
    _sub(ic, "Comment", comment, cdata=True)
    _sub(ic, "Requires", "cycle")
    _sub(ic, "Cmd", _FPWR)
    _sub(ic, "Adp", phys_addr)
    _sub(ic, "Ado", ado)
    _sub(ic, "Data", data.hex())
    _sub(ic, "Retries", 3)


def _dc(slave: Any, c: SlaveConfig, phys_addr: int) -> None:
    """DC as TwinCAT writes it: in PS the SYNC0/SYNC1 cycle times (0x09A0), the start time (0x0990, 0 here:
    the master sets it from the system time when it sends the command) and the activation (0x0980); cleared
    in IP. A SYNC0 cycle the source does not give is refused, never written as 0."""
    if not c.dc_assign_activate:
        return
    if not c.dc_cycle_ns:
        raise EncodeError(f"{c.label}: DC is activated (0x{c.dc_assign_activate:04X}) but the source gives no SYNC0 "
                          "cycle, and an ENI needs it (a cycle of 0 stops the slave in SAFE-OP); give it with "
                          "--sync0-cycle NS", c.source)
    cmds = _sub(slave, "InitCmds")
    cycles = c.dc_cycle_ns.to_bytes(4, "little") + (c.dc_sync1_cycle_ns or 0).to_bytes(4, "little")
    _ecat_cmd(cmds, ("PS",), "set DC cycle time", phys_addr, DC_CYCLE_REGISTER, cycles)
    _ecat_cmd(cmds, ("PS",), "set DC start time", phys_addr, DC_START_REGISTER, bytes(8))
    _ecat_cmd(cmds, ("PS",), "set DC activation", phys_addr, DC_ACTIVATION_REGISTER,
              c.dc_assign_activate.to_bytes(2, "little"))
    _ecat_cmd(cmds, ("IP",), "clear DC activation", phys_addr, DC_ACTIVATION_REGISTER, bytes(2))
    dc = _sub(slave, "DC")
    _sub(dc, "CycleTime0", c.dc_cycle_ns)
    _sub(dc, "CycleTime1", c.dc_sync1_cycle_ns or 0)  # ENI has no SYNC1 shift: a loss the exporter reports
    _sub(dc, "ShiftTime", c.dc_shift_ns or 0)


def export(configs: list[SlaveConfig]) -> str:
    root = etree.Element("EtherCATConfig", Version="1.3")
    config = _sub(root, "Config")
    for i, c in enumerate(configs):
        pos = c.position if c.position is not None else i
        phys = _FIRST_PHYS_ADDR + pos
        slave = _sub(config, "Slave")
        info = _sub(slave, "Info")
        _sub(info, "Name", c.name or f"Slave {pos}", cdata=True)
        _sub(info, "PhysAddr", phys)
        _sub(info, "AutoIncAddr", (-pos) & 0xFFFF)
        ident = c.identity
        if ident is not None:
            _sub(info, "VendorId", ident.vendor_id)
            _sub(info, "ProductCode", ident.product_code)
            _sub(info, "RevisionNo", ident.revision)
            _sub(info, "SerialNo", ident.serial)
        if c.has_pdo_info:
            _process_data(slave, c)
        _mailbox(slave, c)
        _dc(slave, c, phys)
    body = etree.tostring(root, pretty_print=True, encoding="unicode")
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + body


# --- reading -----------------------------------------------------------------------------------------

def _loc(source: str, el: Any) -> Location:
    return Location(source, el.sourceline)


def _text(el: Any, tag: str) -> str | None:
    child = el.find(tag)
    if child is None or child.text is None:
        return None
    text: str = child.text
    return text.strip()


def _comment(el: Any) -> str:
    """The Comment element's text as written (CDATA keeps spaces, so they are not stripped)."""
    child = el.find("Comment")
    return "" if child is None or child.text is None else str(child.text)


def _int(el: Any, tag: str, source: str, default: int | None = None) -> int | None:
    t = _text(el, tag)
    if t is None or t == "":
        return default
    child = el.find(tag)
    return parse_int(t, _loc(source, child), tag)


def _bool_attr(el: Any, name: str) -> bool:
    return (el.get(name) or "").strip().lower() in ("1", "true")


def _coe_initcmds(parent: Any, cfg: SlaveConfig, source: str) -> None:
    for ic in parent.findall("InitCmds/InitCmd"):
        loc = _loc(source, ic)
        if (_text(ic, "Disabled") or "").lower() in ("1", "true"):
            cfg.note("startup.eni.disabled", "disabled InitCmd skipped", loc, Severity.INFO)
            continue
        index = _int(ic, "Index", source)
        sub = _int(ic, "SubIndex", source, 0)
        if index is None:
            raise InputError("CoE InitCmd without Index", loc)
        raw = _text(ic, "Data")
        ccs = _int(ic, "Ccs", source)
        if not raw:
            cfg.note("startup.eni.upload", f"InitCmd 0x{index:04X}:{sub:02X} carries no data (an upload/check, "
                     f"Ccs {ccs}); not a startup write, skipped", loc)
            continue
        if ccs not in (None, 1):
            cfg.note("startup.eni.ccs", f"InitCmd 0x{index:04X}:{sub:02X} has Ccs {ccs} but carries data; read as "
                     "a download (TwinCAT and ETG samples use Ccs 1, SOEM 2.0 uses 2)", loc, Severity.INFO)
        data = parse_hex(raw, loc)
        transitions = [check_transition(t.text or "", _loc(source, t)) for t in ic.findall("Transition")]
        if not transitions:
            raise InputError("InitCmd without Transition", loc)
        for t in transitions:
            cfg.startup.commands.append(StartupCommand(
                t, int(index), int(sub or 0), data, comment=_comment(ic),
                complete_access=_bool_attr(ic, "CompleteAccess"), timeout_ms=_int(ic, "Timeout", source, 0) or 0,
                type_name=unsigned_type(len(data)), value=int.from_bytes(data, "little"), source=loc))


def _soe_initcmds(parent: Any, cfg: SlaveConfig, source: str) -> None:
    found = parent.findall("InitCmds/InitCmd")
    for ic in found:
        loc = _loc(source, ic)
        idn = _int(ic, "IDN", source)
        if idn is None:
            raise InputError("SoE InitCmd without IDN", loc)
        data = parse_hex(_text(ic, "Data") or "", loc)
        for t in ic.findall("Transition"):
            cfg.soe_commands.append(SoeCommand(
                check_transition(t.text or "", loc), idn, data, drive_no=_int(ic, "DriveNo", source, 0) or 0,
                op_code=_int(ic, "OpCode", source, 3) or 0, elements=_int(ic, "Elements", source, 64) or 0,
                attribute=_int(ic, "Attribute", source, 0) or 0, comment=_comment(ic),
                timeout_ms=_int(ic, "Timeout", source, 0) or 0, fixed=_bool_attr(ic, "Fixed"), source=loc))
    if found:
        cfg.note("startup.soe", f"{len(found)} SoE init command(s) kept as SoE entries; they are not CoE SDO "
                 "downloads and only the ENI, TwinCAT, IgH and JSON formats carry them (CSV, ecmc, ros2 and pysoem "
                 "refuse them unless --lossy)", _loc(source, parent),
                 Severity.INFO)


def _pdo(el: Any, direction: Direction, source: str) -> Pdo:
    index = _int(el, "Index", source)
    if index is None:
        raise InputError(f"{el.tag} without Index", _loc(source, el))
    pdo = Pdo(direction, index, name=_text(el, "Name") or "", location=_loc(source, el))
    for e in el.findall("Entry"):
        pdo.entries.append(PdoEntry(_int(e, "Index", source, 0) or 0, _int(e, "SubIndex", source, 0) or 0,
                                    _int(e, "BitLen", source, 0) or 0, name=_text(e, "Name") or "",
                                    data_type=_text(e, "DataType") or "", location=_loc(source, e)))
    return pdo


def _read_process_data(pd: Any, cfg: SlaveConfig, source: str) -> None:
    defined = {Direction.RX: {}, Direction.TX: {}}  # type: dict[Direction, dict[int, Pdo]]
    for tag, direction in (("RxPdo", Direction.RX), ("TxPdo", Direction.TX)):
        for el in pd.findall(tag):
            p = _pdo(el, direction, source)
            defined[direction][p.index] = p
    for number, direction in ((2, Direction.RX), (3, Direction.TX)):
        sm = pd.find(f"Sm{number}")
        target = cfg.pdos(direction)
        if sm is None:
            continue
        start = _int(sm, "StartAddress", source)
        if start:  # what the writer needs to write the sync manager again
            cfg.sync_managers.append(SyncManager(number, direction.sm_kind, start,
                                                 control_byte=_int(sm, "ControlByte", source, 0) or 0,
                                                 location=_loc(source, sm)))
        for ref in sm.findall("Pdo"):
            idx = parse_int((ref.text or "").strip(), _loc(source, ref), "Pdo")
            assigned = defined[direction].get(idx)
            if assigned is None:
                cfg.note("startup.eni.pdo", f"Sm{number} assigns PDO 0x{idx:04X} that ProcessData does not define",
                         _loc(source, ref))
                assigned = Pdo(direction, idx)
            assigned.sm = number
            target.append(assigned)


def _read_slave(slave: Any, source: str, i: int) -> SlaveConfig:
    info = slave.find("Info")
    cfg = SlaveConfig(startup=StartupList(), source=_loc(source, slave))
    if info is not None:
        cfg.name = _text(info, "Name") or ""
        vendor, product = _int(info, "VendorId", source), _int(info, "ProductCode", source)
        if vendor is not None and product is not None:
            cfg.identity = Identity(vendor, product, _int(info, "RevisionNo", source, 0) or 0,
                                    _int(info, "SerialNo", source, 0) or 0)
        auto = _int(info, "AutoIncAddr", source)
        cfg.position = ((-auto) & 0xFFFF) if auto is not None else i
        phys = _int(info, "PhysAddr", source)
        if phys is not None:
            cfg.extra["phys_addr"] = phys
    cfg.startup.name = cfg.name
    if cfg.identity is not None:
        cfg.startup.vendor_id, cfg.startup.product_code = cfg.identity.vendor_id, cfg.identity.product_code
        cfg.startup.revision = cfg.identity.revision
    pd = slave.find("ProcessData")
    if pd is not None:
        _read_process_data(pd, cfg, source)
    mb = slave.find("Mailbox")
    if mb is not None:
        for number, (kind, tag) in enumerate((("MBoxOut", "Send"), ("MBoxIn", "Recv"))):
            box = mb.find(tag)
            start = None if box is None else _int(box, "Start", source)
            if box is not None and start:
                cfg.sync_managers.append(SyncManager(number, kind, start, default_size=_int(box, "Length", source),
                                                     location=_loc(source, box)))
        for child in mb.findall("CoE"):
            _coe_initcmds(child, cfg, source)
        for child in mb.findall("SoE"):
            _soe_initcmds(child, cfg, source)
    cfg.sync_managers.sort(key=lambda m: m.number)
    register_cmds = []
    for ic in slave.findall("InitCmds/InitCmd"):
        ado = _int(ic, "Ado", source)
        if ado == DC_ACTIVATION_REGISTER and "PS" in [t.text for t in ic.findall("Transition")]:
            raw = _text(ic, "Data")
            if raw:
                value = int.from_bytes(parse_hex(raw, _loc(source, ic)), "little")
                if value:
                    cfg.dc_assign_activate = value
        elif ado not in (DC_ACTIVATION_REGISTER, DC_CYCLE_REGISTER, DC_START_REGISTER):  # DC: from the DC element
            register_cmds.append(ic)
    if register_cmds:
        lines = ", ".join(str(ic.sourceline) for ic in register_cmds)
        cfg.note("startup.eni.register", f"{len(register_cmds)} ECAT register init command(s) (lines {lines}: sync "
                 "manager, FMMU, state and watchdog setup) are the master's own work from the ESI, not startup "
                 "commands; not converted", _loc(source, register_cmds[0]), Severity.INFO)
    dc = slave.find("DC")
    if dc is not None:
        cfg.dc_cycle_ns = _int(dc, "CycleTime0", source) or None
        cfg.dc_shift_ns = _int(dc, "ShiftTime", source)
        cfg.dc_sync1_cycle_ns = _int(dc, "CycleTime1", source) or None
    _report_unused(slave, cfg, source)
    return cfg


#: the elements the reader uses, per parent; everything else in a slave is reported
_USED = {"Slave": {"Info", "ProcessData", "Mailbox", "InitCmds", "DC"},
         "Info": set(INFO_ORDER),
         "ProcessData": {"TxPdo", "RxPdo", *(f"Sm{n}" for n in range(16))},
         "Mailbox": {"Send", "Recv", "Protocol", "CoE", "SoE"},
         "DC": {"CycleTime0", "CycleTime1", "ShiftTime"}}


def _report_unused(slave: Any, cfg: SlaveConfig, source: str) -> None:
    """One note per element of the slave that the import does not use (by parent, with the lines)."""
    for parent_tag, used in _USED.items():
        parents = [slave] if parent_tag == "Slave" else slave.findall(parent_tag)
        for parent in parents:
            unused = [el for el in parent if isinstance(el.tag, str) and el.tag not in used]
            if parent_tag == "Mailbox":
                for coe in parent.findall("CoE"):
                    unused += [el for el in coe if isinstance(el.tag, str) and el.tag != "InitCmds"]
            if unused:
                names = ", ".join(f"<{el.tag}> (line {el.sourceline})" for el in unused)
                cfg.note("startup.eni.unused", f"not converted from <{parent_tag}>: {names}", _loc(source, unused[0]),
                         Severity.INFO)


def load_tree(tree: Any, source: str, name: str = "") -> list[SlaveConfig]:
    root = tree.getroot()
    if root.tag == "EtherCATMailbox":
        cfg = SlaveConfig(startup=StartupList(name=name), name=name, source=_loc(source, root))
        for child in root:
            if child.tag == "CoE":
                _coe_initcmds(child, cfg, source)
            elif child.tag == "SoE":
                _soe_initcmds(child, cfg, source)
            else:
                cfg.note("startup.eni.protocol", f"{child.tag} init commands are not supported; skipped",
                         _loc(source, child))
        return [cfg]
    if root.tag != "EtherCATConfig":
        raise InputError(f"root element is <{root.tag}>, expected <EtherCATConfig> (ENI) or <EtherCATMailbox>",
                         _loc(source, root))
    slaves = root.findall("Config/Slave")
    configs = [_read_slave(s, source, i) for i, s in enumerate(slaves)]
    master_parts = [el for el in root.iter() if isinstance(el.tag, str) and el.getparent() is not None
                    and el.getparent().tag in ("EtherCATConfig", "Config") and el.tag not in ("Config", "Slave")]
    if configs and master_parts:
        names = ", ".join(f"<{el.tag}> (line {el.sourceline})" for el in master_parts)
        configs[0].note("startup.eni.master", f"master-level parts not converted (the master's, not a slave's startup "
                        f"list): {names}", _loc(source, master_parts[0]), Severity.INFO)
    return configs


def load(data: bytes, source: str) -> list[SlaveConfig]:
    from ecattool.xmlsafe import parse_xml

    return load_tree(parse_xml(data, source), source, Path(source).stem)


def detect(data: bytes) -> bool:
    head = data[:4096]
    return b"<EtherCATConfig" in head or b"<EtherCATMailbox" in head


def losses(c: SlaveConfig) -> list[str]:
    """What an ENI cannot carry for ``c``: one-shot writes (InitCmds run at every transition), an unknown
    identity (a master matches the slave by VendorId/ProductCode) and a SYNC1 shift (ENI's DC has none)."""
    out = one_shot_losses(c, "an ENI")
    if c.identity is None:
        out.append("no vendor id/product code: an ENI slave needs VendorId and ProductCode, and the source gives none")
    return out + dc_losses(c, "an ENI", sync1_shift=False)
