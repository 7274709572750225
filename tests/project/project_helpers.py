"""Helpers shared by the project, lint and commission tests (samples, temporary projects, the CLI)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

from tests.conftest import ROOT, run  # noqa: F401  (run is re-exported for the project tests)

SAMPLES = ("technosoft_ipos", "hdt", "controltechniques", "generic_esi")
DATA = ROOT / "tests" / "data" / "projects"


#: an HDT drive on a belt: pi in the factors, so they are approximated (info findings, lint still passes)
BELT_PROJECT = """ecattool: 1
drives:
  - name: x
    device: {profile: hdt, product: tomcat}
    scaling:
      feedback: {counts_per_rev: 65536}
      transmission: {type: belt, diameter: 30 mm}
      units: {position: um}
"""


def sample(name: str) -> Path:
    p = ROOT / "samples" / name / "project.yaml"
    assert p.exists(), f"sample project missing: {p}"
    return p


def copy_sample(name: str, tmp_path: Path) -> Path:
    """A writable copy of a sample directory (project, ESI, .sw); returns the project file."""
    dst = tmp_path / name
    shutil.copytree(ROOT / "samples" / name, dst)
    return dst / "project.yaml"


def write_project(tmp_path: Path, text: str, name: str = "project.yaml") -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


def run_json(capsys: Any, *args: str) -> tuple[int, Any]:
    code, out, _ = run(capsys, *args)
    return code, json.loads(out)
