#!/usr/bin/env python3
"""Benchmark: lint a generated 64-drive project, cold (empty ESI cache) and warm (cache filled).

Each run is a whole `ecattool lint` process, so start-up and imports count. The baseline in the same run is
a bare `lxml.etree.parse` of every distinct ESI the project uses (what any tool must at least pay cold).

    python benchmarks/bench_lint.py [--runs 5] [--against DIR]

``--against DIR`` lints the same project with the ``ecattool`` package found in DIR too (another revision,
unpacked by ``git archive REV ecattool | tar -x -C DIR``), cold and warm with its own cache, interleaved with
this checkout's runs; both then run as ``python -m ecattool`` so they start the same way.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CORPUS = ROOT.parent / "shared" / "corpus"
ESIS = [
    ("elmo_Elmo_ECAT_00010420_V11.xml", "0x00030924:1"),
    ("inovance_SV660_EOE_1Axis_V9.12.xml", None),
    ("ingenia_eve-xcr-e_esi.xml", None),
    ("synapticon_Somanet_CiA402-single.xml", None),
]
PROFILES = ["technosoft-ipos", "hdt", "controltechniques"]


def make_project(directory: Path, drives: int = 64) -> Path:
    lines = ["ecattool: 1", "name: bench-64", "drives:"]
    for name, _ in ESIS:
        shutil.copy(CORPUS / "esi" / name, directory / name)
    for i in range(drives):
        kind = i % (len(ESIS) + len(PROFILES))
        lines.append(f"  - name: axis{i}")
        if kind < len(ESIS):
            esi, sel = ESIS[kind]
            lines.append(f"    device: {{esi: {esi}" + (f", select: \"{sel}\"" if sel else "") + "}")
        else:
            lines.append(f"    device: {{profile: {PROFILES[kind - len(ESIS)]}}}")
        lines.append("    parameters:")
        lines.append("      - {object: \"6060:00\", value: 8}")
    p = directory / "project.yaml"
    p.write_text("\n".join(lines) + "\n")
    return p


def timed(cmd: list[str], env: dict[str, str]) -> float:
    t = time.perf_counter()
    subprocess.run(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)
    return time.perf_counter() - t


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--against", type=Path, help="a directory holding another revision's ecattool package")
    args = ap.parse_args()
    if args.against is not None and not (args.against / "ecattool" / "__init__.py").is_file():
        print(f"no ecattool package in {args.against}", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        project = make_project(d)
        # (label, command, package directory put first on PYTHONPATH, cache directory)
        lints: list[tuple[str, list[str], Path | None, Path]] = []
        if args.against is None:
            lints.append(("ecattool lint", [str(Path(sys.executable).parent / "ecattool")], None, d / "cache"))
        else:
            lints.append(("ecattool lint", [sys.executable, "-m", "ecattool"], None, d / "cache"))
            lints.append((f"lint@{args.against.name}", [sys.executable, "-m", "ecattool"], args.against.resolve(),
                          d / "cache-against"))
        baseline_code = "import lxml.etree as e,sys\nfor f in sys.argv[1:]: e.parse(f)"
        esis = [str(d / n) for n, _ in ESIS]
        base: list[float] = []
        cold: dict[str, list[float]] = {label: [] for label, *_ in lints}
        warm: dict[str, list[float]] = {label: [] for label, *_ in lints}
        for _ in range(args.runs):
            base.append(timed([sys.executable, "-c", baseline_code, *esis], dict(os.environ)))
            for label, cmd, package, cache in lints:
                env = {**os.environ, "ECATTOOL_CACHE_DIR": str(cache)}
                if package is not None:
                    env["PYTHONPATH"] = str(package)
                shutil.rmtree(cache, ignore_errors=True)
                cold[label].append(timed([*cmd, "lint", str(project)], env))
                warm[label].append(timed([*cmd, "lint", str(project)], env))
        b = statistics.median(base)
        print(f"64-drive project, median of {args.runs} runs (whole processes)")
        print(f"  bare lxml parse of the {len(esis)} ESI files: {b * 1000:8.1f} ms")
        for label, *_ in lints:
            c, w = statistics.median(cold[label]), statistics.median(warm[label])
            print(f"  {label + ', cold cache:':<40} {c * 1000:8.1f} ms  ({c / b:.2f}x the bare parse)")
            print(f"  {label + ', warm cache:':<40} {w * 1000:8.1f} ms  ({w / b:.2f}x the bare parse, "
                  f"{c / w:.1f}x faster than cold)")
        if args.against is not None:
            this, other = (label for label, *_ in lints)
            for kind, times in (("cold", cold), ("warm", warm)):
                ratio = statistics.median(times[this]) / statistics.median(times[other])
                print(f"  {kind}: this checkout / {args.against.name} = {ratio:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
