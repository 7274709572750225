"""Issue 24: ten places where the built-in profiles or the simulator disagreed with the manuals in
../shared/seeds. Each test quotes the manual line it follows (TS = 000_…, HDT = 003_…, CT = 004_… seed text)."""

from __future__ import annotations

from pathlib import Path

import pytest

from ecattool import profiles
from tests.conftest import seeds_path

from ecattool.od.model import EcState
from ecattool.profiles._build_data import parse_range_spec
from ecattool.sim import Drive, FoeError
from ecattool.sim.cia402 import State
from tests.sim.sim_helpers import OP, PRE, SAFE, at, code_of, r, w

TS_TEXT, HDT_TEXT, CT_TEXT = "000_a0ab57c0bda88c2c.txt", "003_8679b1dde0e37523.txt", "004_b59360cba58a7982.txt"

VALUE_TOO_HIGH, VALUE_TOO_LOW, INVALID_VALUE = 0x06090031, 0x06090032, 0x06090030


def manual_says(seed: str, line: int, text: str) -> None:
    """The quoted text is on (or within 40 lines of) the seed line cited: the test follows the manual."""
    lines = seeds_path(seed).read_text(encoding="utf-8").splitlines()
    window = "\n".join(lines[max(0, line - 41):line + 40])
    assert text in window, f"{seed}:{line} does not say {text!r}"


def entry(family: str, index: int, sub: int, **kw: str):
    e = profiles.load(family, **kw).dictionary.entry(index, sub)
    assert e is not None
    return e


# 1 -------------------------------------------------------------------------------------------------------
def test_1_technosoft_20a0_sub0_is_unsigned8():
    manual_says(TS_TEXT, 4066, "Description\tNumber of sub-indexes")
    e = entry("technosoft-ipos", 0x20A0, 0)
    assert (e.type_name, e.bit_size) == ("USINT", 8)
    # decision Profiles-1: every sub-index 0 of every family is UNSIGNED8
    for family in profiles.PROFILE_NAMES:
        for obj in profiles.load(family).dictionary:
            if obj.object_code.value != "VAR" and 0 in obj.entries:
                assert obj.entries[0].type_name == "USINT", (family, hex(obj.index))


# 2 -------------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("revision, accepted", [("F515F", False), ("F515G", False), ("F515I", True), ("F515K", True)])
def test_2_technosoft_foe_setup_in_boot_from_f515i(revision, accepted):
    manual_says(TS_TEXT, 9955, "Only drives with firmware F515I or newer, support FoE (File over EtherCAT) protocol "
                               "to transfer Setup data while in Bootstrap state when object 210Ch = 1.")
    d = at("technosoft-ipos", PRE, revision=revision)
    w(d, 0x210C, 0, 1, 2)
    d.request_state(EcState.INIT)
    d.request_state(EcState.BOOT)
    image = (0x5E06).to_bytes(2, "little") + (1).to_bytes(2, "little") + bytes.fromhex("3412")
    if accepted:
        d.foe_write("FOESW_AXIS01.bin", image)
        assert d.eeprom_words(0x5E06, 1) == [0x1234]
    else:
        with pytest.raises(FoeError):
            d.foe_write("FOESW_AXIS01.bin", image)


# 3 -------------------------------------------------------------------------------------------------------
def _lint(tmp_path: Path, cycle_ns: int, period: tuple[int, int] | None, slow_loop: str | None = None) -> list:
    from ecattool.project.machine import load_machine

    scaling = (f"    scaling: {{feedback: {{lines: 500}}, units: {{position: rev}}, slow_loop: {slow_loop}}}\n"
               if slow_loop else "")
    params = (f"    parameters:\n      - {{object: \"60C2:02\", value: {period[1]}}}\n"
              f"      - {{object: \"60C2:01\", value: {period[0]}}}\n" if period else "")
    text = ("ecattool: 1\ndrives:\n  - name: x\n    device: {profile: technosoft-ipos}\n"
            f"    dc: {{assign_activate: 0x0300, cycle_ns: {cycle_ns}}}\n{scaling}{params}")
    path = tmp_path / "p.yaml"
    path.write_text(text)
    return [(f.rule, f.severity.value) for f in load_machine(path).findings if f.rule == "PRJ080"]


def test_3_technosoft_sync0_is_the_slow_loop_or_a_multiple_and_60c2_the_sync_cycle(tmp_path):
    manual_says(TS_TEXT, 1843, "The SYNC 0 signal must have the period equal or multiple than the drive slow "
                               "control loop which is by default at 1ms.")
    manual_says(TS_TEXT, 8759, "Its value must be set with the time value of the EtherCAT master communication "
                               "cycle time and sync time")
    assert _lint(tmp_path, 500_000, (4, -3)) == [("PRJ080", "error"), ("PRJ080", "warning")]  # the issue's case
    assert _lint(tmp_path, 1_000_000, None) == []  # default 60C2h = 1 x 10^-3 s
    assert _lint(tmp_path, 2_000_000, (2, -3)) == []
    assert _lint(tmp_path, 2_000_000, None) == [("PRJ080", "warning")]
    assert _lint(tmp_path, 1_500_000, (15, -4)) == [("PRJ080", "error")]
    # the slow loop is the project's: 500 us SYNC0 on a 0.5 ms slow loop is right
    assert _lint(tmp_path, 500_000, (5, -4), slow_loop="0.5 ms") == []
    assert _lint(tmp_path, 250_000, (25, -5), slow_loop="0.5 ms") == [("PRJ080", "error")]


def test_3_other_families_have_no_slow_loop_rule():
    rules = profiles.rules_for(profiles.load("hdt"))
    assert rules.dc_cycle_problems(500_000, 4_000_000, 1_000_000) == []


# 4 -------------------------------------------------------------------------------------------------------
def test_4_technosoft_60c2_sub2_range_minus128_to_63():
    manual_says(TS_TEXT, 8792, "Value range\tINTEGER8, (-128 to +63)")
    e = entry("technosoft-ipos", 0x60C2, 2)
    assert (e.minimum, e.maximum) == (-128, 63)
    d = at("technosoft-ipos")
    assert code_of(w, d, 0x60C2, 2, 64, 1) == VALUE_TOO_HIGH
    assert code_of(w, d, 0x60C2, 2, 127, 1) == VALUE_TOO_HIGH
    w(d, 0x60C2, 2, 63, 1)
    w(d, 0x60C2, 2, -128, 1)


# 5 -------------------------------------------------------------------------------------------------------
def test_5_technosoft_statusword_bit4_is_motor_supply_in_every_state():
    manual_says(TS_TEXT, 2139, "1\tMotor supply voltage is present")
    manual_says(TS_TEXT, 2163, "The state machine cannot transition to states Switched On and Operation enabled "
                               "without this bit being set first.")
    d = at("technosoft-ipos", OP)
    assert r(d, 0x6041) & 0x027F == 0x0250  # SWITCH ON DISABLED with +Vmot present
    d.set_motor_supply(False)
    assert r(d, 0x6041) & 0x027F == 0x0240  # absent: no fault below SWITCHED ON
    for cw in (0x06, 0x07, 0x0F):
        w(d, 0x6040, 0, cw, 2)
    assert d.cia402_state is State.READY  # Switched On needs the bit
    d.set_motor_supply(True)
    w(d, 0x6040, 0, 0x07, 2)
    w(d, 0x6040, 0, 0x0F, 2)
    assert d.cia402_state is State.OPERATION_ENABLED
    d.set_motor_supply(False)  # "the drive will enter fault state due to undervoltage error"
    assert d.cia402_state is State.FAULT
    assert r(d, 0x603F) == 0x3220


def test_5_other_families_keep_the_cia402_voltage_enabled_bit():
    d = at("hdt", OP)
    assert r(d, 0x6041) & 0x0010 == 0  # SWITCH ON DISABLED: no "voltage enabled" (CiA-402)


# 6 -------------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("index, line, printed, values", [
    (0x605A, 2024, "605Ah Quick stop INT16 0..6 0 Yes rw", [0, 1, 2, 5, 6]),
    (0x6060, 2211, "6060h Modes of INT8 -2.10 2 Yes rw", [-2, -1, 1, 2, 3, 4, 6, 7, 8, 9, 10]),
    (0x6086, 4130, "3 | Jerk- limited ramp", [-1, 0, 3]),
    (0x6088, 5540, "6088h Torque profile type INT8 No rw", [-1, 0]),
])
def test_6_hdt_value_lists_are_kept(index, line, printed, values):
    manual_says(HDT_TEXT, line, printed)
    e = entry("hdt", index, 0)
    assert sorted(e.values or ()) == values
    assert (e.minimum, e.maximum) == (min(values), max(values))


def test_6_hdt_simulator_refuses_values_outside_the_list():
    d = at("hdt")
    assert code_of(w, d, 0x605A, 0, 7, 2) == VALUE_TOO_HIGH
    assert code_of(w, d, 0x605A, 0, -1, 2) == VALUE_TOO_LOW
    assert code_of(w, d, 0x605A, 0, 3, 2) == INVALID_VALUE
    assert code_of(w, d, 0x6086, 0, 1, 2) == INVALID_VALUE
    for v in (0, 1, 2, 5, 6):
        w(d, 0x605A, 0, v, 2)


def test_6_decimal_comma_and_value_lists_are_told_apart():
    assert parse_range_spec("0,8000..0,9900").kind == "none"  # decision HDT-6: a display value
    assert parse_range_spec("-1, 0, 3").values == [-1, 0, 3]
    assert parse_range_spec("0..6 (values 0,1,2,5,6)").values == [0, 1, 2, 5, 6]
    assert parse_range_spec("0..35 except 15,16,31,32").values == [v for v in range(36) if v not in (15, 16, 31, 32)]


# 7 -------------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("index, sub, value", [
    (0x60C0, 0, 0), (0x60C2, 2, -3), (0x6089, 0, 0), (0x608B, 0, 0), (0x608D, 0, 0),
    (0x608A, 0, 0xAC), (0x608C, 0, 0xA4), (0x608E, 0, 0xA3),
])
def test_7_hdt_single_value_ranges_are_enforced(index, sub, value):
    manual_says(HDT_TEXT, 4889, "Note: only the linear interpolation is supported at the moment")
    manual_says(HDT_TEXT, 4959, "For our Drives sub-index 2 is\na readonly variable fixed to -3")
    manual_says(HDT_TEXT, 3161, "For our Drives this value is fixed to 0")
    manual_says(HDT_TEXT, 3168, "For our Drives this parameter is fixed to ACh")
    e = entry("hdt", index, sub)
    assert (e.minimum, e.maximum) == (value, value)
    d = at("hdt")
    size = e.byte_size
    w(d, index, sub, value, size)
    other = value - 3 if value > 0 else value + 1
    assert code_of(w, d, index, sub, other, size) in (VALUE_TOO_HIGH, VALUE_TOO_LOW)


def test_7_hdt_60c2_sub2_minus6_is_refused_and_the_cycle_stays_in_ms():
    d = at("hdt")
    assert code_of(w, d, 0x60C2, 2, -6, 1) == VALUE_TOO_LOW
    assert r(d, 0x60C2, 2, signed=True) == -3


# 8 -------------------------------------------------------------------------------------------------------
CT_TO_OP = [("6.42", 0), ("6.43", 1), ("3.22", 0), ("3.23", 1), ("3.13", 0), ("2.10", 1), ("2.20", 1), ("2.02", 1),
            ("1.04", 0), ("1.21", 0), ("1.38", 0), ("1.08", 0), ("1.10", 1), ("1.09", 0), ("1.15", 1), ("1.14", 3)]


@pytest.mark.parametrize("product, open_loop", [("unidrive-sp", False), ("commander-sk", True)])
def test_8_controltechniques_safeop_to_op_writes_all_sixteen_parameters(product, open_loop):
    manual_says(CT_TEXT, 1473, "- Pr **3.13** to OFF (0) (In open-loop operating modes)")
    manual_says(CT_TEXT, 1488, "- Pr **1.14** to 3")
    d = at("controltechniques", SAFE, product=product)
    d.events.clear()
    for par, _ in CT_TO_OP:
        menu, num = par.split(".")
        w(d, 0x2000 + int(menu), int(num), 7, 4)
    d.request_state(OP)
    expect = [(p, v) for p, v in CT_TO_OP if open_loop or p != "3.13"]
    writes = [(e.data["parameter"], e.data["value"]) for e in d.events if e.kind == "drive_parameter"]
    assert writes == expect
    for par, value in expect:
        menu, num = par.split(".")
        assert r(d, 0x2000 + int(menu), int(num)) == value
    if not open_loop:
        assert r(d, 0x2003, 13) == 7  # closed loop: Pr 3.13 untouched


# 9 -------------------------------------------------------------------------------------------------------
def test_9_controltechniques_605a_takes_only_the_defined_values():
    manual_says(CT_TEXT, 1500, "| Access: RW   | Range: 0 to 6   | Size: Unsigned 16 | Unit: N/A |")
    manual_says(CT_TEXT, 1505, "**Table 7.9 Quick stop value definitions**")
    manual_says(CT_TEXT, 1509, "| 2     | Slow down on quick stop ramp and transit into Switch on disabled |\n"
                               "| 5     | Slow down on slow down ramp and stay in Quick stop active        |")
    e = entry("controltechniques", 0x605A, 0)
    assert sorted(e.values or ()) == [0, 1, 2, 5, 6]
    d = at("controltechniques")
    for bad in (3, 4):
        assert code_of(w, d, 0x605A, 0, bad, 2) == INVALID_VALUE
    assert code_of(w, d, 0x605A, 0, 7, 2) == VALUE_TOO_HIGH
    w(d, 0x605A, 0, 6, 2)


# 10 ------------------------------------------------------------------------------------------------------
def test_10_controltechniques_60c1_sub0_is_not_mappable():
    manual_says(CT_TEXT, 1875, "| 0x60C1       | Interpolation_data_record ")
    e = entry("controltechniques", 0x60C1, 0)
    assert e.pdo_mapping == ""
    assert entry("controltechniques", 0x60C1, 1).pdo_mapping == "RT"
    for family in profiles.PROFILE_NAMES:
        for obj in profiles.load(family).dictionary:
            if obj.object_code.value != "VAR" and 0 in obj.entries and len(obj.entries) > 1:
                assert obj.entries[0].pdo_mapping == "", (family, hex(obj.index))


def test_value_lists_reach_the_simulator_for_every_family():
    """Value lists are a range kind of every family's builder; the drive refuses a gap with 0609 0030h."""
    for family in profiles.PROFILE_NAMES:
        dev = profiles.load(family)
        # 6060h is the mode handler's: 0 ("no mode") passes, other gaps abort there (tests/sim/test_sim_families.py)
        listed = [(o.index, e) for o in dev.dictionary for e in o.entries.values() if e.values and o.index != 0x6060]
        for index, e in listed:
            gaps = [v for v in range(int(e.minimum or 0), int(e.maximum or 0) + 1) if v not in e.values]
            if not gaps or not e.access.write or EcState.PREOP not in e.access.write:
                continue
            d = Drive.from_device(dev)
            d.request_state(PRE)
            assert code_of(w, d, index, e.subindex, gaps[0], e.byte_size) == INVALID_VALUE, (family, hex(index))
