"""ecattool's own JSON form of slave configurations: lossless for everything :class:`SlaveConfig` holds.

``{"format": "ecattool-startup", "version": 1, "slaves": [...]}``; data as hex strings, numbers as numbers.
Reading keeps the line of every command (the file is located with the YAML loader, JSON being YAML).
"""

from __future__ import annotations

import json
import math
from typing import Any

from ecattool.errors import InputError, Location
from ecattool.esi.model import Direction, Identity, Pdo, PdoEntry, SyncManager
from ecattool.startup.config import SlaveConfig, SoeCommand
from ecattool.startup.formats._common import (
    MAX_DEPTH,
    as_list,
    check_transition,
    check_tree,
    decode_text,
    long_number_location,
    parse_hex,
)
from ecattool.startup.model import StartupCommand, StartupList

NAME = "json"
EXTENSIONS = (".json",)
DESCRIPTION = "ecattool JSON (lossless: commands, PDOs, identity, DC, SoE)"
FORMAT_TAG = "ecattool-startup"
VERSION = 1


def json_value(v: Any) -> Any:
    if isinstance(v, int) and not isinstance(v, bool) and v.bit_length() > 64:
        return f"0x{v:x}"  # not a value of any CoE type: hex text (decimal stops at Python's 4300 digits)
    if isinstance(v, float) and not math.isfinite(v):
        return str(v)  # JSON has no NaN or infinity
    if v is None or isinstance(v, (bool, int, float, str)):
        return v
    if isinstance(v, (bytes, bytearray)):
        return bytes(v).hex()
    return str(v)


def _cmd(cmd: StartupCommand) -> dict[str, Any]:
    d: dict[str, Any] = {"transition": cmd.transition, "index": cmd.index, "subindex": cmd.subindex,
                         "data": cmd.data.hex()}
    if cmd.comment:
        d["comment"] = cmd.comment
    if cmd.complete_access:
        d["complete_access"] = True
    if cmd.timeout_ms:
        d["timeout_ms"] = cmd.timeout_ms
    if cmd.type_name:
        d["type"] = cmd.type_name
    if cmd.value is not None:
        d["value"] = json_value(cmd.value)
    if cmd.once:
        d["once"] = True
    if not cmd.expect_reply:
        d["expect_reply"] = False
    if not cmd.verify:
        d["verify"] = False
    return d


def _pdo(p: Pdo) -> dict[str, Any]:
    d: dict[str, Any] = {"index": p.index, "name": p.name,
                         "entries": [{"index": e.index, "subindex": e.subindex, "bit_len": e.bit_len,
                                      **({"name": e.name} if e.name else {}),
                                      **({"data_type": e.data_type} if e.data_type else {})} for e in p.entries]}
    if p.sm is not None:
        d["sm"] = p.sm
    return d


def _soe(s: SoeCommand) -> dict[str, Any]:
    return {"transition": s.transition, "idn": s.idn, "drive_no": s.drive_no, "data": s.data.hex(),
            "op_code": s.op_code, "elements": s.elements, "attribute": s.attribute, "comment": s.comment,
            "timeout_ms": s.timeout_ms, "fixed": s.fixed}


def _sm(s: SyncManager) -> dict[str, Any]:
    d: dict[str, Any] = {"number": s.number, "kind": s.kind, "start_address": s.start_address,
                         "control_byte": s.control_byte, "enable": s.enable}
    for key in ("default_size", "min_size", "max_size", "enable_byte"):
        if getattr(s, key) is not None:
            d[key] = getattr(s, key)
    if s.virtual:
        d["virtual"] = True
    if s.op_only:
        d["op_only"] = True
    return d


def slave_to_json(c: SlaveConfig) -> dict[str, Any]:
    d: dict[str, Any] = {"name": c.name, "position": c.position}
    if c.identity is not None:
        d["identity"] = {"vendor_id": c.identity.vendor_id, "product_code": c.identity.product_code,
                         "revision": c.identity.revision, "serial": c.identity.serial}
    dc = {k: v for k, v in (("assign_activate", c.dc_assign_activate), ("cycle_ns", c.dc_cycle_ns),
                            ("shift_ns", c.dc_shift_ns), ("sync1_cycle_ns", c.dc_sync1_cycle_ns),
                            ("sync1_shift_ns", c.dc_sync1_shift_ns)) if v is not None}
    if dc:
        d["dc"] = dc
    d["commands"] = [_cmd(x) for x in c.commands]
    if c.rx_pdos:
        d["rx_pdos"] = [_pdo(p) for p in c.rx_pdos]
    if c.tx_pdos:
        d["tx_pdos"] = [_pdo(p) for p in c.tx_pdos]
    if c.sync_managers:
        d["sync_managers"] = [_sm(s) for s in c.sync_managers]
    if c.soe_commands:
        d["soe_commands"] = [_soe(s) for s in c.soe_commands]
    if c.channel_info:
        d["channel_info"] = [{"pdo": k[0], "entry": k[1], **v} for k, v in c.channel_info.items()]
    if c.extra:
        d["extra"] = c.extra
    if c.notes:
        d["notes"] = [f.to_json() for f in c.notes]
    return d


def export(configs: list[SlaveConfig]) -> str:
    doc = {"format": FORMAT_TAG, "version": VERSION, "slaves": [slave_to_json(c) for c in configs]}
    return json.dumps(doc, indent=2, ensure_ascii=False, default=json_value) + "\n"


# --- reading -----------------------------------------------------------------------------------------

class _Doc:
    def __init__(self, text: str, source: str) -> None:
        self.source = source
        self.located: Any = None
        try:
            from ecattool.yamlloc import load_yaml

            self.located = load_yaml(text, source)
        except (InputError, RecursionError, ValueError):  # the lines are a help; the JSON itself was read
            self.located = None

    def loc(self, *path: str | int) -> Location:
        return self.located.locate(path) if self.located is not None else Location(self.source)


def _need(d: Any, key: str, loc: Location) -> Any:
    if not isinstance(d, dict) or key not in d:
        raise InputError(f"missing {key!r}", loc)
    return d[key]


def _int(v: Any, loc: Location, what: str) -> int:
    if isinstance(v, bool) or not isinstance(v, int):
        raise InputError(f"{what} must be an integer, got {v!r}", loc)
    return v


def _text(v: Any, loc: Location, what: str) -> str | None:
    if v is not None and not isinstance(v, str):
        raise InputError(f"{what} must be text, got {type(v).__name__}", loc)
    return v


def _opt(d: dict[str, Any], key: str, default: int, loc: Location) -> int:
    return _int(d.get(key, default), loc, key)


def _obj(v: Any, loc: Location, what: str) -> dict[str, Any]:
    if not isinstance(v, dict):
        raise InputError(f"{what} must be an object", loc)
    return v


def _read_slave(s: Any, doc: _Doc, i: int) -> SlaveConfig:
    base = ("slaves", i)
    sloc = doc.loc(*base)
    if not isinstance(s, dict):
        raise InputError("a slave must be an object", sloc)
    position = s.get("position")
    cfg = SlaveConfig(startup=StartupList(), name=str(s.get("name") or ""), source=sloc,
                      position=None if position is None else _int(position, sloc, "position"))
    ident = s.get("identity")
    if ident:
        iloc = doc.loc(*base, "identity")
        _obj(ident, iloc, "identity")
        cfg.identity = Identity(_int(_need(ident, "vendor_id", iloc), iloc, "vendor_id"),
                                _int(_need(ident, "product_code", iloc), iloc, "product_code"),
                                _opt(ident, "revision", 0, iloc), _opt(ident, "serial", 0, iloc))
        cfg.startup.vendor_id, cfg.startup.product_code = cfg.identity.vendor_id, cfg.identity.product_code
        cfg.startup.revision = cfg.identity.revision
    cfg.startup.name = cfg.name
    dloc = doc.loc(*base, "dc")
    dc = _obj(s.get("dc") or {}, dloc, "dc")
    (cfg.dc_assign_activate, cfg.dc_cycle_ns, cfg.dc_shift_ns, cfg.dc_sync1_cycle_ns, cfg.dc_sync1_shift_ns) = (
        None if dc.get(k) is None else _int(dc[k], dloc, k)
        for k in ("assign_activate", "cycle_ns", "shift_ns", "sync1_cycle_ns", "sync1_shift_ns"))
    for j, c in enumerate(as_list(s.get("commands"), doc.loc(*base, "commands"), "commands")):
        loc = doc.loc(*base, "commands", j)
        cfg.startup.commands.append(StartupCommand(
            check_transition(str(_need(c, "transition", loc)), loc), _int(_need(c, "index", loc), loc, "index"),
            _int(_need(c, "subindex", loc), loc, "subindex"), parse_hex(str(_need(c, "data", loc)), loc),
            comment=str(c.get("comment", "")), complete_access=bool(c.get("complete_access", False)),
            timeout_ms=_opt(c, "timeout_ms", 0, loc), type_name=_text(c.get("type"), loc, "type"), value=c.get("value"),
            expect_reply=bool(c.get("expect_reply", True)), verify=bool(c.get("verify", True)),
            once=bool(c.get("once", False)), source=loc))
    for key, direction in (("rx_pdos", Direction.RX), ("tx_pdos", Direction.TX)):
        for j, p in enumerate(as_list(s.get(key), doc.loc(*base, key), key)):
            ploc = doc.loc(*base, key, j)
            sm = p.get("sm") if isinstance(p, dict) else None
            pdo = Pdo(direction, _int(_need(p, "index", ploc), ploc, "index"), name=str(p.get("name", "")),
                      sm=None if sm is None else _int(sm, ploc, "sm"), location=ploc)
            for k, e in enumerate(as_list(p.get("entries"), ploc, "entries")):
                eloc = doc.loc(*base, key, j, "entries", k)
                pdo.entries.append(PdoEntry(_int(_need(e, "index", eloc), eloc, "index"),
                                            _opt(e, "subindex", 0, eloc),
                                            _int(_need(e, "bit_len", eloc), eloc, "bit_len"),
                                            name=str(e.get("name", "")), data_type=str(e.get("data_type", "")),
                                            location=eloc))
            cfg.pdos(direction).append(pdo)
    for j, m in enumerate(as_list(s.get("sync_managers"), doc.loc(*base, "sync_managers"), "sync_managers")):
        mloc = doc.loc(*base, "sync_managers", j)
        _obj(m, mloc, "sync manager")
        sizes = {k: None if m.get(k) is None else _int(m[k], mloc, k)
                 for k in ("default_size", "min_size", "max_size", "enable_byte")}
        cfg.sync_managers.append(SyncManager(
            _int(_need(m, "number", mloc), mloc, "number"), str(m.get("kind", "")), _opt(m, "start_address", 0, mloc),
            control_byte=_opt(m, "control_byte", 0, mloc), enable=bool(m.get("enable", True)),
            virtual=bool(m.get("virtual", False)), op_only=bool(m.get("op_only", False)), location=mloc, **sizes))
    for j, x in enumerate(as_list(s.get("soe_commands"), doc.loc(*base, "soe_commands"), "soe_commands")):
        loc = doc.loc(*base, "soe_commands", j)
        cfg.soe_commands.append(SoeCommand(
            check_transition(str(_need(x, "transition", loc)), loc), _int(_need(x, "idn", loc), loc, "idn"),
            parse_hex(str(x.get("data", "")), loc), drive_no=_opt(x, "drive_no", 0, loc),
            op_code=_opt(x, "op_code", 3, loc), elements=_opt(x, "elements", 64, loc),
            attribute=_opt(x, "attribute", 0, loc), comment=str(x.get("comment", "")),
            timeout_ms=_opt(x, "timeout_ms", 0, loc), fixed=bool(x.get("fixed", False)), source=loc))
    for j, ch in enumerate(as_list(s.get("channel_info"), doc.loc(*base, "channel_info"), "channel_info")):
        cloc = doc.loc(*base, "channel_info", j)
        rest = {k: v for k, v in _obj(ch, cloc, "channel_info entry").items() if k not in ("pdo", "entry")}
        channel = (_int(_need(ch, "pdo", cloc), cloc, "pdo"), _int(_need(ch, "entry", cloc), cloc, "entry"))
        cfg.channel_info[channel] = rest
    cfg.extra = dict(_obj(s.get("extra") or {}, doc.loc(*base, "extra"), "extra"))
    return cfg


def load(data: bytes, source: str) -> list[SlaveConfig]:
    text = decode_text(data, source)
    try:
        top = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"invalid JSON: {exc.msg}", Location(source, exc.lineno, exc.colno)) from None
    except RecursionError:
        raise InputError(f"JSON nested deeper than Python can read (a startup file nests {MAX_DEPTH} levels at most)",
                         Location(source, 1)) from None
    except ValueError:  # Python refuses to convert an integer of more than 4300 digits
        raise InputError("a number of more than 4300 digits: no startup value is wider than 64 bits",
                         long_number_location(text, source)) from None
    if not isinstance(top, dict) or top.get("format") != FORMAT_TAG:
        raise InputError(f"not an ecattool startup JSON file (expected \"format\": \"{FORMAT_TAG}\")",
                         Location(source, 1))
    if top.get("version") != VERSION:
        raise InputError(f"unsupported ecattool startup JSON version {top.get('version')!r} (this is {VERSION})",
                         Location(source, 1))
    check_tree(top, lambda path: Location(source))  # before locating it: a deep document stops here
    doc = _Doc(text, source)
    check_tree(top, lambda path: doc.loc(*path))
    slaves = as_list(top.get("slaves"), doc.loc("slaves"), "slaves")
    return [_read_slave(s, doc, i) for i, s in enumerate(slaves)]


def detect(data: bytes) -> bool:
    return data.lstrip()[:1] == b"{" and FORMAT_TAG.encode() in data[:4096]
