"""A hostile slave never takes ecattool down (issue 37, item 1 and its "Done when"): ecattool's own served slave
(``sim serve --misbehave NAME``, on a veth pair in a private network namespace) misbehaves one way at a time --
4 GiB and endless SDO uploads, truncated and empty mailbox replies, wrong working counters, a blank SII, an SII
without an end marker, a slave that vanishes -- and ``bus scan``, ``sdo read``, ``sdo dump``, ``sii read``,
``backup`` and ``audit`` through SOEM (pysoem) each end with an exit status and at most one line on stderr, within
a bounded time (the scenario gives each command 40 s and caps the master's own time limits at 4 s), and exit 0 only
where what they report is true (checked against the served slave's identity and SII).

Before the master ran in a child process of its own (ecattool/target/isolated.py), the 4 GiB and endless uploads
ended ``bus scan``, ``sdo read``, ``sdo dump``, ``backup`` and ``audit`` with SIGSEGV (exit -11 here).

The misbehaviours themselves: ecattool/sim/bus/misbehave.py."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import pytest

from tests.conftest import ROOT
from tests.wire.wire_helpers import run_scenario, skip_without

#: a group of its own: the test is 2.5 min of waits (bounded timeouts of the misbehaving slave, about 20 % of one
#: core), so it runs beside the "wire" group on the other worker instead of after it; its served slave never runs
#: process data, so it does not starve the watchdog-timed buses of the "wire" group
pytestmark = pytest.mark.xdist_group("wire-hostile")

SCENARIO = Path(__file__).with_name("wire_hostile_slave_scenario.py")
PROJECT = "samples/hdt/project.yaml"
MISBEHAVIOURS = ["none", "upload-4gib", "upload-endless", "reply-truncated", "reply-empty", "wrong-wkc",
                 "sii-blank", "sii-no-end", "vanish"]


def _served_sii() -> bytes:
    """The served slave's SII up to its end marker (what a reader of the category chain reads)."""
    from ecattool.project.bus import devices_in_bus_order
    from ecattool.sii.builder import build
    from ecattool.sim.bus.misbehave import _end_marker

    ((_, device),) = devices_in_bus_order(str(ROOT / PROJECT), False)
    image = build(device).to_bytes()
    return image[:_end_marker(image) + 2]


def _vendor() -> int:
    from ecattool.project.bus import devices_in_bus_order

    ((_, device),) = devices_in_bus_order(str(ROOT / PROJECT), False)
    return int(device.identity.vendor_id)


def _untrue(name: str, command: str, run: dict[str, Any], outdir: Path) -> str | None:
    """Why an exit 0 of ``command`` under ``name`` reports something untrue (None: what it says is so)."""
    vendor, sii = _vendor(), _served_sii()
    out = outdir / name
    if command.startswith("sdo read"):
        return None if f"= {vendor} " in run["stdout"] else f"printed {run['stdout'][-200:]!r}"
    if command == "sii read":
        got = bytes.fromhex(run.get("sii_hex", ""))
        return None if got == sii else f"saved {len(got)} bytes that are not the slave's {len(sii)}-byte SII"
    if command == "sdo dump":
        objects = json.loads((out / "dump.json").read_text())["objects"]
        return None if objects.get("0x1018:01", {}).get("value") == vendor else "1018h:01 is not the vendor id"
    if command == "backup":
        folder = out / "backup"
        dicts, images = list(folder.glob("*.dict.json")), list(folder.glob("*.sii.bin"))
        if len(dicts) != 1 or len(images) != 1 or images[0].read_bytes() != sii:
            return "the backed-up SII is not the slave's"
        objects = json.loads(dicts[0].read_text())["objects"]
        return None if objects.get("0x1018:01", {}).get("value") == vendor else "1018h:01 is not the vendor id"
    if command == "bus scan":
        return None if "HDT" in run["stdout"] else "the slave is not named"
    return "the project's values differ from the uncommissioned drive's: audit cannot be clean"


def test_a_hostile_slave_never_ends_ecattool(tmp_path: Path) -> None:
    skip_without("pysoem")
    result = run_scenario(SCENARIO, PROJECT, str(tmp_path), *MISBEHAVIOURS, timeout=900)
    wrong: list[str] = []
    running = result["none"].pop("running bus")
    unknown = result.pop("unknown drive")
    for name in MISBEHAVIOURS:
        runs = result[name]
        assert runs.pop("server") == {"returncode": 0, "stderr": ""}, name  # the server itself never fails
        for command, run in runs.items():
            rc, err = run["returncode"], run["stderr"]
            where = f"{name} / {command}"
            if rc not in (0, 1):  # None: still running after 40 s; -11: SIGSEGV; 2: a usage error
                wrong.append(f"{where}: exit {rc} {err[-300:]!r}")
            elif "Traceback" in err or len(err.strip().splitlines()) > 1:
                wrong.append(f"{where}: more than one line on stderr: {err[-500:]!r}")
            elif rc == 1 and err and not err.startswith("ecattool: error: "):
                wrong.append(f"{where}: {err!r}")
            elif rc == 0 and (why := _untrue(name, command, run, tmp_path)) is not None:
                wrong.append(f"{where}: exit 0, {why}")
    assert not wrong, "\n".join(wrong)
    for name in ("upload-4gib", "upload-endless"):
        # an object of known type (1018h:01, a UDINT): SOEM's buffer is its 4 octets and the announced size is
        # refused (issue 37 item 1; before, the master crashed here too)
        assert result[name]["sdo read"]["stderr"] == ("ecattool: error: slave 0: 0x1018:01: the slave announced more "
                                                      "than the 4 the object can have (refused)\n"), name
    # where the type is not known: SOEM given a 256-octet buffer (not its static one, as pysoem passes size 0) reads
    # the 4 GiB announcement as negative and pysoem refuses to make bytes of it: refused, no crash
    assert result["upload-4gib"]["sdo read (unknown type)"]["stderr"] == (
        "ecattool: error: slave 0: 0x2FFF:00: the slave announced more than the 256 octets read of an object whose "
        "type is not known (refused)\n")
    # the endless segments of an announced 200 octets fit the 256-octet buffer and SOEM copies on past its end:
    # undefined behaviour in the master, which ends in a crash or (memory overwritten) a hang, run to run; either is
    # kept away by the master's child process and named in one line with the slave and the object
    endless = result["upload-endless"]["sdo read (unknown type)"]
    assert endless["returncode"] == 1 and len(endless["stderr"].splitlines()) == 1, endless
    assert re.search(r"the master (crashed|did not answer within [\d.]+ s) reading 2FFFh:00 of slave 0",
                     endless["stderr"]), endless["stderr"]
    # KickCAT: reads the well-behaved slave; refuses the endless segments' announcement of 200 octets now that its
    # buffer is 1018h:01's 4 (it crashed with its 1024-octet buffer before); hangs on an SII chain without end --
    # each one line, the hang stopped at its time limit
    assert result["none"]["sdo read (kickcat)"]["returncode"] == 0
    assert result["upload-endless"]["sdo read (kickcat)"]["stderr"] == (
        "ecattool: error: slave 0, 0x1018:01: CoE.cc:43: Error while reading SDO (KickCAT read at most 4 octets)\n")
    assert result["sii-no-end"]["sdo read (kickcat)"]["stderr"].startswith(
        "ecattool: error: the master did not answer within 15 s opening the bus on kickcat:ecat0")
    # the baseline: every command works against the well-behaved slave
    base = result["none"]
    assert all(base[c]["returncode"] == 0 for c in ("bus scan", "sdo read", "sdo dump", "sii read", "backup"))
    # issue 35 item 4: a bus in SAFE-OP is not reset without --reset-bus; with it, what could not be put back is said
    assert running["safeop"] is True and running["found_safeop"] == ["slave 0 (SAFEOP)"]
    refused = running["refused"]
    assert refused["returncode"] == 1 and refused["stderr"] == (
        "ecattool: error: slave 0 (SAFEOP) on 'ecat0' is running: opening the bus resets every slave to INIT and "
        "would stop the machine; pass --reset-bus to do it anyway\n")
    assert running["after_refusal"] == ["slave 0 (SAFEOP)"]  # untouched
    reset = running["reset"]
    assert reset["returncode"] == 0 and f"= {_vendor()} " in reset["stdout"]
    assert reset["stderr"] == ("ecattool: note: slave 0 (SAFEOP) was left in PRE-OP: ecattool has no configuration "
                               "to take it back to SAFEOP (give the command a project)\n")
    # a slave found in INIT is read (INIT and PRE-OP are not refused) and put back in INIT
    assert running["init"] is True and running["in_init"]["returncode"] == 0, running["in_init"]
    assert running["after_init"] == ["slave 0 (INIT)"]
    # audit: a drive found in INIT is drift; HDT's 6081h/6083h (in its RxPDOs) are process data, not drift
    report = json.loads(running["audit_in_init"]["stdout"])
    assert running["audit_in_init"]["returncode"] == 1
    assert [d["message"] for d in report["drifts"] if d["kind"] == "state"] == [
        "found in INIT before the bus was opened"]
    assert [p["address"] for p in report["process_data"]] == ["0x6081:00", "0x6083:00"]
    # issue 35 item 3: a drive ecattool has no profile for, without SDO Information (its ESI: CoE SdoInfo="0")
    ident = unknown["ready"]["slaves"][0]
    info = unknown["info"]
    assert info["returncode"] == 1 and info["stderr"].startswith("ecattool: error: slave 0 offers no SDO Information")
    read = unknown["read"]  # by index, no dictionary: the raw bytes
    assert read["returncode"] == 0, read["stderr"]
    assert json.loads(read["stdout"])["hex"] == ident["vendor_id"].to_bytes(4, "little").hex()
    by_name = unknown["by_name"]  # by name, through the ESI given as --device
    assert by_name["returncode"] == 0, by_name["stderr"]
    assert json.loads(by_name["stdout"])["address"] == "0x6041:00"
    assert unknown["name_without_dictionary"]["returncode"] == 1
    assert "has no dictionary to find it by name in" in unknown["name_without_dictionary"]["stderr"]
    # the refused SDO Information request does not fail the requests after it (it did: mailbox error 4, 64 times)
    assert unknown["sdo_info"].startswith("slave 0 offers no SDO Information")
    assert unknown["after"] == [ident["vendor_id"].to_bytes(4, "little").hex(),
                                ident["product_code"].to_bytes(4, "little").hex(),
                                ident["vendor_id"].to_bytes(4, "little").hex()]
