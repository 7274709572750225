"""``audit`` and ``backup`` act on a project through one Machine built by the command (issue 36, item 1): the
project is resolved once, and a project with lint errors is refused unless ``--allow-errors`` (the same meaning
as on ``commission``)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from ecattool.project import machine as machine_module
from tests.conftest import ROOT, run

if TYPE_CHECKING:
    from ecattool.project.loader import LoadedProject
    from ecattool.project.slave import Slave

HDT = ROOT / "samples" / "hdt" / "project.yaml"
#: a parameter writing an object the HDT TomCat does not have: lint's PRJ010, an error; the drive still resolves
UNKNOWN_OBJECT = '      - {object: "0x2FFF:00", value: 1, comment: no such object}\n'


def _count_builds(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """Each drive index :func:`build_slave` resolves from now on (load_machine calls it once per drive)."""
    built: list[int] = []
    real = machine_module.build_slave

    def counting(lp: LoadedProject, i: int) -> Slave:
        built.append(i)
        return real(lp, i)

    monkeypatch.setattr(machine_module, "build_slave", counting)
    return built


def test_audit_resolves_the_project_once(monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    built = _count_builds(monkeypatch)
    code, out, _ = run(capsys, "audit", str(HDT), "--target", "sim", "--json")
    assert json.loads(out)["checked"] > 0, out
    # one drive, resolved once: by the command, not again to open the bus nor by the audit
    assert built == [0]


def test_backup_resolves_the_project_once(monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str],
                                          tmp_path: Path) -> None:
    built = _count_builds(monkeypatch)
    code, out, err = run(capsys, "backup", str(HDT), "--target", "sim", "-o", str(tmp_path / "b"))
    assert code == 0, err
    assert built == [0]  # not again for the folder check, the bus and the back-up


def _with_lint_error(tmp_path: Path) -> Path:
    text = HDT.read_text()
    anchor = "comment: profile acceleration 360 deg/s^2}\n"
    assert anchor in text
    path = tmp_path / "project.yaml"
    path.write_text(text.replace(anchor, anchor + UNKNOWN_OBJECT))
    return path


def test_audit_refuses_lint_errors_unless_allow_errors(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    project = _with_lint_error(tmp_path)
    code, out, err = run(capsys, "audit", str(project), "--target", "sim", "--json")
    assert code == 1 and out == "" and len(err.strip().splitlines()) == 1
    assert "cannot audit" in err and "[PRJ010]" in err and f"{project}:18:" in err and "--allow-errors" in err
    code, out, err = run(capsys, "audit", str(project), "--target", "sim", "--json", "--allow-errors")
    report = json.loads(out)
    # the audit ran: the uncommissioned simulator differs from the project's startup values (drift, exit 1),
    # and the refused parameter is not among what is compared
    assert code == 1 and report["checked"] > 0 and report["drifts"], err
    assert not any(d["address"].startswith("0x2FFF") for d in report["drifts"])


def test_backup_refuses_lint_errors_unless_allow_errors(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    project = _with_lint_error(tmp_path)
    folder = tmp_path / "b"
    code, _, err = run(capsys, "backup", str(project), "--target", "sim", "-o", str(folder))
    assert code == 1 and "cannot back up" in err and "[PRJ010]" in err and len(err.strip().splitlines()) == 1
    assert not folder.exists()
    code, out, err = run(capsys, "backup", str(project), "--target", "sim", "-o", str(folder), "--allow-errors")
    assert code == 0, err
    assert sorted(p.name for p in folder.iterdir()) == ["00-table.dict.json", "00-table.sii.bin", "ecattool-backup.json"]


def test_a_project_that_does_not_resolve_is_refused_even_with_allow_errors(tmp_path: Path,
                                                                           capsys: pytest.CaptureFixture[str]) -> None:
    project = tmp_path / "project.yaml"
    project.write_text(HDT.read_text().replace("profile: hdt\n      product: tomcat\n", "esi: missing.xml\n"))
    for args in (("audit", str(project)), ("backup", str(project), "-o", str(tmp_path / "b"))):
        code, _, err = run(capsys, *args, "--target", "sim", "--allow-errors")
        assert code == 1 and "did not resolve" in err and "[PRJ002]" in err and len(err.strip().splitlines()) == 1
