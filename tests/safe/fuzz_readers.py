"""Mutation fuzzing of every file ecattool reads, through the command line (issues 23.2 and 28.5).

Real seeds (samples/ and ../shared/corpus) are mutated by a hypothesis strategy: bytes flipped, cut, inserted or
repeated, numbers replaced by zero, negative, huge and malformed ones, and tokens that readers meet rarely (YAML
tags and aliases, XML markup, control characters). Each mutant is given to every command that reads that kind of
file; the command must end with a result (exit 0), or with exit status 1 and one line ``ecattool: error: …`` that
names a file (checkers: their report names it) — never a raw exception, a traceback or a second line.

Used by tests/safe/test_fuzz_readers.py (a few examples per entry in the suite) and scripts/fuzz.py (the long run:
``python3 scripts/fuzz.py --examples 2000``).
"""

from __future__ import annotations

import io
import os
import re
import shutil
import sys
from dataclasses import dataclass
from pathlib import Path

from hypothesis import strategies as st

ROOT = Path(__file__).resolve().parents[2]
from tests.conftest import CORPUS  # noqa: E402  (the one place that knows where the corpus is)

STEPS = ("- state: PREOP\n- read: '1018:01'\n- write: '6060:00'\n  value: 1\n- state: SAFEOP\n- state: OP\n"
         "- exchange: '0600 00000000'\n- cycles: 10\n- foe: FOESW_X.bin\n  data: '0102'\n  password: 0\n  expect_abort: 0x8004\n")
MAPPING = "rx:\n  - index: 0x1600\n    entries: [controlword, 0x607A:00/32]\ntx:\n  - index: 0x1A00\n" \
          "    entries: [statusword, '0x6064:00/32']\n"


@dataclass(frozen=True)
class Entry:
    """A command that reads one file: ``argv`` with ``{f}`` for it (``{o}`` an output, ``{sw}`` a good image);
    ``seeds`` are paths ('samples/…', 'corpus:…') or ``text:NAME`` (a seed of :data:`TEXT_SEEDS`)."""

    name: str
    argv: tuple[str, ...]
    seeds: tuple[str, ...]
    suffix: str
    reporter: bool = False  # reports a bad input as a finding (lint, sii check)


FACTORS_YAML = "6093:01: 4294967295\n6093:02: 13493038\n6094:01: 0x1000\n6094:02: 1\n"
FACTORS_JSON = ('{"factor_set": "cia402-2", "objects": [{"index": "0x6093", "subindex": 1, "value": 1200}, '
                '{"index": "0x6093", "subindex": 2, "value": 1}, {"index": "0x6094", "subindex": 1, "value": 5}]}\n')
TEXT_SEEDS = {"steps": STEPS, "mapping": MAPPING, "factors-yaml": FACTORS_YAML, "factors-json": FACTORS_JSON}

ESI_SEEDS = ("samples/esi/etg2001_cia402.xml", "corpus:esi/smc_EX260-SECx_V11.xml",
             "corpus:esi/synapticon_Somanet_CiA402-single.xml", "samples/sii/custom_slave.xml")
ENTRIES: tuple[Entry, ...] = (
    Entry("esi devices", ("esi", "devices", "{f}"), ESI_SEEDS, ".xml"),
    Entry("sii build (ESI)", ("sii", "build", "{f}", "--device", "0", "-o", "{o}", "--force"), ESI_SEEDS, ".xml"),
    # the SMC EX260 has no mailbox (its script's SDO read would time out, as on the real slave): the drives only
    Entry("sim run (ESI)", ("sim", "run", "{f}", "{script}", "--device", "0"), (ESI_SEEDS[0], ESI_SEEDS[2]), ".xml"),
    Entry("esi show (EDS)", ("esi", "show", "{f}", "--pdos"), ("corpus:eds/technosoft_iPOS.D.v1.04.eds",), ".eds"),
    Entry("sii info", ("sii", "info", "{f}"),
          ("corpus:sii/ni9144.bin", "corpus:sii/soes_linux_lan9252demo.bin", "samples/sii/custom_slave.bin"), ".bin"),
    Entry("sii check", ("sii", "check", "{f}"), ("corpus:sii/easycat_FEI_1.bin", "samples/sii/custom_slave.bin"),
          ".bin", reporter=True),
    Entry("sw info", ("sw", "info", "{f}"), ("samples/sw/cam.sw", "corpus:sw/ecmc_TMLCode.sw"), ".sw"),
    Entry("sw from-foe (FoE)", ("sw", "from-foe", "{f}", "-o", "{o}", "--force"),
          ("corpus:sw/ecmc_ipos8020BX_FOESW_8020.bin",), ".bin"),
    Entry("sw show -p (parameters)", ("sw", "show", "{sw}", "-p", "{f}"),
          ("corpus:sw/ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.ems_parameters.cfg",), ".cfg"),
    Entry("startup import (ENI)", ("startup", "import", "{f}"), ("corpus:configs/eni_kpierczy_test_eni.xml",), ".xml"),
    Entry("startup import (other formats)", ("startup", "import", "{f}"),
          ("corpus:configs/ros2_elmo_gold.yaml", "corpus:configs/ecmc_ecmciPOSXXXX.cmd",
           "corpus:configs/lcec_initcmds_ethercat-conf.xml", "corpus:configs/ros2_beckhoff_el3104.yaml"), ".txt"),
    Entry("lint (project)", ("lint", "{f}"),
          ("samples/technosoft_ipos/project.yaml", "samples/hdt/project.yaml", "samples/controltechniques/project.yaml",
           "samples/generic_esi/project.yaml"), ".yaml", reporter=True),
    Entry("scale compute (spec)", ("scale", "compute", "{f}"),
          ("samples/scaling/ballscrew.yaml", "samples/scaling/belt.yaml", "samples/scaling/belt_diameter.yaml",
           "samples/scaling/ct_screw.yaml", "samples/scaling/hdt_label.yaml", "samples/scaling/rotary_table.yaml"),
          ".yaml"),
    Entry("sw build (spec)", ("sw", "build", "{f}", "-o", "{o}", "--force"), ("samples/sw/build.yaml",), ".yaml"),
    Entry("sim run (script)", ("sim", "run", "technosoft-ipos", "{f}"), ("text:steps",), ".yaml"),
    Entry("scale explain --from", ("scale", "explain", "--from", "{f}"), ("text:factors-yaml", "text:factors-json"),
          ".yaml"),
    Entry("map check (mapping)", ("map", "check", "--profile", "technosoft-ipos", "--mapping", "{f}"),
          ("text:mapping",), ".yaml", reporter=True),  # a mapping that breaks a rule: findings on stdout
)

#: Numbers a mutation puts where a number was: zero, negative, the edges of the CoE integer types, absurd ones
NUMBERS = (b"0", b"-1", b"-5", b"1", b"255", b"256", b"65535", b"65536", b"4294967295", b"4294967296",
           b"-2147483649", b"34359738360", b"18446744073709551616", b"99999999999999999999999999999999", b"1e999", b"1.0e999",
           b"-1e999", b"1e-999", b"0x", b"0xFFFFFFFFFFFFFFFFF", b"#x1FFFF", b"0.0", b"-0", b".inf", b".nan", b"1/0",
           b"true", b"9" * 5000)
#: Tokens readers meet rarely
TOKENS = (b"!!int x", b"!!float x", b"!!binary x", b"&a ", b"*a", b"*zz", b"<<: *a", b"? ", b"- ", b": ", b"\n",
          b"\t", b"\x00", b"\x01", b"\xff\xfe", b"\xc3\x28", "é".encode(), b"#", b"'", b'"', b"{", b"[", b"}", b"]",
          b"<", b">", b"</", b"/>", b"<!--", b"<![CDATA[", b"&amp;", b"&#0;", b"<!DOCTYPE x>", b"=", b",", b";",
          b"\r\n", b"\r", b":00/8", b":FF", b"/", b"../../../../../etc/passwd", b"/dev/null")

_NUMBER_RE = re.compile(rb"(?<![A-Za-z_])(?:0x[0-9A-Fa-f]+|#x[0-9A-Fa-f]+|\d+(?:\.\d+)?)")


def seed_bytes(seed: str) -> bytes:
    if seed.startswith("text:"):
        return TEXT_SEEDS[seed[5:]].encode()
    if seed.startswith("corpus:"):
        data = (CORPUS / seed[7:]).read_bytes()
    else:
        data = (ROOT / seed).read_bytes()
    # the sample build spec names corpus files relative to the repository: point it at the corpus itself
    return data.replace(b"../../../shared/corpus", str(CORPUS).encode())


@st.composite
def mutants(draw: st.DrawFn, entry: Entry) -> tuple[str, bytes]:
    """A seed of ``entry`` and a mutant of it (one to four mutations; sometimes none, so valid input runs too)."""
    seed = draw(st.sampled_from(entry.seeds))
    data = bytearray(seed_bytes(seed))
    for _ in range(draw(st.integers(0, 4))):
        op = draw(st.sampled_from(("number", "number", "token", "flip", "cut", "insert", "repeat", "truncate")))
        n = len(data)
        pos = draw(st.integers(0, max(n - 1, 0)))
        if op == "number":
            spans = [m.span() for m in _NUMBER_RE.finditer(bytes(data))]
            if spans:
                a, b = spans[draw(st.integers(0, len(spans) - 1))]
                data[a:b] = draw(st.sampled_from(NUMBERS))
        elif op == "token":
            data[pos:pos] = draw(st.sampled_from(TOKENS))
        elif op == "flip" and n:
            data[pos] = draw(st.integers(0, 255))
        elif op == "cut" and n:
            data[pos:pos + draw(st.integers(1, 64))] = b""
        elif op == "insert":
            data[pos:pos] = draw(st.binary(min_size=1, max_size=16))
        elif op == "repeat" and n:
            piece = bytes(data[pos:pos + draw(st.integers(1, 200))])
            data[pos:pos] = piece * draw(st.integers(1, 50))
        elif op == "truncate":
            del data[pos:]
    return seed, bytes(data)


def workdir(base: Path) -> Path:
    """A copy of samples/ (projects name their ESI and .sw files relative to themselves)."""
    w = base / "fuzz"
    if not w.exists():
        shutil.copytree(ROOT / "samples", w / "samples")
        (w / "steps.yaml").write_text("- state: PREOP\n- read: '1018:01'\n- read: '1008:00'\n- state: SAFEOP\n")
    return w


def place(work: Path, entry: Entry, seed: str, data: bytes) -> Path:
    """Where the mutant is written: beside the seed's copy (so its relative references resolve)."""
    folder = work / Path(seed).parent if seed.startswith("samples/") else work
    path = folder / f"mutant{entry.suffix}"
    path.write_bytes(data)
    return path


def invoke(argv: list[str]) -> tuple[int, str, str, BaseException | None]:
    """Run ecattool in this process; (exit status, stdout, stderr, the exception that escaped, if any)."""
    from ecattool.cli import main

    out, err = io.BytesIO(), io.BytesIO()
    tout = io.TextIOWrapper(out, encoding="utf-8", errors="replace", write_through=True)
    terr = io.TextIOWrapper(err, encoding="utf-8", errors="replace", write_through=True)
    real = sys.stdout, sys.stderr
    sys.stdout, sys.stderr = tout, terr
    code, escaped = 0, None
    try:
        main(argv)
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else 0
    except BaseException as exc:  # noqa: BLE001 - the finding
        code, escaped = -1, exc
    finally:
        sys.stdout, sys.stderr = real
        tout.flush()
        terr.flush()
    text_out, text_err = out.getvalue().decode("utf-8", "replace"), err.getvalue().decode("utf-8", "replace")
    tout.detach()
    terr.detach()
    return code, text_out, text_err, escaped


def check(entry: Entry, path: Path, work: Path) -> None:
    """Run ``entry`` on the file at ``path``; raise AssertionError when the outcome breaks the contract."""
    sw = CORPUS / "sw" / "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.sw"
    argv = [a.format(f=path, o=work / "fuzz-output", sw=sw, script=work / "steps.yaml") for a in entry.argv]
    code, out, err, escaped = invoke(argv)
    where = f"{' '.join(argv)}"
    if escaped is not None:
        raise AssertionError(f"{where}: raw exception {type(escaped).__name__}: {escaped}") from escaped
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert "Traceback" not in out + err, f"{where}: traceback\n{err[-2000:]}"
    assert code in (0, 1), f"{where}: exit {code}\n{err[-1000:]}"
    if code == 0:
        return
    if entry.reporter:
        assert len(lines) <= 1, f"{where}: more than one line on stderr:\n{err[-1000:]}"
        return
    assert len(lines) == 1 and lines[0].startswith("ecattool: error: "), f"{where}: not one error line:\n{err[-2000:]}"
    located = re.match(r"ecattool: error: [^:\s][^:]*(?::\d+)*: ", lines[0])
    assert located, f"{where}: the error names no file: {lines[0]}"


# ------------------------------------------------------------------------------------------- hostile paths
#: The paths that are no ordinary file (issue 37.4/37.5), by name; made by :func:`hostile_paths`.
PATH_KINDS = ("missing", "long name", "long path", "directory", "char device", "null device", "dangling link",
              "link loop", "socket", "fifo")
#: FIFO as a command's own input is left out: with no writer, open() waits for one, as `cat FIFO` does (the user
#: named it); as a file a project names or as an output it is covered.
INPUT_KINDS = tuple(k for k in PATH_KINDS if k != "fifo")


def hostile_paths(base: Path) -> dict[str, Path]:
    """One path of each :data:`PATH_KINDS` in a fresh folder under ``base`` (the socket is bound and left open by
    nobody: connecting to it fails; the FIFO has no writer and no reader)."""
    import socket
    import tempfile

    # a short folder name: a UNIX socket's path is at most 107 bytes
    d = Path(tempfile.mkdtemp(prefix="hp", dir="/tmp" if len(str(base)) > 60 else base))
    (d / "folder").mkdir()
    os.mkfifo(d / "pipe")
    (d / "dangling").symlink_to(d / "nowhere" / "planted")
    (d / "loop-a").symlink_to(d / "loop-b")
    (d / "loop-b").symlink_to(d / "loop-a")
    sk = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    sk.bind(str(d / "sock"))
    sk.close()  # the socket file stays; nobody listens
    return {"missing": d / "absent.xml", "long name": d / ("n" * 300), "long path": d / "/".join(["p" * 200] * 30),
            "directory": d / "folder", "char device": Path("/dev/zero"), "null device": Path("/dev/null"),
            "dangling link": d / "dangling", "link loop": d / "loop-a", "socket": d / "sock", "fifo": d / "pipe"}


def check_output_path(entry: Entry, kind: str, path: Path, work: Path, seed: Path) -> None:
    """``entry`` (one with ``{o}``) writing to the hostile ``path``: a result or one located line; a socket and a
    directory are never written, a dangling link is followed only because the entry gives --force."""
    argv = [a.format(f=seed, o=path, sw=CORPUS / "sw" / "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.sw",
                     script=work / "steps.yaml") for a in entry.argv]
    code, out, err, escaped = invoke(argv)
    where = f"{kind}: {' '.join(argv)[:300]}"
    assert escaped is None, f"{where}: raw exception {type(escaped).__name__}: {escaped}"
    lines = [ln for ln in err.splitlines() if ln.strip() and "warning" not in ln]
    assert "Traceback" not in out + err, f"{where}: traceback\n{err[-1000:]}"
    if kind == "directory" and code == 2:  # click's own check of -o (dir_okay=False): a usage error, one message
        assert "is a directory" in err, f"{where}: {err}"
        return
    assert code in (0, 1), f"{where}: exit {code}\n{err[-1000:]}"
    if kind in ("socket", "directory", "long name", "long path", "link loop"):
        assert code == 1 and len(lines) == 1 and lines[0].startswith("ecattool: error: "), f"{where}: {err}"
    if kind == "socket":
        assert "UNIX socket" in lines[0]


def check_named_path(kind: str, path: Path, work: Path) -> None:
    """A project whose ``esi:`` (then ``sw:``) names the hostile ``path``: lint reports exactly one error finding
    at that line, one line or none on stderr, exit 1 — no traceback, no hang (a FIFO is never opened)."""
    import json

    for key, device in (("esi", f"{{esi: {json.dumps(str(path))}}}"), ("sw", "{profile: technosoft-ipos}")):
        text = f"ecattool: 1\nname: m\ndrives:\n  - name: z\n    device: {device}\n"
        if key == "sw":
            text += f"    sw: {json.dumps(str(path))}\n"
        project = work / "hostile.yaml"
        project.write_text(text)
        code, out, err, escaped = invoke(["lint", str(project), "--format", "json"])
        where = f"{kind} as {key}: {str(path)[:120]}"
        assert escaped is None, f"{where}: raw exception {type(escaped).__name__}: {escaped}"
        assert code == 1 and "Traceback" not in out + err and len(err.strip().splitlines()) <= 1, f"{where}: {err}"
        errors = [f for f in json.loads(out)["findings"] if f["severity"] == "error"]
        assert len(errors) == 1 and errors[0]["rule"] in ("PRJ002", "PRJ005", "PRJ030"), f"{where}: {errors}"
