"""The library pieces ``scale explain`` assembles its values from (issue 36.4: the command is flags → model →
action → render): the family a project slave is explained as, the drive a bare simulator holds for a family, the
one drive of a project a command acts on, and the one slave of a target (shared with ``sw``)."""

from __future__ import annotations

import pytest

from ecattool.errors import InputError
from ecattool.od.model import EcState
from ecattool.online.targets import open_slave
from ecattool.project.machine import load_machine
from ecattool.scaling.explain import FACTOR_INDICES, explain, explain_family, family_drives, read_values


def test_a_project_slave_is_explained_in_its_scaling_family_else_as_generic() -> None:
    assert explain_family("hdt") == "hdt"
    assert explain_family("technosoft-ipos") == "technosoft-ipos"
    assert explain_family("beckhoff-io") == "generic"
    assert explain_family(None) == "generic"


def test_a_bare_simulator_holds_the_built_in_familys_drive_and_none_for_generic() -> None:
    (ipos,) = family_drives("technosoft-ipos", "F515I")
    assert ipos.revision != family_drives("technosoft-ipos")[0].revision  # the firmware asked for, not the default
    assert family_drives("generic") == []


def test_the_drive_a_command_acts_on_is_refused_with_the_verb() -> None:
    machine = load_machine("samples/hdt/project.yaml")
    chosen = machine.slave_to_act_on(None if len(machine.slaves) == 1 else machine.slaves[0].name, "explain")
    values = chosen.object_values(FACTOR_INDICES)
    assert (0x6093, 1) in values or (0x608F, 1) in values
    with pytest.raises(InputError, match="has no drive 'nope'"):
        machine.slave_to_act_on("nope", "explain")


def test_a_bare_sim_slave_answers_at_the_position_asked_for_in_preop() -> None:
    found = open_slave("sim", family_drives("hdt"), 3, in_preop=True)
    assert found.position == 3
    assert found.state() is EcState.PREOP
    e = explain(read_values(found), "hdt")
    assert e.family == "hdt" and e.lines
