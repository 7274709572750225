"""SDO downloads per second: the embedded simulator vs python-canopen's LocalNode on its virtual bus.

Both run in the same process and the same run: python-canopen's RemoteNode SDO client talks to a LocalNode
over python-can's ``virtual`` interface (expedited 4-byte downloads), the simulator takes the same
downloads through :meth:`ecattool.sim.Drive.sdo_download` (checks, handlers and event log included).

    .venv/bin/python benchmarks/bench_sim.py [--seconds 2]

Needs the ``bench`` extra (``pip install canopen``). Prints the rates and the ratio.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any


@contextmanager
def canopen_remote(channel: str = "ecattool-bench") -> Iterator[Any]:
    """A python-canopen RemoteNode talking to a LocalNode (607Ah, INTEGER32 rw) over python-can's virtual bus."""
    import canopen
    from canopen.objectdictionary import ODVariable

    od = canopen.ObjectDictionary()
    var = ODVariable("Target position", 0x607A, 0)
    var.data_type = canopen.objectdictionary.INTEGER32
    var.access_type = "rw"
    od.add_object(var)
    server, client = canopen.Network(), canopen.Network()
    server.connect(interface="virtual", channel=channel, receive_own_messages=False)
    client.connect(interface="virtual", channel=channel, receive_own_messages=False)
    try:
        server.add_node(canopen.LocalNode(1, od))
        remote = canopen.RemoteNode(1, od)
        client.add_node(remote)
        for i in range(20):  # warm up
            remote.sdo.download(0x607A, 0, i.to_bytes(4, "little"))
        yield remote
    finally:
        client.disconnect()
        server.disconnect()


def bench_canopen(seconds: float) -> float:
    with canopen_remote() as remote:
        n = 0
        start = time.perf_counter()
        while time.perf_counter() - start < seconds:
            remote.sdo.download(0x607A, 0, (n & 0x7FFFFFFF).to_bytes(4, "little"))
            n += 1
        return n / (time.perf_counter() - start)


def bench_sim(seconds: float) -> float:
    from ecattool.od.model import EcState
    from ecattool.sim import Drive

    drive = Drive.from_profile("technosoft-ipos")
    drive.request_state(EcState.PREOP)
    n = 0
    start = time.perf_counter()
    while time.perf_counter() - start < seconds:
        for _ in range(1000):
            drive.sdo_download(0x607A, 0, (n & 0x7FFFFFFF).to_bytes(4, "little"))
            n += 1
        drive.events.clear()  # keep the event log from growing without bound during the run
    return n / (time.perf_counter() - start)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=2.0)
    args = ap.parse_args()
    base = bench_canopen(args.seconds)
    ours = bench_sim(args.seconds)
    print(f"python-canopen LocalNode (virtual bus): {base:12,.0f} SDO downloads/s")
    print(f"ecattool.sim Drive                    : {ours:12,.0f} SDO downloads/s")
    print(f"ratio                                 : {ours / base:12.1f} x")


if __name__ == "__main__":
    main()
