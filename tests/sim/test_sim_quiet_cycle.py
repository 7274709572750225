"""The drive skips a process data cycle that would change nothing (issue 26): the same outputs as the
cycle before, from the state that cycle left unchanged. These tests run the same sequences of outputs (and
SDO writes between cycles) through a drive that may skip and one that never does, and compare everything
after every cycle: the inputs, the store, the CiA-402 model, the events and the emergencies."""

from __future__ import annotations

import struct

from hypothesis import given, settings
from hypothesis import strategies as st

from ecattool.errors import SdoAbort
from ecattool.esi.model import Direction
from ecattool.od.model import EcState
from ecattool.sim import Drive

#: controlwords a master sends: 0, shutdown, switch on, enable, enable + halt, fault reset, enable + new
#: set-point (PP), quick stop
CONTROLWORDS = (0x00, 0x06, 0x07, 0x0F, 0x10F, 0x80, 0x1F, 0x02)
#: modes of operation written by SDO: PP, PV, homing, CSP, CSV
MODES = (1, 3, 6, 8, 9)


def _in_op(family: str, record_events: bool = True) -> Drive:
    d = Drive.from_profile(family)
    d.record_events = record_events  # without events an SDO write between cycles leaves no trace in the count
    for state in (EcState.PREOP, EcState.SAFEOP, EcState.OP):
        d.request_state(state)
    return d


def _outputs(d: Drive, controlword: int, target: int) -> bytes:
    out = bytearray(d.process_image_sizes()[0])
    for index, _sub, offset, bits in d.layout[Direction.RX].entries:
        at = offset // 8
        if index == 0x6040 and bits == 16:
            out[at:at + 2] = struct.pack("<H", controlword)
        elif index in (0x607A, 0x60FF) and bits == 32:
            out[at:at + 4] = struct.pack("<i", target)
    return bytes(out)


def _observed(d: Drive) -> tuple[object, ...]:
    return (dict(d._store), sorted(vars(d.cia).items(), key=lambda kv: kv[0]) if d.cia.move is None
            else None, [(e.kind, e.data) for e in d.events], [m.to_bytes() for m in d.emergencies],
            d.state(), d.cia402_state)


# a step: (controlword index, target, cycles on these outputs, an SDO write of the mode before it or None)
STEP = st.tuples(st.integers(0, len(CONTROLWORDS) - 1), st.sampled_from((0, 0, 5, -300, 100_000)),
                 st.integers(1, 4), st.one_of(st.none(), st.sampled_from(MODES)))


@settings(max_examples=25, deadline=None)
@given(family=st.sampled_from(("hdt", "technosoft-ipos", "controltechniques")),
       steps=st.lists(STEP, min_size=1, max_size=12), record_events=st.booleans())
def test_skipping_quiet_cycles_changes_nothing(family: str, steps: list[tuple[int, int, int, int | None]],
                                               record_events: bool) -> None:
    fast, general = _in_op(family, record_events), _in_op(family, record_events)
    for cw_at, target, cycles, mode in steps:
        if mode is not None:
            outcomes = []
            for d in (fast, general):
                try:
                    d.sdo_download(0x6060, 0, bytes([mode]))
                    outcomes.append(None)
                except SdoAbort as abort:
                    outcomes.append(abort.code)
            assert outcomes[0] == outcomes[1]
        outputs = _outputs(fast, CONTROLWORDS[cw_at], target)
        for _ in range(cycles):
            general._quiet = None  # the general path every cycle
            got, want = fast.exchange(outputs), general.exchange(outputs)
            assert got == want
            assert _observed(fast) == _observed(general)


def test_an_idle_drive_skips_and_still_follows_what_changes_between_cycles() -> None:
    """An enabled drive at standstill in CSP skips its repeated cycles, and what changes between two of them
    (the mode by SDO, a limit switch) is seen on the next cycle, as by a drive that never skips."""
    fast, general = _in_op("hdt", record_events=False), _in_op("hdt", record_events=False)
    for d in (fast, general):
        d.sdo_download(0x6060, 0, b"\x08")
        for cw in (0x06, 0x07, 0x0F):
            d.exchange(_outputs(d, cw, 0))
    idle = _outputs(fast, 0x0F, 0)
    first = fast.exchange(idle)
    fast.exchange(idle)
    cached = fast._quiet
    assert cached is not None and cached[1] is not None, "standstill on the same outputs: a fixed point"
    assert fast.exchange(idle) == first and fast._quiet is cached  # skipped
    changes = (lambda d: d.sdo_download(0x6060, 0, b"\x09"),  # CSV: the mode display and statusword change
               lambda d: d.set_limit_switches(negative=True),  # 60FDh and statusword bit 11
               lambda d: d.set_limit_switches())
    for change in changes:
        for d in (fast, general):
            change(d)
        for _ in range(3):
            general._quiet = None
            assert fast.exchange(idle) == general.exchange(idle)
            assert _observed(fast) == _observed(general)
    assert fast.exchange(idle) != first  # CSV now
