"""The simulator against the Technosoft iPOS oracles (reference/technosoft/oracles.md)."""

from __future__ import annotations

from fractions import Fraction

import pytest

from ecattool.errors import TargetError

from ecattool.errors import SdoAbort, SdoTimeout, StateChangeError
from ecattool.od.model import EcState
from ecattool.sim import Cia402State, Drive, FoeError, decode_statusword
from tests.conftest import corpus_path

#: the manuals' exact timings and traces: the ideal plant (actual = demand; issue 33)
pytestmark = pytest.mark.usefixtures("ideal_plant")

PRE, SAFE, OP = EcState.PREOP, EcState.SAFEOP, EcState.OP


def drive(revision: str = "F515K", **kw) -> Drive:
    d = Drive.from_profile("technosoft-ipos", revision=revision, **kw)
    d.request_state(PRE)
    return d


def w(d: Drive, index: int, sub: int, value: int, size: int) -> None:
    d.sdo_download(index, sub, value.to_bytes(size, "little", signed=value < 0))


def r(d: Drive, index: int, sub: int = 0, signed: bool = False) -> int:
    return int.from_bytes(d.sdo_upload(index, sub), "little", signed=signed)


def remap(d: Drive, pdo: int, *entries: int) -> None:
    """Disable ``pdo``, write its entries, enable it (sub-index 0 := count), as §2.4 prescribes."""
    w(d, pdo, 0, 0, 1)
    for s, v in enumerate(entries, start=1):
        w(d, pdo, s, v, 4)
    w(d, pdo, 0, len(entries), 1)


def to_op(d: Drive) -> None:
    d.request_state(SAFE)
    d.request_state(OP)


def aborts(code: int, fn, *args) -> None:
    with pytest.raises(SdoAbort) as exc:
        fn(*args)
    assert exc.value.code == code, hex(exc.value.code)


# --- B. PDO mapping ------------------------------------------------------------------------------
def test_oracle_14_default_mappings_and_assignment():
    d = drive()
    assert [r(d, 0x1600, s) for s in (1, 2)] == [0x60400010, 0x607A0020]
    assert [r(d, 0x1601, s) for s in (1, 2)] == [0x60FE0120, 0x60FE0220]
    assert [r(d, 0x1602, s) for s in (1, 2)] == [0x60600008, 0x60710010]
    assert [r(d, 0x1603, s) for s in (1, 2)] == [0x60810020, 0x60830020]
    assert [r(d, 0x1A00, s) for s in (1, 2, 3)] == [0x60410010, 0x60640020, 0x60770010]
    assert r(d, 0x1C12, 0) == 1 and r(d, 0x1C12, 1) == 0x1600
    assert r(d, 0x1C13, 0) == 2 and [r(d, 0x1C13, s) for s in (1, 2)] == [0x1A00, 0x1A01]


def test_default_mapping_reaches_op_after_reset():
    d = drive()
    to_op(d)
    assert d.process_image_sizes() == (6, 16)  # 48-bit RxPDO1; 64 + 64-bit TxPDO1/2


def test_oracle_15_rxpdo3_example():
    d = drive()
    for idx, sub, val, size in [(0x1C12, 0, 0, 1), (0x1602, 0, 0, 1), (0x1602, 1, 0x60400010, 4),
                                (0x1602, 2, 0x60600008, 4), (0x1602, 0, 2, 1), (0x1C12, 3, 0x1602, 2), (0x1C12, 0, 3, 1)]:
        w(d, idx, sub, val, size)
    to_op(d)
    assert d.process_image_sizes()[0] == 6 + 3  # RPDO1 48 bits + RPDO3 24 bits


def test_oracle_16_txpdo4_example():
    d = drive()
    for idx, sub, val, size in [(0x1C13, 0, 0, 1), (0x1A03, 0, 0, 1), (0x1A03, 1, 0x60640020, 4),
                                (0x1A03, 2, 0x60FD0020, 4), (0x1A03, 0, 2, 1), (0x1C13, 4, 0x1A03, 2), (0x1C13, 0, 4, 1)]:
        w(d, idx, sub, val, size)
    to_op(d)
    assert d.process_image_sizes()[1] == 8 + 8 + 8  # TPDO1, TPDO2, TPDO4 (64 bits each)


def test_oracle_17_ip_mapping():
    d = drive()
    w(d, 0x1C12, 0, 0, 1)
    for idx, sub, val, size in [(0x1602, 0, 0, 1), (0x1602, 1, 0x60C10120, 4), (0x1602, 2, 0x60C10220, 4),
                                (0x1602, 0, 2, 1), (0x1C12, 3, 0x1602, 2), (0x1C12, 0, 3, 1)]:
        w(d, idx, sub, val, size)
    to_op(d)
    assert d.process_image_sizes()[0] == 6 + 8


def test_oracle_18_csv_mapping():
    d = drive()
    for idx, sub, val, size in [(0x1C12, 0, 0, 1), (0x1603, 0, 0, 1), (0x1603, 1, 0x60FF0020, 4), (0x1603, 0, 1, 1),
                                (0x1C12, 3, 0x1603, 2), (0x1C12, 0, 3, 1)]:
        w(d, idx, sub, val, size)
    to_op(d)
    assert d.process_image_sizes()[0] == 6 + 4


def test_oracle_19_cst_assignment():
    d = drive()
    for idx, sub, val, size in [(0x1C12, 0, 0, 1), (0x1C12, 3, 0x1602, 2), (0x1C12, 0, 3, 1)]:
        w(d, idx, sub, val, size)
    to_op(d)
    assert d.process_image_sizes()[0] == 6 + 3


def test_oracle_20_48_bit_examples_accepted():
    d = drive()
    w(d, 0x1C12, 0, 0, 1)
    remap(d, 0x1601, 0x60B80010, 0x20920120)
    w(d, 0x1C13, 0, 0, 1)
    remap(d, 0x1A02, 0x60B90010, 0x60BA0020)
    assert r(d, 0x1601, 0) == 2 and r(d, 0x1A02, 0) == 2


def test_72_bit_pdo_refused_with_0604_0042():
    d = drive()
    w(d, 0x1C12, 0, 0, 1)
    w(d, 0x1601, 0, 0, 1)
    for s, v in enumerate((0x607A0020, 0x60FF0020, 0x60600008), start=1):
        w(d, 0x1601, s, v, 4)
    aborts(0x06040042, w, d, 0x1601, 0, 3, 1)


def test_72_bit_pdo_lenient_mode_emcy_8220_and_safeop_refused():
    d = drive(strict_pdo_length=False)
    w(d, 0x1C12, 0, 0, 1)
    w(d, 0x1601, 0, 0, 1)
    for s, v in enumerate((0x607A0020, 0x60FF0020, 0x60600008), start=1):
        w(d, 0x1601, s, v, 4)
    w(d, 0x1601, 0, 3, 1)
    w(d, 0x1C12, 2, 0x1601, 2)
    w(d, 0x1C12, 0, 2, 1)
    with pytest.raises(StateChangeError) as exc:
        d.request_state(SAFE)
    assert exc.value.al_status == 0x001D
    assert d.emergencies[-1].code == 0x8220


def test_unmappable_object_refused_0604_0041():
    d = drive()
    w(d, 0x1C12, 0, 0, 1)
    w(d, 0x1601, 0, 0, 1)
    aborts(0x06040041, w, d, 0x1601, 1, 0x20660020, 4)  # 2066h: PDO mapping "No"


def test_wrong_entry_length_refused_0604_0041():
    d = drive()
    w(d, 0x1C12, 0, 0, 1)
    w(d, 0x1601, 0, 0, 1)
    aborts(0x06040041, w, d, 0x1601, 1, 0x60400020, 4)  # controlword is 16 bits


def test_missing_object_in_mapping_refused_0602_0000():
    d = drive()
    w(d, 0x1C12, 0, 0, 1)
    w(d, 0x1601, 0, 0, 1)
    aborts(0x06020000, w, d, 0x1601, 1, 0x5FFF0010, 4)


def test_mapping_write_while_enabled_refused_0800_0022():
    d = drive()
    w(d, 0x1C12, 0, 0, 1)
    aborts(0x08000022, w, d, 0x1601, 1, 0x60400010, 4)  # 1601h sub0 = 2


def test_mapping_write_while_assigned_refused():
    d = drive()
    aborts(0x08000022, w, d, 0x1600, 0, 0, 1)


def test_assignment_write_needs_sub0_zero():
    d = drive()
    aborts(0x08000022, w, d, 0x1C12, 2, 0x1601, 2)


def test_dummies_only_in_rxpdos():
    d = drive()
    w(d, 0x1C12, 0, 0, 1)
    w(d, 0x1C13, 0, 0, 1)
    remap(d, 0x1601, 0x207D0008, 0x00050008)
    w(d, 0x1A03, 0, 0, 1)
    aborts(0x06040041, w, d, 0x1A03, 1, 0x207D0008, 4)


def test_pdo_mapping_changes_only_in_preop():
    d = drive()
    d.request_state(SAFE)
    aborts(0x08000022, w, d, 0x1C12, 0, 0, 1)


def test_preop_to_op_jump_refused_0011():
    d = drive()
    with pytest.raises(StateChangeError) as exc:
        d.request_state(OP)
    assert exc.value.al_status == 0x0011
    assert d.state() is PRE


# --- C. controlword / statusword / modes ----------------------------------------------------------
def test_oracle_21_23_state_machine():
    d = drive()
    to_op(d)
    assert decode_statusword(r(d, 0x6041)) is Cia402State.SWITCH_ON_DISABLED
    w(d, 0x6040, 0, 0x06, 2)
    assert r(d, 0x6041) & 0x6F == 0x21
    w(d, 0x6040, 0, 0x07, 2)
    assert r(d, 0x6041) & 0x6F == 0x23
    w(d, 0x6040, 0, 0x0F, 2)
    assert r(d, 0x6041) & 0x6F == 0x27
    w(d, 0x6040, 0, 0x02, 2)  # quick stop, 605Ah default 2 -> switch on disabled
    assert r(d, 0x6041) & 0x4F == 0x40


def test_quick_stop_option_6_stays_and_transition_16():
    d = drive()
    to_op(d)
    w(d, 0x605A, 0, 6, 2)
    for cw in (0x06, 0x07, 0x0F, 0x02):
        w(d, 0x6040, 0, cw, 2)
    assert r(d, 0x6041) & 0x6F == 0x07
    w(d, 0x6040, 0, 0x0F, 2)
    assert r(d, 0x6041) & 0x6F == 0x27


def test_fault_and_fault_reset_edge():
    d = drive()
    to_op(d)
    d.inject_fault(0x8611)
    assert r(d, 0x6041) & 0x4F == 0x08 and r(d, 0x603F) == 0x8611
    assert d.emergencies[-1].to_bytes()[:2] == b"\x11\x86"
    w(d, 0x6040, 0, 0x80, 2)
    assert r(d, 0x6041) & 0x4F == 0x40


def test_oracle_25_wrong_mode_gives_emcy_ff04():
    d = drive()
    w(d, 0x6060, 0, 2, 1)  # 2 is reserved on the iPOS
    assert d.emergencies[-1].code == 0xFF04


def test_mode_display_follows_on_enable():
    d = drive()
    to_op(d)
    w(d, 0x6060, 0, 8, 1)
    assert r(d, 0x6061) != 8
    for cw in (0x06, 0x07, 0x0F):
        w(d, 0x6040, 0, cw, 2)
    assert r(d, 0x6061) == 8


# --- D/F. units ---------------------------------------------------------------------------------
def test_oracle_33_38_velocity_16_16_via_derived_factor():
    """PU = rot (2000 IU/rot via 608Fh), VU = rpm (6096h = 60/1), T = 1 ms: 600 rpm -> 0x140000."""
    d = drive()
    w(d, 0x6092, 1, 1, 4)  # feed 1 rot per shaft rotation
    w(d, 0x6096, 1, 60, 4)
    w(d, 0x6096, 2, 1, 4)
    f = d.units.derived_factors()
    assert f["position"] == 2000
    assert f["velocity"] == Fraction(2000 * 65536, 60 * 1000)
    num, den = f["velocity"].numerator, f["velocity"].denominator
    w(d, 0x6094, 1, num, 4)
    w(d, 0x6094, 2, den, 4)
    assert int(d.units.velocity_to_internal(600)) == 0x00140000
    assert int(d.units.velocity_to_internal(150)) == 0x00050000


def test_oracle_33_acceleration_truncated_to_0x28f():
    d = drive()
    w(d, 0x6096, 1, 60, 4)
    w(d, 0x6097, 1, 1, 4)
    w(d, 0x6097, 2, 60, 4)  # AU = rot/s^2: AF = 1/60
    f = d.units.derived_factors()["acceleration"]
    w(d, 0x210F, 1, f.numerator, 4)
    w(d, 0x210F, 2, f.denominator, 4)
    from ecattool.sim.units import to_int

    assert to_int(d.units.acceleration_to_internal(5)) == 0x28F


def test_oracle_49_obsolete_radian_factor_needs_dimension_index():
    d = drive(revision="F515I")
    w(d, 0x6093, 1, 4294967295, 4)
    w(d, 0x6093, 2, 13493038, 4)
    assert d.units.position_to_internal(1) == 1  # dimension index 608Ah still 0: factor inactive
    w(d, 0x608A, 0, 1, 1)
    assert int(d.units.position_to_internal(Fraction(2)) * 1) == 636  # 2 rad = 636.6 counts
    assert abs(d.units.position_to_internal(1) - Fraction(2000) / Fraction(314159265, 50000000)) < Fraction(1, 100)


def test_csp_end_to_end_scaling_through_pdos():
    """CSP: a target in user units (mm) over the RxPDO reaches the internal position the factor says."""
    d = drive()
    w(d, 0x6093, 1, 2000, 4)
    w(d, 0x6093, 2, 5, 4)  # 5 mm per motor revolution of 2000 counts
    w(d, 0x6060, 0, 8, 1)
    to_op(d)
    for cw in (0x06, 0x07, 0x0F):
        d.exchange(cw.to_bytes(2, "little") + (0).to_bytes(4, "little"))
    inputs = d.exchange((0x0F).to_bytes(2, "little") + (10).to_bytes(4, "little", signed=True))
    assert d.internal_position == 4000
    assert int.from_bytes(inputs[2:6], "little", signed=True) == 10  # 6064h back in mm


def test_profile_position_moves_to_target():
    d = drive()
    w(d, 0x6060, 0, 1, 1)
    w(d, 0x607A, 0, 80000, 4)
    w(d, 0x6081, 0, 0x00090000, 4)  # 9.0 counts/ms (oracle 31)
    to_op(d)
    for cw in (0x06, 0x07, 0x0F, 0x1F):
        w(d, 0x6040, 0, cw, 2)
    d.step(100)
    assert d.internal_position == 900
    d.step(9000)
    assert d.internal_position == 80000
    assert r(d, 0x6041) & 0x0400


# --- G. EEPROM ------------------------------------------------------------------------------------
def test_oracle_63_2064_default():
    d = drive()
    assert r(d, 0x2064) == 0x84


def test_oracle_58_16_bit_download():
    d = drive()
    w(d, 0x2064, 0, 0x56380008, 4)
    w(d, 0x2065, 0, 0x0000C400, 4)
    w(d, 0x2065, 0, 0xABCD0000, 4)  # high word ignored in 16-bit mode
    assert d.eeprom_words(0x5638, 2) == [0xC400, 0x0000]
    assert r(d, 0x2064) >> 16 == 0x563A


def test_oracle_62_32_bit_download_and_readback():
    d = drive()
    w(d, 0x2064, 0, 0x5E060009, 4)
    w(d, 0x2065, 0, 0x56781234, 4)
    w(d, 0x2065, 0, 0xCDEF09AB, 4)
    assert d.eeprom_words(0x5E06, 4) == [0x1234, 0x5678, 0x09AB, 0xCDEF]
    w(d, 0x2064, 0, 0x5E060009, 4)
    assert r(d, 0x2066) == 0x56781234 and r(d, 0x2066) == 0xCDEF09AB  # reads auto-increment


def test_oracle_64_2067_write_at_address():
    d = drive()
    w(d, 0x2064, 0, 0x00000008, 4)  # EEPROM memory type
    w(d, 0x2067, 0, 0x036A1234, 4)
    assert d.eeprom_words(0x036A, 1) == [0x1234]


def test_oracle_65_checksum_inclusive_end():
    d = drive()
    w(d, 0x2064, 0, 0x5E060009, 4)
    w(d, 0x2065, 0, 0x56781234, 4)
    w(d, 0x2065, 0, 0xCDEF09AB, 4)
    w(d, 0x2069, 0, 0x5E095E06, 4)
    assert r(d, 0x206A) == 0x4046


def test_oracle_60_checksum_request_range():
    d = drive()
    w(d, 0x2064, 0, 0x00000008, 4)
    w(d, 0x2067, 0, 0x5EFF0001, 4)  # last word of the range counts
    w(d, 0x2067, 0, 0x5F000100, 4)  # one past does not
    for a in range(0x5E06, 0x5EFF):
        d.memory.eeprom[a] = 0
    w(d, 0x2069, 0, 0x5EFF5E06, 4)
    assert r(d, 0x206A) == 0x0001


def test_eeprom_lock_refuses_writes():
    d = drive()
    w(d, 0x2091, 0, 1, 1)
    w(d, 0x2064, 0, 0x5E060008, 4)
    aborts(0x08000020, w, d, 0x2065, 0, 0x1234, 4)
    assert r(d, 0x2091) == 1
    w(d, 0x2091, 0, 0, 1)
    w(d, 0x2065, 0, 0x1234, 4)


def test_reset_2080_has_no_reply_and_keeps_eeprom():
    d = drive()
    w(d, 0x2064, 0, 0x5E060008, 4)
    w(d, 0x2065, 0, 0x1234, 4)
    w(d, 0x6060, 0, 8, 1)
    with pytest.raises(SdoTimeout):
        w(d, 0x2080, 0, 1, 2)
    assert r(d, 0x6060) == 0  # RAM back to defaults
    assert d.eeprom_words(0x5E06, 1) == [0x1234]  # setup kept
    d.sdo_download(0x2080, 0, b"\x01\x00", expect_reply=False)
    assert any(e.kind == "reset" for e in d.events)


def test_power_loss_during_eeprom_write():
    d = drive()
    w(d, 0x2064, 0, 0x5E060009, 4)
    d.faults.power_loss_during_eeprom_write(after_words=3)
    w(d, 0x2065, 0, 0x56781234, 4)
    with pytest.raises(SdoTimeout):
        w(d, 0x2065, 0, 0xCDEF09AB, 4)
    assert d.state() is EcState.INIT
    assert d.eeprom_words(0x5E06, 4) == [0x1234, 0x5678, 0x09AB, 0xFFFF]


def test_power_loss_during_an_eeprom_write_over_process_data():
    # 2065h mapped in an RxPDO (manual §17: EEPROM data through PDOs); the drive drops off the bus
    d = drive()
    w(d, 0x2064, 0, 0x5E060009, 4)
    w(d, 0x1C12, 0, 0, 1)
    w(d, 0x1600, 0, 0, 1)
    w(d, 0x1600, 1, 0x20650020, 4)
    w(d, 0x1600, 0, 1, 1)
    w(d, 0x1C12, 1, 0x1600, 2)
    w(d, 0x1C12, 0, 1, 1)
    d.request_state(EcState.SAFEOP)
    d.request_state(EcState.OP)
    d.exchange((0x56781234).to_bytes(4, "little"))
    d.faults.power_loss_during_eeprom_write(after_words=1)
    with pytest.raises(TargetError, match="lost power"):
        d.exchange((0xCDEF09AB).to_bytes(4, "little"))
    assert d.state() is EcState.INIT
    assert d.eeprom_words(0x5E06, 3) == [0x1234, 0x5678, 0x09AB]
    assert any(e.kind == "power_loss" for e in d.events)


# --- A11 / FoE ------------------------------------------------------------------------------------
def test_oracle_11_foe_setup_names():
    d = drive()
    image = (0x5E06).to_bytes(2, "little") + (2).to_bytes(2, "little") + bytes.fromhex("34127856")
    d.foe_write("FOESW_AXIS01.bin", image)
    assert d.eeprom_words(0x5E06, 2) == [0x1234, 0x5678]
    with pytest.raises(FoeError):
        d.foe_write("FOESW_AXIS0123X", image)
    with pytest.raises(FoeError):
        d.foe_write("SETUP_AXIS01", image)
    with pytest.raises(FoeError):
        d.foe_write("FOESW_AXIS01", image, password=0x35313546)


def test_foe_setup_in_boot_needs_210c():
    d = drive()
    d.request_state(EcState.INIT)
    d.request_state(EcState.BOOT)
    with pytest.raises(FoeError):
        d.foe_write("FOESW_A", b"")
    d.foe_write("FOEFW_F515G.foe", b"\x00" * 4, password=0x35313546)


def test_foe_corpus_setup_image_checksum():
    """A real FoE setup image: its blocks land in the EEPROM and 2069h/206Ah confirm each block's sum."""
    data = corpus_path("sw", "ecmc_ipos8020BX_FOESW_8020.bin").read_bytes()
    d = drive()
    d.foe_write("FOESW_8020.bin", data)
    from ecattool.sim.eeprom import parse_foe_setup

    for start, words in parse_foe_setup(data):
        w(d, 0x2069, 0, ((start + len(words) - 1) << 16) | start, 4)
        assert r(d, 0x206A) == sum(words) & 0xFFFF


def test_oracle_80_value_range_and_write_only():
    d = drive()
    aborts(0x06090032, w, d, 0x2006, 0, 0, 2)  # 2006h range 1..10
    aborts(0x06090031, w, d, 0x2006, 0, 11, 2)
    w(d, 0x2006, 0, 10, 2)
    aborts(0x06010001, d.sdo_upload, 0x2065, 0)  # write-only
    aborts(0x06010002, w, d, 0x2066, 0, 0, 4)  # read-only
    aborts(0x06070013, d.sdo_download, 0x2064, 0, b"\x08\x00")
