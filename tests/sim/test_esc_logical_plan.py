"""The ESC's planned logical access (``Esc.logical``: slice copies per FMMU share, made once per address and length
until an SM or FMMU register is written) equals the general way (``Esc.logical_general``: every share through the
ECAT read and write, segment by segment) for random sync managers and FMMUs: bit offsets, shares over register
space, mailbox areas, SM boundaries and the memory end, SMs the application has deactivated, LRD/LWR/LRW at random
logical addresses, configurations rewritten between accesses. Compared: the working counter flags, the datagram,
the ESC's memory, its SM buffer states and watchdog, and what the application was told, in order."""

from __future__ import annotations

import struct

from hypothesis import given, settings
from hypothesis import strategies as st

from ecattool.sim.esc import Esc, EscApplication
from ecattool.sim.esc import registers as R

_RAM = 0x400  # a small process RAM: FMMUs and SMs past its end are likely
_SII = bytes(128)


class _Recorder(EscApplication):
    def __init__(self) -> None:
        self.told: list[tuple[object, ...]] = []

    def buffer_written(self, esc: Esc, sm: int, data: bytes) -> None:
        self.told.append(("written", sm, data))

    def buffer_read(self, esc: Esc, sm: int) -> None:
        self.told.append(("read", sm))

    def mailbox_written(self, esc: Esc, sm: int, data: bytes) -> None:
        self.told.append(("mbx written", sm, data))

    def mailbox_read(self, esc: Esc, sm: int) -> None:
        self.told.append(("mbx read", sm))


#: SM areas start at a few places so that FMMUs map onto them, across their ends, or next to them
_AREAS = (0x1000, 0x1008, 0x1010, 0x1020, 0x1000 + _RAM - 8)
_address = st.one_of(st.sampled_from(_AREAS), st.sampled_from(_AREAS).map(lambda a: a + 2),
                     st.integers(0x1000, 0x1000 + _RAM + 8), st.integers(0x0F00, 0x1000), st.integers(0, 0x20))
_buffered = st.sampled_from([0x64, 0x20, 0x24, 0x44, 0x00, 0x04])
_mailbox = st.sampled_from([0x02, 0x06, 0x26, 0x22])
_sm = st.tuples(_address, st.integers(0, 24), st.one_of(_buffered, _buffered, _mailbox),
                st.integers(0, 4).map(lambda k: k > 0))
_bit = st.one_of(st.just(0), st.integers(0, 7))


@st.composite
def _fmmu_onto(draw: st.DrawFn, sm: tuple[int, int, int, bool]) -> tuple[int, ...]:
    """An FMMU mapping (most often exactly) the area of ``sm``, on whole bytes or with bit offsets."""
    start, length, _, _ = sm
    physical = draw(st.one_of(st.just(start), st.just(start), st.integers(start, start + max(0, length - 1)),
                              st.integers(start - 2, start + length + 2), _address))
    size = draw(st.one_of(st.just(max(1, length)), st.just(max(1, length)), st.integers(1, 12)))
    whole = draw(st.booleans())
    return (draw(st.integers(0, 40)), size, 0 if whole else draw(_bit), 7 if whole else draw(_bit), physical,
            0 if whole else draw(_bit), draw(st.integers(1, 3)), draw(st.integers(0, 5)) > 0)


@st.composite
def _config(draw: st.DrawFn) -> tuple[list[tuple[int, int, int, bool]], list[tuple[int, ...]], list[object]]:
    """SMs as a master sets them for process data (SM2 outputs, SM3 inputs, each in its own area; SM0 and SM1
    anything), FMMUs that mostly map SM2's and SM3's areas, and steps: logical accesses (most over an FMMU's whole
    range and some bytes around it), SM and FMMU rewrites, SMs the application deactivates, time passing."""
    ram = st.integers(0x1000, 0x1000 + _RAM - 12)
    out_sm = (draw(ram), draw(st.integers(1, 12)), draw(st.sampled_from([0x64, 0x24, 0x44])), True)
    in_sm = (draw(ram), draw(st.integers(1, 12)), draw(st.sampled_from([0x20, 0x00])), True)
    sms = [draw(_sm), draw(_sm), out_sm, in_sm]
    fmmus = [draw(_fmmu_onto(out_sm)), draw(_fmmu_onto(in_sm))]
    fmmus += draw(st.lists(st.sampled_from(sms).flatmap(_fmmu_onto), max_size=2))
    cmd = st.sampled_from(["LRD", "LWR", "LRW"])
    covering = st.sampled_from(fmmus).flatmap(lambda f: st.tuples(
        cmd, st.integers(max(0, f[0] - 3), f[0]), st.binary(min_size=f[1] + 3, max_size=f[1] + 6)))
    anywhere = st.tuples(cmd, st.integers(0, 48), st.binary(min_size=1, max_size=16))
    access = st.one_of(covering, covering, anywhere)
    steps = draw(st.lists(st.one_of(
        st.tuples(st.just("access"), access), st.tuples(st.just("access"), access),
        st.tuples(st.just("access"), access),
        st.tuples(st.just("sm"), st.integers(0, 3), _sm),
        st.tuples(st.just("fmmu"), st.integers(0, 3), st.sampled_from(sms).flatmap(_fmmu_onto)),
        st.tuples(st.just("pdi off"), st.integers(0, 3), st.booleans()),
        st.tuples(st.just("time"), st.integers(0, 10**9))), min_size=1, max_size=25))
    return sms, fmmus, steps


def _sm_regs(start: int, length: int, control: int, enable: bool) -> bytes:
    return struct.pack("<HHBBBB", start, length, control, 0, 1 if enable else 0, 0)


def _fmmu_regs(logical: int, length: int, start_bit: int, stop_bit: int, physical: int, physical_bit: int,
               kind: int, enable: bool) -> bytes:
    return struct.pack("<IHBBHBBBxxx", logical, length, start_bit, stop_bit, physical, physical_bit, kind,
                       1 if enable else 0)


def _state(esc: Esc, app: _Recorder) -> tuple[object, ...]:
    return bytes(esc.mem), list(esc._sm_full), esc._wd_pd_since, list(app.told)


@settings(max_examples=150, deadline=None)
@given(config=_config())
def test_the_planned_access_equals_the_general_one(
        config: tuple[list[tuple[int, int, int, bool]], list[tuple[int, ...]], list[tuple[object, ...]]]) -> None:
    sms, fmmus, steps = config
    pair = []
    for _ in range(2):
        app = _Recorder()
        esc = Esc(_SII, app=app, ram_bytes=_RAM, sms=4, fmmus=4)
        esc.begin_frame(0, None)
        for n, sm in enumerate(sms):
            esc.ecat_write(R.SM + R.SM_SIZE * n, _sm_regs(*sm))
        for n, f in enumerate(fmmus):
            esc.ecat_write(R.FMMU + R.FMMU_SIZE * n, _fmmu_regs(*f))
        esc.ecat_write(0x1000, bytes(range(256)) * (_RAM // 256))  # plain RAM and SM buffers with something in
        pair.append((esc, app))
    (fast, fast_app), (general, general_app) = pair
    assert _state(fast, fast_app) == _state(general, general_app)
    for step in steps:
        outcomes = []
        for esc, logical in ((fast, fast.logical), (general, general.logical_general)):
            if step[0] == "access":
                cmd, address, payload = step[1]  # type: ignore[misc]
                data = bytearray(payload)
                flags = logical(address, data, cmd != "LWR", cmd != "LRD")
                outcomes.append((flags, bytes(data)))
            elif step[0] == "sm":
                n, sm = step[1], step[2]
                esc.ecat_write(R.SM + R.SM_SIZE * n, _sm_regs(*sm))  # type: ignore[misc,operator]
            elif step[0] == "fmmu":
                n, f = step[1], step[2]
                esc.ecat_write(R.FMMU + R.FMMU_SIZE * n, _fmmu_regs(*f))  # type: ignore[misc,operator]
            elif step[0] == "pdi off":
                esc.pdi_deactivate(step[1], step[2])  # type: ignore[arg-type]
            else:
                esc.begin_frame(step[1], None)  # type: ignore[arg-type]
        if outcomes:
            assert outcomes[0] == outcomes[1], step
        assert _state(fast, fast_app) == _state(general, general_app), step


def test_the_common_process_data_access_is_planned_and_a_mailbox_one_is_not() -> None:
    """The test above compares both ways wherever the plan applies; this one makes sure it applies where it
    should (SOEM's process data: an output and an input SM, one FMMU each) and not over a mailbox area."""
    esc = Esc(_SII, app=_Recorder(), ram_bytes=_RAM, sms=4, fmmus=4)
    esc.begin_frame(0, None)
    esc.ecat_write(R.SM + 2 * R.SM_SIZE, _sm_regs(0x1100, 4, 0x64, True) + _sm_regs(0x1180, 4, 0x20, True))
    esc.ecat_write(R.FMMU, _fmmu_regs(0, 4, 0, 7, 0x1100, 0, 2, True) + _fmmu_regs(4, 4, 0, 7, 0x1180, 0, 1, True))
    assert esc.logical(0, bytearray(8), True, True) == (True, True)
    plan = esc._plans[(0, 8)]
    assert not plan.general and len(plan.ops) == 2 and not plan.copy
    esc.ecat_write(R.SM, _sm_regs(0x1180, 4, 0x26, True))  # SM0 a mailbox over SM3's area: SM0 serves it
    assert (0, 8) not in esc._plans  # the SM write forgot the plan
    esc.logical(0, bytearray(8), True, True)
    assert esc._plans[(0, 8)].general
