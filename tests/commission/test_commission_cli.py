"""``ecattool commission``: the JSON report's shape, text output, -o, and exit codes 0/1/2."""

from __future__ import annotations

import json

from tests.project.project_helpers import SAMPLES, copy_sample, run, run_json, sample


def test_json_report_shape(capsys):
    code, doc = run_json(capsys, "commission", "--json", *(str(sample(n)) for n in SAMPLES))
    assert code == 0
    assert set(doc) == {"ok", "projects"} and doc["ok"] is True and len(doc["projects"]) == 4
    for proj, name in zip(doc["projects"], SAMPLES):
        assert set(proj) == {"project", "target", "ok", "drives"}
        assert proj["project"].endswith(f"{name}/project.yaml") and proj["target"] == "sim" and proj["ok"]
        for d in proj["drives"]:
            # "move": the figures of the move on the plant (issue 33), for every sample's axis
            assert set(d) == {"name", "position", "kind", "ok", "error", "final_state", "steps", "move"}
            assert {"following_error_max", "settling_time_s", "overshoot", "peak_speed"} <= set(d["move"])
            assert d["ok"] is True and d["error"] is None and d["final_state"] == "OP"
            for s in d["steps"]:
                assert {"name", "ok", "detail"} <= set(s) <= {"name", "ok", "detail", "abort_code", "al_status"}
                assert s["ok"] is True and isinstance(s["detail"], str)
    move = doc["projects"][0]["drives"][0]["steps"][-1]
    assert move["name"] == "move" and "= 1200 counts" in move["detail"]


def test_text_output_and_report_file(capsys, tmp_path):
    out = tmp_path / "report.json"
    code, text, _ = run(capsys, "commission", str(sample("hdt")), "-o", str(out))
    assert code == 0
    assert "drive table (position 0): OK" in text and "1 of 1 drive(s) commissioned" in text
    doc = json.loads(out.read_text())
    assert doc["ok"] is True and doc["projects"][0]["drives"][0]["name"] == "table"


def test_failed_drive_exits_1_with_the_failing_step(capsys, tmp_path):
    p = copy_sample("hdt", tmp_path)
    p.write_text(p.read_text().replace("value: 90, comment", "value: -1, comment"))  # 6081h is unsigned
    code, doc = run_json(capsys, "commission", "--json", str(p))
    assert code == 1 and doc["ok"] is False
    (d,) = doc["projects"][0]["drives"]
    assert d["ok"] is False and d["steps"][-1]["name"] == "lint" and "PRJ013" in d["error"]


def test_invalid_project_exits_1_with_one_located_line(capsys, tmp_path):
    p = tmp_path / "p.yaml"
    p.write_text("ecattool: 1\ndrives:\n  - name: x\n    device: {profile: hdt}\n    speed: 3\n")
    code, out, err = run(capsys, "commission", str(p))
    assert code == 1 and err.count("\n") == 1 and f"{p}:5" in err and "speed" in err


def test_usage_errors_exit_2(capsys):
    assert run(capsys, "commission")[0] == 2
    assert run(capsys, "commission", "--nope", str(sample("hdt")))[0] == 2


def test_unknown_target_is_an_error(capsys):
    code, _, err = run(capsys, "commission", "--target", "canbus:0", str(sample("hdt")))
    assert code == 1 and "unknown target 'canbus:0'" in err
