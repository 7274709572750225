"""Run inside a private network namespace (tests/test_wire_mailbox.py starts it through ecattool.sim.bus.netns):
the mailbox over the wire with SOEM (pysoem) as the master.

    python wire_mailbox_scenario.py od SOURCE                  # pysoem's slave.od, then config_map
    python wire_mailbox_scenario.py faults PROJECT NTH CODE    # two commission runs against a faulty bus
    python wire_mailbox_scenario.py serve PROJECT NTH CODE     # the faulty bus (started by 'faults')

``faults``: the virtual bus serves PROJECT with an SDO abort injected into its first drive (the NTH SDO
request from now is answered with abort CODE, once); ``ecattool commission --target pysoem`` then runs twice
against the same bus. ``od``: SOEM reads the object dictionary through SDO information (ecx_readODlist,
ecx_readODdescription, ecx_readOE).

Prints one JSON document on stdout. Every wait is bounded."""

from __future__ import annotations

import json
import subprocess
import sys
from typing import Any

from wire_pysoem_scenario import MASTER_IF, SLAVE_IF, start_server, stop_server  # tests/ is the script's folder


def _text(value: str | bytes) -> str:
    return value.decode("latin-1") if isinstance(value, bytes) else value


def od(source: str) -> dict[str, Any]:
    import pysoem

    server, ready = start_server([source])
    out: dict[str, Any] = {"ready": ready}
    try:
        master = pysoem.Master()
        master.open(MASTER_IF)
        out["found"] = master.config_init()
        master.state_check(pysoem.PREOP_STATE, 2_000_000)
        out["od"] = [[o.index, _text(o.name), o.object_code, o.data_type,
                      [[_text(e.name), e.data_type, e.bit_length, e.obj_access] for e in o.entries]]
                     for o in master.slaves[0].od]
        master.config_map()  # SOEM reads the PDO assignment by complete access where the SII says it may
        out["sizes"] = [len(master.slaves[0].output), len(master.slaves[0].input)]
        master.close()
    finally:
        out["server"] = stop_server(server)
    return out


def serve(project: str, nth: int, code: int) -> None:
    from ecattool.project.bus import devices_in_bus_order
    from ecattool.sim.bus.serve import serve as serve_bus
    from ecattool.sim.bus.serve import virtual_slaves

    served = virtual_slaves(devices_in_bus_order(project))
    served[0].slave.drive.faults.abort_sdo(nth, code)

    def ready() -> None:
        print(json.dumps({"iface": SLAVE_IF, "slaves": [s.describe() for s in served]}), flush=True)

    serve_bus(served, SLAVE_IF, ready)


def faults(project: str, nth: int, code: int) -> dict[str, Any]:
    server, ready = start_server([project], [sys.executable, __file__, "serve", project, str(nth), str(code)])
    runs = []
    try:
        for _ in range(2):
            done = subprocess.run([sys.executable, "-m", "ecattool", "commission", project, "--target",
                                   f"pysoem:{MASTER_IF}", "--json"], capture_output=True, text=True, timeout=240)
            runs.append({"returncode": done.returncode, "stdout": done.stdout, "stderr": done.stderr[-2000:]})
    finally:
        stopped = stop_server(server)
    return {"ready": ready, "runs": runs, "server": stopped}


if __name__ == "__main__":
    mode, args = sys.argv[1], sys.argv[2:]
    if mode == "serve":
        serve(args[0], int(args[1]), int(args[2], 0))
    elif mode == "od":
        print(json.dumps(od(args[0])))
    else:
        print(json.dumps(faults(args[0], int(args[1]), int(args[2], 0))))
