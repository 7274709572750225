"""``sdo read`` of one object does less (issue 35 item 5: a whole process at most 1.5x a bare pysoem script,
benchmarks/bench_sdo_read.py): the modules on its way import no XML reader, no audit, scan, library or simulator
engine, and a CiA-301 communication object read by its address is typed by the standard, without the slave's
identity, a family dictionary or the SDO Information service."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from tests.conftest import ROOT, run

#: what ``ecattool sdo read 0x1018:01 --target pysoem:IF`` imports on its way (the CLI, the live bus, the master)
PATH = ("ecattool.cli", "ecattool.cli.sdo", "ecattool.cli.online", "ecattool.online.targets",
        "ecattool.online.objects", "ecattool.online.dictionary", "ecattool.online.bus_state",
        "ecattool.target.isolated", "ecattool.target.pysoem", "ecattool.sim.bus.raw",
        "ecattool.sim.bus.frame")
#: what it must not: each was on the way before (lxml through ecattool.esi, the audit through ecattool.online, the
#: simulator's engine through the raw socket's module, the families through the dictionary)
HEAVY = ("lxml.etree", "ecattool.esi.reader", "ecattool.online.audit", "ecattool.online.scan",
         "ecattool.online.library", "ecattool.sim.bus.engine", "ecattool.sim.esc", "ecattool.profiles")


def test_the_sdo_read_path_imports_nothing_heavy() -> None:
    code = (f"import sys\nfor m in {PATH!r}: __import__(m)\n"
            f"print(sorted(m for m in {HEAVY!r} if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, cwd=ROOT)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]", done.stdout


def test_a_cia301_object_is_typed_by_the_standard(capsys: pytest.CaptureFixture[str],
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    from ecattool.online import library

    def no(*a: object, **k: object) -> None:
        raise AssertionError("a family dictionary was loaded for a CiA-301 object")

    monkeypatch.setattr(library, "family_device", no)
    monkeypatch.setattr(library, "family_match", no)
    code, out, err = run(capsys, "sdo", "read", "0x1018:01", "--target", "sim:hdt", "--json")
    assert code == 0, err
    got = json.loads(out)
    assert (got["value"], got["type"], got["name"], got["dictionary"]) == (0x289, "UDINT", "Vendor ID", "standard")
    # any other object is typed by the slave's dictionary as before
    monkeypatch.undo()
    code, out, err = run(capsys, "sdo", "read", "0x6060:00", "--target", "sim:hdt", "--json")
    assert code == 0 and json.loads(out)["dictionary"] == "family", err
