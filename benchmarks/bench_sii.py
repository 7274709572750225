"""Benchmark: ``ecattool sii build`` of one device of the 141-device beckhoff_EL1xxx.xml, as a whole
process, against a bare ``lxml.etree.parse`` of the same file plus Python start-up.

Each variant runs as its own process (interpreter start, imports, work), several times, interleaved;
the median wall time of each is reported with the ratio to the bare parse measured in the same run.
The aim (issue 8) is a ratio of at most 1.25. The ratio of the minimum times is printed too: on a loaded
machine it moves less than the medians.

    python benchmarks/bench_sii.py [FILE] [--device EL1008] [--runs 9] [--against DIR]

``--against DIR`` adds ``sii-build@DIR``: the same command run with the ``ecattool`` package found in DIR (e.g. an
older revision unpacked by ``git archive REV ecattool | tar -x -C DIR``), to compare two revisions in one run.

Variants:
  bare-parse  python -c "from lxml import etree; etree.parse(FILE)"
  sii-build   python -m ecattool sii build FILE --device EL1008 --policy newest -o OUT.bin
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

from _procs import ROOT, Variant, has_package, interleaved, report  # benchmarks/ is on sys.path as the script's folder

DEFAULT = ROOT.parent / "shared" / "corpus" / "esi" / "beckhoff_EL1xxx.xml"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("file", nargs="?", type=Path, default=DEFAULT)
    ap.add_argument("--device", default="EL1008")
    ap.add_argument("--runs", type=int, default=9)
    ap.add_argument("--against", type=Path, help="a directory holding another revision's ecattool package")
    args = ap.parse_args(argv)
    if not args.file.exists():
        print(f"benchmark file missing: {args.file}", file=sys.stderr)
        return 1
    if args.against is not None and not has_package(args.against):
        print(f"no ecattool package in {args.against}", file=sys.stderr)
        return 1
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out.bin"
        build = [sys.executable, "-m", "ecattool", "sii", "build", str(args.file), "--device", args.device,
                 "--policy", "newest", "-o", str(out), "--force"]  # each run replaces the previous image
        cmds: dict[str, Variant] = {
            "bare-parse": ([sys.executable, "-c", "import sys\nfrom lxml import etree\netree.parse(sys.argv[1])\n",
                            str(args.file)], None),
            "sii-build": (build, None),
        }
        if args.against is not None:
            # a revision older than the shared --force replaces without it (and knows no such flag)
            older = [*build[:-3], "-o", str(Path(tmp) / "older.bin")]
            cmds["sii-build@" + args.against.name] = (older, args.against.resolve())
        times = interleaved(cmds, args.runs, warmups=2)
        size = out.stat().st_size
    print(f"file: {args.file.name} ({args.file.stat().st_size} bytes), device {args.device} -> {size}-byte image, "
          f"{args.runs} runs each, median wall time per process")
    report(times, "bare-parse")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
