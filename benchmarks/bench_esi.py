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
import sys
from pathlib import Path

from _procs import ROOT, Variant, has_package, interleaved, report  # benchmarks/ is on sys.path as the script's folder

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


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("file", nargs="?", type=Path, default=DEFAULT)
    ap.add_argument("--runs", type=int, default=15)
    ap.add_argument("--against", type=Path, help="a directory holding another revision's ecattool package")
    args = ap.parse_args(argv)
    if not args.file.exists():
        print(f"benchmark file missing: {args.file}", file=sys.stderr)
        return 1
    variants: dict[str, Variant] = {
        name: ([sys.executable, "-c", code, str(args.file)], None) for name, code in SCRIPTS.items()}
    if args.against is not None:
        if not has_package(args.against):
            print(f"no ecattool package in {args.against}", file=sys.stderr)
            return 1
        variants["esi-full@" + args.against.name] = (variants["esi-full"][0], args.against.resolve())
    cpu: dict[str, list[float]] = {}
    times = interleaved(variants, args.runs, cpu=cpu)
    print(f"file: {args.file.name} ({args.file.stat().st_size} bytes), {args.runs} runs each, median wall time per "
          "process; CPU time (user + system) per process")
    report(times, "bare-parse", cpu)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
