"""The simulator against the HDT and Control Techniques oracles, and the generic CoE behaviour."""

from __future__ import annotations

from fractions import Fraction

import pytest
from hypothesis import given
from hypothesis import strategies as st

from ecattool.errors import EcatToolError, SdoAbort, SdoTimeout, StateChangeError
from ecattool.od.model import EcState
from ecattool.sim import Drive
from ecattool.target import SimTarget, SlaveTarget, open_target
from tests.sim.sim_helpers import OP, PRE, SAFE, at, code_of, r, w  # noqa: F401


# --- HDT ------------------------------------------------------------------------------------------
def test_hdt_oracle_10_11_13_default_mappings_reach_op():
    d = at("hdt")
    assert [r(d, 0x1600, s) for s in range(4)] == [3, 0x60400010, 0x60420010, 0x607C0020]
    assert [r(d, 0x1603, s) for s in range(2)] == [1, 0x60C10120]
    assert [r(d, 0x1A00, s) for s in range(4)] == [3, 0x60410010, 0x60610008, 0x10010008]
    d.request_state(SAFE)
    d.request_state(OP)
    assert d.process_image_sizes() == (8 + 8 + 8 + 4, 4 + 8 + 4 + 4)


def test_hdt_oracle_14_at_most_8_entries():
    d = at("hdt")
    w(d, 0x1C12, 0, 0, 1)
    assert code_of(w, d, 0x1600, 0, 9, 1) in (0x06090031, 0x06040042)


def test_hdt_oracle_26_modes_and_display():
    d = at("hdt")
    assert r(d, 0x6060) == 2
    w(d, 0x6060, 0, 0xFE, 1)  # -2
    assert code_of(w, d, 0x6060, 0, 5, 1) == 0x06090030


def test_hdt_oracle_27_quick_stop_option_codes():
    for option, end in ((0, 0x40), (2, 0x40), (5, 0x07), (6, 0x07)):
        d = at("hdt", OP)
        w(d, 0x605A, 0, option, 2)
        for cw in (0x06, 0x07, 0x0F, 0x02):
            w(d, 0x6040, 0, cw, 2)
        sw = r(d, 0x6041)
        assert (sw & 0x4F if end == 0x40 else sw & 0x6F) == end


def test_hdt_oracle_d1_degrees_to_65536_counts():
    d = at("hdt")
    w(d, 0x6093, 1, 65536, 4)
    w(d, 0x6093, 2, 360, 4)
    assert d.units.position_to_internal(90) == 16384
    assert d.units.velocity_to_internal(1000) == Fraction(65536 * 1000, 60)  # oracle 40


def test_hdt_alarm_emcy_layout():
    d = at("hdt", OP)
    d.inject_hdt_alarm(13, 0x8611)
    assert d.emergencies[-1].to_bytes()[3:7] == bytes.fromhex("00100000")
    assert r(d, 0x603F) == 0x8611


# --- Control Techniques ---------------------------------------------------------------------------
def test_ct_oracle_10_11_quick_start_sequence():
    """Table 5.3 with TxPDO6 sub 2 as Table 5.2 names it (Pr 20.21; the printed 0x20141620 is Pr 20.22, A1)."""
    d = at("controltechniques")
    for idx, sub, val, size in [
        (0x1600, 0, 3, 1), (0x1600, 1, 0x60400010, 4), (0x1600, 2, 0x60420010, 4), (0x1600, 3, 0x20141520, 4),
        (0x1A00, 0, 2, 1), (0x1A00, 1, 0x60410010, 4), (0x1A00, 2, 0x60640020, 4),
        (0x1C12, 0, 0, 1), (0x1C13, 0, 0, 1), (0x1A05, 0, 2, 1), (0x1A05, 1, 0x20121610, 4),
        (0x1A05, 2, 0x20141520, 4), (0x1C12, 1, 0x1600, 2), (0x1C12, 0, 1, 1),
        (0x1C13, 1, 0x1A00, 2), (0x1C13, 2, 0x1A05, 2), (0x1C13, 0, 2, 1),
    ]:
        w(d, idx, sub, val, size)
    d.request_state(SAFE)
    assert d.process_image_sizes() == (8, 12)


def test_ct_oracle_12_default_configuration():
    d = at("controltechniques", OP)
    assert d.process_image_sizes() == (4, 4)


def test_ct_oracle_14_six_mappings_and_third_pdo_refused():
    d = at("controltechniques")
    w(d, 0x1C12, 0, 0, 1)
    assert code_of(w, d, 0x1600, 0, 6, 1) in (0x06040042, 0x06090031)
    w(d, 0x1C12, 1, 0x1600, 2)
    w(d, 0x1C12, 2, 0x1601, 2)
    assert code_of(w, d, 0x1C12, 0, 3, 1) == 0x06090031


def test_ct_oracle_54_natural_abort_codes():
    d = at("controltechniques")
    assert code_of(w, d, 0x608F, 1, 1, 4) == 0x06010002
    assert code_of(d.sdo_upload, 0x1602, 0) == 0x06020000
    assert code_of(d.sdo_upload, 0x1018, 5) == 0x06090011
    w(d, 0x1C12, 0, 0, 1)
    w(d, 0x1600, 0, 0, 1)
    assert code_of(w, d, 0x1600, 1, 0x60910120, 4) == 0x06040041


def test_ct_oracle_26_shutdown_needs_op():
    d = at("controltechniques", SAFE)
    w(d, 0x6040, 0, 0x06, 2)
    assert r(d, 0x6041) & 0x4F == 0x40
    d.request_state(OP)
    w(d, 0x6040, 0, 0x06, 2)
    assert r(d, 0x6041) & 0x6F == 0x21
    d.request_state(SAFE)  # dropping from OP -> switch on disabled
    assert r(d, 0x6041) & 0x4F == 0x40


def test_ct_oracle_28_mode_locked_when_enabled():
    d = at("controltechniques", OP)
    for cw in (0x06, 0x07, 0x0F):
        w(d, 0x6040, 0, cw, 2)
    assert code_of(w, d, 0x6060, 0, 8, 1) == 0x08000022
    assert code_of(w, d, 0x6060, 0, 1, 1) in (0x06090030, 0x08000022)


def test_ct_oracle_30_position_factor():
    d = at("controltechniques")
    assert r(d, 0x608F, 1) == 65536 and r(d, 0x608F, 2) == 1  # A24: from the drive's encoder configuration
    d.set_encoder_resolution(4096)  # 608Fh is read-only over SDO: the encoder sets it
    w(d, 0x6091, 1, 3, 4)
    w(d, 0x6092, 1, 10, 4)
    assert d.units.position_factor() == Fraction(12288, 10)


def test_ct_oracle_52_trip_codes():
    d = at("controltechniques", OP)
    for trip, code in ((3, 0x2300), (31, 0x5530), (7, 0x1000)):
        d.inject_trip(trip)
        assert r(d, 0x603F) == code
        w(d, 0x6040, 0, 0x00, 2)
        w(d, 0x6040, 0, 0x80, 2)


# --- ESM, SDO rules, faults, target ---------------------------------------------------------------
def test_esm_transitions_and_no_mailbox_in_init():
    d = Drive.from_profile("hdt")
    with pytest.raises(SdoTimeout):
        d.sdo_upload(0x1000, 0)
    with pytest.raises(StateChangeError) as exc:
        d.request_state(SAFE)
    assert exc.value.al_status == 0x0011
    d.request_state(PRE)
    assert r(d, 0x1000) == 0x00020192


def test_sdo_length_and_range_codes():
    d = at("hdt")
    assert code_of(d.sdo_download, 0x6040, 0, b"\x06") == 0x06070013
    assert code_of(d.sdo_download, 0x6040, 0, b"\x06\x00\x00") == 0x06070012
    assert code_of(d.sdo_download, 0x6041, 0, b"\x06\x00") == 0x06010002
    assert code_of(w, d, 0x6046, 1, 2**31, 4) == 0x06090031


def test_fault_injection_abort_drop_and_refuse():
    d = at("hdt")
    d.faults.abort_sdo(2, 0x08000000)
    r(d, 0x1000)
    assert code_of(d.sdo_upload, 0x1000, 0) == 0x08000000
    d.faults.drop_reply(1)
    with pytest.raises(SdoTimeout):
        w(d, 0x6060, 0, 8, 1)
    assert r(d, 0x6060) == 8  # executed, only the reply was lost
    d.faults.refuse_state(SAFE, 0x001A)
    with pytest.raises(StateChangeError) as exc:
        d.request_state(SAFE)
    assert exc.value.al_status == 0x001A
    d.request_state(SAFE)
    assert [e.kind for e in d.events].count("state_refused") == 1


def test_complete_access_upload_and_download():
    d = at("controltechniques")
    d.device.mailbox.coe.complete_access = True
    data = d.sdo_upload(0x1C13, 0, complete_access=True)
    assert data[:2] == b"\x01\x00" and data[2:4] == (0x1A05).to_bytes(2, "little")
    d.sdo_download(0x1C13, 0, b"\x02\x00" + (0x1A00).to_bytes(2, "little") + (0x1A05).to_bytes(2, "little"),
                   complete_access=True)
    assert [r(d, 0x1C13, s) for s in range(3)] == [2, 0x1A00, 0x1A05]
    assert code_of(d.sdo_download, 0x1C13, 0, b"\x03\x00\x00\x1A\x01\x1A\x05\x1A", True) == 0x06070010
    assert code_of(d.sdo_download, 0x1C13, 0, b"\x03\x00\x01\x1A\x05\x1A", True) == 0x06090031
    assert [r(d, 0x1C13, s) for s in range(3)] == [2, 0x1A00, 0x1A05]  # all or nothing


def test_complete_access_refused_when_unsupported():
    d = at("technosoft-ipos")
    assert code_of(d.sdo_upload, 0x1C12, 0, True) == 0x06010004


def test_sim_target():
    from ecattool import profiles

    t = SimTarget.from_devices([profiles.load("hdt"), profiles.load("controltechniques")])
    assert [s.position for s in t.slaves()] == [0, 1]
    assert all(isinstance(s, SlaveTarget) for s in t.slaves())
    assert open_target("sim", [profiles.load("hdt")]).slave(0).identity().vendor_id == 0x289
    with pytest.raises(EcatToolError):
        open_target("pysoem:eth0")


@given(st.lists(st.tuples(st.sampled_from([0x1600, 0x1601, 0x1A00, 0x1C12, 0x1C13, 0x6040, 0x6060, 0x6093, 0x1018,
                                           0x1000, 0x5000, 0x2000]),
                          st.integers(0, 9), st.binary(max_size=6)), max_size=25),
       st.sampled_from(["hdt", "controltechniques", "technosoft-ipos"]))
def test_random_writes_only_raise_ecattool_errors(writes, family):
    d = _fresh(family)
    for index, sub, data in writes:
        try:
            d.sdo_download(index, sub, data)
        except SdoAbort:
            pass
    try:
        d.request_state(SAFE)
        d.request_state(OP)
        d.exchange(bytes(d.process_image_sizes()[0]))
    except StateChangeError as exc:
        assert exc.al_status in (0x001D, 0x001E, 0x0030)


_CACHE: dict[str, object] = {}


def _fresh(family: str) -> Drive:
    from ecattool import profiles

    if family not in _CACHE:
        _CACHE[family] = profiles.load(family)
    d = Drive.from_device(_CACHE[family])  # type: ignore[arg-type]
    d.request_state(PRE)
    return d


def test_hdt_oracle_30_6046_max_not_above_min():
    d = at("hdt")
    assert code_of(w, d, 0x6046, 2, 0, 4) == 0x06090030  # min 0, max 0
    w(d, 0x6046, 2, 100, 4)
    assert code_of(w, d, 0x6046, 1, 100, 4) == 0x06090030


def test_ct_oracle_42_vl_factor_zero_refused():
    d = at("controltechniques")
    assert code_of(w, d, 0x604B, 1, 0, 2) == 0x06090030
    assert code_of(w, d, 0x604C, 2, 0, 2) == 0x06090030
    w(d, 0x604B, 1, 0xFFFF, 2)  # -1 allowed


def test_ct_positioning_mode_needs_dc_and_sync_interval():
    d = at("controltechniques", SAFE)
    d._put(0x6060, 0, 8)
    d._put(0x6061, 0, 8)
    with pytest.raises(StateChangeError) as exc:
        d.request_state(OP)
    assert exc.value.al_status == 0x0030 and d.state() is SAFE
    d.configure_dc(0x0300, 1_100_000)  # 1.1 ms: not a multiple of 250 us (oracle 36)
    with pytest.raises(StateChangeError) as exc:
        d.request_state(OP)
    assert exc.value.al_status == 0x0035
    d.configure_dc(0x0300, 15_000_000)
    d.request_state(OP)


def test_ct_priority_rule_slow_parameter_in_first_pdo():
    """SM-EtherCAT 6.1.1: with two PDOs in SM2, a slow parameter (2046h) in the first one is refused."""
    d = at("controltechniques")
    w(d, 0x1C12, 0, 0, 1)
    w(d, 0x1600, 0, 0, 1)
    w(d, 0x1600, 1, 0x60400010, 4)
    w(d, 0x1600, 2, 0x20460120, 4)
    w(d, 0x1600, 0, 2, 1)
    w(d, 0x1C12, 1, 0x1600, 2)
    w(d, 0x1C12, 2, 0x1605, 2)
    assert code_of(w, d, 0x1C12, 0, 2, 1) == 0x06040043
    w(d, 0x1C12, 1, 0x1605, 2)  # slow parameters in the second (low priority) PDO are fine
    w(d, 0x1C12, 2, 0x1600, 2)
    w(d, 0x1C12, 0, 2, 1)
    w(d, 0x1C12, 0, 0, 1)
    w(d, 0x1C12, 1, 0x1600, 2)
    w(d, 0x1C12, 0, 1, 1)  # alone it is allowed (low priority, not deterministic)


def test_ct_pdo_only_objects_refuse_sdo():
    d = at("controltechniques")
    assert code_of(d.sdo_upload, 0x2830, 0) in (0x06010000, 0x06090011)


def test_limit_switch_bits_per_family():
    """60FDh: Technosoft/CT bit 0 = negative, bit 1 = positive; HDT §4.04.1 bit 0 = CW (positive)."""
    for name, bit in (("technosoft-ipos", 1), ("hdt", 0), ("controltechniques", 1)):
        d = at(name)
        if (0x60FD, 0) not in d._entries:
            continue
        d.set_limit_switches(positive=True)
        assert r(d, 0x60FD) == 1 << bit, name
        assert r(d, 0x6041) & 0x0800


def test_technosoft_limit_switch_emcy():
    d = at("technosoft-ipos")
    d.set_limit_switches(positive=True)
    d.set_limit_switches()
    assert [m.code for m in d.emergencies[-2:]] == [0x5443, 0x0000]


def test_profile_velocity_ramps_with_acceleration():
    d = at("hdt")
    w(d, 0x6060, 0, 3, 1)
    w(d, 0x60FF, 0, 600, 4)  # rpm with the default 6094h = 65536/60
    w(d, 0x6083, 0, 6000, 4)  # rpm/s with the default 6097h
    d.request_state(SAFE)
    d.request_state(OP)
    for cw in (0x06, 0x07, 0x0F):
        w(d, 0x6040, 0, cw, 2)
    assert d.cycle_time() == Fraction(2, 1000)  # 60C2h default 2 x 10^-3 s (oracle 42)
    d.step(25)  # 50 ms at 6000 rpm/s -> 300 rpm
    assert int(d.units.velocity_to_user(d.cia.velocity)) == 300
    d.step(100)
    assert d.internal_velocity == 655360 and not r(d, 0x6041) & 0x4000
    assert any(e.kind == "cia402" and e.data["state"] == "OPERATION_ENABLED" for e in d.events)


_OPS = st.one_of(
    st.tuples(st.just("up"), st.integers(0, 0xFFFF), st.integers(0, 255), st.booleans()),
    st.tuples(st.just("down"), st.sampled_from([0x1600, 0x1603, 0x1A00, 0x1C12, 0x1C13, 0x6040, 0x6060, 0x6081,
                                                0x2064, 0x2065, 0x2069, 0x2091, 0x60C2, 0x6093]),
              st.integers(0, 9), st.binary(max_size=8), st.booleans()),
    st.tuples(st.just("state"), st.sampled_from(list(EcState))),
    st.tuples(st.just("cycle"), st.integers(1, 5)),
)


@given(st.lists(_OPS, max_size=30), st.sampled_from(["hdt", "controltechniques", "technosoft-ipos"]))
def test_random_operations_only_raise_ecattool_errors(ops, family):
    d = _fresh(family)
    for op in ops:
        try:
            if op[0] == "up":
                d.sdo_upload(op[1], op[2], complete_access=op[3])
            elif op[0] == "down":
                d.sdo_download(op[1], op[2], op[3], complete_access=op[4])
            elif op[0] == "state":
                d.request_state(op[1])
            elif d.state() in (SAFE, OP):
                d.exchange(bytes(d.process_image_sizes()[0]))
                d.step(op[1])
        except EcatToolError:
            pass
    assert isinstance(d.state(), EcState)


def test_hdt_oracle_19_603f_is_low_word_of_1003_1():
    d = at("hdt", OP)
    d.inject_fault(0x8611)
    assert r(d, 0x1003, 1) & 0xFFFF == r(d, 0x603F) == 0x8611
    assert r(d, 0x1003, 0) == 1


def _products():
    from ecattool import profiles

    out = []
    for p in profiles.list_profiles():
        for prod in p.products:
            for rev in (prod.revisions or (None,)):
                out.append((p.name, prod.name, rev))
    return out


@pytest.mark.parametrize("profile,product,revision", _products())
def test_every_model_and_revision_reaches_op_after_reset(profile, product, revision):
    d = Drive.from_profile(profile, product=product, revision=revision)
    for s in (PRE, SAFE, OP):
        d.request_state(s)
    outputs, inputs = d.process_image_sizes()
    assert outputs > 0 and inputs > 0
    assert len(d.exchange(bytes(outputs))) == inputs
    d.sdo_download(0x6040, 0, b"\x06\x00")
    assert r(d, 0x6041) & 0x6F == 0x21


def _enabled(name: str) -> Drive:
    d = at(name, OP)
    for cw in (0x06, 0x07, 0x0F):
        w(d, 0x6040, 0, cw, 2)
    return d


def test_lose_communication_abort_connection_option_codes():
    """6007h: HDT oracle 27 (0 no action, 1/2 switch on disabled, 3 stays enabled); Technosoft default 1
    = fault with EMCY 8100h; Control Techniques always switch on disabled."""
    for name, option, mask, state in (("hdt", 0, 0x6F, 0x27), ("hdt", 2, 0x4F, 0x40), ("hdt", 3, 0x6F, 0x27),
                                      ("technosoft-ipos", None, 0x4F, 0x08), ("controltechniques", None, 0x4F, 0x40)):
        d = at(name)
        if option is not None:
            w(d, 0x6007, 0, option, 2)
        d.request_state(SAFE)
        d.request_state(OP)
        for cw in (0x06, 0x07, 0x0F):
            w(d, 0x6040, 0, cw, 2)
        d.lose_communication()
        assert d.state() is SAFE
        assert r(d, 0x6041) & mask == state, (name, option, hex(r(d, 0x6041)))
    tech = _enabled("technosoft-ipos")
    tech.lose_communication()
    assert tech.emergencies[-1].code == 0x8100
