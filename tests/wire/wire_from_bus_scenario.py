"""Run inside a private network namespace (tests/wire/test_wire_from_bus.py starts it through ecattool.sim.bus.netns):
``ecattool sim serve PROJECT`` on one end of the veth pair, ecattool through pysoem on the other.

    python wire_from_bus_scenario.py PROJECT DIR   commission PROJECT (a drive in CSP on DC: it ends in OP), then
                                                   project new --from-bus --reset-bus (DIR/from-bus.yaml), lint
                                                   it, and commission the same bus with it; then the same
                                                   through KickCAT (DIR/from-bus-kickcat.yaml)

Prints one JSON document on stdout. Every wait and loop is bounded (each command has a timeout)."""

from __future__ import annotations

import importlib.util
import json
import subprocess
import sys
from pathlib import Path
from typing import Any

from wire_pysoem_scenario import MASTER_IF, master_priority, start_server, stop_server  # tests/ is the folder


def _ecattool(*args: str) -> dict[str, Any]:
    done = subprocess.run([sys.executable, "-m", "ecattool", *args], capture_output=True, text=True, timeout=300)
    return {"args": list(args), "returncode": done.returncode, "stdout": done.stdout, "stderr": done.stderr[-3000:]}


def main(project: str, folder: str) -> dict[str, Any]:
    target = f"pysoem:{MASTER_IF}"
    made = str(Path(folder) / "from-bus.yaml")
    server, ready = start_server([project])
    runs = []
    try:
        runs.append(_ecattool("commission", project, "--target", target, "--json"))
        # the bus runs as commissioned: the DC registers are read before pysoem's config_init resets them
        runs.append(_ecattool("project", "new", "--from-bus", target, "--reset-bus", "-o", made))
        runs.append(_ecattool("lint", made, "--format", "json"))
        runs.append(_ecattool("commission", made, "--target", target, "--json"))
        # through KickCAT, whose binding reads no SII: the SII is read through the ESC before the master opens,
        # and names the model among those sharing the product code
        if importlib.util.find_spec("kickcat") is not None:
            runs.append(_ecattool("project", "new", "--from-bus", f"kickcat:{MASTER_IF}", "--reset-bus", "-o",
                                  str(Path(folder) / "from-bus-kickcat.yaml")))
    finally:
        stopped = stop_server(server)
    return {"ready": ready, "runs": runs, "server": stopped}


if __name__ == "__main__":
    master_priority()
    print(json.dumps(main(*sys.argv[1:])))
