"""Small helpers the format modules share: hex data, comments, type names by size, C/Python names."""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from ecattool.errors import EncodeError, InputError, Location
from ecattool.esi.model import Direction, Identity, Pdo
from ecattool.findings import Severity
from ecattool.startup.config import SlaveConfig
from ecattool.startup.model import TRANSITIONS, StartupCommand, is_pdo_programming

#: unsigned type names by byte size, for commands that carry no type
_UNSIGNED_BY_SIZE = {1: "USINT", 2: "UINT", 4: "UDINT", 8: "ULINT"}


def unsigned_type(size: int) -> str | None:
    return _UNSIGNED_BY_SIZE.get(size)



def parse_hex(text: str, location: Location | None, what: str = "data") -> bytes:
    """Hex bytes as written by TwinCAT/lcec/ecattool: ``0116``, ``01 16``, ``0x01 0x16``."""
    s = re.sub(r"0x", "", (text or "").strip(), flags=re.IGNORECASE).replace(" ", "").replace(",", "")
    try:
        return bytes.fromhex(s)
    except ValueError:
        raise InputError(f"{what} {text!r} is not hex bytes (write e.g. 0116 or '01 16')", location) from None


def one_line(text: str) -> str:
    """Comments in line-based formats: no line breaks, trimmed."""
    return " ".join((text or "").split())


def check_transition(text: str, location: Location | None) -> str:
    t = (text or "").strip().upper()
    if t not in TRANSITIONS:
        raise InputError(f"unknown transition {text!r} (expected one of {', '.join(TRANSITIONS)})", location)
    return t


def int_in_range(value: int, bits: int, location: Location | None, what: str) -> int:
    if not 0 <= value < (1 << bits):
        raise InputError(f"{what} {value} is out of range (0..0x{(1 << bits) - 1:X})", location)
    return value


def encode_sized(value: int, size: int, location: Location | None, what: str = "value") -> bytes:
    """An integer written with an explicit byte size (ecmc, TwinCAT): negative values in two's complement."""
    if size <= 0 or size > 8:
        raise InputError(f"byte size {size} is not 1..8", location)
    if -(1 << (8 * size - 1)) <= value < 0:
        value += 1 << (8 * size)
    if not 0 <= value < (1 << (8 * size)):
        shown = value if value.bit_length() <= 64 else f"of {value.bit_length()} bits"
        raise InputError(f"{what} {shown} does not fit in {size} byte(s)", location)
    return value.to_bytes(size, "little")


def require_identity(c: SlaveConfig, consumer: str) -> Identity:
    """The slave's vendor id and product code, which ``consumer`` needs: refused when the source has none
    (a 0 there would make the master reject the real slave, or match nothing)."""
    if c.identity is None:
        raise EncodeError(f"{c.label}: no vendor id/product code is known (the source does not give them), and "
                          f"{consumer} needs them; convert from a source that names the device (an ESI-based "
                          "project, ENI or ros2 file)", c.source)
    return c.identity


def one_shot_text(cmd: StartupCommand) -> str:
    """How exporters name a one-shot write they leave out of the startup list."""
    where = f" ({cmd.source})" if cmd.source else ""
    what = f": {one_line(cmd.comment)}" if cmd.comment else ""
    return (f"0x{cmd.index:04X}:{cmd.subindex:02X} := 0x{cmd.int_value:X}{what}{where} is a one-shot write (the drive "
            "answers it by resetting); a startup list is re-sent at every reconfiguration, so send it once "
            "(ecattool commission or sw download does)")


def identifier(text: str, default: str = "slave") -> str:
    """A C/Python identifier made from a slave name."""
    s = re.sub(r"[^0-9A-Za-z_]+", "_", text or "").strip("_").lower()
    if not s:
        s = default
    if s[0].isdigit():
        s = f"{default}_{s}"
    return s


def unique_identifiers(configs: list[SlaveConfig]) -> list[str]:
    seen: dict[str, int] = {}
    out = []
    for i, c in enumerate(configs):
        base = identifier(c.name or (f"slave{c.position}" if c.position is not None else f"slave{i}"))
        n = seen.get(base, 0)
        seen[base] = n + 1
        out.append(base if n == 0 else f"{base}_{n + 1}")
    return out




def decode_text(data: bytes, source: str) -> str:
    """UTF-8 text (a BOM allowed); invalid bytes are an error naming the line."""
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        raise InputError(f"not UTF-8 text (byte 0x{data[exc.start]:02X})", Location(source, line)) from None


def as_list(value: object, location: Location | None, what: str) -> list[Any]:
    """A YAML/JSON value that must be a list (None = empty)."""
    if value is None:
        return []
    if not isinstance(value, list):
        raise InputError(f"{what} must be a list, got {type(value).__name__}", location)
    return value


#: the largest data of one startup download ecattool accepts (a CoE segmented download could be longer, but no
#: startup list holds more than a few kilobytes; a bound keeps every exporter's work small)
MAX_DATA_BYTES = 1 << 16


def _bounded(value: int | None, low: int, high: int, what: str, location: Location | None) -> None:
    """``value`` (None: not given) within ``low..high``, else a located error (a huge value named by its size)."""
    if value is not None and not low <= value <= high:
        raise InputError(f"{what} {value if abs(value) < 1 << 64 else 'of ' + str(value.bit_length()) + ' bits'} is "
                         f"out of range ({low}..{high})", location)


def check_commands(configs: list[SlaveConfig]) -> None:
    """Every number a source gives is within the domain of what it describes, whatever format it came from:
    object index and sub-index, data size, timeout, bus position, identity, DC, PDO entries (a mapping entry's
    bit length is one byte: 0..255, so a PDO table never makes an exporter loop over millions of bits)."""
    for c in configs:
        _bounded(c.position, 0, 0xFFFF, "bus position", c.source)
        if c.identity is not None:
            for what, v in (("vendor id", c.identity.vendor_id), ("product code", c.identity.product_code),
                            ("revision", c.identity.revision), ("serial", c.identity.serial)):
                _bounded(v, 0, 0xFFFFFFFF, what, c.source)
        _bounded(c.dc_assign_activate, 0, 0xFFFF, "DC assign activate", c.source)
        for what, cycle in (("SYNC0 cycle", c.dc_cycle_ns), ("SYNC1 cycle", c.dc_sync1_cycle_ns)):
            _bounded(cycle, 0, 0xFFFFFFFF, f"{what} (ns)", c.source)
        for what, shift in (("SYNC0 shift", c.dc_shift_ns), ("SYNC1 shift", c.dc_sync1_shift_ns)):
            _bounded(shift, -(1 << 31), 0xFFFFFFFF, f"{what} (ns)", c.source)
        for cmd in c.commands:
            if not 0 <= cmd.index <= 0xFFFF or not 0 <= cmd.subindex <= 0xFF:
                raise InputError(f"object 0x{cmd.index:X}:{cmd.subindex:X} is out of range (index 0..0xFFFF, "
                                 "sub-index 0..0xFF)", cmd.source)
            if not cmd.data:
                raise InputError(f"{cmd.address}: a startup download needs at least one data byte", cmd.source)
            if len(cmd.data) > MAX_DATA_BYTES:
                raise InputError(f"{cmd.address}: {len(cmd.data)} data bytes; a startup download of more than "
                                 f"{MAX_DATA_BYTES} bytes is not accepted", cmd.source)
            _bounded(cmd.timeout_ms, 0, 0xFFFFFFFF, f"{cmd.address}: timeout (ms)", cmd.source)
        for s in c.soe_commands:
            if not 0 <= s.idn <= 0xFFFF or not 0 <= s.drive_no <= 7:
                raise InputError(f"SoE IDN {s.idn} drive {s.drive_no} is out of range", s.source)
            if len(s.data) > MAX_DATA_BYTES:
                raise InputError(f"SoE IDN {s.idn}: {len(s.data)} data bytes is more than {MAX_DATA_BYTES}", s.source)
            for what, v, high in (("op code", s.op_code, 0xFF), ("elements", s.elements, 0xFF),
                                  ("attribute", s.attribute, 0xFFFFFFFF), ("timeout (ms)", s.timeout_ms, 0xFFFFFFFF)):
                _bounded(v, 0, high, f"SoE IDN {s.idn}: {what}", s.source)
        for p in (*c.rx_pdos, *c.tx_pdos):
            loc = p.location or c.source
            _bounded(p.index, 0, 0xFFFF, "PDO index", loc)
            _bounded(p.sm, 0, 0xFF, f"PDO 0x{p.index:04X}: sync manager", loc)
            for e in p.entries:
                eloc = e.location or loc
                _bounded(e.index, 0, 0xFFFF, f"PDO 0x{p.index:04X}: entry index", eloc)
                _bounded(e.subindex, 0, 0xFF, f"PDO 0x{p.index:04X}: entry sub-index", eloc)
                _bounded(e.bit_len, 0, 0xFF, f"PDO 0x{p.index:04X}: entry bit length", eloc)
        for sm in c.sync_managers:
            loc = sm.location or c.source
            _bounded(sm.number, 0, 0xFF, "sync manager number", loc)
            for what, size in (("start address", sm.start_address), ("default size", sm.default_size),
                               ("min size", sm.min_size), ("max size", sm.max_size)):
                _bounded(size, 0, 0xFFFF, f"SM{sm.number} {what}", loc)
            _bounded(sm.control_byte, 0, 0xFF, f"SM{sm.number} control byte", loc)


#: how deep a JSON/YAML startup document may nest (the deepest real one nests 6 levels)
MAX_DEPTH = 32


def check_tree(node: Any, locate: Callable[[tuple[str | int, ...]], Location]) -> None:
    """A parsed JSON/YAML document holds no integer beyond 64 bits and nests at most :data:`MAX_DEPTH` levels:
    what no startup value is, and what writers would fail on (checked iteratively, so a deep document cannot
    exhaust the stack). NaN and infinity pass: ros2 channels use ``default: .nan``."""
    stack: list[tuple[Any, tuple[str | int, ...]]] = [(node, ())]
    while stack:
        value, path = stack.pop()
        if len(path) > MAX_DEPTH:
            raise InputError(f"nesting deeper than {MAX_DEPTH} levels", locate(path))
        if isinstance(value, bool):
            continue
        if isinstance(value, int) and not -(1 << 64) < value < (1 << 64):
            raise InputError(f"number of {value.bit_length()} bits: no startup value is wider than 64 bits",
                             locate(path))
        if isinstance(value, dict):
            stack += [(v, (*path, str(k))) for k, v in value.items()]
        elif isinstance(value, list):
            stack += [(v, (*path, i)) for i, v in enumerate(value)]


def long_number_location(text: str, source: str) -> Location:
    """The line of the first number too long for Python to convert (more than 4300 digits)."""
    m = re.search(r"\d{4300}", text)
    return Location(source, text.count("\n", 0, m.start()) + 1 if m else None)


@dataclass(slots=True)
class SmPlan:
    """One sync manager as a master's PDO configuration lists it (IgH ``ec_sync_info_t``, ENI ``Sm``)."""

    number: int
    output: bool
    pdos: list[Pdo] = field(default_factory=list)
    watchdog: bool | None = None  # None: the master's default
    mailbox: bool = False


def _ros2_sm(c: SlaveConfig) -> list[dict[str, Any]]:
    sms = c.extra.get("sm")
    return [s for s in sms if isinstance(s, dict)] if isinstance(sms, list) else []


def pdo_sm(c: SlaveConfig, pdo: Pdo) -> int:
    """The sync manager ``pdo`` is assigned to: as the source says (the PDO's ``sm``, the ros2 ``sm`` section,
    the device's process-data sync manager of that direction), else SM2 for outputs and SM3 for inputs."""
    if pdo.sm is not None:
        return pdo.sm
    key = "rpdo" if pdo.direction is Direction.RX else "tpdo"
    for s in _ros2_sm(c):
        if s.get("pdo") == key and isinstance(s.get("index"), int):
            return int(s["index"])
    for sm in c.sync_managers:
        if sm.kind == pdo.direction.sm_kind:
            return sm.number
    return 2 if pdo.direction is Direction.RX else 3


def sm_watchdog(c: SlaveConfig, number: int) -> bool | None:
    """Whether the source enables the watchdog of sync manager ``number``: the ros2 ``sm`` section's
    ``watchdog``, or bit 6 of the sync manager's ControlByte (ESI/ENI); None when the source does not say."""
    for s in _ros2_sm(c):
        if s.get("index") == number and s.get("watchdog") in ("enable", "disable"):
            return bool(s["watchdog"] == "enable")
    for sm in c.sync_managers:
        if sm.number == number and sm.control_byte:
            return bool(sm.control_byte & 0x40)
    return None


def sync_plan(c: SlaveConfig) -> list[SmPlan]:
    """The sync managers of the slave in number order, with their assigned PDOs: the mailbox sync managers the
    source names (SM0/SM1 when it names none and the PDOs leave them free), every process-data sync manager
    of the source (empty ones too: their assignment is cleared) and those the PDOs are assigned to."""
    plans: dict[int, SmPlan] = {}
    for sm in c.sync_managers:
        if sm.kind in ("MBoxOut", "MBoxIn"):
            plans[sm.number] = SmPlan(sm.number, sm.kind == "MBoxOut", mailbox=True)
        elif sm.kind in ("Outputs", "Inputs"):
            plans[sm.number] = SmPlan(sm.number, sm.kind == "Outputs")
    for s in _ros2_sm(c):
        if isinstance(s.get("index"), int) and s.get("type") in ("input", "output") and s["index"] not in plans:
            plans[s["index"]] = SmPlan(s["index"], s["type"] == "output")
    for p in (*c.rx_pdos, *c.tx_pdos):
        n = pdo_sm(c, p)
        plan = plans.setdefault(n, SmPlan(n, p.direction is Direction.RX))
        plan.pdos.append(p)
    if not any(sm.kind in ("MBoxOut", "MBoxIn") for sm in c.sync_managers):
        for n, out in ((0, True), (1, False)):
            if n not in plans and not c.sync_managers:
                plans[n] = SmPlan(n, out, mailbox=True)
    for plan in plans.values():
        plan.watchdog = None if plan.mailbox else sm_watchdog(c, plan.number)
    return [plans[n] for n in sorted(plans)]


# --- what a format cannot carry -----------------------------------------------------------------------

def _where(items: list[Any]) -> str:
    first = next((x.source for x in items if getattr(x, "source", None) is not None), None)
    return f", first at {first}" if first else ""


def one_shot_losses(c: SlaveConfig, fmt: str) -> list[str]:
    """The one-shot writes a format with startup writes only cannot run once: once-writes (EEPROM programming)
    are written as startup writes in their order, as its master runs them (re-sent at every configuration);
    a reset is left out (a comment names it): in a startup list it would reset the drive at every
    configuration and abort what follows."""
    out = []
    once = [cmd for cmd in c.commands if cmd.kind == "once"]
    if once:
        out.append(f"{len(once)} once-write(s) ({once[0].address} … {once[-1].address}{_where(once)}) are written as "
                   f"startup writes: {fmt} has no one-shot write, its master re-sends them at every configuration")
    resets = [cmd for cmd in c.commands if cmd.kind == "reset"]
    if resets:
        out.append(f"{len(resets)} reset write(s) ({resets[0].address}{_where(resets)}) left out: {fmt} has no "
                   "one-shot write, and a reset among startup writes would reset the drive at every configuration")
    return out


def soe_losses(c: SlaveConfig, fmt: str) -> list[str]:
    if not c.soe_commands:
        return []
    return [f"{len(c.soe_commands)} SoE command(s) ({c.soe_commands[0].address}{_where(c.soe_commands)}): {fmt} "
            "has no SoE write"]


def dc_losses(c: SlaveConfig, fmt: str, *, dc: bool = True, shift0: bool = True, sync1_cycle: bool = True,
              sync1_shift: bool = True) -> list[str]:
    """The DC settings of ``c`` that ``fmt`` has no place for (each keyword: whether it has one)."""
    if not c.dc_assign_activate:
        return []
    if not dc:
        cycle = f"SYNC0 cycle {c.dc_cycle_ns} ns" if c.dc_cycle_ns else "no SYNC0 cycle given"
        return [f"DC (AssignActivate 0x{c.dc_assign_activate:04X}, {cycle}): {fmt} has no DC setting"]
    out = []
    if not shift0 and c.dc_shift_ns:
        out.append(f"SYNC0 shift {c.dc_shift_ns} ns: {fmt} has no SYNC0 shift")
    if not sync1_cycle and c.dc_sync1_cycle_ns:
        out.append(f"SYNC1 cycle {c.dc_sync1_cycle_ns} ns: {fmt} has no SYNC1 cycle")
    if not sync1_shift and c.dc_sync1_shift_ns:
        out.append(f"SYNC1 shift {c.dc_sync1_shift_ns} ns: {fmt} has no SYNC1 shift")
    return out


def pdo_table_losses(c: SlaveConfig, fmt: str) -> list[str]:
    """PDO tables that no startup write programs (a ros2, lcec or ecmc source), in a format of startup writes."""
    if not c.has_pdo_info or any(is_pdo_programming(cmd.index) for cmd in c.commands):
        return []
    pdos = [f"0x{p.index:04X}" for p in (*c.rx_pdos, *c.tx_pdos)]
    return [f"PDO assignment and mapping ({', '.join(pdos)}): the source gives them as tables, and {fmt} only as "
            "startup writes, which the source has none of"]


# --- contradictions within one source -------------------------------------------------------------------

def _programmed_pdos(c: SlaveConfig) -> tuple[dict[int, list[int]], dict[int, list[StartupCommand]]]:
    """What the startup writes leave in the PDO objects, replayed in order: object -> its sub-index values
    (mapping words for 1600h-1BFFh, PDO indices for 1C12h/1C13h), and the writes to each object."""
    subs: dict[int, dict[int, int]] = {}
    writes: dict[int, list[StartupCommand]] = {}
    for cmd in c.commands:
        if not is_pdo_programming(cmd.index):
            continue
        width = 2 if cmd.index in (0x1C12, 0x1C13) else 4
        obj = subs.setdefault(cmd.index, {})
        writes.setdefault(cmd.index, []).append(cmd)
        if cmd.complete_access and cmd.subindex == 0 and len(cmd.data) >= 2:
            obj.clear()
            obj[0] = cmd.data[0]
            body = cmd.data[2:]
            for k in range(len(body) // width):
                obj[k + 1] = int.from_bytes(body[k * width:(k + 1) * width], "little")
        else:
            obj[cmd.subindex] = int.from_bytes(cmd.data[:width], "little")
    # sub-index 0 holds a count of at most 255 sub-indices (a longer write there is bounded, not replayed)
    return ({index: [obj.get(k, 0) for k in range(1, min(obj.get(0, 0), 0xFF) + 1)] for index, obj in subs.items()},
            writes)


def find_contradictions(configs: list[SlaveConfig]) -> None:
    """Findings (notes, with the source line) for what one source says two ways: a PDO table whose entries or
    assignment differ from what the same source's startup writes program into that object, and PDO tables of
    SoE IDNs where CoE mapping objects go."""
    for c in configs:
        pdos = [*c.rx_pdos, *c.tx_pdos]
        idns = [p for p in pdos if not is_pdo_programming(p.index)]
        if idns:
            c.note("startup.pdo.soe", f"PDO(s) {', '.join(f'0x{p.index:04X}' for p in idns)} are no CoE mapping "
                   "objects (1600h-17FFh, 1A00h-1BFFh)" + (": SoE IDNs (AT/MDT telegrams, set by the SoE commands)"
                                                           if c.soe_commands else "") +
                   "; an exporter that programs PDOs over CoE (pysoem) does not write them into 1C12h/1C13h",
                   idns[0].location or c.source, Severity.WARNING)
        if not pdos:
            continue
        state, writes = _programmed_pdos(c)
        for p in pdos:
            if p.index not in state:
                continue
            table = [(e.index << 16) | (e.subindex << 8) | e.bit_len for e in p.entries]
            if state[p.index] != table:
                lines = ", ".join(str(w.source.line) for w in writes[p.index] if w.source and w.source.line)
                bits = sum(w & 0xFF for w in state[p.index])
                c.note("startup.pdo.conflict", f"PDO 0x{p.index:04X} is declared with {len(p.entries)} entries "
                       f"({p.bit_size} bits) but the startup writes (line(s) {lines}) map {len(state[p.index])} "
                       f"({bits} bits): " + ", ".join(f"{w >> 16:04X}:{(w >> 8) & 0xFF:02X}/{w & 0xFF}"
                                                      for w in state[p.index]) + "; the source contradicts itself",
                       p.location or c.source, Severity.WARNING)
        for assign, direction_pdos in ((0x1C12, c.rx_pdos), (0x1C13, c.tx_pdos)):
            if assign in state and direction_pdos and state[assign] != [p.index for p in direction_pdos]:
                lines = ", ".join(str(w.source.line) for w in writes[assign] if w.source and w.source.line)
                c.note("startup.pdo.conflict", f"0x{assign:04X} is written with PDO(s) "
                       f"{', '.join(f'0x{x:04X}' for x in state[assign]) or 'none'} (line(s) {lines}) but the PDO "
                       f"tables assign {', '.join(f'0x{p.index:04X}' for p in direction_pdos)}; the source "
                       "contradicts itself", direction_pdos[0].location or c.source, Severity.WARNING)
