"""SII read and write on a live slave, with the checks IgH's ``ethercat sii_write`` makes before writing: the
image's size (a whole number of words, fits the EEPROM), the CRC of the configuration area, a category chain
that parses to its end marker, and (unless ``any_identity``) the identity against the slave's. The old image is
read and written to a back-up file before the first word of the new one goes out, and the new one is written in
an order that an interruption cannot turn into an image that checks out (:func:`write_sequence`)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ecattool.errors import InputError, Location, TargetError
from ecattool.findings import Finding, Severity


def write_checks(image_bytes: bytes, current: bytes | None, source: str, any_identity: bool = False) -> list[str]:
    """What stops ``image_bytes`` from being written over the slave's ``current`` image (empty: write it); the
    identity (vendor, product code, revision) must be the slave's unless ``any_identity``."""
    from ecattool.sii.checks import check
    from ecattool.sii.crc import preamble_crc
    from ecattool.sii.image import parse

    problems: list[str] = []
    if len(image_bytes) < 128 or len(image_bytes) % 2:
        return [f"{source}: {len(image_bytes)} bytes is not an SII image (a whole number of words, at least the "
                "128-byte configuration area)"]
    if preamble_crc(image_bytes) != image_bytes[14]:
        problems.append(f"{source}: checksum 0x{image_bytes[14]:02X} does not match the CRC-8 of bytes 0-13 "
                        f"(0x{preamble_crc(image_bytes):02X}); fix it with 'ecattool sii fix-crc'")
    try:
        image = parse(image_bytes, source=source)
    except InputError as exc:
        return [*problems, f"{source}: the category chain does not parse: {exc.message}"]
    for f in check(image):
        if f.severity is Severity.ERROR and f.rule in ("sii.size", "sii.category", "sii.length", "sii.blank"):
            problems.append(f"{source}: {f.message} [{f.rule}]")
    if not image.end_marker:
        problems.append(f"{source}: the category chain has no end marker 0xFFFF")
    if current is not None and len(current) >= 128:
        from ecattool.sii.image import parse_header

        size = parse_header(current).eeprom_bytes  # the EEPROM the slave's own image declares
        if parse_header(current).size_word != 0xFFFF and len(image_bytes) > size:
            problems.append(f"{source}: {len(image_bytes)} bytes do not fit the slave's {size}-byte EEPROM")
    if current is not None and not any_identity:
        from ecattool.sii.image import parse_header

        old, new = parse_header(current), image.header
        for field in ("vendor_id", "product_code", "revision"):
            a, b = getattr(old, field), getattr(new, field)
            if a != b:
                problems.append(f"{source}: {field} 0x{b:08X} is not the slave's 0x{a:08X} (--any-identity "
                                "writes it anyway)")
    return problems


def read_problems(data: bytes) -> list[str]:
    """What makes an SII image read from a slave untrustworthy (empty: it checks out): shorter than the fixed area,
    blank (every byte of the fixed area 0xFF, an erased EEPROM) or all zero (what a read whose working counter was
    not checked gives), a checksum that is not the CRC-8 of bytes 0-13, a category chain without its end marker."""
    from ecattool.sii.crc import preamble_crc
    from ecattool.sii.image import parse

    if len(data) < 128:
        return [f"{len(data)} bytes, shorter than the 128-byte fixed area"]
    head = data[:128]
    if head == b"\xff" * 128:
        return ["blank: every byte of the fixed area is 0xFF (an erased EEPROM)"]
    if not any(head):
        return ["all zero: every byte of the fixed area is 0x00 (the EEPROM was not read, or is zeroed)"]
    problems = []
    if preamble_crc(data) != data[14]:
        problems.append(f"checksum 0x{data[14]:02X} is not the CRC-8 of bytes 0-13 (0x{preamble_crc(data):02X})")
    try:
        end_marker = parse(data).end_marker
    except InputError as exc:
        problems.append(f"the category chain does not parse: {exc.message}")
    else:
        if not end_marker:
            problems.append("the category chain has no end marker 0xFFFF")
    return problems


def read_checked(slave: Any) -> bytes:
    """The slave's SII image, checked by :func:`read_problems`: a :class:`TargetError` naming the slave and the
    first problem when it does not check out."""
    data: bytes = slave.sii_read()
    problems = read_problems(data)
    if problems:
        more = f" (and {len(problems) - 1} more)" if len(problems) > 1 else ""
        raise TargetError(f"slave {slave.position}: the SII read does not check out: {problems[0]}{more}")
    return data


def sii_write(slave: Any, image_bytes: bytes, source: str, backup: str | Path, any_identity: bool = False,
              overwrite_backup: bool = False) -> list[str]:
    """Check ``image_bytes`` against the slave (its identity too, unless ``any_identity``), write the slave's
    current image to ``backup``, then write the new one (:func:`write_sequence`: the header and its CRC last) and
    read it back. Returns the problems that stopped the write (nothing was written then); a read-back that differs
    is an :class:`InputError`."""
    from ecattool.fileio import write_atomic
    from ecattool.sii.eeprom import write_sequence

    current = slave.sii_read()
    problems = write_checks(image_bytes, current, source, any_identity)
    if problems:
        return problems
    write_atomic(backup, current, (source,), overwrite=overwrite_backup)
    for word, data in write_sequence(image_bytes, current):
        slave.sii_write_word(word, data)
    back = slave.sii_read()
    if back[:len(image_bytes)] != image_bytes[:len(back)] or len(back) < min(len(image_bytes), 128):
        raise InputError(f"slave {slave.position}: the SII read back differs from {source} (the old image is in "
                         f"{backup})", Location(source))
    return []


def findings_of(problems: list[str]) -> list[Finding]:
    return [Finding("sii.write", Severity.ERROR, p) for p in problems]
