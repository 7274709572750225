"""``ecattool sim``: profiles, show, run (transcript, JSON, exit codes)."""

from __future__ import annotations

import json

import pytest
from click.testing import CliRunner

from ecattool.cli import cli
from ecattool.errors import InputError
from ecattool.sim import Drive
from ecattool.sim.script import parse_steps, run_script
from tests.conftest import corpus_path
from tests.conftest import run as run_main

SCRIPT = """\
- state: PREOP
- write: "1C12:00"
  value: 0
- write: "1602:00"
  value: 0
- write: "1602:01"
  value: 0x60400010
- write: "1602:02"
  data: "08006060"
- write: "1602:00"
  value: 2
- write: "1C12:03"
  value: 0x1602
- write: "1C12:00"
  value: 3
- write: "6041:00"
  value: 1
  expect_abort: 0x06010002
- state: OP
  expect_al_status: 0x0011
- state: SAFEOP
- state: OP
- read: "6041:00"
  expect: 0x0650
- exchange: "060000000000 060008"
"""


def run(*args: str):
    return CliRunner().invoke(cli, list(args), catch_exceptions=False)


def test_profiles_json():
    res = run("sim", "profiles", "--json")
    assert res.exit_code == 0
    rows = json.loads(res.output)
    assert {r["profile"] for r in rows} == {"technosoft-ipos", "hdt", "controltechniques"}


def test_show_json_lists_default_pdos():
    res = run("sim", "show", "technosoft-ipos", "--json")
    info = json.loads(res.output)
    assert info["vendor_id"] == 0x1A3
    assigned = [p["index"] for p in info["pdos"] if p["assigned"]]
    assert assigned == [0x1600, 0x1A00, 0x1A01]


def test_run_script_transcript(tmp_path):
    script = tmp_path / "steps.yaml"
    script.write_text(SCRIPT)
    res = run("sim", "run", "technosoft-ipos", str(script), "--json")
    assert res.exit_code == 0, res.output
    data = json.loads(res.output)
    assert data["ok"] and len(data["steps"]) == 14
    assert data["steps"][8]["code"] == 0x06010002 and data["steps"][9]["code"] == 0x0011


def test_run_stops_at_first_unexpected_abort(tmp_path):
    from ecattool.cli import main

    script = tmp_path / "bad.json"
    script.write_text(json.dumps([{"state": "PREOP"}, {"write": "6041:00", "value": 1}, {"read": "1000:00"}]))
    with pytest.raises(SystemExit) as exc:
        main(["sim", "run", "hdt", str(script)])
    assert exc.value.code == 1


def test_run_on_an_esi_file(tmp_path):
    script = tmp_path / "s.yaml"
    script.write_text("- state: PREOP\n- read: '1018:01'\n  expect: 0x9A\n- state: SAFEOP\n- state: OP\n")
    res = run("sim", "run", str(corpus_path("esi", "elmo_Elmo_ECAT_00010420_V11.xml")), str(script), "--device", "2")
    assert res.exit_code == 0, res.output
    assert "ok" in res.output


def test_script_errors_carry_locations():
    with pytest.raises(InputError):
        parse_steps([{"nothing": 1}], [], "x.yaml")
    d = Drive.from_profile("hdt")
    tr = run_script(d, [{"state": "PREOP"}, {"write": "6060:00", "value": "0x08"}, {"read": "6060:00", "expect": 8}], [])
    assert tr.ok and tr.lines[-1].value == 8


@pytest.mark.parametrize(("step", "words"), [
    ({"read": "6041:00", "expcet": 0x0640}, ["step 2 (read)", "'expcet'", "did you mean 'expect'"]),
    ({"write": "6060:00", "value": 8, "expect": 8}, ["step 2 (write)", "'expect'"]),
    ({"state": "OP", "expect_abort": 0x06010002}, ["step 2 (state)", "'expect_abort'", "expect_al_status"]),
    ({"read": "6041:00", "write": "6060:00"}, ["step 2 has read and write"]),
    ({"cycles": 10, "value": 1}, ["step 2 (cycles)", "nothing else"]),
])
def test_script_key_that_would_be_ignored_is_refused(capsys, tmp_path, step, words):
    """A misspelled or misplaced key would silently check nothing: the script is refused before it runs."""
    script = tmp_path / "s.yaml"
    import yaml

    script.write_text(yaml.safe_dump([{"state": "PREOP"}, step], sort_keys=False))
    code, out, err = run_main(capsys, "sim", "run", "hdt", str(script))
    assert code == 1 and not out
    line = err.strip()
    assert "\n" not in line and f"{script}:" in line and "Traceback" not in line, line
    for w in words:
        assert w in line, line
