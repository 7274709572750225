"""`ecattool scale` end to end: compute, startup, explain, si; errors with locations; exit codes."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.conftest import run

ROOT = Path(__file__).resolve().parents[2]
SAMPLES = ROOT / "samples" / "scaling"




@pytest.mark.parametrize("sample", sorted(p.name for p in SAMPLES.glob("*.yaml")))
def test_every_sample_computes(capsys, sample: str) -> None:
    code, out, err = run(capsys, "scale", "compute", str(SAMPLES / sample), "--json")
    assert code == 0, err
    data = json.loads(out)
    assert data["objects"] and data["family"] in ("technosoft-ipos", "hdt", "controltechniques", "generic")


def test_compute_table_for_ballscrew(capsys) -> None:
    code, out, _ = run(capsys, "scale", "compute", str(SAMPLES / "ballscrew.yaml"))
    assert code == 0
    assert "0x6093:01" in out and "0xFD010100" in out and "1200" in out  # 1200 counts per mm


def test_compute_from_options_reproduces_radian_example(capsys) -> None:
    code, out, _ = run(capsys, "scale", "compute", "--lines", "500", "--position", "rad", "--firmware", "F515I", "--json")
    assert code == 0
    objs = {(o["index"], o["subindex"]): o for o in json.loads(out)["objects"]}
    assert objs[("0x6093", 1)]["value"] == 4294967295 and objs[("0x6093", 2)]["value"] == 13493038
    assert objs[("0x6093", 1)]["exact"] is False and abs(objs[("0x6093", 1)]["error_ppm"]) < 0.1


def test_options_override_spec(capsys) -> None:
    code, out, _ = run(capsys, "scale", "compute", str(SAMPLES / "ballscrew.yaml"), "--family", "hdt", "--gear", "1:1", "--json")
    assert code == 0
    data = json.loads(out)
    objs = {(o["index"], o["subindex"]): o["value"] for o in data["objects"]}
    assert data["family"] == "hdt" and objs[("0x6093", 1)] * 5 == objs[("0x6093", 2)] * 65536


def test_startup_formats(capsys, tmp_path: Path) -> None:
    code, out, _ = run(capsys, "scale", "startup", str(SAMPLES / "ct_screw.yaml"))
    assert code == 0 and "<PS>,CoE,0x6092:01,0x0000000A" in out and "0x608F" not in out
    target = tmp_path / "scaling.json"
    code, _, _ = run(capsys, "scale", "startup", str(SAMPLES / "belt.yaml"), "--format", "json", "-o", str(target))
    assert code == 0 and target.exists()
    from ecattool.startup import import_file

    cmds = import_file(target)[0].commands
    assert any(c.index == 0x6093 for c in cmds)


def test_startup_never_overwrites_the_spec(capsys, tmp_path: Path) -> None:
    spec = tmp_path / "axis.yaml"
    spec.write_bytes((SAMPLES / "belt.yaml").read_bytes())
    code, _, err = run(capsys, "scale", "startup", str(spec), "-o", str(spec))
    assert code == 1 and spec.read_bytes() == (SAMPLES / "belt.yaml").read_bytes()


def test_explain_from_assignments(capsys) -> None:
    code, out, _ = run(capsys, "scale", "explain", "--family", "hdt", "6093:01=65536", "6093:02=360", "6094:01=65536",
                       "6094:02=60", "--json")
    assert code == 0
    data = json.loads(out)
    assert data["data"]["counts per position unit"]["exact"] == "8192/45"


def test_explain_from_compute_json_file(capsys, tmp_path: Path) -> None:
    target = tmp_path / "group.json"
    code, _, _ = run(capsys, "scale", "compute", str(SAMPLES / "rotary_table.yaml"), "-o", str(target))
    assert code == 0
    code, out, _ = run(capsys, "scale", "explain", "--from", str(target))
    assert code == 0 and "1 deg = 2777.777778 (25000/9) counts" in out


def test_explain_from_startup_file(capsys, tmp_path: Path) -> None:
    target = tmp_path / "startup.csv"
    code, _, _ = run(capsys, "scale", "startup", str(SAMPLES / "ballscrew.yaml"), "--format", "csv", "-o", str(target))
    assert code == 0
    code, out, _ = run(capsys, "scale", "explain", "--from", str(target), "--json")
    assert code == 0
    assert json.loads(out)["data"]["counts per position unit"]["exact"] == 1200


def test_si_command(capsys) -> None:
    code, out, _ = run(capsys, "scale", "si", "mm", "rpm", "0x03105700", "--json")
    assert code == 0
    rows = json.loads(out)
    assert rows == [{"word": "0xFD010100", "unit": "mm"}, {"word": "0x00B44700", "unit": "rpm"},
                    {"word": "0x03105700", "unit": "krad/s²"}]


def test_bad_unit_names_file_and_line(capsys, tmp_path: Path) -> None:
    spec = tmp_path / "bad.yaml"
    spec.write_text("feedback: {lines: 500}\nunits:\n  position: mm\n  velocity: furlong/s\n")
    code, _, err = run(capsys, "scale", "compute", str(spec))
    assert code == 1
    assert f"{spec}:4" in err and "furlong" in err and "Traceback" not in err


def test_unit_not_matching_axis_is_an_error(capsys) -> None:
    code, _, err = run(capsys, "scale", "compute", "--lines", "500", "--position", "mm")
    assert code == 1 and "angle unit" in err


def test_missing_feedback_is_an_error(capsys) -> None:
    code, _, err = run(capsys, "scale", "compute", "--position", "deg")
    assert code == 1 and "feedback" in err


def test_usage_error_exit_2(capsys) -> None:
    code, _, _ = run(capsys, "scale", "compute", "--family", "nope")
    assert code == 2
    code, _, _ = run(capsys, "scale", "explain", "6093:01")
    assert code == 2


@pytest.mark.parametrize("cmd", ["compute", "startup", "explain", "si"])
def test_help_has_examples(capsys, cmd: str) -> None:
    code, out, _ = run(capsys, "scale", cmd, "--help")
    assert code == 0 and "Examples:" in out and f"ecattool scale {cmd}" in out


def test_explain_reads_the_simulated_drive(capsys) -> None:
    code, out, _ = run(capsys, "scale", "explain", "--family", "hdt", "--target", "sim", "--json")
    assert code == 0
    data = json.loads(out)
    assert data["data"]["counts/s per velocity unit"]["exact"] == "16384/15"  # HDT default: rpm
    code, out, _ = run(capsys, "scale", "explain", "--family", "technosoft-ipos", "--target", "sim", "--json")
    assert code == 0 and json.loads(out)["findings"] == []  # defaults (IU) are not "inconsistent"
    code, _, _ = run(capsys, "scale", "explain", "--target", "nowhere")
    assert code == 2


def test_compute_with_a_real_esi_leaves_out_missing_objects(capsys) -> None:
    from tests.conftest import corpus_path

    esi = corpus_path("esi", "copley_XE2_4.60.xml")
    code, out, _ = run(capsys, "scale", "compute", str(SAMPLES / "rotary_table.yaml"), "--esi", str(esi), "--json")
    assert code == 0
    data = json.loads(out)
    assert data["family"] == "generic"  # the device decides, not the spec's family
    indices = {o["index"] for o in data["objects"]}
    assert "0x6092" in indices and "0x6093" not in indices
    assert any("0x6093" in n for n in data["notes"])


def test_esi_device_is_chosen_with_device_as_in_every_other_command(capsys) -> None:
    # --device SELECTOR is how esi/map/sii/sim choose a device of an ESI; scale took only --select (kept as alias)
    from tests.conftest import corpus_path

    esi = str(corpus_path("esi", "elmo_Elmo_ECAT_00010420_V11.xml"))
    spec = str(SAMPLES / "ballscrew.yaml")
    results = []
    for opt in ("--device", "--select"):
        code, out, _ = run(capsys, "scale", "compute", spec, "--esi", esi, opt, "0x00030924:0x00010420", "--json")
        assert code == 0, out
        results.append(json.loads(out))
    assert results[0] == results[1]
    assert "0x6092" in {o["index"] for o in results[0]["objects"]}
    # device 0 is the boot device (9 objects, no factor group): refused, not a table nobody can write
    code, _, err = run(capsys, "scale", "compute", spec, "--esi", esi, "--device", "0", "--json")
    assert code == 1 and "none of the scaling objects that set user units" in err


@pytest.mark.parametrize("mechanics, meant", [
    ("transmission: {type: ballscrew, pitch: 5}", "pitch 5 has no unit: a length needs one (did you mean 5 mm?)"),
    ("transmission: {type: belt, diameter: 30.5}", "diameter 30.5 has no unit: a length needs one (did you mean 30.5 mm?)"),
    ("transmission: {type: rack, teeth: 20, module: 2}", "module 2 has no unit"),
    ("transmission: {type: linear_motor, pole_pitch: 32}", "pole_pitch 32 has no unit"),
    ("transmission: 'ballscrew pitch=5'", "pitch 5 has no unit"),
    # on an inch axis a bare number was silently millimetres (25/127 inch): the guess is the axis's own unit
    ("transmission: {type: ballscrew, pitch: 0.2}\nunits: {position: inch}", "(did you mean 0.2 inch?)"),
])
def test_a_length_without_a_unit_is_a_located_error(capsys, tmp_path: Path, mechanics: str, meant: str) -> None:
    spec = tmp_path / "axis.yaml"
    spec.write_text(f"feedback: {{counts_per_rev: 2000}}\n{mechanics}\n")
    code, out, err = run(capsys, "scale", "compute", str(spec))
    assert code == 1 and out == "" and f"{spec}:2:" in err and meant in err, err
    assert len(err.strip().splitlines()) == 1


def test_the_mechanics_option_needs_units_too(capsys) -> None:
    code, _, err = run(capsys, "scale", "compute", "--counts", "2000", "--transmission", "ballscrew pitch=5",
                       "--position", "inch")
    assert code == 2 and "'--transmission'" in err and "pitch 5 has no unit" in err and "5 inch" in err, err
    code, out, err = run(capsys, "scale", "compute", "--counts", "2000", "--transmission", "ballscrew pitch=5mm")
    assert code == 0, err


def test_an_unknown_spec_key_names_the_nearest(capsys, tmp_path: Path) -> None:
    spec = tmp_path / "axis.yaml"
    spec.write_text("feedback: {counts_per_rev: 2000}\ntransmision: {type: ballscrew, pitch: 5 mm}\n")
    code, _, err = run(capsys, "scale", "compute", str(spec))
    assert code == 1 and "unknown key 'transmision' (did you mean 'transmission'?)" in err, err
