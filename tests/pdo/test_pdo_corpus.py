"""PDO configurations of other tools (corpus configs) checked against the matching ESI or built-in family,
with asserted verdicts: what each gets right and wrong. Where a verdict is "clean", the simulator also
reaches OP with the laid-out image."""

from __future__ import annotations

from typing import Any

import pytest

from ecattool import esi, profiles
from ecattool.esi.model import CoeDetails, Device, Direction, Identity, Mailbox, SyncManager
from ecattool.findings import Severity
from ecattool.od.model import EcState
from ecattool.od.numbers import parse_int
from ecattool.pdo import Mapping, check, layout, mapping_from_startup, program
from ecattool.profiles.rules import FamilyRules
from ecattool.yamlloc import load_yaml
from ecattool.sim import Drive
from ecattool.startup.formats import ecmc, ros2
from tests.conftest import corpus_path


def _ros2(name: str) -> Any:
    path = corpus_path("configs", name)
    return ros2.load(path.read_bytes(), str(path))[0]


def _ros2_mapping(cfg: Any, device: Device) -> Mapping:
    """ethercat_driver_ros2 assigns the rpdo/tpdo lists and maps every channel (IgH ecrt_slave_config_pdos)."""
    data = {d: [{"index": p.index, "entries": [e.mapping_value if e.index else f"gap/{e.bit_len}" for e in p.entries]}
                for p in cfg.pdos(direction)]
            for d, direction in (("rx", Direction.RX), ("tx", Direction.TX))}
    return Mapping.from_data(data, device=device, source=cfg.source.file if cfg.source else "")


def _reaches_op(device: Device, mapping: Mapping, startup: list | None = None) -> tuple[int, int]:
    drive = Drive.from_device(device, profiles.rules_for(device))
    drive.request_state(EcState.PREOP)
    for cmd in program(device, mapping):
        drive.sdo_download(cmd.index, cmd.subindex, cmd.data, complete_access=cmd.complete_access)
    drive.request_state(EcState.SAFEOP)
    drive.request_state(EcState.OP)
    return drive.process_image_sizes()


def _rules(findings: list) -> list[tuple[str, str]]:
    return sorted((f.rule, f.severity.value) for f in findings)


# --- ros2 Technosoft iPOS3604 ----------------------------------------------------------------------


def test_ros2_technosoft_ipos3604_is_clean_and_reaches_op() -> None:
    cfg = _ros2("ros2_technosoft_ipos3604.yaml")
    dev = profiles.load("technosoft-ipos")
    assert cfg.identity.vendor_id == dev.vendor_id and cfg.identity.product_code == 0x01AB46E5 == dev.product_code
    m = _ros2_mapping(cfg, dev)
    assert check(dev, m, startup=cfg.commands) == []
    lay = layout(dev, m)
    # rx: 1600h 48 + 1601h 40 + 1602h 16 bits; tx: 48 + 40 + 24 + 32 bits; every PDO within 64 bits, 4+4 PDOs
    assert (lay.outputs.bit_size, lay.inputs.bit_size) == (104, 144)
    assert max(p.bit_size for p in (*m.rx, *m.tx)) <= 64
    assert _reaches_op(dev, m) == (13, 18)


def test_ros2_technosoft_with_an_extra_pdo_would_break_the_family_limits() -> None:
    cfg = _ros2("ros2_technosoft_ipos3604.yaml")
    dev = profiles.load("technosoft-ipos")
    m = _ros2_mapping(cfg, dev)
    m.rx[1].entries.append(m.rx[0].entries[1])  # 1601h: 6060h 8 + 60FFh 32 + 607Ah 32 = 72 bits
    assert ("PDO009", "error") in _rules(check(dev, m))


# --- ecmc Technosoft remap script ------------------------------------------------------------------


def _ecmc() -> tuple[Any, Device, Mapping]:
    path = corpus_path("configs", "ecmc_ecmciPOSXXXX.cmd")
    cfg = ecmc.load(path.read_bytes(), str(path))[0]
    dev = profiles.load("technosoft-ipos", product="ipos4808-bx-cat")
    return cfg, dev, mapping_from_startup(cfg.commands, dev, source=str(path))


def test_ecmc_ipos_remap_sdos_are_clean_and_in_the_right_order() -> None:
    cfg, dev, m = _ecmc()
    assert [p.index for p in m.rx] == [0x1600, 0x1601] and [p.index for p in m.tx] == [0x1A00, 0x1A01, 0x1A02,
                                                                                       0x1A03]
    assert [e.mapping_value for e in m.tx[1].entries] == [0x60FD0020, 0x20450010, 0x60770010]
    others = [c for c in cfg.commands if not 0x1600 <= c.index <= 0x1C13]
    assert check(dev, m, startup=others) == []  # 6060h is set by SDO but not mapped: no PDO021
    # the script clears 1C12h/1C13h first and writes every count as one byte, entries as four, like `map sdo`
    pdo_writes = [c for c in cfg.commands if 0x1600 <= c.index <= 0x1C13]
    assert [(c.index, c.subindex) for c in pdo_writes[:2]] == [(0x1C12, 0), (0x1C13, 0)]
    assert all(len(c.data) == (1 if c.subindex == 0 else 2 if c.index >= 0x1C00 else 4) for c in pdo_writes)
    assert _reaches_op(dev, m) == (14, 26)


def test_ecmc_ipos_declared_entries_disagree_with_the_programmed_mapping() -> None:
    # EcAddEntryComplete declares 6077h in 1A00h and only 60FDh, 2045h in 1A01h, but the SDOs map 6077h as the
    # third entry of 1A01h: ecmc reads 6077h, 60FDh and 2045h at the wrong offsets.
    cfg, dev, m = _ecmc()
    declared = {p.index: [e.index for e in p.entries] for p in cfg.tx_pdos}
    assert declared[0x1A00] == [0x6041, 0x6064, 0x6077] and declared[0x1A01] == [0x60FD, 0x2045]
    actual = {e.index: e.byte for e in layout(dev, m).inputs.entries}
    declared_offsets: dict[int, int] = {}
    offset = 0
    for p in cfg.tx_pdos:
        for e in p.entries:
            declared_offsets[e.index] = offset // 8
            offset += e.bit_len
    wrong = sorted(i for i in declared_offsets if declared_offsets[i] != actual[i])
    assert wrong == [0x2045, 0x6077, 0x60FD]
    # check_config reports exactly these, at the EcAddEntryComplete lines that declare them (PDO028)
    from ecattool.pdo import check_config

    mapping, findings = check_config(dev, cfg)
    assert [p.index for p in mapping.tx] == [p.index for p in m.tx]
    assert [(f.rule, f.data["index"], f.location.line) for f in findings] == [
        ("PDO028", 0x6077, 164), ("PDO028", 0x60FD, 165), ("PDO028", 0x2045, 166)]
    assert all(f.severity is Severity.WARNING for f in findings)


def test_ros2_configs_program_their_declared_pdos() -> None:
    from ecattool.pdo import check_config, mapping_from_config

    cfg = _ros2("ros2_technosoft_ipos3604.yaml")
    dev = profiles.load("technosoft-ipos")
    m = mapping_from_config(cfg, dev)
    assert [p.index for p in m.rx] == [0x1600, 0x1601, 0x1602] and all(p.explicit for p in m.rx)
    assert check_config(dev, cfg)[1] == []


# --- ros2 Elmo Gold ----------------------------------------------------------------------------------


def _elmo(selector: str, policy: str = "exact") -> Device:
    return esi.select(esi.load(corpus_path("esi", "elmo_Elmo_ECAT_00010420_V11.xml")), selector, policy)


def test_ros2_elmo_gold_is_clean_and_reaches_op() -> None:
    cfg = _ros2("ros2_elmo_gold.yaml")
    dev = _elmo("0x00030924:0x00010420")
    m = _ros2_mapping(cfg, dev)
    assert (dev.pdo(0x1607).fixed, dev.pdo(0x1A07).fixed) == (False, False)  # the configurable PDOs
    assert check(dev, m, startup=cfg.commands) == []
    lay = layout(dev, m)
    assert (lay.outputs.byte_size, lay.inputs.byte_size) == (15, 15)
    from ecattool.profiles.generic import complete_generic

    assert _reaches_op(complete_generic(dev), m) == (15, 15)


# --- ros2 Maxon EPOS3 / EPOS4 (no ESI in the corpus, no built-in family) ---------------------------


def _bare_device(identity: Identity) -> Device:
    sms = [SyncManager(2, "Outputs", 0x1800), SyncManager(3, "Inputs", 0x1C00)]
    return Device(identity, "Maxon (no ESI)", sync_managers=sms,
                  mailbox=Mailbox(["CoE"], CoeDetails(pdo_assign=True, pdo_config=True)), source="bare")


@pytest.mark.parametrize("name, rx_bits, tx_bits", [("ros2_maxon_epos3.yaml", 216, 200),
                                                     ("ros2_maxon_epos4_50_5_config.yaml", 216, 200)])
def test_ros2_maxon_can_only_be_checked_structurally(name: str, rx_bits: int, tx_bits: int) -> None:
    cfg = _ros2(name)
    dev = _bare_device(cfg.identity)
    m = _ros2_mapping(cfg, dev)
    rules = FamilyRules("generic", rx_mapping_indices=tuple(range(0x1600, 0x1604)),
                        tx_mapping_indices=tuple(range(0x1A00, 0x1A04)))  # EPOS: 4 + 4 mapping objects
    findings = check(dev, m, rules=rules, startup=cfg.commands)
    # no dictionary: every entry is unverifiable (19 warnings), but nothing is structurally wrong
    assert {f.rule for f in findings} == {"PDO025"} and len(findings) == 19
    assert not any(f.severity is Severity.ERROR for f in findings)
    lay = layout(dev, m)
    assert (lay.outputs.bit_size, lay.inputs.bit_size) == (rx_bits, tx_bits)
    assert len(m.rx[0].entries) == 10  # above the 8 entries many CiA-402 drives allow; EPOS allows it per ESI


# --- tormach hw_device_mgr device config -------------------------------------------------------------

HWDEVMGR = {
    "elmo_gold_420_test": ("elmo_Elmo_ECAT_00010420_V11.xml", "0x00030924:0x00010420", "exact"),
    "elmo_gold_520_test": ("elmo_Elmo_ECAT_00010420_V11.xml", "0x00030925:0x00010520", "newest-not-newer"),
    "inovance_sv660n_test": ("inovance_SV660_EOE_1Axis_V9.12.xml", None, "exact"),
    "everest_xcr_e_test": ("ingenia_eve-xcr-e_esi.xml", None, "exact"),
}


def _hwdevmgr(category: str) -> tuple[Device, Mapping, Any]:
    path = corpus_path("configs", "hwdevmgr_device_config.yaml")
    doc = load_yaml(path.read_bytes(), str(path))
    i, item = next((i, x) for i, x in enumerate(doc.data) if x["test_category"] == category)
    name, selector, policy = HWDEVMGR[category]
    dev = esi.select(esi.load(corpus_path("esi", name)), selector, policy)
    data: dict[str, Any] = {}
    locs: dict[tuple, Any] = {}
    for sm, d in (("2", "rx"), ("3", "tx")):
        pm = item["sync_manager"][sm]["pdo_mapping"]
        data[d] = [{"index": parse_int(pm["index"]), "entries": [f"0x{parse_int(e['index']):04X}:00" for e in pm["entries"]]}]
        locs[(d, 0)] = doc.locate((i, "sync_manager", sm, "pdo_mapping", "index"))
        for k in range(len(pm["entries"])):
            locs[(d, 0, "entries", k)] = doc.locate((i, "sync_manager", sm, "pdo_mapping", "entries", k, "index"))
    return dev, Mapping.from_data(data, device=dev, locations=locs, source=str(path)), doc


def test_hwdevmgr_maps_statusword_twice_everywhere() -> None:
    for category in HWDEVMGR:
        dev, m, _ = _hwdevmgr(category)
        dup = [f for f in check(dev, m) if f.rule == "PDO020"]
        assert len(dup) == 1 and dup[0].data["index"] == 0x6041, category
        assert dup[0].location.line is not None and dup[0].severity is Severity.WARNING


@pytest.mark.parametrize("category, line", [("inovance_sv660n_test", 316), ("everest_xcr_e_test", 405)])
def test_hwdevmgr_inovance_and_everest_only_warn(category: str, line: int) -> None:
    dev, m, _ = _hwdevmgr(category)
    findings = check(dev, m)
    assert _rules(findings) == [("PDO020", "warning")]
    assert findings[0].location.line == line  # the second "index: 6041h"


def test_hwdevmgr_elmo_420_remaps_fixed_pdos() -> None:
    dev, m, _ = _hwdevmgr("elmo_gold_420_test")
    findings = check(dev, m)
    assert _rules(findings) == [("PDO014", "error"), ("PDO014", "error"), ("PDO020", "warning")]
    assert sorted(f.location.line for f in findings if f.rule == "PDO014") == [32, 42]


def test_hwdevmgr_elmo_520_names_pdos_the_esi_does_not_have() -> None:
    dev, m, _ = _hwdevmgr("elmo_gold_520_test")
    assert dev.product_code == 0x30925 and dev.revision == 0x10420  # newest revision not newer than 0x10520
    findings = check(dev, m)
    assert _rules(findings) == [("PDO001", "error"), ("PDO001", "error"), ("PDO020", "warning")]
    assert {f.data["pdo"] for f in findings if f.rule == "PDO001"} == {0x1700, 0x1B00}
