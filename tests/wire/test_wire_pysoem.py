"""Proof by a real master (issue 13, item 6): SOEM through pysoem 1.1.13 commissions the virtual bus over raw
Ethernet, inside a private network namespace with a veth pair that the test makes itself (never the host's
interfaces). Skipped, with the reason printed, only where pysoem is missing or the kernel refuses the namespace.

Each test is one subprocess with a timeout; every loop inside it is bounded."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from ecattool.errors import SdoAbort
from ecattool.od.model import EcState
from ecattool.sim.bus import netns
from ecattool.sim.bus.serve import device_source, virtual_slaves
from tests.conftest import ROOT
from tests.wire.wire_helpers import run_scenario, skip_without

#: every bus of these tests runs in one xdist worker (scripts/dev.py: --dist loadgroup), never two at once
pytestmark = pytest.mark.xdist_group("wire")

SCENARIO = Path(__file__).with_name("wire_pysoem_scenario.py")
GENERIC_ESI = ROOT / "samples" / "generic_esi" / "inovance_SV660_EOE_1Axis_V9.12.xml"
SAMPLES = sorted(str(p.relative_to(ROOT)) for p in (ROOT / "samples").glob("*/project.yaml"))


@pytest.fixture(scope="module")
def wire() -> None:
    skip_without("pysoem")


def _scenario(*args: str, timeout: int) -> dict[str, Any]:
    return run_scenario(SCENARIO, *args, timeout=timeout)


def test_soem_brings_up_the_bus_and_commissions_every_sample(wire: None) -> None:
    """One namespace, one bus at a time: pysoem brings up four drives, then commissions each sample project."""
    sources = ["hdt", "technosoft-ipos", "controltechniques", str(GENERIC_ESI)]
    result = _scenario(*sources, "--", *SAMPLES, timeout=600)
    _check_bringup(sources, result["bringup"])
    _check_commission(result["commission"])


def test_soem_brings_up_a_line_served_by_three_processes(wire: None) -> None:
    """Issue 26, item 2: five drives, ``sim serve --workers 3`` (segments of 2, 2 and 1 slaves, each its own
    process): SOEM finds them in bus order by position addressing through all three, reads their SII and SDOs,
    maps the process data and reaches OP with the full working counter; SIGTERM stops every process."""
    sources = ["hdt", "technosoft-ipos", "controltechniques", str(GENERIC_ESI), "hdt"]
    result = _scenario("--workers", "3", *sources, timeout=300)
    _check_bringup(sources, result["bringup"])


def _check_bringup(sources: list[str], out: dict[str, Any]) -> None:
    expected = virtual_slaves([device_source(s) for s in sources])  # the same drives, in process
    drives = [s.slave.drive for s in expected]
    assert out["found"] == len(drives)
    assert out["identity"] == [[d.identity().vendor_id, d.identity().product_code, d.identity().revision]
                               for d in drives]
    from tests.wire.wire_pysoem_scenario import SDO_READS

    for drive, row in zip(drives, out["sdo"]):
        drive.request_state(EcState.PREOP)
        for index, sub in SDO_READS:
            try:
                want = drive.sdo_upload(index, sub).hex()
            except SdoAbort as exc:
                want = f"abort:{exc.code:08X}"
            assert row[f"{index:04X}:{sub:02X}"] == want, (drive.device.type_name, index, sub)
    sizes = []
    for drive in drives:
        drive.request_state(EcState.SAFEOP)
        sizes.append(list(drive.process_image_sizes()))
    assert out["sizes"] == sizes  # config_map built the IO map from the drives' PDO assignment
    assert out["op"] is True and out["states"] == [8] * len(drives)
    assert out["wkc"] == out["expected_wkc"]
    assert out["init"] is True
    assert out["server"] == {"returncode": 0, "stderr": ""}  # SIGTERM: a clean stop


def _check_commission(out: dict[str, Any]) -> None:
    runs = out["runs"]
    assert [r["project"] for r in runs] == SAMPLES
    for r in runs:
        failed = [f"{s['name']}: {s['detail']}" for p in json.loads(r["stdout"] or '{"projects": []}')["projects"]
                  for d in p["drives"] for s in d["steps"] if not s["ok"]]
        assert r["returncode"] == 0, (r["project"], failed or r["stdout"][-2000:], r["stderr"])
        report = json.loads(r["stdout"])
        assert report["ok"] is True, report
        (project,) = report["projects"]
        assert project["target"] == "pysoem:ecat0" and project["drives"][0]["final_state"] == "OP"
        steps = [s["name"] for s in project["drives"][0]["steps"]]
        assert "move" in steps and "state OP" in steps
        assert r["server"]["returncode"] == 0


def test_serve_without_raw_socket_rights_is_one_line_exit_1() -> None:
    """In a user namespace of its own the process has no CAP_NET_RAW over the network: one line, exit 1."""
    probe = subprocess.run(["unshare", "-U", "true"], capture_output=True)
    if probe.returncode != 0:
        pytest.skip(f"the kernel refused a user namespace: {probe.stderr.decode(errors='replace').strip()}")
    done = subprocess.run(["unshare", "-U", sys.executable, "-m", "ecattool", "sim", "serve", "hdt", "--iface",
                           netns.SLAVE_IF], capture_output=True, text=True, timeout=120, cwd=ROOT)
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 1 and len(lines) == 1 and "raw sockets are not permitted" in lines[0], done.stderr
    assert done.stdout == ""  # never "ready"
