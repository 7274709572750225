"""``ecattool map … --mapping -``: the mapping file read from stdin (found by mypy: the code used click's
deprecated ``get_binary_stream``, which warns on Click 8.5 and is gone in Click 9)."""

from __future__ import annotations

import io
import sys
import warnings

import pytest

from tests.conftest import run

MAPPING = b"pdo:\n  rx:\n    - index: 0x1600\n      entries:\n        - controlword\n        - 0x6040:00/32\n"


def test_mapping_from_stdin_is_located_without_deprecation_warnings(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(io.BytesIO(MAPPING)))
    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)
        code, out, err = run(capsys, "map", "check", "--profile", "technosoft-ipos", "--mapping", "-")
    assert "Traceback" not in err and "deprecated" not in err
    assert code == 1 and "<stdin>:6:11: error:" in out and "[PDO007]" in out


def test_valid_mapping_from_stdin_passes(capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    text = b"rx:\n  - index: 0x1600\n    entries: [controlword, 0x607A:00/32]\n"
    monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(io.BytesIO(text)))
    code, out, _ = run(capsys, "map", "check", "--profile", "technosoft-ipos", "--mapping", "-")
    assert code == 0 and out.startswith("OK: iPOS360x VX-CAT: outputs 6 bytes")
