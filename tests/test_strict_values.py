"""Counts a file gives have domain limits, a boolean is never a number, integers fit the object they go to, and
no input ends in a traceback (issues 28.2, 28.3, 23.2): the cases the issues name, each a located error."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from tests.conftest import ROOT, run

TS_PROJECT = ROOT / "samples" / "technosoft_ipos" / "project.yaml"


def _one_error(err: str) -> str:
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("ecattool: error: "), err
    return lines[0]


def _error_on(capsys: pytest.CaptureFixture[str], path: Path, text: str, *argv: str) -> str:
    """Write ``text`` to ``path``, run ``argv`` ({f} = the path): exit 1 and the one error line, which it returns."""
    path.write_text(text)
    code, _, err = run(capsys, *(a.replace("{f}", str(path)) for a in argv))
    line = _one_error(err)
    assert code == 1, line
    return line


@pytest.mark.parametrize(("steps", "words"), [
    ("- cycles: 1099511627776\n", "cycle count 1099511627776 is out of range 0..100000"),
    ("- state: PREOP\n- cycles: -5\n", "cycle count -5 is out of range"),
    ("- cycles: true\n", "cycle count must be a number, not true"),
    ("- foe: FOESW_X.bin\n  data: zz\n", "foe data must be hex bytes"),
    ("- write: '6040:00'\n  data: 'zz'\n", "data must be hex bytes"),
    ("- exchange: 'nothex'\n", "exchange needs the output image as hex bytes"),
    ("- foe: FOESW_X.bin\n  data: '00'\n  password: 4294967296\n", "FoE password 4294967296 is out of range"),
])
def test_sim_script_counts_and_data_are_checked_where_read(capsys: pytest.CaptureFixture[str], tmp_path: Path,
                                                           steps: str, words: str) -> None:
    line = _error_on(capsys, tmp_path / "s.yaml", steps, "sim", "run", "technosoft-ipos", "{f}")
    assert words in line and re.search(r"s\.yaml:\d+:\d+: ", line), line


@pytest.mark.parametrize("size", ["0", "-128", "0x10000000000", "100"])
def test_sii_build_size_is_checked_as_an_option(capsys: pytest.CaptureFixture[str], tmp_path: Path, size: str) -> None:
    code, _, err = run(capsys, "sii", "build", str(ROOT / "samples" / "sii" / "custom_slave.xml"), "--size", size,
                       "-o", str(tmp_path / "x.bin"))
    assert code == 2 and "--size" in err and "multiple of 128" in err and "Traceback" not in err
    assert not (tmp_path / "x.bin").exists()


@pytest.mark.parametrize(("spec", "words"), [
    ("blocks:\n  - start: 0xFFFFFFFF\n    words: [1]\n", "block start 0xFFFFFFFF is outside"),
    ("blocks:\n  - start: 0xFFFFFFFF\n    cam: {step: 64, points: [0, 1000]}\n", "block start 0xFFFFFFFF is outside"),
    ("blocks:\n  - start: 0xFFFE\n    cam: {step: 64, points: [0, 1000, 4000]}\n", "does not fit 0x0000..0xFFFF"),
    ("blocks:\n  - start: -1\n    words: [1]\n", "block start -1 is negative"),
    ("blocks:\n  - start: true\n    words: [1]\n", "expected a block start, not true"),
    ("base: " + "a" * 300 + ".sw\n", "cannot use file name"),
])
def test_sw_build_spec_values_are_located(capsys: pytest.CaptureFixture[str], tmp_path: Path, spec: str,
                                          words: str) -> None:
    line = _error_on(capsys, tmp_path / "b.yaml", spec, "sw", "build", "{f}", "-o", str(tmp_path / "out.sw"))
    assert words in line and re.search(r"b\.yaml:\d+:\d+: ", line), line


@pytest.mark.parametrize(("args", "words"), [
    (["6093:01=4294967296", "6093:02=1"], "0x6093:01 = 4294967296 does not fit its type UDINT"),
    (["6093:01=-1", "6093:02=1"], "0x6093:01 = -1 does not fit its type UDINT"),
    (["6093:01=1", "6093:02=1", "--counts-per-rev", "0"], "counts per revolution 0 is out of range"),
])
def test_scale_explain_values_fit_their_objects(capsys: pytest.CaptureFixture[str], args: list[str],
                                                words: str) -> None:
    code, _, err = run(capsys, "scale", "explain", "--family", "technosoft-ipos", *args)
    assert code == 1 and words in _one_error(err)


def test_scale_si_word_is_unsigned32(capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = run(capsys, "scale", "si", "0x1FD010100")
    assert code == 1 and "does not fit UNSIGNED32" in _one_error(err)
    assert run(capsys, "scale", "si", "0xFD010100")[0] == 0


def _edited_project(tmp_path: Path, old: str, new: str) -> Path:
    """The Technosoft sample project (and its .sw) in ``tmp_path``, with ``old`` replaced by ``new``."""
    for f in (TS_PROJECT.parent).iterdir():
        (tmp_path / f.name).write_bytes(f.read_bytes())
    project = tmp_path / "project.yaml"
    text = project.read_text()
    assert old in text
    project.write_text(text.replace(old, new))
    return project


@pytest.mark.parametrize(("old", "new", "words"), [
    ("feedback: {lines: 500, on: motor}", "feedback: {counts_per_rev: true, on: motor}",
     "counts_per_rev must be a number, not true"),
    ("value: 50, comment", "value: true, comment", "true is a boolean, not a value of UDINT"),
    ("value: 50, comment", "value: [300, 1], comment", "a list value is bytes: each item an integer 0..255"),
    ("pitch: 5 mm", "pitch: 1.0e999 mm", "out of range"),
])
def test_a_boolean_is_never_a_number_in_a_project(capsys: pytest.CaptureFixture[str], tmp_path: Path, old: str,
                                                  new: str, words: str) -> None:
    project = _edited_project(tmp_path, old, new)
    line = next(i for i, ln in enumerate(project.read_text().splitlines(), 1) if new.split(",")[0] in ln)
    code, out, err = run(capsys, "lint", str(project))
    assert code == 1 and words in out and f"project.yaml:{line}:" in out, out + err


@pytest.mark.parametrize(("old", "new", "words"), [
    ("move: {distance: 1000, mode: pp}", "move: {distance: .inf, mode: pp}", "finite number"),
    ("move: {distance: 1000, mode: pp}", "move: {distance: 1e999, mode: pp}", "finite number"),
    ("move: {distance: 1000, mode: pp}", "move: {distance: true, mode: pp}", "true is a boolean"),
    ("identity: {revision: exact}", "identity: {revision: exact}\n    position: true", "true is a boolean"),
    ("identity: {revision: exact}", "identity: {revision: exact}\n    dc: {opmode: DC, cycle_ns: 18446744073709551616}",
     "less than or equal to 4294967295"),
    ("identity: {revision: exact}", "identity: {revision: exact}\n    dc: {assign_activate: 0x1FFFFFFFF, cycle_ns: 1000000}",
     "does not fit 16 bits"),
])
def test_project_numbers_are_finite_typed_and_bounded(capsys: pytest.CaptureFixture[str], tmp_path: Path, old: str,
                                                      new: str, words: str) -> None:
    """The move distance, bus position and DC values: formerly an OverflowError in commission or startup export."""
    project = _edited_project(tmp_path, old, new)
    for argv in (["lint", str(project)], ["commission", str(project)],
                 ["startup", "export", "--project", str(project), "--format", "eni"]):
        code, out, err = run(capsys, *argv)
        assert code == 1 and "Traceback" not in out + err and words in out + err, (argv, out, err)
        assert re.search(r"project\.yaml:\d+:\d+: ", out + err), (argv, out, err)


def test_parse_int_refuses_booleans() -> None:
    from ecattool.errors import InputError
    from ecattool.od.numbers import parse_int
    from ecattool.od.types import lookup

    with pytest.raises(InputError, match="not true"):
        parse_int(True, what="count")
    dt = lookup("UNSIGNED16")
    assert dt is not None
    with pytest.raises(InputError, match="boolean"):
        dt.encode(True)
    boolean = lookup("BOOLEAN")
    assert boolean is not None and boolean.encode(True) == b"\x01"  # a BOOLEAN object takes true/false


def test_xml_syntax_error_is_one_line(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    bad = tmp_path / "bad.xml"
    bad.write_bytes(b"<EtherCATInfo>\n<![CDATA[ raw text \n second line\n")
    code, _, err = run(capsys, "esi", "devices", str(bad))
    line = _one_error(err)
    assert code == 1 and line.startswith(f"ecattool: error: {bad}:") and "not well-formed XML" in line


def test_pdo_program_overflow_is_located(capsys: pytest.CaptureFixture[str]) -> None:
    """map sdo --force prints even a mapping with errors: 300 entries cannot be counted in one byte."""
    entries = ",".join(["0x6040:00/1"] * 300)
    code, _, err = run(capsys, "map", "sdo", "--profile", "technosoft-ipos", "--rx", f"0x1600={entries}", "--force")
    assert code == 1 and "300 does not fit 1 byte(s)" in _one_error(err)


def test_huge_pdo_bit_length_is_located(capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = run(capsys, "map", "check", "--profile", "technosoft-ipos", "--rx", "0x1600=0x607A:00/" + "9" * 5000)
    assert code == 1 and "(5000 digits)" in _one_error(err)


def test_scaling_exact_reports_huge_ratios_without_overflow() -> None:
    """A ratio too large for a float is still reported (formerly an OverflowError from float())."""
    from fractions import Fraction

    from ecattool.errors import EcatToolError
    from ecattool.scaling.exact import approximate

    with pytest.raises(EcatToolError, match=r"~1e400 is out of reach"):
        approximate(Fraction(10) ** 400)


@pytest.mark.parametrize(("text", "words"), [
    ("family: technosoft-ipos\nfirmware: F515I\nfeedback: {lines: 500}\nunits: {position: rev, time: e99999999}\n",
     "units time must be a time unit"),
    ("feedback: {lines: 500}\nvl_setpoint: 1e99999999\n", "exponent beyond"),
    ("feedback: {lines: 500}\nslow_loop: 1e99999999 ms\n", "exponent beyond"),
])
def test_exponents_are_refused_before_they_are_made_exact(capsys: pytest.CaptureFixture[str], tmp_path: Path,
                                                          text: str, words: str) -> None:
    """Fraction('1e99999999') computes a 100-million-digit integer: such a value is refused where it is read."""
    line = _error_on(capsys, tmp_path / "e.yaml", text, "scale", "compute", "{f}")
    assert words in line and re.search(r"e\.yaml:\d+:\d+: ", line), line


@pytest.mark.parametrize(("text", "words"), [
    ("[" * 100000 + "]" * 100000, "deep.json"),
    ('{"objects": [{"index": 1}], "factor_set": 1}', "objects[0] of a `scale compute --json` file needs"),
    ('{"objects": [5], "factor_set": 1}', "objects[0] of a `scale compute --json` file needs"),
    ('{"objects": [{"index": "0x6093", "subindex": true, "value": 1}], "factor_set": 1}', "not true"),
])
def test_scale_explain_from_a_malformed_file_is_one_line(capsys: pytest.CaptureFixture[str], tmp_path: Path,
                                                         text: str, words: str) -> None:
    """Deep nesting (RecursionError), objects without their keys (KeyError) or not mappings (TypeError)."""
    assert words in _error_on(capsys, tmp_path / "deep.json", text, "scale", "explain", "--from", "{f}")
