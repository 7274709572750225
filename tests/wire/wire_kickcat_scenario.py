"""Run inside a private network namespace (tests/wire/test_wire_mailbox.py starts it through ecattool.sim.bus.netns):
``ecattool sim serve PROJECT...`` on one end of the veth pair, KickCAT's Python master (the ``kickcat``
package) on the other: bus init, identity by SDO reads of 1018h, the projects' PRE-OP -> SAFE-OP startup SDOs
(their PDO mappings) written through KickCAT's mailbox, the mapping KickCAT reads back over SDO, SAFE-OP, OP
with process data, an SDO read in OP, INIT.

    python wire_kickcat_scenario.py PROJECT...

Prints one JSON document on stdout: what was reached, and ``error`` = the step that failed and why. Every wait
is bounded."""

from __future__ import annotations

import json
import sys
import time
from typing import Any

from wire_pysoem_scenario import MASTER_IF, master_priority, start_server, stop_server  # tests/ is the script's folder

#: mailbox polls KickCAT may take for one SDO (each poll is one exchange of frames with the bus)
POLLS = 5000
#: how long KickCAT waits for a frame to come back: its default suits a hardware slave, the virtual bus is a
#: Python process on a shared (often loaded) 2-core machine
LINK_TIMEOUT_S = 0.25
#: during bus init: KickCAT's broadcast read/write (writeThenRead) waits the whole timeout for the copy of the
#: frame from a redundant port even when it has none, once per SII read (about 300 per slave line), so init
#: runs with a short timeout, and once more with a longer one if a frame came too late on a loaded machine
INIT_TIMEOUTS_S = (0.02, 0.1)
SDO_TIMEOUT_S = 3.0
#: the process data watchdog KickCAT programs into every slave (Bus.init's argument writes 0x0400/0x0420). KickCAT's
#: wait_for_state runs the process data once per poll of the slaves' states and waits between polls: here the drive
#: saw 251 ms between two writes of its outputs, and its watchdog (100 ms with init(0.1)) took it out of OP again
#: (AL 0x001B), as a real drive's would. The watchdog must be longer than the master's slowest cycle.
WATCHDOG_S = 1.0
STATE_TIMEOUT_S = 10.0


def init_bus() -> Any:
    """A KickCAT bus on MASTER_IF, initialised (each try with a longer link timeout: the first frames of a fresh
    namespace can come late), its link then at LINK_TIMEOUT_S."""
    import kickcat

    link = kickcat.create_link(MASTER_IF, "")
    bus = kickcat.Bus(link)
    for attempt, timeout in enumerate(INIT_TIMEOUTS_S):
        link.set_timeout(timeout)
        try:
            bus.init(WATCHDOG_S)
            break
        except RuntimeError:
            if attempt == len(INIT_TIMEOUTS_S) - 1:
                raise
    link.set_timeout(LINK_TIMEOUT_S)
    return bus


def run(projects: list[str]) -> dict[str, Any]:
    import kickcat
    from kickcat import State
    from kickcat.mailbox.request import MessageStatus

    from ecattool.project.export import slave_configs

    server, ready = start_server(projects)
    out: dict[str, Any] = {"ready": ready, "error": None}
    step = "init"
    try:
        bus = init_bus()
        slaves = bus.slaves()
        out["found"] = len(slaves)
        step = "identity"
        out["identity"] = [[int.from_bytes(bus.read_sdo(s, 0x1018, sub, kickcat.Access.PARTIAL, 4, SDO_TIMEOUT_S),
                                           "little") for sub in (1, 2, 3)] for s in slaves]
        step = "startup"
        configs = [c for p in projects for c in slave_configs(p)]
        writes: list[list[Any]] = []
        for s, cfg in zip(slaves, configs):
            for cmd in cfg.commands:
                if cmd.transition != "PS":
                    continue
                msg = s.mailbox.write_sdo(cmd.index, cmd.subindex, cmd.complete_access, cmd.data, SDO_TIMEOUT_S)
                for _ in range(POLLS):
                    if msg.status() != MessageStatus.RUNNING:
                        break
                    bus.process_mailboxes()
                writes.append([cmd.index, cmd.subindex, msg.status()])
        out["writes"] = writes
        step = "mapping"
        bus.create_mapping()  # KickCAT reads 1C00h, 1C12h/1C13h and the PDO mappings back over SDO
        out["sizes"] = [[s.output_size, s.input_size] for s in slaves]
        step = "SAFE-OP"
        bus.request_state(State.SAFE_OP)
        bus.wait_for_state(State.SAFE_OP, STATE_TIMEOUT_S)
        out["safeop"] = True
        for s in slaves:
            if s.output_size:
                s.set_output_bytes(bytes(s.output_size))
        bus.process_data_no_check()
        step = "OP"
        bus.request_state(State.OPERATIONAL)
        bus.wait_for_state(State.OPERATIONAL, STATE_TIMEOUT_S, bus.process_data_no_check)
        out["op"] = [bus.get_state(s) == State.OPERATIONAL for s in slaves]
        step = "process data"
        errors = 0
        for _ in range(100):  # bounded: 100 cycles of process data with working-counter checks
            try:
                bus.process_data()
            except Exception:  # KickCAT raises on a wrong working counter or a lost frame
                errors += 1
            time.sleep(0.001)
        out["pd_errors"] = errors
        step = "SDO in OP"
        out["op_sdo"] = [bus.read_sdo(s, 0x1018, 1, kickcat.Access.PARTIAL, 4, SDO_TIMEOUT_S).hex() for s in slaves]
        step = "INIT"
        bus.request_state(State.INIT)
        bus.wait_for_state(State.INIT, STATE_TIMEOUT_S)
        out["init"] = True
    except Exception as exc:  # KickCAT's errors (ErrorAL, ErrorCoE, RuntimeError) end the run: report which step
        out["error"] = f"{step}: {type(exc).__name__}: {exc}"
    finally:
        out["server"] = stop_server(server)
    return out


if __name__ == "__main__":
    master_priority()  # as wire_pysoem_scenario: the master gets the CPU on a busy machine
    print(json.dumps(run(sys.argv[1:])))
