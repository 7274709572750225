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
    return st.lists(one(), min_size=1, max_size=12)  # an export of nothing is refused (tested in test_startup_fuzz)


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
    assert len(slaves) == 1
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


@given(commands(transitions=st.just("PS"), sizes=st.sampled_from([1, 2, 4]), complete_access=st.just(False)))
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


def test_sync_managers_survive_json_and_eni():
    """A project's ENI carries the sync managers' StartAddress/ControlByte and the mailbox Send/Recv. JSON (documented
    as lossless for SlaveConfig) dropped the sync managers and the ENI reader ignored them, so project -> json -> eni
    and eni -> eni wrote an ENI without them (and PDOs lost their sync manager)."""
    from ecattool import esi, pdo
    from tests.conftest import corpus_path

    device = esi.load_device(corpus_path("esi", "copley_XE2_4.60.xml"))
    mapping = pdo.Mapping.from_text(rx="0x1600=0x6040:00/16,0x607A:00/32,0x6060:00/8,gap/8",
                                    tx="0x1A00=0x6041:00/16,0x6064:00/32,0x60F4:00/32", device=device)
    cfg = SlaveConfig.from_device(device, pdo.program(device, mapping), mapping=mapping, position=0,
                                  dc_opmode="DcSync", dc_cycle_ns=1_000_000)
    eni = export(cfg, "eni")
    assert "<StartAddress>4608</StartAddress>" in eni and "<Send>" in eni
    (via_json,) = import_bytes(export(cfg, "json").encode(), "x.json")
    def fields(sms):
        return [{k: v for k, v in s.as_dict().items() if k != "location"} for s in sms]

    assert fields(via_json.sync_managers) == fields(cfg.sync_managers)
    assert export(via_json, "eni") == eni
    (via_eni,) = import_bytes(eni.encode(), "x.xml", "eni")
    assert export(via_eni, "eni") == eni
    assert [(p.index, p.sm) for p in via_eni.rx_pdos + via_eni.tx_pdos] == [(0x1600, 2), (0x1A00, 3)]
    assert [(s.number, s.kind, s.start_address) for s in via_eni.sync_managers] == [
        (0, "MBoxOut", 0x1000), (1, "MBoxIn", 0x1100), (2, "Outputs", 0x1200), (3, "Inputs", 0x1800)]
