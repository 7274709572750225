"""What the blocks of a ``.sw`` image are, and the integrity words that tie them together.

Established from every ``.sw``/FoE image of the corpus (evidence in docs/sw-format.md):

* **Setup table** (one block, its last word at 0x7FAF in every corpus file):
  ``0x649C, configuration id, n1, n2, n3, <n1 words>, <n2 words>, <n3 words>, checksum``.
  Section 1 holds (address, 16-bit value) pairs, section 2 (address, low word, high word) triples, section 3
  (address, value) entries whose value size depends on the variable type (1, 2 or 4 words) and can only be
  decoded with the EasyMotion ``parameters.cfg``. The last word is the 16-bit sum of all words before it.
* **Identification block** at 0x7FBF, 34 words: 31 words of ASCII text (product id without dots followed by
  the firmware id, zero padded), the 16-bit sum of those 31 words, one word of unknown meaning (kept as it
  is), and a last word that makes the whole block sum to 0xFFFF.
* **Setup pointer** at 0x7FFF: one word, the start address of the setup table.
* **TML program** at 0x4000 (F515x) or 0x2000 (FA00x) (manual §18.3.1).
* **CAM table** (manual §18.4.1): header word (bits 15..13 interpolation step power, bits 12..0 points - 1),
  master start (2 words), 2 reserved zero words, 2 words per point, then the 16-bit sum of all table words.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ecattool.errors import InputError, Location
from ecattool.findings import Finding, Severity
from ecattool.sw.image import Block, SwImage, checksum
from ecattool.sw.params import TYPE_WORDS, ParameterTable

SETUP_MAGIC = 0x649C
SETUP_HEADER_WORDS = 5  # magic, configuration id, n1, n2, n3
SETUP_LAST_ADDRESS = 0x7FAF  # where every corpus setup table ends
IDENT_START = 0x7FBF
IDENT_WORDS = 34
IDENT_TEXT_WORDS = 31
POINTER_ADDRESS = 0x7FFF
TML_STARTS = {0x4000: "F515x", 0x2000: "FA00x"}


# --------------------------------------------------------------------------------------------- setup table
@dataclass(frozen=True, slots=True)
class SetupEntry:
    """One variable the setup table writes: ``address`` := ``words`` (low word first)."""

    section: int  # 1, 2 or 3
    address: int
    words: tuple[int, ...]
    offset: int  # index of the first value word inside the block

    @property
    def raw(self) -> int:
        return sum(w << (16 * i) for i, w in enumerate(self.words))


@dataclass(frozen=True, slots=True)
class SetupTable:
    block: Block
    config_id: int
    sizes: tuple[int, int, int]
    entries: tuple[SetupEntry, ...]  # sections 1 and 2
    section3: tuple[int, ...]  # raw words of section 3 (typed only with parameters.cfg)

    @property
    def section3_offset(self) -> int:
        return SETUP_HEADER_WORDS + self.sizes[0] + self.sizes[1]

    @property
    def stored_checksum(self) -> int:
        return self.block.words[-1]

    @property
    def computed_checksum(self) -> int:
        return checksum(self.block.words[:-1])

    def entry(self, address: int) -> SetupEntry | None:
        for e in self.entries:
            if e.address == address:
                return e
        return None


def parse_setup_table(block: Block, source: str | None = None) -> SetupTable:
    """Split a setup-table block into its sections; InputError when it does not have that structure."""
    w = block.words
    loc = Location(source, block.line)
    where = f"block 0x{block.start:04X}"
    if len(w) < SETUP_HEADER_WORDS + 1 or w[0] != SETUP_MAGIC:
        raise InputError(f"{where} is not a setup table (it does not start with 0x{SETUP_MAGIC:04X})", loc)
    n1, n2, n3 = w[2], w[3], w[4]
    if SETUP_HEADER_WORDS + n1 + n2 + n3 + 1 != len(w):
        raise InputError(f"{where}: section sizes {n1}+{n2}+{n3} + 6 header/checksum words != {len(w)} words", loc)
    if n1 % 2 or n2 % 3:
        raise InputError(f"{where}: section 1 ({n1} words) must hold pairs and section 2 ({n2}) triples", loc)
    entries: list[SetupEntry] = []
    off = SETUP_HEADER_WORDS
    for k in range(0, n1, 2):
        entries.append(SetupEntry(1, w[off + k], (w[off + k + 1],), off + k + 1))
    off += n1
    for k in range(0, n2, 3):
        entries.append(SetupEntry(2, w[off + k], (w[off + k + 1], w[off + k + 2]), off + k + 1))
    off += n2
    return SetupTable(block, w[1], (n1, n2, n3), tuple(entries), tuple(w[off : off + n3]))


def is_setup_table(block: Block) -> bool:
    try:
        parse_setup_table(block)
    except InputError:
        return False
    return True


def decode_section3(table: SetupTable, params: ParameterTable) -> list[SetupEntry]:
    """Type section 3 with ``parameters.cfg``; InputError naming the first address it does not know."""
    out: list[SetupEntry] = []
    words = table.section3
    i = 0
    base = table.section3_offset
    while i < len(words):
        address = words[i]
        p = params.by_address(address)
        if p is None:
            raise InputError(
                f"setup table section 3 word {i} names address 0x{address:04X}, which {params.source or 'the parameter file'} "
                "does not define; its size (and so the rest of section 3) cannot be decoded",
                Location(params.source),
            )
        n = TYPE_WORDS[p.type]
        if i + 1 + n > len(words):
            raise InputError(f"setup table section 3 ends inside {p.name} (0x{address:04X}, {p.type})",
                             Location(params.source))
        out.append(SetupEntry(3, address, tuple(words[i + 1 : i + 1 + n]), base + i + 1))
        i += 1 + n
    return out


# ------------------------------------------------------------------------------------ identification block
@dataclass(frozen=True, slots=True)
class Identification:
    text: str
    text_sum: int  # word 31
    unknown: int  # word 32
    complement: int  # word 33

    @property
    def product_id(self) -> str | None:
        """``P027314E221F515K`` -> ``P027.314.E221`` (the ProductID of EasyMotion's setup.cfg)."""
        t = self.text
        if len(t) >= 11 and t[0] == "P" and t[1:4].isdigit() and t[4:7].isdigit() and t[7] == "E":
            return f"{t[:4]}.{t[4:7]}.{t[7:11]}"
        return None

    @property
    def firmware_id(self) -> str:
        return self.text[11:] if self.product_id else self.text


def identification_text_words(text: str) -> tuple[int, ...]:
    if not text.isascii() or len(text) > IDENT_TEXT_WORDS or any(not 0x20 < ord(c) < 0x7F for c in text):
        raise InputError(f"identification text {text!r} must be at most {IDENT_TEXT_WORDS} printable ASCII characters")
    return tuple(ord(c) for c in text) + (0,) * (IDENT_TEXT_WORDS - len(text))


def parse_identification(block: Block) -> Identification:
    w = block.words
    if block.start != IDENT_START or len(w) != IDENT_WORDS:
        raise InputError(f"block 0x{block.start:04X} is not the {IDENT_WORDS}-word identification block at 0x{IDENT_START:04X}")
    chars = w[:IDENT_TEXT_WORDS]
    text = "".join(chr(c) for c in chars).rstrip("\0")
    return Identification(text, w[IDENT_TEXT_WORDS], w[IDENT_TEXT_WORDS + 1], w[IDENT_TEXT_WORDS + 2])


def identification_words(text_words: tuple[int, ...], unknown: int) -> tuple[int, ...]:
    """The 34 identification words with both integrity words computed."""
    text_sum = checksum(text_words)
    head = text_words + (text_sum, unknown)
    return head + ((0xFFFF - checksum(head)) & 0xFFFF,)


# ------------------------------------------------------------------------------------------------ CAM tables
CAM_STEPS = {1 << k: k for k in range(8)}
CAM_MAX_POINTS = 8192


def cam_table_words(step: int, points: list[int], master_start: int = 0) -> tuple[int, ...]:
    """A CAM table in the drive's EEPROM format (§18.4.1), checksum word included.

    ``step`` is the distance of the X points (1, 2, 4 ... 128), ``points`` the Y values (INTEGER32).
    """
    if step not in CAM_STEPS:
        raise InputError(f"CAM interpolation step {step} must be a power of 2 from 1 to 128")
    if not 1 <= len(points) <= CAM_MAX_POINTS:
        raise InputError(f"a CAM table has 1 to {CAM_MAX_POINTS} points, not {len(points)}")
    if not 0 <= master_start <= 0x7FFF_FFFF:
        raise InputError(f"CAM master start {master_start} must be a non-negative INTEGER32")
    words = [(CAM_STEPS[step] << 13) | (len(points) - 1), master_start & 0xFFFF, master_start >> 16, 0, 0]
    for y in points:
        if not -0x8000_0000 <= y <= 0x7FFF_FFFF:
            raise InputError(f"CAM point {y} does not fit an INTEGER32")
        y &= 0xFFFF_FFFF
        words += [y & 0xFFFF, y >> 16]
    return tuple(words) + (checksum(words),)


def cam_tables(block: Block) -> list[tuple[int, int]] | None:
    """``[(offset, points)]`` when the block is made of complete CAM tables (§18.4.1), else None."""
    w = block.words
    found: list[tuple[int, int]] = []
    i = 0
    while i < len(w):
        points = (w[i] & 0x1FFF) + 1
        size = 5 + 2 * points + 1
        if i + size > len(w) or w[i + 3] or w[i + 4] or checksum(w[i : i + size - 1]) != w[i + size - 1]:
            return None
        found.append((i, points))
        i += size
    return found or None


# ---------------------------------------------------------------------------------------------- block kinds
@dataclass(frozen=True, slots=True)
class BlockInfo:
    block: Block
    kind: str  # setup, identification, pointer, tml, cam, data
    description: str
    details: dict[str, object] = field(default_factory=dict)


def describe(image: SwImage) -> list[BlockInfo]:
    """What each block is, where that can be told from the structure."""
    pointer = image.word_at(POINTER_ADDRESS)
    infos: list[BlockInfo] = []
    for b in image.blocks:
        if b.start == POINTER_ADDRESS and b.count == 1:
            infos.append(BlockInfo(b, "pointer", f"setup pointer -> 0x{b.words[0]:04X}", {"target": b.words[0]}))
        elif b.start == IDENT_START and b.count == IDENT_WORDS:
            ident = parse_identification(b)
            infos.append(BlockInfo(b, "identification", f"identification {ident.text!r}",
                                   {"text": ident.text, "product_id": ident.product_id, "firmware_id": ident.firmware_id}))
        elif is_setup_table(b) and (pointer is None or pointer == b.start or b.end == SETUP_LAST_ADDRESS):
            t = parse_setup_table(b)
            infos.append(BlockInfo(b, "setup", f"setup table, configuration id 0x{t.config_id:04X}",
                                   {"config_id": t.config_id, "sections": list(t.sizes)}))
        elif b.start in TML_STARTS:
            infos.append(BlockInfo(b, "tml", f"TML program ({TML_STARTS[b.start]} start address)"))
        elif (cams := cam_tables(b)) is not None:
            infos.append(BlockInfo(b, "cam", f"{len(cams)} CAM table(s), {sum(p for _, p in cams)} points",
                                   {"tables": [{"offset": o, "points": p} for o, p in cams]}))
        else:
            infos.append(BlockInfo(b, "data", "data (structure not recognised)"))
    return infos


# ------------------------------------------------------------------------------------------ integrity words
def _finding(rule: str, msg: str, image: SwImage, block: Block, data: dict[str, object]) -> Finding:
    return Finding(rule, Severity.ERROR, msg, Location(image.source, block.line), data)


def integrity_findings(image: SwImage) -> list[Finding]:
    """Every integrity word that does not hold (setup checksum, identification sums, pointer, CAM checksums)."""
    out: list[Finding] = []
    infos = describe(image)
    setups = [i.block for i in infos if i.kind == "setup"]
    for info in infos:
        b = info.block
        if info.kind == "setup":
            t = parse_setup_table(b)
            if t.stored_checksum != t.computed_checksum:
                out.append(_finding("sw-setup-checksum", f"setup table checksum word at 0x{b.end:04X} is "
                                    f"0x{t.stored_checksum:04X}, the table sums to 0x{t.computed_checksum:04X}",
                                    image, b, {"address": b.end, "expected": t.computed_checksum}))
        elif info.kind == "identification":
            ident = parse_identification(b)
            text_sum = checksum(b.words[:IDENT_TEXT_WORDS])
            if ident.text_sum != text_sum:
                out.append(_finding("sw-ident-sum", f"identification word 0x{b.start + IDENT_TEXT_WORDS:04X} is "
                                    f"0x{ident.text_sum:04X}, the text sums to 0x{text_sum:04X}", image, b,
                                    {"expected": text_sum}))
            if b.checksum != 0xFFFF:
                out.append(_finding("sw-ident-complement", f"identification block sums to 0x{b.checksum:04X}, not 0xFFFF",
                                    image, b, {"sum": b.checksum}))
        elif info.kind == "pointer" and setups and info.block.words[0] != setups[0].start:
            out.append(_finding("sw-pointer", f"setup pointer at 0x{POINTER_ADDRESS:04X} is 0x{b.words[0]:04X} but the "
                                f"setup table starts at 0x{setups[0].start:04X}", image, b, {"expected": setups[0].start}))
    return out


def fix_integrity(image: SwImage) -> SwImage:
    """Recompute the setup-table checksum word, both identification sums and the setup pointer."""
    infos = describe(image)
    changes: dict[int, int] = {}
    setup_start = None
    for info in infos:
        b = info.block
        if info.kind == "setup":
            setup_start = b.start
            changes[b.end] = checksum(b.words[:-1])
        elif info.kind == "identification":
            words = identification_words(tuple(b.words[:IDENT_TEXT_WORDS]), b.words[IDENT_TEXT_WORDS + 1])
            changes.update({b.start + i: w for i, w in enumerate(words)})
    if setup_start is not None and image.word_at(POINTER_ADDRESS) is not None:
        changes[POINTER_ADDRESS] = setup_start
    return image.with_words(changes)


def setup_table(image: SwImage) -> SetupTable:
    """The image's setup table, or InputError when it has none."""
    for info in describe(image):
        if info.kind == "setup":
            return parse_setup_table(info.block, image.source)
    raise InputError("the image has no setup table (a block starting with 0x649C whose section sizes add up)",
                     Location(image.source))
