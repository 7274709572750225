"""The process-image diagram: every sync manager's image drawn as rows of bytes, one box per mapped entry.

The geometry is computed here (and published as constants, so tests can read a box back into a bit
offset); the SVG text comes from the ``process_image.svg.j2`` template. Each mapped entry is one
``<g class="entry">`` with ``data-object``, ``data-offset`` (byte.bit) and ``data-bits``, drawn as one
rectangle per row it covers; gaps (``class="gap"``) and the unused bits of a last byte
(``class="padding"``) are drawn too.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ecattool.pdo.layout import ImageEntry, Layout, SmImage
from ecattool.report.extra import environment

#: bits drawn per row (4 bytes), the width of one bit and the height of one row, in SVG user units
BITS_PER_ROW = 32
BIT_WIDTH = 22
ROW_HEIGHT = 56
ROW_GAP = 6
#: left margin (byte labels) and the height of a section's title and bit ruler
X0 = 64
SECTION_HEAD = 52
SECTION_GAP = 22
CHAR_WIDTH = 6.2  # of the 10.5 px label font, for truncating names that do not fit their box
WIDTH = X0 + BITS_PER_ROW * BIT_WIDTH + 12
#: fills per PDO, cycled (entries of one PDO share a colour; the legend names them)
PALETTE = ("#cfe3f7", "#d8efd0", "#f9e2c4", "#e6d9f2", "#f6d3da", "#d3eeec", "#efe8c0", "#dfe3e8")


@dataclass(slots=True)
class Segment:
    x: float
    y: float
    width: float
    height: float


@dataclass(slots=True)
class Box:
    """One entry (or gap, or padding) as drawn: its segments and the label lines of its widest segment."""

    kind: str  # "entry" | "gap" | "padding"
    entry: ImageEntry | None
    bit_offset: int
    bit_len: int
    fill: str
    segments: list[Segment] = field(default_factory=list)
    label_x: float = 0.0
    label_y: float = 0.0
    lines: list[str] = field(default_factory=list)
    title: str = ""
    continued: list[tuple[float, float, str]] = field(default_factory=list)  # (x, y, text) on the other segments

    @property
    def offset(self) -> str:
        return f"{self.bit_offset // 8}.{self.bit_offset % 8}"


@dataclass(slots=True)
class Section:
    title: str
    y: float
    rows: int
    boxes: list[Box] = field(default_factory=list)
    legend: list[tuple[str, str]] = field(default_factory=list)  # (fill, "0x1600")

    def row_y(self, row: int) -> float:
        return self.y + SECTION_HEAD + row * (ROW_HEIGHT + ROW_GAP)

    @property
    def height(self) -> float:
        return SECTION_HEAD + max(self.rows, 1) * (ROW_HEIGHT + ROW_GAP)


def _fit(text: str, width: float) -> str:
    n = max(int((width - 6) // CHAR_WIDTH), 1)
    return text if len(text) <= n else (text[: n - 1] + "…" if n > 1 else "…")


def _segments(section: Section, bit_offset: int, bit_len: int) -> list[Segment]:
    out = []
    bit, end = bit_offset, bit_offset + bit_len
    while bit < end:
        row, col = divmod(bit, BITS_PER_ROW)
        n = min(end - bit, BITS_PER_ROW - col)
        out.append(Segment(X0 + col * BIT_WIDTH, section.row_y(row), n * BIT_WIDTH, ROW_HEIGHT))
        bit += n
    return out


def _label(box: Box, lines: list[str]) -> None:
    widest = max(box.segments, key=lambda s: s.width)
    box.label_x = widest.x + 4
    box.label_y = widest.y + 15
    box.lines = [_fit(t, widest.width) for t in lines][: 3 if widest.width >= 2 * BIT_WIDTH else 1]
    box.continued = [(s.x + 4, s.y + 15, _fit(f"{lines[0]} (cont.)", s.width)) for s in box.segments
                     if s is not widest and s.width >= 3 * BIT_WIDTH]


def section_of(img: SmImage, y: float) -> Section:
    """The drawing of one sync manager's image, starting at height ``y``."""
    kind = "Outputs (RxPDO)" if img.direction.value == "rx" else "Inputs (TxPDO)"
    sm = f"SM{img.sm}" if img.sm is not None else "SM?"
    pdos = ", ".join(f"0x{p:04X}" for p in img.pdos) or "none"
    title = (f"{sm} {kind}: {img.byte_size} byte(s), {img.bit_size} bit(s); "
             f"0x{img.direction.assign_index:04X} = {pdos}")
    padded = img.byte_size * 8
    sec = Section(title, y, (padded + BITS_PER_ROW - 1) // BITS_PER_ROW)
    fills = {p: PALETTE[i % len(PALETTE)] for i, p in enumerate(img.pdos)}
    sec.legend = [(fills[p], f"0x{p:04X}") for p in img.pdos]
    for e in img.entries:
        if e.is_gap:
            box = Box("gap", e, e.bit_offset, e.bit_len, "")
            box.segments = _segments(sec, e.bit_offset, e.bit_len)
            box.title = f"gap of {e.bit_len} bit(s) at {e.offset} (PDO 0x{e.pdo:04X})"
            _label(box, [f"gap {e.bit_len} bit", e.offset])
        else:
            box = Box("entry", e, e.bit_offset, e.bit_len, fills.get(e.pdo, PALETTE[0]))
            box.segments = _segments(sec, e.bit_offset, e.bit_len)
            obj = f"0x{e.index:04X}:{e.subindex:02X}"
            box.title = (f"{obj} {e.name} ({e.type_name or '?'}, {e.bit_len} bit) at {e.offset} "
                         f"in PDO 0x{e.pdo:04X}")
            _label(box, [obj, e.name or "(unnamed)", f"{e.offset} · {e.bit_len} bit"] if e.bit_len > 1
                   else [e.offset])
        sec.boxes.append(box)
    if padded > img.bit_size:
        box = Box("padding", None, img.bit_size, padded - img.bit_size, "none")
        box.segments = _segments(sec, img.bit_size, padded - img.bit_size)
        box.title = f"{padded - img.bit_size} unused bit(s) of the last byte"
        _label(box, ["unused"])
        sec.boxes.append(box)
    return sec


def sections(layout: Layout, top: float = 40.0) -> list[Section]:
    out: list[Section] = []
    y = top
    for img in (layout.outputs, layout.inputs):
        sec = section_of(img, y)
        out.append(sec)
        y += sec.height + SECTION_GAP
    return out


def process_image_svg(layout: Layout, title: str = "", standalone: bool = True, uid: str = "pi") -> str:
    """SVG text of the diagram; ``standalone`` adds the XML declaration (for a file of its own), ``uid``
    prefixes the ids inside (several diagrams inline in one page must not share ids)."""
    secs = sections(layout, 40.0 if title else 4.0)
    height = secs[-1].y + secs[-1].height + 8
    return str(environment().get_template("process_image.svg.j2").render(
        title=title, sections=secs, width=WIDTH, height=height, standalone=standalone, uid=uid, X0=X0,
        BIT_WIDTH=BIT_WIDTH, BITS_PER_ROW=BITS_PER_ROW, SECTION_HEAD=SECTION_HEAD, ROW_HEIGHT=ROW_HEIGHT,
        ROW_GAP=ROW_GAP))
