import json
from pathlib import Path

import pytest

from ecattool.errors import InputError
from ecattool.findings import Finding, Severity
from ecattool.errors import Location
from ecattool.project import report
from ecattool.project.loader import load_project, parse_project
from ecattool.project.model import json_schema

ROOT = Path(__file__).resolve().parents[2]

GOOD = """\
ecattool: 1
name: test
drives:
  - name: x
    device: {profile: technosoft-ipos}
    parameters:
      - {object: 6060:00, value: 1}
"""


def test_valid_project_loads(tmp_path):
    p = tmp_path / "p.yaml"
    p.write_text(GOOD)
    lp = load_project(p)
    assert lp.project.drives[0].device.profile == "technosoft-ipos"
    # YAML 1.1 would read 6060:00 as the base-60 number 363600; ecattool keeps the address
    assert lp.project.drives[0].parameters[0].object == "6060:00"
    assert lp.drive_location(0, "parameters", 0, "value").line == 7


def test_unknown_field_is_located():
    text = GOOD.replace("    parameters:", "    paramters:")
    project, doc, findings = parse_project(text, "p.yaml")
    assert project is None
    assert findings[0].rule == "PRJ001"
    assert "unknown field 'paramters'" in findings[0].message
    assert (findings[0].location.line, findings[0].location.column) == (6, 5)


def test_wrong_value_is_located_at_the_value():
    text = GOOD.replace("  - name: x\n", "  - name: x\n    position: -3\n")
    _, _, findings = parse_project(text, "p.yaml")
    assert findings and findings[0].location.line == 5 and findings[0].location.column == 15


def test_device_needs_exactly_one_source():
    text = GOOD.replace("{profile: technosoft-ipos}", "{profile: hdt, esi: x.xml}")
    _, _, findings = parse_project(text, "p.yaml")
    assert "exactly one of" in findings[0].message and findings[0].location.line == 5


def test_yaml_syntax_error_is_one_located_error(tmp_path):
    p = tmp_path / "bad.yaml"
    p.write_text("ecattool: 1\ndrives: [\n")
    with pytest.raises(InputError) as ei:
        load_project(p)
    assert str(ei.value).startswith(f"{p}:")


@pytest.mark.parametrize("text,msg", [("drives: []\n", "missing 'ecattool: 1'"), ("ecattool: 7\ndrives: []\n", "unsupported")])
def test_version_checks(tmp_path, text, msg):
    p = tmp_path / "v.yaml"
    p.write_text(text)
    with pytest.raises(InputError, match=msg):
        load_project(p)


def test_duplicate_keys_refused(tmp_path):
    p = tmp_path / "d.yaml"
    p.write_text("ecattool: 1\nname: a\nname: b\ndrives: []\n")
    with pytest.raises(InputError, match="duplicate key 'name'") as ei:
        load_project(p)
    assert ei.value.location.line == 3


def test_the_schemas_scaling_is_the_scaling_specs_model_and_its_reader_validates_it(tmp_path: Path) -> None:
    """issue 36: the project schema's scaling: is typed from scaling's own model (its keys, no others), and the
    file has one validator for it: an unknown key is the spec reader's PRJ050 at its line with the nearest key
    named (as for a spec file), not a schema error."""
    from ecattool.project.machine import load_machine
    from ecattool.scaling.model import SPEC_KEYS

    schema = json_schema()
    ref = schema["$defs"]["Drive"]["properties"]["scaling"]["anyOf"][0]["$ref"].rsplit("/", 1)[1]
    section = schema["$defs"][ref]
    assert set(section["properties"]) == SPEC_KEYS and section["additionalProperties"] is False
    text = (ROOT / "samples" / "hdt" / "project.yaml").read_text()
    assert "      transmission: {type: rotary}\n" in text
    path = tmp_path / "project.yaml"
    path.write_text(text.replace("      transmission:", "      transmision:"))
    (f,) = load_machine(path).findings
    assert (f.rule, f.location.line if f.location else None) == ("PRJ050", 13), f
    assert "transmision" in f.message and "'transmission'" in f.message
    # what the schema's type says stays the schema's: a section that is no mapping is PRJ001, as before
    import re

    path.write_text(re.sub(r"    scaling:\n(      .*\n)+", "    scaling: 5\n", text))
    (f,) = load_machine(path).findings
    assert (f.rule, f.message) == ("PRJ001", "drives.0.scaling: Input should be a valid dictionary"), f


def test_a_project_without_scaling_does_not_import_the_scaling_package(tmp_path: Path) -> None:
    """The schema's scaling: comes from scaling's model when the schema is generated; reading and linting a
    project imports the scaling package only where a drive has a scaling: section (bench_lint's warm run)."""
    import subprocess
    import sys

    path = tmp_path / "project.yaml"
    path.write_text("ecattool: 1\ndrives:\n  - name: a\n    device: {profile: hdt, product: tomcat}\n")
    code = ("import sys\nfrom ecattool.project.machine import load_machine\n"
            f"assert load_machine({str(path)!r}).findings == ()\nprint('ecattool.scaling' in sys.modules)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert done.returncode == 0 and done.stdout.strip() == "False", done.stderr


def test_checked_in_schema_has_not_drifted():
    checked_in = json.loads((ROOT / "schemas" / "project.schema.json").read_text())
    assert checked_in == json.loads(json.dumps(json_schema()))


def _findings():
    return [
        Finding("PRJ010", Severity.ERROR, "object 0x1234 does not exist", Location("a/p.yaml", 7, 9)),
        Finding("PDO011", Severity.WARNING, "mapped twice, 50% of it", Location("a/p.yaml", 9)),
        Finding("PRJ005", Severity.INFO, "note without line", None),
    ]


def test_sarif_is_valid_2_1_0_shape():
    s = report.to_sarif(_findings())
    assert s["version"] == "2.1.0"
    run = s["runs"][0]
    ids = [r["id"] for r in run["tool"]["driver"]["rules"]]
    assert ids == sorted(set(ids))
    res = run["results"]
    assert [r["level"] for r in res] == ["error", "warning", "note"]
    loc = res[0]["locations"][0]["physicalLocation"]
    assert loc["artifactLocation"]["uri"] == "a/p.yaml" and loc["region"] == {"startLine": 7, "startColumn": 9}
    assert "locations" not in res[2]
    for r in res:
        assert ids[r["ruleIndex"]] == r["ruleId"]


def test_github_annotations_escape():
    out = report.to_github(_findings()).splitlines()
    assert out[0] == "::error file=a/p.yaml,line=7,col=9,title=PRJ010::object 0x1234 does not exist"
    assert out[1].startswith("::warning file=a/p.yaml,line=9,title=PDO011::mapped twice, 50%25 of it")
    assert out[2] == "::notice title=PRJ005::note without line"


@pytest.mark.parametrize("data", [b"ecattool: 1\x00\ndrives: []\n", b"\xff\xfe\x00garbage", "ecattool: 1\x07\n".encode()])
def test_non_printable_input_is_a_located_error(tmp_path, data):
    p = tmp_path / "np.yaml"
    p.write_bytes(data)
    with pytest.raises(InputError) as ei:
        load_project(p)
    assert str(ei.value).startswith(str(p)) and "\n" not in str(ei.value)


from hypothesis import given, strategies as st  # noqa: E402


@given(st.binary(max_size=200))
def test_random_bytes_never_crash_the_loader(data):
    try:
        parse_project(data, "fuzz.yaml")
    except InputError:
        pass


def test_an_unknown_yaml_tag_is_one_located_line(tmp_path):
    """PyYAML's constructor message repeats the position on a second line; the error stays one line."""
    from ecattool.errors import InputError
    from ecattool.yamlloc import load_yaml

    with pytest.raises(InputError) as exc:
        load_yaml(b"ecattool: 1\ndrives:\n  - name: !!python/object:os.system a\n", "t.yaml")
    assert "\n" not in exc.value.message and "python/object:os.system" in exc.value.message
    assert (exc.value.location.line, exc.value.location.column) == (3, 11)


TWO_DRIVES = """\
ecattool: 1
drives:
  - name: x
    device: {profile: technosoft-ipos}
    paramters:
      - {object: 6060:00, value: 8}
  - name: y
    device: {profile: technosoft-ipos}
    parameters:
      - {object: 0x5FFF:00, value: 8}
"""


def test_unknown_key_names_the_nearest_known_key():
    _, _, findings = parse_project(TWO_DRIVES, "p.yaml")
    assert [f.message for f in findings] == \
        ["drives.0.paramters: unknown field 'paramters' (did you mean 'parameters'?)"]
    _, _, findings = parse_project(GOOD.replace("{profile: technosoft-ipos}", "{profile: technosoft-ipos, revison: F515K}"), "p.yaml")
    assert "(did you mean 'revision'?)" in findings[0].message
    _, _, findings = parse_project(GOOD.replace("name: test", "nmae: test"), "p.yaml")
    assert "(did you mean 'name'?)" in findings[0].message
    # nothing near: no guess
    _, _, findings = parse_project(GOOD.replace("name: test", "zzzzzz: test"), "p.yaml")
    assert "did you mean" not in findings[0].message


def test_a_schema_error_in_one_drive_does_not_hide_the_others(tmp_path):
    from ecattool.project.machine import load_machine

    p = tmp_path / "p.yaml"
    p.write_text(TWO_DRIVES)
    result = load_machine(p)
    got = [(f.rule, f.location.line) for f in result.findings]
    # the typo in drive x (line 5), and drive y's own finding, located in the file as written (line 10)
    assert ("PRJ001", 5) in got and ("PRJ010", 10) in got, got
    # a file with a schema error is never loaded for use, however many drives are well-formed
    with pytest.raises(InputError, match="paramters"):
        load_project(p)
