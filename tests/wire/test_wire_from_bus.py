"""``project new --from-bus`` through SOEM on a served bus that runs as commissioned (issue 35 item 2): a Digitax
ST commissioned in CSP on DC is written back with its model, its ``dc:`` (read from the ESC registers before
pysoem's ``config_init`` clears 0x0981) and its mode; the project lints without a finding and commissions the same
bus. The in-process tests are tests/online/test_from_bus.py; this one shows the raw register read on the wire."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.conftest import ROOT
from tests.wire.wire_helpers import run_scenario, skip_without

pytestmark = pytest.mark.xdist_group("wire")

SCENARIO = Path(__file__).with_name("wire_from_bus_scenario.py")
CT = ROOT / "samples" / "controltechniques" / "project.yaml"


def test_from_bus_reads_dc_from_the_registers_of_a_running_bus(tmp_path: Path) -> None:
    skip_without("pysoem")
    out = run_scenario(SCENARIO, str(CT), str(tmp_path), timeout=600)
    first, made, lint, again, *kickcat = out["runs"]
    assert first["returncode"] == 0, first["stdout"][-2000:] or first["stderr"]
    assert made["returncode"] == 0, made["stderr"]
    text = (tmp_path / "from-bus.yaml").read_text(encoding="utf-8")
    assert "product: digitax-st" in text, text
    assert 'dc: {opmode: "DC", cycle_ns: 1000000}  # as found: AssignActivate 0x0300' in text, text
    assert '{object: "6060:00", value: 8,' in text, text
    assert lint["returncode"] == 0 and json.loads(lint["stdout"])["findings"] == [], lint["stdout"][-3000:]
    report = json.loads(again["stdout"])
    assert again["returncode"] == 0 and report["ok"] is True, again["stdout"][-3000:]
    assert out["server"]["returncode"] == 0, out["server"]
    if not kickcat:
        return  # no kickcat package here: the SOEM half stands
    (through_kickcat,) = kickcat
    assert through_kickcat["returncode"] == 0, through_kickcat["stderr"]
    text = (tmp_path / "from-bus-kickcat.yaml").read_text(encoding="utf-8")
    # KickCAT binds no SII: read through the ESC's EEPROM interface before it opened, the SII names the model
    # (the first model of the product code, unidrive-sp, before); DC from the registers as through SOEM
    assert "product: digitax-st" in text, text
    assert 'dc: {opmode: "DC", cycle_ns: 1000000}  # as found: AssignActivate 0x0300' in text, text
