"""FoE setup images (``FOESW_*.bin``): the same blocks as a ``.sw`` file, in binary.

Each block is ``[start u16 LE][count u16 LE][count x u16 LE]``; blocks follow each other with no header,
trailer or CRC (checked against the corpus pair ``ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.sw/.bin``). The drive
accepts the file only when its name starts with ``FOESW_`` and is at most 14 characters long without the
extension (manual §17.4.3.1); setup files are saved as ``.bin`` or ``.efw``.
"""

from __future__ import annotations

import struct
from pathlib import Path, PurePath

from ecattool.errors import InputError, Location
from ecattool.sw.image import MAX_ADDRESS, Block, SwImage

FOE_PREFIX = "FOESW_"
FOE_MAX_NAME = 14
FOE_EXTENSIONS = (".bin", ".efw")
#: password of a setup file transfer (manual §17.4.3.1)
FOE_PASSWORD = 0


def check_foe_name(name: str | PurePath) -> str:
    """Return the FoE file name (without directory) or raise :class:`InputError` naming the broken rule."""
    p = PurePath(name)
    stem, ext = p.stem, p.suffix
    loc = Location(str(name))
    if ext.lower() not in FOE_EXTENSIONS:
        raise InputError(f"a FoE setup file is saved as .bin or .efw, not {ext or 'no extension'!r}", loc)
    if not stem.startswith(FOE_PREFIX):
        raise InputError(f"the drive rejects FoE setup files whose name does not start with {FOE_PREFIX!r}: {stem!r}", loc)
    if len(stem) > FOE_MAX_NAME:
        raise InputError(
            f"the drive rejects FoE file names longer than {FOE_MAX_NAME} characters without the extension: "
            f"{stem!r} has {len(stem)}",
            loc,
        )
    if not stem.isascii() or not all(c.isalnum() or c in "_-" for c in stem):
        raise InputError(f"use only ASCII letters, digits, '_' and '-' in a FoE file name: {stem!r}", loc)
    return p.name


def to_foe(image: SwImage) -> bytes:
    """The FoE setup image of ``image`` (blocks in file order)."""
    out = bytearray()
    for b in image.blocks:
        out += struct.pack(f"<HH{b.count}H", b.start, b.count, *b.words)
    return bytes(out)


def from_foe(data: bytes, source: str | None = None, final_blank_line: bool = True) -> SwImage:
    """Parse a FoE setup image. Errors name the byte offset of the broken block header."""
    loc = Location(source)
    if not data:
        raise InputError("empty FoE image: no blocks", loc)
    if len(data) % 2:
        raise InputError(f"a FoE setup image is made of 16-bit words; {len(data)} bytes is odd", loc)
    words = struct.unpack(f"<{len(data) // 2}H", data)
    blocks: list[Block] = []
    i = 0
    while i < len(words):
        offset = 2 * i
        if i + 2 > len(words):
            raise InputError(f"truncated block header at byte offset {offset}: start and count need 4 bytes", loc)
        start, count = words[i], words[i + 1]
        if count == 0:
            raise InputError(f"block 0x{start:04X} at byte offset {offset} has a word count of 0", loc)
        if i + 2 + count > len(words):
            raise InputError(
                f"block 0x{start:04X} at byte offset {offset} announces {count} words but only "
                f"{len(words) - i - 2} follow",
                loc,
            )
        if start + count - 1 > MAX_ADDRESS:
            raise InputError(f"block 0x{start:04X} at byte offset {offset} with {count} words runs past 0xFFFF", loc)
        blocks.append(Block(start, tuple(words[i + 2 : i + 2 + count])))
        i += 2 + count
    return SwImage(tuple(blocks), final_blank_line, source)


def read_foe(path: str | Path) -> SwImage:
    from ecattool.fileio import read_bytes

    return from_foe(read_bytes(path, 1024 * 1024), str(path))
