"""The pysoem target, tested against a fake pysoem module (tests/target/fake_pysoem.py) whose slaves are simulated
drives; the fake follows pysoem's API (checked against the real module in test_pysoem_surface.py)."""

import pytest

from ecattool.errors import SdoAbort, SdoTimeout, StateChangeError, TargetError
from ecattool.od.model import EcState
from ecattool.sim import Drive
from ecattool.target.pysoem import PysoemTarget, dc_sync_args
from tests.target.fake_pysoem import STATE_ERROR, VirtualClock, make_module


def bus(*profiles):
    drives = [Drive.from_profile(p) for p in profiles or ("technosoft-ipos",)]
    clock = VirtualClock()
    target = PysoemTarget("eth0", pysoem_module=make_module(drives), clock=clock.now, sleep=clock.sleep,
                          keep_cycling=False)
    target.master.clock = clock
    return target, drives


def test_sdo_and_aborts():
    t, (drive,) = bus()
    s = t.slaves()[0]
    assert s.identity() == drive.identity()
    assert s.state() is EcState.PREOP  # config_init requested PRE-OP
    s.sdo_download(0x6060, 0, b"\x01")
    assert s.sdo_upload(0x6060, 0) == b"\x01"
    with pytest.raises(SdoAbort) as ei:
        s.sdo_upload(0x1234, 0)
    assert ei.value.code == 0x06020000
    with pytest.raises(SdoAbort) as ei:
        s.sdo_download(0x6041, 0, b"\x00\x00")
    assert ei.value.code == 0x06010002
    # the Technosoft reset gets no reply (pysoem: WkcError): fine when no reply is expected, a timeout otherwise
    drive.faults.drop_reply(1, execute=False)
    s.sdo_download(0x6060, 0, b"\x01", expect_reply=False)
    drive.faults.drop_reply(1, execute=False)
    with pytest.raises(SdoTimeout):
        s.sdo_download(0x6060, 0, b"\x01")


def test_large_objects_are_read_with_a_larger_buffer():
    t, (drive,) = bus()
    s = t.slaves()[0]
    fake = s._slave
    fake.drive = type("Big", (), {"sdo_upload": lambda self, i, sub, ca: b"x" * 300})()
    assert s.sdo_upload(0x1008, 0) == b"x" * 300  # pysoem's 256-byte default buffer would not hold it


def test_emergencies_do_not_break_sdo_transfers():
    t, _ = bus()
    s = t.slaves()[0]
    s._slave.pending_emergencies.append((0x8611, 0x80))
    assert s.sdo_upload(0x6060, 0) is not None
    assert [e.error_code for e in s.emergencies] == [0x8611]


def test_states_refusals_and_acknowledge():
    t, (drive,) = bus()
    s = t.slaves()[0]
    s.request_state(EcState.SAFEOP)
    assert t.mapped and s.state() is EcState.SAFEOP
    drive.faults.refuse_state(EcState.OP, 0x001D)
    with pytest.raises(StateChangeError) as ei:
        s.request_state(EcState.OP)
    assert ei.value.al_status == 0x001D
    assert s._slave.state & STATE_ERROR  # the slave shows the error indication ...
    s.request_state(EcState.PREOP)  # ... and takes the next request only because the master acknowledges it
    assert s.state() is EcState.PREOP and not s._slave.state & STATE_ERROR


def test_exchange_checks_the_image_and_the_working_counter():
    t, (drive,) = bus()
    s = t.slaves()[0]
    s.request_state(EcState.SAFEOP)
    size = len(s._slave.output)
    assert size > 0  # the size config_map read from the drive's PDO assignment
    assert len(s.exchange(bytes(size))) == len(s._slave.input) > 0
    with pytest.raises(TargetError, match="output bytes"):
        s.exchange(bytes(size + 1))  # pysoem would memcpy it past the slave's image
    s.request_state(EcState.PREOP)
    with pytest.raises(TargetError, match="working counter 0"):
        s.exchange(bytes(size))


def test_a_wrong_process_data_working_counter_is_an_error():
    """In SAFE-OP only the inputs count (1 of 3); in OP anything but the full count means a slave missed its part
    of the frame, and more than the full count is never right (tests/wire/test_wire_faults.py: the same on the wire)."""
    t, _ = bus()
    s = t.slaves()[0]
    s.request_state(EcState.SAFEOP)
    size = len(s._slave.output)
    s.exchange(bytes(size))  # working counter 1 of 3: the outputs do not count before OP
    s.request_state(EcState.OP)
    s.exchange(bytes(size))
    received = t.master.receive_processdata
    for delta in (+1, -1):
        t.master.receive_processdata = lambda timeout=2000, d=delta: received(timeout) + d
        with pytest.raises(TargetError, match=f"working counter {3 + delta}, expected 3"):
            s.exchange(bytes(size))


def test_dc_is_configured_once_and_activation_is_mapped():
    t, (drive,) = bus()
    s = t.slaves()[0]
    s.configure_dc(0x0300, 1_000_000, 250_000)
    assert t.dc_configured and s._slave.dc == (0x03, 1_000_000, 250_000, None)
    assert drive.dc == (0x0300, 1_000_000)
    s.configure_dc(0x0730, 1_000_000)  # SYNC0 + SYNC1; the latch bits of the low byte are not pysoem's
    assert s._slave.dc == (0x07, 1_000_000, 0, 0)
    s.configure_dc(0, 0)
    assert s._slave.dc[0] == 0
    with pytest.raises(TargetError, match="0x0100"):
        s.configure_dc(0x0100, 1_000_000)
    assert dc_sync_args(0x0300, 2_000_000) == (True, 2_000_000, 0)


def test_mapping_errors_are_target_errors():
    t, (drive,) = bus()
    s = t.slaves()[0]
    drive.faults.abort_sdo(1, 0x06020000)  # the first CoE read of config_map
    with pytest.raises(TargetError, match=r"PDO mappings .*slave 0, 0x1C12:00"):
        s.request_state(EcState.SAFEOP)


def test_open_failures_are_target_errors(monkeypatch):
    import ecattool.target.pysoem as adapter

    monkeypatch.setattr(adapter, "LINK_WAIT_S", 0.3)
    with pytest.raises(TargetError, match="cannot open"):
        PysoemTarget("nope", pysoem_module=make_module([Drive.from_profile("hdt")]))
    with pytest.raises(TargetError, match="no EtherCAT slaves"):
        PysoemTarget("eth0", pysoem_module=make_module([]))


def test_a_link_that_drops_the_first_frames_is_asked_again():
    """A veth pair or a NIC just brought up loses the first frames: the first config_init finds nobody."""
    module = make_module([Drive.from_profile("hdt")])
    real = module.Master.config_init
    calls = []

    def late(self, *a, **k):
        calls.append(1)
        return -1 if len(calls) < 3 else real(self, *a, **k)

    module.Master.config_init = late
    t = PysoemTarget("eth0", pysoem_module=module)
    assert len(t.slaves()) == 1 and len(calls) == 3


def test_process_data_is_paced_to_the_sync0_cycle():
    t, _ = bus()
    s = t.slaves()[0]
    s.configure_dc(0x0300, 2_000_000)
    s.request_state(EcState.SAFEOP)
    for _ in range(3):
        s.exchange(bytes(len(s._slave.output)))
    sent = t.master.sent_at
    assert [round(b - a, 9) for a, b in zip(sent, sent[1:])] == [0.002, 0.002]  # virtual clock, no real waiting


def test_dc_without_a_sync0_cycle_runs_sync0_at_the_bus_cycle():
    # a SYNC0 cycle time of 0 is the ESC's single-shot mode (one pulse, then none): a project's dc: without
    # cycle_ns must not switch a drive's SYNC0 off; it runs at the cycle the target exchanges process data
    t, (drive,) = bus()
    s = t.slaves()[0]
    s.configure_dc(0x0300)
    assert s._slave.dc == (0x03, 1_000_000, 0, None) and drive.dc == (0x0300, 1_000_000)
    assert t.cycle_s == pytest.approx(0.001)


def _op_on_real_time(**kwargs):
    """One HDT in OP through a target on the real clock, its keeper thread running."""
    drive = Drive.from_profile("hdt")
    t = PysoemTarget("eth0", pysoem_module=make_module([drive]), **kwargs)
    s = t.slaves()[0]
    s.request_state(EcState.SAFEOP)
    s.exchange(bytes(len(s._slave.output)))
    s.request_state(EcState.OP)
    return t, s, drive


def test_the_keeper_cycles_while_the_caller_waits_for_an_sdo():
    """A drive's watchdog takes it out of OP when no outputs come for 100 ms (tests/wire/test_wire_slave.py): while the
    caller waits for a slow SDO answer, the keeper thread sends the last outputs. The fake's SDO waits with the
    GIL released, as pysoem's does once always_release_gil is set."""
    import time

    t, s, drive = _op_on_real_time()
    try:
        assert t.master.always_release_gil is True
        outputs = bytes([6, 0]) + bytes(len(s._slave.output) - 2)  # controlword 6 (shutdown)
        s.exchange(outputs)
        before = len(t.master.sent_at)
        slow = s._slave.sdo_read

        def slow_read(*args, **kwargs):
            time.sleep(0.3)  # the drive is slow to answer (e.g. storing parameters)
            return slow(*args, **kwargs)

        s._slave.sdo_read = slow_read
        s.sdo_upload(0x6041, 0)
        kept = t.kept_cycles
        assert kept > 0 and len(t.master.sent_at) - before >= kept
        # one cycle per 10 ms (a tenth of the 100 ms watchdog), not one per bus cycle: 300 ms hold about 30
        assert t.keep_interval_s == pytest.approx(0.010) and kept <= 0.3 / 0.010 + 3
        assert s._slave.output == outputs and drive.value(0x6040) == 6  # the last outputs, held
        assert s.state() is EcState.OP
    finally:
        t.close()
    assert t._keeper is not None and not t._keeper.is_alive()  # close() ends it


@pytest.mark.parametrize(("watchdogs_ms", "interval_s"), [
    ((100.0, 100.0), 0.010),  # the ESC default: a tenth of it
    ((100.0, 30.0), 0.003),  # the shortest watchdog on the bus counts
    ((0.0, 50.0), 0.005),  # a switched-off watchdog (0) does not
    ((1.0, 100.0), 0.002),  # never less than two bus cycles
])
def test_the_keeper_rests_a_tenth_of_the_shortest_watchdog(watchdogs_ms, interval_s):
    """The keeper does not send every bus cycle: SOEM polls its socket without sleeping while it waits for a
    frame, and a keeper at 1 kHz beside a waiting SDO kept two cores busy (the frames then came back too late
    on a 2-core machine and the SDO failed with no reply)."""
    drives = [Drive.from_profile("hdt"), Drive.from_profile("hdt")]
    t = PysoemTarget("eth0", pysoem_module=make_module(drives), keep_cycling=False)
    for slave, ms in zip(t.master.slaves, watchdogs_ms):
        slave.set_watchdog("processdata", ms)
    t.map()
    assert t.keep_interval_s == pytest.approx(interval_s)


def test_the_keeper_stops_by_itself_when_the_caller_is_gone():
    t, s, _ = _op_on_real_time(keeper_idle_s=0.05)
    assert t._keeper is not None
    t._keeper.join(timeout=10)  # bounded: it ends by itself 50 ms after the last use
    assert not t._keeper.is_alive()
    t.close()


def test_a_drive_that_leaves_op_by_itself_is_reported():
    """In SAFE-OP a drive still takes its outputs and the working counter stays full: the adapter reads the AL
    status every STATE_POLL_S of process data and names what happened."""
    t, (drive,) = bus("hdt")
    s = t.slaves()[0]
    s.request_state(EcState.SAFEOP)
    s.exchange(bytes(len(s._slave.output)))
    s.request_state(EcState.OP)
    for _ in range(5):
        s.exchange(bytes(len(s._slave.output)))
    drive.lose_communication()  # e.g. its watchdog expired
    with pytest.raises(TargetError, match="slave 0 left OP by itself: it is in SAFEOP"):
        for _ in range(200):  # 100 ms of 1 ms cycles at the most
            s.exchange(bytes(len(s._slave.output)))


def test_open_advice_names_root_or_cap_net_raw_and_a_missing_interface():
    """Issue 35 item 8: a non-root pysoem user got "could not open interface" with no word of root."""
    from ecattool.target.pysoem import open_advice

    assert "run as root, or give the Python interpreter CAP_NET_RAW" in open_advice("lo", euid=1000)
    assert open_advice("lo", euid=0) == ""
    assert "this machine has no network interface 'nope0'" in open_advice("nope0", euid=1000)


def test_a_non_root_user_is_told_about_root_and_cap_net_raw():
    """The real pysoem and KickCAT, run as user 'nobody' on the loopback interface: one line naming the fix."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    if os.geteuid() != 0:
        pytest.skip("needs root to run a command as another user")
    root = Path(__file__).resolve().parents[2]
    for spec in ("pysoem:lo", "kickcat:lo"):
        try:
            __import__(spec.split(":")[0])
        except ImportError:
            continue
        try:
            done = subprocess.run([sys.executable, "-m", "ecattool", "sdo", "read", "0x1018:01", "--target", spec],
                                  capture_output=True, text=True, timeout=60, cwd=root, user=65534, group=65534,
                                  extra_groups=[], env={**os.environ, "PYTHONPATH": str(root)})
        except PermissionError:  # this interpreter lives where user 'nobody' may not go (e.g. under /root)
            pytest.skip(f"user 'nobody' cannot run {sys.executable}")
        assert done.returncode == 1 and done.stdout == "", done
        lines = done.stderr.strip().splitlines()
        assert len(lines) == 1 and "cannot open EtherCAT interface 'lo'" in lines[0], done.stderr
        assert "run as root, or give the Python interpreter CAP_NET_RAW" in lines[0], done.stderr
