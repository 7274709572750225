"""Run inside a private network namespace (tests/test_wire_kickcat.py starts it through ecattool.sim.bus.netns):
faults of the mailbox over the wire. The virtual bus serves PROJECT with an SDO abort injected into its first
drive (the NTH SDO request from now is answered with abort CODE, once); ``ecattool commission --target
pysoem`` then runs twice against the same bus: the first run must report the abort and fail, the second must
converge.

    python wire_mailbox_faults_scenario.py PROJECT NTH CODE      # the two commission runs
    python wire_mailbox_faults_scenario.py serve PROJECT NTH CODE  # the faulty bus (started by the above)

Prints one JSON document on stdout. Every wait is bounded."""

from __future__ import annotations

import json
import subprocess
import sys
from typing import Any

from wire_pysoem_scenario import MASTER_IF, SLAVE_IF, start_server, stop_server  # tests/ is the script's folder


def serve(project: str, nth: int, code: int) -> None:
    from ecattool.sim.bus.serve import load_sources, serve as serve_bus

    served = load_sources([project])
    served[0].slave.drive.faults.abort_sdo(nth, code)

    def ready() -> None:
        print(json.dumps({"iface": SLAVE_IF, "slaves": [s.describe() for s in served]}), flush=True)

    serve_bus(served, SLAVE_IF, ready)


def run(project: str, nth: int, code: int) -> dict[str, Any]:
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
    if sys.argv[1] == "serve":
        serve(sys.argv[2], int(sys.argv[3]), int(sys.argv[4], 0))
    else:
        print(json.dumps(run(sys.argv[1], int(sys.argv[2]), int(sys.argv[3], 0))))
