"""Programming mappings: SDO order, exact sizes, complete access, and the manuals' worked examples
(reference/technosoft/oracles.md B.13-20, reference/controltechniques/oracles.md A-B, reference/hdt/oracles.md
10-14) reproduced as SDO sequences."""

from __future__ import annotations

from functools import lru_cache

import pytest
from hypothesis import given
from hypothesis import strategies as st

from ecattool import profiles
from ecattool.errors import InputError
from ecattool.esi.model import Device, Direction, PdoEntry
from ecattool.pdo import Mapping, check, default_mapping, layout, program
from ecattool.profiles.rules import FamilyRules
from tests.pdo.test_pdo_support import make_device

GENERIC = FamilyRules("generic")


@lru_cache(maxsize=None)
def _profile(name: str) -> Device:
    return profiles.load(name)


def seq(startup) -> list[tuple[int, int, int, int]]:
    """(index, sub, size in bytes, value) of each write."""
    return [(c.index, c.subindex, len(c.data), c.int_value) for c in startup]


# --- order and sizes ----------------------------------------------------------------------------


def test_standard_order_and_sizes() -> None:
    dev = make_device()
    m = Mapping.from_text(rx="0x1600=controlword,0x60FF:00/32;0x1601", tx="0x1A00=statusword", device=dev)
    assert seq(program(dev, m, rules=GENERIC)) == [
        (0x1C12, 0, 1, 0), (0x1C13, 0, 1, 0),
        (0x1600, 0, 1, 0), (0x1600, 1, 4, 0x60400010), (0x1600, 2, 4, 0x60FF0020), (0x1600, 0, 1, 2),
        (0x1A00, 0, 1, 0), (0x1A00, 1, 4, 0x60410010), (0x1A00, 0, 1, 1),
        (0x1C12, 1, 2, 0x1600), (0x1C12, 2, 2, 0x1601), (0x1C12, 0, 1, 2),
        (0x1C13, 1, 2, 0x1A00), (0x1C13, 0, 1, 1),
    ]


def test_types_comments_and_transition() -> None:
    dev = make_device()
    m = Mapping.from_text(rx="0x1600=controlword", device=dev)
    cmds = program(dev, m, rules=GENERIC, transition="IP").commands
    assert {c.transition for c in cmds} == {"IP"}
    assert [c.type_name for c in cmds] == ["USINT", "USINT", "UDINT", "USINT", "UINT", "USINT"]
    assert cmds[0].comment == "clear sm pdos (0x1C12)" and cmds[-1].comment == "download pdo 0x1C12 count"
    assert cmds[2].value == 0x60400010


def test_directions_not_given_are_not_programmed() -> None:
    dev = make_device()
    m = Mapping.from_text(tx="0x1A00=statusword", device=dev)
    assert {c.index for c in program(dev, m, rules=GENERIC)} == {0x1C13, 0x1A00}


def test_fixed_pdos_are_assigned_never_rewritten() -> None:
    dev = make_device()
    m = Mapping.from_text(tx="0x1A00;0x1A01=0x6061:00/8", device=dev)  # same contents as the Fixed PDO
    assert check(dev, m, rules=GENERIC) == []
    writes = seq(program(dev, m, rules=GENERIC))
    assert not any(w[0] == 0x1A01 for w in writes)
    assert (0x1C13, 2, 2, 0x1A01) in writes


def test_unwritable_assignment_and_mapping_are_left_alone() -> None:
    dev = make_device()
    m = Mapping.from_text(rx="0x1600=controlword", device=dev)
    assert seq(program(dev, m, rules=FamilyRules("f", assign_writable=False))) == [
        (0x1600, 0, 1, 0), (0x1600, 1, 4, 0x60400010), (0x1600, 0, 1, 1)]
    same = Mapping.from_text(rx="0x1600=controlword,0x607A:00/32", device=dev)  # the PDO's own contents
    assert [w[0] for w in seq(program(dev, same, rules=FamilyRules("f", mapping_writable=False)))] == [0x1C12] * 3
    # asked for what cannot be done (check: PDO022/PDO023), the writes are still made: the drive refuses them
    assert [w[0] for w in seq(program(dev, m, rules=FamilyRules("f", mapping_writable=False)))][1] == 0x1600
    other = Mapping.from_text(rx="0x1601", device=dev)
    assert (0x1C12, 1, 2, 0x1601) in seq(program(dev, other, rules=FamilyRules("f", assign_writable=False)))


def test_complete_access_variant() -> None:
    dev = make_device(complete_access=True)
    m = Mapping.from_text(rx="0x1600=controlword,0x607A:00/32;0x1601", device=dev)
    cmds = program(dev, m, complete_access=True, rules=GENERIC).commands
    assert [(c.index, c.subindex, c.complete_access, c.data.hex()) for c in cmds] == [
        (0x1C12, 0, False, "00"),
        (0x1600, 0, True, "0200" "10004060" "20007a60"),
        (0x1C12, 0, True, "0200" "0016" "0116"),
    ]


def test_complete_access_only_when_the_device_advertises_it() -> None:
    dev = make_device(complete_access=False)
    m = Mapping.from_text(rx="0x1600=controlword", device=dev)
    assert not any(c.complete_access for c in program(dev, m, complete_access=True, rules=GENERIC))


def test_count_first_order() -> None:
    dev = make_device()
    m = Mapping.from_text(rx="0x1600=controlword", device=dev)
    assert seq(program(dev, m, rules=GENERIC, order="count-first")) == [
        (0x1600, 0, 1, 1), (0x1600, 1, 4, 0x60400010), (0x1C12, 0, 1, 1), (0x1C12, 1, 2, 0x1600)]
    with pytest.raises(InputError, match="unknown programming order"):
        program(dev, m, rules=GENERIC, order="sideways")


@given(st.lists(st.sampled_from(["controlword", "0x607A:00/32", "0x60FF:00/32", "0x60B8:00/16", "0x6060:00/8",
                                 "gap/8", "0x60FE:01/32"]), min_size=0, max_size=8))
def test_program_writes_exactly_the_laid_out_entries(entries: list[str]) -> None:
    dev = make_device()
    m = Mapping.from_text(rx="0x1600=" + ",".join(entries), device=dev)
    writes = seq(program(dev, m, rules=GENERIC))
    values = [w[3] for w in writes if w[0] == 0x1600 and w[1] > 0]
    image = layout(dev, m).outputs
    assert [PdoEntry.from_mapping_value(v).bit_len for v in values] == [e.bit_len for e in image.entries]
    assert writes[-1] == (0x1C12, 0, 1, 1)
    assert all(size == {0: 1}.get(sub, 4 if idx == 0x1600 else 2) for idx, sub, size, _ in writes)


# --- Technosoft iPOS (P091.064.UM.0524) ----------------------------------------------------------


def _ts(rx: str | None = None, tx: str | None = None) -> tuple[Device, Mapping]:
    dev = _profile("technosoft-ipos")
    return dev, Mapping.from_text(rx=rx, tx=tx, device=dev)


def test_technosoft_entry_encoding_oracle_13() -> None:
    dev = _profile("technosoft-ipos")
    from ecattool.pdo import parse_entry

    for text, value in (("0x6040:00/16", 0x60400010), ("modes of operation", 0x60600008),
                        ("0x6064:00/32", 0x60640020), ("0x60FD:00", 0x60FD0020), ("0x60C1:01/32", 0x60C10120),
                        ("0x60C1:02/32", 0x60C10220), ("0x60FF:00", 0x60FF0020), ("0x60FE:01/32", 0x60FE0120),
                        ("0x60FE:02/32", 0x60FE0220), ("0x207D:00", 0x207D0008)):
        assert parse_entry(text, dev).mapping_value == value, text


def test_technosoft_default_mapping_oracle_14() -> None:
    dev = _profile("technosoft-ipos")
    m = default_mapping(dev)
    assert [p.index for p in m.rx] == [0x1600] and [p.index for p in m.tx] == [0x1A00, 0x1A01]
    assert [e.mapping_value for e in m.rx[0].entries] == [0x60400010, 0x607A0020]
    assert [[e.mapping_value for e in p.entries] for p in m.tx] == [[0x60410010, 0x60640020, 0x60770010],
                                                                     [0x60F40020, 0x60FD0020]]
    lay = layout(dev, m)
    assert (lay.outputs.bit_size, lay.inputs.bit_size) == (48, 128)
    assert check(dev, m) == []


def test_technosoft_rxpdo3_example_2_5() -> None:
    dev, m = _ts(rx="0x1600;0x1601;0x1602=0x60400010,0x60600008")
    baseline = Mapping.from_text(rx="0x1600;0x1601", device=dev)
    assert check(dev, m) == []
    assert seq(program(dev, m, baseline=baseline)) == [
        (0x1C12, 0, 1, 0), (0x1602, 0, 1, 0), (0x1602, 1, 4, 0x60400010), (0x1602, 2, 4, 0x60600008),
        (0x1602, 0, 1, 2), (0x1C12, 3, 2, 0x1602), (0x1C12, 0, 1, 3)]
    assert m.rx[2].bit_size == 24


def test_technosoft_txpdo4_example_2_6() -> None:
    dev, m = _ts(tx="0x1A00;0x1A01;0x1A02;0x1A03=0x6064:00/32,0x60FD:00/32")
    baseline = Mapping.from_text(tx="0x1A00;0x1A01;0x1A02", device=dev)
    assert check(dev, m) == []
    assert seq(program(dev, m, baseline=baseline)) == [
        (0x1C13, 0, 1, 0), (0x1A03, 0, 1, 0), (0x1A03, 1, 4, 0x60640020), (0x1A03, 2, 4, 0x60FD0020),
        (0x1A03, 0, 1, 2), (0x1C13, 4, 2, 0x1A03), (0x1C13, 0, 1, 4)]
    assert m.tx[3].bit_size == 64


def test_technosoft_ip_mapping_9_4_same_writes_safer_order() -> None:
    # §9.4 writes 1602h before disabling 1C12h (legal there: 1602h is not assigned by default); ecattool
    # always disables the assignment first (docs/decisions.md), so the same writes come in another order.
    dev, m = _ts(rx="0x1600;0x1601;0x1602=0x60C1:01/32,0x60C1:02/32")
    manual = [(0x1602, 0, 1, 0), (0x1602, 1, 4, 0x60C10120), (0x1602, 2, 4, 0x60C10220), (0x1602, 0, 1, 2),
              (0x1C12, 0, 1, 0), (0x1C12, 3, 2, 0x1602), (0x1C12, 0, 1, 3)]
    ours = seq(program(dev, m, baseline=Mapping.from_text(rx="0x1600;0x1601", device=dev)))
    assert sorted(ours) == sorted(manual)
    assert ours[0] == (0x1C12, 0, 1, 0) and m.rx[2].bit_size == 64
    assert check(dev, m) == []


def test_technosoft_csv_mapping_14_2() -> None:
    dev, m = _ts(rx="0x1600;0x1601;0x1603=0x60FF:00/32")
    assert check(dev, m) == []
    assert seq(program(dev, m, baseline=Mapping.from_text(rx="0x1600;0x1601", device=dev))) == [
        (0x1C12, 0, 1, 0), (0x1603, 0, 1, 0), (0x1603, 1, 4, 0x60FF0020), (0x1603, 0, 1, 1),
        (0x1C12, 3, 2, 0x1603), (0x1C12, 0, 1, 3)]


def test_technosoft_cst_mapping_15_3() -> None:
    dev, m = _ts(rx="0x1600;0x1601;0x1602")
    assert [e.mapping_value for e in m.rx[2].entries] == [0x60600008, 0x60710010]  # RPDO3 default has 6071h
    assert seq(program(dev, m, baseline=Mapping.from_text(rx="0x1600;0x1601", device=dev))) == [
        (0x1C12, 0, 1, 0), (0x1C12, 3, 2, 0x1602), (0x1C12, 0, 1, 3)]


def test_technosoft_64_bit_limit_1_6_3() -> None:
    dev, ok = _ts(rx="0x1600;0x1601=0x60B8:00/16,0x2092:01/32", tx="0x1A00;0x1A01;0x1A02=0x60B9:00/16,0x60BA:00/32")
    assert check(dev, ok) == []
    assert (ok.rx[1].bit_size, ok.tx[2].bit_size) == (48, 48)
    _, over = _ts(rx="0x1601=0x60B8:00/16,0x2092:01/32,0x607A:00/32")
    assert [f.rule for f in check(dev, over)] == ["PDO009"]


def test_technosoft_dummies_only_in_rxpdos_and_no_gaps() -> None:
    dev, rx = _ts(rx="0x1600=controlword,0x207D:00/8,0x0005:00/8,0x607A:00/32")
    assert check(dev, rx) == []
    _, tx = _ts(tx="0x1A00=statusword,0x207D:00/8")
    assert [f.rule for f in check(dev, tx)] == ["PDO013"]
    _, gap = _ts(rx="0x1600=controlword,gap/8")
    assert [f.rule for f in check(dev, gap)] == ["PDO013"]


def test_technosoft_four_pdos_per_direction() -> None:
    dev, m = _ts(rx="0x1600;0x1601;0x1602;0x1603;0x1604")
    assert {f.rule for f in check(dev, m)} == {"PDO001", "PDO011"}


# --- Control Techniques SM-EtherCAT quick start (5.1.3-5.1.4) ------------------------------------


CT_QUICK_START = [
    (0x1600, 0, 1, 3), (0x1600, 1, 4, 0x60400010), (0x1600, 2, 4, 0x60420010), (0x1600, 3, 4, 0x20141520),
    (0x1A00, 0, 1, 2), (0x1A00, 1, 4, 0x60410010), (0x1A00, 2, 4, 0x60640020),
    (0x1A05, 0, 1, 2), (0x1A05, 1, 4, 0x20121610), (0x1A05, 2, 4, 0x20141620),
    (0x1C12, 0, 1, 1), (0x1C12, 1, 2, 0x1600),
    (0x1C13, 0, 1, 2), (0x1C13, 1, 2, 0x1A00), (0x1C13, 2, 2, 0x1A05),
]


def _ct_quick_start(tx_second: str) -> tuple[Device, Mapping]:
    dev = _profile("controltechniques")
    return dev, Mapping.from_text(rx="0x1600=0x60400010,0x60420010,0x20141520",
                                  tx=f"0x1A00=0x60410010,0x60640020;0x1A05=0x20121610,{tx_second}", device=dev)


def test_ct_quick_start_sequence_oracle_10() -> None:
    dev, m = _ct_quick_start("0x20141620")  # printed as in Table 5.3 (Pr 20.22, see ambiguity A1)
    assert seq(program(dev, m, order="count-first")) == CT_QUICK_START


def test_ct_quick_start_as_printed_maps_pr_20_22_which_does_not_exist() -> None:
    dev, m = _ct_quick_start("0x20141620")
    findings = check(dev, m)
    assert [(f.rule, f.data.get("index"), f.data.get("subindex")) for f in findings] == [("PDO005", 0x2014, 0x16)]


def test_ct_quick_start_corrected_is_clean_with_image_sizes_oracle_11() -> None:
    dev, m = _ct_quick_start("0x20141520")
    assert check(dev, m) == []
    lay = layout(dev, m)
    assert (lay.outputs.byte_size, lay.inputs.byte_size) == (8, 12)
    standard = seq(program(dev, m))
    assert standard[:2] == [(0x1C12, 0, 1, 0), (0x1C13, 0, 1, 0)]
    assert sorted(w for w in standard if w[3] != 0 or w[1] != 0) == sorted(
        w if w != (0x1A05, 2, 4, 0x20141620) else (0x1A05, 2, 4, 0x20141520) for w in CT_QUICK_START)


def test_ct_entry_encodings_oracles_2_to_5() -> None:
    from ecattool.pdo import parse_entry

    dev = _profile("controltechniques")
    assert parse_entry("0x2014:15/32", dev).mapping_value == 0x20141520
    assert parse_entry("0x2012:16/16", dev).mapping_value == 0x20121610
    decoded = PdoEntry.from_mapping_value(0x20141620)
    assert (decoded.index, decoded.subindex, decoded.bit_len) == (0x2014, 0x16, 32)
    for obj, value in ((0x6040, 0x60400010), (0x6042, 0x60420010), (0x6060, 0x60600008), (0x6041, 0x60410010),
                       (0x6061, 0x60610008), (0x6064, 0x60640020), (0x6044, 0x60440010)):
        assert parse_entry(f"0x{obj:04X}", dev).mapping_value == value


def test_ct_limits_oracle_14() -> None:
    dev = _profile("controltechniques")
    five = ",".join(["controlword", "0x6042:00/16", "0x6060:00/8", "gap/8", "0x2014:15/32"])
    ok = Mapping.from_text(rx=f"0x1600={five}", device=dev)
    assert check(dev, ok) == []
    six = Mapping.from_text(rx=f"0x1600={five},gap/8", device=dev)
    assert [f.rule for f in check(dev, six)] == ["PDO010"]
    three = Mapping.from_text(rx="0x1600;0x1601;0x1605", device=dev)
    assert "PDO011" in {f.rule for f in check(dev, three)}


def test_ct_default_assignment_oracle_12() -> None:
    dev = _profile("controltechniques")
    m = default_mapping(dev)
    assert [p.index for p in m.rx] == [0x1605] and [p.index for p in m.tx] == [0x1A05]
    assert [e.mapping_value for e in m.rx[0].entries] == [0x60400010, 0x60420010]  # ambiguity A2: 6042h
    assert (layout(dev, m).outputs.byte_size, layout(dev, m).inputs.byte_size) == (4, 4)


def test_ct_priority_rule_6_1_1() -> None:
    dev = _profile("controltechniques")
    first = Mapping.from_text(rx="0x1600=controlword,0x2046:01/32;0x1605", device=dev)
    assert [f.rule for f in check(dev, first)] == ["PDO012"]
    second = Mapping.from_text(rx="0x1605;0x1600=controlword,0x2046:01/32", device=dev)
    assert check(dev, second) == []
    alone = Mapping.from_text(rx="0x1600=controlword,0x2046:01/32", device=dev)
    assert check(dev, alone) == []  # one PDO: allowed, the whole PDO becomes low priority


# --- HDT defaults (§4.02) --------------------------------------------------------------------------


HDT_DEFAULTS = {
    0x1600: [0x60400010, 0x60420010, 0x607C0020], 0x1601: [0x607A0020, 0x60810020],
    0x1602: [0x60830020, 0x60840020], 0x1603: [0x60C10120],
    0x1A00: [0x60410010, 0x60610008, 0x10010008], 0x1A01: [0x60620020, 0x60640020],
    0x1A02: [0x60430010, 0x60440010], 0x1A03: [0x60FD0020],
}
HDT_BITS = {0x1600: 64, 0x1601: 64, 0x1602: 64, 0x1603: 32, 0x1A00: 32, 0x1A01: 64, 0x1A02: 32, 0x1A03: 32}


def test_hdt_defaults_oracles_10_to_13() -> None:
    dev = _profile("hdt")
    m = default_mapping(dev)
    pdos = {p.index: p for p in (*m.rx, *m.tx)}
    assert {i: [e.mapping_value for e in p.entries] for i, p in pdos.items()} == HDT_DEFAULTS
    assert {i: p.bit_size for i, p in pdos.items()} == HDT_BITS
    assert check(dev, m) == []  # 1001h in 1A00h is legal because the drive maps it itself (ambiguity 15)


def test_hdt_defaults_as_sdo_sequence() -> None:
    dev = _profile("hdt")
    text = {d: ";".join(f"0x{i:04X}=" + ",".join(f"0x{v:08X}" for v in HDT_DEFAULTS[i])
                        for i in sorted(HDT_DEFAULTS) if (i < 0x1A00) == (d is Direction.RX)) for d in Direction}
    m = Mapping.from_text(rx=text[Direction.RX], tx=text[Direction.TX], device=dev)
    writes = seq(program(dev, m))
    for index, values in HDT_DEFAULTS.items():
        mine = [w for w in writes if w[0] == index]
        assert mine == [(index, 0, 1, 0)] + [(index, k, 4, v) for k, v in enumerate(values, 1)] + [
            (index, 0, 1, len(values))]
    assert [w for w in writes if w[0] == 0x1C12] == [(0x1C12, 0, 1, 0)] + [
        (0x1C12, k, 2, 0x1600 + k - 1) for k in range(1, 5)] + [(0x1C12, 0, 1, 4)]


def test_hdt_eight_entries_per_pdo_oracle_14() -> None:
    dev = _profile("hdt")
    nine = Mapping.from_text(rx="0x1600=" + ",".join(["0x6060:00/8"] * 9), device=dev)
    assert "PDO010" in {f.rule for f in check(dev, nine)}


# --- program <-> mapping_from_startup (encoder/decoder pair) -------------------------------------


@given(st.lists(st.sampled_from(["0x1600=controlword,0x60FF:00/32", "0x1600=0x6060:00/8,gap/8", "0x1601",
                                 "0x1601=0x60FE:01/32,0x60FE:02/32", "0x1600="]), max_size=2, unique=True),
       st.lists(st.sampled_from(["0x1A00=statusword", "0x1A01", "0x1A02=0x6077:00/16,0x2000:00/1,gap/7"]),
                max_size=3, unique=True),
       st.booleans(), st.sampled_from(["standard", "count-first"]))
def test_the_startup_list_installs_the_mapping(rx: list[str], tx: list[str], ca: bool, order: str) -> None:
    from hypothesis import assume

    from ecattool.pdo import mapping_from_startup

    assume(len({p.split("=")[0] for p in rx}) == len(rx))  # a PDO assigned twice is PDO003, not a mapping
    dev = make_device(complete_access=True)
    m = Mapping.from_text(rx=";".join(rx), tx=";".join(tx), device=dev)
    startup = program(dev, m, complete_access=ca, rules=GENERIC, order=order)
    back = mapping_from_startup(startup, dev)
    assert back.given == m.given
    for d in Direction:
        assert [(p.index, [(e.index, e.subindex, e.bit_len) for e in p.entries]) for p in back.pdos(d)] == \
               [(p.index, [(e.index, e.subindex, e.bit_len) for e in p.entries]) for p in m.pdos(d)]
