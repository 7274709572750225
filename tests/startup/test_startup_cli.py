"""``ecattool startup`` commands: import (text and JSON), export, convert, errors and exit codes."""

from __future__ import annotations

import json

import pytest

from ecattool.startup import import_file
from tests.conftest import corpus_path
from tests.project.project_helpers import run


def test_import_shows_commands_and_pdos(capsys):
    code, out, _ = run(capsys, "startup", "import", str(corpus_path("configs", "ros2_technosoft_ipos3604.yaml")))
    assert code == 0
    assert "0x60C2:01" in out and "Set base 10-3s" in out and "RxPDO 0x1602" in out


def test_import_json_has_locations(capsys):
    path = str(corpus_path("configs", "ecmc_ecmciPOSXXXX.cmd"))
    code, out, _ = run(capsys, "startup", "import", path, "--json")
    assert code == 0
    doc = json.loads(out)
    assert doc["format"] == "ecmc" and len(doc["slaves"]) == 1
    assert doc["slaves"][0]["commands"][0]["source"] == f"{path}:11"


def test_import_reports_soe_entries(capsys):
    code, out, _ = run(capsys, "startup", "import", str(corpus_path("configs", "lcec_initcmds_AX5206-AM8032-async.xml")))
    assert code == 0 and "87 SoE init command(s)" in out and "startup.soe" in out


def test_export_to_stdout(capsys):
    src = str(corpus_path("configs", "ros2_elmo_gold.yaml"))
    code, out, err = run(capsys, "startup", "export", "--from", src, "--format", "twincat")
    # TwinCAT lines carry neither its DC nor its PDO tables (the file programs no PDO by SDO): refused, listed
    assert code == 1 and not out and "twincat cannot carry 2 part(s)" in err and "PDO assignment and mapping" in err
    code, out, err = run(capsys, "startup", "export", "--from", src, "--format", "twincat", "--lossy")
    assert code == 0 and err.count("not written (twincat): ") == 2
    assert out.splitlines() == [
        "<PS>,CoE,0x60C2:01,0x0A (10),Set interpolation time for cyclic modes to 10 ms",
        "<PS>,CoE,0x60C2:02,0xFD (253),Set base 10-3s",
        "<PS>,CoE,0x6098:00,0x23 (35),",
    ]


def test_convert_writes_file_and_round_trips(tmp_path, capsys):
    out_file = tmp_path / "ipos.json"
    src = corpus_path("configs", "ecmc_ecmciPOSXXXX.cmd")
    code, _, _ = run(capsys, "startup", "convert", str(src), "--format", "json", "-o", str(out_file))
    assert code == 0
    (again,) = import_file(out_file)
    (orig,) = import_file(src)
    assert [(c.index, c.subindex, c.data) for c in again.commands] == [(c.index, c.subindex, c.data) for c in orig.commands]
    code, _, _ = run(capsys, "startup", "export", "--from", str(out_file), "--format", "ecmc", "-o", str(tmp_path / "x.cmd"))
    assert code == 0 and "Cfg.EcAddSdo(" in (tmp_path / "x.cmd").read_text()
    # the script leaves vendor and product to the device script that includes it: IgH needs them, so it is
    # refused with a one-line error, and nothing is written
    code, _, err = run(capsys, "startup", "export", "--from", str(out_file), "--format", "igh", "-o", str(tmp_path / "x.c"))
    assert code == 1 and "no vendor id/product code" in err and not (tmp_path / "x.c").exists()


def test_convert_never_overwrites_its_input(tmp_path, capsys):
    src = tmp_path / "in.json"
    src.write_text(json.dumps({"format": "ecattool-startup", "version": 1, "slaves": []}))
    code, _, err = run(capsys, "startup", "convert", str(src), "--format", "json", "-o", str(src))
    assert code == 1 and "ecattool: error:" in err


def test_bad_input_is_one_line_with_location(tmp_path, capsys):
    bad = tmp_path / "bad.txt"
    bad.write_text("<PS>,CoE,0x1C12:00,0x00 (0),ok\n<PS>,CoE,nonsense,0x00 (0),x\n")
    code, _, err = run(capsys, "startup", "import", str(bad))
    assert code == 1
    assert err.strip().count("\n") == 0 and f"{bad}:2:" in err


def test_hwdevmgr_refusal_exit_code(capsys):
    code, _, err = run(capsys, "startup", "import", str(corpus_path("configs", "hwdevmgr_device_config.yaml")))
    assert code == 1 and "hw_device_mgr" in err


@pytest.mark.parametrize("args", [["startup", "export", "--format", "eni"], ["startup", "convert", "x", "--format", "nope"]])
def test_usage_errors_exit_2(capsys, args):
    code, _, _ = run(capsys, *args)
    assert code == 2


def test_help_has_examples(capsys):
    for sub in ("import", "export", "convert"):
        code, out, _ = run(capsys, "startup", sub, "--help")
        assert code == 0 and "Examples:" in out and "ecattool startup" in out


def test_import_from_stdin(capsys, monkeypatch):
    import io
    import sys

    monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(io.BytesIO(b"<PS>,CoE,0x6060:00,0x08 (8),CSP\n")))
    code, out, _ = run(capsys, "startup", "import", "-", "--json")
    assert code == 0
    doc = json.loads(out)
    assert doc["format"] == "twincat" and doc["slaves"][0]["commands"][0]["source"] == "<stdin>:1"


def test_export_one_drive_of_a_project_for_the_one_slave_formats(capsys, tmp_path):
    """TwinCAT lines and ros2 files hold one slave: a two-drive project could not be exported to them at all
    (the error said 'export them one by one', and nothing selected a drive)."""
    for name in ("inovance_SV660_EOE_1Axis_V9.12.xml", "copley_XE2_4.60.xml"):
        (tmp_path / name).symlink_to(corpus_path("esi", name))
    project = tmp_path / "m.yaml"
    project.write_text("ecattool: 1\nname: m\ndrives:\n"
                       "  - name: x\n    device: {esi: inovance_SV660_EOE_1Axis_V9.12.xml}\n"
                       "    parameters: [{object: '6060:00', value: 8}]\n"
                       "    dc: {opmode: DC, cycle_ns: 1000000}\n"
                       "  - name: y\n    device: {esi: copley_XE2_4.60.xml}\n"
                       "    parameters: [{object: '6060:00', value: 1}]\n", encoding="utf-8")
    code, _, err = run(capsys, "startup", "export", "--project", str(project), "--format", "ros2")
    assert code == 1 and "one by one: --drive" in err
    code, out, _ = run(capsys, "startup", "export", "--project", str(project), "--format", "ros2", "--drive", "y")
    assert code == 0 and "product_id: 0x000010b0" in out and "0x000c010d" not in out
    code, out, _ = run(capsys, "startup", "export", "--project", str(project), "--format", "twincat", "--drive", "0",
                       "--lossy")  # drive x runs DC, which a TwinCAT startup list has no place for
    assert (code, out) == (0, "<PS>,CoE,0x6060:00,0x08 (8),Modes of operation\n")
    code, out, _ = run(capsys, "startup", "export", "--project", str(project), "--format", "json",
                       "--drive", "y", "--drive", "x")
    assert [s["name"] for s in json.loads(out)["slaves"]] == ["x", "y"]  # bus order
    code, _, err = run(capsys, "startup", "export", "--project", str(project), "--format", "json", "--drive", "z")
    assert code == 1 and "no slave named or at position 'z' (slaves: x at 0, y at 1)" in err


def test_a_soe_only_drive_to_csv_is_refused_never_a_header_only_file(tmp_path, capsys):
    """Issue 27: 87 SoE commands into CSV gave a header-only file with exit 0, and the note said CSV carried them."""
    src = str(corpus_path("configs", "lcec_initcmds_AX5206-AM8032-async.xml"))
    out = tmp_path / "x.csv"
    code, _, err = run(capsys, "startup", "convert", src, "--format", "csv", "-o", str(out))
    assert code == 1 and "csv cannot carry" in err and "87 SoE command(s)" in err and not out.exists()
    assert "only the ENI, TwinCAT, IgH and JSON formats carry them" in err  # the import's note says it right
    code, _, err = run(capsys, "startup", "convert", src, "--format", "csv", "--lossy", "-o", str(out))
    assert code == 1 and "nothing to write: csv carries nothing" in err and not out.exists()
    code, _, err = run(capsys, "startup", "import", str(_header_only(tmp_path)))
    assert code == 1 and "nothing to import" in err and err.count("\n") == 1


def _header_only(tmp_path):
    path = tmp_path / "empty.csv"
    path.write_text("slave,position,transition,index,subindex,data,complete_access,timeout_ms,type,value,comment,kind\n")
    return path


def test_ros2_tables_to_twincat_is_refused_never_an_empty_file(tmp_path, capsys):
    """Issue 27: a ros2 file whose PDOs are tables only became a 0-byte TwinCAT file with exit 0."""
    src = str(corpus_path("configs", "ros2_beckhoff_el3104.yaml"))
    out = tmp_path / "x.txt"
    for extra in ((), ("--lossy",)):
        code, _, err = run(capsys, "startup", "convert", src, "--format", "twincat", *extra, "-o", str(out))
        assert code == 1 and not out.exists() and "PDO assignment and mapping" in err
