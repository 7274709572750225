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


#: the variables that would make the venv's Python load modules from outside the venv (a PYTHONPATH set for
#: another interpreter puts its compiled lxml before the venv's own): cleared for everything run in the venv
_FOREIGN = ("PYTHONPATH", "PYTHONHOME", "PYTHONSTARTUP", "PYTHONUSERBASE")
#: the compiled and pure dependencies every test module needs, checked right after the install
_CORE = ("lxml.etree", "pydantic", "yaml", "click", "rich", "canopen", "hypothesis", "xdist")


def venv_env() -> dict[str, str]:
    return {k: v for k, v in os.environ.items() if k not in _FOREIGN}


def check_imports() -> str | None:
    """None when the venv imports every core dependency, else the first failure (module, error, where from)."""
    probe = ("import importlib, sys\n"
             f"for name in {_CORE!r}:\n"
             "    try:\n"
             "        importlib.import_module(name)\n"
             "    except Exception as exc:\n"
             "        top = sys.modules.get(name.split('.')[0])\n"
             "        print(f'{name}: {type(exc).__name__}: {exc} (from {getattr(top, \"__file__\", None)})')\n"
             "        sys.exit(1)\n")
    done = subprocess.run([str(BIN / "python"), "-c", probe], capture_output=True, text=True, env=venv_env())
    return None if done.returncode == 0 else (done.stdout.strip() or done.stderr.strip().splitlines()[-1])


def ensure_venv(extras: str) -> None:
    if not (BIN / "python").exists():
        print(f"creating virtual environment in {VENV}", flush=True)
        venv.EnvBuilder(with_pip=True).create(VENV)
    pyproject = ROOT / "pyproject.toml"
    wanted = f"{extras}:{pyproject.stat().st_mtime_ns}"
    if STAMP.exists() and STAMP.read_text() in (wanted, f"test:{pyproject.stat().st_mtime_ns}") \
            and check_imports() is None:
        return
    print(f"installing ecattool[{extras}] into {VENV}", flush=True)
    pip = [str(BIN / "python"), "-m", "pip", "install", "-q", "--disable-pip-version-check", "-e"]
    # the tests also take the real masters the virtual bus is proven with (extra "wire": compiled wheels of
    # pysoem and kickcat); where those cannot be installed, the wire tests skip and say why
    if extras != "test" or subprocess.call([*pip, f"{ROOT}[test,wire]"], stderr=subprocess.DEVNULL,
                                           env=venv_env()) != 0:
        if extras == "test":
            print("note: the 'wire' extra (pysoem, kickcat) could not be installed; the wire tests will skip",
                  flush=True)
        subprocess.check_call([*pip, f"{ROOT}[{extras}]"], env=venv_env())
    broken = check_imports()
    if broken:
        # a wheel from a stale cache, or one pip built against the wrong libraries: fetch them afresh once
        print(f"note: {broken}; reinstalling the dependencies without pip's cache", flush=True)
        subprocess.check_call([*pip[:-1], "--force-reinstall", "--no-cache-dir", "-e", f"{ROOT}[{extras}]"],
                              env=venv_env())
        broken = check_imports()
        if broken:
            raise SystemExit(f"dev.py: the virtual environment {VENV} cannot import {broken}")
    STAMP.write_text(wanted)


def main() -> int:
    if len(sys.argv) < 2 or sys.argv[1] not in ("demo", "test"):
        print(__doc__)
        return 2
    cmd, rest = sys.argv[1], sys.argv[2:]
    if cmd == "demo":
        ensure_venv("test")
        if rest:
            return subprocess.call([str(BIN / "ecattool"), *rest], env=venv_env())
        # run from the repository root with relative paths, so the report reads as in README.md
        args = ["commission", *sorted(p.relative_to(ROOT).as_posix() for p in (ROOT / "samples").glob("*/project.yaml"))]
        if len(args) == 1:
            args = ["esi", "show", "samples/esi/etg2001_cia402.xml", "--pdos"]
        return subprocess.call([str(BIN / "ecattool"), *args], cwd=ROOT, env=venv_env())
    ensure_venv("test")
    # two workers; the tests that run a bus in a network namespace share one of them (xdist_group "wire"), so
    # that two buses never compete for the CPU: a master starved for 100 ms loses its drives to their watchdogs
    workers = ["-n", "2", "--dist", "loadgroup"] if "-n" not in rest else []
    return subprocess.call([str(BIN / "python"), "-m", "pytest", *workers, *rest], cwd=ROOT, env=venv_env())


if __name__ == "__main__":
    sys.exit(main())
