"""``sii build`` against every corpus ESI+SII pair.

Each pair lists every field where ecattool's image differs from the generator's, with the reason
ecattool's choice is right (docs/decisions.md, "SII images"). The test fails when a listed difference
disappears (the table is stale) or an unlisted one appears (a regression).
"""

from __future__ import annotations

import re

import pytest
from hypothesis import given

from ecattool.errors import InputError
from ecattool.esi import load as load_esi
from ecattool.sii import build, load
from ecattool.sii.builder import data_type_code, physical_port
from ecattool.sii.compare import diff
from tests.conftest import corpus_files, corpus_path

# reasons shared by several pairs
NO_FILL = "the generator writes only the used bytes; ecattool fills the EEPROM (ByteSize) with 0xFF like real dumps"
DC_ABSENT = "the generator wrote no DC category; ecattool writes the ESI's Dc/OpMode list"
DC_DESC = "real dumps (NI 9144) leave the DC description index 0; the generator added Desc strings"
SYNC0_DEFAULT = "an OpMode without CycleTimeSync0 gets Sync0 cycle factor 1, as in the NI 9144 dump and SOES"
STRINGS_PAD = "the pad byte of an odd STRINGS body is 0xFF in the NI 9144 dumps; the generator writes 0x00"
STRING_TABLE = "string table differs: ecattool de-duplicates and orders Type, GroupType, Group name, Name, DC, PDOs"
DLL_FLAG = "Mailbox@DataLinkLayer=true sets General flag bit 2 (mailbox DLL); the generator ignores it"
GROUP_NAME = "General byte 0x0E holds the Group Name string in real dumps; the generator writes 0 or the group idx"
PHYS_LAYER = "General byte 0x04 is not described by the ESI (reserved for writers); ecattool writes 0"
SOES_OLD_PORTS = "Physics=\"YY\" is two MII ports (0x11); this older SOES generator wrote 0 (the newer one writes 0x11)"
SIITOOL_ORDER = "siitool leaves the order string index (Type) at 0"
FEI_SIZE = ("EasyCAT's 4320-byte image overflows the 4096-byte EEPROM (no END marker); ecattool's de-duplicated "
            "string table fits, with room for the END marker")

CASES: dict[str, dict] = {
    "ni9144": {  # real device dump, rev 2 (3 TxPDOs)
        "diffs": {"general.physical_layer": PHYS_LAYER},
    },
    "ni9144_rev1": {
        "esi": "ni9144", "diffs": {"general.physical_layer": PHYS_LAYER},
    },
    "easycat_FEI_1": {"diffs": {
        "image.fill": "follows from the string table", "strings": STRING_TABLE, "strings.extra": STRINGS_PAD,
        "dc[0].sync0_cycle_factor": SYNC0_DEFAULT, "dc[*].desc": DC_DESC}},
    "easycat_FEI_2": {"diffs": {
        "image.fill": "follows from the string table", "strings": STRING_TABLE, "strings.extra": STRINGS_PAD,
        "dc[0].sync0_cycle_factor": SYNC0_DEFAULT, "dc[*].desc": DC_DESC}},
    "easycat_FEI_5": {"diffs": {
        "image.fill": "follows from the string table", "strings": STRING_TABLE,
        "dc[0].sync0_cycle_factor": SYNC0_DEFAULT, "dc[*].desc": DC_DESC}},
    "easycat_FEI_256": {"diffs": {
        "image.length": FEI_SIZE, "image.categories": FEI_SIZE,
        "image.fill": FEI_SIZE, "strings": STRING_TABLE, "strings.extra": STRINGS_PAD,
        "dc[0].sync0_cycle_factor": SYNC0_DEFAULT, "dc[*].desc": DC_DESC}},
    "soes_linux_lan9252demo": {"pdo": False, "diffs": {
        "general.physical_layer": PHYS_LAYER, "general.flags": DLL_FLAG, "general.group_name": GROUP_NAME,
        "general.physical_port": SOES_OLD_PORTS, "strings.extra": STRINGS_PAD,
        "general.coe_details": "the ESI says PdoUpload=false (0x03); the image was made from the project file "
                               "with PdoUpload on (0x13)"}},
    "soes_rtl_lwip_eoe_slave30": {"pdo": False, "diffs": {
        "general.flags": DLL_FLAG, "general.group_name": GROUP_NAME, "general.physical_port": SOES_OLD_PORTS}},
    "soes_rtl_xmc4_dynpdo": {"pdo": False, "diffs": {
        "general.physical_layer": PHYS_LAYER, "general.flags": DLL_FLAG, "general.group_name": GROUP_NAME,
        "general.physical_port": SOES_OLD_PORTS, "strings.extra": STRINGS_PAD}},
    "soes_tiesc_am335xice": {"pdo": False, "diffs": {
        "image.fill": "follows from the group name string", "strings": "the group name string is added (byte 0x0E)",
        "general.physical_layer": PHYS_LAYER, "general.flags": DLL_FLAG, "general.group_name": GROUP_NAME,
        "general.physical_port": SOES_OLD_PORTS, "strings.extra": STRINGS_PAD}},
    "soes_xmc4300_slavedemo": {"diffs": {
        # the .bin was generated from another project (RTL_ATO): it references string 6 of 2
        "image.length": NO_FILL, "image.fill": NO_FILL, "strings": STRING_TABLE,
        "general.group": "the image was made from another ESI (group 'ATO'); this ESI's GroupType is ATENSLAVE",
        "general.order": "the image has no order string; the ESI Type is 'ATO sample application'",
        "general.flags": DLL_FLAG, "general.group_name": GROUP_NAME,
        "dc[0].name": "the image names DC mode 0 'ATO' (another ESI); the ESI says DcOff",
        "dc[1].*": "the image has a second DC mode that this ESI does not define"}},
    "metalmusings_EaserCAT_2000": {"pdo": False, "diffs": {
        "header.serial": "the ESI has no serial number; the SOES generator wrote 1 from its project file",
        "image.categories": DC_ABSENT, "image.fill": NO_FILL + " (and the DC category)", "dc[*": DC_ABSENT,
        "strings": STRING_TABLE, "strings.extra": STRINGS_PAD,
        "general.image": "the image name 'IMGCBY' is not in the ESI", "general.flags": DLL_FLAG,
        "general.group_name": GROUP_NAME}},
    "metalmusings_EaserCAT_3000": {"pdo": False, "diffs": {
        "header.serial": "the ESI has no serial number; the SOES generator wrote 1 from its project file",
        "image.categories": DC_ABSENT, "image.fill": NO_FILL + " (and the DC category)", "dc[*": DC_ABSENT,
        "strings": STRING_TABLE, "general.image": "the image name 'IMGCBY' is not in the ESI",
        "general.flags": DLL_FLAG, "general.group_name": GROUP_NAME}},
    "asix_AX58100_EVB_DIO": {"pdo": False, "diffs": {
        "image.length": NO_FILL, "image.fill": NO_FILL, "image.categories": DC_ABSENT, "dc[*": DC_ABSENT,
        "strings": STRING_TABLE, "general.order": SIITOOL_ORDER,
        "sm[0].enable": "Sm OpOnly=\"1\": ecattool sets SyncM enable bit 3 (OP only); siitool does not",
        "sm[1].enable": "Sm OpOnly=\"1\": ecattool sets SyncM enable bit 3 (OP only); siitool does not"}},
    "pollen_Orbita2d": {"diffs": {
        "header.vendor_id": "the ESI writes <Id>0xF3F</Id> (0x, not #x); siitool read 0, ecattool reads 0xF3F",
        "image.length": NO_FILL, "image.fill": NO_FILL,
        "image.categories": "siitool writes one TXPDO and one DC category per PDO/OpMode and skips FMMUs it "
                            "does not know; ecattool writes one category of each kind",
        "fmmu[*]": "the ESI's FMMU texts (OrbitaIn…) are not FMMU usages; ecattool writes them as unused",
        "sm[2].type": "the ESI names SM2 'OrbitaIn'; its ControlByte #x64 makes it Outputs (ETG.2000), which "
                      "ecattool writes; siitool wrote unused",
        "sm[3].type": "the ESI names SM3 'OrbitaOut'; its ControlByte #x20 makes it Inputs (ETG.2000), which "
                      "ecattool writes; siitool wrote unused",
        "strings": STRING_TABLE, "strings.extra": STRINGS_PAD, "general.order": SIITOOL_ORDER,
        "general.flags": DLL_FLAG, "general.group_name": GROUP_NAME,
        "*.entry[*].data_type": "UINT8 is an 8-bit unsigned (USINT, 0x05); siitool wrote UINT (0x06)",
        "dc[0].sync0_cycle_factor": SYNC0_DEFAULT, "dc[*].desc": DC_DESC,
        "dc[1].shift_time0": "siitool's ShiftTime0 masking bug: 2000200000 = 0x7738A140, siitool wrote 0x7030A040",
        "dc[1].assign_activate": "siitool dropped AssignActivate #x300",
        "dc[1].sync0_cycle_factor": "CycleTimeSync0 Factor=\"1\"; siitool wrote 0"}},
}


def _match(field: str, pattern: str) -> bool:
    """``*`` matches anything; everything else (brackets included) literally."""
    return re.fullmatch(re.escape(pattern).replace(r"\*", ".*"), field) is not None


def _built(stem: str, case: dict):
    image = load(corpus_path("sii", f"{stem}.bin"))
    esi = load_esi(corpus_path("sii", f"{case.get('esi', stem)}.xml"))
    h = image.header
    device = next(d for d in esi.devices if (d.product_code, d.revision) == (h.product_code, h.revision)) \
        if len(esi.devices) > 1 else esi.devices[0]
    return image, build(device, pdo_categories=case.get("pdo", True), size=case.get("size"))


@pytest.mark.parametrize("stem", sorted(CASES))
def test_build_matches_corpus_except_named_fields(stem: str) -> None:
    case = CASES[stem]
    image, built = _built(stem, case)
    fields = [d.field for d in diff(image, built)]
    unexplained = [f for f in fields if not any(_match(f, p) for p in case["diffs"])]
    assert not unexplained, f"differences without a reason: {unexplained}"
    stale = [p for p in case["diffs"] if not any(_match(f, p) for f in fields)]
    assert not stale, f"listed differences that no longer occur: {stale}"


def test_ni9144_dumps_reproduced_byte_for_byte_except_general_byte_4() -> None:
    for stem in ("ni9144", "ni9144_rev1"):
        image, built = _built(stem, CASES[stem])
        a, b = image.to_bytes(), built.to_bytes()
        assert len(a) == len(b) == 2048
        general_offset = a.index(bytes([30, 0, 16, 0])) + 4
        assert [i for i in range(len(a)) if a[i] != b[i]] == [general_offset + 4]


def test_fei_256_fits_its_declared_eeprom_when_strings_are_shared() -> None:
    from ecattool.sii import check

    esi = load_esi(corpus_path("sii", "easycat_FEI_256.xml"))
    img = build(esi.devices[0])
    assert len(img.to_bytes()) == 4096 and img.end_marker
    assert not [f for f in check(img) if f.severity.value == "error"]
    with pytest.raises(InputError, match="the EEPROM holds 2048"):
        build(esi.devices[0], size=2048)


def test_no_pdo_categories_fits_lan9252_in_256_bytes() -> None:
    esi = load_esi(corpus_path("sii", "soes_linux_lan9252demo.xml"))
    with pytest.raises(InputError, match="holds 256"):
        build(esi.devices[0])
    assert len(build(esi.devices[0], pdo_categories=False).to_bytes()) == 256


def test_pollen_vendor_id_is_read_despite_0x_syntax() -> None:
    esi = load_esi(corpus_path("sii", "pollen_Orbita2d.xml"))
    assert build(esi.devices[0]).header.vendor_id == 0xF3F


def test_size_option_overrides_byte_size_and_fills_with_ff() -> None:
    esi = load_esi(corpus_path("sii", "ni9144.xml"))
    img = build(esi.devices[1], size=4096)
    raw = img.to_bytes()
    assert len(raw) == 4096 and img.header.size_word == 31 and raw.endswith(b"\xff" * 1024)
    with pytest.raises(InputError, match="multiple of 128"):
        build(esi.devices[1], size=1000)


def test_physics_letters_map_to_port_codes() -> None:
    assert physical_port("YY") == 0x11
    assert physical_port("YYKK") == 0x3311  # K = EBUS (3), as in the EK1100 dump 0x0131 order per port
    assert physical_port("KK ") == 0x33
    assert physical_port("H") == 0x4


def test_data_type_codes() -> None:
    assert data_type_code("BOOL") == 0x01
    assert data_type_code("UINT8") == 0x05
    assert data_type_code("WORD") == 0x06  # NI 9144 dump
    assert data_type_code("ULINT") == 0x1B
    assert data_type_code("BIT2") == 0x31
    assert data_type_code("DT0800") == 0


def test_build_of_an_ebus_device_from_a_large_esi() -> None:
    from ecattool.esi import select

    esi = load_esi(corpus_path("esi", "beckhoff_EL1xxx.xml"))
    dev = select(esi, "EL1008", "newest")
    img = build(dev)
    g = img.general
    assert g is not None and img.string(g.order_idx) == "EL1008"
    assert g.physical_port & 0xF == 3  # Physics "KK": E-bus
    inputs_sm = [i for i, s in enumerate(img.sync_managers) if s.type == 4]
    assert img.tx_pdos and inputs_sm and all(p.sm in inputs_sm for p in img.tx_pdos if p.sm != 0xFF)
    assert img.crc_ok


def _device(**kw):
    from ecattool.esi.model import Device, Identity, SyncManager

    dev = Device(Identity(0xE0000001, 0x10, 2), "T", "Test device", physics="KK",
                 sync_managers=[SyncManager(0, "Outputs", 0x1000, 2, control_byte=0x64),
                                SyncManager(1, "Inputs", 0x1100, 2, control_byte=0x20)], **kw)
    return dev


def test_vendor_categories_come_first_and_ebus_current_is_signed() -> None:
    from ecattool.esi.model import Eeprom, EepromCategory
    from ecattool.sii import RawCategory

    dev = _device(eeprom=Eeprom(byte_size=256, categories=[EepromCategory(0x0800, b"\x01\x02\x03\x04")]),
                  ebus_current_ma=-2000)
    img = build(dev)
    assert isinstance(img.categories[0], RawCategory) and img.categories[0].type == 0x0800
    assert img.categories[0].data == b"\x01\x02\x03\x04"
    assert img.general is not None and img.general.current_on_ebus == -2000 and img.general.physical_port == 0x33
    assert load_bytes_roundtrip(img)


def load_bytes_roundtrip(img) -> bool:
    from ecattool.sii import parse

    return parse(img.to_bytes()) == img


def test_raw_eeprom_data_is_used_as_is() -> None:
    from ecattool.esi.model import Eeprom

    raw = corpus_path("sii", "ni9144.bin").read_bytes()
    assert build(_device(eeprom=Eeprom(data=raw))).to_bytes() == raw


def test_check_against_reports_a_sync_manager_mismatch() -> None:
    from ecattool.sii import check_against

    dev = _device()
    img = build(dev)
    img.sync_managers[1].start = 0x1200
    findings = check_against(dev, img)
    assert [(f.rule, f.data["field"]) for f in findings] == [("sii.esi.sm", "sm[1].start")]


ESI_WITH_CATEGORIES = b"""<?xml version="1.0"?>
<EtherCATInfo><Vendor><Id>#x1234</Id><Name>V</Name></Vendor><Descriptions><Groups/><Devices>
<Device Physics="YY"><Type ProductCode="#x7" RevisionNo="1">CAT</Type><Name>Cat device</Name>
<Eeprom><ByteSize>512</ByteSize><ConfigData>0800</ConfigData>
<Category><CatNo>#x0800</CatNo><Data>0102030405</Data></Category>
<Category><CatNo>1</CatNo><DataString>abc</DataString></Category>
<Category><CatNo>3</CatNo><DataUDINT>#x11223344</DataUDINT></Category>
</Eeprom></Device></Devices></Descriptions></EtherCATInfo>"""


def test_esi_eeprom_categories_end_to_end() -> None:
    from ecattool.esi import load_bytes
    from ecattool.sii import RawCategory, parse

    dev = load_bytes(ESI_WITH_CATEGORIES, "cat.xml").devices[0]
    img = parse(build(dev).to_bytes())
    raws = [(c.type, c.data) for c in img.categories if isinstance(c, RawCategory)]
    assert raws == [(0x0800, b"\x01\x02\x03\x04\x05\x00"), (1, b"abc\x00"), (3, b"\x44\x33\x22\x11")]
    assert img.header.pdi_control == 0x0008 and img.header.size_word == 3 and img.crc_ok


def test_esi_eeprom_data_end_to_end() -> None:
    from ecattool.esi import load_bytes

    raw = corpus_path("sii", "soes_linux_lan9252demo.bin").read_bytes()
    xml = ESI_WITH_CATEGORIES.replace(b"<ByteSize>512</ByteSize>", b"<Data>" + raw.hex().encode() + b"</Data>")
    dev = load_bytes(xml, "data.xml").devices[0]
    assert build(dev).to_bytes() == raw


def test_elmo_boot_device_general_and_syncm_from_the_esi_replace_the_generated_ones() -> None:
    from ecattool.sii import GeneralCategory, SyncMCategory, parse

    esi = load_esi(corpus_path("esi", "elmo_Elmo_ECAT_00010420_V11.xml"))
    boot = next(d for d in esi.devices if d.eeprom and any(c.cat_no == 30 for c in d.eeprom.categories))
    img = build(boot)
    assert [type(c).__name__ for c in img.categories[:2]] == ["GeneralCategory", "SyncMCategory"]
    assert sum(isinstance(c, GeneralCategory) for c in img.categories) == 1
    assert sum(isinstance(c, SyncMCategory) for c in img.categories) == 1
    assert parse(img.to_bytes()) == img


ESI_FILES = corpus_files("esi/*.xml", "sii/*.xml", form="name")


@pytest.mark.parametrize("name", ESI_FILES)
def test_every_corpus_device_builds_round_trips_and_checks_clean(name: str) -> None:
    from ecattool.findings import has_errors
    from ecattool.sii import check, check_against, parse

    path = corpus_path("esi", name) if corpus_path("esi").joinpath(name).exists() else corpus_path("sii", name)
    for dev in load_esi(path).devices:
        try:
            img = build(dev)
        except InputError as exc:  # more PDOs than Eeprom/ByteSize holds (EL1259, EM7004…)
            assert "needs" in exc.message
            img = build(dev, pdo_categories=False)
        assert parse(img.to_bytes()) == img
        if dev.eeprom and any(c.cat_no == 41 for c in dev.eeprom.categories):
            # Elmo's boot devices bring their own one-SM SYNCM category while their PDOs name SM2/SM3:
            # the image says what the ESI says, and check reports the inconsistency
            assert {f.rule for f in check(img) if f.severity.value == "error"} <= {"sii.pdo"}
            continue
        assert not has_errors(check(img)), dev.type_name
        assert not has_errors(check_against(dev, img)), dev.type_name


def _devices():
    from hypothesis import strategies as st

    from ecattool.esi.model import (CoeDetails, DcOpMode, Device, Direction, Eeprom, Fmmu, Identity, Mailbox, Pdo,
                                    PdoEntry, SyncManager)

    u16, u32 = st.integers(0, 0xFFFF), st.integers(0, 0xFFFFFFFF)
    text = st.text(max_size=40)
    kinds = st.sampled_from(["MBoxOut", "MBoxIn", "Outputs", "Inputs", "", "Other"])
    sms = st.lists(st.builds(SyncManager, st.integers(0, 7), kinds, u16, st.none() | u16, control_byte=st.integers(0, 255),
                             enable=st.booleans(), virtual=st.booleans()), max_size=5)
    entries = st.lists(st.builds(PdoEntry, u16, st.integers(0, 255), st.integers(0, 64), text,
                                 st.sampled_from(["BOOL", "UINT", "WORD", "REAL", "DT0800", "BIT2", ""])), max_size=6)
    pdos = lambda d: st.lists(st.builds(Pdo, st.just(d), u16, text, entries, st.none() | st.integers(0, 7),  # noqa: E731
                                        st.booleans(), st.booleans()), max_size=4)
    dcs = st.lists(st.builds(DcOpMode, text, text, u16, st.none() | u32, st.none() | st.integers(-5, 5),
                             st.none() | st.integers(-2 ** 31, 2 ** 31 - 1)), max_size=3)
    mbx = st.none() | st.builds(Mailbox, st.lists(st.sampled_from(["AoE", "EoE", "CoE", "FoE", "SoE", "VoE"]),
                                                  unique=True), st.none() | st.builds(CoeDetails, *[st.booleans()] * 5),
                                st.booleans())
    eeprom = st.none() | st.builds(Eeprom, st.sampled_from([None, 2048, 4096, 65536]),
                                   st.none() | st.binary(max_size=16), st.none() | st.binary(max_size=8))
    return st.builds(Device, st.builds(Identity, u32, u32, u32), text, text, text, text,
                     st.text("YKH ", max_size=4), sync_managers=sms,
                     fmmus=st.lists(st.builds(Fmmu, st.sampled_from(["Outputs", "Inputs", "MBoxState", "x"]),
                                              st.none() | st.integers(0, 7)), max_size=4),
                     rx_pdos=pdos(Direction.RX), tx_pdos=pdos(Direction.TX), mailbox=mbx, dc_opmodes=dcs,
                     eeprom=eeprom, ebus_current_ma=st.none() | st.integers(-40000, 40000))


@given(_devices())
def test_random_devices_build_or_refuse_and_round_trip(dev) -> None:
    from ecattool.sii import check, parse

    try:
        img = build(dev)
    except InputError:
        return
    assert parse(img.to_bytes()) == img and img.crc_ok
    check(img)
