"""The reader's fast paths for the common shapes (a PDO entry's five children, PDO attributes spelled the common
way, an Info/SubItem of one Name and one Info) read exactly what the general paths read: the same values, and
the same warnings at the same lines when a value is spelled another way."""

from __future__ import annotations

from typing import Any

from ecattool.esi import load_bytes, materialize


def _doc(pdo: str, objects: str = "", datatypes: str = "") -> bytes:
    dictionary = (f"<Profile><Dictionary><DataTypes>{datatypes}</DataTypes><Objects>{objects}</Objects></Dictionary>"
                  "</Profile>") if objects else ""
    return ('<?xml version="1.0"?>\n<EtherCATInfo><Vendor><Id>2</Id><Name>V</Name></Vendor><Descriptions><Groups/>'
            '<Devices><Device><Type ProductCode="#x1" RevisionNo="#x1">D</Type><Name>D</Name>\n'
            '<Sm ControlByte="#x64" Enable="1">Outputs</Sm><Sm ControlByte="#x20" Enable="1">Inputs</Sm>\n'
            f'{pdo}\n{dictionary}</Device></Devices></Descriptions></EtherCATInfo>').encode()


FIVE = ("<Entry>\n<Index>{i}</Index>\n<SubIndex>{s}</SubIndex>\n<BitLen>{b}</BitLen>\n<Name{lc}>{n}</Name>\n"
        "<DataType>{t}</DataType></Entry>")


def _entries(entries: str, attrs: str = 'Sm="3" Fixed="1"') -> tuple[list[Any], list[Any]]:
    esi = load_bytes(_doc(f'<TxPdo {attrs}><Index>#x1A00</Index><Name>In</Name>{entries}</TxPdo>'), "f.xml")
    return esi.devices[0].tx_pdos[0].entries, [(w.rule, w.location.line) for w in esi.warnings]


def test_five_children_entry_reads_as_the_general_loop() -> None:
    common, w1 = _entries(FIVE.format(i="#x6000", s="2", b="16", lc="", n=" Value ", t="UINT"))
    # the same children in another order go through the general loop
    other, w2 = _entries("<Entry><SubIndex>2</SubIndex><Index>#x6000</Index><BitLen>16</BitLen><DataType>UINT</DataType>"
                         "<Name> Value </Name></Entry>")
    assert [(e.index, e.subindex, e.bit_len, e.name, e.data_type) for e in common] == \
        [(e.index, e.subindex, e.bit_len, e.name, e.data_type) for e in other] == [(0x6000, 2, 16, "Value", "UINT")]
    assert w1 == w2 == []
    assert common[0].location.line == 4  # the Entry's own line


def test_five_children_entry_warns_at_each_child() -> None:
    # uncommon spellings leave the memo to Context.number: warnings at the child's line, in document order
    entries, warnings = _entries(FIVE.format(i="0x6000", s="#X2", b=" 8 ", lc=' LcId="1031"', n="Wert", t="USINT"))
    e = entries[0]
    assert (e.index, e.subindex, e.bit_len, e.name) == (0x6000, 2, 8, "Wert")  # the only Name, whatever its LcId
    assert warnings == [("esi-number-0x", 5)]  # at the Index, on line 5 (the Entry starts on line 4)


def test_empty_subindex_in_the_common_shape_is_zero() -> None:
    entries, _ = _entries(FIVE.format(i="#x7000", s="", b="1", lc="", n="Bit", t="BOOL"))
    assert entries[0].subindex == 0


def test_pdo_attributes_common_and_other_spellings() -> None:
    esi = load_bytes(_doc('<TxPdo Fixed="true" Mandatory="0" Sm="#x3" Su="0" OSFac="2"><Index>#x1A00</Index>'
                          '<Name>In</Name></TxPdo>'), "f.xml")
    p = esi.devices[0].tx_pdos[0]
    assert (p.fixed, p.mandatory, p.sm, p.su, p.os_fac) == (True, False, 3, 0, 2)
    assert esi.warnings == []
    # one attribute spelled another way: every one is read by Context, its warning located at the PDO
    esi = load_bytes(_doc('<TxPdo Fixed="1" Sm="0x3"><Index>#x1A00</Index><Name>In</Name></TxPdo>'), "f.xml")
    p = esi.devices[0].tx_pdos[0]
    assert (p.fixed, p.sm) == (True, 3)
    assert [(w.rule, w.location.line) for w in esi.warnings] == [("esi-number-0x", 4)]


def test_info_subitem_with_an_lcid_name_takes_the_english_one() -> None:
    datatypes = ('<DataType><Name>DT1A00</Name><BitSize>48</BitSize><SubItem><SubIdx>0</SubIdx><Name>SubIndex 000</Name>'
                 '<Type>USINT</Type><BitSize>8</BitSize><BitOffs>0</BitOffs></SubItem><SubItem><SubIdx>1</SubIdx>'
                 '<Name>SubIndex 001</Name><Type>UDINT</Type><BitSize>32</BitSize><BitOffs>16</BitOffs></SubItem>'
                 '</DataType>')
    info = ('<Info><SubItem><Name>SubIndex 000</Name><Info><DefaultData>01</DefaultData></Info></SubItem>'
            '<SubItem><Name LcId="1031">Eintrag</Name><Name LcId="1033">Entry</Name><Info><DefaultData>10000060'
            '</DefaultData></Info></SubItem></Info>')
    objects = f"<Object><Index>#x1A00</Index><Name>M</Name><Type>DT1A00</Type><BitSize>48</BitSize>{info}</Object>"
    esi = load_bytes(_doc('<TxPdo><Index>#x1A00</Index><Name>In</Name></TxPdo>', objects, datatypes), "f.xml")
    materialize(esi)
    o = esi.devices[0].dictionary.get(0x1A00)
    assert o is not None
    assert [(e.subindex, e.name, e.default) for e in o.entries.values()] == \
        [(0, "SubIndex 000", b"\x01"), (1, "Entry", bytes.fromhex("10000060"))]
