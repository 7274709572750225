"""The ESI reader's fast paths (issue 2) change no fact of the model.

* Every PDO (index, name, line, excludes) and PDO entry of every corpus ESI (devices and modules, with the line
  of each entry) equals what a plain reader written here with ``find``/``findall`` reads from the same tree.
* Every materialised dictionary of every corpus ESI has the facts (objects, entries, types, sizes, offsets,
  access, defaults, limits, enums, lines) and the reader warnings it had before the fast paths: a digest
  computed with the reader of commit ff2b56f (before issue 2's changes). A deliberate change of a dictionary
  fact changes a digest; print the new ones with ``python -m tests.esi.test_esi_identity`` and say why in the commit.
"""

from __future__ import annotations

import hashlib
from typing import Any

import pytest

from ecattool.errors import InputError
from ecattool.esi import load, load_bytes, materialize
from ecattool.od.model import ObjectDictionary
from ecattool.xmlsafe import parse_xml
from tests.conftest import CORPUS, corpus_files, corpus_path

# sha256 of _dictionary_facts(file), by the reader before issue 2's fast paths; the 14 Beckhoff families the corpus
# gained with issue 34 (EJ1-9xxx, EK13xx, EK15xx, EL15xx, EL47xx, EL66xx, EM3xxx, EP4xxx, EQ2xxx, ER5xxx) by the reader
# of that day, a guard against regressions
DIGESTS = {
    "beckhoff_AX2xxx.xml": "7dca06da9e6b59b5ae36ae60f258177e3f069f506d89964c9ac835e768ed22a0",
    "beckhoff_AX5021-xxxx-0001_Dict.xml": "333e2a342bf02c27f0a53bc132ab54a684357e78089da4d3ed28b7cc0d2044bf",
    "beckhoff_AX5xxx.xml": "2b5fc6fd1371ab25a2f05bb9ef59cc269f6f394f95dc933d87e24c40e8f50848",
    "beckhoff_CUxxxx.xml": "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855",
    "beckhoff_EJ1xxx.xml": "0f4d7faf2e69782ca1ca76c715098c1727836c43f596f96a11e3c763feb47839",
    "beckhoff_EJ2xxx.xml": "5ab0045fbd4e78997e0b8774f080f47f4b9d919d4807b601a5d0d3331a85eb77",
    "beckhoff_EJ3xxx.xml": "466ecd4d8abdf9d68ba1f7c69563e2d5b8c698a620f5675b4718a40414bd2c2b",
    "beckhoff_EJ5xxx.xml": "e5c738aed03e03d80cc09a97157e150d943e87f4f2db2b8b0f5d33ef1a884426",
    "beckhoff_EJ9xxx.xml": "0ad409d1332d82a5b3448735a302d96f4a86be6f093de0c796e77be5ab25929a",
    "beckhoff_EK11xx.xml": "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855",
    "beckhoff_EK13xx.xml": "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855",
    "beckhoff_EK15xx.xml": "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855",
    "beckhoff_EL15xx.xml": "cbd22805886a2941d426a0c3c5399fe76d7d23b1b077fb3df3034bf26373bc68",
    "beckhoff_EL1xxx.xml": "788abafd9b9e43691d371bb51b77c81f4dcff291f5b00b5e031daecd670312a6",
    "beckhoff_EL47xx.xml": "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855",
    "beckhoff_EL66xx.xml": "e4bb9c06a66b52f62efbb0d392c0e89fd6facb886e0f9a43399eb22a31ce1a0c",
    "beckhoff_EM3xxx.xml": "7fd190e283fb3cc602920efbd82dbf753f40c923646ccd441d5a85487833e819",
    "beckhoff_EM7xxx.xml": "1bd873b10ba7e714b23faf2483e7f8412012e77f09380fe9697d0095531a67fb",
    "beckhoff_EP4xxx.xml": "75b77312de470109094a8a78831a527c009dcda64762735765bdee8d892b1c23",
    "beckhoff_EQ2xxx.xml": "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855",
    "beckhoff_ER5xxx.xml": "17340244c2c99eca9603c63b3b5c629d7c409f80c0926f55bd26cbed40474e71",
    "copley_XE2_4.60.xml": "12bf20bfbd6b04a3ee8ef2edc7cb5beb72ff3da480a07de8651f186928f62695",
    "elmo_Elmo_ECAT_00010420_V11.xml": "3668e0b075bf676387266bc31628ae1ee2dae0500c5b8825160884eaa5f7069d",
    "etg_ETG2001_ModulesSlots_CiA402.xml": "221e917b8c4c71ed184e5caef6b1b47e8b032b449b2918e8b9c8ff0f9555f3b1",
    "ingenia_eve-xcr-e_esi.xml": "7869707c8e82ac9f7f81deb83559ee61986547f87de66011a3f113cc3edd31cd",
    "inovance_SV660_EOE_1Axis_V9.12.xml": "68079689d5a154e6f1a5925deec282fa04b667e6c63cbd6d3c75ec6e3451d9fe",
    "itegva_E7x_Series.xml": "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855",
    "smc_EX260-SECx_V11.xml": "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855",
    "synapticon_Somanet_CiA402-single.xml": "cea7efd7794dc798247afba6682328512505620f5dccdde3232ff9260d27806c",
    "synapticon_Somanet_CtrlProto.xml": "5475eb9613cedf4461cb342fa5324d7104316a45b3a7f5db4a83f71f1a5c8dd8",
    "weidmueller_UR20_FBC.xml": "11e51178e32b52c7d6088add334394cbf4cd09daefa0d9797f5ec87b3c3bcd7e",
    # its four Sm elements have no text: four esi-sm-kind warnings (the kind from the ControlByte, issue 22)
    "weidmueller_UR20_FBC_from_IgH.xml": "6452a4ffc14e99558be5d0dd8a9b251b0d13dc94f1da6db2d05edf313dca6924",
    "weidmueller_UR20_IO.xml": "c17ffb3a7040dbc300f5349e7f7ed23100805da13eb28d2437c540b9d1ac6405",
}


def _esi_files() -> list[str]:
    files = corpus_files("esi/*.xml", form="name")
    if not files:
        raise FileNotFoundError(f"no ESI files under {CORPUS / 'esi'}")
    return files


# --- the plain reader of PDO facts ---------------------------------------------------------------------------
def _num(text: str | None) -> int:
    s = (text or "").strip()
    return int(s[2:], 16) if s[:2].lower() in ("#x", "0x") else int(s)


def _name(el: Any) -> str:
    names = el.findall("Name")
    english = [n for n in names if (n.get("LcId") or "").strip() == "1033"]
    chosen = english[0] if english else (names[0] if names else None)
    return (chosen.text or "").strip() if chosen is not None else ""


def _entry_facts(en: Any) -> tuple[Any, ...]:
    sub = en.findtext("SubIndex")
    return (_num(en.findtext("Index")), _num(sub) if sub is not None and sub.strip() else 0,
            _num(en.findtext("BitLen")), _name(en), (en.findtext("DataType") or "").strip(), en.sourceline)


def _pdo_facts_xml(owner: Any) -> list[tuple[Any, ...]]:
    return [(pdo.tag, _num(pdo.findtext("Index")), _name(pdo), pdo.sourceline,
             [_entry_facts(en) for en in pdo.findall("Entry")], [_num(x.text) for x in pdo.findall("Exclude")])
            for pdo in owner if pdo.tag in ("RxPdo", "TxPdo")]


def _pdo_facts_model(owner: Any) -> list[tuple[Any, ...]]:
    out = []
    for pdo in list(owner.rx_pdos) + list(owner.tx_pdos):
        tag = "RxPdo" if pdo.direction.name == "RX" else "TxPdo"
        out.append((tag, pdo.index, pdo.name, pdo.location.line,
                    [(e.index, e.subindex, e.bit_len, e.name, e.data_type, e.location.line) for e in pdo.entries],
                    pdo.excludes))
    return out


def _by_line(facts: list[tuple[Any, ...]]) -> list[tuple[Any, ...]]:
    return sorted(facts, key=lambda f: f[3])  # the model keeps Rx and Tx apart; the file interleaves them


@pytest.mark.parametrize("name", _esi_files())
def test_pdos_and_entries_equal_a_plain_reader(name: str) -> None:
    path = corpus_path("esi", name)
    esi = load(path)
    root = parse_xml(path.read_bytes(), str(path), drop_blank_text=True).getroot()
    devices = root.findall("Descriptions/Devices/Device")
    assert len(devices) == len(esi.devices)
    n_entries = 0
    for dev_el, dev in zip(devices, esi.devices):
        expected = _pdo_facts_xml(dev_el)
        assert _by_line(_pdo_facts_model(dev)) == _by_line(expected), f"{name}: {dev.type_name}"
        n_entries += sum(len(p[4]) for p in expected)
    module_els = root.findall("Descriptions/Modules/Module") + root.findall("Modules/Module")
    own_modules = esi.modules[:len(module_els)]  # InfoReference modules follow the file's own
    for mod_el, mod in zip(module_els, own_modules, strict=True):
        assert _by_line(_pdo_facts_model(mod)) == _by_line(_pdo_facts_xml(mod_el)), f"{name}: module {mod.type}"
    if name == "beckhoff_EL1xxx.xml":
        assert n_entries == 6392  # the benchmark file: every entry compared


def test_entry_number_memo_keeps_warnings_and_errors_per_element() -> None:
    """The reader remembers numbers by text; a 0x spelling still warns at each element, a bad one still fails."""
    pdo = ("<TxPdo><Index>#x1A00</Index><Name>In</Name>"
           "<Entry><Index>0x6000</Index><SubIndex>1</SubIndex><BitLen>1</BitLen><Name>A</Name><DataType>BOOL</DataType></Entry>"
           "<Entry><Index>0x6000</Index><SubIndex>2</SubIndex><BitLen>1</BitLen><Name>B</Name><DataType>BOOL</DataType></Entry>"
           "<Entry><Index>#x6000</Index><SubIndex>3</SubIndex><BitLen>1</BitLen><Name>C</Name><DataType>BOOL</DataType></Entry>"
           "</TxPdo>")
    doc = ("<EtherCATInfo><Vendor><Id>2</Id><Name>V</Name></Vendor><Descriptions><Devices><Device>"
           "<Type ProductCode=\"#x1\" RevisionNo=\"#x1\">D</Type><Name>D</Name>\n" + pdo.replace("<Entry>", "\n<Entry>")
           + "</Device></Devices></Descriptions></EtherCATInfo>")
    esi = load_bytes(doc.encode(), "m.xml")
    entries = esi.devices[0].tx_pdos[0].entries
    assert [(e.index, e.subindex, e.location.line) for e in entries] == [(0x6000, 1, 3), (0x6000, 2, 4), (0x6000, 3, 5)]
    warned = [w.location.line for w in esi.warnings if w.rule == "esi-number-0x"]
    assert warned == [3, 4]
    with pytest.raises(InputError, match="BitLen"):
        load_bytes(doc.replace("<BitLen>1</BitLen><Name>C", "<BitLen>x1</BitLen><Name>C").encode(), "bad.xml")


def test_datatype_subitem_values_only_where_the_subitem_has_them() -> None:
    """Defaults and limits written on a DataType's SubItem reach that entry only (a comment child is ignored)."""
    datatypes = ("<DataType><Name>DT2000</Name><BitSize>48</BitSize>"
                 "<SubItem><SubIdx>0</SubIdx><Name>n</Name><Type>USINT</Type><BitSize>8</BitSize><BitOffs>0</BitOffs></SubItem>"
                 "<SubItem><SubIdx>1</SubIdx><Name>Limit</Name><Type>UINT</Type><BitSize>16</BitSize><BitOffs>16</BitOffs>"
                 "<!-- vendor note --><MinValue>5</MinValue><MaxValue>#x100</MaxValue><DefaultValue>7</DefaultValue></SubItem>"
                 "<SubItem><SubIdx>2</SubIdx><Name>Plain</Name><Type>UINT</Type><BitSize>16</BitSize><BitOffs>32</BitOffs>"
                 "<!-- no values --></SubItem></DataType>")
    objects = ("<Object><Index>#x2000</Index><Name>Rec</Name><Type>DT2000</Type><BitSize>48</BitSize>"
               "<Flags><Access>rw</Access></Flags></Object>")
    doc = ("<EtherCATInfo><Vendor><Id>2</Id><Name>V</Name></Vendor><Descriptions><Devices><Device>"
           "<Type ProductCode=\"#x1\" RevisionNo=\"#x1\">D</Type><Name>D</Name><Profile><Dictionary>"
           f"<DataTypes>{datatypes}</DataTypes><Objects>{objects}</Objects>"
           "</Dictionary></Profile></Device></Devices></Descriptions></EtherCATInfo>")
    od = load_bytes(doc.encode(), "dt.xml").devices[0].dictionary
    limit, plain = od.entry(0x2000, 1), od.entry(0x2000, 2)
    assert (limit.minimum, limit.maximum, limit.default) == (5, 256, b"\x07\x00")
    assert (plain.minimum, plain.maximum, plain.default) == (None, None, None)


# --- the dictionary digest ------------------------------------------------------------------------------------
def _dictionaries(esi: Any) -> list[tuple[str, ObjectDictionary]]:
    out = [("file", esi.dictionary)] if esi.dictionary is not None else []
    out += [(f"device {i}", d.dictionary) for i, d in enumerate(esi.devices) if d.dictionary is not None]
    out += [(f"module {i}", m.dictionary) for i, m in enumerate(esi.modules) if m.dictionary is not None]
    return out


def _line(loc: Any) -> int | None:
    return loc.line if loc is not None else None


def _dictionary_facts(esi: Any) -> str:
    lines = []
    for owner, od in _dictionaries(esi):
        for index in od.indices():
            o = od.get(index)
            lines.append(f"{owner} {index:04X} {o.name!r} {o.object_code.name} {o.type_name!r} {o.category!r} {_line(o.location)}")
            for sub, e in sorted(o.entries.items()):
                dt = e.datatype.name if e.datatype is not None else None
                default = e.default.hex() if e.default is not None else None
                lines.append(
                    f"  {sub} {e.subindex} {e.name!r} {dt} {e.bit_size} {e.type_name!r} {e.bit_offset} "
                    f"{e.access.text} {sorted(s.name for s in e.access.read)} {sorted(s.name for s in e.access.write)} "
                    f"{e.pdo_mapping} {default} {e.minimum!r} {e.maximum!r} {sorted(e.enum.items())} {e.backup} "
                    f"{e.setting} {e.category!r} {e.unit!r} {e.comment!r} {_line(e.location)}")
    for w in esi.warnings:
        lines.append(f"warning {w.rule} {_line(w.location)} {w.message}")
    return "\n".join(lines)


def _digest(name: str) -> str:
    esi = load(corpus_path("esi", name))
    materialize(esi)
    return hashlib.sha256(_dictionary_facts(esi).encode()).hexdigest()


@pytest.mark.parametrize("name", sorted(DIGESTS))
def test_materialised_dictionaries_are_unchanged(name: str) -> None:
    assert _digest(name) == DIGESTS[name]


def test_every_corpus_esi_has_a_digest() -> None:
    corpus_path("esi")
    assert sorted(DIGESTS) == _esi_files()


def test_load_leaves_the_garbage_collector_as_it_was() -> None:
    """The reader pauses the cyclic collector while it builds; enabled or not, it is as before, also after errors."""
    import gc

    path = corpus_path("esi", "etg_ETG2001_ModulesSlots_CiA402.xml")
    was = gc.isenabled()
    try:
        for enabled in (True, False):
            (gc.enable if enabled else gc.disable)()
            materialize(load(path))
            assert gc.isenabled() is enabled
            with pytest.raises(InputError, match="not an ESI file"):
                load_bytes(b"<Other/>", "x.xml")
            assert gc.isenabled() is enabled
    finally:
        (gc.enable if was else gc.disable)()


if __name__ == "__main__":
    for f in _esi_files():
        print(f"    {f!r}: {_digest(f)!r},")
