"""How long this machine stops a running program: a loop that only reads the clock, for a while, and the gaps it saw.

A gap is time between two consecutive clock reads of the loop (normally well under a microsecond). The loop
runs with the garbage collector off and allocates nothing, so a gap of a millisecond is time the process did not
run: either another task of this system took the CPU (the loop reads its involuntary context switches each time
round and marks such a gap) or the machine under this system stopped the virtual CPU (a gap with no switch; the
kernel's steal time may or may not count it). A bus master at 1 kHz that is stopped for a millisecond misses a
cycle whatever the served bus does, which is why ``bench_wire.py`` reports the master's late starts apart from
the frames that came back short.

    python benchmarks/machine_stalls.py [--seconds 30] [--over-us 200] [--json]

No privileges needed; nothing is sent anywhere. The loop is bounded by ``--seconds`` (at most 600).
"""

from __future__ import annotations

import argparse
import gc
import json
import resource
import time
from typing import Any

from _procs import steal_s  # benchmarks/ is on sys.path as the script's folder

#: the longest run --seconds allows
MAX_SECONDS = 600.0
#: how many of the longest gaps are listed
LISTED = 20


def probe(seconds: float, over_ns: int) -> dict[str, Any]:
    """Spin for ``seconds`` reading the clock; every gap longer than ``over_ns`` is recorded (at most 100,000)."""
    seconds = min(max(seconds, 0.1), MAX_SECONDS)
    clock = time.perf_counter_ns
    usage = resource.getrusage
    me = resource.RUSAGE_SELF
    gaps: list[tuple[int, int, bool]] = []  # (gap ns, at ns from the start, another task ran meanwhile)
    switches0 = usage(me).ru_nivcsw
    steal0 = steal_s() * 1000
    enabled = gc.isenabled()
    gc.disable()
    try:
        start = last = clock()
        before = switches = switches0
        end = start + int(seconds * 1e9)
        while last < end:
            # the clock, then the count of switches, each time round: a switch inside the gap from the last read
            # to this one is counted by this count and not by the one read before the last clock read (the kernel
            # often switches on the way out of a system call, after the count was taken). A switch just before
            # the gap marks it too: a marked gap may be the machine's, an unmarked one is
            now = clock()
            counted = usage(me).ru_nivcsw
            if now - last > over_ns and len(gaps) < 100_000:
                gaps.append((now - last, now - start, counted != before))
            last, before, switches = now, switches, counted
    finally:
        if enabled:
            gc.enable()
    over_1ms = [g for g in gaps if g[0] >= 1_000_000]
    return {"seconds": seconds, "over_us": over_ns / 1000, "gaps": len(gaps), "gaps_over_1ms": len(over_1ms),
            "gaps_over_1ms_without_switch": sum(1 for g in over_1ms if not g[2]),
            "longest_ms": max((g[0] for g in gaps), default=0) / 1e6,
            "stopped_ms": sum(g[0] for g in gaps) / 1e6, "involuntary_switches": switches - switches0,
            "steal_ms": steal_s() * 1000 - steal0,
            "longest": [[round(g / 1e6, 3), round(at / 1e9, 3), switched]
                        for g, at, switched in sorted(gaps, reverse=True)[:LISTED]]}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--seconds", type=float, default=30.0, help=f"how long the loop runs (at most {MAX_SECONDS:g})")
    ap.add_argument("--over-us", type=float, default=200.0, help="the shortest gap recorded, in microseconds")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    out = probe(args.seconds, int(args.over_us * 1000))
    if args.json:
        print(json.dumps(out))
        return 0
    print(f"{out['seconds']:g} s of a loop reading the clock: {out['gaps']} gaps over {out['over_us']:g} us, "
          f"{out['gaps_over_1ms']} of 1 ms or more, the longest {out['longest_ms']:.3f} ms, "
          f"{out['stopped_ms']:.1f} ms stopped in all")
    print(f"  {out['gaps_over_1ms_without_switch']} of those of 1 ms or more with no other task of this system "
          f"running (the machine stopped the virtual CPU); the loop's involuntary context switches: "
          f"{out['involuntary_switches']}; the machine's steal time meanwhile: {out['steal_ms']:.0f} ms")
    if out["longest"]:
        print("  longest gaps (ms at s, * another task ran): "
              + ", ".join(f"{g:g} at {at:g}{'*' if sw else ''}" for g, at, sw in out["longest"][:10]))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
