"""Waits bounded by the slave's own timeouts (issue 37 item 6, issue 35 item 5): the ESI's ``Info/Mailbox/Timeout``
and ``Info/StateMachine/Timeout`` (or documented defaults) set the bus init limit, the master's mailbox wait and
the isolated master's per-SDO limit; an upload that got no answer is repeated, each try after the slave's mailbox
window, a bounded number of times; the timeout error names the slave and what was waited. In process, with the fake
pysoem and a virtual clock (no timed assertion: the clock only moves when the adapter sleeps)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from ecattool import esi
from ecattool.errors import SdoTimeout
from ecattool.sim import Drive
from ecattool.target.pysoem import PysoemTarget
from ecattool.target.timeouts import LINK_WAIT_S, OPEN_MARGIN_S, REPEATS, SII_S, BusLimits, bus_limits, of_device
from tests.conftest import ROOT
from tests.target.fake_pysoem import PREOP_STATE, VirtualClock, make_module

INGENIA = ROOT.parent / "shared" / "corpus" / "esi" / "ingenia_eve-xcr-e_esi.xml"


def _ingenia() -> Any:
    if not INGENIA.exists():
        pytest.skip(f"{INGENIA} is not here (../shared/corpus)")
    return esi.load_device(INGENIA, "0")


def test_the_esi_timeouts_are_read() -> None:
    # ingenia_eve-xcr-e_esi.xml:23-26 <PreopTimeout>2000 <SafeopOpTimeout>5000 <BackToInitTimeout>5000
    # <BackToSafeopTimeout>200; :31-32 <RequestTimeout>100 <ResponseTimeout>2000
    t = of_device(_ingenia())
    assert (t.preop_ms, t.safeop_op_ms, t.back_to_init_ms, t.back_to_safeop_ms) == (2000, 5000, 5000, 200)
    assert (t.request_ms, t.response_ms, t.known) == (100, 2000, True)
    # a built-in profile has no ESI timeouts: the defaults, said as such
    assert not of_device(Drive.from_profile("hdt").device).known


def test_the_limits_scale_with_the_slaves_timeouts() -> None:
    slow = type("Dev", (), {"extra": {"Mailbox/Timeout/RequestTimeout": "500",
                                      "Mailbox/Timeout/ResponseTimeout": "#x1388",  # 5000 ms, in ESI hex
                                      "StateMachine/Timeout/PreopTimeout": "8000"}})()
    limits = bus_limits([_ingenia(), slow], count=3)
    assert limits.mailbox_s == pytest.approx(5.5)  # the longest request + the longest response
    assert limits.sdo_call_s == pytest.approx((REPEATS + 1) * 5.5 + 3.0)
    assert limits.open_s == pytest.approx(LINK_WAIT_S + 8.0 + 3 * SII_S + OPEN_MARGIN_S)
    # an ESI that says an hour is not waited for; nonsense is the default
    odd = type("Dev", (), {"extra": {"Mailbox/Timeout/ResponseTimeout": "3600000",
                                     "Mailbox/Timeout/RequestTimeout": "soon"}})()
    assert of_device(odd).response_ms == 60_000 and of_device(odd).request_ms == 100
    # before: a fixed 30 s for the bus init and 20 s per request, whatever the bus
    assert BusLimits().open_s < 30 and BusLimits().sdo_call_s < 20


def _target(limits: BusLimits | None = None) -> tuple[PysoemTarget, Drive, VirtualClock]:
    drive = Drive.from_profile("hdt")
    clock = VirtualClock()
    target = PysoemTarget("eth0", pysoem_module=make_module([drive]), clock=clock.now, sleep=clock.sleep,
                          keep_cycling=False, limits=limits)
    return target, drive, clock


def test_soem_waits_the_slaves_mailbox_and_preop_timeouts() -> None:
    slow = type("Dev", (), {"extra": {"Mailbox/Timeout/ResponseTimeout": "4000",
                                      "StateMachine/Timeout/PreopTimeout": "6000"}})()
    target, _, _ = _target(bus_limits([slow]))
    assert target.master.sdo_read_timeout == target.master.sdo_write_timeout == 4_100_000
    assert (PREOP_STATE, 6_000_000) in target.master.state_checks


def test_an_upload_without_an_answer_is_repeated_each_after_the_mailbox_window() -> None:
    target, drive, clock = _target()
    s = target.slaves()[0]
    t0 = clock.now()
    for nth in range(1, REPEATS + 1):  # the first tries get no answer, the last one does
        drive.faults.drop_reply(nth)
    assert s.sdo_upload(0x6060, 0, size=1) is not None
    assert s.repeats == REPEATS  # before: asked again once only, at once
    assert clock.now() - t0 >= REPEATS * BusLimits().mailbox_s  # each repeat waited for the window to pass


def test_a_slave_that_never_answers_is_one_timeout_naming_it_and_the_wait() -> None:
    target, drive, clock = _target()
    s = target.slaves()[0]
    for nth in range(1, REPEATS + 2):
        drive.faults.drop_reply(nth)
    with pytest.raises(SdoTimeout) as ei:
        s.sdo_upload(0x6060, 0, size=1)
    assert str(ei.value) == ("SDO timeout on 0x6060:00 of slave 0 (fake): no reply in 3 tries of 2.1 s (default: "
                             "request 0.1 s + response 2 s)")
    assert s.repeats == REPEATS


def test_open_bus_passes_the_projects_timeouts_to_the_master(monkeypatch: pytest.MonkeyPatch) -> None:
    from ecattool.online import bus_state, targets
    from ecattool.online.live import LiveBus

    seen: list[BusLimits | None] = []

    def isolated(spec: str, opener: Any, limits: BusLimits | None = None) -> LiveBus:
        seen.append(limits)
        return LiveBus(spec, [])

    monkeypatch.setattr(targets, "isolated_bus", isolated)
    monkeypatch.setattr(bus_state, "guard", lambda ifname, reset, sii=False: [object(), object()])  # two slaves found
    monkeypatch.setattr("ecattool.target.pysoem._import_pysoem", lambda: None)
    targets.open_bus("pysoem:eth9", [_ingenia()])
    (limits,) = seen
    assert limits is not None and limits.count == 2 and limits.slaves[0].known
    assert limits.open_s == pytest.approx(LINK_WAIT_S + 2.0 + 2 * SII_S + OPEN_MARGIN_S)


def test_the_docs_say_the_bounds() -> None:
    text = (Path(ROOT) / "docs" / "at-the-machine.md").read_text(encoding="utf-8")
    assert "### How long ecattool waits" in text and "RequestTimeout" in text and "PreopTimeout" in text
