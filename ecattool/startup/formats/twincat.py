"""TwinCAT startup-list text lines, as TwinCAT shows and exports the "Startup" tab.

One command per line: ``<PS>,CoE,0x1C12:00,0x00 (0),clear sm pdos`` — transition, protocol, object,
value (hex of the object's exact width, then the unsigned decimal), comment. ecattool's additions, all
read back by :func:`load`: `` CA`` after the object for Complete Access, data longer than 8 bytes as hex
bytes (``03 00 01 16 02 16``), and SoE lines ``<PS>,SoE,IDN 15 drive 0,0700,comment``.
Lines starting with ``#`` and blank lines are ignored on reading.
"""

from __future__ import annotations

import re

from ecattool.errors import EncodeError, InputError, Location
from ecattool.startup.config import SlaveConfig, SoeCommand
from ecattool.startup.formats._common import (
    check_transition,
    dc_losses,
    decode_text,
    int_in_range,
    one_line,
    one_shot_losses,
    one_shot_text,
    parse_hex,
    pdo_table_losses,
    unsigned_type,
)
from ecattool.startup.model import StartupCommand, StartupList

NAME = "twincat"
EXTENSIONS = (".txt",)
DESCRIPTION = "TwinCAT startup list text lines (<PS>,CoE,0x1C12:00,0x00 (0),comment)"

_LINE = re.compile(r"^\s*<([A-Za-z]{2})>\s*,")
_ADDR = re.compile(r"^(?:0x)?([0-9A-Fa-f]{1,4})\s*:\s*(?:0x)?([0-9A-Fa-f]{1,2})(\s+CA)?$", re.IGNORECASE)
_INT_VALUE = re.compile(r"^0x([0-9A-Fa-f ]+?)\s*(?:\(\s*-?\d*\s*\))?$")
_SOE_ADDR = re.compile(r"^IDN\s+(\d+)\s+drive\s+(\d+)$", re.IGNORECASE)


def format_value(data: bytes) -> str:
    if 0 < len(data) <= 8:
        v = int.from_bytes(data, "little")
        return f"0x{v:0{2 * len(data)}X} ({v})"
    return " ".join(f"{b:02X}" for b in data)


def format_line(cmd: StartupCommand) -> str:
    ca = " CA" if cmd.complete_access else ""
    address = f"0x{cmd.index:04X}:{cmd.subindex:02X}{ca}"
    return f"<{cmd.transition}>,CoE,{address},{format_value(cmd.data)},{one_line(cmd.comment)}"


def export(configs: list[SlaveConfig]) -> str:
    if len(configs) != 1:
        raise EncodeError(f"a TwinCAT startup list holds one slave; got {len(configs)} (export them one by one: --drive)")
    c = configs[0]
    # a one-shot write (a reset the drive answers by resetting) is no startup line: TwinCAT sends the list at
    # every transition; it stays visible as a comment line (skipped when read back)
    lines = [f"# not a startup line: {one_shot_text(cmd)}" if cmd.kind == "reset" else format_line(cmd) for cmd in c.commands]
    for s in c.soe_commands:
        lines.append(f"<{s.transition}>,SoE,IDN {s.idn} drive {s.drive_no},{s.data.hex()},{one_line(s.comment)}")
    return "".join(line + "\n" for line in lines)


def parse_value(text: str, loc: Location) -> bytes:
    t = text.strip()
    m = _INT_VALUE.match(t)
    if m:
        digits = m.group(1).replace(" ", "")
        if not digits or len(digits) % 2:
            raise InputError(f"value {text!r} needs an even number of hex digits; the width gives the size", loc)
        return int(digits, 16).to_bytes(len(digits) // 2, "little")
    data = parse_hex(t, loc, "value")
    if not data:
        raise InputError("empty value (write 0x00 (0) for a one-byte zero)", loc)
    return data


def parse_line(line: str, loc: Location) -> StartupCommand | SoeCommand:
    """One TwinCAT startup line → a command (the comment may contain commas)."""
    parts = line.rstrip("\r\n").split(",", 4)
    if len(parts) < 4 or not _LINE.match(line):
        raise InputError("not a TwinCAT startup line (expected <PS>,CoE,0x1C12:00,0x00 (0),comment)", loc)
    transition = check_transition(parts[0].strip()[1:-1], loc)
    proto, addr, value = parts[1].strip(), parts[2].strip(), parts[3]
    comment = parts[4].strip() if len(parts) > 4 else ""
    if proto.upper() == "SOE":
        m = _SOE_ADDR.match(addr)
        if not m:
            raise InputError(f"SoE address {addr!r} is not 'IDN <n> drive <d>'", loc)
        return SoeCommand(transition, int_in_range(int(m.group(1)), 16, loc, "IDN"), parse_hex(value, loc),
                          drive_no=int(m.group(2)), comment=comment, source=loc)
    if proto.upper() != "COE":
        raise InputError(f"protocol {proto!r} is not supported (CoE or SoE)", loc)
    m = _ADDR.match(addr)
    if not m:
        raise InputError(f"object {addr!r} is not an address like 0x1C12:00", loc)
    data = parse_value(value, loc)
    return StartupCommand(transition, int(m.group(1), 16), int(m.group(2), 16), data, comment=comment,
                          complete_access=bool(m.group(3)), type_name=unsigned_type(len(data)),
                          value=int.from_bytes(data, "little") if len(data) <= 8 else None, source=loc)


def load(data: bytes, source: str) -> list[SlaveConfig]:
    text = decode_text(data, source)
    cfg = SlaveConfig(startup=StartupList(), source=Location(source, 1))
    for n, line in enumerate(text.splitlines(), 1):
        s = line.strip()
        if not s or s.startswith("#"):
            continue
        item = parse_line(s, Location(source, n))
        if isinstance(item, SoeCommand):
            cfg.soe_commands.append(item)
        else:
            cfg.startup.commands.append(item)
    return [cfg]


def detect(data: bytes) -> bool:
    for line in data.decode("utf-8-sig", errors="replace").splitlines()[:20]:
        s = line.strip()
        if s and not s.startswith("#"):
            return bool(_LINE.match(s)) and s.count(",") >= 3
    return False


def losses(c: SlaveConfig) -> list[str]:
    """What TwinCAT startup lines cannot carry: one-shot writes, DC and PDO tables no startup write programs."""
    return (one_shot_losses(c, "a TwinCAT startup list") + dc_losses(c, "a TwinCAT startup list", dc=False)
            + pdo_table_losses(c, "a TwinCAT startup list"))


def nothing_left(c: SlaveConfig) -> bool:
    return not c.soe_commands and all(cmd.kind == "reset" for cmd in c.commands)
