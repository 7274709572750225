"""The ``.sw`` EEPROM image text format (Technosoft manual §17.3): reader, writer, block checksums.

A ``.sw`` file is ASCII text made of blocks separated by an empty line. The first line of a block is the
EEPROM word address of the block; every following line is one 16-bit data word for the next address.
All numbers are hexadecimal without prefix, at most 4 digits, right-justified ("92" = 0x0092).

The reader accepts CRLF or LF, upper or lower case, surrounding blanks and several blank lines in a row,
and refuses with ``file:line`` errors anything else: a line that is not a hex word of at most 4 digits,
an address line without data (empty block), a block that runs past 0xFFFF, two blocks that overlap.
The writer writes the way EasySetUp/EasyMotion Studio do: CRLF, upper case, no zero padding, one empty line
after every block (a file that did not end with an empty line is written back without one, so every
vendor file round-trips byte for byte).
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from ecattool.errors import InputError, Location

#: the last EEPROM word address a block may reach
MAX_ADDRESS = 0xFFFF
#: largest .sw file accepted (a full 64 Ki-word EEPROM image is ~400 KiB of text)
MAX_FILE_BYTES = 4 * 1024 * 1024

_WORD = re.compile(r"[0-9A-Fa-f]{1,4}")


def checksum(words: Iterable[int]) -> int:
    """The drive's EEPROM checksum: the 16-bit unsigned sum of the words (manual §17.2.5)."""
    return sum(words) & 0xFFFF


def checksum_request(start: int, end: int) -> int:
    """The 2069h value that makes the drive sum ``start..end`` (both inclusive) into 206Ah.

    ``end`` in the high word, ``start`` in the low word (manual §17.4.1: 0x5E06..0x5EFF -> 0x5EFF5E06).
    """
    if not (0 <= start <= end <= MAX_ADDRESS):
        raise ValueError(f"bad checksum range 0x{start:X}..0x{end:X}")
    return (end << 16) | start


@dataclass(frozen=True, slots=True)
class Block:
    """One contiguous run of EEPROM words starting at ``start``."""

    start: int
    words: tuple[int, ...]
    #: 1-based line of the address line in the source file (None for built images)
    line: int | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        if not 0 <= self.start <= MAX_ADDRESS:
            raise ValueError(f"block start 0x{self.start:X} is outside 0x0000..0xFFFF")
        if not self.words:
            raise ValueError(f"block at 0x{self.start:04X} has no data words")
        if self.start + len(self.words) - 1 > MAX_ADDRESS:
            raise ValueError(f"block at 0x{self.start:04X} with {len(self.words)} words runs past 0xFFFF")
        if any(not 0 <= w <= 0xFFFF for w in self.words):
            raise ValueError(f"block at 0x{self.start:04X} holds a value that is not a 16-bit word")

    @property
    def count(self) -> int:
        return len(self.words)

    @property
    def end(self) -> int:
        """Last address of the block (inclusive)."""
        return self.start + len(self.words) - 1

    @property
    def checksum(self) -> int:
        return checksum(self.words)

    @property
    def checksum_request(self) -> int:
        """The 2069h value for this block: ``end << 16 | start``."""
        return checksum_request(self.start, self.end)

    def covers(self, address: int) -> bool:
        return self.start <= address <= self.end

    def word_at(self, address: int) -> int:
        if not self.covers(address):
            raise KeyError(address)
        return self.words[address - self.start]

    def replace_words(self, changes: dict[int, int]) -> "Block":
        """A copy with the words at the given absolute addresses replaced."""
        words = list(self.words)
        for address, value in changes.items():
            words[address - self.start] = value
        return Block(self.start, tuple(words), self.line)


@dataclass(frozen=True, slots=True)
class SwImage:
    """A ``.sw`` image: blocks in file order (the order matters for byte-identical rewrites)."""

    blocks: tuple[Block, ...]
    #: whether the text ends with an empty line after the last block (vendor files do)
    final_blank_line: bool = True
    source: str | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        check_overlaps(self.blocks, self.source)

    def __iter__(self) -> Iterator[Block]:
        return iter(self.blocks)

    def __len__(self) -> int:
        return len(self.blocks)

    def block_at(self, address: int) -> Block | None:
        for b in self.blocks:
            if b.covers(address):
                return b
        return None

    def word_at(self, address: int) -> int | None:
        b = self.block_at(address)
        return None if b is None else b.word_at(address)

    def words(self) -> dict[int, int]:
        """Every programmed address and its word."""
        return {b.start + i: w for b in self.blocks for i, w in enumerate(b.words)}

    def replace_block(self, old: Block, new: Block) -> "SwImage":
        blocks = tuple(new if b is old else b for b in self.blocks)
        return SwImage(blocks, self.final_blank_line, self.source)

    def with_words(self, changes: dict[int, int]) -> "SwImage":
        """A copy with words changed at existing addresses (KeyError for an address outside every block)."""
        per_block: dict[int, dict[int, int]] = {}
        for address, value in changes.items():
            for i, b in enumerate(self.blocks):
                if b.covers(address):
                    per_block.setdefault(i, {})[address] = value
                    break
            else:
                raise KeyError(address)
        blocks = tuple(b.replace_words(per_block[i]) if i in per_block else b for i, b in enumerate(self.blocks))
        return SwImage(blocks, self.final_blank_line, self.source)

    @property
    def total_words(self) -> int:
        return sum(b.count for b in self.blocks)


def check_overlaps(blocks: Sequence[Block], source: str | None = None) -> None:
    ordered = sorted(blocks, key=lambda b: b.start)
    for a, b in zip(ordered, ordered[1:]):
        if b.start <= a.end:
            first, second = sorted((a, b), key=lambda x: (x.line or 0))
            where = f" (line {first.line})" if first.line else ""
            raise InputError(
                f"block 0x{second.start:04X}..0x{second.end:04X} overlaps block 0x{first.start:04X}..0x{first.end:04X}"
                f"{where}; each EEPROM address may be written once",
                Location(source, second.line),
            )


def parse(text: str | bytes, source: str | None = None, quote: bool = True) -> SwImage:
    """Parse ``.sw`` text. Raises :class:`InputError` with file and line for anything malformed; with
    ``quote=False`` the error quotes nothing of the text (not the line, not the byte), only where it is: for a file
    a project names, which may be any file (lint must not print a secret's first line)."""
    content: str
    if isinstance(text, bytes):
        raw = text[3:] if text.startswith(b"\xef\xbb\xbf") else text
        try:
            content = raw.decode("ascii")
        except UnicodeDecodeError as exc:
            line = raw.count(b"\n", 0, exc.start) + 1
            shown = f"byte 0x{raw[exc.start]:02X}" if quote else "a byte"
            raise InputError(
                f"{shown} is not ASCII; a .sw line holds one hex word of at most 4 digits",
                Location(source, line),
            ) from None
    else:
        content = text
    lines = content.split("\n")
    if lines and lines[-1] == "":
        lines.pop()  # the newline that ends the last line
    blocks: list[Block] = []
    start: int | None = None
    start_line = 0
    words: list[int] = []

    def close() -> None:
        nonlocal start
        if start is None:
            return
        if not words:
            raise InputError(
                f"empty block: address 0x{start:04X} is not followed by any data word", Location(source, start_line)
            )
        blocks.append(Block(start, tuple(words), start_line))
        start = None

    last_blank = False
    for no, text_line in enumerate(lines, 1):
        s = text_line.strip()
        if s == "":
            close()
            last_blank = True
            continue
        last_blank = False
        if not _WORD.fullmatch(s):
            shown = repr(s if len(s) <= 20 else s[:20] + "...") if quote else "the line"
            raise InputError(
                f"{shown} is not a hex word of at most 4 digits (expected e.g. 7ABD or 92)", Location(source, no)
            )
        value = int(s, 16)
        if start is None:
            start, start_line, words = value, no, []
            continue
        address = start + len(words)
        if address > MAX_ADDRESS:
            raise InputError(
                f"block 0x{start:04X} (line {start_line}) runs past address 0xFFFF at this word", Location(source, no)
            )
        words.append(value)
    close()
    if not blocks:
        raise InputError("no data blocks: a .sw file needs a start address followed by data words", Location(source, 1))
    return SwImage(tuple(blocks), final_blank_line=last_blank, source=source)


def read(path: str | Path, quote: bool = True) -> SwImage:
    """Read a ``.sw`` file (``quote``: see :func:`parse`)."""
    from ecattool.fileio import read_bytes

    return parse(read_bytes(path, MAX_FILE_BYTES), str(path), quote)


def write(image: SwImage, final_blank_line: bool | None = None) -> bytes:
    """The ``.sw`` text the vendor tools write: CRLF, upper-case hex without padding."""
    out: list[str] = []
    for i, b in enumerate(image.blocks):
        if i:
            out.append("")
        out.append(f"{b.start:X}")
        out.extend(f"{w:X}" for w in b.words)
    blank = image.final_blank_line if final_blank_line is None else final_blank_line
    text = "\r\n".join(out) + "\r\n"
    if blank:
        text += "\r\n"
    return text.encode("ascii")


def make_image(blocks: Iterable[tuple[int, Sequence[int]]], final_blank_line: bool = True) -> SwImage:
    """Build an image from ``(start, words)`` pairs; ValueError/InputError for invalid blocks."""
    return SwImage(tuple(Block(s, tuple(w)) for s, w in blocks), final_blank_line)
