"""The 'ecattool sw' commands end to end (in-process; one subprocess run checks the one-line error)."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from ecattool.sw import read, write
from tests.conftest import ROOT, corpus_path, run, sample_sw_spec

SW = "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.sw"
PARAMS = "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.ems_parameters.cfg"




def c(name: str) -> str:
    return str(corpus_path("sw", name))


def test_info_json_is_exactly_the_documented_shape(capsys):
    code, out, _ = run(capsys, "sw", "info", "--json", c(SW))
    assert code == 0
    assert json.loads(out) == {"blocks": [
        {"start": 0x7ABD, "end": 0x7FAF, "count": 1267, "checksum": 0x4A2A},
        {"start": 0x7FBF, "end": 0x7FE0, "count": 34, "checksum": 0xFFFF},
        {"start": 0x7FFF, "end": 0x7FFF, "count": 1, "checksum": 0x7ABD}]}


def test_info_table_names_the_blocks(capsys):
    code, out, _ = run(capsys, "sw", "info", c("ecmc_ipos4808_BRUSHDC_VOLT_48V_20A_plusTML.sw"))
    assert code == 0
    for text in ("0x7FAF7ABD", "setup table, configuration id 0x2E63", "identification 'P027314E221F515K'",
                 "setup pointer -> 0x7ABD", "TML program", "0x40264000"):
        assert text in out


def test_info_flags_a_wrong_integrity_word(capsys, tmp_path):
    raw = corpus_path("sw", SW).read_bytes().replace(b"\r\n7ABD\r\n\r\n", b"\r\n7ABE\r\n\r\n")
    bad = tmp_path / "bad.sw"
    bad.write_bytes(raw)
    code, out, _ = run(capsys, "sw", "info", str(bad))
    assert code == 1 and "sw-pointer" in out


def test_corrupt_file_is_one_line_with_file_and_line():
    out = subprocess.run([sys.executable, "-m", "ecattool", "sw", "info", c("march_imc_rotational_joint.sw")],
                         capture_output=True, text=True)
    assert out.returncode == 1
    assert out.stderr.strip().splitlines() == [
        f"ecattool: error: {c('march_imc_rotational_joint.sw')}:207: '9E9(E(' is not a hex word of at most 4 digits "
        "(expected e.g. 7ABD or 92)"]


def test_foe_and_back_are_byte_identical_with_the_corpus(capsys, tmp_path):
    foe = tmp_path / "FOESW_AXIS01.bin"
    assert run(capsys, "sw", "foe", c(SW), "-o", str(foe))[0] == 0
    assert foe.read_bytes() == corpus_path("sw", "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.bin").read_bytes()
    back = tmp_path / "back.sw"
    assert run(capsys, "sw", "from-foe", str(foe), "-o", str(back))[0] == 0
    assert back.read_bytes() == corpus_path("sw", SW).read_bytes()


def test_foe_refuses_a_name_the_drive_rejects(capsys, tmp_path):
    code, _, err = run(capsys, "sw", "foe", c(SW), "-o", str(tmp_path / "FOESW_AXIS0123X.bin"))
    assert code == 1 and "longer than 14" in err
    assert not (tmp_path / "FOESW_AXIS0123X.bin").exists()


def test_dry_run_json_lists_the_plan(capsys):
    code, out, _ = run(capsys, "sw", "download", "--dry-run", "--json", "--mode", "32", c("ecmc_TMLCode.sw"))
    data = json.loads(out)
    assert code == 0 and data["mode"] == 32
    cmds = data["commands"]
    assert cmds[0] == {"index": 0x2064, "subindex": 0, "value": 0x40000009, "size": 4, "expect_reply": True,
                       "comment": cmds[0]["comment"]}
    assert [c_["index"] for c_ in cmds[-4:]] == [0x2064, 0x2065, 0x2069, 0x2080]
    assert cmds[-1]["expect_reply"] is False and cmds[-1]["size"] == 2


def test_dry_run_table(capsys):
    code, out, _ = run(capsys, "sw", "download", "--dry-run", c("ecmc_TMLCode.sw"))
    assert code == 0 and "0x40000008" in out and "0x2080:00" in out


def test_verify_download_verify_on_the_simulator(capsys):
    code, out, _ = run(capsys, "sw", "verify", c(SW), "--target", "sim")
    assert code == 1 and "DIFFERENT" in out
    code, out, _ = run(capsys, "sw", "download", c(SW), "--target", "sim", "--json")
    report = json.loads(out)
    assert code == 0 and report["ok"] and report["reset"] and len(report["written"]) == 3
    code, out, _ = run(capsys, "sw", "verify", c(SW), "--target", "sim", "--preload", c(SW), "--json")
    assert code == 0 and json.loads(out)["ok"] is True


def test_no_reset_download_that_checks_out_says_so(capsys):
    """Issue 37.6: every block written and verified, the reset left out on purpose: not "still different"."""
    code, out, _ = run(capsys, "sw", "download", c(SW), "--target", "sim", "--no-reset")
    assert code == 0 and "still different" not in out
    assert out.strip().splitlines()[-1] == ("every block checks out; drive NOT reset (--no-reset): reset it to load "
                                            "the new setup")


def test_download_when_everything_matches_writes_nothing(capsys):
    code, out, _ = run(capsys, "sw", "download", c(SW), "--preload", c(SW))
    assert code == 0 and "nothing written" in out


def test_preload_on_a_real_master_is_refused_before_it_is_opened(capsys, monkeypatch):
    from ecattool.target import pysoem as pysoem_target

    def never(*args, **kwargs):
        raise AssertionError("a real master was opened")

    monkeypatch.setattr(pysoem_target, "PysoemTarget", never)
    code, _, err = run(capsys, "sw", "verify", c(SW), "--target", "pysoem:ecat0", "--preload", c(SW))
    assert code == 1 and "--preload is for the simulator only" in err


def test_unknown_target_is_an_error(capsys):
    code, _, err = run(capsys, "sw", "verify", c(SW), "--target", "nope")
    assert code == 1 and "unknown target" in err


def test_show_patch_diff(capsys, tmp_path):
    code, out, _ = run(capsys, "sw", "show", c(SW), "-p", c(PARAMS), "--json")
    values = {v["name"]: v for v in json.loads(out)["values"]}
    assert code == 0 and values["PWMPER"]["value"] == 2250 and values["PWMPER"]["address"] == 0x0252
    new = tmp_path / "new.sw"
    code, _, _ = run(capsys, "sw", "patch", c(SW), "-p", c(PARAMS), "--set", "PWMPER=2251", "--set", "SLPER=10",
                     "-o", str(new))
    assert code == 0 and new.read_bytes().count(b"\r\n") == corpus_path("sw", SW).read_bytes().count(b"\r\n")
    assert run(capsys, "sw", "info", str(new))[0] == 0
    code, out, _ = run(capsys, "sw", "diff", c(SW), str(new), "-p", c(PARAMS), "--json")
    data = json.loads(out)
    assert code == 1 and {d["name"] for d in data["differences"]} == {"PWMPER", "SLPER"}
    assert run(capsys, "sw", "diff", c(SW), c(SW))[0] == 0


def test_diff_with_parameters_shows_values_as_show_does(capsys, tmp_path):
    new = tmp_path / "new.sw"
    assert run(capsys, "sw", "patch", c(SW), "-p", c(PARAMS), "--set", "CACC=0.5", "--set", "SLPER=-3",
               "-o", str(new))[0] == 0
    code, out, _ = run(capsys, "sw", "diff", c(SW), str(new), "-p", c(PARAMS), "--json")
    by_name = {d["name"]: d for d in json.loads(out)["differences"]}
    assert code == 1
    # FIXED 16.16 as a decimal (raw 0x32EE0 = 3.18311), INT signed (raw 0xFFFD = -3), raw words kept too
    assert by_name["CACC"].items() >= {"type": "FIXED", "a": 0x32EE0, "a_value": "3.18311", "b": 0x8000, "b_value": "0.5"}.items()
    assert by_name["SLPER"].items() >= {"type": "INT", "a": 20, "a_value": "20", "b": 0xFFFD, "b_value": "-3"}.items()
    code, out, _ = run(capsys, "sw", "diff", c(SW), str(new), "-p", c(PARAMS))
    assert "3.18311 (0x32EE0)" in out and "-3 (0xFFFD)" in out
    code, out, _ = run(capsys, "sw", "diff", c(SW), str(new), "--json")  # untyped without parameters.cfg
    assert all("a_value" not in d for d in json.loads(out)["differences"])


def test_show_without_parameters_mentions_section_3(capsys):
    code, out, _ = run(capsys, "sw", "show", c("march_imc_left_ankle.sw"))
    assert code == 0 and "section 3" in out and "0x0252" in out


def test_patch_never_overwrites_its_input(capsys, tmp_path):
    src = tmp_path / "a.sw"
    src.write_bytes(corpus_path("sw", SW).read_bytes())
    code, _, err = run(capsys, "sw", "patch", str(src), "--set", "0x0252=1", "-o", str(src))
    assert code == 1 and "overwrite an input" in err
    assert src.read_bytes() == corpus_path("sw", SW).read_bytes()


def test_patch_needs_name_equals_value(capsys):
    code, _, _ = run(capsys, "sw", "patch", c(SW), "--set", "PWMPER", "-o", "x.sw")
    assert code == 2


def test_build_sample(capsys, tmp_path):
    out = tmp_path / "axis1.sw"
    assert run(capsys, "sw", "build", str(sample_sw_spec(tmp_path)), "-o", str(out))[0] == 0
    image = read(out)
    assert [b.start for b in image] == [0x7ABD, 0x7FBF, 0x7FFF, 0x4000, 0x5638]
    assert write(image) == out.read_bytes()


@pytest.mark.parametrize("command", ["info", "foe", "from-foe", "verify", "download", "show", "patch", "diff", "build"])
def test_every_command_has_help_with_an_example(capsys, command):
    code, out, _ = run(capsys, "sw", command, "--help")
    assert code == 0 and "Examples:" in out and f"ecattool sw {command}" in out


def _project(tmp_path) -> str:
    (tmp_path / "axis.sw").write_bytes(corpus_path("sw", SW).read_bytes())
    p = tmp_path / "machine.yaml"
    p.write_text("ecattool: 1\nname: m\ndrives:\n  - name: x\n    device: {profile: technosoft-ipos}\n"
                 "  - name: y\n    device: {profile: technosoft-ipos}\n    sw: axis.sw\n")
    return str(p)


def test_project_drive_with_sw_is_verified_and_downloaded(capsys, tmp_path):
    project = _project(tmp_path)
    code, out, _ = run(capsys, "sw", "verify", "--project", project, "--json")
    assert code == 1 and len(json.loads(out)["blocks"]) == 3
    code, out, _ = run(capsys, "sw", "download", "--project", project, "--drive", "y", "--json")
    assert code == 0 and json.loads(out)["reset"] is True


def test_project_drive_selection_errors(capsys, tmp_path):
    project = _project(tmp_path)
    code, _, err = run(capsys, "sw", "verify", "--project", project, "--drive", "z")
    assert code == 1 and "no drive 'z'" in err and "(x, y)" in err
    code, _, err = run(capsys, "sw", "verify", "--project", project, "--drive", "x")
    assert code == 1 and "has no readable sw image" in err
    code, _, err = run(capsys, "sw", "verify", c(SW), "--drive", "x")
    assert code == 1 and "--drive needs --project" in err
