"""The one drive of a project a command acts on (issue 36.4: the CLI only reads ``--project``/``--drive``):
``Machine.slave_to_act_on`` (``scale explain --project``) and ``Machine.sw_drive`` (``sw … --project``)."""

from __future__ import annotations

from pathlib import Path

import pytest

from ecattool.errors import InputError
from ecattool.project.machine import load_machine
from tests.conftest import corpus_path

#: a Technosoft .sw image of the corpus (as tests/sw/test_sw_cli.py uses)
SW = "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.sw"


def _machine_text(sw: str) -> str:
    return ("ecattool: 1\nname: m\ndrives:\n  - name: x\n    device: {profile: technosoft-ipos}\n"
            f"  - name: y\n    device: {{profile: technosoft-ipos}}\n    sw: {sw}\n")


def test_the_sw_drive_is_the_one_with_an_sw_image(tmp_path: Path) -> None:
    (tmp_path / "axis.sw").write_bytes(corpus_path("sw", SW).read_bytes())
    (tmp_path / "m.yaml").write_text(_machine_text("axis.sw"))
    machine = load_machine(tmp_path / "m.yaml")
    assert machine.sw_drive(None).name == "y"
    assert machine.sw_drive("x").name == "x"  # named: taken as named (its missing image is the command's to say)
    with pytest.raises(InputError, match="has several drives"):
        machine.slave_to_act_on(None, "explain")


def test_an_sw_image_that_does_not_read_is_refused_with_lints_reason_first(tmp_path: Path) -> None:
    (tmp_path / "m.yaml").write_text(_machine_text("missing.sw"))
    machine = load_machine(tmp_path / "m.yaml")
    with pytest.raises(InputError, match="drive 'y': .*missing.sw"):
        machine.sw_drive(None, allow_errors=True)
    # the same drive, acted on without its image, is refused by the lint policy, naming the verb
    with pytest.raises(InputError, match="cannot explain drive 'y': the project has lint errors"):
        machine.slave_to_act_on("y", "explain")
    assert machine.slave_to_act_on("y", "explain", allow_errors=True).name == "y"
