#!/usr/bin/env python3
"""One-step set-up and run for a fresh machine with only Python and pip.

    python3 scripts/dev.py demo   # create .venv, install ecattool, run the main job on the bundled samples
    python3 scripts/dev.py test   # create .venv, install ecattool with test extras, run the whole test suite

Extra arguments after the command are passed on (to ``ecattool`` for demo, to ``pytest`` for test).
"""

from __future__ import annotations

import os
import subprocess
import sys
import venv
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
VENV = Path(os.environ.get("ECATTOOL_VENV", ROOT / ".venv"))
BIN = VENV / ("Scripts" if os.name == "nt" else "bin")
STAMP = VENV / ".ecattool-installed"


def ensure_venv(extras: str) -> None:
    if not (BIN / "python").exists():
        print(f"creating virtual environment in {VENV}", flush=True)
        venv.EnvBuilder(with_pip=True).create(VENV)
    pyproject = ROOT / "pyproject.toml"
    wanted = f"{extras}:{pyproject.stat().st_mtime_ns}"
    if STAMP.exists() and STAMP.read_text() in (wanted, f"test:{pyproject.stat().st_mtime_ns}"):
        return
    print(f"installing ecattool[{extras}] into {VENV}", flush=True)
    pip = [str(BIN / "python"), "-m", "pip", "install", "-q", "--disable-pip-version-check", "-e"]
    # the tests also take the real masters the virtual bus is proven with (extra "wire": compiled wheels of
    # pysoem and kickcat); where those cannot be installed, the wire tests skip and say why
    if extras != "test" or subprocess.call([*pip, f"{ROOT}[test,wire]"], stderr=subprocess.DEVNULL) != 0:
        if extras == "test":
            print("note: the 'wire' extra (pysoem, kickcat) could not be installed; the wire tests will skip",
                  flush=True)
        subprocess.check_call([*pip, f"{ROOT}[{extras}]"])
    STAMP.write_text(wanted)


def main() -> int:
    if len(sys.argv) < 2 or sys.argv[1] not in ("demo", "test"):
        print(__doc__)
        return 2
    cmd, rest = sys.argv[1], sys.argv[2:]
    if cmd == "demo":
        ensure_venv("test")
        if rest:
            return subprocess.call([str(BIN / "ecattool"), *rest])
        # run from the repository root with relative paths, so the report reads as in README.md
        args = ["commission", *sorted(p.relative_to(ROOT).as_posix() for p in (ROOT / "samples").glob("*/project.yaml"))]
        if len(args) == 1:
            args = ["esi", "show", "samples/esi/etg2001_cia402.xml", "--pdos"]
        return subprocess.call([str(BIN / "ecattool"), *args], cwd=ROOT)
    ensure_venv("test")
    # two workers; the tests that run a bus in a network namespace share one of them (xdist_group "wire"), so
    # that two buses never compete for the CPU: a master starved for 100 ms loses its drives to their watchdogs
    workers = ["-n", "2", "--dist", "loadgroup"] if "-n" not in rest else []
    return subprocess.call([str(BIN / "python"), "-m", "pytest", *workers, *rest], cwd=ROOT)


if __name__ == "__main__":
    sys.exit(main())
