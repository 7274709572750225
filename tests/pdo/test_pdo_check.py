"""Every static rule of ``ecattool.pdo.check``: one mapping that triggers exactly that rule, plus the catalogue
in docs/pdo-mapping.md agreeing with the code."""

from __future__ import annotations

import re
from typing import Any

import pytest

from ecattool.errors import InputError, Location
from ecattool.esi.model import Direction
from ecattool.findings import Severity, has_errors
from ecattool.od.model import ObjectDictionary
from ecattool.pdo import RULES, Mapping, check, default_mapping, layout
from ecattool.pdo.check import input_finding
from ecattool.profiles.rules import FamilyRules
from ecattool.startup.model import StartupCommand
from tests.conftest import ROOT
from tests.pdo.test_pdo_support import make_device

GENERIC = FamilyRules("generic")


def _mandatory_1601(dev: Any) -> None:
    dev.rx_pdos[1].mandatory = True


def _sm3_on_1601(dev: Any) -> None:
    dev.rx_pdos[1].sm = 3


def _no_dictionary(dev: Any) -> None:
    dev.dictionary = ObjectDictionary()


def _latch_window(dev: Any) -> None:
    """A virtual TxPDO without a sync manager, as the EL1252's 1A10h (beckhoff_EL1xxx.xml): DC latch registers."""
    from ecattool.esi.model import Pdo, PdoEntry

    dev.tx_pdos.append(Pdo(Direction.TX, 0x1A10, "Latch", [PdoEntry(0x1D09, 0xAE, 8, "Status0")], fixed=True,
                           virtual=True, su=1))


#: rule -> (rx, tx, rules, device edit, startup)
CASES: dict[str, tuple[str | None, str | None, FamilyRules, Any, list[StartupCommand]]] = {
    "PDO001": ("0x1605=controlword", None, GENERIC, None, []),
    "PDO002": ("0x1A00", None, GENERIC, None, []),
    "PDO003": ("0x1600;0x1600", None, GENERIC, None, []),
    "PDO004": ("0x1600=0x5000:00/16", None, GENERIC, None, []),
    "PDO005": ("0x1600=0x60FE:05/32", None, GENERIC, None, []),
    "PDO006": (None, "0x1A00=controlword", GENERIC, None, []),
    "PDO007": ("0x1600=0x6040:00/32", None, GENERIC, None, []),
    "PDO008": ("0x1600=0x6077:00/16", None, GENERIC, None, []),
    "PDO009": ("0x1600=controlword,0x607A:00/32", None, FamilyRules("f", max_pdo_bits=32), None, []),
    "PDO010": ("0x1600=controlword,0x6060:00/8", None, FamilyRules("f", max_pdo_entries=1), None, []),
    "PDO011": ("0x1600;0x1601", None, FamilyRules("f", max_assigned_rx=1), None, []),
    "PDO012": ("0x1600=0x2001:00/32;0x1601", None, FamilyRules("f", priority_rule=True), None, []),
    "PDO013": ("0x1600=controlword,gap/16", None, FamilyRules("f", gaps_allowed=False), None, []),
    "PDO014": (None, "0x1A00;0x1A01=0x6064:00/32", GENERIC, None, []),
    "PDO015": ("0x1600", None, GENERIC, _mandatory_1601, []),
    "PDO016": (None, "0x1A00;0x1A01;0x1A02", GENERIC, None, []),
    "PDO017": ("0x1600;0x1601", None, GENERIC, _sm3_on_1601, []),
    "PDO018": ("0x1600=controlword,0x607A:00/32,0x60FF:00/32,0x60B8:00/16;0x1601=0x60FE:01/32,0x60FE:02/32", None,
               GENERIC, None, []),
    "PDO019": ("0x1600=0x6060:00/8,gap/4,controlword,gap/4", None, GENERIC, None, []),
    "PDO020": ("0x1600=controlword,controlword", None, GENERIC, None, []),
    "PDO021": ("0x1600=controlword,0x6060:00/8", None, GENERIC, None,
               [StartupCommand("PS", 0x6060, 0, b"\x08", source=Location("p.yaml", 30))]),
    "PDO022": ("0x1601", None, FamilyRules("f", assign_writable=False), None, []),
    "PDO023": ("0x1600=controlword", None, FamilyRules("f", mapping_writable=False), None, []),
    "PDO024": ("0x1600=", None, GENERIC, None, []),
    "PDO025": ("0x1600=0x5000:00/16", None, GENERIC, _no_dictionary, []),
    "PDO027": (None, "0x1A00=statusword,0x2000:00/1", GENERIC, None, []),
    "PDO029": (None, "0x1A00;0x1A10", GENERIC, _latch_window, []),
}


def _run(rule: str) -> list:
    rx, tx, rules, edit, startup = CASES[rule]
    dev = make_device()
    if edit is not None:
        edit(dev)
    m = Mapping.from_text(rx=rx, tx=tx, device=dev, source="cli")
    return check(dev, m, rules=rules, startup=startup)


def test_default_mapping_is_clean() -> None:
    dev = make_device()
    assert check(dev, default_mapping(dev), rules=GENERIC) == []


@pytest.mark.parametrize("rule", sorted(CASES))
def test_each_rule_triggers_alone(rule: str) -> None:
    findings = _run(rule)
    assert {f.rule for f in findings} == {rule}, [str(f) for f in findings]
    assert all(f.severity is RULES[rule][0] for f in findings)
    assert all(f.location is not None for f in findings)


def test_dummy_in_txpdo_is_refused_but_allowed_in_rxpdo() -> None:
    dev = make_device()
    rules = FamilyRules("f", dummy_indices=frozenset({5}), dummies_in_rx=True, dummies_in_tx=False)
    tx = Mapping.from_text(tx="0x1A00=statusword,0x0005:00/8", device=dev)
    assert {f.rule for f in check(dev, tx, rules=rules)} == {"PDO013"}
    rx = Mapping.from_text(rx="0x1600=controlword,0x0005:00/8", device=dev)
    assert check(dev, rx, rules=rules) == []
    wrong = Mapping.from_text(rx="0x1600=controlword,0x0005:00/16", device=dev)
    assert {f.rule for f in check(dev, wrong, rules=rules)} == {"PDO007"}


def test_repeated_dummies_pad_without_a_duplicate_warning() -> None:
    # Technosoft §2.3.1/§2.3.12: data-type dummies and 207Dh fill an RxPDO; repeating them maps no object twice
    from ecattool import profiles
    dev = profiles.load("technosoft-ipos")
    m = Mapping.from_text(rx="0x1600=controlword,0x0005:00/8,0x0005:00/8,0x207D:00/8,0x207D:00/8", device=dev)
    assert check(dev, m) == []
    twice = Mapping.from_text(rx="0x1600=controlword,controlword", device=dev)
    assert [f.rule for f in check(dev, twice)] == ["PDO020"]


def test_odd_image_hint_proposes_what_the_family_accepts() -> None:
    # a family without gaps must not be told to add a gap (that is PDO013): it is told to pad with dummies
    from ecattool import profiles
    dev = profiles.load("technosoft-ipos")
    m = Mapping.from_text(rx="0x1600=controlword,0x0001:00/1", device=dev)
    (f,) = check(dev, m)
    assert f.rule == "PDO027" and "gap/" not in f.message and "dummy entries" in f.message
    generic = _run("PDO027")
    assert "gap/7" in generic[0].message


def test_entry_limit_of_the_mapping_object() -> None:
    dev = make_device()
    m = Mapping.from_text(rx="0x1600=" + ",".join(["gap/8"] * 9), device=dev)
    assert {f.rule for f in check(dev, m, rules=GENERIC)} == {"PDO010"}


def test_assignment_limit_of_the_assign_object() -> None:
    dev = make_device()
    dev.dictionary.get(0x1C12).entries.pop(2)
    m = Mapping.from_text(rx="0x1600;0x1601", device=dev)
    findings = check(dev, m, rules=GENERIC)
    assert [f.rule for f in findings] == ["PDO011"] and "0x1C12 allows at most 1" in findings[0].message


def test_entry_size_range_rule() -> None:
    dev = make_device()
    rules = FamilyRules("f", min_entry_bits=8, max_entry_bits=16)
    m = Mapping.from_text(rx="0x1600=controlword,0x60FF:00/32", device=dev)
    assert {f.rule for f in check(dev, m, rules=rules)} == {"PDO026"}


def test_rx_only_flag_is_trusted_over_read_only_access() -> None:
    # Beckhoff-style output objects: Access ro, PdoMapping R -> mappable in RxPDOs
    dev = make_device()
    dev.dictionary.entry(0x6040, 0).access = dev.dictionary.entry(0x6041, 0).access
    m = Mapping.from_text(rx="0x1600=controlword", device=dev)
    assert check(dev, m, rules=GENERIC) == []


def test_bit_entries_may_start_inside_a_byte() -> None:
    dev = make_device()
    m = Mapping.from_text(tx="0x1A00=0x2000:00/1,gap/7,statusword", device=dev)
    assert check(dev, m, rules=GENERIC) == []
    bad = Mapping.from_text(tx="0x1A00=0x2000:00/1,statusword,gap/7", device=dev)
    assert {f.rule for f in check(dev, bad, rules=GENERIC)} == {"PDO019"}


def test_startup_overlap_by_complete_access() -> None:
    dev = make_device()
    m = Mapping.from_text(rx="0x1600=controlword,0x60FE:01/32", device=dev)
    ca = StartupCommand("PS", 0x60FE, 0, bytes(10), complete_access=True)
    assert [f.rule for f in check(dev, m, rules=GENERIC, startup=[ca])] == ["PDO021"]
    other = StartupCommand("PS", 0x60FE, 2, bytes(4))
    assert check(dev, m, rules=GENERIC, startup=[other]) == []


def test_findings_point_at_the_entry_line() -> None:
    dev = make_device()
    data = {"rx": [{"index": "0x1600", "entries": ["controlword", "0x6040:00/32"]}]}
    locs = {("rx", 0): Location("p.yaml", 3), ("rx", 0, "entries", 1): Location("p.yaml", 6, 9)}
    m = Mapping.from_data(data, device=dev, locations=locs)
    findings = check(dev, m, rules=GENERIC)
    pdo007 = [f for f in findings if f.rule == "PDO007"]
    assert pdo007 and pdo007[0].location == Location("p.yaml", 6, 9)
    assert "0x6040:00/16" in pdo007[0].message  # says what would be right


def test_input_errors_become_pdo000() -> None:
    dev = make_device()
    with pytest.raises(InputError) as exc:
        Mapping.from_text(rx="0x1600=nonsense", device=dev, source="cli")
    f = input_finding(exc.value)
    assert f.rule == "PDO000" and f.severity is Severity.ERROR and has_errors([f])


def test_layout_offsets_and_json() -> None:
    dev = make_device()
    m = Mapping.from_text(rx="0x1600=0x6060:00/8,gap/8,controlword,0x607A:00/32", tx="0x1A00=0x2000:00/1,gap/7",
                          device=dev)
    lay = layout(dev, m)
    assert [e.offset for e in lay.outputs.entries] == ["0.0", "1.0", "2.0", "4.0"]
    assert (lay.outputs.bit_size, lay.outputs.byte_size, lay.inputs.byte_size) == (64, 8, 1)
    j = lay.to_json()
    assert j["outputs"]["sm"] == 2 and j["inputs"]["sm"] == 3
    assert j["outputs"]["entries"][3] == {"pdo": "0x1600", "index": "0x607A", "subindex": 0, "offset": "4.0",
                                          "byte": 4, "bit": 0, "bits": 32, "name": "Target position", "type": "DINT"}


def test_layout_of_a_direction_without_sync_manager() -> None:
    dev = make_device()
    dev.sync_managers = [sm for sm in dev.sync_managers if sm.number != 2]
    m = Mapping.from_text(rx="0x1600=controlword", device=dev)
    assert layout(dev, m).outputs.sm is None
    assert {f.rule for f in check(dev, m, rules=GENERIC)} == {"PDO018"}


def test_rule_catalogue_matches_docs() -> None:
    text = (ROOT / "docs" / "pdo-mapping.md").read_text(encoding="utf-8")
    documented = set(re.findall(r"^\|\s*(PDO\d{3})\s*\|", text, re.MULTILINE))
    assert documented == set(RULES)
    for rule, (severity, _title) in RULES.items():
        row = re.search(rf"^\|\s*{rule}\s*\|\s*(\w+)\s*\|", text, re.MULTILINE)
        assert row and row.group(1) == severity.value, rule


def test_every_rule_has_a_triggering_test() -> None:
    extra = {"PDO000", "PDO026", "PDO028"}  # tested by their own tests (PDO028: tests/pdo/test_pdo_corpus.py)
    assert set(CASES) | extra == set(RULES)


def test_assignment_order_is_kept() -> None:
    dev = make_device()
    m = Mapping.from_text(tx="0x1A02;0x1A00", device=dev)
    assert check(dev, m, rules=GENERIC) == []
    assert [p.index for p in m.pdos(Direction.TX)] == [0x1A02, 0x1A00]
