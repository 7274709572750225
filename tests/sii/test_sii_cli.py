"""The ``ecattool sii`` commands: info, check, fix-crc, set-alias, build, diff (exit codes, JSON, files)."""

from __future__ import annotations

import json
import shutil

import pytest

from ecattool.sii import crc8, load
from tests.conftest import run, ROOT, corpus_path

SAMPLE_ESI = ROOT / "samples" / "sii" / "custom_slave.xml"
SAMPLE_BIN = ROOT / "samples" / "sii" / "custom_slave.bin"




def test_info_json_has_the_listed_keys(capsys) -> None:
    code, out, _ = run(capsys, "sii", "info", str(corpus_path("sii", "ni9144.bin")), "--json")
    assert code == 0
    d = json.loads(out)
    assert {"vendor_id", "product_code", "revision", "serial", "crc_ok", "categories"} <= set(d)
    assert (d["vendor_id"], d["product_code"], d["revision"], d["serial"], d["crc_ok"]) == (0x1F9, 0x23B8, 2, 0, True)
    assert [(c["type"], c["words"]) for c in d["categories"]] == [(10, 89), (30, 16), (40, 1), (41, 16), (42, 4),
                                                                   (50, 60), (60, 24)]


def test_info_text(capsys) -> None:
    code, out, _ = run(capsys, "sii", "info", str(corpus_path("sii", "easycat_FEI_2.bin")))
    assert code == 0 and "FEI_SLAVE_Count" in out and "0x00000EEA" in out and "DC_Sync" in out


def test_check_exit_codes(capsys) -> None:
    assert run(capsys, "sii", "check", str(corpus_path("sii", "ni9144.bin")))[0] == 0
    code, out, _ = run(capsys, "sii", "check", str(corpus_path("sii", "easycat_FEI_256.bin")))
    assert code == 1 and "[sii.size]" in out
    code, out, _ = run(capsys, "sii", "check", str(corpus_path("sii", "pollen_Orbita2d.bin")), "--strict", "--json")
    assert code == 1 and json.loads(out)["findings"][0]["rule"] == "sii.vendor"


def test_check_against_esi(capsys) -> None:
    code, out, _ = run(capsys, "sii", "check", str(corpus_path("sii", "pollen_Orbita2d.xml")),
                       str(corpus_path("sii", "pollen_Orbita2d.bin")), "--json")
    assert code == 1
    assert "sii.esi.identity" in {f["rule"] for f in json.loads(out)["findings"]}
    code, _, _ = run(capsys, "sii", "check", str(corpus_path("sii", "ni9144.xml")), str(corpus_path("sii", "ni9144.bin")))
    assert code == 0


def test_check_truncated_file_is_one_located_line(capsys, tmp_path) -> None:
    p = tmp_path / "cut.bin"
    p.write_bytes(corpus_path("sii", "ni9144.bin").read_bytes()[:420])
    code, out, _ = run(capsys, "sii", "check", str(p))
    assert code == 1 and out.splitlines()[0].startswith(f"{p}: error:")


def test_fix_crc_and_set_alias_write_new_files(capsys, tmp_path) -> None:
    src = tmp_path / "in.bin"
    raw = bytearray(corpus_path("sii", "ni9144.bin").read_bytes())
    raw[14] = 0
    src.write_bytes(bytes(raw))
    out = tmp_path / "fixed.bin"
    assert run(capsys, "sii", "fix-crc", str(src), "-o", str(out))[0] == 0
    assert out.read_bytes() == corpus_path("sii", "ni9144.bin").read_bytes()
    alias = tmp_path / "alias.hex"
    assert run(capsys, "sii", "set-alias", str(out), "0x0007", "-o", str(alias))[0] == 0
    data = load(alias).to_bytes()
    assert data[8:10] == b"\x07\x00" and data[14] == crc8(data[:14])


def test_outputs_never_overwrite_the_input(capsys, tmp_path) -> None:
    src = tmp_path / "in.bin"
    shutil.copy(corpus_path("sii", "ni9144.bin"), src)
    code, _, err = run(capsys, "sii", "set-alias", str(src), "1", "-o", str(src))
    assert code == 1 and "refusing to overwrite" in err
    assert src.read_bytes() == corpus_path("sii", "ni9144.bin").read_bytes()


def test_build_the_sample_reproduces_the_committed_image(capsys, tmp_path) -> None:
    out = tmp_path / "custom.bin"
    assert run(capsys, "sii", "build", str(SAMPLE_ESI), "-o", str(out))[0] == 0
    assert out.read_bytes() == SAMPLE_BIN.read_bytes()
    assert run(capsys, "sii", "check", str(SAMPLE_ESI), str(out))[0] == 0


def test_build_options(capsys, tmp_path) -> None:
    out = tmp_path / "small.bin"
    assert run(capsys, "sii", "build", str(SAMPLE_ESI), "--no-pdo-categories", "--size", "512", "-o", str(out))[0] == 0
    img = load(out)
    assert len(out.read_bytes()) == 512 and not img.tx_pdos and not img.rx_pdos
    code, _, err = run(capsys, "sii", "build", str(SAMPLE_ESI), "--size", "256", "-o", str(tmp_path / "x.bin"))
    assert code == 1 and "holds 256" in err and err.count("\n") == 1


def test_build_selects_a_device_from_a_multi_device_esi(capsys, tmp_path) -> None:
    esi = corpus_path("sii", "ni9144.xml")
    code, _, err = run(capsys, "sii", "build", str(esi), "-o", str(tmp_path / "a.bin"))
    assert code == 1 and "ecattool: error:" in err
    out = tmp_path / "rev2.bin"
    assert run(capsys, "sii", "build", str(esi), "--device", "#x23B8:2", "-o", str(out))[0] == 0
    assert load(out).header.revision == 2


def test_diff(capsys) -> None:
    a, b = str(corpus_path("sii", "ni9144.bin")), str(corpus_path("sii", "ni9144_rev1.bin"))
    code, out, _ = run(capsys, "sii", "diff", a, b)
    assert code == 1 and out.splitlines()[0] == "header.revision: 2 != 1"
    code, out, _ = run(capsys, "sii", "diff", a, a, "--json")
    assert code == 0 and json.loads(out)["identical"] is True


@pytest.mark.parametrize("cmd", ["info", "check", "fix-crc", "set-alias", "build", "diff"])
def test_help_has_an_example(capsys, cmd: str) -> None:
    code, out, _ = run(capsys, "sii", cmd, "--help")
    assert code == 0 and "ecattool sii " + cmd in out


def test_swapped_arguments_name_the_order(capsys) -> None:
    code, out, _ = run(capsys, "sii", "check", str(corpus_path("sii", "ni9144.bin")), str(corpus_path("sii", "ni9144.xml")))
    assert code == 1 and "XML file (an ESI?)" in out and "ni9144.xml:1:" in out


def test_image_from_stdin() -> None:
    from click.testing import CliRunner

    from ecattool.cli import cli

    data = corpus_path("sii", "ni9144.bin").read_bytes()
    res = CliRunner().invoke(cli, ["sii", "info", "-", "--json"], input=data, catch_exceptions=False)
    assert res.exit_code == 0 and json.loads(res.output)["source"] == "<stdin>"
    res = CliRunner().invoke(cli, ["sii", "check", str(corpus_path("sii", "ni9144.xml")), "-"], input=data)
    assert res.exit_code == 0 and res.output.startswith("OK")


def test_build_warns_when_the_esis_own_categories_make_an_image_that_fails_check(capsys, tmp_path) -> None:
    # Elmo's boot device gives its own GENERAL and a 9-byte SYNCM (Eeprom/Category 30, 41): the image is what
    # the ESI says, and the build says it will not pass `sii check`
    out = tmp_path / "boot.bin"
    code, _, err = run(capsys, "sii", "build", str(corpus_path("esi", "elmo_Elmo_ECAT_00010420_V11.xml")),
                       "--device", "0", "-o", str(out))
    assert code == 0 and out.exists()
    assert len(err.strip().splitlines()) == 1 and "warning" in err and "Eeprom/Category 30, 41" in err
    assert run(capsys, "sii", "check", str(out))[0] == 1
    good = tmp_path / "good.bin"  # an ESI whose image checks clean builds silently
    code, _, err = run(capsys, "sii", "build", str(corpus_path("sii", "metalmusings_EaserCAT_2000.xml")),
                       "-o", str(good))
    assert code == 0 and err == "" and run(capsys, "sii", "check", str(good))[0] == 0
