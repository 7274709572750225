"""What real vendor files do, one small document each: encodings, numbers, booleans, names, data types."""

from __future__ import annotations

import shutil

import pytest

from ecattool.errors import InputError, SelectionError
from ecattool.esi import check_structure, load, load_bytes, materialize, select
from ecattool.od.model import EcState, ObjectCode
from tests.conftest import corpus_path


def esi_doc(devices: str = "", datatypes: str = "", objects: str = "", vendor: str = "<Id>#x1A3</Id><Name>V</Name>",
            extra_device: str = "", head: str = '<?xml version="1.0" encoding="UTF-8"?>', modules: str = "") -> bytes:
    dictionary = ""
    if datatypes or objects:
        dictionary = (f"<Profile><ProfileNo>402</ProfileNo><Dictionary><DataTypes>{datatypes}</DataTypes>"
                      f"<Objects>{objects}</Objects></Dictionary></Profile>")
    if not devices:
        devices = (f'<Device Physics="YY"><Type ProductCode="#x10" RevisionNo="#x1">Drive</Type>'
                   f'<Name LcId="1031">Antrieb</Name><Name LcId="1033">Drive</Name>'
                   f'<Sm StartAddress="#x1000" DefaultSize="128" ControlByte="#x26" Enable="1">MBoxOut</Sm>'
                   f'<Sm StartAddress="#x1080" DefaultSize="128" ControlByte="#x22" Enable="1">MBoxIn</Sm>'
                   f'<Sm StartAddress="#x1100" ControlByte="#x64" Enable="1" MaxSize="8">Outputs</Sm>'
                   f'<Sm StartAddress="#x1400" ControlByte="#x20" Enable="#x1">Inputs</Sm>'
                   f"{extra_device}{dictionary}</Device>")
    mods = f"<Modules>{modules}</Modules>" if modules else ""
    return (f"{head}<EtherCATInfo Version=\"1.6\"><Vendor>{vendor}</Vendor><Descriptions><Groups/>"
            f"<Devices>{devices}</Devices>{mods}</Descriptions></EtherCATInfo>").encode("utf-8")


OBJ = "<Object><Index>{idx}</Index><Name>{name}</Name><Type>{type}</Type><BitSize>{bits}</BitSize>{rest}</Object>"


def obj(idx: str, name: str, type_: str, bits: int, rest: str = "") -> str:
    return OBJ.format(idx=idx, name=name, type=type_, bits=bits, rest=rest)


def test_lcid_1033_preferred_and_bom_and_crlf():
    data = b"\xef\xbb\xbf" + esi_doc().replace(b"><", b">\r\n<")
    dev = load_bytes(data, "bom.xml").devices[0]
    assert dev.name == "Drive" and dev.type_name == "Drive"
    assert dev.sync_managers[3].enable is True and dev.sync_managers[0].control_byte == 0x26


def test_iso_8859_1_declared_and_undeclared():
    doc = esi_doc(head='<?xml version="1.0" encoding="ISO-8859-1"?>').replace(b"<Name>V</Name>", "<Name>Müller</Name>".encode("latin-1"))
    assert load_bytes(doc, "latin1.xml").vendor_name == "Müller"
    undeclared = esi_doc(head="").replace(b"<Name>V</Name>", "<Name>Müller</Name>".encode("latin-1"))
    esi = load_bytes(undeclared, "undeclared.xml")
    assert esi.vendor_name == "Müller" and [w.rule for w in esi.warnings] == ["esi-encoding"]


def test_numbers_hexdec_0x_and_signed_sentinels():
    objects = obj("#x2000", "Offset", "DINT", 32,
                  "<Info><DefaultValue>#xFFFFFFFF</DefaultValue><MinValue>#x80000000</MinValue>"
                  "<MaxValue>2147483647</MaxValue></Info><Flags><Access>rw</Access></Flags>")
    objects += obj("0x2001", "Gain", "UINT", 16, "<Info><DefaultValue>1000</DefaultValue></Info>")
    esi = load_bytes(esi_doc(objects=objects), "n.xml")
    od = esi.devices[0].dictionary
    e = od.entry(0x2000, 0)
    assert e.default == b"\xff\xff\xff\xff" and e.default_value == -1
    assert (e.minimum, e.maximum) == (-(2**31), 2**31 - 1)
    assert od.entry(0x2001, 0).default_value == 1000
    w = [w for w in esi.warnings if w.rule == "esi-number-0x"]
    assert len(w) == 1 and w[0].location.line == 1


@pytest.mark.parametrize("text, expected", [("1", True), ("true", True), ("0", False), ("false", False), (" True ", True)])
def test_booleans(text, expected):
    dev = load_bytes(esi_doc(extra_device=f'<TxPdo Fixed="{text}" Sm="3"><Index>#x1A00</Index><Name>T</Name></TxPdo>'), "b.xml").devices[0]
    assert dev.tx_pdos[0].fixed is expected


def test_bad_boolean_is_an_error_with_line():
    data = esi_doc(extra_device='<TxPdo Fixed="yes"><Index>#x1A00</Index></TxPdo>').replace(b"<TxPdo", b"\n<TxPdo")
    with pytest.raises(InputError, match=r"b\.xml:2: Fixed 'yes' is not a boolean"):
        load_bytes(data, "b.xml")


def test_bad_number_is_an_error_with_line():
    data = esi_doc(extra_device="<TxPdo>\n<Index>#xZZ</Index></TxPdo>")
    with pytest.raises(InputError, match=r"x\.xml:2: .*'#xZZ' is not a number"):
        load_bytes(data, "x.xml")


def test_dictionary_without_datatypes_and_vendor_type_names():
    datatypes = ("<DataType><Name>DT0800</Name><BaseType>SINT</BaseType><BitSize>8</BitSize></DataType>"
                 "<DataType><Name>DT0801</Name><BitSize>16</BitSize></DataType>"
                 "<DataType><Name>DT0802</Name><BitSize>3</BitSize></DataType>"
                 "<DataType><Name>DT0803</Name><BaseType>DT0800</BaseType><BitSize>8</BitSize>"
                 "<EnumInfo><Text>Off</Text><Enum>0</Enum></EnumInfo><EnumInfo><Text>On</Text><Enum>#x1</Enum></EnumInfo></DataType>")
    objects = (obj("#x6060", "Modes of operation", "DT0800", 8, "<Flags><Access>rw</Access><PdoMapping>R</PdoMapping></Flags>")
               + obj("#x2002", "Word", "DT0801", 16) + obj("#x2003", "Three bits", "DT0802", 3)
               + obj("#x2004", "Switch", "DT0803", 8) + obj("#x2005", "Mystery", "VENDOR_X", 32)
               + obj("#x2006", "Count", "DINT32", 32))
    esi = load_bytes(esi_doc(datatypes=datatypes, objects=objects), "t.xml")
    od = esi.devices[0].dictionary
    e = od.entry(0x6060, 0)
    assert e.datatype.name == "SINT" and e.type_name == "DT0800" and e.rx_mappable and not e.tx_mappable
    assert od.entry(0x2002, 0).datatype.name == "UINT"
    assert od.entry(0x2003, 0).datatype.name == "BIT3" and od.entry(0x2003, 0).datatype.is_bit_type
    assert od.entry(0x2004, 0).enum == {0: "Off", 1: "On"} and od.entry(0x2004, 0).datatype.name == "SINT"
    assert od.entry(0x2005, 0).datatype is None
    assert od.entry(0x2006, 0).datatype.name == "DINT"
    assert [w.rule for w in esi.warnings] == ["esi-type-unknown"] and "VENDOR_X" in esi.warnings[0].message
    # a Dictionary without DataTypes (as in beckhoff_CUxxxx.xml) reads standard types
    bare = esi_doc(objects=obj("#x1000", "Device type", "UDINT", 32)).replace(b"<DataTypes></DataTypes>", b"")
    assert load_bytes(bare, "bare.xml").devices[0].dictionary.entry(0x1000, 0).datatype.name == "UDINT"


def test_records_arrays_and_arrays_of_records():
    datatypes = (
        "<DataType><Name>DT1600ARR</Name><BaseType>UDINT</BaseType><BitSize>64</BitSize>"
        "<ArrayInfo><LBound>1</LBound><Elements>2</Elements></ArrayInfo></DataType>"
        "<DataType><Name>DT1600</Name><BitSize>80</BitSize>"
        "<SubItem><SubIdx>0</SubIdx><Name>SubIndex 000</Name><Type>USINT</Type><BitSize>8</BitSize><BitOffs>0</BitOffs>"
        "<Flags><Access WriteRestrictions=\"PreOP\">rw</Access></Flags></SubItem>"
        "<SubItem><Name>Elements</Name><Type>DT1600ARR</Type><BitSize>64</BitSize><BitOffs>16</BitOffs>"
        "<Flags><Access WriteRestrictions=\"PreOP\">rw</Access></Flags></SubItem></DataType>"
        "<DataType><Name>DTPAIR</Name><BitSize>32</BitSize>"
        "<SubItem><SubIdx>1</SubIdx><Name>a</Name><Type>UINT</Type><BitSize>16</BitSize><BitOffs>0</BitOffs></SubItem>"
        "<SubItem><SubIdx>2</SubIdx><Name>b</Name><Type>UINT</Type><BitSize>16</BitSize><BitOffs>16</BitOffs></SubItem></DataType>"
        "<DataType><Name>DTPAIRARR</Name><BaseType>DTPAIR</BaseType><BitSize>96</BitSize>"
        "<ArrayInfo><LBound>1</LBound><Elements>3</Elements></ArrayInfo></DataType>"
        "<DataType><Name>DT3000</Name><BitSize>112</BitSize>"
        "<SubItem><SubIdx>0</SubIdx><Name>Count</Name><Type>USINT</Type><BitSize>8</BitSize><BitOffs>0</BitOffs></SubItem>"
        "<SubItem><Name>Elements</Name><Type>DTPAIRARR</Type><BitSize>96</BitSize><BitOffs>16</BitOffs></SubItem></DataType>"
        "<DataType><Name>DT4000</Name><BitSize>48</BitSize>"
        "<SubItem><SubIdx>0</SubIdx><Name>Count</Name><Type>USINT</Type><BitSize>8</BitSize><BitOffs>0</BitOffs></SubItem>"
        "<SubItem><SubIdx>1</SubIdx><Name>Pair</Name><Type>DTPAIR</Type><BitSize>32</BitSize><BitOffs>16</BitOffs></SubItem></DataType>"
    )
    objects = (
        obj("#x1600", "RxPDO map", "DT1600", 80,
            "<Info><SubItem><Name>SubIndex 000</Name><Info><DefaultData>02</DefaultData></Info></SubItem>"
            "<SubItem><Name>SubIndex 001</Name><Info><DefaultData>10004060</DefaultData></Info></SubItem>"
            "<SubItem><Name>SubIndex 002</Name><Info><DefaultValue>#x607A0020</DefaultValue></Info></SubItem></Info>")
        + obj("#x3000", "Pairs", "DT3000", 112) + obj("#x4000", "Nested", "DT4000", 48)
    )
    od = load_bytes(esi_doc(datatypes=datatypes, objects=objects), "r.xml").devices[0].dictionary
    m = od.get(0x1600)
    assert m.object_code is ObjectCode.ARRAY and [e.subindex for e in m] == [0, 1, 2]
    assert m.entry(1).default_value == 0x60400010 and m.entry(2).default_value == 0x607A0020
    assert [e.bit_offset for e in m] == [0, 16, 48]
    assert m.entry(1).access.writable(EcState.PREOP) and not m.entry(1).access.writable(EcState.OP)
    pairs = od.get(0x3000)  # an array of records: one octet-string element per record
    assert [(e.subindex, e.type_name, e.bit_size) for e in pairs] == [(0, "USINT", 8), (1, "DTPAIR", 32), (2, "DTPAIR", 32), (3, "DTPAIR", 32)]
    assert pairs.entry(2).datatype.kind.value == "octets" and pairs.entry(3).bit_offset == 16 + 64
    nested = od.get(0x4000)
    assert nested.object_code is ObjectCode.RECORD and nested.entry(1).datatype.bits == 32


def test_type_cycle_is_a_warning_not_a_crash():
    datatypes = ("<DataType><Name>A</Name><BaseType>B</BaseType><BitSize>8</BitSize></DataType>"
                 "<DataType><Name>B</Name><BaseType>A</BaseType><BitSize>8</BitSize></DataType>")
    esi = load_bytes(esi_doc(datatypes=datatypes, objects=obj("#x2000", "x", "A", 8)), "c.xml")
    assert esi.devices[0].dictionary.entry(0x2000, 0).datatype is None
    assert any(w.rule == "esi-type-cycle" for w in esi.warnings)


def test_odd_length_default_data_and_bad_object_skipped():
    objects = obj("#x2000", "x", "USINT", 8, "<Info><DefaultData>2</DefaultData></Info>") + obj("bogus", "y", "UINT", 16)
    esi = load_bytes(esi_doc(objects=objects), "o.xml")
    od = esi.devices[0].dictionary
    assert od.entry(0x2000, 0).default == b"\x02" and len(od) == 1
    assert {w.rule for w in esi.warnings} == {"esi-hex-odd", "esi-object-skipped"}


def test_vendor_without_name_and_missing_vendor():
    esi = load_bytes(esi_doc(vendor="<Id>2</Id>"), "v.xml")
    assert esi.vendor_id == 2 and esi.vendor_name == "" and esi.warnings[0].rule == "esi-vendor-name"


def test_not_an_esi_root():
    with pytest.raises(InputError, match="root element is <EtherCATConfig>"):
        load_bytes(b"<EtherCATConfig/>", "eni.xml")


def test_dictionary_file_resolved_relative_to_the_file(tmp_path):
    sub = tmp_path / "Beckhoff AX5xxx"
    sub.mkdir()
    shutil.copy(corpus_path("esi", "beckhoff_AX5021-xxxx-0001_Dict.xml"), sub / "Beckhoff AX5021-xxxx-0001 Dict.xml")
    dev = ('<Device><Type ProductCode="#x13ad6012" RevisionNo="#x1">AX5021</Type><Name>AX5021</Name>'
           "<Profile><DictionaryFile>Beckhoff AX5xxx\\Beckhoff AX5021-xxxx-0001 Dict.xml</DictionaryFile></Profile></Device>")
    path = tmp_path / "drive.xml"
    path.write_bytes(esi_doc(devices=dev))
    esi = load(path)
    assert len(esi.devices[0].dictionary) == 119
    missing = tmp_path / "other.xml"
    missing.write_bytes(esi_doc(devices=dev.replace("AX5021-xxxx", "AX9999-xxxx")))
    esi2 = load(missing)
    assert len(esi2.devices[0].dictionary) == 0 and esi2.warnings[0].rule == "esi-dictionaryfile-missing"


def test_device_and_module_init_cmds_dc_eeprom():
    extra = ("<Mailbox DataLinkLayer=\"1\"><CoE SdoInfo=\"1\" PdoAssign=\"true\" PdoConfig=\"1\" CompleteAccess=\"1\">"
             "<InitCmd Fixed=\"1\" CompleteAccess=\"true\"><Transition>PS</Transition><Transition>SO</Transition>"
             "<Index>#x1C12</Index><SubIndex>0</SubIndex><Data>0100001600</Data><Comment>assign</Comment></InitCmd>"
             "</CoE><FoE/></Mailbox>"
             "<Dc><OpMode><Name>DC</Name><Desc>DC sync</Desc><AssignActivate>#x300</AssignActivate>"
             "<CycleTimeSync0 Factor=\"1\">0</CycleTimeSync0><ShiftTimeSync0>-2000</ShiftTimeSync0></OpMode></Dc>"
             "<Eeprom AssignToPdi=\"0\"><ByteSize>2048</ByteSize><ConfigData>080E</ConfigData><BootStrap>00100001</BootStrap>"
             "<Category><CatNo>1</CatNo><DataUINT>#x1234</DataUINT></Category></Eeprom>")
    dev = load_bytes(esi_doc(extra_device=extra), "m.xml").devices[0]
    assert dev.has_coe and dev.mailbox.protocols == ["CoE", "FoE"] and dev.mailbox.data_link_layer
    assert dev.mailbox.coe.pdo_assign and dev.mailbox.coe.complete_access and not dev.mailbox.coe.pdo_upload
    c = dev.mailbox.init_cmds[0]
    assert (c.transitions, c.index, c.subindex, c.data, c.fixed, c.complete_access) == (
        ["PS", "SO"], 0x1C12, 0, bytes.fromhex("0100001600"), True, True)
    m = dev.dc_opmodes[0]
    assert (m.assign_activate, m.cycle_time_sync0_factor, m.shift_time_sync0) == (0x300, 1, -2000)
    assert dev.eeprom.categories[0].cat_no == 1 and dev.eeprom.categories[0].data == b"\x34\x12"
    assert dev.eeprom.bootstrap == bytes.fromhex("00100001")


def test_xml_revision_oracle_technosoft():
    # reference/technosoft/oracles.md A.1: firmware F515I → revision "515I" = 892417353 = 0x35313549
    devs = ('<Device><Type ProductCode="27314221" RevisionNo="892417353">iPOS4808 BX-CAT</Type><Name>a</Name></Device>'
            '<Device><Type ProductCode="27314221" RevisionNo="#x35313546">iPOS4808 BX-CAT</Type><Name>b</Name></Device>')
    esi = load_bytes(esi_doc(devices=devs), "ipos.xml")
    assert esi.devices[0].revision == int.from_bytes(b"515I", "big") == 0x35313549
    assert select(esi, "27314221:0x35313549") is select(esi, "#x1A0C82D:892417353") is esi.devices[0]
    # FoE-capable revision threshold (oracle A.2): 0x35313546 = "515F"
    assert select(esi, "27314221:892417350", "newest-not-newer").name == "b"
    assert select(esi, "iPOS4808 BX-CAT", "newest").name == "a"
    with pytest.raises(SelectionError, match="unknown selection policy"):
        select(esi, "27314221", "latest")


def test_structure_checks_each_rule():
    objects = obj("#x6040", "Controlword", "UINT", 16, "<Flags><Access>rw</Access><PdoMapping>R</PdoMapping></Flags>")
    pdos = ('<RxPdo Sm="2"><Index>#x1600</Index><Name>a</Name>'
            "<Entry><Index>#x6040</Index><SubIndex>0</SubIndex><BitLen>32</BitLen><DataType>UINT</DataType></Entry>"
            "<Entry><Index>#x607A</Index><SubIndex>0</SubIndex><BitLen>32</BitLen></Entry>"
            "<Entry><Index>#x0</Index><BitLen>8</BitLen></Entry></RxPdo>"
            '<RxPdo Sm="2"><Index>#x1600</Index><Name>dup</Name></RxPdo>'
            '<RxPdo Sm="3"><Index>#x1601</Index><Name>wrong sm</Name><Exclude>#x1699</Exclude></RxPdo>'
            '<TxPdo Sm="7"><Index>#x1A00</Index><Name>no sm</Name></TxPdo>')
    esi = load_bytes(esi_doc(objects=objects, extra_device=pdos), "s.xml")
    rules = sorted(f.rule for f in check_structure(esi))
    assert rules == sorted(["esi-pdo-bitlen", "esi-pdo-object-missing", "esi-pdo-duplicate", "esi-pdo-sm-direction",
                            "esi-exclude-missing", "esi-pdo-sm-missing", "esi-sm-size"])
    assert all(f.location is not None and f.location.line for f in check_structure(esi))


def test_materialize_counts_objects():
    esi = load(corpus_path("esi", "synapticon_Somanet_CiA402-single.xml"))
    assert materialize(esi) == 20


def test_absurd_sizes_are_bounded():
    datatypes = ("<DataType><Name>ARR</Name><BaseType>UDINT</BaseType><BitSize>64</BitSize>"
                 "<ArrayInfo><LBound>1</LBound><Elements>99999999999999999999</Elements></ArrayInfo></DataType>"
                 "<DataType><Name>REC</Name><BitSize>80</BitSize>"
                 "<SubItem><SubIdx>0</SubIdx><Name>n</Name><Type>USINT</Type><BitSize>8</BitSize><BitOffs>0</BitOffs></SubItem>"
                 "<SubItem><Name>Elements</Name><Type>ARR</Type><BitSize>64</BitSize><BitOffs>16</BitOffs></SubItem></DataType>")
    objects = (obj("#x1600", "m", "REC", 80)
               + obj("#x2000", "s", "STRING(99999999999)", 799999999992, "<Info><DefaultValue>abc</DefaultValue></Info>"))
    esi = load_bytes(esi_doc(datatypes=datatypes, objects=objects), "big.xml")
    od = esi.devices[0].dictionary
    # a 100-GB object is skipped with a located finding (a simulator would otherwise try to store it)
    assert len(od.get(0x1600).entries) == 256 and od.get(0x2000) is None
    assert {w.rule for w in esi.warnings} == {"esi-array-size", "esi-default-size", "esi-object-skipped"}


def test_unreadable_referenced_files_are_warnings(tmp_path):
    (tmp_path / "bad Dict.xml").write_bytes(b"<EtherCATDict><Dictionary>")
    (tmp_path / "mods.xml").write_bytes(b"<NotModules/>")
    dev = ('<Device><Type ProductCode="1" RevisionNo="1">D</Type>'
           "<Profile><DictionaryFile>bad Dict.xml</DictionaryFile></Profile></Device>")
    doc = esi_doc(devices=dev).replace(b'<EtherCATInfo Version="1.6">',
                                       b'<EtherCATInfo Version="1.6"><InfoReference>mods.xml</InfoReference>')
    path = tmp_path / "main.xml"
    path.write_bytes(doc)
    esi = load(path)
    assert len(esi.devices[0].dictionary) == 0 and esi.modules == []
    assert {w.rule for w in esi.warnings} == {"esi-inforeference-bad", "esi-dictionaryfile-bad"}


def test_names_prefer_1033_else_the_first():
    pdo = ('<TxPdo><Index>#x1A00</Index><Name LcId="1031">Eingänge</Name><Name LcId="1036">Entrées</Name>'
           '<Entry><Index>#x6000</Index><SubIndex>1</SubIndex><BitLen>1</BitLen><Name LcId="1031">Eingang</Name>'
           '<Name LcId="1033">Input</Name><DataType>BOOL</DataType></Entry></TxPdo>')
    objects = obj("#x6000", "x", "BOOL", 1).replace("<Name>x</Name>", '<Name>Plain</Name><Name LcId="1033">English</Name>')
    dev = load_bytes(esi_doc(extra_device=pdo, objects=objects), "n.xml").devices[0]
    assert dev.tx_pdos[0].name == "Eingänge" and dev.tx_pdos[0].entries[0].name == "Input"
    assert dev.dictionary.get(0x6000).name == "English"
