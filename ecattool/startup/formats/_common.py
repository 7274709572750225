"""Small helpers the format modules share: hex data, comments, type names by size, C/Python names."""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any

from ecattool.errors import EncodeError, InputError, Location
from ecattool.esi.model import Direction, Identity, Pdo
from ecattool.startup.config import SlaveConfig
from ecattool.startup.model import TRANSITIONS, StartupCommand

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
        raise InputError(f"{what} {value} does not fit in {size} byte(s)", location)
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


def check_commands(configs: list[SlaveConfig]) -> None:
    """Index, sub-index and data of every command are within CoE limits (whatever format they came from)."""
    for c in configs:
        for cmd in c.commands:
            if not 0 <= cmd.index <= 0xFFFF or not 0 <= cmd.subindex <= 0xFF:
                raise InputError(f"object 0x{cmd.index:X}:{cmd.subindex:X} is out of range (index 0..0xFFFF, "
                                 "sub-index 0..0xFF)", cmd.source)
            if not cmd.data:
                raise InputError(f"{cmd.address}: a startup download needs at least one data byte", cmd.source)
        for s in c.soe_commands:
            if not 0 <= s.idn <= 0xFFFF or not 0 <= s.drive_no <= 7:
                raise InputError(f"SoE IDN {s.idn} drive {s.drive_no} is out of range", s.source)


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
