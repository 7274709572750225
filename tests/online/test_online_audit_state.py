"""``audit`` (issue 35 item 4): a drive found in INIT, BOOT or with the AL error indication before the master reset
the bus is drift (the project expects every drive at least in PRE-OP without error); objects mapped into the
drive's RxPDOs are process data -- the master writes them every cycle -- listed apart, not drift. Before: HDT's
6081h/6083h (in its default RxPDOs) were drift on any bus a master had sent process data on, and three slaves in
INIT with an AL error gave "no drift", exit 0."""

from __future__ import annotations

import json

import pytest

from ecattool.online import audit, open_bus
from ecattool.online.bus_state import Found
from ecattool.project.machine import load_machine
from tests.conftest import run

HDT = "samples/hdt/project.yaml"


def test_objects_in_the_rxpdos_are_process_data_not_drift() -> None:
    with open_bus("sim:hdt") as bus:
        report = audit(load_machine(HDT), bus)
    drifted = {d.address for d in report.drifts}
    assert "0x6081:00" not in drifted and "0x6083:00" not in drifted  # HDT maps both into its default RxPDOs
    assert {(p["address"], p["project"], p["read"]) for p in report.process_data} == {
        ("0x6081:00", 90, 1000), ("0x6083:00", 360, 1000)}
    assert "0x6093:01" in drifted  # a setting that is not process data is still compared


@pytest.mark.parametrize(("al_status", "code", "drift"), [
    (0x01, 0x0000, "found in INIT before the bus was opened"),
    (0x11, 0x001D, "found in INIT with an error, AL status code 0x001D"),
    (0x14, 0x001D, "found in SAFEOP with an error, AL status code 0x001D"),
    (0x14, 0x001B, None),  # the watchdog of a drive whose master stopped: not drift
    (0x02, 0x0000, None), (0x08, 0x0000, None), (0x04, 0x0000, None)])
def test_a_drive_not_in_the_state_the_project_expects_is_drift(al_status: int, code: int, drift: str | None) -> None:
    with open_bus("sim:hdt") as bus:
        bus.found = [Found(0, al_status, code)]
        report = audit(load_machine(HDT), bus)
    states = [d for d in report.drifts if d.kind == "state"]
    if drift is None:
        assert states == []
    else:
        (d,) = states
        assert d.message.startswith(drift) and d.position == 0 and d.address == "AL status"


def test_audit_json_lists_the_process_data(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, "audit", HDT, "--target", "sim", "--json")
    report = json.loads(out)
    assert code == 1 and [p["address"] for p in report["process_data"]] == ["0x6081:00", "0x6083:00"]
