"""HDT Tomcat/DGFOX/NTT built-in family against reference/hdt/oracles.md (dictionary, defaults, mappings)."""

from __future__ import annotations

import pytest

from ecattool import profiles
from ecattool.errors import SelectionError
from ecattool.esi.model import Direction
from tests.profiles.profiles_helpers import mapping, value


@pytest.fixture(scope="module")
def dev():
    return profiles.load("hdt")


def test_oracle_1_device_type(dev):
    assert value(dev, 0x1000) == 0x00020192
    assert profiles.rules_for(dev).device_type == 0x00020192


def test_oracle_2_vendor_id(dev):
    assert dev.vendor_id == 0x289 == value(dev, 0x1018, 1)
    assert profiles.family_of(dev) == "hdt"


def test_oracle_3_product_code_decision(dev):
    # printed 00C0458h with a digit lost: decision HDT-2 reads it as 000C0458h
    assert dev.product_code == 0x000C0458 == value(dev, 0x1018, 2)
    assert {p.product_code for p in profiles.list_profiles()[1].products} == {0x000C0458}


@pytest.mark.parametrize("index,sub,expected", [
    (0x1005, 0, 0x80), (0x1014, 0, 0x81), (0x1200, 1, 0x601), (0x1200, 2, 0x581),
    (0x1400, 1, 0x201), (0x1401, 1, 0x301), (0x1402, 1, 0x401), (0x1403, 1, 0x501),
    (0x1800, 1, 0x181), (0x1801, 1, 0x281), (0x1802, 1, 0x381), (0x1803, 1, 0x481),
])
def test_oracle_4_cob_ids_for_node_1(dev, index, sub, expected):
    assert value(dev, index, sub) == expected


def test_oracle_6_node_guarding_defaults(dev):
    assert value(dev, 0x100C) == 100 and value(dev, 0x100D) == 2
    assert value(dev, 0x100C) * value(dev, 0x100D) == 200


def test_oracle_7_store_parameters_has_three_targets(dev):
    obj = dev.dictionary.get(0x1010)
    assert value(dev, 0x1010, 0) == 3 and sorted(obj.entries) == [0, 1, 2, 3]


def test_oracle_9_transmission_types_default_0(dev):
    for idx in (*range(0x1400, 0x1404), *range(0x1800, 0x1804)):
        assert value(dev, idx, 2) == 0


def test_oracle_10_default_rpdo_mappings(dev):
    assert mapping(dev, 0x1600) == [0x60400010, 0x60420010, 0x607C0020]
    assert mapping(dev, 0x1601) == [0x607A0020, 0x60810020]
    assert mapping(dev, 0x1602) == [0x60830020, 0x60840020]
    assert mapping(dev, 0x1603) == [0x60C10120]
    for idx in range(0x1600, 0x1604):
        n = value(dev, idx, 0)
        assert all(value(dev, idx, s) == 0 for s in range(n + 1, 9))


def test_oracle_11_default_tpdo_mappings(dev):
    assert mapping(dev, 0x1A00) == [0x60410010, 0x60610008, 0x10010008]
    assert mapping(dev, 0x1A01) == [0x60620020, 0x60640020]
    assert mapping(dev, 0x1A02) == [0x60430010, 0x60440010]
    assert mapping(dev, 0x1A03) == [0x60FD0020]


def test_oracle_12_13_default_pdo_sizes_and_decoding(dev):
    sizes = {p.index: p.bit_size for p in (*dev.rx_pdos, *dev.tx_pdos)}
    assert sizes == {0x1600: 64, 0x1601: 64, 0x1602: 64, 0x1603: 32, 0x1A00: 32, 0x1A01: 64, 0x1A02: 32, 0x1A03: 32}
    entry = dev.tx_pdos[0].entries[2]
    assert (entry.index, entry.subindex, entry.bit_len) == (0x1001, 0, 8)
    assert dev.rx_pdos[3].entries[0].subindex == 1 and dev.rx_pdos[3].entries[0].bit_len == 32


def test_oracle_14_max_8_entries_per_pdo(dev):
    for idx in (*range(0x1600, 0x1604), *range(0x1A00, 0x1A04)):
        assert dev.dictionary.get(idx).max_subindex == 8
        assert dev.dictionary.entry(idx, 0).maximum == 8
    assert profiles.rules_for(dev).max_pdo_entries == 8


def test_oracle_15_assignment_objects(dev):
    for idx in (0x1C12, 0x1C13):
        obj = dev.dictionary.get(idx)
        assert sorted(obj.entries) == [0, 1, 2, 3, 4]
        assert all(obj.entries[s].type_name == "UINT" for s in range(1, 5))
    # decision HDT-7: all four PDOs of each direction assigned by default
    assert [p.sm for p in dev.rx_pdos] == [2, 2, 2, 2] and [p.sm for p in dev.tx_pdos] == [3, 3, 3, 3]
    assert dev.process_sm(Direction.RX).default_size == 28 and dev.process_sm(Direction.TX).default_size == 20


def test_oracle_16_sync_types_supported(dev):
    assert value(dev, 0x1C32, 4) == 7


def test_decision_1001_mappable_in_tpdo(dev):
    assert dev.dictionary.entry(0x1001, 0).tx_mappable


def test_oracle_22_alarm_mode_default(dev):
    assert value(dev, 0x200F) == 0x025A


def test_oracle_26_modes_of_operation(dev):
    e = dev.dictionary.entry(0x6060, 0)
    assert e.default_value == 2 and set(e.enum) == {-2, -1, 1, 2, 3, 4, 6, 7, 8, 9, 10}
    assert set(profiles.rules_for(dev).supported_modes) == set(e.enum)


def test_oracle_27_option_code_end_states(dev):
    states = {(i, v): s for i, v, s in profiles.rules_for(dev).option_code_end_states}
    assert states[(0x605A, 5)] == states[(0x605A, 6)] == "QUICK_STOP_ACTIVE"
    assert states[(0x605D, 0)] == "SWITCH_ON_DISABLED" and states[(0x605D, 1)] == "OPERATION_ENABLED"
    assert states[(0x6007, 1)] == "SWITCH_ON_DISABLED" and states[(0x6007, 3)] == "OPERATION_ENABLED"


def test_oracle_28_stop_ramp_defaults(dev):
    assert value(dev, 0x604E) == 3000 and value(dev, 0x6050) == 1000 == value(dev, 0x6051)


def test_oracle_29_homing_method_range(dev):
    e = dev.dictionary.entry(0x6098, 0)
    assert (e.minimum, e.maximum) == (0, 35)


def test_oracle_30_31_vl_defaults(dev):
    assert (value(dev, 0x6046, 1), value(dev, 0x6046, 2)) == (0, 5000)
    assert (value(dev, 0x6048, 1), value(dev, 0x6048, 2)) == (1000, 1)


def test_oracle_32_factor_defaults(dev):
    assert (value(dev, 0x6093, 1), value(dev, 0x6093, 2)) == (65536, 65536)
    assert (value(dev, 0x6094, 1), value(dev, 0x6094, 2)) == (65536, 60)
    assert (value(dev, 0x6097, 1), value(dev, 0x6097, 2)) == (65536, 60)
    assert (value(dev, 0x604C, 1), value(dev, 0x604C, 2)) == (1, 1)
    assert [value(dev, i) for i in (0x6089, 0x608B, 0x608D, 0x607E)] == [0, 0, 0, 0]
    # decision HDT-8: the dimension indices keep their printed raw bytes
    assert [dev.dictionary.entry(i, 0).default for i in (0x608A, 0x608C, 0x608E)] == [b"\xac", b"\xa4", b"\xa3"]
    for idx in (0x6093, 0x6094, 0x6097, 0x604C):
        assert not dev.dictionary.entry(idx, 1).pdo_mapping


def test_oracle_33_counts_per_revolution(dev):
    assert profiles.rules_for(dev).counts_per_rev == 65536


def test_oracle_36_following_error_window_default(dev):
    assert value(dev, 0x6065) == 910


def test_oracle_42_interpolation_period_defaults(dev):
    assert (value(dev, 0x60C2, 1), value(dev, 0x60C2, 2)) == (2, -3)


def test_oracle_44_current_limit_default(dev):
    assert value(dev, 0x2006) == 2000


@pytest.mark.parametrize("index,expected", [
    (0x2001, 100), (0x2002, 200), (0x2033, 100), (0x203A, 20), (0x20B9, 1300), (0x205C, 1000), (0x240D, 200),
])
def test_oracle_45_fixed_point_raw_defaults(dev, index, expected):
    assert value(dev, index) == expected


def test_oracle_54_input_setting_default_is_uint8(dev):
    e = dev.dictionary.entry(0x201B, 0)
    assert e.default_value == 0x5A and e.bit_size == 8


def test_oracle_55_57_input_defaults(dev):
    assert value(dev, 0x2076) == 0xF
    assert [value(dev, i) for i in (0x2077, 0x2078, 0x2079, 0x2080, 0x2081)] == [0, 1, 2, 0, 0]


def test_oracle_56_limit_switch_bit_order(dev):
    assert profiles.rules_for(dev).limit_switch_bits == (1, 0)  # bit 0 = CW = positive


def test_ntt_only_objects():
    tomcat = profiles.load("hdt", product="tomcat")
    ntt = profiles.load("ntt")
    for idx in (0x2023, 0x203D, 0x2082, 0x2083, 0x2084):
        assert idx not in tomcat.dictionary and idx in ntt.dictionary
    assert ntt.extra["product"] == "ntt"
    with pytest.raises(SelectionError):
        profiles.load("hdt", product="lynx")


def test_hdt_rules(dev):
    r = profiles.rules_for(dev)
    assert r.rx_mapping_indices == (0x1600, 0x1601, 0x1602, 0x1603)
    assert r.tx_mapping_indices == (0x1A00, 0x1A01, 0x1A02, 0x1A03)
    assert r.max_assigned_rx == r.max_assigned_tx == 4 and r.factor_group == "cia402-obsolete"


# oracles 63-67: Caliper screenshots that agree with the printed defaults; 68: the table defaults where a
# screenshot shows a user setting instead (6007h, 6083h/6084h, 2011h, 60C2h:1, 2074h, 2406h, 2411h, 241Dh,
# 2047h, 20AAh/20ACh, 209Ch)
SCREEN_DEFAULTS = {
    (0x2000, 0): 3000, (0x2034, 0): 230, (0x2035, 0): 20, (0x2036, 0): 2, (0x204D, 0): 80, (0x2037, 0): 120,
    (0x2200, 0): 1, (0x2201, 0): 1, (0x2204, 0): 0, (0x220F, 0): 1024, (0x2210, 0): 0, (0x2212, 0): 100,
    (0x2206, 0): 5000, (0x2207, 0): 30000, (0x2208, 0): 65536, (0x2209, 0): 5000, (0x220A, 0): 30000,
    (0x220D, 0): 65536, (0x220B, 0): 1000, (0x220C, 0): 2000, (0x2017, 0): 10, (0x2018, 0): 200, (0x200C, 0): 0,
    (0x6098, 0): 0, (0x6099, 1): 100, (0x6099, 2): 10, (0x609A, 0): 1000, (0x2075, 0): 1000, (0x207B, 0): 0,
    (0x606D, 0): 20, (0x606E, 0): 500, (0x606F, 0): 20, (0x6070, 0): 500, (0x204C, 0): 0, (0x2050, 0): 20,
    (0x2051, 0): 200, (0x6088, 0): 0, (0x6087, 0): 1000, (0x6049, 1): 1000, (0x6049, 2): 1, (0x6066, 0): 200,
    (0x607D, 1): -2147483648, (0x607D, 2): 2147483647, (0x607C, 0): 0, (0x2091, 0): 0, (0x2019, 0): 65536,
    (0x201C, 0): 0, (0x6086, 0): 3, (0x6081, 0): 1000, (0x2021, 0): 100, (0x2005, 0): 5000, (0x2007, 0): 200,
    (0x200A, 0): 1200, (0x200B, 0): 200, (0x2009, 0): 300, (0x2418, 0): 120, (0x2419, 0): 20, (0x241A, 0): 2500,
    (0x241B, 0): 1000, (0x2403, 0): 400, (0x240E, 0): 250, (0x2410, 0): 8, (0x240C, 0): 20, (0x241C, 0): 180,
    (0x2405, 0): 6000, (0x240A, 0): 4500, (0x240B, 0): 60000, (0x2424, 0): 1000, (0x2425, 0): 1000,
    (0x2412, 0): 450, (0x2413, 0): 5, (0x2415, 0): 9, (0x2416, 0): 5, (0x2046, 0): 100, (0x2048, 0): 1,
    (0x2070, 0): 5, (0x203B, 0): 0, (0x203C, 0): 1, (0x203D, 0): 2, (0x2082, 0): 0, (0x2083, 0): 0,
    (0x2084, 0): 5, (0x200D, 0): 220, (0x605A, 0): 0, (0x605D, 0): 0, (0x605E, 0): 0,
    # oracle 68: table defaults, not the screenshots' user settings
    (0x6007, 0): 0, (0x6083, 0): 1000, (0x6084, 0): 1000, (0x2011, 0): 100000, (0x60C2, 1): 2, (0x2074, 0): 70,
    (0x2406, 0): 6000, (0x2411, 0): 5, (0x241D, 0): 3000, (0x2047, 0): 920, (0x20AA, 0): 200, (0x20AC, 0): 500,
    (0x209C, 0): 99,
}


@pytest.mark.parametrize("address", sorted(SCREEN_DEFAULTS), ids=lambda a: f"{a[0]:04X}:{a[1]}")
def test_oracle_63_68_screenshot_defaults(address):
    assert value(profiles.load("ntt"), *address) == SCREEN_DEFAULTS[address]


def test_oracle_23_i2t_time_default(dev):
    assert value(dev, 0x2037) == 120


def test_revision_is_an_optional_number():
    assert profiles.load("hdt", revision="0x00010002").revision == 0x00010002
    assert value(profiles.load("hdt", revision=5), 0x1018, 3) == 5
    with pytest.raises(SelectionError):
        profiles.load("hdt", revision="rev-b")


def test_ambiguity_6_emcy_cob_id_read_only(dev):
    assert not dev.dictionary.entry(0x1014, 0).access.writable()


def test_ambiguity_9_tpdo1_inhibit_and_event_timer(dev):
    assert dev.dictionary.entry(0x1800, 3) is not None and dev.dictionary.entry(0x1800, 5) is not None


def test_ambiguities_34_35_option_codes_mappable(dev):
    for idx in (0x6007, 0x605A, 0x605D):
        assert dev.dictionary.entry(idx, 0).rx_mappable
    assert dev.dictionary.entry(0x6007, 0).type_name == "UINT"


def test_ambiguities_53_55_57_types_and_access(dev):
    assert dev.dictionary.entry(0x60B9, 0).access.writable()  # printed rw
    assert dev.dictionary.entry(0x604C, 1).type_name == "DINT"
    assert not dev.dictionary.entry(0x6093, 0).access.writable()
