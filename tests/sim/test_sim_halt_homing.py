"""Halt (controlword bit 8) and homing mode (6) of the simulator against each family's manual.

Sections: HDT "CANopen/EtherCAT user guide" §4.03.7 (605Dh), §4.06.6 (607Ch), §4.07 (profile position),
§4.08 (homing), §4.10 (profile velocity); Technosoft "iPOS CoE Programming" §4.4.10 (605Dh), §6 (homing),
§13/§14 (CSP/CSV); Control Techniques "SM-EtherCAT User Guide" §7.7 (homing). Decisions where the manuals
are silent: docs/decisions.md, "Simulator: halt and homing".
"""

from __future__ import annotations

from fractions import Fraction

import pytest
from hypothesis import given
from hypothesis import strategies as st

from ecattool.errors import SdoAbort
from ecattool.esi.model import Direction
from ecattool.od.model import EcState
from ecattool.sim import Drive
from ecattool.sim.cia402 import State, decode_statusword
from tests.conftest import corpus_path

#: the manuals' exact timings and traces: the ideal plant (actual = demand; issue 33)
pytestmark = pytest.mark.usefixtures("ideal_plant")

PRE, SAFE, OP = EcState.PREOP, EcState.SAFEOP, EcState.OP
INOVANCE = "inovance_SV660_EOE_1Axis_V9.12.xml"
HOMING_BITS = 0x2000 | 0x1000 | 0x0400  # statusword bits 13, 12, 10 in homing mode
NOT_STARTED, IN_PROGRESS, ATTAINED, ERROR_STOPPED = 0x0400, 0x0000, 0x1400, 0x2400  # Technosoft Table 6.3.3


def w(d: Drive, index: int, sub: int, value: int, size: int) -> None:
    d.sdo_download(index, sub, value.to_bytes(size, "little", signed=value < 0))


def r(d: Drive, index: int, sub: int = 0, signed: bool = False) -> int:
    return int.from_bytes(d.sdo_upload(index, sub), "little", signed=signed)


def code_of(fn, *args) -> int:
    with pytest.raises(SdoAbort) as exc:
        fn(*args)
    return exc.value.code


def at_op(d: Drive) -> Drive:
    for s in (PRE, SAFE, OP):
        d.request_state(s)
    return d


def enabled(name: str, mode: int, **setup: tuple[int, int, int]) -> Drive:
    """A drive of family ``name`` in OP and OPERATION ENABLED in ``mode`` (set by SDO before enabling);
    ``setup`` holds more SDO writes as name=(index, value, size)."""
    d = at_op(Drive.from_profile(name))
    w(d, 0x6060, 0, mode, 1)
    for index, value, size in setup.values():
        w(d, index, 0, value, size)
    for cw in (0x06, 0x07, 0x0F):
        w(d, 0x6040, 0, cw, 2)
    assert r(d, 0x6041) & 0x6F == 0x27
    return d


class Master:
    """Drives a simulated slave through its process image, as a master does: every cycle sends all mapped
    outputs (kept between cycles) and decodes the mapped inputs."""

    def __init__(self, drive: Drive) -> None:
        self.d = drive
        self.out: dict[int, int] = {}

    def cycle(self, n: int = 1, **values: int) -> dict[int, int]:
        self.out.update({int(k[1:], 16): v for k, v in values.items()})  # keys like x6040=...
        rx, tx = self.d.layout[Direction.RX], self.d.layout[Direction.TX]
        inputs: dict[int, int] = {}
        for _ in range(n):
            image = 0
            for index, _sub, offset, bits in rx.entries:
                image |= (self.out.get(index, 0) & ((1 << bits) - 1)) << offset
            raw = int.from_bytes(self.d.exchange(image.to_bytes(rx.size, "little")), "little")
            for index, _sub, offset, bits in tx.entries:
                v = (raw >> offset) & ((1 << bits) - 1)
                inputs[index] = v - (1 << bits) if bits == 32 and v >> 31 else v
        return inputs


def _home_on_the_spot_through_pdos(d: Drive, offset: int) -> Master:
    """Mode 6, method 35, 607Ch = ``offset`` by SDO; enable and start (0x1F) through the process image:
    not started (001) before, attained (011) with 6064h = 607Ch after."""
    w(d, 0x6060, 0, 6, 1)
    w(d, 0x6098, 0, 35, 1)
    w(d, 0x607C, 0, offset, 4)
    m = Master(d)
    for cw in (0x06, 0x07, 0x0F):
        ins = m.cycle(x6040=cw)
    assert ins[0x6041] & HOMING_BITS == NOT_STARTED
    ins = m.cycle(x6040=0x1F)
    assert ins[0x6041] & HOMING_BITS == ATTAINED and ins[0x6064] == offset
    return m


def homing_status(d: Drive) -> int:
    return r(d, 0x6041) & HOMING_BITS


# --- HDT ----------------------------------------------------------------------------------------------
def test_hdt_4_03_7_halt_option_0_disables_the_drive():
    """605Dh = 0 (the default): "Power is disabled ... the Drive goes in Switch On Disabled" (oracle 27)."""
    d = enabled("hdt", 1)
    assert r(d, 0x605D) == 0
    w(d, 0x6040, 0, 0x010F, 2)
    assert decode_statusword(r(d, 0x6041)) is State.SWITCH_ON_DISABLED
    assert any(e.kind == "cia402" and e.data["reason"] == "halt, 605Dh = 0" for e in d.events)
    assert any(e.kind == "halt" and e.data["active"] for e in d.events)


@pytest.mark.parametrize("option,time_index,rpm_after_50ms", [(1, 0x6050, 450), (2, 0x6051, 300)])
def test_hdt_4_03_7_halt_options_1_2_ramp_with_604e_over_6050_6051(option, time_index, rpm_after_50ms):
    """605Dh 1/2: a ramp with deceleration 604Eh / 6050h (slow) or 6051h (quick) and the drive stays in
    OPERATION ENABLED; profile velocity statusword bit 10 with halt: 0 decelerating, 1 stationary (§4.10.2)."""
    d = enabled("hdt", 3, halt=(0x605D, option, 2), quick=(0x6051, 500, 4), accel=(0x6083, 6000, 4),
                target=(0x60FF, 600, 4))
    d.step(50)  # 100 ms at 6000 rpm/s -> 600 rpm (60C2h = 2 ms)
    assert r(d, 0x606C, signed=True) == 600
    w(d, 0x6040, 0, 0x010F, 2)
    d.step(25)  # 50 ms at 3000 rpm/s (604Eh 3000 rpm over 1000 ms) or 6000 rpm/s (over 500 ms)
    assert r(d, 0x606C, signed=True) == rpm_after_50ms
    sw = r(d, 0x6041)
    assert sw & 0x6F == 0x27 and not sw & 0x0400
    d.step(100)
    sw = r(d, 0x6041)
    assert r(d, 0x606C) == 0 and sw & 0x6F == 0x27 and sw & 0x0400
    w(d, 0x6040, 0, 0x000F, 2)  # halt released: the velocity set-point applies again with 6083h
    d.step(25)
    assert r(d, 0x606C, signed=True) == 300 and not r(d, 0x6041) & 0x0400


def test_hdt_4_07_halt_in_profile_position_keeps_the_set_point_and_resumes():
    """§4.07.1 bit 8: "the motor stops in ramp"; §4.07.2 bit 10 with halt = 1: 1 = the motor stands still;
    clearing the halt continues to the pending target. Driven through the default RxPDO/TxPDO."""
    d = at_op(Drive.from_profile("hdt"))
    w(d, 0x605D, 0, 1, 2)
    w(d, 0x6060, 0, 1, 1)
    m = Master(d)
    for cw in (0x06, 0x07, 0x0F):
        m.cycle(x6040=cw, x6081=1000, x6083=1000, x6084=1000)
    w(d, 0x6086, 0, 0, 2)  # linear ramp (trapezoidal profile)
    ins = m.cycle(100, x6040=0x1F, x607A=65536)  # 200 ms at 1000 rpm/s: 200 rpm
    assert 0 < ins[0x6064] < 65536 and not ins[0x6041] & 0x0400 and r(d, 0x606C) == 200
    held = m.cycle(x6040=0x11F)
    assert not held[0x6041] & 0x0400 and 0 < r(d, 0x606C) < 200  # "the motor stops in ramp" (6084h)
    held = m.cycle(100, x6040=0x11F)
    assert r(d, 0x606C) == 0 and held[0x6041] & 0x0400 and held[0x6041] & 0x6F == 0x27
    assert m.cycle(x6040=0x11F)[0x6064] == held[0x6064]
    moving = m.cycle(2, x6040=0x1F)
    assert not moving[0x6041] & 0x0400 and moving[0x6064] > held[0x6064]
    done = m.cycle(2000, x6040=0x1F)
    assert done[0x6064] == 65536 and done[0x6041] & 0x0400


@pytest.mark.parametrize("method,code", [(15, 0x06090030), (16, 0x06090030), (31, 0x06090030), (32, 0x06090030),
                                         (36, 0x06090031), (-1, 0x06090032)])
def test_hdt_4_08_3_reserved_homing_methods_are_refused(method, code):
    """6098h range "0..35 (eccetto 15, 16, 31 e 32)" (oracle 29)."""
    d = at_op(Drive.from_profile("hdt"))
    assert code_of(w, d, 0x6098, 0, method, 1) == code
    assert r(d, 0x6098) == 0


def test_hdt_4_08_3_valid_homing_methods_are_accepted():
    d = Drive.from_profile("hdt")
    d.request_state(PRE)
    for method in [*range(15), *range(17, 31), 33, 34, 35]:
        w(d, 0x6098, 0, method, 1)
        assert r(d, 0x6098) == method


def _hdt_at(position: int, **setup: tuple[int, int, int]) -> Drive:
    """HDT in OPERATION ENABLED, moved by profile position to ``position`` counts, then in homing mode."""
    # a homing acceleration steep enough for the searches to be at full speed within the first 2 ms cycle
    setup.setdefault("homing_acceleration", (0x609A, 1_000_000, 4))
    d = enabled("hdt", 1, halt=(0x605D, 1, 2), **setup)
    w(d, 0x607A, 0, position, 4)
    w(d, 0x6040, 0, 0x1F, 2)
    for _ in range(100):
        d.step(20)
        if r(d, 0x6041) & 0x0400:
            break
    assert r(d, 0x6064, signed=True) == position
    w(d, 0x6040, 0, 0x0F, 2)
    w(d, 0x6060, 0, 6, 1)
    assert homing_status(d) == NOT_STARTED
    return d


def test_hdt_4_08_3_s_method_35_current_position_becomes_home():
    """Method 35: "the current position will become the home position"; §4.06.6: the sensor position is
    reset to 0 by homing and 6064h = sensor position + 607Ch."""
    d = _hdt_at(3000)
    w(d, 0x607C, 0, 250, 4)
    assert r(d, 0x6064, signed=True) == 3250  # 607Ch applies to the measured position at all times
    w(d, 0x6098, 0, 35, 1)
    w(d, 0x6040, 0, 0x1F, 2)
    assert homing_status(d) == ATTAINED
    assert r(d, 0x6063, signed=True) == 0 and r(d, 0x6064, signed=True) == 250
    assert [e.data["event"] for e in d.events if e.kind == "homing"] == ["start", "attained"]


def test_hdt_4_08_3_a_method_0_home_is_the_power_on_zero():
    """Method 0: "when the drive is turned on the measured position is reset to zero and set as the home
    position": a homing start attains at once and nothing moves."""
    d = _hdt_at(3000)
    w(d, 0x6040, 0, 0x1F, 2)
    assert homing_status(d) == ATTAINED and r(d, 0x6064, signed=True) == 3000


def test_hdt_oracle_38_home_offset_zeroes_the_measured_position():
    """§4.06.6: to zero 6064h write 607Ch = -6064h (read with 607Ch = 0); absolute targets then count from
    the new zero."""
    d = _hdt_at(1000)
    w(d, 0x607C, 0, -r(d, 0x6064, signed=True), 4)
    assert r(d, 0x6064, signed=True) == 0 and r(d, 0x6063, signed=True) == 1000
    w(d, 0x6060, 0, 1, 1)
    w(d, 0x607A, 0, 500, 4)
    w(d, 0x6040, 0, 0x1F, 2)
    d.step(500)  # the profile move (6081h/6083h/6084h, S-curve by default: 6086h = 3)
    assert r(d, 0x6064, signed=True) == 500 and r(d, 0x6063, signed=True) == 1500


@pytest.mark.parametrize("method,direction,speed_sub", [(17, -1, 1), (18, 1, 1), (34, 1, 2), (33, -1, 2), (7, 1, 1),
                                                         (11, -1, 1)])
def test_hdt_homing_search_without_switches_ends_in_error_ff02(method, direction, speed_sub):
    """§4.08.3: limit/home switch methods search at 6099h:1, index methods at 6099h:2 (CW = positive,
    CCW = negative); the simulated axis has none connected, so after the search the drive reports bit 13
    and alarm FA_14 (EMCY FF02h, bit 13 of the alarm bitmap, §2.04/§2.08.2) and stays enabled."""
    d = _hdt_at(0)
    w(d, 0x6098, 0, method, 1)
    w(d, 0x6040, 0, 0x1F, 2)
    d.step(10)
    assert homing_status(d) == IN_PROGRESS
    rpm = r(d, 0x6099, speed_sub)
    assert r(d, 0x606C, signed=True) == direction * rpm  # 6099h is converted with 6094h (§4.08.4)
    d.step(int(d.homing_search_s / d.cycle_time()))
    sw = r(d, 0x6041)
    assert sw & HOMING_BITS == ERROR_STOPPED and sw & 0x6F == 0x27
    assert d.emergencies[-1].to_bytes() == bytes([0x02, 0xFF, 0x01, 0x00, 0x20, 0x00, 0x00, 0x00])
    assert [e.data["event"] for e in d.events if e.kind == "homing"] == ["start", "error"]


def test_hdt_4_08_1_bit4_cleared_stops_homing_and_halt_pauses_it():
    """§4.08.1: bit 4 "0->1 homing start, 1->0 stop"; bit 8 "the motor stops with a ramp" (homing
    acceleration); §4.08.2 bit 10 with halt = 1: 1 = the axis is stationary."""
    d = _hdt_at(0)
    w(d, 0x6098, 0, 18, 1)
    w(d, 0x6040, 0, 0x1F, 2)
    d.step(10)
    w(d, 0x6040, 0, 0x11F, 2)
    d.step(1)
    paused = r(d, 0x6064, signed=True)
    assert homing_status(d) == NOT_STARTED and r(d, 0x606C) == 0
    d.step(5)
    assert r(d, 0x6064, signed=True) == paused
    w(d, 0x6040, 0, 0x1F, 2)  # halt released with bit 4 still set: the search continues
    d.step(1)
    assert homing_status(d) == IN_PROGRESS and r(d, 0x6064, signed=True) > paused
    w(d, 0x6040, 0, 0x0F, 2)
    d.step(1)
    assert homing_status(d) == NOT_STARTED and r(d, 0x606C) == 0


def test_hdt_4_08_3_method_17_homes_where_the_ccw_limit_switch_is_left():
    """§4.08.3.b (method 1 = 17 with the index pulse): move CCW at the switch search speed to the CCW limit
    switch, reverse at low speed (6099h:2) to leave it; 17 takes that point as home (6064h = 607Ch)."""
    d = _hdt_at(5000)
    w(d, 0x607C, 0, 40, 4)
    w(d, 0x6098, 0, 17, 1)
    w(d, 0x6040, 0, 0x1F, 2)
    d.step(5)
    assert r(d, 0x606C, signed=True) == -100
    d.set_limit_switches(negative=True)
    assert r(d, 0x60FD) & 0b10  # HDT: bit 1 = CCW limit (oracle 56)
    d.step(5)
    assert r(d, 0x606C, signed=True) == 10 and homing_status(d) == IN_PROGRESS
    d.set_limit_switches()
    assert homing_status(d) == ATTAINED and r(d, 0x6063) == 0 and r(d, 0x6064) == 40
    events = [e.data["event"] for e in d.events if e.kind == "homing"]
    assert events == ["start", "limit switch found", "attained"]


def test_hdt_4_08_3_method_1_needs_the_index_pulse_after_the_switch():
    """Method 1 continues from the switch edge to an index pulse; none is connected: homing error, FF02h."""
    d = _hdt_at(0)
    w(d, 0x6098, 0, 1, 1)
    w(d, 0x6040, 0, 0x1F, 2)
    d.step(2)
    d.set_limit_switches(negative=True)
    d.step(2)
    d.set_limit_switches()
    d.step(2)
    assert homing_status(d) == IN_PROGRESS and r(d, 0x606C, signed=True) == 10
    d.step(int(d.homing_search_s / d.cycle_time()))
    assert homing_status(d) == ERROR_STOPPED and d.emergencies[-1].code == 0xFF02


# --- Technosoft -------------------------------------------------------------------------------------------
@pytest.mark.parametrize("option,ramp_index,ramp,counts_per_ms_after_3", [(1, 0x6083, 65536, 7), (2, 0x6085, 131072, 4)])
def test_technosoft_4_4_10_halt_ramps_with_6083_or_6085(option, ramp_index, ramp, counts_per_ms_after_3):
    """605Dh default 1: "slow down on slow down ramp (6083h) and stay in Operation Enabled"; 2: quick stop
    ramp (6085h). Velocity IU = 16.16 counts per 1 ms sample; acceleration IU = 16.16 counts per sample²."""
    d = enabled("technosoft-ipos", 3, accel=(0x6083, 65536, 4), target=(0x60FF, 10 * 65536, 4))
    assert r(d, 0x605D) == 1
    w(d, 0x605D, 0, option, 2)
    w(d, ramp_index, 0, ramp, 4)
    d.step(20)
    assert d.internal_velocity == 10 * 65536
    w(d, 0x6040, 0, 0x010F, 2)
    d.step(3)
    assert d.internal_velocity == counts_per_ms_after_3 * 65536 and not r(d, 0x6041) & 0x0400
    d.step(10)
    sw = r(d, 0x6041)
    assert d.internal_velocity == 0 and sw & 0x6F == 0x27 and sw & 0x0400


def test_technosoft_13_14_halt_in_csp_and_csv_ignores_the_target():
    """§13 CSP: 6041h bit 12 target position ignored (0) / used (1); §14 CSV: bit 12 = 0 "when 6040h.8
    halt = 1". Through the default RxPDO (6040h, 607Ah) and TxPDO (6041h, 6064h)."""
    d = at_op(Drive.from_profile("technosoft-ipos"))
    w(d, 0x6060, 0, 8, 1)
    m = Master(d)
    for cw in (0x06, 0x07, 0x0F):
        m.cycle(x6040=cw)
    ins = m.cycle(x607A=100)
    assert ins[0x6064] == 100 and ins[0x6041] & 0x1000
    ins = m.cycle(3, x6040=0x10F, x607A=200)
    assert ins[0x6064] == 100 and not ins[0x6041] & 0x1000 and ins[0x6041] & 0x0400
    ins = m.cycle(x6040=0x0F)
    assert ins[0x6064] == 200 and ins[0x6041] & 0x1000
    w(d, 0x6060, 0, 9, 1)
    w(d, 0x60FF, 0, 5 * 65536, 4)
    ins = m.cycle(2)
    assert ins[0x6064] == 210 and ins[0x6041] & 0x1000
    ins = m.cycle(2, x6040=0x10F)
    assert ins[0x6064] == 210 and not ins[0x6041] & 0x1000 and d.internal_velocity == 0


def test_technosoft_6_2_13_method_35_sets_6064_to_home_offset_through_pdos():
    """§6.1/§6.3.3: after homing 6064h = 607Ch; method 35 homes on the current position (oracle 33: home
    offset 1 rev of a 500-line encoder = 0x7D0); start 0x001F in mode 6 (oracle 22)."""
    _home_on_the_spot_through_pdos(at_op(Drive.from_profile("technosoft-ipos")), 0x7D0)


def test_technosoft_6_3_3_asr2_bit12_keeps_the_position():
    """§6.3.3: with 210Bh bit 12 = 1 the actual position is not reset to 607Ch after homing."""
    d = enabled("technosoft-ipos", 1, asr2=(0x210B, 0x1000, 2), target=(0x607A, 300, 4), speed=(0x6081, 400 * 65536, 4))
    w(d, 0x6040, 0, 0x1F, 2)
    d.step(1)
    assert r(d, 0x6064) == 300
    w(d, 0x6060, 0, 6, 1)
    w(d, 0x607C, 0, 5, 4)
    w(d, 0x6098, 0, 35, 1)
    w(d, 0x6040, 0, 0x0F, 2)
    w(d, 0x6040, 0, 0x1F, 2)
    assert homing_status(d) == ATTAINED and r(d, 0x6064) == 300


@pytest.mark.parametrize("method", [15, 16, 31, 32, 36, -5])
def test_technosoft_6_3_4_reserved_method_is_stored_and_answered_with_emcy_ff03(method):
    """6098h value range INTEGER8 (reserved values listed, not refused); a homing start with a method the
    drive does not have sends EMCY FF03h "Specified homing method not available" (§3.1.3) and homing is not
    carried out (bit 13)."""
    d = enabled("technosoft-ipos", 6)
    w(d, 0x6098, 0, method, 1)
    w(d, 0x6040, 0, 0x1F, 2)
    assert d.emergencies[-1].code == 0xFF03
    assert homing_status(d) == ERROR_STOPPED


def test_technosoft_6_2_8_method_18_starting_on_the_positive_limit_switch():
    """§6.2.8 method 18 (positive limit switch, no index): already on the switch, the drive leaves it in the
    negative direction at the zero search speed and homes where it becomes inactive (6064h = 607Ch)."""
    d = enabled("technosoft-ipos", 6, method=(0x6098, 18, 1), offset=(0x607C, -7, 4), acc=(0x609A, 0, 4))
    w(d, 0x6099, 2, 3 * 65536, 4)
    d.set_limit_switches(positive=True)
    assert d.emergencies[-1].code == 0x5443
    w(d, 0x6040, 0, 0x1F, 2)
    d.step(4)
    assert d.internal_velocity == -3 * 65536 and r(d, 0x6064, signed=True) == -12
    d.set_limit_switches()
    assert homing_status(d) == ATTAINED and r(d, 0x6064, signed=True) == -7


def test_technosoft_6_3_4_method_0_executes_no_homing():
    d = enabled("technosoft-ipos", 6)
    w(d, 0x6040, 0, 0x1F, 2)
    assert homing_status(d) == NOT_STARTED and not d.emergencies


def test_technosoft_oracle_33_homing_setup_and_search_status_sequence():
    """Oracle 33 (§6.4): 6099h.1 = 0x00140000 (600 rpm), 6099h.2 = 0x00050000, 609Ah = 0x28F, method 18 =
    0x12; oracle 24 / Table 6.3.3: (13,12,10) 001 not started, 000 in progress, 101 error at standstill.
    Statusword bit 8 = homing executing, bit 7 = a homing call ignored (§4.2.2). Only the 0 -> 1 edge of
    bit 4 matters (§6.3.1)."""
    d = enabled("technosoft-ipos", 6, fast=(0x609A, 0x28F, 4), method=(0x6098, 0x12, 1))
    w(d, 0x6099, 1, 0x00140000, 4)
    w(d, 0x6099, 2, 0x00050000, 4)
    assert homing_status(d) == NOT_STARTED
    w(d, 0x6040, 0, 0x1F, 2)
    d.step(10)
    sw = r(d, 0x6041)
    assert sw & HOMING_BITS == IN_PROGRESS and sw & 0x0100
    # the search speeds up with 609Ah: 0x28F IU = 0.01 counts per sample² (towards 20 counts per sample)
    assert d.internal_velocity == 10 * 0x28F and r(d, 0x6064) == 655 * 55 // 65536
    w(d, 0x6040, 0, 0x0F, 2)  # bit 4 back to 0 does not stop a Technosoft homing
    w(d, 0x6040, 0, 0x1F, 2)  # a second start while it runs is ignored with the warning bit 7 (§4.2.2)
    assert r(d, 0x6041) & 0x0180 == 0x0180
    n = int(d.homing_search_s / d.cycle_time())
    d.step(n - 10)
    sw = r(d, 0x6041)
    assert sw & HOMING_BITS == ERROR_STOPPED and not sw & 0x0180 and d.internal_velocity == 0
    assert r(d, 0x6064) == 655 * n * (n + 1) // 2 // 65536  # one second of the ramp: no switch connected


# --- Control Techniques ------------------------------------------------------------------------------------
def _ct(mode: int = 6) -> Drive:
    d = at_op(Drive.from_profile("controltechniques"))
    w(d, 0x6060, 0, mode, 1)
    return d


def test_ct_7_7_method_35_needs_no_operation_enabled():
    """§7.7.1 method 35: "the current position shall be taken to be the home position. This method does not
    require the drive device to be in operational enabled state"; Table 7.54 bits 12/10 = 1/1 completed."""
    d = _ct()
    w(d, 0x607C, 0, -500, 4)
    w(d, 0x6098, 0, 35, 1)
    for cw in (0x06, 0x07, 0x17):
        w(d, 0x6040, 0, cw, 2)
    sw = r(d, 0x6041)
    assert sw & 0x6F == 0x23 and sw & HOMING_BITS == ATTAINED
    assert r(d, 0x6064, signed=True) == -500


@pytest.mark.parametrize("method,code", [(15, 0x06090030), (16, 0x06090030), (31, 0x06090030), (32, 0x06090030),
                                         (36, 0x06090031)])
def test_ct_7_7_2_reserved_homing_methods_are_refused(method, code):
    """Table 7.58/7.59: U8 range 0-35, 15, 16, 31, 32 reserved (oracle 46; 36 -> 0609 0031h)."""
    d = _ct()
    assert code_of(w, d, 0x6098, 0, method, 1) == code


def test_ct_table_7_53_halt_stops_the_search_and_bit4_continues_it():
    """Table 7.53: bit 4 = 1 "start or continue homing", bit 8 = 1 "stop axis according to 605Dh" (605Dh
    has no table: slow-down ramp, stays OPERATION ENABLED); bit 4 = 0 interrupts (Table 7.54 0/1)."""
    d = _ct()
    w(d, 0x6098, 0, 34, 1)
    w(d, 0x6099, 2, 4000, 4)  # user velocity units per second
    for cw in (0x06, 0x07, 0x0F, 0x1F):
        w(d, 0x6040, 0, cw, 2)
    d.step(4)  # 1 ms at 250 us cycles
    assert homing_status(d) == IN_PROGRESS and r(d, 0x6064) == 4
    w(d, 0x6040, 0, 0x11F, 2)
    d.step(4)
    assert homing_status(d) == NOT_STARTED and r(d, 0x6064) == 4 and r(d, 0x6041) & 0x6F == 0x27
    w(d, 0x6040, 0, 0x1F, 2)
    d.step(4)
    assert homing_status(d) == IN_PROGRESS and r(d, 0x6064) == 8
    w(d, 0x6040, 0, 0x0F, 2)
    d.step(4)
    assert homing_status(d) == NOT_STARTED and r(d, 0x6064) == 8
    assert [e.data["event"] for e in d.events if e.kind == "homing"] == ["start", "interrupted"]
    assert [e.data["active"] for e in d.events if e.kind == "halt"] == [True, False]


def test_ct_mode_change_interrupts_homing():
    d = _ct()
    w(d, 0x6098, 0, 17, 1)
    w(d, 0x6099, 1, 1000, 4)
    for cw in (0x06, 0x07, 0x0F, 0x1F):
        w(d, 0x6040, 0, cw, 2)
    d.step(1)
    w(d, 0x6040, 0, 0x07, 2)  # disable operation: leaving OPERATION ENABLED ends the search
    assert homing_status(d) == NOT_STARTED and d.cia.velocity == 0


# --- a corpus ESI drive (generic CiA-402) -----------------------------------------------------------------
def _inovance() -> Drive:
    return at_op(Drive.from_esi(corpus_path("esi", INOVANCE)))


def test_generic_inovance_605d_range_from_the_esi():
    """A generic drive takes 605Dh's range from its ESI (Inovance 1..3, default 1)."""
    d = _inovance()
    assert r(d, 0x605D) == 1
    assert code_of(w, d, 0x605D, 0, 0, 2) == 0x06090032
    assert code_of(w, d, 0x605D, 0, 4, 2) == 0x06090031


def test_generic_inovance_homing_35_and_manufacturer_method_through_pdos():
    """CiA-402 method 35 homes on the current position (6064h = 607Ch); a manufacturer method (-1) needs
    signals the simulated axis does not have: homing error (bit 13) at standstill, no EMCY (none documented)."""
    d = _inovance()
    m = _home_on_the_spot_through_pdos(d, 12345)
    w(d, 0x6098, 0, -1, 1)
    m.cycle(x6040=0x0F)
    ins = m.cycle(x6040=0x1F)
    assert ins[0x6041] & HOMING_BITS == IN_PROGRESS
    ins = m.cycle(int(d.homing_search_s / d.cycle_time()))
    assert ins[0x6041] & HOMING_BITS == ERROR_STOPPED and not d.emergencies


def test_generic_inovance_halt_in_profile_position_through_pdos():
    d = _inovance()
    w(d, 0x6060, 0, 1, 1)
    w(d, 0x6081, 0, 1000, 4)
    m = Master(d)
    for cw in (0x06, 0x07, 0x0F):
        m.cycle(x6040=cw)
    ins = m.cycle(20, x6040=0x1F, x607A=100_000)
    pos = ins[0x6064]
    assert 0 < pos < 100_000
    for _ in range(100):  # the halt ramps down (6084h)
        ins = m.cycle(10, x6040=0x11F)
        if ins[0x6041] & 0x0400:
            break
    assert ins[0x6041] & 0x0400 and ins[0x6041] & 0x6F == 0x27
    assert m.cycle(x6040=0x11F)[0x6064] == ins[0x6064]
    assert m.cycle(x6040=0x1F)[0x6064] > ins[0x6064]


# --- properties -----------------------------------------------------------------------------------------
#: aborts the manuals document for these writes (value range, state, length)
DOCUMENTED = {0x06090030, 0x06090031, 0x06090032, 0x08000022, 0x06070010, 0x06070012, 0x06070013}
_CW = st.one_of(st.sampled_from([0x00, 0x02, 0x06, 0x07, 0x0F, 0x1F, 0x10F, 0x11F, 0x0F | 0x40 | 0x10, 0x80, 0x100]),
                st.integers(0, 0xFFFF))
_OPS = st.one_of(
    st.tuples(st.just("cw"), _CW),
    st.tuples(st.just("mode"), st.sampled_from([1, 3, 6, 8, 9, 0, -1])),
    st.tuples(st.just("halt"), st.integers(-1, 4)),
    st.tuples(st.just("method"), st.integers(-6, 40)),
    st.tuples(st.just("cycles"), st.integers(1, 40)),
    st.tuples(st.just("pdo"), _CW),
    st.tuples(st.just("limits"), st.tuples(st.booleans(), st.booleans())),
)
_DEVICES: dict[str, Drive] = {}


def _fresh(family: str) -> Drive:
    if family not in _DEVICES:
        _DEVICES[family] = Drive.from_esi(corpus_path("esi", INOVANCE)) if family == "generic" else \
            Drive.from_profile(family)
    proto = _DEVICES[family]
    d = at_op(Drive(proto.device, proto.rules))
    d.homing_search_s = Fraction(1, 50)
    w(d, 0x6099, 1, 100, 4)
    return d


@given(st.lists(_OPS, max_size=25), st.sampled_from(["hdt", "technosoft-ipos", "controltechniques", "generic"]))
def test_random_controlword_sequences_keep_statusword_consistent(ops, family):
    """Random controlwords, modes, halt options, homing methods and limit switches raise nothing but
    documented aborts, and the statusword always shows the drive's state and a valid homing pattern (never
    bits 13 and 12 together)."""
    d = _fresh(family)
    m = Master(d)
    for op, value in ops:
        try:
            if op == "cw":
                w(d, 0x6040, 0, value, 2)
            elif op == "mode":
                w(d, 0x6060, 0, value, 1)
            elif op == "halt":
                w(d, 0x605D, 0, value, 2)
            elif op == "method":
                w(d, 0x6098, 0, value, 1)
            elif op == "cycles":
                d.step(value)
            elif op == "limits":
                d.set_limit_switches(negative=value[0], positive=value[1])
            else:
                m.cycle(x6040=value)
        except SdoAbort as exc:
            assert exc.code in DOCUMENTED, (op, value, hex(exc.code))
        sw = r(d, 0x6041)
        assert decode_statusword(sw) is d.cia402_state
        if d.mode() == 6:
            assert sw & 0x3000 != 0x3000
        if d.cia402_state is State.OPERATION_ENABLED and d.cia.controlword & 0x100 and d.cia.velocity == 0:
            assert sw & 0x0400
        if d.cia402_state is not State.OPERATION_ENABLED:
            assert d.cia.velocity == 0
