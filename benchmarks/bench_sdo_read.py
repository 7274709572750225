"""``ecattool sdo read`` of one object against a bare pysoem script doing the same (issue 35 item 5, issue 37
item 1): each a fresh process, side by side in one run, against one drive served by ``ecattool sim serve`` over
a veth pair in a private network namespace that the script makes itself (never the host's interfaces).

* bare: ``python -c "import pysoem; m = pysoem.Master(); m.open(IF); m.config_init(); m.slaves[0].sdo_read(0x1018,
  1); m.close()"``;
* ecattool: ``python -m ecattool sdo read 0x1018:01 --target pysoem:IF`` (the master in its child process,
  ecattool.target.isolated; the bus state read before and restored after; the value typed by the CiA-301 table);
* ecattool through a held bus: the same command line on a second veth pair of the namespace (``HELD_IF``, the same
  drive served behind it), whose master ``ecattool bus hold`` keeps open (ecattool.online.held): the read goes to
  the holder, no bus init, no master library loaded; as IgH's ``ethercat upload`` reads through the master that
  owns its bus.

The two alternate (bare, ecattool, bare, …) so that a busy machine slows both alike; the figures are the median
and the lower quartile wall time of a whole process, and their ratio, and the median CPU time of each (its own and
its children's: a loaded machine's wall times follow it). A third command in the same rounds is the floor of any
click command line that reads through pysoem, ``python -c "import click, pysoem"`` (no bus, no ecattool).
``--against DIR``: one more command in the same rounds, ``sdo read`` of the package in DIR (another revision:
``git archive REV ecattool | tar -x -C DIR``), run from DIR with this interpreter.

    .venv/bin/python benchmarks/bench_sdo_read.py [--rounds 15] [--against DIR] [--json]

Needs the ``wire`` extra (pysoem) and root (or unprivileged user namespaces). Every loop is bounded in count.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
MASTER_IF, SLAVE_IF = "ecat0", "ecat1"
#: the second veth pair: its master held by ``ecattool bus hold`` for the whole run
HELD_IF, HELD_SLAVE_IF = "ecat2", "ecat3"
BARE = ("import pysoem\nm = pysoem.Master()\nm.open({iface!r})\nassert m.config_init() > 0\n"
        "print(int.from_bytes(m.slaves[0].sdo_read(0x1018, 1), 'little'))\nm.close()\n")


#: as an installed package runs: with its compiled modules cached (this machine's environment sets
#: PYTHONDONTWRITEBYTECODE, which makes every start compile ecattool's sources again; pysoem is compiled code)
ENV = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}


#: the CPU time of every process run (and reaped) so far, in seconds, per command
CPU: dict[str, list[float]] = {}


def _cpu_s() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _timed(argv: list[str], where: str | None = None, name: str = "") -> tuple[float, str]:
    """One whole process's wall time and its output; ``where``: the checkout whose package runs (``-m`` puts the
    working directory first on the path); ``name``: its CPU time is kept under that name in :data:`CPU`."""
    env = ENV if where is None else dict(ENV, PYTHONPATH=where)
    cpu0 = _cpu_s()
    t0 = time.perf_counter()
    done = subprocess.run(argv, capture_output=True, text=True, timeout=60, cwd=where or ROOT, env=env)
    took = time.perf_counter() - t0
    if name:
        CPU.setdefault(name, []).append(_cpu_s() - cpu0)
    if done.returncode != 0:
        raise SystemExit(f"{argv[:4]} failed: {done.stderr[-1000:]}")
    return took, done.stdout.strip()


def _started(argv: list[str], what: str) -> subprocess.Popen[str]:
    """A process that says it is ready with a first line on its stdout (``sim serve``, ``bus hold``)."""
    import select

    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT, env=ENV)
    assert proc.stdout is not None
    ready, _, _ = select.select([proc.stdout], [], [], 60)
    if not ready or not proc.stdout.readline():
        proc.kill()
        raise SystemExit(f"{what} did not get ready: {proc.stderr.read()[-1000:] if proc.stderr else ''}")
    return proc


def inside(rounds: int, against: str | None = None) -> dict[str, Any]:
    from ecattool.sim.bus import netns

    subprocess.run(["sh", "-c", netns.pair_script(HELD_IF, HELD_SLAVE_IF)], check=True)  # in the namespace
    procs = [_started([sys.executable, "-m", "ecattool", "sim", "serve", "hdt", "--iface", SLAVE_IF], "the server")]
    try:
        procs.append(_started([sys.executable, "-m", "ecattool", "sim", "serve", "hdt", "--iface", HELD_SLAVE_IF],
                              "the second server"))
        procs.append(_started([sys.executable, "-m", "ecattool", "bus", "hold", "--target", f"pysoem:{HELD_IF}",
                               "--for", str(120 + 10 * rounds), "--json"], "the holder"))
        held_argv = [sys.executable, "-m", "ecattool", "sdo", "read", "0x1018:01", "--target", f"pysoem:{HELD_IF}"]
        bare_argv = [sys.executable, "-c", BARE.format(iface=MASTER_IF)]
        tool_argv = [sys.executable, "-m", "ecattool", "sdo", "read", "0x1018:01", "--target", f"pysoem:{MASTER_IF}"]
        _timed(bare_argv)  # the link's first frames, the page cache: not measured
        _timed(tool_argv)
        _timed(held_argv)
        if against:
            _timed(tool_argv, against)
        floor_argv = [sys.executable, "-c", "import click, pysoem"]
        bare, tool, other, floor, through = [], [], [], [], []
        outputs = set()
        for _ in range(rounds):
            t, out = _timed(bare_argv, name="bare")
            bare.append(t)
            outputs.add(("bare", out))
            t, out = _timed(tool_argv, name="ecattool")
            tool.append(t)
            outputs.add(("ecattool", out.split(" = ")[1].split(" ")[0] if " = " in out else out))
            floor.append(_timed(floor_argv, name="floor")[0])
            t, out = _timed(held_argv, name="held")
            through.append(t)
            outputs.add(("held", out.split(" = ")[1].split(" ")[0] if " = " in out else out))
            if against:
                t, out = _timed(tool_argv, against, name="against")
                other.append(t)
                outputs.add(("against", out.split(" = ")[1].split(" ")[0] if " = " in out else out))
    finally:
        for proc in reversed(procs):  # the holder first: it closes its master before its server goes
            proc.terminate()
            proc.wait(30)

    def fig(xs: list[float]) -> dict[str, float]:
        q = statistics.quantiles(xs, n=4)
        return {"median_s": round(statistics.median(xs), 4), "q1_s": round(q[0], 4), "min_s": round(min(xs), 4)}

    b, e, f, h = fig(bare), fig(tool), fig(floor), fig(through)
    cpu = {name: round(statistics.median(xs), 4) for name, xs in CPU.items()}
    result = {"rounds": rounds, "bare_pysoem": b, "ecattool_sdo_read": e,
              "ratio_median": round(e["median_s"] / b["median_s"], 2), "ratio_q1": round(e["q1_s"] / b["q1_s"], 2),
              "import_click_pysoem": f, "floor_ratio_median": round(f["median_s"] / b["median_s"], 2),
              "cpu_median_s": cpu, "cpu_ratio": round(cpu["ecattool"] / cpu["bare"], 2),
              "floor_cpu_ratio": round(cpu["floor"] / cpu["bare"], 2),
              "held_sdo_read": h, "held_ratio_median": round(h["median_s"] / b["median_s"], 2),
              "held_ratio_q1": round(h["q1_s"] / b["q1_s"], 2), "held_cpu_ratio": round(cpu["held"] / cpu["bare"], 2),
              "values": sorted(outputs), "loadavg": os.getloadavg()}
    if against:
        a = fig(other)
        result.update(against=against, against_sdo_read=a,
                      against_ratio_median=round(a["median_s"] / b["median_s"], 2),
                      against_ratio_q1=round(a["q1_s"] / b["q1_s"], 2))
    return result


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=15)
    ap.add_argument("--against", metavar="DIR", help="also time the sdo read of the package in DIR (another revision)")
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--inside", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    rounds = max(3, min(args.rounds, 200))
    against = str(Path(args.against).resolve()) if args.against else None
    if against and not (Path(against) / "ecattool" / "__main__.py").is_file():
        raise SystemExit(f"--against {args.against}: no ecattool package there")
    if args.inside:
        print(json.dumps(inside(rounds, against)))
        return
    sys.path.insert(0, str(ROOT))
    from ecattool.sim.bus import netns

    reason = netns.unavailable()
    if reason:
        raise SystemExit(f"cannot make a private network namespace: {reason}")
    argv = netns.command([sys.executable, __file__, "--inside", "--rounds", str(rounds),
                          *(["--against", against] if against else [])])
    done = subprocess.run(argv, capture_output=True, text=True, timeout=60 + 30 * rounds, cwd=ROOT)
    if done.returncode != 0:
        raise SystemExit(done.stderr[-2000:])
    result = json.loads(done.stdout.strip().splitlines()[-1])
    if args.json:
        print(json.dumps(result, indent=2))
        return
    b, e = result["bare_pysoem"], result["ecattool_sdo_read"]
    print(f"{rounds} rounds, load average {' '.join(f'{x:.1f}' for x in result['loadavg'])}")
    print(f"bare pysoem script     median {b['median_s'] * 1000:7.1f} ms   lower quartile {b['q1_s'] * 1000:7.1f} ms")
    print(f"ecattool sdo read      median {e['median_s'] * 1000:7.1f} ms   lower quartile {e['q1_s'] * 1000:7.1f} ms")
    print(f"ratio                  median {result['ratio_median']:.2f}x      lower quartile {result['ratio_q1']:.2f}x")
    h = result["held_sdo_read"]
    print(f"through bus hold       median {h['median_s'] * 1000:7.1f} ms   lower quartile {h['q1_s'] * 1000:7.1f} ms   "
          f"ratio {result['held_ratio_median']:.2f}x (lower quartiles {result['held_ratio_q1']:.2f}x, CPU "
          f"{result['held_cpu_ratio']:.2f}x)")
    f, cpu = result["import_click_pysoem"], result["cpu_median_s"]
    print(f"import click, pysoem   median {f['median_s'] * 1000:7.1f} ms   ({result['floor_ratio_median']:.2f}x of the "
          "bare script: the floor of a click command line)")
    print("CPU time, medians      " + ", ".join(f"{k} {v * 1000:.1f} ms" for k, v in cpu.items()) +
          f"; ecattool {result['cpu_ratio']:.2f}x, the floor {result['floor_cpu_ratio']:.2f}x of the bare script")
    if against:
        a = result["against_sdo_read"]
        print(f"--against sdo read     median {a['median_s'] * 1000:7.1f} ms   "
              f"lower quartile {a['q1_s'] * 1000:7.1f} ms   ({against})")
        print(f"its ratio              median {result['against_ratio_median']:.2f}x      lower quartile "
              f"{result['against_ratio_q1']:.2f}x")
    print(f"values read: {result['values']}")


if __name__ == "__main__":
    main()
