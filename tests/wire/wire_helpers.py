"""What every wire test does around its scenario: skip where a real master or a private network namespace cannot
be had, and run a scenario script in a namespace of its own, its result the last JSON line it prints."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from ecattool.sim.bus import netns
from tests.conftest import ROOT


def skip_reason(*modules: str) -> str | None:
    """Why the wire tests cannot run here (a master module missing, the kernel refusing the namespace), or None."""
    for module in modules:
        try:
            __import__(module)
        except ImportError:
            return f"{module} is not installed (pip install 'ecattool[wire]')"
    return netns.unavailable()


def skip_without(*modules: str) -> None:
    """Skip the calling test where :func:`skip_reason` gives a reason, saying it once on stderr too."""
    reason = skip_reason(*modules)
    if reason:
        print(f"wire test skipped: {reason}", file=sys.stderr)
        pytest.skip(reason)


def last_json(stdout: str) -> dict[str, Any]:
    """A scenario's result: its last line that is a JSON object (a master's C++ side may print after Python's)."""
    result: dict[str, Any] = json.loads([ln for ln in stdout.splitlines() if ln.startswith("{")][-1])
    return result


def run_scenario(script: Path, *args: str, timeout: int) -> dict[str, Any]:
    """``script ARGS`` in a private network namespace (faulthandler on: a crash inside a master's compiled code
    still names the Python line that called it); it must exit 0."""
    argv = netns.command([sys.executable, "-X", "faulthandler", str(script), *args])
    done = subprocess.run(argv, capture_output=True, text=True, timeout=timeout, cwd=ROOT)
    assert done.returncode == 0, done.stderr[-3000:]
    return last_json(done.stdout)
