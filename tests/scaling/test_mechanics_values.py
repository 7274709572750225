"""Zero, negative and absurd numbers: in every mechanics field and every numeric CLI option, exit 1 or 2 with a
located message, never a traceback (issues 23.2 and 28.3; docs/scaling.md, "Limits").

Mechanics fields go through every command that reads them (scale compute, lint, commission, startup export); the
values are drawn by hypothesis from zero, negative, huge, non-finite, malformed and boolean ones.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.conftest import ROOT, corpus_path
from tests.safe.fuzz_readers import invoke

#: a base spec (feedback, transmission) per mechanics field, with {v} where the hostile value goes
FIELDS: dict[str, str] = {
    "counts_per_rev": "feedback: {{counts_per_rev: {v}}}\ntransmission: {{type: ballscrew, pitch: 5 mm}}",
    "lines": "feedback: {{lines: {v}}}\ntransmission: {{type: ballscrew, pitch: 5 mm}}",
    "steps": "feedback: {{steps: {v}, microsteps: 16}}\ntransmission: {{type: ballscrew, pitch: 5 mm}}",
    "microsteps": "feedback: {{steps: 200, microsteps: {v}}}\ntransmission: {{type: ballscrew, pitch: 5 mm}}",
    "resolution": "feedback: {{resolution: {v}}}\ntransmission: {{type: ballscrew, pitch: 5 mm}}",
    "gear motor": "feedback: {{lines: 500}}\ngear: {{motor: {v}, load: 1}}\ntransmission: {{type: ballscrew, pitch: 5 mm}}",
    "gear load": "feedback: {{lines: 500}}\ngear: {{motor: 3, load: {v}}}\ntransmission: {{type: ballscrew, pitch: 5 mm}}",
    "gear ratio": "feedback: {{lines: 500}}\ngear: '{v}:1'\ntransmission: {{type: ballscrew, pitch: 5 mm}}",
    "ballscrew pitch": "feedback: {{lines: 500}}\ntransmission: {{type: ballscrew, pitch: {v}}}",
    "hollow shaft pitch": "feedback: {{lines: 500}}\ntransmission: {{type: hollow_shaft, pitch: {v}}}",
    "belt diameter": "feedback: {{lines: 500}}\ntransmission: {{type: belt, diameter: {v}}}",
    "belt teeth": "feedback: {{lines: 500}}\ntransmission: {{type: belt, teeth: {v}, tooth_pitch: 5 mm}}",
    "belt tooth pitch": "feedback: {{lines: 500}}\ntransmission: {{type: belt, teeth: 20, tooth_pitch: {v}}}",
    "rack module": "feedback: {{lines: 500}}\ntransmission: {{type: rack, teeth: 20, module: {v}}}",
    "rack pitch diameter": "feedback: {{lines: 500}}\ntransmission: {{type: rack, pitch_diameter: {v}}}",
    "linear motor pole pitch": "feedback: {{counts_per_rev: 4096}}\ntransmission: {{type: linear_motor, pole_pitch: {v}}}",
    "rotary driving teeth": "feedback: {{lines: 500}}\ntransmission: {{type: rotary, driving_teeth: {v}, driven_teeth: 60}}",
    "rotary driven diameter": "feedback: {{lines: 500}}\ntransmission: {{type: rotary, driving_diameter: 20 mm, "
                              "driven_diameter: {v}}}",
    "label units": "feedback: {{lines: 500}}\ntransmission: {{type: label, name: bottle, units: {v}, motor_revs: 1}}",
    "label motor revs": "feedback: {{lines: 500}}\ntransmission: {{type: label, name: bottle, units: 10, motor_revs: {v}}}",
    "slow loop": "feedback: {{lines: 500}}\ntransmission: {{type: ballscrew, pitch: 5 mm}}\nslow_loop: {v}",
}
UNITS = {"label units": "bottle", "label motor revs": "bottle", "rotary driving teeth": "deg",
         "rotary driven diameter": "deg"}

#: hostile values as they would be written in YAML (a length field gets them with and without a unit)
HOSTILE = ("0", "-1", "-5", "0.0", "1e999", "1.0e999", "-1e999", "1e-999", "1e99999999", ".inf", ".nan", "true",
           "false", "99999999999999999999999999999999999999", "0x", "1/0", "'0 mm'", "'-5 mm'", "'1e999 mm'",
           "'0 ms'", "'1e999 ms'", "'99999999999999999999 mm'", "'0.000000000000000000001 mm'")

COMMANDS = ("scale compute", "lint", "startup export", "commission")


@pytest.fixture(scope="module")
def work(tmp_path_factory: pytest.TempPathFactory) -> Path:
    w = tmp_path_factory.mktemp("mechanics")
    shutil.copytree(ROOT / "samples", w / "samples")
    return w


@pytest.fixture(autouse=True)
def _own_cache(monkeypatch: pytest.MonkeyPatch, tmp_path_factory: pytest.TempPathFactory) -> None:
    monkeypatch.setenv("ECATTOOL_CACHE_DIR", str(tmp_path_factory.getbasetemp() / "mechanics-cache"))


def _project(work: Path, scaling: str) -> Path:
    """The Technosoft sample project with its scaling block replaced (its .sw image beside it)."""
    p = work / "samples" / "technosoft_ipos" / "hostile.yaml"
    text = (ROOT / "samples" / "technosoft_ipos" / "project.yaml").read_text()
    start, end = text.index("    scaling:\n"), text.index("    parameters:\n")
    block = "    scaling:\n" + "".join(f"      {ln}\n" for ln in scaling.splitlines())
    p.write_text(text[:start] + block + text[end:])
    return p


def _located(line: str, name: str) -> bool:
    return re.search(rf"{re.escape(name)}:\d+(:\d+)?: ", line) is not None


@pytest.mark.parametrize("field", sorted(FIELDS))
def test_hostile_mechanics_value_is_a_located_error_everywhere(field: str, work: Path) -> None:
    @settings(max_examples=6, deadline=None, derandomize=True, database=None, suppress_health_check=list(HealthCheck))
    @given(value=st.sampled_from(HOSTILE), command=st.sampled_from(COMMANDS))
    def run(value: str, command: str) -> None:
        unit = UNITS.get(field, "mm")
        scaling = FIELDS[field].format(v=value) + f"\nunits: {{position: {unit}}}"
        if command == "scale compute":
            spec = work / "hostile-spec.yaml"
            spec.write_text(scaling + "\n")
            code, out, err, escaped = invoke(["scale", "compute", str(spec)])
            name = spec.name
        else:
            project = _project(work, scaling)
            argv = {"lint": ["lint", str(project)], "commission": ["commission", str(project)],
                    "startup export": ["startup", "export", "--project", str(project), "--format", "json"]}[command]
            code, out, err, escaped = invoke(argv)
            name = project.name
        where = f"{command} with {field} = {value}"
        assert escaped is None, f"{where}: raw {type(escaped).__name__}: {escaped}"
        assert "Traceback" not in out + err, where
        if code == 0:  # a value that is valid after all (e.g. a small but real length): fine
            return
        assert code == 1, f"{where}: exit {code}: {err}"
        lines = [ln for ln in err.splitlines() if ln.strip()]
        if command in ("lint", "commission"):  # the finding in the report, located
            assert len(lines) == 0 and _located(out, name), f"{where}: {out[-800:]}"
        else:
            assert len(lines) == 1 and _located(lines[0], name), f"{where}: {err}"

    run()


@pytest.mark.parametrize("field", ["ballscrew pitch", "belt diameter", "rack module", "linear motor pole pitch",
                                   "counts_per_rev", "slow loop"])
def test_zero_is_refused_where_it_is_written(field: str, work: Path) -> None:
    """The 23.2 cases: a zero length (or count, or period) is an error at its own line, in every command."""
    value = {"counts_per_rev": "0", "slow loop": "0 ms"}.get(field, "0 mm")
    scaling = FIELDS[field].format(v=value) + "\nunits: {position: mm}"
    project = _project(work, scaling)
    line = next(i for i, ln in enumerate(project.read_text().splitlines(), 1)
                if f": {value}}}" in ln or f": {value}," in ln or ln.rstrip().endswith(f": {value}"))
    for argv in (["lint", str(project)], ["commission", str(project)],
                 ["startup", "export", "--project", str(project), "--format", "json"]):
        code, out, err, escaped = invoke(argv)
        assert escaped is None and code == 1 and "Traceback" not in out + err, (argv, err)
        assert f"{project.name}:{line}:" in out + err and "positive" in out + err, (argv, out, err)
    spec = work / "zero.yaml"
    spec.write_text(scaling + "\n")
    code, _, err, escaped = invoke(["scale", "compute", str(spec)])
    assert escaped is None and code == 1 and re.match(rf"ecattool: error: .*zero.yaml:\d+:\d+: .*positive", err), err


def test_lint_writes_its_sarif_report_when_mechanics_are_wrong(work: Path) -> None:
    project = _project(work, FIELDS["ballscrew pitch"].format(v="0 mm") + "\nunits: {position: mm}")
    sarif = work / "lint.sarif"
    code, _, err, escaped = invoke(["lint", str(project), "--format", "sarif", "-o", str(sarif), "--force"])
    assert escaped is None and code == 1, err
    assert "must be positive" in sarif.read_text()


# ------------------------------------------------------------------------------------------- CLI options
SW = "sw/ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.sw"


def _option_cases() -> list[tuple[str, list[str]]]:
    """Every numeric option or argument, in a valid invocation, with {v} for the value."""
    sw = str(corpus_path(*SW.split("/")))
    params = str(corpus_path("sw", "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.ems_parameters.cfg"))
    sii = str(corpus_path("sii", "ni9144.bin"))
    ros2 = str(corpus_path("configs", "ros2_technosoft_ipos3604.yaml"))
    ecmc = str(corpus_path("configs", "ecmc_ecmciPOSXXXX.cmd"))
    mech = ["--counts", "10000", "--transmission", "ballscrew pitch=5mm", "--position", "mm"]
    cases: list[tuple[str, list[str]]] = []
    for cmd in ("compute", "startup"):
        fmt = ["--format", "json"] if cmd == "startup" else []
        cases += [
            (f"scale {cmd} --counts", ["scale", cmd, *fmt, "--counts", "{v}", "--position", "rev"]),
            (f"scale {cmd} --lines", ["scale", cmd, *fmt, "--lines", "{v}", "--position", "rev"]),
            (f"scale {cmd} --steps", ["scale", cmd, *fmt, "--steps", "{v}x16", "--position", "rev"]),
            (f"scale {cmd} --steps micro", ["scale", cmd, *fmt, "--steps", "200x{v}", "--position", "rev"]),
            (f"scale {cmd} --gear", ["scale", cmd, *fmt, *mech, "--gear", "{v}:1"]),
            (f"scale {cmd} --transmission pitch", ["scale", cmd, *fmt, "--counts", "10000", "--position", "mm",
                                                   "--transmission", "ballscrew pitch={v}mm"]),
            (f"scale {cmd} --transmission teeth", ["scale", cmd, *fmt, "--counts", "10000", "--position", "mm",
                                                   "--transmission", "belt teeth={v} tooth_pitch=5mm"]),
            (f"scale {cmd} --slow-loop", ["scale", cmd, *fmt, *mech, "--slow-loop", "{v}ms"]),
        ]
    cases += [
        ("scale explain value", ["scale", "explain", "6093:01={v}", "6093:02=1"]),
        ("scale explain --counts-per-rev", ["scale", "explain", "6093:01=1", "6093:02=1", "--counts-per-rev", "{v}"]),
        ("scale explain --slow-loop", ["scale", "explain", "6094:01=1", "6094:02=1", "--slow-loop", "{v}ms"]),
        ("scale explain --slave", ["scale", "explain", "--target", "sim", "--slave", "{v}"]),
        ("scale si", ["scale", "si", "{v}"]),
        ("sii build --size", ["sii", "build", str(ROOT / "samples" / "sii" / "custom_slave.xml"), "--size", "{v}",
                              "-o", "{o}", "--force"]),
        ("sii set-alias", ["sii", "set-alias", sii, "{v}", "-o", "{o}", "--force"]),
        ("map check --slave", ["map", "check", "--profile", "technosoft-ipos", "--product", "ipos4808-bx-cat",
                               "--startup", ecmc, "--slave", "{v}"]),
        ("startup convert --sync0-cycle", ["startup", "convert", ros2, "--format", "eni", "-o", "{o}", "--force",
                                           "--sync0-cycle", "{v}"]),
        ("startup export --sync0-cycle", ["startup", "export", "--from", ros2, "--format", "eni", "--sync0-cycle",
                                          "{v}"]),
        ("sw verify --slave", ["sw", "verify", sw, "--preload", sw, "--slave", "{v}"]),
        ("sw patch --set", ["sw", "patch", sw, "-p", params, "--set", "PWMPER={v}", "-o", "{o}", "--force"]),
    ]
    return cases


OPTION_CASES = _option_cases()
NUMBERS = ("0", "-1", "-5", "1e99999999", "4294967296", "18446744073709551616", "99999999999999999999999999999999999", "1e999",
           "0x", "0x1FD010100", "true", "-0", "1/0", "9" * 5000)


@pytest.mark.parametrize(("name", "argv"), OPTION_CASES, ids=[c[0] for c in OPTION_CASES])
def test_hostile_number_option_is_exit_1_or_2_with_a_message(name: str, argv: list[str], work: Path) -> None:
    @settings(max_examples=5, deadline=None, derandomize=True, database=None, suppress_health_check=list(HealthCheck))
    @given(value=st.sampled_from(NUMBERS))
    def run(value: str) -> None:
        args = [a.replace("{v}", value).replace("{o}", str(work / "option-output")) for a in argv]
        code, out, err, escaped = invoke(args)
        where = f"{name} = {value[:30]}"
        assert escaped is None, f"{where}: raw {type(escaped).__name__}: {escaped}"
        assert "Traceback" not in out + err, where
        assert code in (0, 1, 2), f"{where}: exit {code}"
        lines = [ln for ln in err.splitlines() if ln.strip()]
        if code == 1:
            assert len(lines) == 1 and lines[0].startswith("ecattool: error: "), f"{where}: {err}"
        elif code == 2:  # click's usage error: the last line says what is wrong
            assert lines and lines[-1].startswith("Error: "), f"{where}: {err}"

    run()
