"""Project paths are data, never a channel (issue 37, item 4; docs/project-format.md, "Files a project names").

A project may name any file in `esi:` and `sw:` (a symbolic link, `../`, an absolute path): lint reads it as the
format it expects and reports what is wrong with it, and never quotes its content; a name longer than the system
allows, a FIFO, a device or a directory is a one-line finding, never a traceback or a hang.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import ROOT, run

SECRET = "SECRET_TOKEN=hunter2-do-not-print"


def _project(folder: Path, esi: str | None = None, sw: str | None = None) -> Path:
    device = f"{{esi: {json.dumps(esi)}}}" if esi is not None else "{profile: technosoft-ipos}"
    text = f"ecattool: 1\nname: m\ndrives:\n  - name: z\n    device: {device}\n"
    if sw is not None:
        text += f"    sw: {json.dumps(sw)}\n"
    path = folder / "machine.yaml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("fmt", ["text", "json", "sarif"])
def test_lint_never_quotes_a_file_the_project_names(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                    fmt: str) -> None:
    """Today lint quoted the first 20 characters of an `sw:` file's first line, in text and SARIF: CI lint of an
    untrusted project printed a secret's (or /etc/shadow's) first line."""
    secret = tmp_path / "credentials"
    secret.write_text(SECRET + "\nsecond line\n")
    (tmp_path / "link.sw").symlink_to(secret)
    for sw in ("credentials", "link.sw", str(secret), "../" + tmp_path.name + "/credentials"):
        project = _project(tmp_path, sw=sw)
        code, out, err = run(capsys, "lint", str(project), "--format", fmt)
        assert code == 1 and "PRJ030" in out + err, (sw, out, err)
        assert "hunter2" not in out + err and "SECRET" not in out + err, (sw, out, err)
        assert "is not a hex word" in out + err  # what is wrong, and where (file:line) — not what the line says


def test_a_sw_file_with_a_non_ascii_byte_is_not_quoted_either(tmp_path: Path,
                                                              capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "key.bin").write_bytes(b"\x00\xc3\xa9secret")
    code, out, _ = run(capsys, "lint", str(_project(tmp_path, sw="key.bin")))
    assert code == 1 and "a byte is not ASCII" in out and "0xC3" not in out


def _kinds(tmp_path: Path) -> dict[str, tuple[str, str]]:
    """name -> (what the project names, what the finding says)."""
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    (tmp_path / "folder").mkdir()
    return {
        "fifo": ("pipe", "is a FIFO (named pipe), not a file"),
        "directory": ("folder", "is a directory, not a file"),
        "char device": ("/dev/zero", "is a character device, not a file"),
        "null device": ("/dev/null", "is a character device, not a file"),
        "long name": ("x" * 300 + ".xml", "the file name is longer than the system allows"),
        "long path": ("/".join(["y" * 200] * 30), "the file name is longer than the system allows"),
    }


@pytest.mark.parametrize("key", ["esi", "sw"])
def test_fifos_devices_directories_and_long_names_are_one_line_findings(tmp_path: Path, key: str) -> None:
    """Today: an OSError traceback for a name over 255 bytes, and lint hangs on a FIFO. Run as a child process so a
    hang fails the test (bounded by the timeout) instead of stopping the suite."""
    for name, (path, says) in _kinds(tmp_path).items():
        project = _project(tmp_path, **{key: path})
        proc = subprocess.run([sys.executable, "-m", "ecattool", "lint", str(project)], cwd=ROOT, capture_output=True,
                              text=True, timeout=120, stdin=subprocess.DEVNULL)
        errors = [ln for ln in proc.stdout.splitlines() if ": error: " in ln]
        assert proc.returncode == 1 and "Traceback" not in proc.stderr, (name, proc.stdout, proc.stderr)
        assert len(errors) == 1 and says in errors[0], (name, proc.stdout)
        assert errors[0].startswith(f"{project}:6:" if key == "sw" else f"{project}:5:"), errors[0]
        assert len(errors[0]) < 450  # a 6,000-character name is not repeated whole


def test_project_new_esi_of_a_fifo_or_a_long_name(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    kinds = _kinds(tmp_path)
    for name in ("fifo", "long name", "directory"):
        path, says = kinds[name]
        code, _, err = run(capsys, "project", "new", "--esi", str(tmp_path / path))
        assert code == 1 and says in err and len(err.strip().splitlines()) == 1, (name, err)
