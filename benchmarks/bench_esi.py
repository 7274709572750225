"""Benchmark: the full ESI model of the largest corpus file against a bare ``lxml.etree.parse``.

Each variant runs as a whole process (interpreter start, imports, work), several times, interleaved;
the median wall time of each is reported with the ratio to the bare parse measured in the same run.

    python benchmarks/bench_esi.py [FILE] [--runs 9]

Variants:
  bare-parse   python -c "from lxml import etree; etree.parse(FILE)"
  esi-load     ecattool.esi.load(FILE): every device, PDO, SM, DC, EEPROM, module; dictionaries on demand
  esi-full     esi-load plus building every object dictionary (all objects, entries, data types)
  esi-device   ecattool.esi.load_device(FILE, "EL1008", "newest"): the selective load (one device built,
               with its dictionary; vendor, groups and modules of the file read too)
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DEFAULT = ROOT.parent / "shared" / "corpus" / "esi" / "beckhoff_EL1xxx.xml"

SCRIPTS = {
    "bare-parse": "import sys\nfrom lxml import etree\netree.parse(sys.argv[1])\n",
    "esi-load": "import sys\nfrom ecattool.esi import load\nload(sys.argv[1])\n",
    "esi-full": (
        "import sys\nfrom ecattool.esi import load, materialize\n"
        "esi = load(sys.argv[1])\nn = materialize(esi)\nassert n > 0 or not esi.devices\n"
    ),
    "esi-device": (
        "import sys\nfrom ecattool.esi import load_device\n"
        "dev = load_device(sys.argv[1], 'EL1008', 'newest')\nlen(dev.dictionary)\n"
    ),
}


def _env() -> dict[str, str]:
    # measure ecattool as installed: byte-compiled modules (the warm-up run writes the .pyc files even
    # where the shell sets PYTHONDONTWRITEBYTECODE, which would otherwise recompile every module per run)
    env = dict(os.environ)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    return env


def run_once(code: str, path: Path) -> float:
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-c", code, str(path)], check=True, cwd=ROOT, env=_env())
    return time.perf_counter() - t0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("file", nargs="?", type=Path, default=DEFAULT)
    ap.add_argument("--runs", type=int, default=15)
    args = ap.parse_args(argv)
    if not args.file.exists():
        print(f"benchmark file missing: {args.file}", file=sys.stderr)
        return 1
    for code in SCRIPTS.values():  # warm the OS file cache and the .pyc files
        run_once(code, args.file)
    times: dict[str, list[float]] = {k: [] for k in SCRIPTS}
    for _ in range(args.runs):
        for name, code in SCRIPTS.items():
            times[name].append(run_once(code, args.file))
    base = statistics.median(times["bare-parse"])
    print(f"file: {args.file.name} ({args.file.stat().st_size} bytes), {args.runs} runs each, median wall time per process")
    for name, ts in times.items():
        med = statistics.median(ts)
        print(f"  {name:11s} {med * 1000:7.1f} ms   ratio {med / base:4.2f}x   (min {min(ts) * 1000:.1f} ms)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
