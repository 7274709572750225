"""Control Techniques SM-EtherCAT built-in family against reference/controltechniques/oracles.md."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from ecattool import profiles
from ecattool.errors import SelectionError
from ecattool.esi.model import Direction, PdoEntry
from ecattool.profiles import controltechniques as ct
from tests.profiles.profiles_helpers import mapping, value


@pytest.fixture(scope="module")
def dev():
    return profiles.load("controltechniques")


# --- A. parameter addressing ------------------------------------------------------------------------------

def test_oracle_a1_a2_pr_20_21(dev):
    e = dev.dictionary.entry(0x2014, 0x15)
    assert e.bit_size == 32 and e.type_name == "DINT" and e.rx_mappable
    assert PdoEntry(0x2014, 0x15, e.bit_size).mapping_value == 0x20141520


def test_oracle_a3_pr_18_22_16_bit(dev):
    e = dev.dictionary.entry(0x2012, 0x16)
    assert PdoEntry(0x2012, 0x16, e.bit_size).mapping_value == 0x20121610


def test_oracle_a4_misprinted_entry_decodes_to_pr_20_22():
    pe = PdoEntry.from_mapping_value(0x20141620)
    assert (pe.index, pe.subindex, pe.bit_len) == (0x2014, 0x16, 32)


@pytest.mark.parametrize("index,bits,expected", [
    (0x6040, 16, 0x60400010), (0x6042, 16, 0x60420010), (0x6060, 8, 0x60600008), (0x6041, 16, 0x60410010),
    (0x6061, 8, 0x60610008), (0x6064, 32, 0x60640020), (0x6044, 16, 0x60440010),
])
def test_oracle_a5_standard_mapping_entries(dev, index, bits, expected):
    e = dev.dictionary.entry(index, 0)
    assert e.bit_size == bits and e.pdo_mapping
    assert PdoEntry(index, 0, bits).mapping_value == expected


def test_oracle_a6_gap_entry():
    assert PdoEntry(0, 0, 16).mapping_value == 0x00000010
    assert profiles.rules_for(profiles.load("ct")).gaps_allowed


def test_oracle_a7_parameter_zero_via_61_01(dev):
    e = dev.dictionary.entry(0x203D, 1)
    assert e is not None and e.access.writable() and e.maximum == 32767


def test_oracle_a8_sub0_is_highest_parameter(dev):
    for idx in (0x200F, 0x203C, 0x203D, 0x2014):
        obj = dev.dictionary.get(idx)
        assert value(dev, idx, 0) == max(obj.entries)


def test_oracle_a9_slot_menu_addresses(dev):
    assert value(dev, 0x200F, 3) == 0  # MM.03 station alias in slot 1
    assert value(dev, 0x200F, 1) == 421 == value(dev, 0x203C, 1)


# --- B. quick start, defaults --------------------------------------------------------------------------------

def test_oracle_b10_quick_start_objects_and_sizes(dev):
    od = dev.dictionary
    for idx, sub, size in ((0x1600, 0, 1), (0x1600, 3, 4), (0x1A00, 2, 4), (0x1A05, 2, 4), (0x1C12, 0, 1),
                           (0x1C12, 1, 2), (0x1C13, 2, 2)):
        assert od.entry(idx, sub).byte_size == size


def test_oracle_b11_quick_start_image_sizes(dev):
    od = dev.dictionary
    out = [0x60400010, 0x60420010, 0x20141520]
    assert sum(od.entry(v >> 16, (v >> 8) & 0xFF).bit_size for v in out) == 64
    tx = [0x60410010, 0x60640020, 0x20121610, 0x20141520]
    assert sum(od.entry(v >> 16, (v >> 8) & 0xFF).bit_size for v in tx) == 96


def test_oracle_b12_default_configuration(dev):
    assert (value(dev, 0x1C12, 0), value(dev, 0x1C12, 1)) == (1, 0x1605)
    assert (value(dev, 0x1C13, 0), value(dev, 0x1C13, 1)) == (1, 0x1A05)
    # decision CT-2: RxPDO6 carries vl_target_velocity (Table 6.6), not modes of operation (Table 6.9)
    assert mapping(dev, 0x1605) == [0x60400010, 0x60420010]
    assert mapping(dev, 0x1A05) == [0x60410010, 0x60440010]
    assert dev.process_sm(Direction.RX).default_size == 4 and dev.process_sm(Direction.TX).default_size == 4
    assert [p.index for p in dev.rx_pdos if p.sm == 2] == [0x1605]
    assert [p.index for p in dev.tx_pdos if p.sm == 3] == [0x1A05]


def test_oracle_b13_default_mapping_counts(dev):
    counts = {i: value(dev, i, 0) for i in (0x1600, 0x1601, 0x1605, 0x1615, 0x1A00, 0x1A01, 0x1A02, 0x1A05, 0x1A15)}
    assert counts == {0x1600: 1, 0x1601: 2, 0x1605: 2, 0x1615: 0, 0x1A00: 1, 0x1A01: 2, 0x1A02: 2, 0x1A05: 2, 0x1A15: 0}
    assert mapping(dev, 0x1601) == [0x60400010, 0x60600008]
    assert mapping(dev, 0x1A02) == [0x60410010, 0x60640020]


def test_oracle_b14_limits(dev):
    r = profiles.rules_for(dev)
    assert r.max_pdo_entries == 5 and r.max_assigned_rx == 2 and r.max_assigned_tx == 2
    assert (r.min_entry_bits, r.max_entry_bits) == (8, 32)
    for idx in (0x1600, 0x1601, 0x1605, 0x1615, 0x1A00, 0x1A01, 0x1A02, 0x1A05, 0x1A15):
        assert dev.dictionary.get(idx).max_subindex == 5
    assert r.rx_mapping_indices == (0x1600, 0x1601, 0x1605, 0x1615)
    assert r.tx_mapping_indices == (0x1A00, 0x1A01, 0x1A02, 0x1A05, 0x1A15)
    assert 0x1602 not in dev.dictionary and 0x1A03 not in dev.dictionary


# --- C. identity -------------------------------------------------------------------------------------------

def test_oracle_c15_printed_device_type_kept_in_data():
    from ecattool.profiles._common import load_data

    rec = next(o for o in load_data("controltechniques")["objects"] if o["index"] == 0x1000)
    assert rec["entries"][0]["default"] == 0x00030192


@pytest.mark.parametrize("drive,expected", [
    ("unidrive-sp", 0x00020192), ("digitax-st", 0x00020192), ("mentor-mp", 0x00010192),
])
def test_oracle_c16_device_type_by_drive(drive, expected):
    d = profiles.load("controltechniques", product=drive)
    assert value(d, 0x1000) == expected == profiles.rules_for(d).device_type


def test_oracle_c17_identity(dev):
    assert [value(dev, 0x1018, s) for s in range(3)] == [4, 0xF9, 0x1A5]
    d = profiles.load("controltechniques", revision="01.01.00")
    assert value(d, 0x1018, 3) == 0x00650000 == d.revision


def test_oracle_c18_version_parameters():
    d = profiles.load("controltechniques", revision="01.01.00")
    assert value(d, 0x200F, 2) == 101 and value(d, 0x200F, 51) == 0


# --- E/F. modes and profile objects ------------------------------------------------------------------------

def test_oracle_e28_modes(dev):
    e = dev.dictionary.entry(0x6060, 0)
    assert e.default_value == 2 and e.type_name == "USINT"
    assert set(e.enum) == {0, 2, 4, 6, 7, 8}


@pytest.mark.parametrize("drive,modes", [
    ("unidrive-sp", (2, 4, 6, 7, 8)), ("digitax-st", (2, 4, 6, 7, 8)), ("mentor-mp", (2, 4, 6, 7, 8)),
    ("commander-sk", (2, 4)), ("affinity", (2, 4)),
])
def test_supported_modes_per_drive_and_dc(drive, modes):
    r = profiles.rules_for(profiles.load("controltechniques", product=drive))
    assert r.supported_modes == modes
    assert r.dc_required_modes == tuple(m for m in (7, 8) if m in modes)


def test_oracle_e29_quick_stop_defaults(dev):
    assert value(dev, 0x605A) == 2 and value(dev, 0x6085) == 2


def test_oracle_f30_scaling_defaults_and_access(dev):
    od = dev.dictionary
    assert [value(dev, 0x608F, s) for s in (1, 2)] == [1, 1]
    assert [value(dev, 0x6091, s) for s in (1, 2)] == [1, 1] == [value(dev, 0x6092, s) for s in (1, 2)]
    assert not od.entry(0x608F, 1).access.writable()
    for idx in (0x608F, 0x6091, 0x6092):
        assert not od.entry(idx, 1).pdo_mapping and not od.entry(idx, 2).pdo_mapping
    r = profiles.rules_for(dev)
    assert r.read_only_indices == {0x608F} and r.sdo_only_indices == {0x608F, 0x6091, 0x6092}


def test_oracle_f32_f34_defaults(dev):
    assert (value(dev, 0x60FB, 1), value(dev, 0x60FB, 2)) == (2500, 1000)
    assert value(dev, 0x6080) == 3000 and value(dev, 0x6084) == 65536


def test_oracle_f35_f38_interpolation_period(dev):
    assert (value(dev, 0x60C2, 1), value(dev, 0x60C2, 2)) == (250, -6)
    e = dev.dictionary.entry(0x60C2, 2)
    assert (e.minimum, e.maximum) == (-6, 0)


def test_oracle_g41_vl_defaults(dev):
    assert value(dev, 0x6042) == 0
    assert [value(dev, 0x6046, s) for s in (1, 2)] == [0, 2147483647]
    assert [value(dev, 0x6047, s) for s in (1, 2, 3, 4)] == [0, 2147483647, 0, 2147483647]
    for idx in (0x6048, 0x6049, 0x604A):
        assert [value(dev, idx, s) for s in (1, 2)] == [1000, 2]
    assert [value(dev, 0x604B, s) for s in (1, 2)] == [1, 1] == [value(dev, 0x604C, s) for s in (1, 2)]


def test_oracle_i48_homing_source(dev):
    e = dev.dictionary.entry(0x2803, 1)
    assert e.default_value == 5 and (e.minimum, e.maximum) == (1, 8)


def test_oracle_j49_network_loss_defaults(dev):
    assert (value(dev, 0x2813, 1), value(dev, 0x2813, 2)) == (0, 0)


def test_shortcuts_are_pdo_only(dev):
    r = profiles.rules_for(dev)
    assert r.pdo_only_indices == {0x2830, 0x2831}
    assert dev.dictionary.entry(0x2830, 0).category == "pdo-only"
    assert dev.dictionary.entry(0x2831, 0).rx_mappable


def test_priority_rule_data(dev):
    r = profiles.rules_for(dev)
    assert r.priority_rule and r.slow_indices == {0x2046, 0x2047}
    assert dev.dictionary.entry(0x2046, 1).category == "slow"
    assert dev.dictionary.entry(0x2014, 0x15).category == ""
    # Commander SK has a single option slot: no SM-Applications module, so no slow registers
    assert 0x2046 not in profiles.load("controltechniques", product="commander-sk").dictionary


def test_decision_6041_read_only(dev):
    assert not dev.dictionary.entry(0x6041, 0).access.writable()


def test_listed_only_objects_exist_with_cia402_types(dev):
    assert dev.dictionary.entry(0x6065, 0).type_name == "UDINT"
    assert dev.dictionary.entry(0x605D, 0).type_name == "INT"


def test_mentor_needs_firmware_01_02():
    with pytest.raises(SelectionError):
        profiles.load("controltechniques", product="mentor-mp", revision="01.01.00")
    with pytest.raises(SelectionError):
        profiles.load("controltechniques", product="unidrive")
    with pytest.raises(SelectionError):
        profiles.load("controltechniques", revision="one.two")


@given(st.integers(0, 99), st.integers(0, 99), st.integers(0, 99))
def test_revision_round_trip(xx, yy, zz):
    value_, text = ct.parse_revision(f"{xx:02d}.{yy:02d}.{zz:02d}")
    assert ct.parse_revision(value_) == (value_, text)
    assert value_ >> 16 == xx * 100 + yy and value_ & 0xFFFF == zz


def test_oracle_j53_error_register(dev):
    e = dev.dictionary.entry(0x1001, 0)
    assert e.default_value == 0 and e.bit_size == 8 and not e.access.writable()
    assert value(dev, 0x603F) == 0


def test_rules_for_esi_device_infers_host_drive_from_its_name():
    from ecattool.esi.model import Device, Identity

    sk = Device(Identity(0xF9, 421, 0x00660000), "SM-EtherCAT Commander SK")
    assert profiles.rules_for(sk).supported_modes == (2, 4)
    unknown = Device(Identity(0xF9, 421, 0x00660000), "SM-EtherCAT")
    assert profiles.rules_for(unknown).supported_modes == (2, 4, 6, 7, 8)


def test_ambiguities_a17_a23_types(dev):
    assert dev.dictionary.entry(0x60C1, 1).type_name == "DINT"
    assert dev.dictionary.entry(0x6099, 0).type_name == "USINT"
