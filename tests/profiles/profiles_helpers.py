"""Helpers shared by the tests/profiles/test_profiles_*.py files."""

from __future__ import annotations

from typing import Any

from ecattool.esi.model import Device


def value(device: Device, index: int, sub: int = 0) -> Any:
    """The decoded default of ``index:sub``; fails the test when the entry does not exist."""
    e = device.dictionary.entry(index, sub)
    assert e is not None, f"missing {index:04X}:{sub}"
    return e.default_value


def mapping(device: Device, index: int) -> list[int]:
    """The default entries (mapping values or assigned indices) up to sub-index 0's count."""
    return [value(device, index, s) for s in range(1, value(device, index, 0) + 1)]
