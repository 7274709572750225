"""Run inside a private network namespace (tests/wire/test_wire_pysoem.py starts it through ecattool.sim.bus.netns):
``ecattool sim serve`` on one end of the veth pair, a real master (SOEM through pysoem) on the other.

    python wire_pysoem_scenario.py SOURCE... -- PROJECT...

first a bus of SOURCEs brought up by pysoem (config_init, identities, SDO reads, config_map, OP, INIT), then
``ecattool commission PROJECT --target pysoem`` for each PROJECT on a bus of its own.

Prints one JSON document on stdout. Every wait is bounded."""

from __future__ import annotations

import ctypes
import json
import os
import select
import signal
import subprocess
import sys
import time
from typing import Any

MASTER_IF, SLAVE_IF = "ecat0", "ecat1"
#: objects read over SDO in PRE-OP (compared with the in-process drive by the test)
SDO_READS = [(0x1018, 1), (0x1018, 2), (0x1018, 3), (0x1018, 4), (0x1C12, 0), (0x1C13, 0), (0x1C12, 1),
             (0x1C13, 1), (0x1600, 0), (0x1A00, 0), (0x1A00, 1), (0x6041, 0), (0x6060, 0), (0x6064, 0)]


#: extra arguments of ``sim serve`` (``--workers N``)
WORKERS: list[str] = []

#: the served bus's real-time priority (SCHED_FIFO) where permitted
SERVER_PRIORITY = 10


def master_priority() -> None:
    """The master side: this scenario and the masters it starts (they inherit it) at a raised nice value. Not
    real-time: SOEM polls its socket without sleeping while it waits for a frame, and two such threads (the
    pysoem target's caller and its keeper) at a real-time priority starve the kernel's softirq threads that carry
    the frames over the veth pair (an SDO answer then never arrives). A master starved for 100 ms stops the
    process data and the drives' watchdogs take them out of OP (AL 0x001B), as on a real bus."""
    try:
        os.nice(-10)
    except OSError:
        pass  # not permitted: normal priority (may time out on a busy machine)


def _server_child() -> None:
    """In the server's process before it starts. The server sleeps in select() until a frame comes and then needs
    the CPU at once: SOEM gives a frame 2 ms to come back (EC_TIMEOUTRET) and a mailbox write no second chance. A
    real-time priority (where it is permitted) wakes it before the rest of a busy machine; its work per frame is
    some hundred microseconds. And the server ends with the scenario (PR_SET_PDEATHSIG): a master that crashes
    inside its compiled code (KickCAT once did, under load) leaves no server behind, nor its namespace."""
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(SERVER_PRIORITY))
    except (OSError, AttributeError):
        pass  # not permitted: it keeps the scenario's raised priority
    try:
        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGTERM)  # 1 = PR_SET_PDEATHSIG (Linux)
    except (OSError, AttributeError):
        pass


def start_server(sources: list[str], argv: list[str] | None = None) -> tuple[subprocess.Popen[str], dict[str, Any]]:
    """``ecattool sim serve SOURCES`` on the slave end, or ``argv``: a server that prints the same ready line."""
    argv = argv or [sys.executable, "-m", "ecattool", "sim", "serve", *sources, "--iface", SLAVE_IF, "--json",
                    *WORKERS]
    server = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, preexec_fn=_server_child)
    assert server.stdout is not None
    ready, _, _ = select.select([server.stdout], [], [], 60)
    line = server.stdout.readline() if ready else ""
    if not line:
        server.kill()
        raise SystemExit(f"the server did not get ready: {server.communicate(timeout=10)[1][-2000:]}")
    return server, json.loads(line)


def stop_server(server: subprocess.Popen[str]) -> dict[str, Any]:
    server.send_signal(signal.SIGTERM)
    try:
        _, err = server.communicate(timeout=20)
    except subprocess.TimeoutExpired:
        server.kill()
        _, err = server.communicate()
    return {"returncode": server.returncode, "stderr": err[-2000:]}


def open_preop(out: dict[str, Any]) -> Any:
    """A pysoem master on MASTER_IF with the bus found (``out["found"]``) and brought to PRE-OP."""
    import pysoem

    master = pysoem.Master()
    master.open(MASTER_IF)
    out["found"] = master.config_init()
    master.state_check(pysoem.PREOP_STATE, 2_000_000)
    return master


def reach_op(master: Any) -> tuple[int, int]:
    """Request OP and run the process data until the slaves are in OP, bounded: at most 2000 cycles of 1 ms.
    Returns the last working counter and the cycles it took."""
    import pysoem

    master.state = pysoem.OP_STATE
    master.write_state()
    wkc, cycles = 0, 0
    for cycles in range(1, 2001):
        master.send_processdata()
        wkc = master.receive_processdata(2000)
        if master.state_check(pysoem.OP_STATE, 1000) == pysoem.OP_STATE:
            break
        time.sleep(0.001)
    return wkc, cycles


def bringup(sources: list[str]) -> dict[str, Any]:
    import pysoem

    server, ready = start_server(sources)
    out: dict[str, Any] = {"ready": ready}
    try:
        master = open_preop(out)
        out["identity"] = [[s.man, s.id, s.rev] for s in master.slaves]
        out["names"] = [s.name for s in master.slaves]
        reads = []
        for s in master.slaves:
            row = {}
            for index, sub in SDO_READS:
                try:
                    row[f"{index:04X}:{sub:02X}"] = bytes(s.sdo_read(index, sub)).hex()
                except pysoem.SdoError as exc:
                    row[f"{index:04X}:{sub:02X}"] = f"abort:{exc.abort_code:08X}"
            reads.append(row)
        out["sdo"] = reads
        master.config_map()
        out["sizes"] = [[len(s.output), len(s.input)] for s in master.slaves]
        out["safeop"] = master.state_check(pysoem.SAFEOP_STATE, 2_000_000)
        wkc, cycles = reach_op(master)
        out["op"] = master.read_state() == pysoem.OP_STATE
        out["states"] = [s.state for s in master.slaves]
        out["wkc"], out["expected_wkc"], out["cycles"] = wkc, master.expected_wkc, cycles
        master.state = pysoem.INIT_STATE
        master.write_state()
        out["init"] = master.state_check(pysoem.INIT_STATE, 2_000_000) == pysoem.INIT_STATE
        master.close()
    finally:
        out["server"] = stop_server(server)
    return out


def commission(projects: list[str]) -> dict[str, Any]:
    runs = []
    for project in projects:
        server, ready = start_server([project])
        try:
            done = subprocess.run([sys.executable, "-m", "ecattool", "commission", project, "--target",
                                   f"pysoem:{MASTER_IF}", "--json"], capture_output=True, text=True, timeout=240)
        finally:
            stopped = stop_server(server)
        runs.append({"project": project, "returncode": done.returncode, "stdout": done.stdout,
                     "stderr": done.stderr[-2000:], "server": stopped})
    return {"runs": runs}


if __name__ == "__main__":
    # SOEM gives each frame 2 ms to come back (EC_TIMEOUTRET) and a mailbox send no second chance: both the
    # master and the server must get the CPU when a frame is on its way, also on a loaded machine (the rest of
    # the test suite runs beside this)
    master_priority()
    # "bringup SOURCE... -- PROJECT...": one after the other (never two buses at once on a small machine)
    args = sys.argv[1:]
    if args[:1] == ["--workers"]:  # "--workers N bringup...": the line served by N processes
        WORKERS[:] = args[:2]
        args = args[2:]
    split = args.index("--") if "--" in args else len(args)
    print(json.dumps({"bringup": bringup(args[:split]), "commission": commission(args[split + 1:])}))
