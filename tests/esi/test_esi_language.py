"""The one English-name rule of ESI files (esi.values.lang_rank): LcId 1033 wherever it stands, else another
English (2057 en-GB…), else the first element; the same for groups, devices, URLs, objects, sub-items and PDO
entries, on corpus files written in several languages."""

from __future__ import annotations

import pytest

from ecattool.esi import load, load_bytes
from ecattool.esi.values import is_english, lang_rank
from tests.conftest import corpus_path


@pytest.mark.parametrize(("lcid", "rank"), [("1033", 0), (" +01033 ", 0), ("2057", 1), ("3081", 1), ("1031", 2),
                                            ("2052", 2), (None, 2), ("en", 2), ("", 2)])
def test_lang_rank(lcid: str | None, rank: int) -> None:
    assert lang_rank(lcid) == rank
    assert is_english(lcid) is (rank == 0)


def test_ek11xx_english_first_then_german() -> None:
    esi = load(corpus_path("esi", "beckhoff_EK11xx.xml"))
    assert esi.groups["System"] == "System Terminals"
    dev = esi.devices[0]
    assert dev.name == "EK1100 EtherCAT Coupler (0.5A E-Bus)" and dev.url == "http://www.beckhoff.com/EK1100"


def _synapticon(**swaps: str) -> bytes:
    data = corpus_path("esi", "synapticon_Somanet_CiA402-single.xml").read_bytes()
    for old, new in swaps.items():
        before = old.replace("_", " ").encode()
        assert data.count(b"<Name>" + before + b"</Name>") >= 1
        data = data.replace(b"<Name>" + before + b"</Name>", new.encode(), 1)
    return data


def test_synapticon_german_first_then_english() -> None:
    esi = load(corpus_path("esi", "synapticon_Somanet_CiA402-single.xml"))
    assert esi.devices[0].name == "CiA402 Drive"  # 1033 first, then 1031 "CiA402 Antrieb (Modules/Slots)"


def test_every_named_element_takes_english_wherever_it_stands() -> None:
    esi = load_bytes(_synapticon(
        Device_Type='<Name LcId="1031">Geraetetyp</Name><Name LcId="1033">Device Type</Name>',
        Identity='<Name LcId="1031">Identitaet</Name><Name LcId="2057">Identity (GB)</Name>',
        Op_Modes='<Name LcId="1036">Mode de fonctionnement</Name><Name LcId="1031">Betriebsart</Name>',
    ), "multi.xml")
    dev = esi.devices[0]
    od = dev.dictionary
    assert od.get(0x1000).name == "Device Type"  # 1033 after German
    assert od.get(0x1018).name == "Identity (GB)"  # no 1033: another English before German
    entry = next(e for p in dev.rx_pdos for e in p.entries if e.index == 0x6060)
    assert entry.name == "Mode de fonctionnement"  # no English: the first
