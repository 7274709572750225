"""Every corpus ESI loads, and per-file facts computed without the reader (plain lxml XPath, or the literal
numbers of corpus/SOURCES.md) match the model."""

from __future__ import annotations

from pathlib import Path

import pytest
from lxml import etree

from ecattool.errors import SelectionError
from ecattool.esi import load, load_device, materialize, select
from ecattool.esi.model import Direction
from ecattool.od.model import EcState, ObjectCode
from tests.conftest import corpus_files, corpus_path

ESI_FILES = corpus_files("esi/*.xml", "sii/*.xml")


def _ids(p: Path) -> str:
    return f"{p.parent.name}/{p.name}"


def test_corpus_is_present():
    assert len(list((corpus_path("esi")).glob("*.xml"))) == 33
    assert len(list((corpus_path("sii")).glob("*.xml"))) == 14


@pytest.mark.parametrize("path", ESI_FILES, ids=_ids)
def test_every_corpus_file_loads_with_independent_counts(path: Path):
    esi = load(path)
    tree = etree.parse(str(path))
    root = tree.getroot()
    assert esi.root == root.tag
    devices = root.xpath("/EtherCATInfo/Descriptions/Devices/Device")
    assert len(esi.devices) == len(devices)
    for dev, el in zip(esi.devices, devices):
        assert dev.type_name == el.findtext("Type").strip()
        assert len(dev.rx_pdos) == len(el.xpath("RxPdo"))
        assert len(dev.tx_pdos) == len(el.xpath("TxPdo"))
        assert len(dev.sync_managers) == len(el.xpath("Sm"))
        objs = el.xpath("Profile[1]/Dictionary/Objects/Object")
        assert len(dev.dictionary) == len({o.findtext("Index").strip().lower() for o in objs})
        assert sum(len(p.entries) for p in dev.rx_pdos) == len(el.xpath("RxPdo/Entry"))
        assert dev.location is not None and dev.location.line == el.sourceline
    mods = root.xpath("/EtherCATInfo/Descriptions/Modules/Module | /EtherCATModule/Modules/Module")
    assert len(esi.modules) >= len(mods)
    materialize(esi)  # building every dictionary never raises on a real file


# --- literal facts from corpus/SOURCES.md -------------------------------------------------------------
@pytest.mark.parametrize(
    "name, devices, objects, rx, tx",
    [
        ("beckhoff_EL1xxx.xml", 141, 1031, 192, 1240),
        ("elmo_Elmo_ECAT_00010420_V11.xml", 4, 350, 64, 72),
        ("copley_XE2_4.60.xml", 1, 661, 8, 8),  # RxPdo/TxPdo counted anywhere: device + modules
        ("ingenia_eve-xcr-e_esi.xml", 1, 527, 3, 3),
        ("beckhoff_AX5xxx.xml", 147, 0, 192, 192),
        ("itegva_E7x_Series.xml", 8, 0, 72, 72),
        ("synapticon_Somanet_CiA402-single.xml", 1, 20, 1, 1),
    ],
)
def test_sources_md_counts(name, devices, objects, rx, tx):
    esi = load(corpus_path("esi", name))
    assert len(esi.devices) == devices
    assert sum(len(d.dictionary) for d in esi.devices) + sum(len(m.dictionary) for m in esi.modules) == objects
    assert sum(len(d.rx_pdos) for d in esi.devices) + sum(len(m.rx_pdos) for m in esi.modules) == rx
    assert sum(len(d.tx_pdos) for d in esi.devices) + sum(len(m.tx_pdos) for m in esi.modules) == tx


def test_ethercatmodule_root_has_82_modules():
    esi = load(corpus_path("esi", "weidmueller_UR20_IO.xml"))
    assert esi.root == "EtherCATModule" and esi.devices == [] and len(esi.modules) == 82
    assert esi.vendor_id == 560
    assert sum(len(m.dictionary) for m in esi.modules) == 470  # SOURCES.md: objects=470
    assert sum(len(m.init_cmds) for m in esi.modules) == 164  # SOURCES.md: InitCmd=164


def test_ethercatdict_root_gives_a_dictionary():
    esi = load(corpus_path("esi", "beckhoff_AX5021-xxxx-0001_Dict.xml"))
    assert esi.root == "EtherCATDict" and esi.dictionary is not None
    assert len(esi.dictionary) == 119


# --- named objects, entries and data types -----------------------------------------------------------
@pytest.fixture(scope="module")
def el1xxx():
    return load(corpus_path("esi", "beckhoff_EL1xxx.xml"))


def test_bit_typed_pdo_entry(el1xxx):
    el1002 = el1xxx.devices[0]
    assert (el1002.type_name, el1002.product_code, el1002.revision) == ("EL1002", 0x03EA3052, 0)
    e = el1002.tx_pdos[0].entries[0]
    assert (e.index, e.subindex, e.bit_len, e.data_type, e.name) == (0x3101, 1, 1, "BOOL", "Input")
    assert el1002.tx_pdos[0].fixed and el1002.tx_pdos[0].mandatory and el1002.tx_pdos[0].sm == 0
    assert el1002.sync_managers[0].kind == "Inputs" and el1002.sync_managers[0].direction is Direction.TX
    assert el1002.eeprom.byte_size == 2048 and el1002.eeprom.config_data == bytes.fromhex("0101")
    assert el1002.ebus_current_ma == 110 and el1002.physics == "KK" and el1002.group_name.startswith("Digital Input")


def test_identity_record_and_defaults(el1xxx):
    dev = select(el1xxx, "EL1258:0x00100000")
    obj = dev.dictionary.get(0x1018)
    assert obj.name == "Identity" and obj.object_code is ObjectCode.RECORD and obj.type_name == "DT1018"
    vid = obj.entry(1)
    assert vid.name == "Vendor ID" and vid.datatype.name == "UDINT" and vid.bit_offset == 16
    assert vid.default == bytes.fromhex("02000000") and vid.default_value == 2
    assert dev.dictionary.get(0x1000).entry(0).default_value == 0x1389
    assert dev.dictionary.get(0x1008).entry(0).default_value == "EL1258"


def test_array_object(el1xxx):
    obj = select(el1xxx, "EL1258:0x00100000").dictionary.get(0x1011)
    assert obj.object_code is ObjectCode.ARRAY
    assert [(e.subindex, e.type_name, e.bit_size, e.bit_offset) for e in obj] == [(0, "USINT", 8, 0), (1, "UDINT", 32, 16)]
    assert obj.entry(0).default == b"\x01"


def test_enum_entry_with_flags(el1xxx):
    e = select(el1xxx, "EL1258:0x00100000").dictionary.entry(0x8000, 19)
    assert e.name == "Buffer overflow behaviour" and e.type_name == "DT0801EN16" and e.datatype.name == "UINT"
    assert e.enum == {0: "Lock buffer", 1: "Overwrite oldest event"}
    assert e.backup and e.setting and e.access.writable(EcState.PREOP)


def test_bool_entry_in_dictionary(el1xxx):
    dev = select(el1xxx, "EL1258:0x00100000")
    bools = [e for o in dev.dictionary for e in o if e.datatype is not None and e.datatype.is_bit_type]
    assert bools and all(e.bit_size == 1 for e in bools if e.datatype.name == "BOOL")


def test_multi_device_selection_policies(el1xxx):
    # EL1008 exists in three revisions (counted here with XPath, not with the reader)
    revs = sorted(int(t.get("RevisionNo")[2:], 16) for t in etree.parse(str(corpus_path("esi", "beckhoff_EL1xxx.xml")))
                  .xpath("//Device/Type[text()='EL1008']"))
    assert revs == [0x00100000, 0x00110000, 0x00120000]
    with pytest.raises(SelectionError, match=r"matches 3 devices.*EL1008.*0x00110000"):
        select(el1xxx, "EL1008")
    assert select(el1xxx, "EL1008", "newest").revision == 0x00120000
    assert select(el1xxx, "EL1008", "newest-not-newer").revision == 0x00120000
    assert select(el1xxx, "#x03f03052:#x00110000").revision == 0x00110000
    assert select(el1xxx, "0x03F03052:1114112").revision == 0x00110000  # decimal revision
    assert select(el1xxx, "66072658:0x00115000", "newest-not-newer").revision == 0x00110000
    assert select(el1xxx, "EL1008:0x00115000", "newest-not-newer").revision == 0x00110000
    with pytest.raises(SelectionError, match="0x00115000 exactly"):
        select(el1xxx, "0x03F03052:0x00115000", "exact")
    with pytest.raises(SelectionError, match="or older"):
        select(el1xxx, "0x03F03052:0x00000001", "newest-not-newer")
    with pytest.raises(SelectionError, match="candidates: \\[0\\] EL1002"):
        select(el1xxx, "0x12345678")
    assert select(el1xxx, "3") is el1xxx.devices[3]


def test_load_device_and_list_of_devices():
    path = corpus_path("esi", "elmo_Elmo_ECAT_00010420_V11.xml")
    esi = load(path)
    products = sorted({d.product_code for d in esi.devices})
    assert len(esi.devices) == 4 and len(products) == 2
    dev = load_device(path, f"0x{products[0]:X}", "newest")
    assert dev.product_code == products[0]
    assert select(esi.devices, f"{products[1]}", "newest").product_code == products[1]
    with pytest.raises(SelectionError, match="4 devices"):
        select(esi)


def test_modules_and_slots_etg2001():
    esi = load(corpus_path("esi", "etg_ETG2001_ModulesSlots_CiA402.xml"))
    tree = etree.parse(str(corpus_path("esi", "etg_ETG2001_ModulesSlots_CiA402.xml")))
    idents = [int(t.get("ModuleIdent")[2:], 16) for t in tree.xpath("//Modules/Module/Type")]
    assert [m.ident for m in esi.modules] == idents and len(idents) == 8
    dev = esi.devices[0]
    assert [s.name for s in dev.slots] == ["Axis 1", "Axis 2"]
    assert dev.slots[0].default_module == 0x100 and dev.slots[0].slot_index_increment == 0x800
    assert dev.slots[0].slot_pdo_increment == 16
    assert {m.ident for m in dev.modules} == set(idents)
    m110 = next(m for m in esi.modules if m.ident == 0x110)
    assert [p.index for p in m110.rx_pdos] == [0x1600, 0x1601, 0x1602]
    assert m110.rx_pdos[0].depend_on_slot and m110.rx_pdos[0].entries[0].depend_on_slot
    assert m110.tx_pdos[0].entries[0].index == 0x6064 and m110.tx_pdos[0].sm == 3
    assert [m.name for m in dev.dc_opmodes] == ["Synchron", "DC"]
    assert dev.dc_opmodes[1].assign_activate == 0x300


def test_inforeference_loads_referenced_modules():
    esi = load(corpus_path("esi", "weidmueller_UR20_FBC.xml"))
    assert esi.info_references == ["UR20-IO-Modules\\Weidmueller_UR20_IO.xml"]
    own = len(etree.parse(str(corpus_path("esi", "weidmueller_UR20_FBC.xml"))).xpath("//Descriptions/Modules/Module"))
    assert len(esi.modules) == own + 82
    assert any(d.modules for d in esi.devices)


def test_copley_init_cmds_and_odd_hex():
    esi = load(corpus_path("esi", "copley_XE2_4.60.xml"))
    materialize(esi)  # dictionaries are read on first use; their warnings arrive then
    odd = [w for w in esi.warnings if w.rule == "esi-hex-odd"]
    assert odd and odd[0].location.line is not None
    sync_type = esi.devices[0].dictionary.entry(0x1C32, 1)  # DefaultData "2" for a UINT
    assert sync_type.default == b"\x02\x00" and sync_type.default_value == 2
    cmds = [c for m in esi.modules for c in m.init_cmds]
    assert cmds and cmds[0].transitions == ["PS"] and cmds[0].index == 0x6060 and cmds[0].depend_on_slot
    assert esi.vendor_id == 171
    assert esi.devices[0].extra["ESC"] == "Reg0108=0 Reg0400=2498 Reg0410=1000 Reg0420=1000"  # kept, not dropped


def test_soe_init_cmds_and_missing_dictionary_file():
    esi = load(corpus_path("esi", "beckhoff_AX5xxx.xml"))
    dev = esi.devices[0]
    assert dev.mailbox.protocols == ["FoE", "SoE"]
    cmd = dev.mailbox.init_cmds[0]
    assert (cmd.protocol, cmd.transitions, cmd.index, cmd.data) == ("SoE", ["IP"], 32778, bytes.fromhex("FE7F000000000000"))
    assert any(w.rule == "esi-dictionaryfile-missing" for w in esi.warnings)
    assert len(dev.dictionary) == 0


def test_decimal_numbers_and_quirks():
    ing = load(corpus_path("esi", "ingenia_eve-xcr-e_esi.xml")).devices[0]
    assert (ing.product_code, ing.revision) == (46338049, 327700)
    mm = load(corpus_path("sii", "metalmusings_EaserCAT_3000.xml"))
    assert mm.vendor_id == 0xD0BED1D0
    pollen = load(corpus_path("sii", "pollen_Orbita2d.xml"))
    assert pollen.vendor_id == 0xF3F and any(w.rule == "esi-number-0x" for w in pollen.warnings)
    igh = load(corpus_path("esi", "weidmueller_UR20_FBC_from_IgH.xml"))
    assert igh.vendor_name == "" and any(w.rule == "esi-vendor-name" for w in igh.warnings)
    cu = load(corpus_path("esi", "beckhoff_CUxxxx.xml"))  # ISO-8859-1, Dictionary without DataTypes
    assert len(cu.devices) == 20 and sum(len(d.tx_pdos) for d in cu.devices) == 30


def test_alternative_sm_mapping(el1xxx):
    devs = [d for d in el1xxx.devices if d.alternative_sm_mappings]
    assert devs
    alt = devs[0].alternative_sm_mappings[0]
    assert alt.default and alt.name == "Standard (MDP 125)" and alt.sms[0][:2] == [0x1A00, 0x1A01]


def test_loaded_file_pickles_with_its_dictionaries():
    import pickle

    esi = load(corpus_path("esi", "etg_ETG2001_ModulesSlots_CiA402.xml"))
    back = pickle.loads(pickle.dumps(esi, protocol=pickle.HIGHEST_PROTOCOL))
    assert [d.type_name for d in back.devices] == ["Drive1"]
    assert back.devices[0].dictionary.indices() == esi.devices[0].dictionary.indices() and len(back.devices[0].dictionary) == 14
    assert back.devices[0].dictionary.entry(0x1018, 1) is not None
    assert len(back.modules) == 8


@pytest.mark.parametrize("path", corpus_files("esi/*.xml", "sii/*.xml", keep=lambda p: p.stat().st_size < 1_000_000),
                         ids=_ids)
def test_missing_object_findings_match_an_independent_count(path: Path):
    from ecattool.esi import check_structure

    expected = 0
    for dev in etree.parse(str(path)).xpath("/EtherCATInfo/Descriptions/Devices/Device"):
        objs = {int(i.strip()[2:], 16) if i.strip().startswith("#x") else int(i) for i in
                dev.xpath("Profile[1]/Dictionary/Objects/Object/Index/text()")}
        if not objs:
            continue
        sms = dev.xpath("Sm")
        for pdo in dev.xpath("RxPdo | TxPdo"):
            # issue 34 (docs/esi.md, "Virtual PDOs, partial entries and standard objects"): a virtual PDO off a
            # real SM maps ESC registers; dummies 1h-7h, TxPDO state/toggle, sync error and 10F4h are standard
            sm = pdo.get("Sm")
            on_virtual = sm is None or int(sm) >= len(sms) or sms[int(sm)].get("Virtual", "").lower() in ("1", "true")
            if pdo.get("Virtual", "").lower() in ("1", "true") and on_virtual:
                continue
            for entry in pdo.xpath("Entry"):
                idx = entry.findtext("Index")
                v = int(idx.strip()[2:], 16) if idx.strip().startswith("#x") else int(idx)
                sub_text = (entry.findtext("SubIndex") or "0").strip()
                sub = int(sub_text[2:], 16) if sub_text.startswith("#x") else int(sub_text)
                standard = (1 <= v <= 7 or (0x1800 <= v <= 0x1BFF and sub in (7, 9))
                            or (v in (0x1C32, 0x1C33) and sub == 0x20) or (v == 0x10F4 and 1 <= sub <= 0x12))
                if v and v not in objs and not standard:
                    expected += 1
    found = [f for f in check_structure(load(path)) if f.rule == "esi-pdo-object-missing" and "no such object" in f.message]
    assert len(found) == expected
