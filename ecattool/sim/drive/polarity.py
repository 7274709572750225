"""Polarity 607Eh: bit 7 reverses the sign of positions, bit 6 of velocities.

* Technosoft §5.1.1 (TS 4222): "This object is used to multiply by 1 or -1 position and velocity objects. The
  object applies only to position profile, velocity profile, CSP and CSV" — the targets (607Ah, 60FFh) and the
  actual values (6064h, 6062h, 60F4h, 606Ch) in those modes (``Behaviour.polarity = "targets+actuals"``).
* HDT §4.05.11 (HDT 3418): "7 Position polarity, referred to the 'target position' (index 607Ah); 6 Velocity
  Polarity, referred to the 'target velocity' (index 60FFh)" — the targets only (``"targets"``), in every mode
  that reads them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ecattool.sim.drive.app import DriveApp

#: the modes Technosoft's polarity applies to (PP, PV, CSP, CSV)
_TS_MODES = frozenset({1, 3, 8, 9})


def _bits(drive: DriveApp, mode: int) -> int:
    kind = drive.behaviour.polarity
    if not kind or (kind == "targets+actuals" and mode not in _TS_MODES):
        return 0
    return drive._read_int(0x607E, 0) or 0


#: the signs of no polarity
_PLAIN = (1, 1)


def target_signs(drive: DriveApp, mode: int) -> tuple[int, int]:
    """(position, velocity) sign the targets 607Ah and 60FFh are read with in ``mode`` (kept per store version and
    mode: a write to 607Eh changes the version, core.SETTING_OBJECTS; every cycle asks)."""
    if not drive.behaviour.polarity:
        return _PLAIN
    version = drive.objects.store.version
    cached = drive._polarity_cache
    if cached[0] == version and cached[1] == mode:
        return cached[2]
    bits = _bits(drive, mode)
    signs = (-1 if bits & 0x80 else 1), (-1 if bits & 0x40 else 1)
    drive._polarity_cache = (version, mode, signs)
    return signs


def actual_signs(drive: DriveApp, mode: int) -> tuple[int, int]:
    """(position, velocity) sign the actual values are reported with in ``mode``."""
    if drive.behaviour.polarity != "targets+actuals":
        return 1, 1
    return target_signs(drive, mode)
