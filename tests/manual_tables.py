"""Object tables read straight from the manuals' seed texts (../shared/seeds), for the conformance test
(tests/test_manual_conformance.py). Each reader returns ``{(index, sub): Row}``; a cell the text does not give
(or the OCR left unreadable) is "" and is not compared.

* Technosoft (000_…): the "Object description / Entry description" blocks, one ``key<TAB>value`` line each.
* HDT (003_…): the detail row under each "Index Name Type Range Default Unit Map Attributes" header (OCR text:
  only rows whose type, map and attribute columns are readable are taken).
* Control Techniques (004_…): the markdown object tables ("| 0x605A | name |", "| Access: RW | Range: … |
  Size: … | Unit: … |", "| Default: … |"); the guide has no PDO-mapping column (decision CT-5).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from tests.conftest import seeds_path

TS_SEED, HDT_SEED, CT_SEED = "000_a0ab57c0bda88c2c.txt", "003_8679b1dde0e37523.txt", "004_b59360cba58a7982.txt"


@dataclass
class Row:
    line: int
    type: str = ""
    access: str = ""
    pdo: str = ""  # the printed PDO-mapping cell ("" where the manual has none)
    default: str = ""
    range: str = ""


def _lines(seed: str) -> list[str]:
    return seeds_path(seed).read_text(encoding="utf-8").splitlines()


_SUPERSCRIPT = str.maketrans("⁰¹²³⁴⁵⁶⁷⁸⁹", "0123456789")


def _ts_clean(value: str) -> str:
    v = value.replace(" _h", "h").replace("_h", "h").replace("$", "").replace("{", "").replace("}", "")
    v = re.sub(r"(\d)\s*([⁰¹²³⁴⁵⁶⁷⁸⁹]+)", lambda m: f"{m.group(1)}^{m.group(2).translate(_SUPERSCRIPT)}", v)
    return v.replace("\\", "").strip()


_TS_TYPE_WORD = re.compile(r"^(UNSIGNED\d+|INTEGER\d+)\b")


def technosoft() -> dict[tuple[int, int], list[Row]]:
    out: dict[tuple[int, int], list[Row]] = {}
    obj: dict[str, str] | None = None
    index = 0
    entries: dict[int, dict[str, str]] = {}

    def flush() -> None:
        if obj is None:
            return
        record = obj.get("Object code", "VAR").upper() != "VAR" or any(s > 0 for s in entries)
        for sub, cells in entries.items():
            typ = cells.get("Data type", "")
            if not typ and not record:
                typ = obj.get("Data type", "")  # a VAR's type is the object's
            elif not typ and sub > 0:
                # an array's elements have the object's type; a record's element names its type in the range cell
                m = _TS_TYPE_WORD.match(cells.get("Value range", ""))
                typ = m.group(1) if m else (obj.get("Data type", "") if obj.get("Object code", "").upper() == "ARRAY"
                                            else "")
            out.setdefault((index, sub), []).append(
                Row(int(cells["line"]), typ, cells.get("Access", "").lower(), cells.get("PDO mapping", ""),
                    cells.get("Default value", ""), cells.get("Value range", "")))

    current: dict[str, str] | None = None
    for no, line in enumerate(_lines(TS_SEED), 1):
        m = re.match(r"Index\t([0-9A-Fa-f]{4})", line)
        if m:
            flush()
            obj, index, entries, current = {}, int(m.group(1), 16), {}, None
            continue
        if obj is None:
            continue
        if re.match(r"^\d+(\.\d+)+\s", line) or line.startswith("Table "):
            flush()
            obj, current = None, None
            continue
        if "\t" not in line:
            if line.strip() == "Entry description:" and current is None:
                current = entries.setdefault(0, {"line": str(no)})
            continue
        key, _, value = line.partition("\t")
        key, value = key.strip(), _ts_clean(value)
        if key == "Sub-index":  # "00h", "0", "01h – 04h" (one description for several sub-indices)
            sm = re.match(r"([0-9A-Fa-f]+)(h?)(?:\s*[–-]\s*([0-9A-Fa-f]+)h?)?$", value)
            if sm:
                base = 16 if sm.group(2) else 10
                first = int(sm.group(1), base)
                last = int(sm.group(3), base) if sm.group(3) else first
                shared: dict[str, str] = {"line": str(no)}
                for sub in range(first, last + 1):
                    entries[sub] = shared
                current = shared
            continue
        if current is None:
            obj[key] = value
        else:
            current[key] = value
    flush()
    return out


_HDT_TYPES = r"(UINT8|UINT16|UINT32|INT8|INT16|INT32|INT64|STR)"
_HDT_ROW = re.compile(rf"^([0-9A-F]{{4}})h\s+(?:\|\s*)?(?:(\d+)\s+)?(.*?)\s+{_HDT_TYPES}\s*\|?\s*(.*?)\s+(Yes|No)\s+(rw|ro|const|w)\b",
                      re.IGNORECASE)
_HDT_SUB = re.compile(rf"^(?:[A-Z€] )?(\d+)\s+(.*?)\s+{_HDT_TYPES}\s*\|?\s*(.*?)\s+(Yes|No)\s+(rw|ro|const|w)\b",
                      re.IGNORECASE)


def _hdt_cells(rest: str) -> tuple[str, str]:
    """The range and default columns of an HDT row's middle part ("0..65535 0", "0... 65535 20", "+7FFFFFFFh 0").
    The OCR turned "±" into "+" (or "-") and split ranges at the dots; a cell that runs over several lines
    ("-1 | Immediate", "0..35 (eccetto") is left unread."""
    text = rest.strip()
    if "|" in text or text.count("(") != text.count(")") or "," in text:
        return "", ""
    text = re.sub(r"\s*\.{2,3}\s*", "..", text)
    text = re.sub(r"^([+-])\s+", r"\1", text)
    parts = text.split()
    if len(parts) < 2:
        return "", ""
    rng, default = parts[0], parts[1]
    if re.fullmatch(r"[+-](?:[0-9A-F]+h|\d+)", rng):
        rng = "±" + rng[1:]  # the printed "±"
    if not re.fullmatch(r"[-+±]?[0-9A-Fa-f]+h?(?:\.\.[-+]?[0-9A-Fa-f]+h?)?", rng):
        rng = ""
    if not re.fullmatch(r"[-+]?[0-9A-Fa-f]+h?", default):
        default = ""
    return rng, default


def hdt() -> dict[tuple[int, int], list[Row]]:
    """Every printing of each entry (the guide prints some objects twice, e.g. 2006h in §4.14.4.a and §5.11.2)."""
    out: dict[tuple[int, int], list[Row]] = {}
    lines = _lines(HDT_SEED)
    for no, line in enumerate(lines, 1):
        if not re.match(r"Index (?:Name|Nome) (?:Type|Tipo) Range Default", line):  # some headers are Italian
            continue
        index = None
        for k in range(no, min(no + 8, len(lines))):
            text = lines[k].strip()
            m = _HDT_ROW.match(text)
            if m:
                index = int(m.group(1), 16)
                rest = m.group(5)
                # a range printed over two lines: "0.. 1000 rpm/s No rw" / "acceleration 7FFFFFFFh"
                split = re.match(r"^([-+]?[0-9A-Fa-f]+h?)\.{2,3}\s+(\S+)(.*)$", rest)
                tail = re.search(r"\s([-+]?[0-9A-F]+h)$", lines[k + 1].strip()) if k + 1 < len(lines) else None
                if split and tail:
                    rest = f"{split.group(1)}..{tail.group(1)} {split.group(2)}{split.group(3)}"
                rng, default = _hdt_cells(rest)
                out.setdefault((index, int(m.group(2) or 0)), []).append(
                    Row(k + 1, m.group(4).upper(), m.group(7).lower(), m.group(6), default, rng))
                continue
            s = _HDT_SUB.match(text)
            if s and index is not None:
                rng, default = _hdt_cells(s.group(4))
                out.setdefault((index, int(s.group(1))), []).append(
                    Row(k + 1, s.group(3).upper(), s.group(6).lower(), s.group(5), default, rng))
    return out


_CT_SIZE = {"1 byte": "UNSIGNED 8", "2 bytes": "UNSIGNED 16", "4 bytes": "UNSIGNED 32"}


def controltechniques() -> dict[tuple[int, int], list[Row]]:
    out: dict[tuple[int, int], list[Row]] = {}
    index: int | None = None
    sub = 0
    last: Row | None = None
    for no, line in enumerate(_lines(CT_SEED), 1):
        if not line.startswith("|"):
            if not line.strip():
                continue
            index, last = None, None
            continue
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        head = re.match(r"^(?:<b>)?0x([0-9A-F]{4})\b", cells[0])
        if head and len(cells) >= 2 and not cells[0].startswith("0x2"):
            index, sub, last = int(head.group(1), 16), 0, None
            continue
        if index is None:
            continue
        sm = re.match(r"^Sub-index (\d+)(?:\s*(?:to|-)\s*\d+)?:", cells[0])
        if sm:
            sub = int(sm.group(1))
            continue
        if cells[0].startswith("Access:"):
            cell = dict(c.split(":", 1) for c in cells if ":" in c)
            size = cell.get("Size", "").strip()
            last = Row(no, _CT_SIZE.get(size.lower(), size), cell.get("Access", "").strip().lower(), "", "",
                       cell.get("Range", "").strip())
            out.setdefault((index, sub), []).append(last)
            continue
        if cells[0].startswith("Default:") and last is not None:
            value = cells[0][len("Default:"):].strip() or (cells[1] if len(cells) > 1 else "")
            last.default = value
    return out
