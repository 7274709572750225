"""The whole bus on the wire (issue 34, item 8; issue 35, item 1): a served bus of the terminals a machine is made
of -- a coupler (EK1100), digital terminals without a mailbox (EL1008 inputs, EJ2008 outputs over the digital output
registers 0x0F00), an analog terminal with CoE (EJ3004), a gateway (EL6692 EtherCAT bridge) and two drives (HDT, the
Inovance SV660N sample) -- from real corpus ESI files through a project file, brought to OP by SOEM and by KickCAT
with the full working counter; the read commands on it never send an SDO to a slave without a mailbox, and
``project new --from-bus`` writes a project that lints clean, commissions the same bus and audits clean. And a
sample of the corpus sweep (tests/test_corpus_sweep.py) on the wire: one device of each corpus ESI file, the first
whose ``project new`` skeleton lints clean, all on one served bus, commissioned through SOEM.

Each test is one subprocess in a private network namespace (ecattool.sim.bus.netns) with a timeout; every loop in
it is bounded. Skipped, with the reason printed, only where pysoem/kickcat is missing or the kernel refuses the
namespace."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from ecattool.errors import EcatToolError
from ecattool.findings import Severity
from ecattool.project.cache import load_esi_cached
from ecattool.project.machine import load_machine
from ecattool.project.skeleton import esi_flaws, new_project, resolve
from ecattool.sim.bus.serve import virtual_slaves
from tests.conftest import CORPUS, ROOT, need_corpus
from tests.wire.wire_helpers import run_scenario, skip_without

need_corpus()
pytestmark = pytest.mark.xdist_group("wire")

SCENARIO = Path(__file__).with_name("wire_whole_bus_scenario.py")
ESI = CORPUS / "esi"
SV660 = ROOT / "samples" / "generic_esi" / "inovance_SV660_EOE_1Axis_V9.12.xml"

#: the mixed bus: (name, device reference) in bus order
MIXED = [
    ("coupler", f"{{esi: {json.dumps(str(ESI / 'beckhoff_EK11xx.xml'))}, select: EK1100, policy: newest}}"),
    ("inputs", f"{{esi: {json.dumps(str(ESI / 'beckhoff_EL1xxx.xml'))}, select: EL1008, policy: newest}}"),
    ("outputs", f"{{esi: {json.dumps(str(ESI / 'beckhoff_EJ2xxx.xml'))}, select: EJ2008, policy: newest}}"),
    ("analog", f"{{esi: {json.dumps(str(ESI / 'beckhoff_EJ3xxx.xml'))}, select: EJ3004, policy: newest}}"),
    ("bridge", f"{{esi: {json.dumps(str(ESI / 'beckhoff_EL66xx.xml'))}, select: EL6692, policy: newest}}"),
    ("axis1", "{profile: hdt, product: tomcat}"),
    ("axis2", f"{{esi: {json.dumps(str(SV660))}, select: InoSV660N}}"),
]
#: (vendor, product) of each slave of MIXED, and which have no mailbox (from their ESI: no <Mailbox>)
IDENTITY = [[2, 0x044C2C52], [2, 0x03F03052], [2, 0x07D82852], [2, 0x0BBC2852], [2, 0x1A243052],
            [0x289, 0x000C0458], [0x00100000, 0x000C010D]]
NO_MAILBOX = {0, 1, 2}


def _scenario(*args: str, timeout: int) -> dict[str, Any]:
    return run_scenario(SCENARIO, *args, timeout=timeout)


@pytest.fixture(scope="module")
def mixed(tmp_path_factory: pytest.TempPathFactory) -> Path:
    project = tmp_path_factory.mktemp("bus") / "mixed.yaml"
    drives = "".join(f"  - name: {name}\n    device: {ref}\n" for name, ref in MIXED)
    drives = drives.replace("  - name: axis1\n    device: {profile: hdt, product: tomcat}\n",
                            "  - name: axis1\n    device: {profile: hdt, product: tomcat}\n    move: {distance: 1000}\n")
    drives = drives.replace("select: InoSV660N}\n", "select: InoSV660N}\n    identity: {revision: at-least}\n"
                            "    dc: {opmode: DC, cycle_ns: 1000000}\n    move: {distance: 10000, mode: csp}\n")
    project.write_text("ecattool: 1\nname: mixed-bus\ndrives:\n" + drives, encoding="utf-8")
    machine = load_machine(project)
    assert not [f for f in machine.findings if f.severity is Severity.ERROR], machine.findings
    return project


def _check_op(out: dict[str, Any], sizes_key: str = "sizes") -> None:
    assert out["error"] is None, out["error"]
    assert out["found"] == len(MIXED)
    sizes = out[sizes_key]
    # the mailbox-less terminals have their fixed images: EL1008 8 bits in, EJ2008 8 bits out (0x0F00)
    assert sizes[:3] == [[0, 0], [0, 1], [1, 0]]
    assert out["server"] == {"returncode": 0, "stderr": ""}


def test_soem_brings_the_mixed_bus_to_op_with_the_full_working_counter(mixed: Path) -> None:
    """Was: the three mailbox-less slaves refused INIT -> PRE-OP with AL 0x0016 under ``sim serve``."""
    skip_without("pysoem")
    out = _scenario("soem", str(mixed), timeout=300)
    _check_op(out)
    assert [i[:2] for i in out["identity"]] == IDENTITY
    assert out["preop"] and out["safeop"] and out["states"] == [8] * len(MIXED)
    assert set(out["wkc"]) == {out["full_wkc"]} and out["full_wkc"] == out["soem_expected_wkc"]
    assert out["init"] is True


def test_kickcat_brings_the_mixed_bus_to_op_with_the_full_working_counter(mixed: Path) -> None:
    skip_without("kickcat")
    out = _scenario("kickcat", str(mixed), timeout=300)
    _check_op(out)
    assert out["op"] == [True] * len(MIXED)
    assert out["pd_errors"] == []  # KickCAT checked the working counter of every cycle
    assert out["init"] is True


def test_read_commands_on_the_mixed_bus_and_from_bus_commissions_it(mixed: Path, tmp_path: Path) -> None:
    """``bus scan`` reads the mailbox-less slaves from their SII (no "1018h: SDO timeout" note), ``project new
    --from-bus`` writes every slave (it stopped at the first mailbox-less one: ``SDO timeout on 0x1C12:00``), the
    project lints clean, commissions the same bus and audits clean; ``backup`` takes the SII of every slave and
    the dictionary of those with CoE."""
    skip_without("pysoem")
    out = _scenario("commands", str(mixed), str(ESI), str(tmp_path), timeout=600)
    scan, made, lint, commission, audit, backup = out["runs"]
    assert scan["returncode"] == 0, scan["stderr"]
    slaves = json.loads(scan["stdout"])["slaves"]
    assert [[s["sii_identity"]["vendor_id"], s["sii_identity"]["product_code"]] for s in slaves] == IDENTITY
    for i, s in enumerate(slaves):
        assert not any("1018h" in u for u in s["unknown"]), (i, s["unknown"])
        assert (s["coe_identity"] is None) == (i in NO_MAILBOX), (i, s)
    assert made["returncode"] == 0 and made["stderr"] == "", made["stderr"]
    text = (tmp_path / "from-bus.yaml").read_text(encoding="utf-8")
    assert text.count("  - name: ") == len(MIXED) and text.count("no CoE mailbox") == len(NO_MAILBOX)
    assert lint["returncode"] == 0, lint["stdout"][-3000:]
    report = json.loads(commission["stdout"])
    failed = [(d["name"], s["name"], s["detail"]) for p in report["projects"] for d in p["drives"]
              for s in d["steps"] if not s["ok"]]
    assert commission["returncode"] == 0 and report["ok"] is True, failed or commission["stderr"]
    assert [d["final_state"] for d in report["projects"][0]["drives"]] == ["OP"] * len(MIXED)
    assert audit["returncode"] == 0 and json.loads(audit["stdout"])["ok"] is True, audit["stdout"][-2000:]
    assert backup["returncode"] == 0, backup["stderr"]
    files = sorted(p.name for p in (tmp_path / "backup").iterdir())
    assert [f for f in files if f.endswith(".sii.bin")] == [f"{i:02d}-{n}.sii.bin" for i, (n, _) in enumerate(MIXED)]
    assert [f[:2] for f in files if f.endswith(".dict.json")] == [f"{i:02d}" for i in range(len(MIXED))
                                                                  if i not in NO_MAILBOX]
    assert backup["stdout"].count("has no CoE mailbox") == len(NO_MAILBOX)
    assert out["server"] == {"returncode": 0, "stderr": ""}
    # issue 35, done when: "with [the reset flag] each slave ends in the state it was found in". After commission
    # every slave was in OP; the drives' watchdogs took them to SAFE-OP (0x001B) once its process data stopped,
    # the coupler and the terminals (no application) stay in OP. audit and backup, each with a project, put every
    # slave back where they found it, as the project configures it: the raw reads around them show the same
    # states, the watchdog's error acknowledged
    before, after_audit, after_backup = out["states"]
    assert before is not None and len(before) == len(MIXED), before
    assert all(al & 0x0F in (0x04, 0x08) for al, _ in before), before  # running: SAFE-OP or OP
    assert after_audit == after_backup == [[al & 0x0F, 0] for al, _ in before], (before, after_audit, after_backup)
    assert "was put back in" in audit["stderr"] and "left in PRE-OP" not in audit["stderr"], audit["stderr"]


def _selector(devices: list[Any], k: int) -> str:
    from tests.test_corpus_sweep import _selector as sweep_selector

    return sweep_selector(devices, k)


def sweep_sample(folder: Path) -> tuple[str, list[str], list[str]]:
    """One device of each corpus ESI file (each is a device family: couplers, digital and analog I/O, counters,
    gateways, drives...), the first whose ``project new`` skeleton lints clean and ``sim serve`` accepts, as the
    corpus sweep makes and lints them; returns the bus project's text, the devices and what sim serve refused."""
    parts, names, refused = [], [], []
    probe = folder / "probe.yaml"
    for path in sorted(ESI.glob("*.xml")):
        devices = list(load_esi_cached(path).devices)
        for k in range(len(devices)):
            select = _selector(devices, k)
            try:
                device = resolve(None, None, str(path), select, folder)
                text = new_project(device, name=f"s{len(parts)}", esi=str(path), select=select,
                                   findings=esi_flaws(str(path), select, folder))
            except EcatToolError:
                continue
            probe.write_text(text, encoding="utf-8")
            machine = load_machine(probe)
            if any(f.severity is Severity.ERROR for f in machine.findings):
                continue
            try:
                virtual_slaves(machine.devices())
            except EcatToolError as exc:
                refused.append(f"{path.name} [{k}]: {exc}")
                continue
            parts.append(text.split("drives:\n", 1)[1])
            names.append(f"{path.name} [{k}] {devices[k].type_name}")
            break
    return "ecattool: 1\nname: corpus-sample\ndrives:\n" + "".join(parts), names, refused


def test_a_sample_of_the_corpus_sweep_commissions_on_the_wire(tmp_path: Path) -> None:
    """Lint clean => commissions, on the wire: one device of each corpus file on one bus through SOEM. Found on
    the way: Ingenia's 60C2h of 1 s paced the served drive (its enable failed), the EM7004's one-buffer process
    data SMs were refused (AL 0x001D), and SOEM's expected working counter leaves out slaves with bit inputs."""
    skip_without("pysoem")
    text, names, refused = sweep_sample(tmp_path)
    # the one device family sim serve refuses: Elmo's ESI gives its SII a SyncM category (Eeprom/Category 41)
    # whose SM0 is at 0x0000, 32792 bytes (a master programs SM0 from it): refused in one line, as it should be
    assert refused and all(r.startswith("elmo_") and "SM0 (mailbox out) at 0x0000" in r for r in refused), refused
    assert len(names) >= 20, names
    project = tmp_path / "sample.yaml"
    project.write_text(text, encoding="utf-8")
    out = _scenario("commission", str(project), timeout=600)
    run = out["run"]
    report = json.loads(run["stdout"]) if run["stdout"] else {"projects": []}
    failed = [(names[int(d["name"][1:])], s["name"], s["detail"]) for p in report["projects"] for d in p["drives"]
              for s in d["steps"] if not s["ok"]]
    assert run["returncode"] == 0 and report.get("ok") is True, failed or run["stderr"]
    assert len(report["projects"][0]["drives"]) == len(names)
    assert out["server"] == {"returncode": 0, "stderr": ""}
