"""``sdo read`` of one object does less (issue 35 item 5: a whole process at most 1.5x a bare pysoem script,
benchmarks/bench_sdo_read.py): the command as it runs imports no rich, pydantic, lxml, YAML, XML reader, audit,
scan, library, profile or simulator engine; a CiA-301 communication object read by its address is typed by the
standard, without the slave's identity, a family dictionary or the SDO Information service; and the bus state read
before the master opens costs no RCU grace period of the kernel (10-15 ms each on this project's machines)."""

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
#: what the command as it runs must not import either: the table and JSON-schema libraries of other commands, the
#: project layer, the simulator's drives
NOT_ON_THE_WAY = ("rich", "pydantic", "lxml", "yaml", "ruamel", "ecattool.project", "ecattool.sim.drive",
                  "multiprocessing", *HEAVY)


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


def test_the_command_as_it_runs_imports_nothing_heavy() -> None:
    """The whole ``sdo read`` command line, through click and the lazy command loading (ecattool.cli), as far as it
    gets on an interface this machine does not have (the state read and the master both fail to open it: no frame
    is sent anywhere), in a fresh interpreter: no rich, pydantic, lxml, project layer or simulator on its way."""
    code = ("import sys\nfrom ecattool.cli import main\n"
            "try:\n    main(['sdo', 'read', '0x1018:01', '--target', 'pysoem:ecatnone9'])\n"
            "except SystemExit as exc:\n    print('exit', exc.code)\n"
            f"heavy = {NOT_ON_THE_WAY!r}\n"
            "print(sorted(m for m in sys.modules if any(m == h or m.startswith(h + '.') for h in heavy)))\n"
            "print('ecattool.cli.sdo' in sys.modules, 'ecattool.cli.esi' in sys.modules)\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, cwd=ROOT)
    assert done.returncode == 0, done.stderr
    exit_line, heavy, loaded = done.stdout.strip().splitlines()
    assert exit_line == "exit 1" and "ecatnone9" in done.stderr, done.stderr  # one line naming the interface
    assert heavy == "[]", heavy
    assert loaded == "True False"  # only the command that runs is loaded


def test_the_state_read_socket_is_bound_to_the_ethertype_not_made_with_it(monkeypatch: pytest.MonkeyPatch) -> None:
    """Linux hooks a packet socket made with a protocol into the receive path at once; binding it then takes the
    hook out and waits for an RCU grace period (10-15 ms, every ``sdo read``). Made with protocol 0 and bound to
    0x88A4 it receives the same frames (the wire tests and benchmarks/bench_sdo_read.py read through it) without
    the wait. (The wait itself is not asserted: no timed tests.)"""
    import socket as socket_module

    from ecattool.sim.bus import raw

    made: list[tuple[object, ...]] = []

    class Recorder:
        def __init__(self, *args: object) -> None:
            made.append(("socket", *args))

        def bind(self, address: object) -> None:
            made.append(("bind", address))

        def setsockopt(self, *args: object) -> None:
            pass

    monkeypatch.setattr(socket_module, "socket", Recorder)
    raw.open_raw("ecat9")
    assert made == [("socket", socket_module.AF_PACKET, socket_module.SOCK_RAW, 0), ("bind", ("ecat9", 0x88A4))]


def test_a_read_through_a_held_bus_imports_no_dataclasses() -> None:
    """``sdo read 0x1018:01`` through a held bus (``ecattool bus hold``), the real command line in a fresh
    interpreter: every record on its way (the target spec, the bus limits, the live bus, the states found, the
    typed dictionary, the value read) is an ``ecattool.record`` class, so the ``dataclasses`` module (and the ~1 ms
    each dataclass costs at import) is not loaded at all."""
    from ecattool.online import held
    from tests.online.test_held import _start

    holding = _start()
    try:
        code = ("import runpy, sys\n"
                f"sys.argv = ['ecattool', 'sdo', 'read', '0x1018:01', '--target', {holding.name!r}]\n"
                "try:\n    runpy.run_module('ecattool', run_name='__main__', alter_sys=True)\n"
                "except SystemExit as exc:\n    assert not exc.code, exc.code\n"
                "print('dataclasses' in sys.modules, 'ecattool.online.held' in sys.modules)\n")
        done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, cwd=ROOT)
    finally:
        held.release(holding.name)
        holding.wait()
    assert done.returncode == 0, done.stderr
    value, loaded = done.stdout.strip().splitlines()
    assert value.startswith("0x1018:01 Vendor ID") and "= 649" in value, value  # read through the holder
    assert loaded == "False True", loaded
