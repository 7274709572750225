"""Read a Technosoft drive's EEPROM setup back into a ``.sw`` image (the reverse of ``download``).

The drive is asked for each range through its memory objects (manual §17.4): 2064h selects the EEPROM address
with auto-increment and 32-bit access, each read of 2066h returns two words (low word at the lower address) and
advances the address by two; an odd last word is read in 16-bit mode. The ranges are the blocks of a reference
``.sw`` (the project's), or ranges given by the caller. Every block read is then checked by the drive itself:
its checksum of the range (2069h/206Ah) must equal the sum of the words read, so a word lost or garbled on the
way shows as a checksum error, never as a silently wrong file.

Upload writes only the drive's address registers (2064h, and 2069h for the checksum request), never its EEPROM.
"""

from __future__ import annotations

from collections.abc import Sequence

from ecattool.errors import InputError
from ecattool.od.numbers import parse_int
from ecattool.sw.apply import BlockCheck, ensure_mailbox, verify
from ecattool.sw.image import Block, SwImage
from ecattool.sw.plan import OBJ_CONFIG, OBJ_READ, config_value
from ecattool.target.base import SlaveTarget


def _u32(value: int) -> bytes:
    return value.to_bytes(4, "little")


def read_words(target: SlaveTarget, start: int, count: int) -> tuple[int, ...]:
    """``count`` EEPROM words from ``start``."""
    words: list[int] = []
    target.sdo_download(OBJ_CONFIG, 0, _u32(config_value(start, 32)))
    for _ in range(count // 2):
        v = int.from_bytes(target.sdo_upload(OBJ_READ, 0, size=4)[:4].ljust(4, b"\0"), "little")
        words += [v & 0xFFFF, v >> 16]
    if count % 2:
        target.sdo_download(OBJ_CONFIG, 0, _u32(config_value(start + count - 1, 16)))
        words.append(int.from_bytes(target.sdo_upload(OBJ_READ, 0, size=4)[:2].ljust(2, b"\0"), "little"))
    return tuple(words)


def parse_range(text: str) -> tuple[int, int]:
    """``0x5638-0x5A37`` (inclusive word addresses) -> (start, end)."""
    a, sep, b = text.partition("-")
    if not sep:
        raise InputError(f"range {text!r}: write START-END, e.g. 0x5638-0x5A37")
    start, end = parse_int(a, what="range start"), parse_int(b, what="range end")
    if not 0 <= start <= end <= 0xFFFF:
        raise InputError(f"range {text!r}: START <= END within 0x0000..0xFFFF expected")
    return start, end


def upload_ranges(ranges: Sequence[str], like: SwImage | None = None) -> list[tuple[int, int]]:
    """The word ranges ``sw upload`` reads: those given (``0x4000-0x40FF`` …, :func:`parse_range`), else the blocks
    of ``like`` (another .sw, or a project drive's); none without either (``upload`` then says what to give)."""
    if ranges:
        return [parse_range(r) for r in ranges]
    return [(b.start, b.end) for b in like.blocks] if like is not None else []


def upload(target: SlaveTarget, ranges: Sequence[tuple[int, int]]) -> tuple[SwImage, list[BlockCheck]]:
    """The drive's EEPROM words of ``ranges`` (inclusive start, end) as a ``.sw`` image, and the drive's own
    checksum of each block compared with the words read."""
    if not ranges:
        raise InputError("no EEPROM ranges to read: give a reference .sw or ranges")
    ensure_mailbox(target)
    blocks = tuple(Block(start, read_words(target, start, end - start + 1)) for start, end in ranges)
    image = SwImage(blocks)
    return image, verify(image, target)
