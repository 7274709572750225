#!/usr/bin/env python3
"""One-step set-up and run for a fresh machine with only Python and pip.

    python3 scripts/dev.py demo   # create .venv, install ecattool, run the main job on the bundled samples
    python3 scripts/dev.py test   # create .venv, install ecattool with test extras, run the whole test suite
    python3 scripts/dev.py corpus # fetch the real-file corpus the tests read (tests/corpus-manifest.json), check it
    python3 scripts/dev.py corpus --check   # only check the corpus that is there against the manifest

Extra arguments after the command are passed on (to ``ecattool`` for demo, to ``pytest`` for test).
The tests that read the corpus find it at $ECATTOOL_CORPUS or ../shared/corpus beside the checkout; without it
they skip (pytest -rs says how many and why) and the rest of the suite runs.
"""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
import urllib.error
import urllib.parse
import urllib.request
import venv
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
VENV = Path(os.environ.get("ECATTOOL_VENV", ROOT / ".venv"))
BIN = VENV / ("Scripts" if os.name == "nt" else "bin")
STAMP = VENV / ".ecattool-installed"
MANIFEST = ROOT / "tests" / "corpus-manifest.json"
CORPUS = Path(os.environ.get("ECATTOOL_CORPUS") or ROOT.parent / "shared" / "corpus")
#: where a file of a public GitHub repository at a commit is served as it is
RAW = "https://raw.githubusercontent.com/{repository}/{commit}/{source}"


#: the variables that would make the venv's Python load modules from outside the venv (a PYTHONPATH set for
#: another interpreter puts its compiled lxml before the venv's own): cleared for everything run in the venv
_FOREIGN = ("PYTHONPATH", "PYTHONHOME", "PYTHONSTARTUP", "PYTHONUSERBASE")
#: the compiled and pure dependencies every test module needs, checked right after the install
_CORE = ("lxml.etree", "pydantic", "yaml", "click", "rich", "canopen", "hypothesis", "xdist", "pytest_rerunfailures")


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


def pip_install(cmd: list[str], quiet_errors: bool = False) -> int:
    """Run pip, showing one short line per package it fetches or installs (a fresh install is silent otherwise
    for half a minute); its other output only when it fails, unless ``quiet_errors``."""
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=venv_env())
    assert proc.stdout is not None
    rest = []
    for line in proc.stdout:
        if line.startswith(("Collecting ", "Installing collected packages", "Successfully installed")):
            print(f"  pip: {line.strip()[:100]}", flush=True)
        else:
            rest.append(line)
    code = proc.wait()
    if code != 0 and not quiet_errors:
        sys.stderr.write("".join(rest[-30:]))
    return code


def ensure_venv(extras: str) -> None:
    if not (BIN / "python").exists():
        print(f"creating virtual environment in {VENV}", flush=True)
        venv.EnvBuilder(with_pip=True).create(VENV)
    pyproject = ROOT / "pyproject.toml"
    wanted = f"{extras}:{pyproject.stat().st_mtime_ns}"
    if STAMP.exists() and STAMP.read_text() in (wanted, f"test:{pyproject.stat().st_mtime_ns}") \
            and check_imports() is None:
        return
    print(f"installing ecattool[{extras}] and its dependencies into {VENV} with pip (once; about half a minute)",
          flush=True)
    pip = [str(BIN / "python"), "-m", "pip", "install", "--disable-pip-version-check", "-e"]
    # the tests also take the real masters the virtual bus is proven with (extra "wire": compiled wheels of
    # pysoem and kickcat); where those cannot be installed, the wire tests skip and say why
    if extras != "test" or pip_install([*pip, f"{ROOT}[test,wire]"], quiet_errors=True) != 0:
        if extras == "test":
            print("note: the 'wire' extra (pysoem, kickcat) could not be installed; the wire tests will skip",
                  flush=True)
        if pip_install([*pip, f"{ROOT}[{extras}]"]) != 0:
            raise SystemExit(f"dev.py: pip could not install ecattool[{extras}] (its messages are above)")
    broken = check_imports()
    if broken:
        # a wheel from a stale cache, or one pip built against the wrong libraries: fetch them afresh once
        print(f"note: {broken}; reinstalling the dependencies without pip's cache", flush=True)
        if pip_install([*pip[:-1], "--force-reinstall", "--no-cache-dir", "-e", f"{ROOT}[{extras}]"]) != 0:
            raise SystemExit(f"dev.py: pip could not reinstall ecattool[{extras}] (its messages are above)")
        broken = check_imports()
        if broken:
            raise SystemExit(f"dev.py: the virtual environment {VENV} cannot import {broken}")
    STAMP.write_text(wanted)


def check_corpus(corpus: Path, entries: list[dict[str, str]]) -> list[str]:
    """One line per file of the manifest that is missing or differs from its SHA-256; empty when all match."""
    problems = []
    for e in entries:
        f = corpus / e["path"]
        if not f.is_file():
            problems.append(f"{f}: missing")
        elif hashlib.sha256(f.read_bytes()).hexdigest() != e["sha256"]:
            problems.append(f"{f}: SHA-256 differs from the manifest (not the file at {e['repository']}@{e['commit'][:7]})")
    return problems


def fetch_corpus(corpus: Path, entries: list[dict[str, str]]) -> str | None:
    """Download every missing or differing file from its origin; None when done, else the one-line reason it stopped."""
    for e in entries:
        f = corpus / e["path"]
        if f.is_file() and hashlib.sha256(f.read_bytes()).hexdigest() == e["sha256"]:
            continue
        url = RAW.format(repository=e["repository"], commit=e["commit"], source=urllib.parse.quote(e["source"]))
        try:
            with urllib.request.urlopen(url, timeout=20) as response:
                data = response.read()
        except (urllib.error.URLError, OSError) as exc:
            reason = getattr(exc, "reason", exc)
            return (f"cannot fetch {e['path']} from {url}: {reason}; without a network, copy the corpus beside the "
                    f"checkout as ../shared/corpus or point ECATTOOL_CORPUS at it")
        if hashlib.sha256(data).hexdigest() != e["sha256"]:
            return f"{url}: the file served has another SHA-256 than tests/corpus-manifest.json records for {e['path']}"
        f.parent.mkdir(parents=True, exist_ok=True)
        tmp = f.with_name(f".{f.name}.part")
        tmp.write_bytes(data)
        tmp.replace(f)
        print(f"fetched {e['path']}", flush=True)
    return None


def corpus_command(args: list[str]) -> int:
    entries = json.loads(MANIFEST.read_text(encoding="utf-8"))["files"]
    if "--check" not in args:
        stopped = fetch_corpus(CORPUS, entries)
        if stopped:
            print(f"dev.py corpus: {stopped}", file=sys.stderr)
            return 1
    problems = check_corpus(CORPUS, entries)
    for line in problems:
        print(line, file=sys.stderr)
    print(f"{CORPUS}: {len(entries) - len(problems)} of {len(entries)} files match tests/corpus-manifest.json")
    return 1 if problems else 0


def main() -> int:
    if len(sys.argv) < 2 or sys.argv[1] not in ("demo", "test", "corpus"):
        print(__doc__)
        return 2
    cmd, rest = sys.argv[1], sys.argv[2:]
    if cmd == "corpus":
        return corpus_command(rest)
    if cmd == "demo":
        ensure_venv("test")
        if rest:
            return subprocess.call([str(BIN / "ecattool"), *rest], env=venv_env())
        # run from the repository root with relative paths, so the report reads as in README.md
        args = ["commission", *sorted(p.relative_to(ROOT).as_posix() for p in (ROOT / "samples").glob("*/project.yaml"))]
        if len(args) == 1:
            args = ["esi", "show", "samples/esi/etg2001_cia402.xml", "--pdos"]
        print(f"running: ecattool {' '.join(args)}", flush=True)
        return subprocess.call([str(BIN / "ecattool"), *args], cwd=ROOT, env=venv_env())
    ensure_venv("test")
    # two workers; the tests that run a bus in a network namespace share one of them (xdist_group "wire"), so
    # that two buses never compete for the CPU: a master starved for 100 ms loses its drives to their watchdogs
    workers = ["-n", "2", "--dist", "loadgroup"] if "-n" not in rest else []
    # -rs: every skipped test says why in the summary (one line for all the tests that need the absent corpus)
    report = [] if any(a.startswith("-r") for a in rest) else ["-rs"]
    return subprocess.call([str(BIN / "python"), "-m", "pytest", *workers, *report, *rest], cwd=ROOT, env=venv_env())


if __name__ == "__main__":
    sys.exit(main())
