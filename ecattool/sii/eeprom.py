"""The SII EEPROM of a live slave, word by word, as every master adapter reads and writes it: how far an image is
read (:func:`read_sii`: the fixed area, then the category chain to its end marker) and the order its words are
written in (:func:`write_sequence`: one an interruption cannot turn into an image that checks out). The masters'
own EEPROM calls stay in their adapters (``ecattool.target.pysoem``; the simulator's in ``ecattool.target.sim``)."""

from __future__ import annotations

from collections.abc import Callable

from ecattool.errors import TargetError

#: the SII EEPROM is read up to this many bytes at most (a 32 kbit EEPROM; IgH reads to the end marker too)
SII_MAX_BYTES = 4096
#: the fixed area of the SII (words 0x00-0x3F)
SII_HEADER_BYTES = 128


def read_sii(read_words: Callable[[int], bytes], max_bytes: int = SII_MAX_BYTES) -> bytes:
    """An SII image read through ``read_words(word_address) -> bytes`` (4 or 8 bytes per read, as the ESC
    gives them): the fixed area, then category headers until the end marker 0xFFFF (IgH's ``sii_read`` reads
    the same range). A chain that runs past ``max_bytes`` ends there."""
    data = bytearray()

    def fill(upto: int) -> None:
        while len(data) < upto:
            chunk = bytes(read_words(len(data) // 2))
            if not chunk or len(chunk) % 2:
                raise TargetError(f"the SII read at word 0x{len(data) // 2:04X} returned {len(chunk)} bytes")
            data.extend(chunk)

    fill(SII_HEADER_BYTES)
    offset = SII_HEADER_BYTES
    while offset + 4 <= max_bytes:
        fill(offset + 2)  # the type first: nothing is read past an end marker
        cat_type = int.from_bytes(data[offset:offset + 2], "little")
        if cat_type == 0xFFFF:
            offset += 2
            break
        fill(offset + 4)
        size_words = int.from_bytes(data[offset + 2:offset + 4], "little")
        offset += 4 + 2 * size_words
        fill(min(offset, max_bytes))
    return bytes(data[:min(max(offset, SII_HEADER_BYTES), max_bytes)])


#: word address of the checksum word (CRC-8 of bytes 0-13 in its low byte)
CRC_WORD = 7
#: words of the fixed area (0x00-0x3F); the categories start after it
HEADER_WORDS = 64


def write_sequence(image: bytes, current: bytes) -> list[tuple[int, bytes]]:
    """The word writes (word address, 2 bytes) that put ``image`` into an EEPROM that holds ``current``, in an
    order an interruption cannot turn into an image that checks out:

    1. the checksum word first, with a checksum byte that is the CRC of none of the contents words 0-6 pass
       through on the way (so from here on the image fails its CRC, whatever else is written);
    2. the categories (word 0x40 on), then the rest of the fixed area (words 8-0x3F), then words 0-6;
    3. the checksum word with the right CRC last.

    A write cut anywhere after step 1 leaves a CRC that does not match (``sii check`` and the slave's own load
    refuse it); one cut before it leaves the old image whole. (A mixed EEPROM with a valid CRC was what a kill
    during a write left before: new header and CRC first, old categories after.)"""
    from ecattool.sii.crc import preamble_crc

    data = bytes(image) + (b"\xff" if len(image) % 2 else b"")
    words = [data[2 * w:2 * w + 2] for w in range(len(data) // 2)]
    if len(words) <= CRC_WORD:
        return list(enumerate(words))
    old = bytearray(bytes(current[:14]).ljust(14, b"\xff"))
    passed = {preamble_crc(bytes(old))}
    for w in range(CRC_WORD):  # words 0-6 are written in this order in step 2
        old[2 * w:2 * w + 2] = words[w]
        passed.add(preamble_crc(bytes(old)))
    invalid = next(x for x in range(256) if x not in passed)
    crc_word = words[CRC_WORD]
    seq = [(CRC_WORD, bytes([invalid, crc_word[1]]))]
    seq += [(w, words[w]) for w in range(HEADER_WORDS, len(words))]
    seq += [(w, words[w]) for w in range(CRC_WORD + 1, min(HEADER_WORDS, len(words)))]
    seq += [(w, words[w]) for w in range(CRC_WORD)]
    seq.append((CRC_WORD, crc_word))
    return seq
