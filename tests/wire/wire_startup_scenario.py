"""Run inside a private network namespace (tests/wire/test_wire_startup.py starts it through ecattool.sim.bus.netns):
for each sample project, the pysoem module ``ecattool startup export --project P --format pysoem`` wrote is
imported as written and used the way its docstring says, against ``ecattool sim serve P`` on the other end of
the veth pair, up to OP; then every value it wrote is read back over SDO.

    python wire_startup_scenario.py PROJECT=MODULE.py ...

Prints one JSON document on stdout. Every wait is bounded."""

from __future__ import annotations

import importlib.util
import json
import os
import re
import sys
from typing import Any

from wire_pysoem_scenario import MASTER_IF, master_priority, reach_op, start_server, stop_server

WRITE = re.compile(r"slave\.sdo_write\(0x([0-9A-F]{4}), 0x([0-9A-F]{2}), bytes\.fromhex\('([0-9a-f]*)'\)")


def run_module(project: str, module_path: str) -> dict[str, Any]:
    import pysoem

    spec = importlib.util.spec_from_file_location(f"startup_{len(project)}_{os.getpid()}", module_path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    server, _ = start_server([project])
    out: dict[str, Any] = {"project": project}
    try:
        master = pysoem.Master()
        master.open(MASTER_IF)  # the usage the module's docstring gives
        out["found"] = master.config_init()
        module.install(master)
        master.config_map()
        module.to_safe_op(master)  # starts the distributed clocks, then requests SAFE-OP
        out["safeop"] = master.state_check(pysoem.SAFEOP_STATE, 2_000_000) == pysoem.SAFEOP_STATE
        # every value the module wrote, as the drive holds it in SAFE-OP (the last write of each
        # entry; in OP the outputs would overwrite the objects mapped to the RxPDOs)
        written: dict[str, str] = {}
        with open(module_path, encoding="utf-8") as f:
            for m in WRITE.finditer(f.read()):
                written[f"{m.group(1)}:{m.group(2)}"] = m.group(3)
        readback = {}
        for key in written:
            index, sub = (int(p, 16) for p in key.split(":"))
            try:
                readback[key] = bytes(master.slaves[0].sdo_read(index, sub)).hex()
            except pysoem.SdoError as exc:
                readback[key] = f"abort:{exc.abort_code:08X}"
        out["written"], out["readback"] = written, readback
        reach_op(master)
        out["op"] = master.read_state() == pysoem.OP_STATE
        out["al_status_code"] = [s.al_status for s in master.slaves]
        master.state = pysoem.INIT_STATE
        master.write_state()
        master.close()
    finally:
        out["server"] = stop_server(server)
    return out


if __name__ == "__main__":
    master_priority()  # see wire_pysoem_scenario: SOEM gives a frame 2 ms to come back
    runs = [run_module(*arg.split("=", 1)) for arg in sys.argv[1:]]
    print(json.dumps({"runs": runs}))
