"""Benchmark: the full ESI model of the largest corpus file against a bare ``lxml.etree.parse``.

Each variant runs as a whole process (interpreter start, imports, work), several times, interleaved;
the median wall time of each is reported with the ratio to the bare parse measured in the same run.

    python benchmarks/bench_esi.py [FILE] [--runs 9] [--against DIR]

``--against DIR`` adds ``esi-full@DIR``: esi-full with the ``ecattool`` package found in DIR (e.g. an older
revision unpacked by ``git archive REV ecattool | tar -x -C DIR``), to compare two revisions in one run.
The ratio of the minimum times is printed too: on a loaded machine it moves less than the medians.

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


def _env(package_dir: Path | None = None) -> dict[str, str]:
    # measure ecattool as installed: byte-compiled modules (the warm-up run writes the .pyc files even
    # where the shell sets PYTHONDONTWRITEBYTECODE, which would otherwise recompile every module per run)
    env = dict(os.environ)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    if package_dir is not None:
        env["PYTHONPATH"] = str(package_dir)
    return env


def run_once(code: str, path: Path, package_dir: Path | None = None) -> float:
    # another revision's package: run outside the repository so that its ecattool is found first
    cwd = package_dir if package_dir is not None else ROOT
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-c", code, str(path)], check=True, cwd=cwd, env=_env(package_dir))
    return time.perf_counter() - t0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("file", nargs="?", type=Path, default=DEFAULT)
    ap.add_argument("--runs", type=int, default=15)
    ap.add_argument("--against", type=Path, help="a directory holding another revision's ecattool package")
    args = ap.parse_args(argv)
    if not args.file.exists():
        print(f"benchmark file missing: {args.file}", file=sys.stderr)
        return 1
    variants: dict[str, tuple[str, Path | None]] = {name: (code, None) for name, code in SCRIPTS.items()}
    if args.against is not None:
        if not (args.against / "ecattool" / "__init__.py").is_file():
            print(f"no ecattool package in {args.against}", file=sys.stderr)
            return 1
        variants["esi-full@" + args.against.name] = (SCRIPTS["esi-full"], args.against.resolve())
    for code, package_dir in variants.values():  # warm the OS file cache and the .pyc files
        run_once(code, args.file, package_dir)
    times: dict[str, list[float]] = {k: [] for k in variants}
    for _ in range(args.runs):
        for name, (code, package_dir) in variants.items():
            times[name].append(run_once(code, args.file, package_dir))
    base = statistics.median(times["bare-parse"])
    base_min = min(times["bare-parse"])
    print(f"file: {args.file.name} ({args.file.stat().st_size} bytes), {args.runs} runs each, median wall time per process")
    for name, ts in times.items():
        med = statistics.median(ts)
        print(f"  {name:16s} {med * 1000:7.1f} ms   ratio {med / base:4.2f}x   "
              f"(min {min(ts) * 1000:.1f} ms, ratio of minima {min(ts) / base_min:4.2f}x)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
