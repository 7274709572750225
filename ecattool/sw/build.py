"""``sw build``: assemble a ``.sw`` image from a YAML spec, with every integrity word correct.

Spec (paths relative to the spec file; numbers as 0x7ABD, #x7ABD or decimal)::

    base: ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.sw   # optional: start from this image (.sw or FoE .bin)
    blocks:                                       # optional, added in this order
      - from: ecmc_TMLCode.sw                     # every block of another image ...
        start: 0x4000                             # ... or only the block starting here
      - start: 0x5638                             # raw words
        words: [0x1234, 0x5678]
        replace: true                             # replace a base block with the same start
      - start: 0x5700                             # a CAM table (§18.4.1), checksum word computed
        cam: {step: 64, master_start: 0, points: [0, 1000, 4000]}
    setup:                                        # values over the base image's setup table
      parameters: ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.ems_parameters.cfg
      values: {PWMPER: 2250, CLPER: 2, 0x0250: 2}
    identification: P027314E221F515K              # optional: new identification text
    final_blank_line: true

Nothing is invented: a setup table, an identification block (its word 32 has unknown meaning) and the
pointer at 0x7FFF come from the base image or from other images; the spec only changes values in them.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ecattool.errors import InputError, Location
from ecattool.od.numbers import parse_int
from ecattool.sw.foe import read_foe
from ecattool.sw.image import Block, SwImage, check_overlaps, read
from ecattool.sw.layout import (
    IDENT_START,
    IDENT_TEXT_WORDS,
    cam_table_words,
    fix_integrity,
    identification_text_words,
    identification_words,
    setup_table,
)
from ecattool.sw.params import read_parameters
from ecattool.sw.setup import patch

_TOP_KEYS = {"base", "blocks", "setup", "identification", "final_blank_line"}


def load_image(path: Path) -> SwImage:
    """A ``.sw`` text image, or a FoE binary image (``.bin``/``.efw``)."""
    return read_foe(path) if path.suffix.lower() in (".bin", ".efw") else read(path)


def build(spec_path: str | Path, read: list[Path] | None = None) -> SwImage:
    """The image a build spec describes; ``read`` (when given) collects the files the spec names."""
    from ecattool.fileio import read_bytes
    from ecattool.yamlloc import load_yaml

    spec_path = Path(spec_path)
    doc = load_yaml(read_bytes(spec_path, 4 * 1024 * 1024), str(spec_path))
    return build_from(doc.data, doc.locate, spec_path.parent, str(spec_path), read)


def build_from(data: Any, locate: Any, base_dir: Path, source: str, read: list[Path] | None = None) -> SwImage:
    if not isinstance(data, dict):
        raise InputError("a build spec is a mapping with base/blocks/setup keys", Location(source, 1))
    for key in data:
        if key not in _TOP_KEYS:
            raise InputError(f"unknown key {key!r} (known: {', '.join(sorted(_TOP_KEYS))})", locate((key,)))

    def path_of(value: Any, where: tuple[Any, ...]) -> Path:
        if not isinstance(value, str) or not value:
            raise InputError("expected a file path", locate(where))
        p = base_dir / value
        try:
            found = p.is_file()
        except (OSError, ValueError) as exc:  # a name too long for the file system, a NUL byte
            raise InputError(f"cannot use file name {value[:40]!r}{'…' if len(value) > 40 else ''}: "
                             f"{getattr(exc, 'strerror', None) or exc}", locate(where)) from None
        if not found:
            raise InputError(f"file not found: {p}" if not p.is_dir() else f"not a file: {p}", locate(where))
        if read is not None:
            read.append(p)
        return p

    def start_of(spec: dict[str, Any], where: tuple[Any, ...]) -> int:
        start = number(spec["start"], where + ("start",), "block start")
        if not 0 <= start <= 0xFFFF:
            raise InputError(f"block start 0x{start:X} is outside the drive's 16-bit word space 0x0000..0xFFFF"
                             if start >= 0 else f"block start {start} is negative", locate(where + ("start",)))
        return start

    def number(value: Any, where: tuple[Any, ...], what: str) -> int:
        if isinstance(value, bool):
            raise InputError(f"expected a {what}, not {str(value).lower()}", locate(where))
        try:
            n = parse_int(value, locate(where), what)
        except InputError:
            raise
        except Exception:  # noqa: BLE001 - a YAML list or mapping where a number belongs
            raise InputError(f"expected a {what}", locate(where)) from None
        return n

    blocks: list[Block] = []
    if "base" in data:
        blocks = list(load_image(path_of(data["base"], ("base",))).blocks)
    for i, spec in enumerate(data.get("blocks") or []):
        where = ("blocks", i)
        if not isinstance(spec, dict):
            raise InputError("each block is a mapping with 'from' or 'start' + 'words'", locate(where))
        new: list[Block]
        if "from" in spec:
            other = load_image(path_of(spec["from"], where + ("from",)))
            new = list(other.blocks)
            if "start" in spec:
                start = start_of(spec, where)
                new = [b for b in new if b.start == start]
                if not new:
                    raise InputError(f"{spec['from']} has no block starting at 0x{start:04X}", locate(where + ("start",)))
        elif "start" in spec and "words" in spec:
            start = start_of(spec, where)
            raw = spec["words"]
            if not isinstance(raw, list) or not raw:
                raise InputError("words must be a non-empty list of 16-bit values", locate(where + ("words",)))
            words: list[int] = []
            for k, w in enumerate(raw):
                v = number(w, where + ("words", k), "16-bit word")
                if not 0 <= v <= 0xFFFF:
                    raise InputError(f"{w!r} is not a 16-bit word", locate(where + ("words", k)))
                words.append(v)
            if not 0 <= start <= 0xFFFF or start + len(words) - 1 > 0xFFFF:
                raise InputError(f"block 0x{start:X} with {len(words)} words does not fit 0x0000..0xFFFF", locate(where))
            new = [Block(start, tuple(words))]
        elif "start" in spec and "cam" in spec:
            start = start_of(spec, where)
            cam_words = _cam_words(spec["cam"], where + ("cam",), locate, number)
            if start + len(cam_words) - 1 > 0xFFFF:
                raise InputError(f"block 0x{start:X} with {len(cam_words)} words does not fit 0x0000..0xFFFF",
                                 locate(where))
            new = [Block(start, cam_words)]
        else:
            raise InputError("a block needs 'from: FILE' (optionally with 'start'), or 'start' with 'words' or 'cam'",
                             locate(where))
        if spec.get("replace"):
            starts = {b.start for b in new}
            blocks = [b for b in blocks if b.start not in starts]
        line = locate(where).line
        blocks.extend(Block(b.start, b.words, line) for b in new)
    if not blocks:
        raise InputError("the spec builds no blocks: give 'base' or 'blocks'", Location(source, 1))
    try:
        check_overlaps(blocks, source)
    except InputError as exc:
        raise InputError(exc.message + " (use 'replace: true' to replace a base block)", exc.location) from None
    image = SwImage(tuple(Block(b.start, b.words) for b in blocks), bool(data.get("final_blank_line", True)), source)

    if "identification" in data:
        text = data["identification"]
        ident = image.block_at(IDENT_START)
        if ident is None or ident.start != IDENT_START:
            raise InputError("identification needs an identification block at 0x7FBF from the base image",
                             locate(("identification",)))
        try:
            ident_words = identification_words(identification_text_words(str(text)), ident.words[IDENT_TEXT_WORDS + 1])
        except InputError as exc:
            raise InputError(exc.message, locate(("identification",))) from None
        image = image.with_words({IDENT_START + i: w for i, w in enumerate(ident_words)})

    setup = data.get("setup")
    if setup is not None:
        image = _apply_setup(image, setup, locate, path_of)
    return fix_integrity(image)


def _cam_words(cam: Any, where: tuple[Any, ...], locate: Any, number: Any) -> tuple[int, ...]:
    if not isinstance(cam, dict) or not isinstance(cam.get("points"), list):
        raise InputError("cam is a mapping with 'step' (1..128), 'points' (Y list) and optional 'master_start'",
                         locate(where))
    step = number(cam.get("step", 1), where + ("step",), "interpolation step")
    points = [number(y, where + ("points", k), "CAM point") for k, y in enumerate(cam["points"])]
    master = number(cam.get("master_start", 0), where + ("master_start",), "master start")
    try:
        return cam_table_words(step, points, master)
    except InputError as exc:
        raise InputError(exc.message, locate(where)) from None


def _apply_setup(image: SwImage, setup: Any, locate: Any, path_of: Any) -> SwImage:
    if not isinstance(setup, dict) or not isinstance(setup.get("values", {}), dict):
        raise InputError("setup is a mapping with 'parameters' (file) and 'values' (NAME: value)", locate(("setup",)))

    try:
        setup_table(image)
    except InputError as exc:
        raise InputError(exc.message, locate(("setup",))) from None
    params = read_parameters(path_of(setup["parameters"], ("setup", "parameters"))) if "parameters" in setup else None
    values = setup.get("values") or {}
    assignments = [(str(k), str(v)) for k, v in values.items()]
    locations = [locate(("setup", "values", k)) for k in values]
    return patch(image, assignments, params, locations)
