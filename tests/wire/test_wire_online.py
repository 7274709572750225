"""Proof on the virtual bus (issue 25): the commands that read a live bus, each a CLI process with a real master
(SOEM through pysoem, and KickCAT where its binding allows), against ``ecattool sim serve`` in a private network
namespace that the test makes itself. One subprocess with a timeout; every command in it has its own timeout."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

import pytest

from ecattool.sii.builder import build
from ecattool import profiles
from ecattool.esi import load_device
from ecattool.od.types import lookup
from ecattool.sim.slave import drive_for_device
from tests.conftest import ROOT
from tests.wire.wire_helpers import run_scenario, skip_without

pytestmark = pytest.mark.xdist_group("wire")

SCENARIO = Path(__file__).with_name("wire_online_scenario.py")
ETG2001 = ROOT / "samples" / "esi" / "etg2001_cia402.xml"


#: the scenario's result, once per test process: pytest tears a module fixture down whenever it sees no next test
#: (an xdist worker that has not been sent the rest of the group yet), and the scenario takes two minutes
_RESULT: dict[str, Any] = {}


@pytest.fixture(scope="module")
def result(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    if not _RESULT:
        _RESULT.update(_run_scenario(tmp_path_factory))
    return _RESULT


def _run_scenario(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    skip_without("pysoem", "kickcat")
    work = tmp_path_factory.mktemp("online")
    out = run_scenario(SCENARIO, str(work), timeout=1500)
    out["work"] = str(work)
    return out


def ok(step: dict[str, Any]) -> Any:
    assert step["returncode"] == 0, (step["args"], step["stdout"], step["stderr"])
    return step["stdout"]


def test_a_held_bus_serves_the_commands_and_is_put_back_as_found(result: dict[str, Any]) -> None:
    """Issue 35 item 5 by IgH's way (one bus owner): ``ecattool bus hold`` keeps one SOEM master open; commands read
    a known and an unknown drive through it, by index and by name, without a bus init of their own (what one writes
    the next reads back); a command that resets the bus and a second hold are refused naming the holder; the
    release puts every slave back in the state a raw read found it in before the hold."""
    r = result["held"]
    assert r["held"] is not None and r["held"]["held"] == "pysoem:ecat0" and r["held"]["slaves"] == 2, r
    pid = r["held"]["pid"]
    assert ok(r["read_index"])["value"] == 0x289  # HDT's vendor ID
    assert ok(r["read_name"])["address"] == "0x6041:00"  # by name: the HDT family's dictionary
    unknown, by_name = ok(r["unknown_index"]), ok(r["unknown_name"])
    assert unknown["dictionary"] == by_name["dictionary"] == "sdo-info"  # its own SDO Information, through the holder
    assert (by_name["address"], by_name["hex"]) == ("0x6040:00", unknown["hex"])
    ok(r["write"])
    assert ok(r["read_back"])["value"] == 4321
    scan = r["scan"]  # exit status 1: no library or family knows the ETG.2001 sample
    assert scan["returncode"] == 1 and [s["coe_identity"]["vendor_id"] for s in scan["stdout"]["slaves"]] == [
        0x289, 0xE0000001], scan
    for key in ("resets_refused", "second_hold"):
        step = r[key]
        assert step["returncode"] == 1 and len(step["stderr"].strip().splitlines()) == 1, step
        assert "pysoem:ecat0 is held" in step["stderr"] and f"pid {pid}" in step["stderr"], step
    release = ok(r["release"])
    assert (release["target"], release["pid"], release["commands"]) == ("pysoem:ecat0", pid, 7)
    holder = r["holder"]
    assert holder["returncode"] == 0, holder
    assert json.loads(holder["stdout"].splitlines()[-1])["ended"] == "released"
    assert r["states_before"] is not None and r["states_after"] == r["states_before"]


def test_scan_finds_the_four_samples_with_their_families(result: dict[str, Any]) -> None:
    for key in ("scan", "scan_kickcat"):
        slaves = ok(result["four"][key])["slaves"]
        assert [s["match"]["profile"] or s["match"]["name"] for s in slaves] == [
            "hdt", "technosoft-ipos", "controltechniques", "InoSV660N"], key
        assert all(s["state"] == "PREOP" for s in slaves)
    pysoem_rows = ok(result["four"]["scan"])["slaves"]
    assert all(s["al_status"] == 0 and "CoE" in s["mailbox_protocols"] for s in pysoem_rows)
    assert pysoem_rows[1]["sii_identity"] == pysoem_rows[1]["coe_identity"]
    kickcat_rows = ok(result["four"]["scan_kickcat"])["slaves"]
    assert all(s["sii_identity"] is None and s["al_status"] is None for s in kickcat_rows)  # not bound


def test_sdo_access_is_typed_on_both_masters_and_aborts_are_named(result: dict[str, Any]) -> None:
    r = result["four"]
    assert ok(r["read"])["type"] == "SINT"
    assert ok(r["read_kickcat"])["value"] == 421  # the Unidrive SP's product code, UDINT
    ok(r["write_kickcat"])
    assert ok(r["read_back"])["value"] == 4321  # written through KickCAT, read through SOEM
    assert r["abort"]["returncode"] == 1 and "0x06010002" in r["abort"]["stderr"]
    assert len(r["abort"]["stderr"].strip().splitlines()) == 1
    for key in ("abort_kickcat", "abort_kickcat_write"):
        k = r[key]  # through KickCAT 2.5 an abort comes back as a timeout, without its code (docs/at-the-machine.md)
        assert k["returncode"] == 1 and "SDO timeout" in k["stderr"] and len(k["stderr"].strip().splitlines()) == 1, k
    info = ok(r["info"])
    assert info["dictionary"] == "family" and any(e["address"] == "0x6040:00" for e in info["entries"])


def test_sdo_information_types_a_drive_nothing_else_describes(result: dict[str, Any]) -> None:
    r = result["sdo_info"]
    own = ok(r["info"])  # the drive's own SDO Information service, read by SOEM
    esi = {f"0x{o.index:04X}:{e.subindex:02X}": (e.datatype.code if e.datatype else None, e.bit_size)
           for o in drive_for_device(load_device(ETG2001)).device.dictionary for e in o}  # the drive served
    assert own["dictionary"] == "sdo-info" and len(own["entries"]) > 20
    wrong = [(e["address"], e["type"], e["bits"], esi.get(e["address"])) for e in own["entries"]
             if esi.get(e["address"]) != (lookup(e["type"]).code, e["bits"])]
    assert not wrong
    read = ok(r["read"])
    assert read["dictionary"] == "sdo-info" and esi["0x6041:00"] == (lookup(read["type"]).code, 8 * len(read["hex"]) // 2)
    # KickCAT binds no OD list: sdo info says so in one line, exit 1 (issue 35 item 3; it printed "0 entries", exit 0)
    info_kickcat = r["info_kickcat"]
    assert info_kickcat["returncode"] == 1 and "no SDO Information OD list" in info_kickcat["stderr"]


def test_sii_read_and_the_refused_writes(result: dict[str, Any]) -> None:
    r = result["four"]
    work = Path(result["work"])
    ok(r["sii_read"])
    read, built = (work / "hdt.bin").read_bytes(), build(profiles.load("hdt")).to_bytes()
    # up to the end marker of the category chain; the built image pads the EEPROM beyond it with 0xFF
    assert built[:len(read)] == read and set(built[len(read):]) <= {0xFF} and read[-2:] == b"\xff\xff"
    assert r["sii_kickcat"]["returncode"] == 1 and "no SII EEPROM access" in r["sii_kickcat"]["stderr"]
    assert r["sii_bad_crc"]["returncode"] == 1 and "CRC-8" in r["sii_bad_crc"]["stderr"]
    assert r["sii_wrong_identity"]["returncode"] == 1 and "vendor_id" in r["sii_wrong_identity"]["stderr"]
    assert not (work / "old1.bin").exists() and not (work / "old2.bin").exists() and not (work / "none.bin").exists()


def test_project_from_the_bus_lints_clean_and_commissions_the_same_bus(result: dict[str, Any]) -> None:
    r = result["four"]
    ok(r["from_bus"])
    assert ok(r["from_bus_lint"])["findings"] == []
    report = ok(r["from_bus_commission"])
    assert report["ok"] is True and len(report["projects"][0]["drives"]) == 4


def test_a_failed_dump_leaves_no_file(result: dict[str, Any]) -> None:
    r = result["four"]
    assert r["dump_fails"]["returncode"] == 1 and "no slave at position 9" in r["dump_fails"]["stderr"]
    assert not (Path(result["work"]) / "none.json").exists()


def test_audit_reports_nothing_then_exactly_the_three_changes(result: dict[str, Any]) -> None:
    r = result["technosoft"]
    assert ok(r["commission"])["ok"] is True
    assert ok(r["audit_clean"])["ok"] is True
    for c in r["changes"]:
        ok(c)
    drift = r["audit_drift"]
    assert drift["returncode"] == 1
    assert sorted(d["address"] for d in drift["stdout"]["drifts"]) == ["0x6081:00", "0x6083:00", "0x6091:01"]
    kc = r["audit_kickcat"]
    assert kc["returncode"] == 1 and sorted(d["address"] for d in kc["stdout"]["drifts"]) == [
        "0x6081:00", "0x6083:00", "0x6091:01"]


def test_a_running_bus_is_refused_and_audit_puts_the_drive_back_where_it_was_found(result: dict[str, Any]) -> None:
    """Issue 35, done when: "a read on a bus in OP is refused without the reset flag, and with it each slave ends in
    the state it was found in". The commissioned drive, whose watchdog took it to SAFE-OP (AL status code 0x001B)
    once commission's process data stopped, is refused in one line; ``audit --reset-bus`` (SOEM's bus init takes it
    to INIT) configures it again from the project and requests SAFE-OP: an independent raw read of the AL status
    after the command shows SAFE-OP, without the error. A command without a project (``sdo write``) leaves it in
    PRE-OP and says so."""
    r = result["technosoft"]
    refused = r["audit_refused"]
    assert refused["returncode"] == 1 and "slave 0 (SAFEOP, error)" in refused["stderr"], refused
    assert "--reset-bus" in refused["stderr"] and len(refused["stderr"].strip().splitlines()) == 1
    assert r["states_before"] == [[0, 0x14, 0x001B]]  # SAFE-OP with the error indication, the watchdog's code
    ok(r["audit_clean"])
    assert "ecattool: note: slave 0 was put back in SAFEOP as the project configures it" in r["audit_clean"]["stderr"]
    assert r["states_after"] == [[0, 0x04, 0]]  # SAFE-OP, as found; the error acknowledged
    first = r["changes"][0]
    assert "slave 0 (SAFEOP) was left in PRE-OP: ecattool has no configuration" in first["stderr"], first


def test_backup_succeeds_10_of_10(result: dict[str, Any]) -> None:
    """Issue 35 item 5: ``backup`` ten times in a row on the served bus, while the suite loads the machine: every
    run succeeds and every folder is complete (the same files, the .sw equal to the project's, the SII and the
    dictionary the first backup wrote)."""
    r = result["technosoft"]
    work = Path(result["work"])
    runs = r["backups"]
    assert [b["returncode"] for b in runs] == [0] * 10, [b["stderr"] for b in runs if b["returncode"]]
    first = work / "backup"
    names = sorted(p.name for p in first.iterdir())
    for n in range(10):
        folder = work / f"backup-{n}"
        assert sorted(p.name for p in folder.iterdir()) == names, n
        for name in ("00-z_axis.sw", "00-z_axis.sii.bin"):
            assert (folder / name).read_bytes() == (first / name).read_bytes(), (n, name)
        objects = json.loads((folder / "00-z_axis.dict.json").read_text())["objects"]
        assert sorted(objects) == sorted(json.loads((first / "00-z_axis.dict.json").read_text())["objects"]), n
        manifest = json.loads((folder / "ecattool-backup.json").read_text())
        assert sorted(manifest["files"]) == [name for name in names if name != "ecattool-backup.json"]
        for name, entry in manifest["files"].items():  # each file whole, as the manifest recorded it
            data = (folder / name).read_bytes()
            assert (len(data), hashlib.sha256(data).hexdigest()) == (entry["bytes"], entry["sha256"]), (n, name)


def test_sw_upload_equals_the_sw_and_backup_holds_everything(result: dict[str, Any]) -> None:
    r = result["technosoft"]
    work = Path(result["work"])
    assert ok(r["upload"])["ok"] is True
    sw = (ROOT / "samples" / "technosoft_ipos" / "setup.sw").read_bytes()
    assert (work / "back.sw").read_bytes() == sw
    ok(r["backup"])
    assert sorted(p.name for p in (work / "backup").iterdir()) == ["00-z_axis.dict.json", "00-z_axis.sii.bin",
                                                                   "00-z_axis.sw", "ecattool-backup.json"]
    assert (work / "backup" / "00-z_axis.sw").read_bytes() == sw
    manifest = json.loads((work / "backup" / "ecattool-backup.json").read_text())
    assert manifest["format"] == "ecattool-backup" and sorted(manifest["files"]) == [
        "00-z_axis.dict.json", "00-z_axis.sii.bin", "00-z_axis.sw"]


def test_frames_lost_half_way_give_one_line_and_no_backup(result: dict[str, Any]) -> None:
    """The bus goes quiet during a backup (the server stops answering): a one-line error, exit 1, no folder."""
    b = result["lost_frames"]["backup"]
    lines = b["stderr"].strip().splitlines()
    assert b["returncode"] == 1 and len(lines) == 1 and "Traceback" not in b["stderr"], b
    assert any(w in lines[0] for w in ("SDO timeout", "no reply", "no answer", "did not come back")), lines
    assert not (Path(result["work"]) / "lost").exists()


def test_a_master_program_installs_the_projects_startup_list(result: dict[str, Any]) -> None:
    """Machine.install on a pysoem.Master and a kickcat.Bus: the IO map each master reads from the drive is the project's mapping."""
    from ecattool.commission.runner import commission
    from ecattool.project.machine import load_machine
    from ecattool.target.sim import SimTarget

    r = result["install"]
    assert "pysoem_error" not in r and "kickcat_error" not in r, r
    project = ROOT / "samples" / "controltechniques" / "project.yaml"  # its mapping is not the drive's default
    target = SimTarget.from_devices([rd.device for rd in load_machine(project).slaves])
    commission(project, target)  # the same startup list, in process: the sizes it leads to
    want = [list(d.process_image_sizes()) for d in target.slaves()]
    assert r["pysoem_positions"] == r["kickcat_positions"] == [0]
    assert r["pysoem_sizes"] == r["kickcat_sizes"] == want == [[6, 7]]  # the default would be [4, 4]
