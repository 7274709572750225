"""SDO round trips per second: over the wire (SOEM through pysoem against ``ecattool sim serve`` on a veth
pair in a private network namespace), through the mailbox layer alone, in process, and python-canopen's
LocalNode — all in the same run, expedited 4-byte uploads of 1018h:01.

    .venv/bin/python benchmarks/bench_wire.py [--seconds 2]

Variants:
  canopen   python-canopen RemoteNode -> LocalNode on python-can's ``virtual`` bus (the baseline)
  drive     ecattool.sim.Drive.sdo_upload (the in-process simulator)
  mailbox   ecattool.sim.mailbox.MailboxServer: the request frame built, handled, the reply frame taken
  wire      pysoem ``sdo_read`` on one end of a veth pair, ``ecattool sim serve`` on the other (each round
            trip is two EtherCAT frame exchanges or more: write SM0, poll SM1 until the reply is there)

Needs the ``bench`` extra (canopen) and, for ``wire``, pysoem and a kernel that allows ``unshare -n``
(root here); the wire variant is skipped with the reason printed otherwise. Prints rates and ratios.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
HERE = Path(__file__).resolve()


def bench_canopen(seconds: float) -> float:
    import canopen
    from canopen.objectdictionary import ODVariable

    from bench_sim import canopen_remote  # benchmarks/ is on sys.path as the script's folder

    od = canopen.ObjectDictionary()
    var = ODVariable("Vendor ID", 0x1018, 1)
    var.data_type = canopen.objectdictionary.UNSIGNED32
    var.access_type = "ro"
    var.default = 0x289
    od.add_object(var)
    with canopen_remote(od, "ecattool-bench-wire") as remote:
        for _ in range(20):
            remote.sdo.upload(0x1018, 1)
        n, start = 0, time.perf_counter()
        while time.perf_counter() - start < seconds:
            remote.sdo.upload(0x1018, 1)
            n += 1
        return n / (time.perf_counter() - start)


def _drive():  # type: ignore[no-untyped-def]
    from ecattool.od.model import EcState
    from ecattool.sim import Drive

    drive = Drive.from_profile("hdt", record_events=False)
    drive.request_state(EcState.PREOP)
    return drive


def bench_drive(seconds: float) -> float:
    drive = _drive()
    n, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds:
        for _ in range(1000):
            drive.sdo_upload(0x1018, 1)
        n += 1000
    return n / (time.perf_counter() - start)


def bench_mailbox(seconds: float) -> float:
    import struct

    from ecattool.sim.mailbox import MailboxServer

    server = MailboxServer(_drive(), 128, 128)
    n, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds:
        for _ in range(1000):
            counter = n % 7 + 1
            server.handle(struct.pack("<HHBBHBHBI", 10, 0, 0, 0x03 | counter << 4, 0x2000, 0x40, 0x1018, 1, 0))
            reply = server.pending()
            assert reply is not None and reply[8] == 0x43
            n += 1
    return n / (time.perf_counter() - start)


def wire_inside(seconds: float) -> dict[str, float]:
    """Inside the namespace: serve hdt on ecat1, read 1018h:01 with pysoem on ecat0 for ``seconds``."""
    sys.path.insert(0, str(ROOT / "tests"))
    import pysoem
    from wire_pysoem_scenario import MASTER_IF, start_server, stop_server

    server, _ = start_server(["hdt"])
    try:
        master = pysoem.Master()
        master.open(MASTER_IF)
        assert master.config_init() == 1
        master.state_check(pysoem.PREOP_STATE, 2_000_000)
        slave = master.slaves[0]
        for _ in range(20):
            slave.sdo_read(0x1018, 1)
        n, start = 0, time.perf_counter()
        while time.perf_counter() - start < seconds:
            slave.sdo_read(0x1018, 1)
            n += 1
        rate = n / (time.perf_counter() - start)
        master.close()
    finally:
        stop_server(server)
    return {"wire": rate}


def bench_wire(seconds: float) -> float | str:
    try:
        import pysoem  # noqa: F401
    except ImportError:
        return "pysoem is not installed"
    from ecattool.sim.bus import netns

    why = netns.unavailable()
    if why:
        return why
    done = subprocess.run(netns.command([sys.executable, str(HERE), "--inside", "--seconds", str(seconds)]),
                          capture_output=True, text=True, timeout=120 + 2 * seconds, cwd=ROOT)
    if done.returncode:
        return "the wire run failed: " + done.stderr.strip()[-500:]
    return float(json.loads(done.stdout.strip().splitlines()[-1])["wire"])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=2.0)
    ap.add_argument("--inside", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.inside:
        print(json.dumps(wire_inside(args.seconds)))
        return
    rates: dict[str, float | str] = {"canopen": bench_canopen(args.seconds), "drive": bench_drive(args.seconds),
                                     "mailbox": bench_mailbox(args.seconds), "wire": bench_wire(args.seconds)}
    base = rates["canopen"]
    assert isinstance(base, float)
    for name, rate in rates.items():
        if isinstance(rate, str):
            print(f"{name:8s}: skipped ({rate})")
        else:
            print(f"{name:8s}: {rate:12,.0f} SDO uploads/s   {rate / base:8.2f} x canopen")


if __name__ == "__main__":
    main()
