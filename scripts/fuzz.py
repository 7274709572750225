#!/usr/bin/env python3
"""The long fuzzing run: mutated real files through every command that reads a file (tests/safe/fuzz_readers.py).

    python3 scripts/fuzz.py --examples 2000            # every entry, 2000 mutants each, random
    python3 scripts/fuzz.py --examples 500 -k sw-build  # only the entries whose id matches (pytest -k)
    python3 scripts/fuzz.py --paths                     # hostile paths instead of mutated content

``--paths`` gives every command that reads a file, every command that writes one and a project's ``esi:``/``sw:``
the paths that are no ordinary file (tests/safe/fuzz_readers.py, PATH_KINDS): a missing file, a name over 255 bytes, a
path over 4,096, a directory, /dev/zero, /dev/null, a dangling link, a loop of links, a UNIX socket, a FIFO (as an
output and in a project; as a command's own input a FIFO without a writer waits, as `cat` does). The suite runs
the same cases; each must end in a result or one located line, never a traceback or a hang.

It runs tests/safe/test_fuzz_readers.py with ECATTOOL_FUZZ_EXAMPLES set (the suite runs the same test with a few fixed
examples): each failure is a raw exception, a traceback, a second error line or an error that names no file, shown
with the smallest mutant hypothesis found. Needs the venv of ``python3 scripts/dev.py test`` (created if missing).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--examples", type=int, default=2000, help="mutants per entry (default 2000)")
    ap.add_argument("-k", dest="select", help="only entries whose name matches (pytest -k expression)")
    ap.add_argument("--paths", action="store_true", help="hostile paths (long names, FIFOs, devices, directories, "
                    "dangling links, sockets) instead of mutated content")
    args = ap.parse_args(argv)
    if args.examples < 1:
        ap.error("--examples must be at least 1")
    sys.path.insert(0, str(ROOT / "scripts"))
    import dev  # the same venv as the test suite

    dev.ensure_venv("test")
    python = dev.BIN / "python"
    env = {**dev.venv_env(), "ECATTOOL_FUZZ_EXAMPLES": str(args.examples)}
    cmd = [str(python), "-m", "pytest", "-q", "-n", "0", "-p", "no:randomly", "-p", "no:cacheprovider",
           "tests/safe/test_fuzz_readers.py", "-k",
           f"{'hostile' if args.paths else 'mutated'}{' and (' + args.select + ')' if args.select else ''}"]
    return subprocess.call(cmd, cwd=ROOT, env=env)


if __name__ == "__main__":
    raise SystemExit(main())
