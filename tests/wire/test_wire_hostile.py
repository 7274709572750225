"""The served bus under a wrong master, on the wire (issue 28, items 4 and 5): bounded bursts of hostile frames
at ``ecattool sim serve`` through a raw socket, then a fresh SOEM (pysoem) master finds the bus, takes it to OP
with the full working counter, and commissions the project -- without a restart of the server. All inside a
private network namespace with a veth pair the test makes itself (never the host's interfaces); skipped, with
the reason printed, only where pysoem is missing or the kernel refuses the namespace.

The rules one by one, in process: tests/wire/test_wire_esc_bounds.py."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from tests.wire.wire_helpers import run_scenario, skip_without

#: every bus of these tests runs in one xdist worker (scripts/dev.py: --dist loadgroup), never two at once
pytestmark = pytest.mark.xdist_group("wire")

SCENARIO = Path(__file__).with_name("wire_hostile_scenario.py")
#: a drive with CoE and FoE, a custom mapping and a .sw image: every mailbox protocol the bursts abuse
PROJECT = "samples/technosoft_ipos/project.yaml"


def _run(seed: int) -> dict[str, Any]:
    skip_without("pysoem")
    return run_scenario(SCENARIO, PROJECT, str(seed), timeout=300)


@pytest.mark.parametrize("seed", [1, 2])
def test_after_hostile_bursts_a_fresh_soem_finds_and_commissions_the_bus(seed: int) -> None:
    out = _run(seed)
    hostile = out["hostile"]
    assert hostile["preop"] is True  # the wrong master really had a mailbox to abuse
    assert hostile["sent"] > 500 and 0 < hostile["answered"] < hostile["sent"]  # malformed frames get no answer
    assert out["alive_after_burst"] is True
    soem = out["soem"]
    (slave,) = out["ready"]["slaves"]
    assert soem["found"] == 1 and soem["identity"] == [[slave["vendor_id"], slave["product_code"], slave["revision"]]]
    assert len(soem["sdo"]) == 1  # 1018h:01 read back by SDO
    assert int.from_bytes(bytes.fromhex(soem["sdo"][0]), "little") == slave["vendor_id"]
    assert soem["safeop"] is True and soem["op"] is True and soem["init"] is True
    assert soem["wkc"] == soem["expected_wkc"] == 3
    run = out["commission"]
    report = json.loads(run["stdout"]) if run["stdout"] else {}
    failed = [f"{s['name']}: {s['detail']}" for p in report.get("projects", []) for d in p["drives"]
              for s in d["steps"] if not s["ok"]]
    assert run["returncode"] == 0 and report["ok"] is True, (failed, run["stderr"])
    assert report["projects"][0]["drives"][0]["final_state"] == "OP"
    assert out["server"] == {"returncode": 0, "stderr": ""}  # never restarted, and a clean stop at the end
