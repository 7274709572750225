"""Shared fixtures. The real-file corpus lives in ../shared/corpus beside the checkout; tests that need it
fail loudly (never skip) when it is missing."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from hypothesis import HealthCheck, settings

ROOT = Path(__file__).resolve().parent.parent
CORPUS = Path(os.environ.get("ECATTOOL_CORPUS", ROOT.parent / "shared" / "corpus"))
REFERENCE = CORPUS.parent / "reference"

settings.register_profile(
    "ci", max_examples=60, deadline=None, derandomize=True,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
settings.load_profile("ci")


def corpus_path(*parts: str) -> Path:
    p = CORPUS.joinpath(*parts)
    if not p.exists():
        raise FileNotFoundError(f"corpus file missing: {p} (the tests need ../shared/corpus)")
    return p


@pytest.fixture(scope="session")
def corpus() -> Path:
    if not CORPUS.is_dir():
        raise FileNotFoundError(f"corpus directory missing: {CORPUS}")
    return CORPUS


def run(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    """Run ``ecattool ARGS`` through the real entry point; returns (exit code, stdout, stderr)."""
    from ecattool.cli import main

    try:
        main(list(args))
        code = 0
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else 0
    out, err = capsys.readouterr()
    return code, out, err
