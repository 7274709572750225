"""Reading a live bus (issue 25) in process: the simulator target and the fake pysoem (tests/fake_pysoem.py,
checked against the real module by tests/test_pysoem_surface.py). The same commands on the virtual bus with real
SOEM and KickCAT: tests/test_wire_online.py."""

from __future__ import annotations

import json

import pytest

from ecattool.commission.runner import commission
from ecattool.errors import SdoAbort
from ecattool.online import Library, audit, open_bus, scan, sim_bus
from ecattool.online.dictionary import typed
from ecattool.online.objects import dump, read_value, write_value
from ecattool.online.pysoem_bus import open_pysoem
from ecattool.online.sii_access import write_checks
from ecattool.project.lint import lint_project
from ecattool.sii.crc import preamble_crc
from ecattool.target.sim import SimTarget
from tests import fake_pysoem
from tests.conftest import ROOT, run

GENERIC_ESI = ROOT / "samples" / "generic_esi" / "inovance_SV660_EOE_1Axis_V9.12.xml"
FOUR = f"sim:hdt,technosoft-ipos,controltechniques,{GENERIC_ESI}"
TECHNOSOFT = "samples/technosoft_ipos/project.yaml"


def test_scan_finds_the_four_samples_with_their_families() -> None:
    with open_bus(FOUR) as bus:
        rows = scan(bus, Library(ROOT / "samples" / "generic_esi"))
    assert [(r.match.kind, r.match.profile or r.match.name) for r in rows] == [
        ("family", "hdt"), ("family", "technosoft-ipos"), ("family", "controltechniques"), ("esi", "InoSV660N")]
    assert all(r.state == "PREOP" and r.al_status == 0 and "CoE" in r.protocols for r in rows)
    assert rows[3].match.exact and rows[1].coe_identity == rows[1].sii_identity and not rows[1].identity_differs


def test_scan_names_an_unknown_device() -> None:
    with open_bus(f"sim:{GENERIC_ESI}") as bus:  # no library: the ESI device is neither in it nor a family
        (row,) = scan(bus)
    assert row.match is None and any("no library file" in u for u in row.unknown)


def _commissioned(project: str) -> tuple[SimTarget, object]:
    result = lint_project(project)
    target = SimTarget.from_devices([rd.device for rd in sorted(result.drives, key=lambda r: r.position)])
    assert commission(project, target).ok
    return target, sim_bus(target.slaves())


def test_audit_of_a_freshly_commissioned_bus_reports_nothing_and_never_writes() -> None:
    _, bus = _commissioned(TECHNOSOFT)
    report = audit(TECHNOSOFT, bus)
    assert report.ok and report.checked > 10
    assert bus.write_log == []  # the simulator saw no SDO download, no SII write


def test_audit_reports_exactly_the_three_changed_objects() -> None:
    _, bus = _commissioned(TECHNOSOFT)
    slave = bus.slaves[0]
    for index, sub, data in ((0x6081, 0, (12345).to_bytes(4, "little")), (0x6083, 0, (777).to_bytes(4, "little")),
                             (0x6091, 1, (7).to_bytes(4, "little"))):
        slave.sdo_download(index, sub, data)
    bus.write_log.clear()
    report = audit(TECHNOSOFT, bus)
    assert sorted(d.address for d in report.drifts) == ["0x6081:00", "0x6083:00", "0x6091:01"]
    assert {d.kind for d in report.drifts} == {"value"} and bus.write_log == []
    assert any(d.actual == 12345 for d in report.drifts)  # decoded by the dictionary


def test_audit_cli_on_an_uncommissioned_bus_is_drift_in_every_format(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, "audit", TECHNOSOFT, "--target", "sim", "--json")
    report = json.loads(out)
    assert code == 1 and not report["ok"] and report["drifts"]
    assert report["drifts"][0]["location"]  # the project line that sets the value
    code, out, _ = run(capsys, "audit", TECHNOSOFT, "--target", "sim", "--format", "sarif")
    assert code == 1 and json.loads(out)["runs"][0]["results"][0]["ruleId"].startswith("audit.")
    code, out, _ = run(capsys, "audit", TECHNOSOFT, "--target", "sim")
    assert code == 1 and "drifted" in out


def test_sdo_read_write_are_typed_and_aborts_named(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, "sdo", "read", "0x1018:01", "--target", "sim:hdt", "--json")
    assert code == 0 and json.loads(out)["value"] == 0x289 and json.loads(out)["type"] == "UDINT"
    code, _, err = run(capsys, "sdo", "write", "0x1018:01", "5", "--target", "sim:hdt")
    assert code == 1 and "0x06010002" in err and "read-only object" in err and len(err.splitlines()) == 1
    code, _, err = run(capsys, "sdo", "write", "0x6060:00", "300", "--target", "sim:technosoft-ipos")
    assert code == 1 and "out of range" in err
    with open_bus("sim:technosoft-ipos") as bus:
        s = bus.slaves[0]
        t = typed(s)
        assert write_value(s, t, 0x6081, 0, "0x1000") == (0x1000).to_bytes(4, "little")
        assert read_value(s, t, 0x6081, 0).value == 0x1000
        with pytest.raises(SdoAbort):
            read_value(s, t, 0x5FFF, 0)


def test_dump_snapshot_has_every_readable_object(tmp_path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "hdt.json"
    code, _, _ = run(capsys, "sdo", "dump", "--target", "sim:hdt", "-o", str(out))
    snap = json.loads(out.read_text())
    assert code == 0 and snap["format"] == "ecattool-dictionary-snapshot" and snap["dictionary"] == "family"
    assert snap["objects"]["0x1018:01"]["value"] == 0x289 and len(snap["objects"]) > 50


def test_fake_pysoem_scan_sdo_info_and_sii() -> None:
    from ecattool.sim import Drive

    drives = [Drive.from_profile("hdt"), Drive.from_profile("technosoft-ipos")]
    mod = fake_pysoem.make_module(drives)
    bus = open_pysoem("eth0", mod)
    try:
        rows = scan(bus)
        assert [r.match.profile for r in rows] == ["hdt", "technosoft-ipos"]
        assert rows[1].protocols == ["EoE", "CoE", "FoE"] and rows[0].sii_identity.vendor_id == 0x289
        od = bus.slaves[1].sdo_info()  # SOEM's OD list, typed
        assert od.entry(0x6060, 0).type_name == "SINT" and od.entry(0x1018, 1).type_name == "UDINT"
        assert read_value(bus.slaves[1], typed(bus.slaves[1], sdo_info=True), 0x6060, 0).value == 0
        snap = dump(bus.slaves[0], typed(bus.slaves[0]), "pysoem:eth0")
        assert snap["objects"]["0x1018:01"]["value"] == 0x289
    finally:
        bus.close()


def _image(bus) -> bytes:
    return bus.slaves[0].sii_read()


def test_sii_write_refuses_a_bad_crc_and_a_wrong_identity(tmp_path, capsys: pytest.CaptureFixture[str]) -> None:
    with open_bus("sim:hdt") as bus:
        good = _image(bus)
    bad_crc = bytearray(good)
    bad_crc[14] ^= 0xFF
    other = bytearray(good)
    other[0x10:0x14] = (0x1234).to_bytes(4, "little")
    other[14] = preamble_crc(bytes(other))  # a valid image of another vendor
    assert any("CRC-8" in p for p in write_checks(bytes(bad_crc), good, "x.bin"))
    assert any("vendor_id" in p for p in write_checks(bytes(other), good, "x.bin"))
    assert write_checks(bytes(other), good, "x.bin", force=True) == []
    for image, word in ((bad_crc, "CRC-8"), (other, "vendor_id")):
        path, backup = tmp_path / "new.bin", tmp_path / "old.bin"
        path.write_bytes(bytes(image))
        code, _, err = run(capsys, "sii", "write", str(path), "--target", "sim:hdt", "--backup", str(backup))
        assert code == 1 and word in err and len(err.splitlines()) == 1 and not backup.exists()  # refused before anything, even the back-up
    path.write_bytes(good)
    code, out, _ = run(capsys, "sii", "write", str(path), "--target", "sim:hdt", "--backup", str(backup))
    assert code == 0 and "written" in out and backup.read_bytes() == good


def test_sii_write_goes_to_the_eeprom_word_by_word_after_the_backup(tmp_path) -> None:
    from ecattool.online.sii_access import sii_write
    from ecattool.sim import Drive

    drive = Drive.from_profile("technosoft-ipos")
    mod = fake_pysoem.make_module([drive])
    bus = open_pysoem("eth0", mod)
    try:
        raw = bus.slaves[0]._raw
        old = bytes(raw.sii)
        new = bytearray(old)
        new[8:10] = b"\x34\x12"  # the alias word (0x0004)
        new[14] = preamble_crc(bytes(new))
        assert sii_write(bus.slaves[0], bytes(new), "new.bin", tmp_path / "old.bin") == []
        assert (tmp_path / "old.bin").read_bytes() == old[:len((tmp_path / "old.bin").read_bytes())]
        assert bytes(raw.sii[:len(new)]) == bytes(new) and raw.sii_writes[0][0] == 0
    finally:
        bus.close()
