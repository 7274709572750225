"""Property tests: random startup lists survive export -> import for every format that reads and writes,
and the text parsers answer garbage with an InputError (never a crash)."""

from __future__ import annotations

import string

import pytest
from hypothesis import given
from hypothesis import strategies as st

from ecattool.errors import EcatToolError, InputError
from ecattool.esi.model import Identity
from ecattool.startup import SlaveConfig, StartupCommand, StartupList, export, import_bytes
from ecattool.startup.formats._common import one_line
from ecattool.startup.model import TRANSITIONS

COMMENT = st.text(alphabet=string.ascii_letters + string.digits + " ,.:;-_()/=+*'\"[]{}#", max_size=40)


def commands(transitions=st.sampled_from(TRANSITIONS), sizes=st.integers(1, 12), complete_access=st.booleans(),
             comment=COMMENT, ca_sub_zero: bool = False):
    @st.composite
    def one(draw):
        ca = draw(complete_access)
        size = draw(sizes)
        return StartupCommand(draw(transitions), draw(st.integers(0, 0xFFFF)),
                              0 if (ca and ca_sub_zero) else draw(st.integers(0, 0xFF)),
                              draw(st.binary(min_size=size, max_size=size)), comment=draw(comment),
                              complete_access=ca, timeout_ms=draw(st.integers(0, 60000)))
    return st.lists(one(), max_size=12)


def _config(cmds, position=None) -> SlaveConfig:
    return SlaveConfig(StartupList(list(cmds), name="drive"), name="drive", position=position,
                       identity=Identity(0x1A3, 0x019F418D))


def _basic(cmds):
    return [(c.transition, c.index, c.subindex, c.data, c.complete_access) for c in cmds]


@given(commands(), st.integers(0, 100))
def test_json_round_trip(cmds, position):
    (back,) = import_bytes(export(_config(cmds, position), "json").encode(), "x.json")
    assert _basic(back.commands) == _basic(cmds)
    assert [(c.comment, c.timeout_ms) for c in back.commands] == [(c.comment, c.timeout_ms) for c in cmds]
    assert back.position == position


@given(commands())
def test_csv_round_trip(cmds):
    slaves = import_bytes(export(_config(cmds, 0), "csv").encode(), "x.csv")
    assert len(slaves) == (1 if cmds else 0)  # CSV rows are commands: no commands, no slave
    back = [c for s in slaves for c in s.commands]
    assert _basic(back) == _basic(cmds)
    assert [(c.comment, c.timeout_ms) for c in back] == [(c.comment, c.timeout_ms) for c in cmds]


@given(commands())
def test_eni_round_trip(cmds):
    (back,) = import_bytes(export(_config(cmds, 3), "eni").encode(), "x.xml")
    assert _basic(back.commands) == _basic(cmds)
    assert [(c.comment, c.timeout_ms) for c in back.commands] == [(c.comment, c.timeout_ms) for c in cmds]
    assert back.position == 3 and back.identity.vendor_id == 0x1A3


@given(commands())
def test_twincat_round_trip(cmds):
    (back,) = import_bytes(export(_config(cmds), "twincat").encode(), "x.txt", "twincat")
    assert _basic(back.commands) == _basic(cmds)
    assert [c.comment for c in back.commands] == [one_line(c.comment) for c in cmds]


@given(commands(transitions=st.just("PS"), ca_sub_zero=True))
def test_ecmc_round_trip(cmds):
    (back,) = import_bytes(export(_config(cmds, 1), "ecmc").encode(), "x.cmd")
    assert _basic(back.commands) == _basic(cmds)
    assert [c.comment for c in back.commands] == [one_line(c.comment) for c in cmds]


@given(assign=st.integers(1, 0xFFFF), cycle=st.integers(1, 0xFFFFFFFF), shift=st.integers(-(1 << 31), (1 << 31) - 1))
def test_ecmc_round_trip_keeps_distributed_clocks(assign, cycle, shift):
    # a Control Techniques drive in CSP stays in SAFE-OP without its DC settings: ecmc writes them with
    # Cfg.EcSlaveConfigDC(slave, assign_activate, sync0_cycle, sync0_shift, sync1_cycle, sync1_shift); no (0) cycle
    # is the ecmc sample rate, see test_ecmc_dc_without_cycle_runs_at_the_ecmc_sample_rate
    cfg = _config([], 1)
    cfg.dc_assign_activate, cfg.dc_cycle_ns, cfg.dc_shift_ns = assign, cycle, shift
    (back,) = import_bytes(export([cfg], "ecmc").encode(), "x.cmd")
    assert (back.dc_assign_activate, back.dc_cycle_ns, back.dc_shift_ns) == (assign, cycle, shift)


@given(commands(transitions=st.just("PS"), sizes=st.sampled_from([1, 2, 4, 8]), complete_access=st.just(False)))
def test_ros2_round_trip(cmds):
    (back,) = import_bytes(export(_config(cmds), "ros2").encode(), "x.yaml")
    assert _basic(back.commands) == _basic(cmds)
    assert [c.comment for c in back.commands] == [one_line(c.comment) for c in cmds]


@pytest.mark.parametrize("fmt", ["twincat", "ecmc", "csv", "json", "eni", "ros2", "lcec"])
@given(st.binary(max_size=300))
def test_parsers_answer_garbage_with_input_errors(fmt, data):
    try:
        import_bytes(data, "garbage", fmt)
    except InputError:
        pass
    except EcatToolError as exc:  # pragma: no cover - would be a wrong error class
        raise AssertionError(f"unexpected {type(exc).__name__}: {exc}") from exc


@pytest.mark.parametrize("fmt", ["twincat", "ecmc"])
@given(st.text(alphabet=string.printable, max_size=200))
def test_line_parsers_answer_near_miss_text_with_input_errors(fmt, text):
    prefix = {"twincat": "<PS>,CoE,", "ecmc": 'ecmcConfigOrDie "Cfg.EcAddSdo('}[fmt]
    try:
        import_bytes((prefix + text).encode(), "near", fmt)
    except InputError:
        pass
