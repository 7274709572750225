"""Every input is bounded (issue 28.2 and 28.5; docs/cli.md, "Output files", last paragraph).

Each reader runs, in a child process limited to 512 MiB of address space (``RLIMIT_AS``), on

* a 270-byte YAML alias bomb (seven levels of nine aliases: 4.8 million values if expanded),
* ``/dev/zero`` (endless, and 0 bytes "on disk"), and standard input fed from it,
* a FIFO whose writer never stops,

and must end with exit status 1 and one located line (a checker: a located error finding in its report), without
a MemoryError or any other exception. The child's timeout is only a guard against a hang, never an assertion
on speed.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from tests.conftest import ROOT, corpus_path

LIMIT = 512 * 1024 * 1024

BOMB = """\
a: &a ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]
b: &b [*a,*a,*a,*a,*a,*a,*a,*a,*a]
c: &c [*b,*b,*b,*b,*b,*b,*b,*b,*b]
d: &d [*c,*c,*c,*c,*c,*c,*c,*c,*c]
e: &e [*d,*d,*d,*d,*d,*d,*d,*d,*d]
f: &f [*e,*e,*e,*e,*e,*e,*e,*e,*e]
g: &g [*f,*f,*f,*f,*f,*f,*f,*f,*f]
"""
#: a script is a list of steps: the same bomb as a list
BOMB_LIST = BOMB.replace("a: &a", "- &a").replace("b: &b", "- &b").replace("c: &c", "- &c").replace(
    "d: &d", "- &d").replace("e: &e", "- &e").replace("f: &f", "- &f").replace("g: &g", "- &g")

#: commands that read a YAML file ({f}); {o} is an output file
YAML_READERS: list[list[str]] = [
    ["lint", "{f}"],
    ["commission", "{f}"],
    ["scale", "compute", "{f}"],
    ["scale", "explain", "--from", "{f}"],
    ["sim", "run", "technosoft-ipos", "{f}"],
    ["sw", "build", "{f}", "-o", "{o}"],
    ["startup", "import", "{f}"],
    ["map", "check", "--profile", "technosoft-ipos", "--mapping", "{f}"],
]
#: commands that read other kinds of file (ESI, EDS, SII, .sw, FoE, parameters, schema, ENI)
OTHER_READERS: list[list[str]] = [
    ["esi", "devices", "{f}"],
    ["esi", "show", "{f}"],
    ["esi", "validate", "{f}"],
    ["sii", "info", "{f}"],
    ["sii", "check", "{f}"],
    ["sii", "build", "{f}", "-o", "{o}"],
    ["sw", "info", "{f}"],
    ["sw", "from-foe", "{f}", "-o", "{o}"],
    ["sw", "show", "{sw}", "-p", "{f}"],
    ["project", "schema", "--check", "{f}"],
    ["startup", "import", "--from-format", "eni", "{f}"],
    ["lint", "{project_esi}"],  # a project naming the file as its drive's ESI
    ["sw", "verify", "--project", "{project_sw}", "--preload", "{sw}"],  # ... and as its .sw image
]
#: commands reading standard input ('-')
STDIN_READERS: list[list[str]] = [
    ["esi", "devices", "-"],
    ["sii", "info", "-"],
    ["startup", "import", "-"],
    ["map", "check", "--profile", "technosoft-ipos", "--mapping", "-"],
    ["scale", "compute", "-"],
]

#: checkers report an unreadable input as an error finding on stdout (docs/cli.md, "Checkers report")
REPORTERS = {"lint", "commission", "sii check"}


def _fill(argv: list[str], f: str, tmp: Path, n: int) -> list[str]:
    project_esi = tmp / f"esi-{n}.yaml"
    project_esi.write_text("ecattool: 1\nname: m\ndrives:\n  - name: a\n    device:\n"
                           f"      esi: {f}\n")
    project_sw = tmp / f"sw-{n}.yaml"
    project_sw.write_text(f"ecattool: 1\nname: m\ndrives:\n  - name: y\n    device: {{profile: technosoft-ipos}}\n"
                          f"    sw: {f}\n")
    sw = str(corpus_path("sw", "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.sw"))
    return [a.format(f=f, o=tmp / f"out-{n}", sw=sw, project_esi=project_esi, project_sw=project_sw) for a in argv]


def _endless_writer(fifo: Path) -> threading.Thread:
    def write() -> None:
        try:
            fd = os.open(fifo, os.O_WRONLY)
        except OSError:
            return
        chunk = b"\0" * 65536
        try:
            while True:
                os.write(fd, chunk)
        except OSError:  # the reader stopped (EPIPE): what the test wants
            pass
        finally:
            os.close(fd)

    t = threading.Thread(target=write, daemon=True)
    t.start()
    return t


def _release(fifo: Path) -> None:
    """Let a writer whose FIFO was never opened by the command end (its open() blocks until a reader comes)."""
    try:
        fd = os.open(fifo, os.O_RDONLY | os.O_NONBLOCK)
        os.close(fd)
    except OSError:
        pass


def _run_child(cases: list[dict[str, object]], tmp: Path) -> list[dict[str, object]]:
    cases_path, result_path = tmp / "cases.json", tmp / "results.json"
    cases_path.write_text(json.dumps(cases))
    env = {**os.environ, "ECATTOOL_CACHE_DIR": str(tmp / "cache"), "PYTHONPATH": str(ROOT)}
    proc = subprocess.run([sys.executable, "-m", "tests.safe.bounded_child", str(LIMIT), str(cases_path), str(result_path)],
                          cwd=ROOT, env=env, capture_output=True, text=True, timeout=600)  # a hang guard only
    assert proc.returncode == 0, proc.stderr[-3000:]
    results: list[dict[str, object]] = json.loads(result_path.read_text())
    return results


def _check(argv: list[str], named: str, result: dict[str, object]) -> None:
    where = " ".join(argv)
    assert result["exception"] is None, f"{where}: {result['exception']}"
    out, err = str(result["stdout"]), str(result["stderr"])
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert result["code"] == 1, f"{where}: exit {result['code']}\nstdout: {out[-500:]}\nstderr: {err[-500:]}"
    assert "Traceback" not in out + err, where
    if " ".join(argv[:2]) in REPORTERS or argv[0] in REPORTERS:
        assert len(lines) <= 1 and named in out + err, f"{where}: the report does not name {named}:\n{out[-500:]}"
        return
    assert len(lines) == 1 and lines[0].startswith("ecattool: error:"), f"{where}: stderr is not one line:\n{err}"
    assert named in lines[0], f"{where}: the error does not name {named}: {lines[0]}"


@pytest.mark.parametrize("kind", ["alias-bomb", "dev-zero", "fifo"])
def test_every_reader_stops_on_endless_input_under_512_mib(tmp_path: Path, kind: str) -> None:
    readers = YAML_READERS if kind == "alias-bomb" else YAML_READERS + OTHER_READERS
    cases: list[dict[str, object]] = []
    named: list[str] = []
    fifos: list[Path] = []
    for n, argv in enumerate(readers):
        if kind == "alias-bomb":
            f = tmp_path / f"bomb-{n}.yaml"
            f.write_text(BOMB_LIST if argv[:2] == ["sim", "run"] else BOMB)
        elif kind == "dev-zero":
            f = Path("/dev/zero")
        else:
            f = tmp_path / f"fifo-{n}"
            os.mkfifo(f)
            fifos.append(f)
        cases.append({"argv": _fill(argv, str(f), tmp_path, n), "stdin": None})
        named.append(f.name if kind != "dev-zero" else "/dev/zero")
    if kind == "dev-zero":
        for argv in STDIN_READERS:
            cases.append({"argv": argv, "stdin": "/dev/zero"})
            named.append("<stdin>")
    writers = [_endless_writer(f) for f in fifos]
    try:
        results = _run_child(cases, tmp_path)
    finally:
        for f in fifos:
            _release(f)
        for w in writers:
            w.join(30)
    assert len(results) == len(cases)
    for case, name, result in zip(cases, named, results):
        _check(list(case["argv"]), name, result)  # type: ignore[call-overload]


#: counts a small file gives that would mean unbounded work: (command, file name, content)
HUGE_COUNTS: list[tuple[list[str], str, str]] = [
    (["sim", "run", "technosoft-ipos", "{f}"], "cycles.yaml", "- state: PREOP\n- cycles: 1099511627776\n"),
    (["scale", "compute", "{f}"], "spec.yaml",
     "feedback: {lines: 500}\ntransmission: {type: ballscrew, pitch: 1e99999999 mm}\n"),
    (["sw", "build", "{f}", "-o", "{o}"], "build.yaml", "blocks:\n  - start: 0xFFFFFFFF\n    words: [1]\n"),
    (["map", "check", "--profile", "technosoft-ipos", "--mapping", "{f}"], "mapping.yaml",
     "rx:\n  - index: 0x1600\n    entries: ['0x607A:00/" + "9" * 5000 + "']\n"),
    (["lint", "{f}"], "project.yaml", "ecattool: 1\nname: m\ndrives:\n  - name: a\n    device: {profile: hdt}\n"
                                      "    scaling: {feedback: {counts_per_rev: 1e99999999}}\n"),
]


def test_huge_counts_end_with_a_located_error_under_512_mib(tmp_path: Path) -> None:
    """cycles: 2^40 and its kind are refused where they are read, not run (the child's timeout is a hang guard)."""
    cases: list[dict[str, object]] = []
    for n, (argv, name, text) in enumerate(HUGE_COUNTS):
        f = tmp_path / name
        f.write_text(text)
        cases.append({"argv": _fill(argv, str(f), tmp_path, n), "stdin": None})
    results = _run_child(cases, tmp_path)
    assert len(results) == len(cases)
    for (argv, name, _), case, result in zip(HUGE_COUNTS, cases, results):
        _check(list(case["argv"]), name, result)  # type: ignore[call-overload]
        assert re.search(rf"{re.escape(name)}:\d+:\d+: ", str(result["stdout"]) + str(result["stderr"])), result


def test_an_esi_object_of_gigabytes_is_skipped_not_allocated(tmp_path: Path) -> None:
    """BitSize 34359738360 (4 GiB) on one object: the dictionary reader skips it with a located finding, so the
    simulator never allocates it (it did: 5.8 GB before the limit)."""
    text = (ROOT / "samples" / "esi" / "etg2001_cia402.xml").read_text()
    start = text.index("<Index>#x1008</Index>")
    head, tail = text[:start], text[start:]
    esi = tmp_path / "huge.xml"
    esi.write_text(head + tail.replace("<BitSize>48</BitSize>", "<BitSize>34359738360</BitSize>", 1))
    script = tmp_path / "s.yaml"
    script.write_text("- state: PREOP\n- read: '1018:01'\n")
    results = _run_child([{"argv": ["sim", "run", str(esi), str(script)], "stdin": None},
                          {"argv": ["esi", "validate", str(esi)], "stdin": None}], tmp_path)
    assert results[0]["exception"] is None and results[0]["code"] == 0, results[0]
    assert results[1]["exception"] is None and re.search(r"huge\.xml:\d+: warning: object skipped: 0x1008:00 has a "
                                                         r"BitSize of 34359738360", str(results[1]["stdout"])), results[1]


def test_alias_bomb_error_is_located() -> None:
    from ecattool.errors import InputError
    from ecattool.yamlloc import load_yaml

    with pytest.raises(InputError, match=r"aliases expand to more than") as info:
        load_yaml(BOMB, "bomb.yaml")
    assert info.value.location is not None and info.value.location.line is not None


def test_aliases_a_real_file_uses_still_load() -> None:
    from ecattool.yamlloc import load_yaml

    text = "defaults: &d {transition: PS, comment: x}\nparameters:\n" + "".join(
        f"  - {{object: '6081:00', value: {i}}}\n" for i in range(50)) + "repeat: [*d, *d, *d]\n"
    doc = load_yaml(text, "ok.yaml")
    assert doc.data["repeat"][2] == {"transition": "PS", "comment": "x"}


@pytest.mark.parametrize("text", ["a: !!int x", "!!int", "a: !!set x", "a: !!float x", "a: !!int 0x", "a: !!float 1e", "a: !!bool maybe",
                                  "a: " + "9" * 5000, "a: !!int " + "9" * 5000])
def test_explicit_tags_and_huge_numbers_are_validated(text: str) -> None:
    from ecattool.errors import InputError
    from ecattool.yamlloc import load_yaml

    try:
        load_yaml(text, "t.yaml")
    except InputError as exc:
        assert exc.location is not None and exc.location.line == 1
