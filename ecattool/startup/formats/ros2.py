"""ethercat_driver_ros2 slave configuration YAML (ICube-Robotics): identity, DC, ``sdo``, ``rpdo``/``tpdo``.

The driver sends every ``sdo`` entry in PRE-OP before SAFE-OP, so imported commands get transition PS and
commands of other transitions are written with a YAML comment saying so. The ``sdo`` entries need a type;
commands without one are written as ``uint8/16/32/64`` by size. Complete-access writes and data of other
sizes have no ros2 form and are refused with the command named. Per-channel attributes
(``command_interface``, ``state_interface``, ``default``, ``factor``, ``mask``) and other top-level keys
(``period``, ``auto_fault_reset``, ``sm``) survive a read/write round trip; YAML comments become command
comments and PDO entry names.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from ecattool.errors import EncodeError, InputError, Location
from ecattool.esi.model import Direction, Identity, Pdo, PdoEntry
from ecattool.od import types as dt
from ecattool.od.numbers import parse_int
from ecattool.od.standard import standard_type
from ecattool.startup.config import SlaveConfig
from ecattool.startup.formats._common import (
    as_list,
    check_tree,
    dc_losses,
    decode_text,
    long_number_location,
    one_line,
    one_shot_losses,
    one_shot_text,
    require_identity,
    soe_losses,
    sync_plan,
)
from ecattool.startup.model import StartupCommand, StartupList, is_pdo_programming

NAME = "ros2"
EXTENSIONS = (".yaml", ".yml")
DESCRIPTION = "ethercat_driver_ros2 slave YAML (vendor_id, product_id, assign_activate, sdo, rpdo/tpdo)"

#: ros2 type name -> CoE type name
ROS_TO_COE = {"bool": "BOOL", "int8": "SINT", "int16": "INT", "int32": "DINT", "int64": "LINT",
              "uint8": "USINT", "uint16": "UINT", "uint32": "UDINT", "uint64": "ULINT",
              "float": "REAL", "double": "LREAL"}
COE_TO_ROS = {v: k for k, v in ROS_TO_COE.items()}
COE_TO_ROS.update({"BYTE": "uint8", "WORD": "uint16", "DWORD": "uint32", "INTEGER8": "int8",
                   "INTEGER16": "int16", "INTEGER32": "int32", "UNSIGNED8": "uint8", "UNSIGNED16": "uint16",
                   "UNSIGNED32": "uint32", "REAL32": "float", "REAL64": "double"})
_BY_SIZE = {1: "uint8", 2: "uint16", 4: "uint32", 8: "uint64"}
_KNOWN_KEYS = ("vendor_id", "product_id", "assign_activate", "sdo", "rpdo", "tpdo")
#: what other importers keep in ``SlaveConfig.extra`` about their own format (ecmc's slave reference, ENI's
#: PhysAddr): not ros2 keys, so not written as such
_OTHER_FORMATS_KEYS = ("ecmc_slave", "phys_addr")


def _scalar(value: Any) -> str:
    import yaml

    if isinstance(value, float) and math.isnan(value):
        return ".nan"
    text = yaml.safe_dump(value, default_flow_style=True, width=1 << 16).strip()
    return text[:-4].strip() if text.endswith("\n...") else text.removesuffix("...").strip()


class _Raw(str):
    """Text written into the YAML as is (hex numbers)."""


def _flow(items: list[tuple[str, Any]]) -> str:
    return "{" + ", ".join(f"{k}: {v if isinstance(v, _Raw) else _scalar(v)}" for k, v in items) + "}"


#: channel types the driver maps with their size (its ``type2bits``); float and double it has not: it would map
#: them as 255 bits (``return -1`` into a uint8_t), shifting every later entry of the domain
DRIVER_CHANNEL_FLOATS = {"float": "uint32", "double": "uint64"}


def _ros_type_of_entry(e: PdoEntry) -> str:
    name = (e.data_type or standard_type(e.index, e.subindex, e.bit_len) or "").upper()
    if name in COE_TO_ROS:
        ros = COE_TO_ROS[name]
        return DRIVER_CHANNEL_FLOATS.get(ros, ros)  # a float channel: its raw bits, at its size (a listed loss)
    if name.startswith("BIT") and name[3:].isdigit():
        return f"bit{name[3:]}"
    if e.bit_len == 1:
        return "bool"
    if e.bit_len < 8 or e.index == 0:
        return f"bit{e.bit_len}"
    return _BY_SIZE.get(e.bit_len // 8, f"bit{e.bit_len}")


#: the integer types ethercat_driver_ros2's SdoConfigEntry writes, by byte size (float/double/bool it does not)
DRIVER_SDO_TYPES = {"int8": 1, "uint8": 1, "int16": 2, "uint16": 2, "int32": 4, "uint32": 4, "int64": 8, "uint64": 8}
INT32_MIN, INT32_MAX = -(1 << 31), (1 << 31) - 1


def driver_value(data: bytes) -> int | None:
    """The ``value`` the driver turns into ``data``: it reads every sdo value as a C ``int`` (yaml-cpp
    ``as<int>()``, which throws above INT32_MAX) and writes ``static_cast<type>(value)``; so the value is the
    signed reading of the bytes, which must fit 32 bits (always true up to 4 bytes; 8-byte data only when its
    upper half is the sign extension). None: no int writes these bytes."""
    v = int.from_bytes(data, "little", signed=True)
    return v if INT32_MIN <= v <= INT32_MAX else None


def _sdo_line(cmd: StartupCommand) -> str:
    where = f"0x{cmd.index:04X}:{cmd.subindex:02X}{f' ({cmd.source})' if cmd.source else ''}"
    if cmd.complete_access:
        raise EncodeError(f"{where}: ethercat_driver_ros2 has no complete-access SDO writes")
    coe = (cmd.type_name or standard_type(cmd.index, cmd.subindex, 8 * len(cmd.data)) or "").upper()
    ros = COE_TO_ROS.get(coe) if coe else None
    t = dt.lookup(ROS_TO_COE[ros]) if ros else None
    notes = [one_line(cmd.comment)] if cmd.comment else []
    if ros is None or t is None or t.bits is None or t.bits // 8 != len(cmd.data) or ros not in DRIVER_SDO_TYPES:
        if ros in ("float", "double") and t is not None and t.bits == 8 * len(cmd.data):
            notes.append(f"{ros} {t.decode(cmd.data)!r} written as its bytes: the driver writes integer types only")
            ros = "int32" if len(cmd.data) == 4 else "int64"
        else:
            ros = _BY_SIZE.get(len(cmd.data))
        if ros is None:
            raise EncodeError(f"{where}: {len(cmd.data)} data bytes have no ethercat_driver_ros2 sdo type")
        t = dt.require(ROS_TO_COE[ros])
    value = t.decode(cmd.data)
    if not (isinstance(value, int) and INT32_MIN <= value <= INT32_MAX):
        # the driver reads the value as a signed 32-bit int and casts it to the type: the same bytes as a
        # negative number (3221225472 = 0xC0000000 -> -1073741824 for a uint32)
        value = driver_value(cmd.data)
        if value is None:
            raise EncodeError(f"{where}: 0x{int.from_bytes(cmd.data, 'little'):X} does not fit the 32-bit int "
                              "ethercat_driver_ros2 reads every sdo value as; write this object with another master "
                              "format or from the application")
    line = "  - " + _flow([("index", _Raw(f"0x{cmd.index:04X}")), ("sub_index", cmd.subindex), ("type", ros),
                           ("value", value)])
    if cmd.transition != "PS":
        notes.append(f"transition {cmd.transition} (ros2 sends every sdo in PRE-OP)")
    return line + (f"  # {'; '.join(notes)}" if notes else "")


def _pdo_lines(c: SlaveConfig, pdos: list[Pdo]) -> list[str]:
    out = []
    for p in pdos:
        out.append(f"  - index: 0x{p.index:04x}" + (f"  # {one_line(p.name)}" if p.name else ""))
        out.append("    channels:")
        for pos, e in enumerate(p.entries):
            items: list[tuple[str, Any]] = [("index", _Raw(f"0x{e.index:04x}")),
                                            ("sub_index", _Raw(f"0x{e.subindex:02x}")), ("type", _ros_type_of_entry(e))]
            items += list(c.channel_info.get((p.index, pos), {}).items())
            out.append("      - " + _flow(items) + (f"  # {one_line(e.name)}" if e.name else ""))
    return out


def export(configs: list[SlaveConfig]) -> str:
    import yaml

    if len(configs) != 1:
        raise EncodeError(f"an ethercat_driver_ros2 slave file describes one slave; got {len(configs)} (export them one by one: --drive)")
    c = configs[0]
    title = f": {one_line(c.name)}" if c.name else ""
    lines = [f"# ethercat_driver_ros2 slave configuration written by ecattool{title}"]
    ident = require_identity(c, "ethercat_driver_ros2 (it configures the slave by vendor_id/product_id)")
    lines += [f"vendor_id: 0x{ident.vendor_id:08x}", f"product_id: 0x{ident.product_code:08x}"]
    if c.dc_assign_activate is not None:
        lines.append(f"assign_activate: 0x{c.dc_assign_activate:04x}  # DC Synch register")
    for key, value in c.extra.items():
        if key not in _KNOWN_KEYS and key != "sm" and key not in _OTHER_FORMATS_KEYS:
            if isinstance(value, (dict, list)):
                lines.append(yaml.safe_dump({key: value}, default_flow_style=None, sort_keys=False).strip())
            else:
                lines.append(f"{key}: {_scalar(value)}")
    commands = list(c.commands)
    if c.has_pdo_info:
        # the driver configures the PDOs from rpdo/tpdo itself; writing 1C12h/1C13h/16xxh/1Axxh as SDOs too
        # would program the mapping twice
        skipped = [cmd for cmd in commands if is_pdo_programming(cmd.index)]
        commands = [cmd for cmd in commands if not is_pdo_programming(cmd.index)]
        if skipped:
            lines.append(f"# {len(skipped)} PDO assignment/mapping writes of the startup list are done by the driver "
                         "from rpdo/tpdo")
    once = [cmd for cmd in commands if cmd.kind == "reset"]  # once-writes stay, in order (a loss export() reports)
    commands = [cmd for cmd in commands if cmd.kind != "reset"]
    lines += [f"# not an sdo entry: {one_shot_text(cmd)}" for cmd in once]
    if commands:
        lines.append("sdo:  # sdo data to be transferred at drive startup")
        lines += [_sdo_line(cmd) for cmd in commands]
    for key, pdos in (("rpdo", c.rx_pdos), ("tpdo", c.tx_pdos)):
        if pdos:
            lines.append(f"{key}:")
            lines += _pdo_lines(c, pdos)
    sms = c.extra.get("sm") if "sm" in c.extra else _sm_section(c)
    if sms:
        lines.append("sm:  # Sync Manager")
        lines += ["  - " + _flow(list(s.items())) for s in sms]
    return "\n".join(lines) + "\n"


def _sm_section(c: SlaveConfig) -> list[dict[str, Any]]:
    """The driver's ``sm`` entries where the source assigns the PDOs to other sync managers than its default
    (SM2 rpdo, SM3 tpdo) or says how their watchdogs are set; nothing where the default holds."""
    plans = [p for p in sync_plan(c) if not p.mailbox and p.pdos]
    default = all(p.number == (2 if p.output else 3) and p.watchdog is None for p in plans)
    if default or len({p.output for p in plans}) != len(plans):  # the driver puts all rpdo (tpdo) on one SM
        return []
    out = []
    for p in plans:
        entry: dict[str, Any] = {"index": p.number, "type": "output" if p.output else "input",
                                 "pdo": "rpdo" if p.output else "tpdo"}
        if p.watchdog is not None:
            entry["watchdog"] = "enable" if p.watchdog else "disable"
        out.append(entry)
    return out


# --- reading -----------------------------------------------------------------------------------------

def _comment_at(lines: list[str], loc: Location) -> str:
    """The YAML comment that belongs to a flow mapping starting at ``loc`` (on its closing line)."""
    if loc.line is None:
        return ""
    depth = 0
    for n in range(loc.line - 1, min(len(lines), loc.line + 40)):
        text = lines[n] if n != loc.line - 1 else lines[n][(loc.column or 1) - 1:]
        code, _, comment = text.partition("#")
        depth += code.count("{") - code.count("}")
        if depth <= 0:
            return comment.strip()
    return ""


def _int(value: Any, loc: Location, what: str) -> int:
    if isinstance(value, bool) or value is None:
        raise InputError(f"{what} must be a number, got {value!r}", loc)
    return parse_int(value if isinstance(value, int) else str(value), loc, what)


def _ros_type(name: Any, loc: Location) -> tuple[str, int]:
    key = str(name).strip().lower()
    if key in ROS_TO_COE:
        t = dt.require(ROS_TO_COE[key])
        return t.name, t.bits or 0
    if key.startswith("bit") and key[3:].isdigit():
        return f"BIT{key[3:]}", int(key[3:])
    raise InputError(f"unknown ethercat_driver_ros2 type {name!r} (bool, int8..int64, uint8..uint64, float, "
                     "double, bitN)", loc)


def _sdo(item: Any, loc: Location, comment: str) -> StartupCommand:
    if not isinstance(item, dict):
        raise InputError("an sdo entry must be a mapping {index, sub_index, type, value}", loc)
    for key in ("index", "sub_index", "type", "value"):
        if key not in item:
            raise InputError(f"sdo entry has no {key!r}", loc)
    coe, _bits = _ros_type(item["type"], loc)
    t = dt.require(coe)
    value = item["value"]
    if isinstance(value, int) and not isinstance(value, bool) and t.kind in (dt.Kind.UNSIGNED, dt.Kind.SIGNED) \
            and t.bits and INT32_MIN <= value <= INT32_MAX:
        data = (value & ((1 << t.bits) - 1)).to_bytes(t.bits // 8, "little")  # the driver's static_cast<type>
        value = t.decode(data)
    else:
        try:
            data = t.encode(value)
        except EncodeError as exc:
            raise EncodeError(exc.message, loc) from None
    return StartupCommand("PS", _int(item["index"], loc, "index"), _int(item["sub_index"], loc, "sub_index"), data,
                          comment=comment, type_name=t.name, value=value, source=loc)


def _driver_notes(cfg: SlaveConfig, item: Any, loc: Location) -> None:
    """What ethercat_driver_ros2 itself would refuse in an sdo entry (it reads values with ``as<int>()``)."""
    value, kind = item.get("value"), str(item.get("type", "")).strip().lower()
    if kind not in DRIVER_SDO_TYPES:
        cfg.note("startup.ros2.driver", f"sdo type {kind!r}: ethercat_driver_ros2 writes only "
                 f"{', '.join(DRIVER_SDO_TYPES)} (it would send no data for this entry)", loc)
    elif not (isinstance(value, int) and not isinstance(value, bool) and INT32_MIN <= value <= INT32_MAX):
        cfg.note("startup.ros2.driver", f"sdo value {value!r}: ethercat_driver_ros2 reads every value as a signed "
                 "32-bit int and stops on this one (write the same bytes as the signed value)", loc)


def load_located(text: str, source: str) -> Any:
    """YAML with locations; errors PyYAML raises before parsing (bad characters) become InputErrors too."""
    import yaml

    from ecattool.yamlloc import load_yaml

    try:
        doc = load_yaml(text, source)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        raise InputError(f"invalid YAML: {getattr(exc, 'problem', None) or exc}",
                         Location(source, mark.line + 1 if mark else None)) from None
    except RecursionError:  # PyYAML composes nested nodes recursively
        raise InputError("YAML nested deeper than can be read (a ros2 slave file nests a few levels)",
                         Location(source, 1)) from None
    except ValueError:  # Python refuses to convert an integer of more than 4300 digits
        raise InputError("a number of more than 4300 digits: no startup value is wider than 64 bits",
                         long_number_location(text, source)) from None
    check_tree(doc.data, doc.locate)
    return doc


def load(data: bytes, source: str) -> list[SlaveConfig]:
    text = decode_text(data, source)
    doc = load_located(text, source)
    lines = text.splitlines()
    top = doc.data
    if not isinstance(top, dict):
        raise InputError("an ethercat_driver_ros2 slave file is a mapping (vendor_id, product_id, rpdo, …)",
                         doc.locate(()))

    cfg = SlaveConfig(startup=StartupList(name=Path(source).stem), name=Path(source).stem, source=doc.locate(()))
    if "vendor_id" in top and "product_id" in top:
        cfg.identity = Identity(_int(top["vendor_id"], doc.locate(("vendor_id",)), "vendor_id"),
                                _int(top["product_id"], doc.locate(("product_id",)), "product_id"))
        cfg.startup.vendor_id, cfg.startup.product_code = cfg.identity.vendor_id, cfg.identity.product_code
    if "assign_activate" in top:
        cfg.dc_assign_activate = _int(top["assign_activate"], doc.locate(("assign_activate",)), "assign_activate")
    for i, item in enumerate(as_list(top.get("sdo"), doc.locate(("sdo",)), "sdo")):
        loc = doc.locate(("sdo", i))
        cfg.startup.commands.append(_sdo(item, loc, _comment_at(lines, loc)))
        if isinstance(item, dict):
            _driver_notes(cfg, item, loc)
    for key, direction in (("rpdo", Direction.RX), ("tpdo", Direction.TX)):
        for i, p in enumerate(as_list(top.get(key), doc.locate((key,)), key)):
            ploc = doc.locate((key, i))
            if not isinstance(p, dict) or "index" not in p:
                raise InputError(f"a {key} entry needs an index and channels", ploc)
            pdo = Pdo(direction, _int(p["index"], doc.locate((key, i, "index")), "PDO index"),
                      name=_comment_at(lines, doc.locate((key, i, "index"))), location=ploc)
            for j, ch in enumerate(as_list(p.get("channels"), doc.locate((key, i, "channels")), "channels")):
                cloc = doc.locate((key, i, "channels", j))
                if not isinstance(ch, dict) or "type" not in ch:
                    raise InputError("a channel needs index, sub_index and type", cloc)
                coe, bits = _ros_type(ch["type"], cloc)
                pdo.entries.append(PdoEntry(_int(ch.get("index", 0), cloc, "index"),
                                            _int(ch.get("sub_index", 0), cloc, "sub_index"), bits,
                                            name=_comment_at(lines, cloc), data_type=coe, location=cloc))
                rest = {k: v for k, v in ch.items() if k not in ("index", "sub_index", "type")}
                if rest:
                    cfg.channel_info[(pdo.index, j)] = rest
            cfg.pdos(direction).append(pdo)
    for i, sm in enumerate(as_list(top.get("sm"), doc.locate(("sm",)), "sm")):
        if not isinstance(sm, dict) or not isinstance(sm.get("index"), int) or isinstance(sm.get("index"), bool):
            raise InputError("an sm entry is a mapping {index, type, pdo, watchdog} with an integer index "
                             "(the driver's SMConfig)", doc.locate(("sm", i)))
        if not 0 <= sm["index"] <= 0xFF:
            raise InputError(f"sm index {sm['index']} is out of range (0..255)", doc.locate(("sm", i, "index")))
    for key, value in top.items():
        if key not in _KNOWN_KEYS:
            cfg.extra[key] = value
    return [cfg]


def detect_yaml(top: Any) -> bool:
    return isinstance(top, dict) and any(k in top for k in ("rpdo", "tpdo", "sdo", "product_id"))


def losses(c: SlaveConfig) -> list[str]:
    """What the driver's slave file cannot carry: one-shot writes, SoE commands, DC beyond assign_activate
    (the driver runs SYNC0 at its own period, unshifted, and SYNC1 with it) and float channels (written as the
    unsigned integer of their size: the driver's type2bits maps float/double as 255 bits)."""
    floats = [f"0x{p.index:04X}/0x{e.index:04X}:{e.subindex:02X}" for p in (*c.rx_pdos, *c.tx_pdos) for e in p.entries
              if COE_TO_ROS.get((e.data_type or standard_type(e.index, e.subindex, e.bit_len) or "").upper())
              in DRIVER_CHANNEL_FLOATS]
    out = [f"float channel(s) {', '.join(floats)} written as uint32/uint64 (their raw bits): the driver has no float "
           "channel type (it maps float/double as 255 bits)"] if floats else []
    other = [cmd for cmd in c.commands if cmd.transition != "PS" and cmd.kind != "reset"]
    if other:
        out.append(f"the transition of {len(other)} write(s) ({other[0].transition} {other[0].address}…): the "
                   "driver sends every sdo entry in PRE-OP")
    return (one_shot_losses(c, "ethercat_driver_ros2") + soe_losses(c, "ethercat_driver_ros2") + out
            + dc_losses(c, "ethercat_driver_ros2", shift0=False, sync1_cycle=False, sync1_shift=False))
