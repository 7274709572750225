"""Run inside a private network namespace (tests/wire/test_wire_hostile_slave.py starts it through ecattool.sim.bus.netns):
for each misbehaviour, ``ecattool sim serve PROJECT --misbehave NAME`` on one end of the veth pair, and on the
other end the read commands of ecattool through SOEM (pysoem): ``bus scan``, ``sdo read``, ``sdo dump``,
``sii read``, ``backup`` and ``audit``, each a process of its own, each bounded in time.

    python wire_hostile_slave_scenario.py PROJECT OUTDIR NAME...

Prints one JSON document on stdout: per misbehaviour and command the exit status, the time taken, stderr and
the end of stdout. Every wait is bounded."""

from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path
from typing import Any

from wire_pysoem_scenario import MASTER_IF, master_priority, start_server, stop_server

#: the longest one command may take (the master's own time limits are capped at MASTER_TIMEOUT_S)
COMMAND_TIMEOUT_S = 40
MASTER_TIMEOUT_S = "4"


def commands(project: str, out: Path) -> dict[str, list[str]]:
    target = ["--target", f"pysoem:{MASTER_IF}"]
    return {
        "bus scan": ["bus", "scan", *target],
        "sdo read": ["sdo", "read", "0x1018:01", *target],
        "sdo dump": ["sdo", "dump", *target, "-o", str(out / "dump.json")],
        "sii read": ["sii", "read", *target, "-o", str(out / "slave.sii.bin")],
        "backup": ["backup", project, *target, "-o", str(out / "backup")],
        "audit": ["audit", project, *target],
    }


def _warm() -> None:
    """Import every command once in this process: each command then runs in a fork of it (as ``python -m ecattool``
    would, its own process with its own exit status, without importing ecattool again: seconds per run on a
    loaded machine)."""
    import ecattool.cli
    from ecattool.cli import audit, backup, bus, sdo, sii  # noqa: F401
    from ecattool.online import audit as _audit, bus_state, objects, scan, targets  # noqa: F401
    from ecattool.target import isolated  # noqa: F401

    ecattool.cli.cli.list_commands  # noqa: B018 - the group itself


def run(argv: list[str], cap: str = MASTER_TIMEOUT_S) -> dict[str, Any]:
    """``ecattool ARGV`` in a forked process of its own: exit status (None: killed after COMMAND_TIMEOUT_S;
    negative: the signal that ended it), time taken, stdout and stderr."""
    import tempfile

    os.environ["ECATTOOL_MASTER_TIMEOUT_S"] = cap
    t0 = time.monotonic()
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        sys.stdout.flush()
        sys.stderr.flush()
        pid = os.fork()
        if pid == 0:  # the command
            os.dup2(out.fileno(), 1)
            os.dup2(err.fileno(), 2)
            code = 1
            try:
                from ecattool.cli import main

                main(argv)
                code = 0
            except SystemExit as exc:
                code = exc.code if isinstance(exc.code, int) else 1
            finally:
                sys.stdout.flush()
                sys.stderr.flush()
                os._exit(code)
        rc: int | None = None
        while time.monotonic() - t0 < COMMAND_TIMEOUT_S:
            done, status = os.waitpid(pid, os.WNOHANG)
            if done:
                rc = os.waitstatus_to_exitcode(status)
                break
            time.sleep(0.02)
        else:
            os.kill(pid, 9)
            os.waitpid(pid, 0)
        out.seek(0)
        err.seek(0)
        stdout, stderr = out.read().decode(errors="replace"), err.read().decode(errors="replace")
    if rc is None:
        stderr += f"\nstill running after {COMMAND_TIMEOUT_S} s"
    return {"returncode": rc, "seconds": round(time.monotonic() - t0, 2), "stdout": stdout[-50000:], "stderr": stderr}


def _take(state_name: str) -> bool:
    """A bare SOEM master takes the slave to INIT or SAFE-OP and goes away (as a machine's master that stopped)."""
    import pysoem

    master = pysoem.Master()
    master.open(MASTER_IF)
    try:
        if master.config_init() <= 0:
            return False
        if state_name == "SAFEOP":
            master.config_map()
        code = getattr(pysoem, f"{state_name}_STATE")
        master.state = code
        master.write_state()
        return bool(master.state_check(code, 2_000_000) == code)
    finally:
        master.close()


def running_bus(project: str) -> dict[str, Any]:
    """Issue 35 item 4 on the wire: a bus found in SAFE-OP is refused without --reset-bus; with it the read runs
    and says what it could not put back; a slave found in INIT is put back in INIT."""
    from ecattool.online.bus_state import read_states

    read = ["sdo", "read", "0x1018:01", "--target", f"pysoem:{MASTER_IF}"]
    out: dict[str, Any] = {"safeop": _take("SAFEOP")}
    out["found_safeop"] = [str(f) for f in read_states(MASTER_IF) or []]
    out["refused"] = run(read)
    out["after_refusal"] = [str(f) for f in read_states(MASTER_IF) or []]
    out["reset"] = run([*read, "--reset-bus"])
    out["init"] = _take("INIT")
    out["in_init"] = run(read)
    out["after_init"] = [str(f) for f in read_states(MASTER_IF) or []]
    out["audit_in_init"] = run(["audit", project, "--target", f"pysoem:{MASTER_IF}", "--json"])
    return out


#: the misbehaviours also read through KickCAT (its bus init follows an SII chain without end for minutes)
KICKCAT_UNDER = ("none", "upload-endless", "sii-no-end")
#: KickCAT's bus init reads the SII slowly (seconds for one slave here): its cap is higher
KICKCAT_TIMEOUT_S = "15"
#: a drive ecattool has no profile for, whose ESI says it has no SDO Information (CoE SdoInfo="0")
UNKNOWN = "samples/generic_esi/inovance_SV660_EOE_1Axis_V9.12.xml"


def unknown_drive() -> dict[str, Any]:
    """Issue 35 item 3 on the wire: a drive without a profile and without SDO Information."""
    from ecattool.online.targets import open_bus

    server, ready = start_server([UNKNOWN])
    target = ["--target", f"pysoem:{MASTER_IF}"]
    out: dict[str, Any] = {"ready": ready}
    try:
        out["info"] = run(["sdo", "info", *target])
        out["read"] = run(["sdo", "read", "0x1018:01", *target, "--json"])
        out["by_name"] = run(["sdo", "read", "statusword", *target, "--device", UNKNOWN, "--json"])
        out["name_without_dictionary"] = run(["sdo", "read", "statusword", *target])
        with open_bus(f"pysoem:{MASTER_IF}") as bus:  # SDO Information refused, then every later SDO still works
            slave = bus.slaves[0]
            try:
                slave.sdo_info()
                out["sdo_info"] = "answered"
            except Exception as exc:  # noqa: BLE001 - recorded for the test
                out["sdo_info"] = str(exc)
            out["after"] = [slave.sdo_upload(0x1018, s).hex() for s in (1, 2, 1)]
    finally:
        out["server"] = stop_server(server)
    return out


def one(project: str, name: str, outdir: Path) -> dict[str, Any]:
    out = outdir / name
    out.mkdir(parents=True)
    extra = [] if name == "none" else ["--misbehave", name]
    server, _ready = start_server([project, *extra])
    results: dict[str, Any] = {}
    try:
        for label, argv in commands(project, out).items():
            results[label] = run(argv)
            sii = out / "slave.sii.bin"
            if label == "sii read" and sii.exists():
                results[label]["sii_hex"] = sii.read_bytes().hex()
        if name in ("upload-4gib", "upload-endless"):  # an object whose type ecattool does not know: no size bound
            results["sdo read (unknown type)"] = run(["sdo", "read", "0x2FFF:00", "--target", f"pysoem:{MASTER_IF}"])
        if name in KICKCAT_UNDER:  # KickCAT as the master, where it has been seen to crash or hang
            results["sdo read (kickcat)"] = run(["sdo", "read", "0x1018:01", "--target", f"kickcat:{MASTER_IF}"],
                                                KICKCAT_TIMEOUT_S)
        if name == "none":
            results["running bus"] = running_bus(project)
    finally:
        results["server"] = stop_server(server)
    return results


if __name__ == "__main__":
    master_priority()
    _warm()
    project, outdir, *names = sys.argv[1:]
    result = {name: one(project, name, Path(outdir)) for name in names}
    result["unknown drive"] = unknown_drive()
    print(json.dumps(result))
