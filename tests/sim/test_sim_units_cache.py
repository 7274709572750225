"""The drive computes its unit factors once per change of the factor objects (sim.units.FACTOR_OBJECTS): a write
to one of them, by SDO or by restoring a store after an aborted complete access, must show at once."""

from __future__ import annotations

from fractions import Fraction

import pytest

from ecattool.errors import SdoAbort
from ecattool.od.model import EcState
from ecattool.sim import Drive


def _hdt() -> Drive:
    d = Drive.from_profile("hdt")
    d.request_state(EcState.PREOP)
    return d


def test_a_factor_written_by_sdo_converts_at_once() -> None:
    d = _hdt()
    d.sdo_download(0x6093, 1, (16384).to_bytes(4, "little"))
    d.sdo_download(0x6093, 2, (25).to_bytes(4, "little"))
    assert d.units.position_to_internal(100) == 65536
    d.sdo_download(0x6093, 2, (50).to_bytes(4, "little"))
    assert d.units.position_to_internal(100) == 32768
    assert d.units.position_to_user(Fraction(32768)) == 100


def test_the_cycle_follows_60c2() -> None:
    d = _hdt()
    assert (0x60C2, 1) in d._entries
    d.sdo_download(0x60C2, 1, bytes([2]))
    d.sdo_download(0x60C2, 2, (-3).to_bytes(1, "little", signed=True))
    assert d.cycle_time() == Fraction(2, 1000)
    assert d.cycle_ns() == 2_000_000
    d.sdo_download(0x60C2, 1, bytes([4]))
    assert d.cycle_time() == Fraction(4, 1000)
    assert d.cycle_ns() == 4_000_000  # the nanoseconds sim serve paces a drive by follow the same write
    t = Drive.from_profile("technosoft")  # its 60C2h takes what HDT's range refuses
    t.request_state(EcState.PREOP)
    t.sdo_download(0x60C2, 1, bytes([125]))
    t.sdo_download(0x60C2, 2, (-6).to_bytes(1, "little", signed=True))
    assert (t.cycle_time(), t.cycle_ns()) == (Fraction(125, 10**6), 125_000)
    t.sdo_download(0x60C2, 1, bytes([0]))  # no cycle given: the default 1 ms
    assert (t.cycle_time(), t.cycle_ns()) == (Fraction(1, 1000), 1_000_000)


def test_a_restored_store_is_a_new_version() -> None:
    d = _hdt()
    before = d._store.version
    d._store[(0x6093, 1)] = (1).to_bytes(4, "little")
    assert d._store.version != before
    d._store[(0x6040, 0)] = b"\x00\x00"  # not a factor object: the cached factors stay
    v = d._store.version
    d._store[(0x6040, 0)] = b"\x06\x00"
    assert d._store.version == v


def test_the_factors_follow_the_store_an_aborted_complete_access_puts_back() -> None:
    """An aborted complete-access download puts the store of before back in place (sim/drive/sdo.py): the unit
    factors' version is that store's from then on, so a factor written after it shows at once (they followed the
    store of the last reset, whose version no later write moves)."""
    import struct

    d = Drive.from_esi("samples/esi/etg2001_cia402.xml")  # complete access on
    d.request_state(EcState.PREOP)
    mapping = d.sdo_upload(0x1A00, 0, complete_access=True)
    with pytest.raises(SdoAbort):  # a read-only entry in the middle: the store of before is put back
        d.sdo_download(0x1A00, 0, mapping[:2] + struct.pack("<I", 0x77770020) + mapping[6:], complete_access=True)
    assert d.units.version() == d._store.version
