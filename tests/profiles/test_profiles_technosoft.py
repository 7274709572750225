"""Technosoft iPOS built-in family against the oracles of reference/technosoft/oracles.md (one test each)."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from ecattool import profiles
from ecattool.errors import SelectionError
from ecattool.esi.model import Direction, PdoEntry
from ecattool.od.model import EcState
from ecattool.profiles import technosoft
from ecattool.profiles.generic import supported_modes_of
from ecattool.profiles.technosoft import Firmware
from tests.profiles.profiles_helpers import mapping, value


@pytest.fixture(scope="module")
def dev():
    return profiles.load("technosoft-ipos")


@pytest.fixture(scope="module")
def old():
    return profiles.load("technosoft-ipos", revision="F515I")


# --- A. identity, revisions -----------------------------------------------------------------------------

def test_oracle_a1_f515i_revision_is_ascii_msb_first():
    d = profiles.load("technosoft-ipos", revision="F515I")
    assert d.revision == 892417353 == 0x35313549
    assert value(d, 0x1018, 3) == 892417353


def test_oracle_a2_foe_capable_revision_515f():
    assert Firmware.parse("F515F").revision == 892417350 == 0x35313546
    assert "FoE" in profiles.load("technosoft", revision="F515F").mailbox.protocols


def test_oracle_a3_eoe_capable_revision_515j():
    assert Firmware.parse("F515J").revision == 892417354 == 0x3531354A
    assert "EoE" in profiles.load("technosoft", revision="F515J").mailbox.protocols
    assert "EoE" not in profiles.load("technosoft", revision="F515I").mailbox.protocols
    assert 0x210E not in profiles.load("technosoft", revision="F515I").dictionary


def test_oracle_a4_printed_1018_revision_default_kept_in_data_and_replaced_by_firmware():
    from ecattool.profiles._common import load_data

    rec = next(o for o in load_data("technosoft")["objects"] if o["index"] == 0x1018)
    assert rec["entries"][3]["default"] == 0x30313030
    assert technosoft.ascii_msb_first(0x30313030) == "0100"
    assert value(profiles.load("technosoft", revision="F515K"), 0x1018, 3) == Firmware.parse("F515K").revision


def test_oracle_a6_product_code_from_label():
    assert technosoft.product_code_from_label("P027.214.E121") == 27214121


def test_oracle_a7_product_code_table():
    info = {p.name: p.product_code for p in technosoft.INFO.products}
    assert info["ipos360x-vx-cat"] == 28002021
    assert info["ipos4808-my-cat-sto"] == 27314121
    assert info["ipos4808-bx-cat-sto"] == 27314221
    d = profiles.load("technosoft", product="ipos4808-my-cat-sto")
    assert d.product_code == 27314121 == value(d, 0x1018, 2)


def test_oracle_a8_vendor_id(dev):
    assert dev.vendor_id == 0x1A3 == value(dev, 0x1018, 1)


def test_oracle_a9_serial_number_text():
    assert technosoft.serial_text(0x4C451158) == "LE1158"


def test_oracle_a10_tml_version_is_lsb_first(dev):
    assert technosoft.ascii_lsb_first(0x322E3156) == "V1.2"
    e = dev.dictionary.entry(0x2060, 0)
    assert e.type_name == "UDINT" and not e.access.writable()


# --- B. PDO mapping values ---------------------------------------------------------------------------------

@pytest.mark.parametrize("index,sub,bits,expected", [
    (0x6040, 0, 16, 0x60400010), (0x6060, 0, 8, 0x60600008), (0x6064, 0, 32, 0x60640020),
    (0x60FD, 0, 32, 0x60FD0020), (0x60C1, 1, 32, 0x60C10120), (0x60C1, 2, 32, 0x60C10220),
    (0x60FF, 0, 32, 0x60FF0020), (0x60FE, 1, 32, 0x60FE0120), (0x60FE, 2, 32, 0x60FE0220),
    (0x207D, 0, 8, 0x207D0008),
])
def test_oracle_b13_entry_encoding_matches_dictionary_sizes(dev, index, sub, bits, expected):
    assert PdoEntry(index, sub, bits).mapping_value == expected
    e = dev.dictionary.entry(index, sub)
    assert e.bit_size == bits
    assert e.pdo_mapping  # every example object is PDO-mappable


def test_oracle_b14_default_mappings(dev):
    assert mapping(dev, 0x1600) == [0x60400010, 0x607A0020]
    assert mapping(dev, 0x1601) == [0x60FE0120, 0x60FE0220]
    assert mapping(dev, 0x1602) == [0x60600008, 0x60710010]
    assert mapping(dev, 0x1603) == [0x60810020, 0x60830020]
    assert mapping(dev, 0x1A00) == [0x60410010, 0x60640020, 0x60770010]
    assert mapping(dev, 0x1A01) == [0x60F40020, 0x60FD0020]
    assert mapping(dev, 0x1A02) == [0x606C0020]
    assert mapping(dev, 0x1A03) == [0x60610008]
    sizes = {p.index: p.bit_size for p in (*dev.rx_pdos, *dev.tx_pdos)}
    assert sizes == {0x1600: 48, 0x1601: 64, 0x1602: 24, 0x1603: 64, 0x1A00: 64, 0x1A01: 64, 0x1A02: 32, 0x1A03: 8}


def test_oracle_b14_default_assignment_and_sm_types(dev):
    assert value(dev, 0x1C12, 0) == 1 and value(dev, 0x1C12, 1) == 0x1600
    assert value(dev, 0x1C13, 0) == 2 and [value(dev, 0x1C13, s) for s in (1, 2)] == [0x1A00, 0x1A01]
    assert [p.index for p in dev.rx_pdos if p.sm == 2] == [0x1600]
    assert [p.index for p in dev.tx_pdos if p.sm == 3] == [0x1A00, 0x1A01]
    # decision TS-2: the printed 3 for SM3 is a misprint of 4 (process data input)
    assert [value(dev, 0x1C00, s) for s in range(5)] == [4, 1, 2, 3, 4]
    assert dev.process_sm(Direction.RX).default_size == 6 and dev.process_sm(Direction.TX).default_size == 16


def test_oracle_b15_b16_rxpdo3_txpdo4_examples_fit_the_dictionary(dev):
    # §2.5: RPDO3 := 6040h + 6060h (24 bits); §2.6: TPDO4 := 6064h + 60FDh (64 bits)
    rx = [PdoEntry.from_mapping_value(v) for v in (0x60400010, 0x60600008)]
    tx = [PdoEntry.from_mapping_value(v) for v in (0x60640020, 0x60FD0020)]
    assert sum(e.bit_len for e in rx) == 24 and sum(e.bit_len for e in tx) == 64
    assert all(dev.dictionary.entry(e.index, e.subindex).rx_mappable for e in rx)
    assert all(dev.dictionary.entry(e.index, e.subindex).tx_mappable for e in tx)
    # the assignment slots those examples write exist, writable in Pre-Op only (decision TS-4)
    for idx, sub in ((0x1C12, 3), (0x1C13, 4), (0x1602, 2), (0x1A03, 2)):
        acc = dev.dictionary.entry(idx, sub).access
        assert acc.writable(EcState.PREOP) and not acc.writable(EcState.SAFEOP)


def test_oracle_b20_64_bit_examples(dev):
    od = dev.dictionary
    assert od.entry(0x60B8, 0).bit_size + od.entry(0x2092, 1).bit_size == 48
    assert od.entry(0x60B8, 0).rx_mappable and od.entry(0x2092, 1).rx_mappable
    assert od.entry(0x60B9, 0).bit_size + od.entry(0x60BA, 0).bit_size == 48
    assert od.entry(0x60B9, 0).tx_mappable and od.entry(0x60BA, 0).tx_mappable
    rules = profiles.rules_for(dev)
    assert rules.max_pdo_bits == 64 and rules.max_pdo_entries == 8


# --- C. modes ------------------------------------------------------------------------------------------------

def test_oracle_c25_modes_of_operation(dev):
    enum = dev.dictionary.entry(0x6060, 0).enum
    assert {1, 3, 4, 6, 7, 8, 9, 10, -1, -2} <= set(enum)
    assert set(profiles.rules_for(dev).supported_modes) == {1, 3, 4, 6, 7, 8, 9, 10, -1, -2}
    assert dev.dictionary.entry(0x6060, 0).encode(-1) == b"\xff"
    assert dev.mailbox.init_cmds[0].index == 0x6060 and dev.mailbox.init_cmds[0].data == b"\x08"


def test_oracle_c26_supported_drive_modes_6502(dev):
    assert value(dev, 0x6502) == 0x001C03E5
    assert supported_modes_of(dev.dictionary) == (1, 3, 6, 7, 8, 9, 10)


def test_profile_torque_mode_only_from_f515k():
    assert 4 not in profiles.rules_for(profiles.load("technosoft", revision="F515I")).supported_modes


# --- D/F. factor group and defaults ---------------------------------------------------------------------------

def test_oracle_d41_homing_and_encoder_defaults(dev):
    assert value(dev, 0x6099, 1) == 0x00010000 == value(dev, 0x6099, 2)
    assert value(dev, 0x609A) == 0x0000199A
    assert value(dev, 0x608F, 1) == 2000 and value(dev, 0x608F, 2) == 1


def test_oracle_f49_obsolete_factor_objects_before_f515k(old):
    od = old.dictionary
    assert [e.name for e in od.get(0x6093)][1:] == ["Numerator", "Divisor"]
    for idx in (0x6089, 0x608A, 0x608B, 0x608C, 0x608D, 0x608E, 0x206F, 0x2070, 0x2071):
        assert idx in od
    for idx in (0x608F, 0x6091, 0x6092, 0x6096, 0x60A2, 0x60A8, 0x210F, 0x2110):
        assert idx not in od
    assert od.entry(0x6093, 1).encode(4294967295) == b"\xff\xff\xff\xff"
    assert od.entry(0x6093, 2).encode(13493038) == (13493038).to_bytes(4, "little")
    assert profiles.rules_for(old).factor_group == "cia402-obsolete"


def test_oracle_f51_si_unit_defaults_cia402_2(dev):
    od = dev.dictionary
    assert value(dev, 0x60A8) == 0x00B50100
    assert [value(dev, i) for i in (0x60A9, 0x60AA, 0x60AB)] == [0, 0, 0]
    assert not od.entry(0x60A8, 0).pdo_mapping
    assert [e.name for e in od.get(0x6093)][1:] == ["Position internal units (IU)", "Position units (PU)"]
    for idx in (0x6089, 0x608A, 0x206F, 0x2070, 0x2071):
        assert idx not in od
    assert profiles.rules_for(dev).factor_group == "cia402-2"


# --- G/I. EEPROM objects and misc defaults -------------------------------------------------------------------

def test_oracle_g63_2064_default_0x84(dev):
    assert value(dev, 0x2064) == 0x84


def test_eeprom_access_objects_attributes(dev):
    od = dev.dictionary
    assert od.entry(0x2065, 0).access.text == "wo" and od.entry(0x2065, 0).rx_mappable
    assert od.entry(0x2067, 0).access.text == "wo"
    assert od.entry(0x2066, 0).access.text == "ro" and not od.entry(0x2066, 0).pdo_mapping
    assert od.entry(0x2069, 0).type_name == "UDINT" and od.entry(0x206A, 0).type_name == "UINT"
    assert value(dev, 0x2091) == 0 and value(dev, 0x2080) == 0


@pytest.mark.parametrize("index,sub,expected", [
    (0x2109, 0, 1000), (0x210A, 0, 3), (0x2082, 0, 0), (0x2073, 0, 7), (0x208E, 0, 0x0100),
    (0x201A, 0, 0x9E00), (0x2012, 0, 0x80000001), (0x607D, 1, -2147483648), (0x607D, 2, 2147483647),
    (0x60C2, 1, 1), (0x60C2, 2, -3), (0x2108, 2, 50), (0x605A, 0, 2), (0x605E, 0, 2),
])
def test_oracle_i77_defaults(dev, index, sub, expected):
    assert value(dev, index, sub) == expected


def test_oracle_i77_fa00g_option_codes():
    d = profiles.load("technosoft", revision="FA00G")
    assert value(d, 0x2114) == 32768 and value(d, 0x2113, 15) == 32768
    assert value(d, 0x2115) == 1
    assert 0x2113 not in profiles.load("technosoft", revision="F515K").dictionary


def test_2109_range_and_2006_range(dev):
    assert dev.dictionary.entry(0x2109, 0).maximum == 55000
    e = dev.dictionary.entry(0x2006, 0)
    assert (e.minimum, e.maximum) == (1, 10) and e.access.text == "wo"


# --- rules, decisions -------------------------------------------------------------------------------------------

def test_rules_dummies_only_in_rx(dev):
    r = profiles.rules_for(dev)
    assert r.dummy_indices == frozenset({1, 2, 3, 4, 5, 6, 7, 0x207D})
    assert r.dummies_in_rx and not r.dummies_in_tx
    assert r.rx_mapping_indices == (0x1600, 0x1601, 0x1602, 0x1603)
    assert r.tx_mapping_indices == (0x1A00, 0x1A01, 0x1A02, 0x1A03)
    assert r.max_assigned_rx == r.max_assigned_tx == 4
    e = dev.dictionary.entry(0x207D, 0)
    assert e.bit_size == 8 and e.rx_mappable


def test_decision_mapping_objects_have_eight_entries(dev):
    for idx in (*range(0x1600, 0x1604), *range(0x1A00, 0x1A04)):
        assert dev.dictionary.get(idx).max_subindex == 8
        assert dev.dictionary.entry(idx, 0).maximum == 8


def test_decision_untabulated_assignment_slots_hold_same_numbered_pdo(dev):
    assert [value(dev, 0x1C12, s) for s in range(1, 5)] == [0x1600, 0x1601, 0x1602, 0x1603]
    assert [value(dev, 0x1C13, s) for s in range(1, 5)] == [0x1A00, 0x1A01, 0x1A02, 0x1A03]
    assert dev.dictionary.entry(0x1C12, 0).access.writable(EcState.PREOP)


def test_decision_identity_sub0_is_4(dev):
    assert value(dev, 0x1018, 0) == 4


def test_decision_2001_mask_writable(dev):
    assert dev.dictionary.entry(0x2001, 0).access.writable()


def test_unknown_product_and_bad_revision_raise():
    with pytest.raises(SelectionError):
        profiles.load("technosoft", product="ipos9999")
    with pytest.raises(SelectionError):
        profiles.load("technosoft", revision="G999")


def test_revision_accepted_in_every_notation():
    for rev in ("F515K", "515K", "f515k", 0x3531354B, "0x3531354B", "892417355"):
        assert profiles.load("technosoft", revision=rev).revision == 0x3531354B


@given(st.sampled_from(["F510", "F511", "F515", "FA00", "FA02", "FA05"]), st.sampled_from("ABCDEFGHIJKLMNOPQRSTUVWXYZ"))
def test_firmware_revision_round_trip(line, letter):
    fw = Firmware.parse(line + letter)
    assert Firmware.parse(fw.revision) == fw
    assert technosoft.ascii_msb_first(fw.revision) == fw.name[1:]
    assert fw.has("cia402-2") != fw.has("cia402-obsolete")


@given(st.integers(min_value=0, max_value=2**32 - 1))
def test_firmware_parse_rejects_or_round_trips_any_int(n):
    try:
        fw = Firmware.parse(n)
    except SelectionError:
        return
    assert fw.revision == n


def test_oracle_c30_sync_test_config_range(dev):
    e = dev.dictionary.entry(0x2089, 0)
    assert (e.minimum, e.maximum) == (0, 7) and e.access.writable()


def test_oracle_g69_cam_scaling_defaults_are_fixed32_one(dev):
    assert value(dev, 0x206B) == 0x00010000 == value(dev, 0x206C)


def test_oracle_g70_egear_ratio_defaults(dev):
    assert (value(dev, 0x2013, 1), value(dev, 0x2013, 2)) == (1, 1)
    assert dev.dictionary.entry(0x2013, 1).type_name == "INT" and dev.dictionary.entry(0x2013, 2).type_name == "UINT"


def test_oracle_i75_eoe_ip_config_objects():
    d = profiles.load("technosoft", revision="F515J")
    assert [d.dictionary.entry(0x210E, s).type_name for s in (1, 2, 3)] == ["UDINT"] * 3
    assert d.dictionary.entry(0x210E, 1).encode(0x0C18A8C0) == bytes([192, 168, 24, 12])
    assert d.dictionary.entry(0x210D, 0).bit_size == 48


def test_ambiguity_3_device_type_kept_as_printed(dev):
    assert value(dev, 0x1000) == 0x00060192


def test_ambiguities_13_14_16_assignment_types_and_ranges(dev):
    od = dev.dictionary
    for idx in (0x1C12, 0x1C13):
        assert od.entry(idx, 0).type_name == "USINT" and (od.entry(idx, 0).minimum, od.entry(idx, 0).maximum) == (0, 4)
        assert all(od.entry(idx, s).type_name == "UINT" for s in range(1, 5))
    assert (od.entry(0x1C13, 1).minimum, od.entry(0x1C13, 1).maximum) == (0x1A00, 0x1A03)


def test_ambiguities_38_75_record_objects(dev):
    assert dev.dictionary.get(0x20A0).object_code.value == "RECORD"
    assert not dev.dictionary.entry(0x20A0, 0).pdo_mapping and dev.dictionary.entry(0x20A0, 2).tx_mappable
    fa = profiles.load("technosoft", revision="FA00G").dictionary
    assert fa.get(0x2113).object_code.value == "ARRAY" and fa.get(0x2113).max_subindex == 15


def test_ambiguities_54_71_72_ranges(dev):
    od = dev.dictionary
    assert od.entry(0x607E, 0).maximum == 255
    assert od.entry(0x2012, 0).maximum is None and od.entry(0x201E, 0).maximum is None


def test_ambiguity_78_6063_heading_name(dev):
    assert dev.dictionary.get(0x6063).name == "Position actual internal value"


# --- cross-check with Technosoft's own CANopen EDS of the iPOS (corpus/eds), read by ecattool.esi.eds -----------
#: where the EtherCAT manual prints another type than the EDS (docs/decisions.md, "Cross-check with the EDS")
_MANUAL_TYPE = {(0x2083, 0), (0x2084, 0), (0x2092, 1), (0x2092, 2), (0x2092, 3), (0x2092, 4), (0x206B, 0),
                (0x206C, 0), (0x2060, 0)}
#: where the EDS and the manual's tables disagree on PDO mapping; the profile follows the manual (decision TS-9):
#: (index, sub) -> mappable in the EDS
_MANUAL_MAPPING = {(0x2050, 0): True, (0x2066, 0): True, (0x2051, 0): False, (0x2058, 0): False,
                   (0x2086, 0): False, (0x6007, 0): False}


@pytest.fixture(scope="module")
def eds_device():
    from ecattool import esi
    from tests.conftest import corpus_path

    return esi.load_device(corpus_path("eds", "technosoft_iPOS.D.v1.04.eds"))


@pytest.mark.parametrize("revision", ["F515I", "F515K"])
def test_profile_agrees_with_technosoft_eds_on_types_writability_and_mapping(eds_device, revision):
    eds = {(o.index, e.subindex): e for o in eds_device.dictionary for e in o}
    assert len(eds) > 300  # the file was read
    od = profiles.load("technosoft-ipos", revision=revision).dictionary
    compared, wrong, mapping = 0, [], {}
    for (index, sub), x in sorted(eds.items()):
        e = od.entry(index, sub)
        if e is None or e.datatype is None or x.datatype is None:
            continue
        compared += 1
        if (index, sub) not in _MANUAL_TYPE and e.type_name != x.type_name:
            wrong.append(f"{index:04X}:{sub} type {e.type_name}, EDS {x.type_name}")
        if x.access.writable() is not e.access.writable():
            wrong.append(f"{index:04X}:{sub} access {e.access.text}, EDS {x.access.text}")
        if bool(x.pdo_mapping) is not bool(e.pdo_mapping):
            mapping[(index, sub)] = bool(x.pdo_mapping)
        elif x.pdo_mapping and not set(x.pdo_mapping) <= set(e.pdo_mapping):
            wrong.append(f"{index:04X}:{sub} mappable {e.pdo_mapping}, EDS {x.pdo_mapping} ({x.access.text})")
    assert compared > 240 and wrong == []
    assert mapping == _MANUAL_MAPPING


def test_eds_2050h_2066h_mappable_but_the_profile_follows_the_manual(eds_device):
    """Decision TS-9: 2050h is a protection setting and 2066h advances 2064h's address on every read (§17.2.3):
    the manual's "PDO mapping No" wins over the EDS's PDOMapping=1; map check refuses both."""
    from ecattool import pdo

    assert eds_device.dictionary.entry(0x2050, 0).pdo_mapping == "R"
    assert eds_device.dictionary.entry(0x2066, 0).pdo_mapping == "T"
    dev = profiles.load("technosoft-ipos")
    for rx, tx in (("0x1600=controlword,0x2050:00/16", None), (None, "0x1A00=statusword,0x2066:00/32")):
        findings = pdo.check(dev, pdo.Mapping.from_text(rx=rx, tx=tx, device=dev))
        assert [f.rule for f in findings] == ["PDO006"]
