"""Run inside a private network namespace (tests/wire/test_wire_mailbox.py starts it through ecattool.sim.bus.netns):
the mailbox over the wire with SOEM (pysoem) as the master.

    python wire_mailbox_scenario.py od SOURCE                  # pysoem's slave.od, then config_map
    python wire_mailbox_scenario.py faults PROJECT SPEC...     # two commission runs against each faulty bus
    python wire_mailbox_scenario.py serve PROJECT SPEC         # a faulty bus (started by 'faults')
    python wire_mailbox_scenario.py watchdog PROJECT MS        # a slow SDO in OP against the drive's watchdog
    python wire_mailbox_scenario.py foe PROJECT SW              # a .sw setup image by FoE through SOEM

``faults``: for each PROJECT SPEC pair, the virtual bus serves PROJECT with the fault SPEC (see ``serve``)
armed in its first drive or on its link; ``ecattool commission --target pysoem`` then runs twice against the
same bus. ``od``: SOEM reads the object dictionary through SDO information (ecx_readODlist,
ecx_readODdescription, ecx_readOE).

Prints one JSON document on stdout. Every wait is bounded."""

from __future__ import annotations

import json
import subprocess
import sys
from typing import Any

from wire_pysoem_scenario import (  # tests/ is the script's folder
    MASTER_IF, SLAVE_IF, master_priority, open_preop, start_server, stop_server)


def _text(value: str | bytes) -> str:
    return value.decode("latin-1") if isinstance(value, bytes) else value


def od(source: str) -> dict[str, Any]:
    server, ready = start_server([source])
    out: dict[str, Any] = {"ready": ready}
    try:
        master = open_preop(out)
        out["od"] = [[o.index, _text(o.name), o.object_code, o.data_type,
                      [[_text(e.name), e.data_type, e.bit_length, e.obj_access] for e in o.entries]]
                     for o in master.slaves[0].od]
        master.config_map()  # SOEM reads the PDO assignment by complete access where the SII says it may
        out["sizes"] = [len(master.slaves[0].output), len(master.slaves[0].input)]
        master.close()
    finally:
        out["server"] = stop_server(server)
    return out


#: what a frame fault does to one frame the master sent (the bus sees the result): see FrameFaults
FRAME_FAULTS = ("lost", "corrupt", "wkc")


class FrameFaults:
    """A link fault from the (AFTER+1)th frame on, until the link is restored (SIGUSR1, sent between the two
    commission runs: the cable is plugged back in). ``lost``: frames vanish; ``corrupt``: one bit flipped, the
    FCS does not match and the slave discards the frame (counting it); ``wkc``: process data frames (LRD,
    LWR, LRW) reach the bus with their working counter already raised by one, so they come back one too high."""

    def __init__(self, kind: str, after: int) -> None:
        self.kind, self.after, self.seen, self.restored = kind, after, 0, False

    def __call__(self, raw: bytes) -> tuple[bytes | None, bool]:
        from ecattool.sim.bus.frame import Cmd, parse_frame

        self.seen += 1
        if self.restored or self.seen <= self.after:
            return raw, True
        if self.kind == "lost":
            return None, True
        if self.kind == "corrupt":
            spoilt = bytearray(raw)
            spoilt[-1] ^= 0x10
            return bytes(spoilt), False
        frame = parse_frame(raw)
        if frame is None or not any(d.cmd in (Cmd.LRD, Cmd.LWR, Cmd.LRW) for d in frame.datagrams):
            return raw, True
        for d in frame.datagrams:
            if d.cmd in (Cmd.LRD, Cmd.LWR, Cmd.LRW):
                d.wkc += 1
        return frame.to_bytes(), True


def serve(project: str, spec: str) -> None:
    """Serve PROJECT with the fault SPEC armed: ``sdo-abort:NTH:CODE`` (the NTH SDO request from now is
    answered with abort CODE), ``al-refusal:STATE:CODE`` (the next request for STATE is refused with AL status
    code CODE), ``eeprom-power:WORDS`` (the power fails after WORDS more EEPROM words are written),
    ``mailbox-slow:STATE:MS:TIMES`` (the next TIMES mailbox requests in STATE are answered MS late), or
    ``lost|corrupt|wkc:AFTER`` (:class:`FrameFaults`)."""
    import signal

    from ecattool.od.model import EcState
    from ecattool.project.bus import devices_in_bus_order
    from ecattool.sim.bus.serve import serve as serve_bus
    from ecattool.sim.bus.serve import virtual_slaves

    served = virtual_slaves(devices_in_bus_order(project))
    faults = served[0].slave.drive.faults
    kind, *args = spec.split(":")
    frame_fault = None
    if kind == "sdo-abort":
        faults.abort_sdo(int(args[0]), int(args[1], 0))
    elif kind == "al-refusal":
        faults.refuse_state(EcState[args[0]], int(args[1], 0))
    elif kind == "eeprom-power":
        faults.power_loss_during_eeprom_write(int(args[0]))
    elif kind == "mailbox-slow":
        faults.slow_mailbox(EcState[args[0]], int(args[1]), int(args[2]))
    elif kind in FRAME_FAULTS:
        frame_fault = FrameFaults(kind, int(args[0]))

    def restore(signum: int, frame: object) -> None:
        if frame_fault is not None:
            frame_fault.restored = True

    signal.signal(signal.SIGUSR1, restore)

    def ready() -> None:
        print(json.dumps({"iface": SLAVE_IF, "slaves": [s.describe() for s in served]}), flush=True)

    serve_bus(served, SLAVE_IF, ready, fault=frame_fault)


def faults(cases: list[tuple[str, str]]) -> dict[str, Any]:
    """For each (PROJECT, SPEC), one after the other: a bus of its own with the fault armed, two commission
    runs against it (the link restored between them)."""
    import signal

    out = []
    for project, spec in cases:
        server, ready = start_server([project], [sys.executable, __file__, "serve", project, spec])
        runs = []
        try:
            for _ in range(2):
                done = subprocess.run([sys.executable, "-m", "ecattool", "commission", project, "--target",
                                       f"pysoem:{MASTER_IF}", "--json"], capture_output=True, text=True, timeout=240)
                runs.append({"returncode": done.returncode, "stdout": done.stdout, "stderr": done.stderr[-2000:]})
                server.send_signal(signal.SIGUSR1)
        finally:
            stopped = stop_server(server)
        out.append({"project": project, "fault": spec, "ready": ready, "runs": runs, "server": stopped})
    return {"cases": out}


#: commission through a pysoem target that does not cycle while it waits for an SDO (argv: PROJECT IFNAME)
_WITHOUT_KEEPER = """
import json, sys
from ecattool.commission.runner import commission
from ecattool.target.pysoem import PysoemTarget
target = PysoemTarget(sys.argv[2], keep_cycling=False)
try:
    report = commission(sys.argv[1], target)
finally:
    target.close()
print(json.dumps(report.to_json()))
sys.exit(0 if report.ok else 1)
"""


def watchdog(project: str, ms: str) -> dict[str, Any]:
    """PROJECT's drive answers its first SDO request in OP MS late (longer than its 100 ms process data
    watchdog), twice: commission through a target that stops the process data while it waits (the drive must
    leave OP with AL status code 0x001B and commission must say so), then ``ecattool commission`` (its
    pysoem target keeps the process data cycling: the drive stays in OP)."""
    spec = f"mailbox-slow:OP:{ms}:2"
    server, ready = start_server([project], [sys.executable, __file__, "serve", project, spec])
    runs = []
    try:
        for argv in ([sys.executable, "-c", _WITHOUT_KEEPER, project, MASTER_IF],
                     [sys.executable, "-m", "ecattool", "commission", project, "--target", f"pysoem:{MASTER_IF}",
                      "--json"]):
            done = subprocess.run(argv, capture_output=True, text=True, timeout=240)
            runs.append({"returncode": done.returncode, "stdout": done.stdout, "stderr": done.stderr[-2000:]})
    finally:
        stopped = stop_server(server)
    return {"project": project, "fault": spec, "ready": ready, "runs": runs, "server": stopped}


def _verify(sw: str) -> dict[str, Any]:
    done = subprocess.run([sys.executable, "-m", "ecattool", "sw", "verify", sw, "--target", f"pysoem:{MASTER_IF}",
                           "--json"], capture_output=True, text=True, timeout=120)
    return {"returncode": done.returncode, "stdout": done.stdout, "stderr": done.stderr[-2000:]}


def foe(project: str, sw: str) -> dict[str, Any]:
    """The setup image SW as an FoE setup file (``ecattool sw foe``) written by SOEM's ``foe_write`` (Technosoft
    §17.4: FOESW_ files, password 0, in PRE-OP) into the served drive of PROJECT: ``ecattool sw verify`` over
    the wire before (the drive's EEPROM differs) and after (it holds the image); first two write requests the
    drive refuses (a name without FOESW_, a wrong password)."""
    import pysoem

    from ecattool.sw import read, to_foe

    data = to_foe(read(sw))
    server, ready = start_server([project])
    out: dict[str, Any] = {"ready": ready, "bytes": len(data)}
    try:
        out["verify_before"] = _verify(sw)
        master = open_preop(out)
        slave = master.slaves[0]
        writes = []
        for name, password in (("setup.bin", 0), ("FOESW_AXIS1.bin", 7), ("FOESW_AXIS1.bin", 0)):
            try:
                writes.append({"name": name, "password": password,
                               "result": int(slave.foe_write(name, password, data, 5_000_000))})
            except Exception as exc:  # noqa: BLE001 - whatever pysoem raises is the result
                writes.append({"name": name, "password": password, "error": f"{type(exc).__name__}: {exc}"})
        out["writes"] = writes
        master.close()
        out["verify_after"] = _verify(sw)
    finally:
        out["server"] = stop_server(server)
    return out


if __name__ == "__main__":
    mode, args = sys.argv[1], sys.argv[2:]
    if mode != "serve":  # the served bus takes the server's priority itself (start_server)
        master_priority()
    if mode == "serve":
        serve(args[0], args[1])
    elif mode == "od":
        print(json.dumps(od(args[0])))
    elif mode == "watchdog":
        print(json.dumps(watchdog(args[0], args[1])))
    elif mode == "foe":
        print(json.dumps(foe(args[0], args[1])))
    else:  # faults PROJECT SPEC [PROJECT SPEC ...]
        print(json.dumps(faults(list(zip(args[::2], args[1::2])))))
