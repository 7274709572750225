"""Printed oracles (reference/<family>/oracles.md) answered by the simulator over SDO.

tests/profiles/test_profiles_*.py check the built-in dictionaries; issue 3 asks that the *simulated drive* gives the
printed values too. Every row names its oracle (TS = technosoft, HDT = hdt, CT = controltechniques); the
index of oracles to tests is tests/ORACLES.md.
"""

from __future__ import annotations


import pytest

from ecattool.od.model import EcState
from ecattool.sim import Drive
from ecattool.sim.cia402 import State, decode_statusword
from tests.sim.sim_helpers import OP, PRE, SAFE, at, code_of, r, w  # noqa: F401

TS, HDT, CT = "technosoft-ipos", "hdt", "controltechniques"

#: (oracle, profile, load options, index, sub, printed value); a negative value is read as signed.
DEFAULTS: list[tuple[str, str, dict[str, str], int, int, int]] = [
    # --- Technosoft iPOS
    ("TS-1", TS, {"revision": "F515I"}, 0x1018, 3, 892417353),
    ("TS-6", TS, {"product": "ipos4808-my-cat-sto"}, 0x1018, 2, 27314121),
    ("TS-7", TS, {"product": "ipos360x-vx-cat"}, 0x1018, 2, 28002021),
    ("TS-7", TS, {"product": "ipos4808-bx-cat-sto"}, 0x1018, 2, 27314221),
    ("TS-8", TS, {}, 0x1018, 1, 0x000001A3),
    ("TS-14", TS, {}, 0x1C12, 0, 1),
    ("TS-14", TS, {}, 0x1C13, 0, 2),
    ("TS-14", TS, {}, 0x1C13, 1, 0x1A00),
    ("TS-14", TS, {}, 0x1C13, 2, 0x1A01),
    ("TS-14", TS, {}, 0x1C00, 0, 4),
    ("TS-14", TS, {}, 0x1C00, 1, 1),
    ("TS-14", TS, {}, 0x1C00, 2, 2),
    ("TS-14", TS, {}, 0x1C00, 3, 3),
    ("TS-14", TS, {}, 0x1A01, 1, 0x60F40020),
    ("TS-14", TS, {}, 0x1A01, 2, 0x60FD0020),
    ("TS-14", TS, {}, 0x1A02, 1, 0x606C0020),
    ("TS-14", TS, {}, 0x1A03, 1, 0x60610008),
    ("TS-26", TS, {}, 0x6502, 0, 0x001C03E5),
    ("TS-41", TS, {}, 0x6099, 1, 0x00010000),
    ("TS-41", TS, {}, 0x6099, 2, 0x00010000),
    ("TS-41", TS, {}, 0x609A, 0, 0x0000199A),
    ("TS-41", TS, {}, 0x608F, 1, 2000),
    ("TS-51", TS, {}, 0x60A8, 0, 0x00B50100),
    ("TS-63", TS, {}, 0x2064, 0, 0x84),
    ("TS-67", TS, {}, 0x201A, 0, 0x9E00),
    ("TS-69", TS, {}, 0x206B, 0, 0x00010000),
    ("TS-69", TS, {}, 0x206C, 0, 0x00010000),
    ("TS-70", TS, {}, 0x2013, 1, 1),
    ("TS-70", TS, {}, 0x2013, 2, 1),
    ("TS-77", TS, {}, 0x2109, 0, 1000),
    ("TS-77", TS, {}, 0x210A, 0, 3),
    ("TS-77", TS, {}, 0x2082, 0, 0),
    ("TS-77", TS, {}, 0x208E, 0, 0x0100),
    ("TS-77", TS, {}, 0x2012, 0, 0x80000001),
    ("TS-77", TS, {"revision": "FA00G"}, 0x2114, 0, 32768),
    ("TS-77", TS, {"revision": "FA00G"}, 0x2113, 15, 32768),
    # --- HDT
    ("HDT-1", HDT, {}, 0x1000, 0, 0x00020192),
    ("HDT-2", HDT, {}, 0x1018, 1, 0x00000289),
    ("HDT-3", HDT, {}, 0x1018, 2, 0x000C0458),
    ("HDT-6", HDT, {}, 0x100C, 0, 100),
    ("HDT-6", HDT, {}, 0x100D, 0, 2),
    ("HDT-9", HDT, {}, 0x1400, 2, 0),
    ("HDT-9", HDT, {}, 0x1403, 2, 0),
    ("HDT-9", HDT, {}, 0x1800, 2, 0),
    ("HDT-9", HDT, {}, 0x1803, 2, 0),
    ("HDT-10", HDT, {}, 0x1601, 0, 2),
    ("HDT-10", HDT, {}, 0x1601, 1, 0x607A0020),
    ("HDT-10", HDT, {}, 0x1601, 2, 0x60810020),
    ("HDT-10", HDT, {}, 0x1602, 0, 2),
    ("HDT-10", HDT, {}, 0x1602, 1, 0x60830020),
    ("HDT-10", HDT, {}, 0x1602, 2, 0x60840020),
    ("HDT-10", HDT, {}, 0x1600, 4, 0),
    ("HDT-11", HDT, {}, 0x1A01, 0, 2),
    ("HDT-11", HDT, {}, 0x1A01, 1, 0x60620020),
    ("HDT-11", HDT, {}, 0x1A01, 2, 0x60640020),
    ("HDT-11", HDT, {}, 0x1A02, 0, 2),
    ("HDT-11", HDT, {}, 0x1A02, 1, 0x60430010),
    ("HDT-11", HDT, {}, 0x1A02, 2, 0x60440010),
    ("HDT-11", HDT, {}, 0x1A03, 0, 1),
    ("HDT-11", HDT, {}, 0x1A03, 1, 0x60FD0020),
    ("HDT-16", HDT, {}, 0x1C32, 4, 7),
    ("HDT-22", HDT, {}, 0x200F, 0, 0x025A),
    ("HDT-23", HDT, {}, 0x2037, 0, 120),
    ("HDT-26", HDT, {}, 0x6060, 0, 2),
    ("HDT-28", HDT, {}, 0x604E, 0, 3000),
    ("HDT-28", HDT, {}, 0x6050, 0, 1000),
    ("HDT-28", HDT, {}, 0x6051, 0, 1000),
    ("HDT-30", HDT, {}, 0x6046, 1, 0),
    ("HDT-30", HDT, {}, 0x6046, 2, 5000),
    ("HDT-31", HDT, {}, 0x6048, 1, 1000),
    ("HDT-31", HDT, {}, 0x6048, 2, 1),
    ("HDT-32", HDT, {}, 0x6093, 1, 65536),
    ("HDT-32", HDT, {}, 0x6093, 2, 65536),
    ("HDT-32", HDT, {}, 0x6094, 1, 65536),
    ("HDT-32", HDT, {}, 0x6094, 2, 60),
    ("HDT-32", HDT, {}, 0x6097, 1, 65536),
    ("HDT-32", HDT, {}, 0x6097, 2, 60),
    ("HDT-32", HDT, {}, 0x604C, 1, 1),
    ("HDT-32", HDT, {}, 0x604C, 2, 1),
    ("HDT-32", HDT, {}, 0x6089, 0, 0),
    ("HDT-32", HDT, {}, 0x608A, 0, 0xAC),
    ("HDT-32", HDT, {}, 0x608B, 0, 0),
    ("HDT-32", HDT, {}, 0x608C, 0, 0xA4),
    ("HDT-32", HDT, {}, 0x608D, 0, 0),
    ("HDT-32", HDT, {}, 0x608E, 0, 0xA3),
    ("HDT-32", HDT, {}, 0x607E, 0, 0),
    ("HDT-36", HDT, {}, 0x6065, 0, 910),
    ("HDT-41", HDT, {}, 0x2011, 0, 100000),
    ("HDT-42", HDT, {}, 0x60C2, 1, 2),
    ("HDT-42", HDT, {}, 0x60C2, 2, -3),
    ("HDT-43", HDT, {}, 0x2001, 0, 100),
    ("HDT-44", HDT, {}, 0x2006, 0, 2000),
    ("HDT-54", HDT, {}, 0x201B, 0, 0x5A),
    ("HDT-55", HDT, {}, 0x2076, 0, 0x0F),
    ("HDT-57", HDT, {}, 0x2077, 0, 0),
    ("HDT-57", HDT, {}, 0x2078, 0, 1),
    ("HDT-57", HDT, {}, 0x2079, 0, 2),
    ("HDT-57", HDT, {}, 0x2080, 0, 0),
    ("HDT-57", HDT, {}, 0x2081, 0, 0),
    # --- Control Techniques (Unidrive SP unless a drive is named)
    ("CT-13", CT, {}, 0x1600, 0, 1),
    ("CT-13", CT, {}, 0x1601, 0, 2),
    ("CT-13", CT, {}, 0x1605, 0, 2),
    ("CT-13", CT, {}, 0x1615, 0, 0),
    ("CT-13", CT, {}, 0x1A00, 0, 1),
    ("CT-13", CT, {}, 0x1A01, 0, 2),
    ("CT-13", CT, {}, 0x1A02, 0, 2),
    ("CT-13", CT, {}, 0x1A05, 0, 2),
    ("CT-13", CT, {}, 0x1A15, 0, 0),
    ("CT-16", CT, {"product": "unidrive-sp"}, 0x1000, 0, 0x00020192),
    ("CT-16", CT, {"product": "digitax-st"}, 0x1000, 0, 0x00020192),
    ("CT-16", CT, {"product": "mentor-mp"}, 0x1000, 0, 0x00010192),
    ("CT-17", CT, {}, 0x1018, 0, 4),
    ("CT-17", CT, {}, 0x1018, 1, 0x000000F9),
    ("CT-17", CT, {}, 0x1018, 2, 0x000001A5),
    ("CT-17", CT, {"revision": "01.01.00"}, 0x1018, 3, 0x00650000),
    ("CT-18", CT, {"revision": "01.01.00"}, 0x200F, 2, 101),
    ("CT-18", CT, {"revision": "01.01.00"}, 0x200F, 51, 0),
    ("CT-28", CT, {}, 0x6060, 0, 2),
    ("CT-29", CT, {}, 0x605A, 0, 2),
    ("CT-29", CT, {}, 0x6085, 0, 2),
    ("CT-30", CT, {}, 0x6091, 1, 1),
    ("CT-30", CT, {}, 0x6091, 2, 1),
    ("CT-30", CT, {}, 0x6092, 1, 1),
    ("CT-30", CT, {}, 0x6092, 2, 1),
    ("CT-32", CT, {}, 0x60FB, 1, 2500),
    ("CT-32", CT, {}, 0x60FB, 2, 1000),
    ("CT-33", CT, {}, 0x6080, 0, 3000),
    ("CT-34", CT, {}, 0x6084, 0, 65536),
    ("CT-35", CT, {}, 0x60C2, 1, 250),
    ("CT-35", CT, {}, 0x60C2, 2, -6),
    ("CT-37", CT, {}, 0x60C0, 0, 0),
    ("CT-41", CT, {}, 0x6042, 0, 0),
    ("CT-41", CT, {}, 0x6046, 1, 0),
    ("CT-41", CT, {}, 0x6046, 2, 2147483647),
    ("CT-41", CT, {}, 0x6047, 1, 0),
    ("CT-41", CT, {}, 0x6047, 2, 2147483647),
    ("CT-41", CT, {}, 0x6047, 3, 0),
    ("CT-41", CT, {}, 0x6047, 4, 2147483647),
    ("CT-41", CT, {}, 0x6048, 1, 1000),
    ("CT-41", CT, {}, 0x6048, 2, 2),
    ("CT-41", CT, {}, 0x6049, 1, 1000),
    ("CT-41", CT, {}, 0x6049, 2, 2),
    ("CT-41", CT, {}, 0x604A, 1, 1000),
    ("CT-41", CT, {}, 0x604A, 2, 2),
    ("CT-41", CT, {}, 0x604B, 1, 1),
    ("CT-41", CT, {}, 0x604B, 2, 1),
    ("CT-41", CT, {}, 0x604C, 1, 1),
    ("CT-41", CT, {}, 0x604C, 2, 1),
    ("CT-48", CT, {}, 0x2803, 1, 5),
    ("CT-49", CT, {}, 0x2813, 1, 0),
    ("CT-53", CT, {}, 0x1001, 0, 0),
    ("CT-57", CT, {}, 0x200F, 1, 421),
]


@pytest.mark.parametrize("oracle,name,options,index,sub,expected", DEFAULTS,
                         ids=[f"{o}-{i:04X}:{s}-{'-'.join(kw.values())}" for o, _, kw, i, s, _v in DEFAULTS])
def test_printed_value_read_back_over_sdo(oracle, name, options, index, sub, expected):
    d = at(name, **options)
    assert r(d, index, sub, signed=expected < 0) == expected, oracle


def test_hdt_63_67_screenshot_defaults_over_sdo():
    """HDT-63/67: every Caliper screenshot default the dictionary tests check is what the NTT answers."""
    from tests.profiles.test_profiles_hdt import SCREEN_DEFAULTS

    d = at(HDT, product="ntt")
    wrong = {f"{i:04X}:{s}": (r(d, i, s, signed=v < 0), v) for (i, s), v in SCREEN_DEFAULTS.items()
             if r(d, i, s, signed=v < 0) != v}
    assert not wrong and len(SCREEN_DEFAULTS) > 80


# --- controlword / statusword, the same table in all three manuals ----------------------------------------
@pytest.mark.parametrize("name", [TS, HDT, CT])
def test_ts21_23_hdt24_25_ct24_25_controlword_commands(name):
    d = at(name, OP)
    state = lambda: decode_statusword(r(d, 0x6041))  # noqa: E731
    assert state() is State.SWITCH_ON_DISABLED
    w(d, 0x6040, 0, 0x0006, 2)  # shutdown
    assert state() is State.READY
    w(d, 0x6040, 0, 0x0007, 2)  # switch on
    assert state() is State.SWITCHED_ON
    w(d, 0x6040, 0, 0x000F, 2)  # enable operation
    assert state() is State.OPERATION_ENABLED
    w(d, 0x6040, 0, 0x0007, 2)  # disable operation
    assert state() is State.SWITCHED_ON
    w(d, 0x6040, 0, 0x0000, 2)  # disable voltage
    assert state() is State.SWITCH_ON_DISABLED
    for cw in (0x06, 0x07, 0x0F):
        w(d, 0x6040, 0, cw, 2)
    w(d, 0x6040, 0, 0x0002, 2)  # quick stop; 605Ah default 2 (TS, CT) / 0 (HDT): ends switch on disabled
    assert state() is State.SWITCH_ON_DISABLED
    d.inject_fault(0x8611)
    assert state() is State.FAULT
    w(d, 0x6040, 0, 0x0000, 2)
    w(d, 0x6040, 0, 0x0080, 2)  # fault reset: rising edge of bit 7
    assert state() is State.SWITCH_ON_DISABLED


@pytest.mark.parametrize("sw,state", [
    (0x0250, State.SWITCH_ON_DISABLED), (0x0237, State.OPERATION_ENABLED), (0x0233, State.SWITCHED_ON),
    (0x0231, State.READY), (0x0217, State.QUICK_STOP), (0x0218, State.FAULT),
    (0x0000, State.NOT_READY), (0x000F, State.FAULT_REACTION), (0x0008, State.FAULT), (0x0040, State.SWITCH_ON_DISABLED),
])
def test_ct25_ts23_hdt25_statusword_examples(sw, state):
    assert decode_statusword(sw) is state


# --- Technosoft ---------------------------------------------------------------------------------------
def test_ts25_modes_egear_ecam_and_csp_accepted():
    d = at(TS, revision="F515K")
    for mode in (1, 3, 4, 6, 7, 8, 9, 10, -1, -2):
        w(d, 0x6060, 0, mode, 1)
        assert r(d, 0x6060, signed=True) == mode


def test_ts30_sync_test_outputs_2089():
    d = at(TS)
    for v in (7, 0):
        w(d, 0x2089, 0, v, 2)
        assert r(d, 0x2089) == v
    assert code_of(w, d, 0x2089, 0, 8, 2) == 0x06090031


def test_ts42_csp_interpolation_period_4_ms():
    d = at(TS)
    w(d, 0x60C2, 1, 4, 1)
    w(d, 0x60C2, 2, -3, 1)
    assert (r(d, 0x60C2, 1), r(d, 0x60C2, 2, signed=True)) == (4, -3)


# --- HDT ----------------------------------------------------------------------------------------------
def test_hdt7_store_parameters_answers_and_accepts_save():
    d = at(HDT)
    for sub in (1, 2, 3):
        d.sdo_download(0x1010, sub, b"save")  # 65766173h: bytes 73 61 76 65 on the wire
        assert code_of(w, d, 0x1010, sub, 0x73617665, 4) == 0x08000020  # the bytes as the doc shows them


# --- Control Techniques ---------------------------------------------------------------------------------
def test_ct28_undefined_modes_refused():
    d = at(CT)
    for mode in (1, 3, 5):
        assert code_of(w, d, 0x6060, 0, mode, 1) == 0x06090030
    for mode in (0, 2, 4, 6, 7, 8):
        w(d, 0x6060, 0, mode, 1)
        assert r(d, 0x6060) == mode


def test_ct29_quick_stop_option_codes():
    d = at(CT)
    for v in (0, 1, 2, 5, 6):
        w(d, 0x605A, 0, v, 2)
        assert r(d, 0x605A) == v
    assert code_of(w, d, 0x605A, 0, 7, 2) in (0x06090030, 0x06090031)


@pytest.mark.parametrize("period", [(250, -6), (25, -5), (50, -5), (5, -4), (1, -3), (10, -4), (100, -5),
                                    (2, -3), (20, -4), (200, -5), (15, -3)])
def test_ct35_valid_interpolation_periods(period):
    """Each write is checked with the other sub-index as stored, so the way there passes through k x 1 ms:
    (250, -3) = 250 ms, (base, -3) = base ms, then the exponent."""
    d = at(CT)
    w(d, 0x60C2, 2, -3, 1)
    w(d, 0x60C2, 1, period[0], 1)
    w(d, 0x60C2, 2, period[1], 1)
    assert (r(d, 0x60C2, 1), r(d, 0x60C2, 2, signed=True)) == period


@pytest.mark.parametrize("period", [(100, -6), (75, -5), (3, -4)])
def test_ct35_invalid_interpolation_periods(period):
    d = at(CT)
    w(d, 0x60C2, 2, -3, 1)
    w(d, 0x60C2, 1, period[0], 1)  # period[0] ms: valid on the way
    assert code_of(w, d, 0x60C2, 2, period[1], 1) == 0x06090030
    assert (r(d, 0x60C2, 1), r(d, 0x60C2, 2, signed=True)) == (period[0], -3)


def test_ct38_exponent_below_minus_6():
    d = at(CT)
    assert code_of(w, d, 0x60C2, 2, -7, 1) == 0x06090032


def test_ct37_interpolation_submode_only_linear():
    d = at(CT)
    w(d, 0x60C0, 0, 0, 2)
    assert code_of(w, d, 0x60C0, 0, 1, 2) == 0x06090031
    assert code_of(w, d, 0x60C0, 0, -1, 2) == 0x06090032


def test_ct41_vl_min_max_writes_copy_into_6047():
    d = at(CT)
    w(d, 0x6046, 2, 3000, 4)
    w(d, 0x6046, 1, 100, 4)
    assert [r(d, 0x6047, s) for s in (1, 2, 3, 4)] == [100, 3000, 100, 3000]


def test_ct46_homing_method_36_out_of_range():
    d = at(CT)
    assert code_of(w, d, 0x6098, 0, 36, 1) == 0x06090031
    w(d, 0x6098, 0, 35, 1)
    assert r(d, 0x6098) == 35


def test_ct48_homing_source_range_1_to_8():
    d = at(CT)
    for v in (7, 8, 1):
        w(d, 0x2803, 1, v, 1)
        assert r(d, 0x2803, 1) == v
    assert code_of(w, d, 0x2803, 1, 0, 1) == 0x06090032
    assert code_of(w, d, 0x2803, 1, 9, 1) == 0x06090031


# --- Technosoft profile position (§7.3): the printed 607Ah/6081h values move the simulated motor ------
def _pp_move(d: Drive, target: int, start: int, steps: int) -> None:
    w(d, 0x607A, 0, target, 4)
    w(d, 0x6040, 0, 0x000F, 2)  # bit 4 low: the next 0x1F/0x5F is a new set-point (oracle 22)
    w(d, 0x6040, 0, start, 2)
    d.step(steps)


def _pp_drive() -> Drive:
    d = at(TS)
    w(d, 0x6060, 0, 1, 1)
    w(d, 0x6081, 0, 0x0010AAAC, 4)  # 500 rpm of a 2000-count motor, as printed
    d.request_state(SAFE)
    d.request_state(OP)
    for cw in (0x06, 0x07, 0x0F):
        w(d, 0x6040, 0, cw, 2)
    return d


def test_ts22_35_absolute_trapezoid_4_then_16_rev():
    d = _pp_drive()
    _pp_move(d, 0x00001F40, 0x001F, 1000)
    assert d.internal_position == 4 * 2000
    _pp_move(d, 0x00007D00, 0x001F, 2000)
    assert d.internal_position == 16 * 2000 and r(d, 0x6041) & 0x0400


def test_ts22_34_relative_trapezoid_20_then_200_rev():
    d = _pp_drive()
    _pp_move(d, 0x00009C40, 0x005F, 3000)
    assert d.internal_position == 20 * 2000
    _pp_move(d, 0x00061A80, 0x005F, 25000)
    assert d.internal_position == 220 * 2000 and r(d, 0x6041) & 0x0400


def test_ts32_50_iu_per_ms_is_0x00320000():
    d = _pp_drive()
    w(d, 0x6081, 0, 0x00320000, 4)  # 50.00 IU = 50 counts per 1-ms slow loop
    _pp_move(d, 100000, 0x001F, 20)
    assert d.internal_position == 20 * 50


def test_hdt39_default_6093_position_equals_internal():
    d = at(HDT, OP)
    w(d, 0x6060, 0, 1, 1)
    w(d, 0x607A, 0, -98304, 4)  # -1.5 turns of 65536
    for cw in (0x06, 0x07, 0x0F, 0x1F):
        w(d, 0x6040, 0, cw, 2)
    d.step(20000)
    assert r(d, 0x6064, signed=True) == r(d, 0x6063, signed=True) == d.internal_position == -98304


def test_ct20_mm04_follows_the_esm_in_both_menus():
    """CT-20 (5.5, Table 5.6): Pr MM.04 = 1 INIT, 2 PRE-OP, 4 SAFE-OP, 8 OP (slot menu 15 and mirror menu 60)."""
    d = Drive.from_profile("controltechniques", product="digitax-st")
    seen = [(d.value(0x200F, 4), d.value(0x203C, 4))]  # in INIT there is no mailbox: read as the keypad does
    for s in (EcState.PREOP, EcState.SAFEOP, EcState.OP, EcState.SAFEOP, EcState.INIT):
        d.request_state(s)
        seen.append((d.value(0x200F, 4), d.value(0x203C, 4)))
    assert seen == [(1, 1), (2, 2), (4, 4), (8, 8), (4, 4), (1, 1)]
    for s in (EcState.PREOP, EcState.SAFEOP, EcState.OP):
        d.request_state(s)
    assert r(d, 0x200F, 4) == 8  # over SDO too
    d.lose_communication()  # the watchdog drops the module to SAFE-OP: MM.04 says so
    assert r(d, 0x200F, 4) == 4


def test_ct27_safeop_to_op_writes_the_drive_parameters_in_order():
    """CT-27 (7.3.1): on SAFE-OP -> OP the module writes Pr 6.42 = 0, 6.43 = 1, 3.22 = 0, 3.23 = 1 first (and
    the twelve of tests/profiles/test_families_manuals.py after them)."""
    d = at("controltechniques", EcState.SAFEOP, product="digitax-st")
    for index, sub, junk in ((0x2006, 42, 7), (0x2006, 43, 7), (0x2003, 22, 7), (0x2003, 23, 7)):
        w(d, index, sub, junk, 4)
    d.request_state(EcState.OP)
    assert [r(d, 0x2006, 42), r(d, 0x2006, 43), r(d, 0x2003, 22), r(d, 0x2003, 23)] == [0, 1, 0, 1]
    writes = [e.data["parameter"] for e in d.events if e.kind == "drive_parameter"]
    assert writes[:4] == ["6.42", "6.43", "3.22", "3.23"]


def test_oracle_index_names_real_tests_and_its_counts_add_up():
    """tests/ORACLES.md: every ``ABBR::test_name`` it cites exists in that file, and the counts are the rows'."""
    import re
    from collections import Counter
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    text = (root / "tests" / "ORACLES.md").read_text(encoding="utf-8")
    files = dict(re.findall(r"^\| ([A-Z]+) \| (tests/[\w/]+\.py) \|$", text, re.M))
    sources = {abbr: (root / path).read_text(encoding="utf-8") for abbr, path in files.items()}
    # a name ending in * or … stands for the tests that start with it
    cited = [(a, n + ("" if more else "(")) for a, n, more in re.findall(r"\b([A-Z]+)::(test_\w+)(\*|…)?", text)]
    missing = [f"{a}::{n}" for a, n in cited if f"def {n}" not in sources.get(a, "")]
    assert cited and not missing, missing
    rows = re.findall(r"^\| (TS|HDT|CT)-\w+ \|.*\| ([^|]+?) *\|$", text, re.M)

    def status(cell: str) -> str:  # "sim (new, partial)" counts as sim (new), "lib (file format)" as lib
        return "sim (new)" if cell.startswith("sim (new") else re.split(r"[ :(]", cell)[0]

    for family in ("TS", "HDT", "CT"):
        counted = Counter(status(cell) for fam, cell in rows if fam == family)
        line = re.search(rf"^- {family}: (.*) \(total (\d+)\)$", text, re.M)
        assert line is not None
        stated = {k: int(v) for v, k in (p.rsplit(" ", 1)[::-1] for p in line.group(1).split(", "))}
        assert stated == dict(counted) and sum(counted.values()) == int(line.group(2)), (family, counted)
