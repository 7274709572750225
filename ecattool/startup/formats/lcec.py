"""LinuxCNC-EtherCAT (lcec) ``ethercat-conf.xml``: slaves, ``sdoConfig``, ``syncManager``/``pdo``, ``dcConf``,
and ``initCmds`` files (TwinCAT ``EtherCATMailbox`` exports, read with the ENI reader). Import only.

``sdoConfig subIdx="complete"`` is a complete-access write of sub-index 0 with all ``sdoDataRaw`` bytes
concatenated; lcec writes its SDO configuration in PRE-OP, so commands get transition PS. Numbers in lcec
attributes are hexadecimal without prefix (``idx="1c12"``, ``vid="00000002"``). ``halPin``/``halType`` of
PDO entries are kept in ``channel_info``; ``assignActivate`` is hex, ``sync0Cycle="*1"`` (a multiple of the
application period) is kept in ``extra``.
"""

from __future__ import annotations

import glob
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

from ecattool.errors import InputError, Location
from ecattool.esi.model import Direction, Identity, Pdo, PdoEntry
from ecattool.findings import Severity
from ecattool.od.numbers import parse_int
from ecattool.startup.config import SlaveConfig
from ecattool.startup.formats._common import parse_hex, unsigned_type
from ecattool.startup.model import StartupCommand, StartupList

if TYPE_CHECKING:
    from lxml import etree

NAME = "lcec"
EXTENSIONS = (".xml",)
DESCRIPTION = "LinuxCNC-EtherCAT ethercat-conf.xml (sdoConfig, syncManager/pdo, dcConf, initCmds files); import only"


def _line(el: etree._Element) -> int | None:
    """The element's source line (lxml-stubs declare ``sourceline`` as ``...``; lxml gives ``int | None``)."""
    return cast("int | None", el.sourceline)


def _hex(el: Any, attr: str, source: str, default: int | None = None) -> int | None:
    text = el.get(attr)
    if text is None or not text.strip():
        return default
    try:
        return int(text.strip().removeprefix("0x").removeprefix("0X"), 16)
    except ValueError:
        raise InputError(f"{attr}={text!r} is not a hex number (lcec writes hex without prefix)",
                         Location(source, el.sourceline)) from None


def _sdo_configs(slave: Any, cfg: SlaveConfig, source: str) -> None:
    for sc in slave.findall("sdoConfig"):
        loc = Location(source, sc.sourceline)
        index = _hex(sc, "idx", source)
        if index is None:
            raise InputError("sdoConfig without idx", loc)
        sub_text = (sc.get("subIdx") or "").strip().lower()
        complete = sub_text == "complete"
        sub = 0 if complete else (_hex(sc, "subIdx", source) or 0)
        raw = b"".join(parse_hex(r.get("data") or "", Location(source, r.sourceline)) for r in sc.findall("sdoDataRaw"))
        if not raw:
            raise InputError("sdoConfig without sdoDataRaw data (only raw data is supported)", loc)
        cfg.startup.commands.append(StartupCommand("PS", index, sub, raw, complete_access=complete,
                                                   type_name=None if complete else unsigned_type(len(raw)),
                                                   value=int.from_bytes(raw, "little") if len(raw) <= 8 else None,
                                                   source=loc))


def _pdos(slave: Any, cfg: SlaveConfig, source: str) -> None:
    for sm in slave.findall("syncManager"):
        direction = Direction.RX if (sm.get("dir") or "").lower() == "out" else Direction.TX
        number = _hex(sm, "idx", source)
        for p in sm.findall("pdo"):
            pdo = Pdo(direction, _hex(p, "idx", source) or 0, sm=number, location=Location(source, p.sourceline))
            for k, e in enumerate(p.findall("pdoEntry")):
                pdo.entries.append(PdoEntry(_hex(e, "idx", source) or 0, _hex(e, "subIdx", source, 0) or 0,
                                            parse_int(e.get("bitLen") or "0", Location(source, e.sourceline), "bitLen"),
                                            name=e.get("halPin") or "",
                                            location=Location(source, e.sourceline)))
                info = {a: e.get(a) for a in ("halPin", "halType") if e.get(a)}
                complex_entries = [dict(c.attrib) for c in e.findall("complexEntry")]
                if complex_entries:
                    info["complexEntry"] = complex_entries
                if info:
                    cfg.channel_info[(pdo.index, k)] = info
            cfg.pdos(direction).append(pdo)


def _find_beside(folder: Path, name: str) -> Path | None:
    """The initCmds file: ``name`` beside the configuration, else the one sibling ending in ``_<name>``
    (collections such as ecattool's corpus prefix copied files with their origin)."""
    if not name or "\0" in name:
        return None
    try:
        exact = folder / name
        if exact.is_file():
            return exact
        if "/" in name or "\\" in name:
            return None
        matches = sorted(p for p in folder.glob(f"*_{glob.escape(name)}") if p.is_file())
    except (OSError, ValueError):  # a name the file system refuses (too long): not found, and reported so
        return None
    return matches[0] if len(matches) == 1 else None


def _init_cmds(slave: Any, cfg: SlaveConfig, source: str) -> None:
    from ecattool.startup.formats import eni
    from ecattool.xmlsafe import read_xml_file

    for ic in slave.findall("initCmds"):
        loc = Location(source, ic.sourceline)
        name = ic.get("filename") or ""
        path = _find_beside(Path(source).parent, name)
        if path is None:
            cfg.note("startup.lcec.initcmds", f"initCmds file {name!r} not found beside the configuration; its "
                     "commands are missing from this import", loc)
            continue
        for sub in eni.load_tree(read_xml_file(path), str(path), path.stem):
            cfg.startup.commands.extend(sub.startup.commands)
            cfg.soe_commands.extend(sub.soe_commands)
            cfg.notes.extend(sub.notes)


def load(data: bytes, source: str) -> list[SlaveConfig]:
    from ecattool.xmlsafe import parse_xml

    root = parse_xml(data, source).getroot()
    if root.tag != "masters":
        raise InputError(f"root element is <{root.tag}>, expected <masters> (lcec ethercat-conf.xml)",
                         Location(source, _line(root)))
    out = []
    for master in root.findall("master"):
        for slave in master.findall("slave"):
            loc = Location(source, _line(slave))
            idx = slave.get("idx")
            cfg = SlaveConfig(startup=StartupList(), name=slave.get("name") or slave.get("type") or "",
                              position=parse_int(idx, loc, "idx") if idx and idx.isdigit() else None, source=loc)
            cfg.extra["lcec_type"] = slave.get("type") or ""
            if master.get("idx") not in (None, "0"):
                cfg.extra["master"] = master.get("idx")
            vid, pid = _hex(slave, "vid", source), _hex(slave, "pid", source)
            if vid is not None and pid is not None:
                cfg.identity = Identity(vid, pid)
                cfg.startup.vendor_id, cfg.startup.product_code = vid, pid
            elif cfg.extra["lcec_type"] not in ("generic", ""):
                cfg.note("startup.lcec.identity", f"slave type {cfg.extra['lcec_type']!r} is identified by lcec's "
                         "built-in driver; no vendor/product code in the file", loc, Severity.INFO)
            _sdo_configs(slave, cfg, source)
            _pdos(slave, cfg, source)
            if cfg.has_pdo_info:
                _config_pdos_note(slave, cfg, source)
            dc = slave.find("dcConf")
            if dc is not None:
                _dc(dc, cfg, source, _app_period(master, source))
            _init_cmds(slave, cfg, source)
            _report_unused(master, slave, cfg, source)
            out.append(cfg)
    return out


def _app_period(master: Any, source: str) -> int | None:
    text = (master.get("appTimePeriod") or "").strip()
    if not text:
        return None
    return parse_int(text, Location(source, master.sourceline), "appTimePeriod")


def _cycle(text: str, app_period: int | None, loc: Location) -> int | None:
    """An lcec cycle: ns, or ``*N`` = N application periods (lcec's ``parseSyncCycle``)."""
    t = text.strip()
    if t.startswith("*") and t[1:].isdigit():
        return parse_int(t[1:], loc, "cycle multiple") * app_period if app_period else None
    return parse_int(t, loc, "cycle") if t.lstrip("-").isdigit() else None


def _dc(dc: Any, cfg: SlaveConfig, source: str, app_period: int | None) -> None:
    loc = Location(source, dc.sourceline)
    cfg.dc_assign_activate = _hex(dc, "assignActivate", source)
    for attr in ("sync0Cycle", "sync0Shift", "sync1Cycle", "sync1Shift"):
        if dc.get(attr) is not None:
            cfg.extra[attr] = dc.get(attr)
    cfg.dc_cycle_ns = _cycle(dc.get("sync0Cycle") or "", app_period, loc)
    shift = dc.get("sync0Shift") or ""
    cfg.dc_shift_ns = parse_int(shift, loc, "sync0Shift") if shift.lstrip("-").isdigit() else None
    if (dc.get("sync0Cycle") or "").startswith("*") and cfg.dc_cycle_ns is None:
        cfg.note("startup.lcec.dc", f"sync0Cycle={dc.get('sync0Cycle')!r} is a multiple of the master's "
                 "appTimePeriod, which the file does not give: the SYNC0 cycle is unknown", loc)
    if (dc.get("sync1Cycle") or "").strip():
        cfg.dc_sync1_cycle_ns = _cycle(dc.get("sync1Cycle") or "", app_period, loc)
        if cfg.dc_sync1_cycle_ns is None:
            cfg.note("startup.lcec.sync1", f"sync1Cycle={dc.get('sync1Cycle')!r} is not a cycle in ns or a multiple "
                     "of a known appTimePeriod: SYNC1 is not converted", loc)
    shift1 = (dc.get("sync1Shift") or "").strip()
    cfg.dc_sync1_shift_ns = parse_int(shift1, loc, "sync1Shift") if shift1.lstrip("-").isdigit() else None


def _config_pdos_note(slave: Any, cfg: SlaveConfig, source: str) -> None:
    """lcec programs a generic slave's PDO tables only with ``configPdos="true"``; otherwise they name the
    slave's own mapping for the HAL pins. Either way the reader says what it did with them."""
    loc = Location(source, slave.sourceline)
    if (slave.get("configPdos") or "").strip().lower() == "true":
        cfg.note("startup.lcec.configpdos", 'configPdos="true": lcec programs these PDO tables; they are converted '
                 "as the slave's PDO assignment and mapping", loc, Severity.INFO)
    else:
        cfg.note("startup.lcec.configpdos", "configPdos is not \"true\": lcec leaves the slave's own PDO mapping and "
                 "uses these tables for its HAL pins only; they are converted as the PDO assignment and mapping, "
                 "which IgH, ros2 and pysoem exports program", loc)


#: what the reader uses; every other element or attribute is reported
_USED_SLAVE_ATTRS = {"idx", "type", "name", "vid", "pid", "configPdos"}
_USED_SLAVE_CHILDREN = {"sdoConfig", "syncManager", "dcConf", "initCmds"}
_WHY = {"watchdog": "the ESC watchdog timing (divider, intervals) has no place in a startup list",
        "idnConfig": "SoE IDN configuration of lcec is not read (TwinCAT initCmds files are)",
        "modParam": "lcec module parameters are lcec driver settings, not startup writes"}


def _report_unused(master: Any, slave: Any, cfg: SlaveConfig, source: str) -> None:
    """A note for each element and attribute of the slave (and its master) that the import does not use."""
    for name in sorted(set(slave.attrib) - _USED_SLAVE_ATTRS):
        cfg.note("startup.lcec.unused", f"slave attribute {name}={slave.get(name)!r} is not converted",
                 Location(source, slave.sourceline))
    for child in slave:
        if not isinstance(child.tag, str) or child.tag in _USED_SLAVE_CHILDREN:
            continue
        attrs = " ".join(f'{k}="{v}"' for k, v in child.attrib.items())
        why = _WHY.get(child.tag, "not an lcec element this reader knows")
        cfg.note("startup.lcec.unused", f"<{child.tag} {attrs}> is not converted: {why}",
                 Location(source, child.sourceline))
    if master.get("appTimePeriod") and cfg is not None and slave is master.find("slave"):
        cfg.note("startup.lcec.master", f"master appTimePeriod={master.get('appTimePeriod')!r} ns is lcec's "
                 "application cycle: used for the sync cycles given as *N; a master setting, not part of a slave "
                 "configuration", Location(source, master.sourceline), Severity.INFO)
    extra = sorted(set(master.attrib) - {"idx", "appTimePeriod"})
    if extra and cfg is not None and slave is master.find("slave"):
        cfg.note("startup.lcec.master", "master attributes " + ", ".join(f"{k}={master.get(k)!r}" for k in extra)
                 + " belong to the master, not to a slave's startup list", Location(source, master.sourceline),
                 Severity.INFO)


def detect(data: bytes) -> bool:
    return b"<masters" in data[:4096]
