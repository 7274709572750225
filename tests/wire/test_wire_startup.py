"""Issue 13, item 6: the pysoem module ``ecattool startup export --project P --format pysoem`` writes for each
sample project runs unmodified against the served bus (SOEM through pysoem 1.1.13, ``ecattool sim serve P``)
inside a private network namespace with a veth pair the test makes itself, and brings the drive to OP; every
value it writes is then read back over SDO. One namespace subprocess with a timeout; every loop is bounded."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import ROOT
from tests.wire.test_wire_pysoem import SAMPLES
from tests.wire.wire_helpers import run_scenario, skip_without

#: every bus of these tests runs in one xdist worker (scripts/dev.py: --dist loadgroup), never two at once
pytestmark = pytest.mark.xdist_group("wire")

SCENARIO = Path(__file__).with_name("wire_startup_scenario.py")


def test_exported_pysoem_module_reaches_op_on_the_wire(tmp_path: Path) -> None:
    skip_without("pysoem")
    args = []
    for project in SAMPLES:
        module = tmp_path / f"startup_{Path(project).parent.name}.py"
        done = subprocess.run([sys.executable, "-m", "ecattool", "startup", "export", "--project", project,
                               "--format", "pysoem", "-o", str(module)], capture_output=True, text=True,
                              timeout=120, cwd=ROOT)
        assert done.returncode == 0, done.stderr
        args.append(f"{project}={module}")
    runs = run_scenario(SCENARIO, *args, timeout=300)["runs"]
    assert [r["project"] for r in runs] == SAMPLES
    for r in runs:
        assert r["found"] == 1 and r["safeop"] is True, r
        assert r["op"] is True and r["al_status_code"] == [0], r
        assert r["readback"] == r["written"], r["project"]  # every startup SDO arrived and was kept
        assert r["server"] == {"returncode": 0, "stderr": ""}
    # the samples that have a startup list wrote it (the generic ESI drive runs on its ESI defaults)
    assert sum(len(r["written"]) for r in runs) > 50
