"""rules_for / complete_generic on the corpus ESIs (real vendor files) and on each built-in profile."""

from __future__ import annotations

import pytest

from ecattool import esi, profiles
from ecattool.esi.model import Device, Direction, Identity, Mailbox, CoeDetails, Pdo, PdoEntry, SyncManager
from ecattool.od.model import EcState
from ecattool.profiles.generic import supported_modes_of
from tests.conftest import corpus_path

DRIVES = {
    "elmo": "elmo_Elmo_ECAT_00010420_V11.xml",
    "copley": "copley_XE2_4.60.xml",
    "ingenia": "ingenia_eve-xcr-e_esi.xml",
    "inovance": "inovance_SV660_EOE_1Axis_V9.12.xml",
    "synapticon": "synapticon_Somanet_CiA402-single.xml",
    "beckhoff-ax2000": "beckhoff_AX2xxx.xml",
    "etg2001": "etg_ETG2001_ModulesSlots_CiA402.xml",
}


@pytest.fixture(scope="module")
def devices() -> dict[str, Device]:
    out = {}
    for key, name in DRIVES.items():
        out[key] = esi.load(corpus_path("esi", name)).devices[0]
    return out


@pytest.mark.parametrize("key", sorted(DRIVES))
def test_complete_generic_has_communication_objects(devices, key):
    dev = devices[key]
    done = profiles.complete_generic(dev)
    od = done.dictionary
    for idx in (0x1000, 0x1018, 0x1C00, 0x1C12, 0x1C13):
        assert idx in od, f"{key}: 0x{idx:04X} missing"
    vendor = od.entry(0x1018, 1).default_value
    assert vendor is not None  # the ESI's value where it gives one (ETG.2001 prints 2), else the identity's
    if 0x1018 not in dev.dictionary or dev.dictionary.entry(0x1018, 1).default is None:
        assert vendor == dev.vendor_id
    for direction in (Direction.RX, Direction.TX):
        assign = direction.assign_index
        n = od.entry(assign, 0).default_value
        assigned = [od.entry(assign, s).default_value for s in range(1, n + 1)]
        for index in assigned:
            pdo = done.pdo(index)
            assert pdo is not None and index in od, f"{key}: assigned 0x{index:04X} has no mapping object"
            count = od.entry(index, 0).default_value
            if count is not None:
                assert count == len(pdo.entries)
            for e in pdo.entries:
                assert e.is_gap or od.entry(e.index, e.subindex) is not None
    # the input is untouched
    assert len(dev.dictionary) <= len(od)


def test_complete_generic_does_not_modify_its_input(devices):
    dev = devices["elmo"]
    before = sorted(dev.dictionary.indices())
    profiles.complete_generic(dev)
    assert sorted(dev.dictionary.indices()) == before


def test_complete_generic_keeps_esi_objects(devices):
    dev = devices["ingenia"]
    done = profiles.complete_generic(dev)
    for idx in dev.dictionary.indices():
        assert done.dictionary.get(idx).name == dev.dictionary.get(idx).name


def test_slot_expansion_copley_two_axes(devices):
    done = profiles.complete_generic(devices["copley"])
    od = done.dictionary
    assert [od.entry(0x1C12, s).default_value for s in range(3)] == [2, 0x1700, 0x1740]
    axis_b = done.pdo(0x1740)
    assert axis_b.entries[0].index == 0x6840  # SlotIndexIncrement 0x800


def test_etg2001_default_modules(devices):
    done = profiles.complete_generic(devices["etg2001"])
    assert [p.index for p in done.rx_pdos if p.sm == 2] == [0x1600, 0x1610]
    assert done.dictionary.entry(0x6840, 0).rx_mappable


def test_synthesised_assignment_read_only_without_pdo_assign():
    dev = Device(Identity(0x99, 0x1234, 1), "Test", sync_managers=[
        SyncManager(0, "MBoxOut"), SyncManager(1, "MBoxIn"), SyncManager(2, "Outputs"), SyncManager(3, "Inputs")],
        rx_pdos=[Pdo(Direction.RX, 0x1600, "Rx", [PdoEntry(0x7000, 1, 16, "Out", "UINT")], sm=2, fixed=True)],
        tx_pdos=[Pdo(Direction.TX, 0x1A00, "Tx", [PdoEntry(0x6000, 1, 8, "In", "USINT")], sm=3)],
        mailbox=Mailbox(["CoE"], CoeDetails(pdo_assign=False, pdo_config=True)))
    done = profiles.complete_generic(dev)
    od = done.dictionary
    assert not od.entry(0x1C12, 0).access.writable()
    assert not od.entry(0x1600, 1).access.writable()  # Fixed PDO
    assert od.entry(0x1A00, 1).access.writable(EcState.PREOP)
    assert od.entry(0x1A00, 1).default_value == 0x60000108
    assert [od.entry(0x1C00, s).default_value for s in range(5)] == [4, 1, 2, 3, 4]
    assert od.entry(0x7000, 1).rx_mappable and od.entry(0x6000, 1).tx_mappable
    rules = profiles.rules_for(dev)
    assert rules.family == "generic" and not rules.assign_writable and rules.mapping_writable


@pytest.mark.parametrize("key", sorted(DRIVES))
def test_rules_for_corpus_esis_are_generic(devices, key):
    dev = devices[key]
    rules = profiles.rules_for(dev)
    assert rules.family == "generic" and profiles.family_of(dev) == "generic"
    assert rules.vendor_id == dev.vendor_id
    for p in dev.rx_pdos:
        assert p.index in rules.rx_mapping_indices
    for p in dev.tx_pdos:
        assert p.index in rules.tx_mapping_indices


def test_rules_for_elmo_fixed_pdos(devices):
    rules = profiles.rules_for(devices["elmo"])
    assert not rules.mapping_writable and rules.assign_writable


def test_rules_for_ingenia_modes_from_6502(devices):
    rules = profiles.rules_for(devices["ingenia"])
    assert rules.supported_modes == supported_modes_of(devices["ingenia"].dictionary)
    assert {1, 3, 6, 8, 9, 10} <= set(rules.supported_modes)


def test_rules_for_synapticon_no_assign_no_config(devices):
    rules = profiles.rules_for(devices["synapticon"])
    assert not rules.assign_writable and not rules.mapping_writable


@pytest.mark.parametrize("name,family,vendor", [
    ("technosoft-ipos", "technosoft-ipos", 0x1A3), ("hdt", "hdt", 0x289), ("controltechniques", "controltechniques", 0xF9),
])
def test_rules_for_each_profile(name, family, vendor):
    dev = profiles.load(name)
    rules = profiles.rules_for(dev)
    assert rules.family == family == profiles.family_of(dev) and rules.vendor_id == vendor
    for p in dev.rx_pdos:
        assert p.index in rules.rx_mapping_indices
    for p in dev.tx_pdos:
        assert p.index in rules.tx_mapping_indices
    assert rules.supported_modes


def test_rules_by_vendor_id_for_foreign_device_description():
    # a device from some other description with Technosoft's vendor id gets Technosoft's rules
    dev = Device(Identity(0x1A3, 28002021, 0x3531354B), "iPOS from ESI")
    assert profiles.rules_for(dev).family == "technosoft-ipos" and profiles.rules_for(dev).max_pdo_bits == 64
    ct = Device(Identity(0xF9, 421, 0x00650000), "SM-EtherCAT from ESI")
    assert profiles.rules_for(ct).max_assigned_rx == 2


def test_complete_generic_on_a_profile_is_harmless():
    dev = profiles.load("hdt")
    done = profiles.complete_generic(dev)
    assert done.dictionary.indices() == dev.dictionary.indices()
