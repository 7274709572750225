"""``ecattool map check|layout|sdo``: exit codes, JSON, files with line numbers, outputs, help examples."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from ecattool.esi.model import Direction
from tests.conftest import corpus_path
from tests.project.project_helpers import run

TS = ["--profile", "technosoft-ipos"]


def test_check_ok_and_failed(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, "map", "check", *TS, "--rx", "0x1600=controlword,0x607A:00/32")
    assert code == 0 and out.startswith("OK: iPOS360x VX-CAT: outputs 6 bytes")
    code, out, _ = run(capsys, "map", "check", *TS, "--rx", "0x1600=controlword,0x607A:00/32,0x60FF:00/32")
    assert code == 1 and "[PDO009]" in out and "FAILED" in out


def test_check_json(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, "map", "check", *TS, "--tx", "0x1A00=statusword,0x207D:00/8", "--json")
    doc = json.loads(out)
    assert code == 1 and doc["ok"] is False and [f["rule"] for f in doc["findings"]] == ["PDO013"]
    assert doc["inputs_bytes"] == 3 and doc["mapping"]["tx"][0]["entries"] == ["0x6041:00/16", "0x207D:00/8"]


def test_check_strict_fails_on_warnings(capsys: pytest.CaptureFixture[str]) -> None:
    args = ("map", "check", *TS, "--rx", "0x1600=controlword,controlword")
    assert run(capsys, *args)[0] == 0
    assert run(capsys, *args, "--strict")[0] == 1


def test_bad_mapping_text_is_one_line_error(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run(capsys, "map", "check", *TS, "--rx", "0x1600=nonsense")
    assert code == 1 and err.count("\n") == 1 and "no object named 'nonsense'" in err and "Traceback" not in err
    code, out, _ = run(capsys, "map", "check", *TS, "--rx", "0x1600=nonsense", "--json")
    assert code == 1 and json.loads(out)["findings"][0]["rule"] == "PDO000"


def test_usage_errors_exit_2(capsys: pytest.CaptureFixture[str]) -> None:
    assert run(capsys, "map", "check", "--rx", "0x1600")[0] == 2  # no device
    assert run(capsys, "map", "sdo", *TS, "--order", "sideways")[0] == 2


def test_device_name_without_esi_is_a_profile(capsys: pytest.CaptureFixture[str]) -> None:
    # the top-level --help example
    code, out, _ = run(capsys, "map", "check", "--device", "technosoft-ipos", "--rx", "0x6040:00/16,0x607A:00/32")
    assert code == 0


def test_layout_json_and_output_file(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    code, out, _ = run(capsys, "map", "layout", *TS, "--rx", "0x1600=controlword,modes of operation,gap/8",
                       "--json")
    doc = json.loads(out)
    assert code == 0 and [e["offset"] for e in doc["outputs"]["entries"]] == ["0.0", "2.0", "3.0"]
    target = tmp_path / "image.json"
    assert run(capsys, "map", "layout", *TS, "-o", str(target))[0] == 0
    assert json.loads(target.read_text())["inputs"]["bytes"] == 16


def test_layout_table(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, "map", "layout", *TS)
    assert code == 0 and "Outputs SM2 (6 bytes, 48 bits)" in out and "0x607A:00" in out


def test_sdo_table_json_and_refusal(capsys: pytest.CaptureFixture[str]) -> None:
    args = ("map", "sdo", *TS, "--rx", "0x1600;0x1601;0x1602=controlword,modes of operation")
    code, out, _ = run(capsys, *args)
    assert code == 0 and "9 SDO writes" in out and "0x60600008" in out
    code, out, _ = run(capsys, *args, "--json")
    rows = json.loads(out)
    assert [(r["index"], r["subindex"], r["size"]) for r in rows][:3] == [("0x1C12", 0, 1), ("0x1602", 0, 1),
                                                                        ("0x1602", 1, 4)]
    code, _, err = run(capsys, "map", "sdo", *TS, "--tx", "0x1A00=statusword,0x207D:00/8")
    assert code == 1 and "[PDO013]" in err
    code, out, _ = run(capsys, "map", "sdo", *TS, "--tx", "0x1A00=statusword,0x207D:00/8", "--force", "--json")
    assert code == 0 and json.loads(out)


def test_sdo_complete_access_with_esi(capsys: pytest.CaptureFixture[str]) -> None:
    esi = str(corpus_path("esi", "ingenia_eve-xcr-e_esi.xml"))
    code, out, _ = run(capsys, "map", "sdo", "--esi", esi, "--rx", "0x1600=controlword,0x607A:00/32",
                       "--complete-access", "--json")
    rows = json.loads(out)
    assert code == 0 and rows[1] == {"transition": "PS", "index": "0x1600", "subindex": 0, "size": 10,
                                     "data": "020010004060" "20007a60", "value": None, "complete_access": True,
                                     "comment": "download pdo 0x1600 entries (complete access)"}


def test_mapping_file_findings_have_lines(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    f = tmp_path / "mapping.yaml"
    f.write_text("pdo:\n  rx:\n    - index: 0x1600\n      entries:\n        - controlword\n        - 0x6040:00/32\n")
    code, out, _ = run(capsys, "map", "check", *TS, "--mapping", str(f))
    assert code == 1 and f"{f}:6:11: error:" in out and "[PDO007]" in out


def test_output_never_overwrites_an_input(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    f = tmp_path / "mapping.yaml"
    f.write_text("rx:\n  - index: 0x1600\n    entries: [controlword]\n")
    code, _, err = run(capsys, "map", "sdo", *TS, "--mapping", str(f), "-o", str(f))
    assert code == 1 and f.read_text().startswith("rx:")


@pytest.mark.parametrize("command", ["check", "layout", "sdo"])
def test_help_has_examples(capsys: pytest.CaptureFixture[str], command: str) -> None:
    code, out, _ = run(capsys, "map", command, "--help")
    assert code == 0 and f"ecattool map {command} --profile technosoft-ipos" in out and "Mapping syntax" in out


def test_check_a_master_configuration(capsys: pytest.CaptureFixture[str]) -> None:
    ecmc = str(corpus_path("configs", "ecmc_ecmciPOSXXXX.cmd"))
    code, out, _ = run(capsys, "map", "check", *TS, "--product", "ipos4808-bx-cat", "--startup", ecmc, "--json")
    doc = json.loads(out)
    assert code == 0 and [f["rule"] for f in doc["findings"]] == ["PDO028"] * 3
    assert doc["inputs_bytes"] == 26 and len(doc["mapping"]["tx"]) == 4
    code, out, _ = run(capsys, "map", "check", *TS, "--product", "ipos4808-bx-cat", "--startup", ecmc, "--strict")
    assert code == 1 and f"{ecmc}:164: warning:" in out
    assert run(capsys, "map", "check", *TS, "--startup", ecmc, "--rx", "0x1600")[0] == 2


def test_a_slave_of_a_master_configuration_by_name_or_position(capsys: pytest.CaptureFixture[str]) -> None:
    """--drive picks a slave of a --startup file as `startup export` does; --slave N is its old spelling."""
    eni = str(corpus_path("configs", "eni_kpierczy_test_eni.xml"))
    base = ("map", "layout", "--profile", "hdt", "--startup", eni, "--json")
    code, _, err = run(capsys, *base)
    assert code == 1 and "has 5 slaves; choose one with --drive NAME (Imu at 0, WheelRearLeft at 1," in err
    outs = [run(capsys, *base, *sel) for sel in (["--drive", "WheelRearLeft"], ["--drive", "1"], ["--slave", "1"])]
    assert [o[0] for o in outs] == [0, 0, 0] and outs[0][1] == outs[1][1] == outs[2][1]
    assert outs[0][1] != run(capsys, *base, "--drive", "Imu")[1]
    code, _, err = run(capsys, *base, "--drive", "Nope")
    assert code == 1 and "no slave named or at position 'Nope' (slaves: Imu at 0," in err
    lcec = str(corpus_path("configs", "lcec_generic-complex_ethercat-conf.xml"))
    code, _, err = run(capsys, "map", "layout", "--profile", "hdt", "--startup", lcec, "--drive", "EL1809")
    assert code == 1 and "has 2 slaves named 'EL1809'; choose one by its bus position" in err


@pytest.mark.parametrize("fmt", ["twincat", "eni", "ecmc", "json"])
def test_sdo_as_a_master_startup_list_round_trips(capsys: pytest.CaptureFixture[str], tmp_path: Path,
                                                  fmt: str) -> None:
    from ecattool import pdo, profiles
    from ecattool.startup import import_file

    target = tmp_path / f"startup.{ {'twincat': 'txt', 'eni': 'xml', 'ecmc': 'cmd', 'json': 'json'}[fmt]}"
    spec = "0x1600;0x1601;0x1602=controlword,modes of operation"
    code, _, _ = run(capsys, "map", "sdo", *TS, "--rx", spec, "--format", fmt, "-o", str(target))
    assert code == 0
    if fmt == "twincat":
        assert target.read_text().splitlines()[0] == "<PS>,CoE,0x1C12:00,0x00 (0),clear sm pdos (0x1C12)"
    dev = profiles.load("technosoft-ipos")
    back = pdo.mapping_from_startup(import_file(target)[0].commands, dev)
    assert back.to_text(Direction.RX) == "0x1600;0x1601;0x1602=0x6040:00/16,0x6060:00/8"
