"""Reading SII images: binary and Intel HEX in (the writer, ``serialize``, is in :mod:`ecattool.sii.model`).

The parser stops at the 0xFFFF end marker or at the end of the data. A category whose declared
length runs past the data, or a header cut short, is an :class:`~ecattool.errors.InputError` located
at the file (and, for Intel HEX, the line holding that byte).
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from pathlib import Path

from ecattool.errors import InputError, Location
from ecattool.sii.model import (
    DC_LAYOUT,
    ENTRY_LAYOUT,
    GENERAL_LAYOUT,
    HEADER_BYTES,
    HEADER_LAYOUT,
    PDO_LAYOUT,
    SM_LAYOUT,
    Category,
    CategoryType,
    DcCategory,
    FmmuCategory,
    GeneralCategory,
    PdoCategory,
    RawCategory,
    SiiDcOpMode,
    SiiHeader,
    SiiImage,
    SiiPdo,
    SiiPdoEntry,
    SiiSyncManager,
    StringsCategory,
    SyncMCategory,
)

#: Largest image accepted (the largest SII EEPROMs are 64 KiB; the spec allows up to 4 MiBit).
MAX_IMAGE_BYTES = 4 * 1024 * 1024 // 8 * 2


# ---------------------------------------------------------------------------------------------------
# Intel HEX
# ---------------------------------------------------------------------------------------------------
class ByteLocator:
    """Turns a byte offset of the image into a :class:`Location` (hex line numbers when known)."""

    def __init__(self, source: str | None, lines: list[tuple[int, int, int]] | None = None) -> None:
        self.source = source
        self._lines = lines or []  # (start address, end address exclusive, line number)

    def __call__(self, offset: int) -> Location:
        for start, end, line in self._lines:
            if start <= offset < end:
                return Location(self.source, line)
        if self._lines:
            return Location(self.source, self._lines[-1][2])
        return Location(self.source)


def is_intel_hex(data: bytes) -> bool:
    """Text starting with ':' is Intel HEX (a malformed record then gets a located error, not a binary read):
    a binary image has control bytes or NULs in its first words, so printable ASCII alone tells the two apart."""
    head = data[:256]
    return data.lstrip()[:1] == b":" and all(c in b"\t\r\n" or 0x20 <= c < 0x7F for c in head)


def read_intel_hex(data: bytes, source: str | None = None) -> tuple[bytes, ByteLocator]:
    """Intel HEX (record types 00, 01, 02, 04; 03/05 ignored) → bytes; gaps are filled with 0xFF."""
    mem: dict[int, int] = {}
    lines: list[tuple[int, int, int]] = []
    base = 0
    eof = False
    for lineno, raw in enumerate(data.decode("ascii", "replace").splitlines(), start=1):
        text = raw.strip()
        if not text:
            continue
        loc = Location(source, lineno, 1)
        if eof:
            raise InputError("data after the end-of-file record (:00000001FF)", loc)
        if not text.startswith(":"):
            raise InputError(f"not an Intel HEX record (must start with ':'): {text[:20]!r}", loc)
        try:
            rec = bytes.fromhex(text[1:])
        except ValueError:
            raise InputError("Intel HEX record has non-hex characters or an odd digit count", loc) from None
        if len(rec) < 5 or len(rec) != rec[0] + 5:
            raise InputError(f"Intel HEX record length {len(rec)} does not match its count byte", loc)
        if sum(rec) & 0xFF:
            want = (-sum(rec[:-1])) & 0xFF
            raise InputError(f"Intel HEX checksum 0x{rec[-1]:02X} is wrong (should be 0x{want:02X})",
                             Location(source, lineno, len(text) - 1))
        count, addr, rtype, payload = rec[0], (rec[1] << 8) | rec[2], rec[3], rec[4:-1]
        if rtype == 0x00:
            start = base + addr
            for i, b in enumerate(payload):
                mem[start + i] = b
            lines.append((start, start + count, lineno))
        elif rtype == 0x01:
            eof = True
        elif rtype == 0x02 and count == 2:
            base = ((payload[0] << 8) | payload[1]) << 4
        elif rtype == 0x04 and count == 2:
            base = ((payload[0] << 8) | payload[1]) << 16
        elif rtype in (0x03, 0x05):
            continue
        else:
            raise InputError(f"unsupported Intel HEX record type 0x{rtype:02X}", loc)
    if not mem:
        return b"", ByteLocator(source, lines)
    size = max(mem) + 1
    if size > MAX_IMAGE_BYTES:
        raise InputError(f"Intel HEX data reaches address 0x{size - 1:X}, beyond any SII EEPROM", Location(source))
    out = bytearray(b"\xff" * size)
    for a, b in mem.items():
        out[a] = b
    return bytes(out), ByteLocator(source, lines)


def write_intel_hex(data: bytes, record_len: int = 16) -> str:
    out = []
    for off in range(0, len(data), record_len):
        if off and off % 0x10000 == 0:
            rec = bytes([2, 0, 0, 4, (off >> 24) & 0xFF, (off >> 16) & 0xFF])
            out.append(":" + (rec + bytes([(-sum(rec)) & 0xFF])).hex().upper())
        chunk = data[off:off + record_len]
        rec = bytes([len(chunk), (off >> 8) & 0xFF, off & 0xFF, 0]) + chunk
        out.append(":" + (rec + bytes([(-sum(rec)) & 0xFF])).hex().upper())
    out.append(":00000001FF")
    return "\n".join(out) + "\n"


# ---------------------------------------------------------------------------------------------------
# Category bodies
# ---------------------------------------------------------------------------------------------------
def _split_pad(content_len: int, body: bytes) -> bytes:
    """Bytes after the typed content; a lone 0x00 that pads odd content to a word is implied."""
    extra = body[content_len:]
    if content_len % 2 and extra == b"\x00":
        return b""
    return extra


def _parse_strings(body: bytes) -> Category:
    if not body:
        return StringsCategory([], b"")
    n = body[0]
    pos = 1
    strings = []
    for i in range(n):
        if pos >= len(body):
            raise ValueError(f"string {i + 1} of {n} starts beyond the category end")
        ln = body[pos]
        if pos + 1 + ln > len(body):
            raise ValueError(f"string {i + 1} ({ln} bytes) runs past the category end")
        strings.append(body[pos + 1:pos + 1 + ln].decode("latin-1"))
        pos += 1 + ln
    return StringsCategory(strings, _split_pad(pos, body))


def _parse_general(body: bytes) -> Category:
    if len(body) < 32:
        raise ValueError(f"GENERAL body is {len(body)} bytes, 32 expected")
    v = GENERAL_LAYOUT.unpack_from(body)
    return GeneralCategory(*v, extra=body[32:])  # type: ignore[misc]


def _parse_fmmu(body: bytes) -> Category:
    """One byte per FMMU; a final 0x00 after an odd count is the word padding (0x00 = unused anyway)."""
    usages = list(body)
    if len(usages) % 2 == 0 and usages and usages[-1] == 0:
        usages.pop()
    return FmmuCategory(usages)


def _parse_syncm(body: bytes) -> Category:
    n = len(body) // 8
    sms = [SiiSyncManager(*SM_LAYOUT.unpack_from(body, 8 * i)) for i in range(n)]
    return SyncMCategory(sms, body[8 * n:])


def _parse_pdos(cat_type: int) -> Callable[[bytes], Category]:
    def parse(body: bytes) -> Category:
        pos = 0
        pdos = []
        while pos + 8 <= len(body):
            index, n, sm, dc, name, flags = PDO_LAYOUT.unpack_from(body, pos)
            if pos + 8 + 8 * n > len(body):
                raise ValueError(f"PDO 0x{index:04X} declares {n} entries but the category ends first")
            entries = [SiiPdoEntry(*ENTRY_LAYOUT.unpack_from(body, pos + 8 + 8 * k)) for k in range(n)]
            pdos.append(SiiPdo(index, sm, dc, name, flags, entries))
            pos += 8 + 8 * n
        return PdoCategory(cat_type, pdos, body[pos:])

    return parse


def _parse_dc(body: bytes) -> Category:
    n = len(body) // 24
    ops = [SiiDcOpMode(*DC_LAYOUT.unpack_from(body, 24 * i)) for i in range(n)]
    return DcCategory(ops, body[24 * n:])


_PARSERS: dict[int, Callable[[bytes], Category]] = {
    CategoryType.STRINGS: _parse_strings,
    CategoryType.GENERAL: _parse_general,
    CategoryType.FMMU: _parse_fmmu,
    CategoryType.SYNCM: _parse_syncm,
    CategoryType.TXPDO: _parse_pdos(CategoryType.TXPDO),
    CategoryType.RXPDO: _parse_pdos(CategoryType.RXPDO),
    CategoryType.DC: _parse_dc,
}


def parse_category(cat_type: int, body: bytes) -> Category:
    """Decode one category body; bodies that do not decode are kept as :class:`RawCategory` with a problem."""
    parser = _PARSERS.get(cat_type)
    if parser is None:
        return RawCategory(cat_type, bytes(body))
    try:
        return parser(bytes(body))
    except (ValueError, struct.error) as exc:
        return RawCategory(cat_type, bytes(body), problem=str(exc))


# ---------------------------------------------------------------------------------------------------
# Whole images
# ---------------------------------------------------------------------------------------------------
def parse_header(data: bytes) -> SiiHeader:
    return SiiHeader(*HEADER_LAYOUT.unpack_from(data))


def parse(data: bytes, source: str | None = None, locate: ByteLocator | None = None) -> SiiImage:
    """Parse a binary image (use :func:`load` for files, which also reads Intel HEX)."""
    locate = locate or ByteLocator(source)
    if len(data) == 0:
        raise InputError("the SII image is empty (0 bytes); an image needs at least the 128-byte fixed area",
                         locate(0))
    if len(data) > MAX_IMAGE_BYTES:
        raise InputError(f"the SII image is {len(data)} bytes, larger than any SII EEPROM", locate(0))
    if len(data) < HEADER_BYTES:
        raise InputError(f"the SII image is truncated: {len(data)} bytes, but the fixed area (words "
                         f"0x00-0x3F) alone needs {HEADER_BYTES} bytes", locate(len(data) - 1))
    header = parse_header(data)
    cats: list[Category] = []
    pos = HEADER_BYTES
    end_marker = False
    while pos + 2 <= len(data):
        (cat_type,) = struct.unpack_from("<H", data, pos)
        if cat_type == CategoryType.END:
            end_marker = True
            pos += 2
            break
        if pos + 4 > len(data):
            raise InputError(f"category header at byte 0x{pos:04X} (word 0x{pos // 2:04X}) is cut off by the "
                             f"end of the data ({len(data)} bytes)", locate(pos))
        (words,) = struct.unpack_from("<H", data, pos + 2)
        end = pos + 4 + 2 * words
        if end > len(data):
            raise InputError(
                f"category 0x{cat_type:04X} at byte 0x{pos:04X} (word 0x{pos // 2:04X}) declares {words} words "
                f"(to byte 0x{end:04X}) but the image ends at byte 0x{len(data):04X}", locate(pos))
        cats.append(parse_category(cat_type, data[pos + 4:end]))
        pos = end
    return SiiImage(header, cats, end_marker, bytes(data[pos:]), source or "")


def load(path: str | Path, data: bytes | None = None) -> SiiImage:
    """Read an image file: binary, or Intel HEX (detected by its leading ':')."""
    from ecattool.fileio import read_bytes

    src = str(path)
    raw = data if data is not None else read_bytes(path, max_bytes=4 * MAX_IMAGE_BYTES)
    if raw.lstrip(b"\xef\xbb\xbf \t\r\n")[:1] == b"<":
        raise InputError("this is an XML file (an ESI?), not an SII image (`sii build ESI -o IMAGE` makes one; "
                         "`sii check ESI IMAGE` compares the two)", Location(src, 1))
    if is_intel_hex(raw):
        binary, locator = read_intel_hex(raw, src)
        return parse(binary, src, locator)
    return parse(raw, src)
