"""Choosing one device from an ESI file: by type name, ``[vendor:]product[:revision]`` or list index.

Policies for the revision (numbers compared as integers, never as strings):

* ``exact`` — the revision must equal the requested one; without a revision the match must be unique;
* ``newest-not-newer`` — the highest revision that is not newer than the requested one (without a revision:
  the newest);
* ``newest`` — the highest revision, whatever was requested.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from typing import Any, TypeVar

from ecattool.errors import InputError, SelectionError
from ecattool.esi.model import Device, EsiFile
from ecattool.od.numbers import parse_int

# a Device, or a reader DeviceHead (type name and identity of a device not built yet)
_D = TypeVar("_D", bound=Any)

POLICIES = ("exact", "newest-not-newer", "newest")
_MAX_LISTED = 25


def describe(dev: Any, index: int | None = None) -> str:
    pre = f"[{index}] " if index is not None else ""
    return f"{pre}{dev.type_name} (product 0x{dev.product_code:08X} revision 0x{dev.revision:08X})"


def candidates_text(devices: Sequence[Any], all_devices: Sequence[Any] | None = None) -> str:
    """``[i] TYPE (product … revision …)`` for each candidate; ``i`` is the position in the whole file."""
    pos = {id(d): i for i, d in enumerate(all_devices if all_devices is not None else devices)}
    shown = [describe(d, pos.get(id(d))) for d in devices[:_MAX_LISTED]]
    more = len(devices) - _MAX_LISTED
    return "; ".join(shown) + (f"; … and {more} more" if more > 0 else "")


def _parse_selector(selector: str) -> tuple[int | None, int, int | None]:
    parts = [p.strip() for p in selector.split(":")]
    try:
        nums = [parse_int(p, what="number") for p in parts]
    except InputError:
        raise SelectionError(f"device selector {selector!r} is not a type name, product[:revision] or index") from None
    if len(nums) == 1:
        return None, nums[0], None
    if len(nums) == 2:
        return None, nums[0], nums[1]
    if len(nums) == 3:
        return nums[0], nums[1], nums[2]
    raise SelectionError(f"device selector {selector!r} has too many ':' parts (use product[:revision])")


def _by_revision(pool: list[_D], revision: int | None, policy: str, what: str, all_devices: list[_D]) -> _D:
    if policy not in POLICIES:
        raise SelectionError(f"unknown selection policy {policy!r} (use {', '.join(POLICIES)})")
    if not pool:
        raise SelectionError(f"no device matches {what}; candidates: {candidates_text(all_devices)}")
    if policy == "newest" or (policy == "newest-not-newer" and revision is None):
        return _one(pool, max(d.revision for d in pool), what, all_devices)
    if policy == "newest-not-newer":
        older = [d for d in pool if d.revision <= revision]
        if not older:
            raise SelectionError(
                f"no revision of {what} is 0x{revision:08X} or older; candidates: {candidates_text(pool, all_devices)}")
        return _one(older, max(d.revision for d in older), what, all_devices)
    if revision is None:
        if len(pool) == 1:
            return pool[0]
        if len({d.revision for d in pool}) == 1:
            _one(pool, pool[0].revision, what, all_devices)
        raise SelectionError(
            f"{what} matches {len(pool)} devices; give a revision (product:revision) or --policy newest (in a project file: policy: newest under device:); "
            f"candidates: {candidates_text(pool, all_devices)}")
    exact = [d for d in pool if d.revision == revision]
    if not exact:
        raise SelectionError(f"no device matches {what} with revision 0x{revision:08X} exactly; candidates: {candidates_text(pool, all_devices)}")
    return _one(exact, revision, what, all_devices)


def _one(pool: list[_D], revision: int, what: str, all_devices: list[_D]) -> _D:
    """The device of ``pool`` with ``revision``; where several devices of other type names share the product and
    the revision (end caps and bus-end terminals with product 0), none is picked by chance: they are told apart
    by type name or list index."""
    same = [d for d in pool if d.revision == revision]
    if len({d.type_name for d in same}) > 1:
        k = next((i for i, d in enumerate(all_devices) if d is same[0]), 0)
        raise SelectionError(
            f"{what} matches {len(same)} devices of the same revision 0x{revision:08X}; choose one by type name or "
            f"list index (--device {same[0].type_name} or --device {k}); candidates: {candidates_text(same, all_devices)}")
    return same[0]


def select(esi: EsiFile | list[Device], selector: str | int | None = None, policy: str = "exact") -> Device:
    """Pick one device. Raises :class:`SelectionError` listing the candidates when nothing (or too much) matches.

    On a lazily loaded file (``load(path, lazy=True)``) only the chosen device is built."""
    if isinstance(esi, EsiFile):
        return select_index(esi, selector, policy)[1]
    return _choose(list(esi), "", selector, policy)


def select_index(esi: EsiFile, selector: str | int | None = None, policy: str = "exact") -> tuple[int, Device]:
    """:func:`select`, also giving the device's position in the file (without building the others if lazy).

    When the file had devices that could not be read (``esi-device-skipped`` findings), a failed selection
    names them: the device asked for may be one of them."""
    from ecattool.esi.reader import LazyEsiFile  # here: the model and a selection need no XML reader (lxml)

    try:
        if isinstance(esi, LazyEsiFile) and esi.pending:
            head = _choose(esi.device_heads, esi.source, selector, policy)
            return head.index, esi.device_at(head.index)
        devices = list(esi.devices)
        dev = _choose(devices, esi.source, selector, policy)
        return next(i for i, d in enumerate(devices) if d is dev), dev
    except SelectionError as exc:
        skipped = [w for w in esi.warnings if w.rule == "esi-device-skipped"]
        if not skipped:
            raise
        raise SelectionError(f"{exc.message}; {len(skipped)} device(s) of the file could not be read: "
                             f"{skipped[0]}") from None


def _choose(devices: list[_D], source: str, selector: str | int | None, policy: str) -> _D:
    if policy not in POLICIES:
        raise SelectionError(f"unknown selection policy {policy!r} (use {', '.join(POLICIES)})")
    if not devices:
        raise SelectionError(f"{source or 'the input'} describes no devices")
    if selector is None or (isinstance(selector, str) and not selector.strip()):
        if len(devices) == 1:
            return devices[0]
        if policy == "newest" and len({d.product_code for d in devices}) == 1:
            return max(devices, key=lambda d: d.revision)
        raise SelectionError(f"{source or 'the input'} has {len(devices)} devices; choose one with a selector; "
                             f"candidates: {candidates_text(devices)}")
    if isinstance(selector, int):
        selector = str(selector)
    sel = selector.strip()
    by_type = [d for d in devices if d.type_name == sel] or [d for d in devices if d.type_name.lower() == sel.lower()]
    if by_type:
        return _by_revision(by_type, None, policy, f"type {sel!r}", devices)
    m = re.fullmatch(r"(.+?)\s*:\s*(.+)", sel)
    if m and any(d.type_name.lower() == m.group(1).lower() for d in devices):
        pool = [d for d in devices if d.type_name.lower() == m.group(1).lower()]
        _, _, rev = _parse_selector("0:" + m.group(2))
        return _by_revision(pool, rev, policy, f"type {m.group(1)!r}", devices)
    if sel.isdigit() and int(sel) < len(devices) and ":" not in sel:
        if not any(d.product_code == int(sel) for d in devices):
            return devices[int(sel)]
    vendor, product, revision = _parse_selector(sel)
    pool = [d for d in devices if d.product_code == product and (vendor is None or d.vendor_id == vendor)]
    return _by_revision(pool, revision, policy, f"product 0x{product:08X}", devices)
