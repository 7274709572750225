"""CSV: one startup command per row, for spreadsheets and reviews.

Columns: ``slave, position, transition, index, subindex, data, complete_access, timeout_ms, type, value,
comment, kind``. Index and sub-index as hex (``0x1C12``, ``0x00``), data as little-endian hex bytes, value as JSON
(so ``-3``, ``2.5`` and ``"FOESW_x"`` come back as they were). Identity, PDO information and SoE commands
are not part of the CSV form (use JSON or ENI for those).
"""

from __future__ import annotations

import csv
import io
import json
from typing import Any

from ecattool.errors import InputError, Location
from ecattool.od.numbers import parse_int
from ecattool.startup.config import SlaveConfig
from ecattool.startup.formats._common import (
    check_transition,
    dc_losses,
    decode_text,
    parse_hex,
    pdo_table_losses,
    soe_losses,
)
from ecattool.startup.formats.jsonfmt import json_value
from ecattool.startup.model import KINDS, StartupCommand, StartupList, set_kind

NAME = "csv"
EXTENSIONS = (".csv",)
DESCRIPTION = "CSV, one command per row (slave, position, transition, index, subindex, data, …)"
COLUMNS = ("slave", "position", "transition", "index", "subindex", "data", "complete_access", "timeout_ms", "type",
           "value", "comment")
#: the last column (files without it are read as startup writes): when the write happens (startup, once, reset;
#: ``+noverify`` where a read-back cannot return what was written)
KIND_COLUMN = "kind"


def export(configs: list[SlaveConfig]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow((*COLUMNS, KIND_COLUMN))
    for c in configs:
        for cmd in c.commands:
            kind = cmd.kind + ("" if cmd.verify else "+noverify")
            value = "" if cmd.value is None else json.dumps(json_value(cmd.value))
            w.writerow([c.name, "" if c.position is None else c.position, cmd.transition, f"0x{cmd.index:04X}",
                        f"0x{cmd.subindex:02X}", cmd.data.hex(), "1" if cmd.complete_access else "0", cmd.timeout_ms,
                        cmd.type_name or "", value, cmd.comment, kind])
    return buf.getvalue()


def load(data: bytes, source: str) -> list[SlaveConfig]:
    text = decode_text(data, source)
    reader = csv.reader(io.StringIO(text))
    try:
        return _rows(reader, source)
    except csv.Error as exc:  # a line break or NUL inside an unquoted cell, a cell over the csv module's limit
        raise InputError(f"not CSV: {exc}", Location(source, reader.line_num or 1)) from None


def _rows(reader: Any, source: str) -> list[SlaveConfig]:  # a csv reader (its type is private)
    header = next(reader, None)
    if header is None or [h.strip().lower() for h in header[:len(COLUMNS)]] != list(COLUMNS):
        raise InputError(f"CSV header must be: {','.join(COLUMNS)},{KIND_COLUMN}", Location(source, 1))
    with_kind = len(header) > len(COLUMNS) and header[len(COLUMNS)].strip().lower() == KIND_COLUMN
    slaves: dict[tuple[str, str], SlaveConfig] = {}
    for row in reader:
        loc = Location(source, reader.line_num)
        if not any(cell.strip() for cell in row):
            continue
        if len(row) < len(COLUMNS):
            raise InputError(f"row has {len(row)} columns, expected {len(COLUMNS)}", loc)
        rec = dict(zip(COLUMNS, row))
        key = (rec["slave"], rec["position"].strip())
        cfg = slaves.get(key)
        if cfg is None:
            pos = parse_int(key[1], loc, "position") if key[1] else None
            cfg = SlaveConfig(startup=StartupList(name=rec["slave"]), name=rec["slave"], position=pos, source=loc)
            slaves[key] = cfg
        value = None
        if rec["value"].strip():
            try:
                value = json.loads(rec["value"])
            except (ValueError, RecursionError):  # not JSON (or a number past Python's 4300 digits): the text
                value = rec["value"]
            if not isinstance(value, (bool, int, float, str)) or isinstance(value, int) and value.bit_length() > 64:
                value = rec["value"]  # a value is one number or text; anything else stays as written
        cmd = StartupCommand(
            check_transition(rec["transition"], loc), parse_int(rec["index"], loc, "index"),
            parse_int(rec["subindex"], loc, "subindex"), parse_hex(rec["data"], loc),
            comment=rec["comment"], complete_access=rec["complete_access"].strip().lower() in ("1", "true", "yes"),
            timeout_ms=parse_int(rec["timeout_ms"] or "0", loc, "timeout_ms"), type_name=rec["type"] or None,
            value=value, source=loc)
        kind, *flags = (row[len(COLUMNS)] if with_kind and len(row) > len(COLUMNS) else "").strip().lower().split("+")
        if kind not in ("", *KINDS) or any(f != "noverify" for f in flags):
            raise InputError(f"kind {row[len(COLUMNS)]!r} is not one of {', '.join(KINDS)} (+noverify)", loc)
        set_kind(cmd, kind or "startup")
        cmd.verify = "noverify" not in flags
        cfg.startup.commands.append(cmd)
    return list(slaves.values())


def detect(data: bytes) -> bool:
    return data.lstrip(b"\xef\xbb\xbf").lower().startswith(b"slave,position,transition")


def losses(c: SlaveConfig) -> list[str]:
    """What CSV rows cannot carry: SoE commands, DC and PDO tables no startup write programs."""
    return soe_losses(c, "CSV") + dc_losses(c, "CSV", dc=False) + pdo_table_losses(c, "CSV")


def nothing_left(c: SlaveConfig) -> bool:
    return not c.commands
