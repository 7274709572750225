"""``sim serve``'s sources as devices in bus order (``project.bus.served_devices``, issue 36.4: the command only
reads its flags and renders): a project file gives its slaves in the project's bus order, a profile name or an ESI
file one device, each as it runs."""

from __future__ import annotations

import pytest

from ecattool.errors import SelectionError
from ecattool.profiles.running import RunningDevice
from ecattool.project.bus import devices_in_bus_order, is_project_file, served_devices


def test_sources_are_served_in_the_order_given_a_project_expanded_in_its_bus_order() -> None:
    project = devices_in_bus_order("samples/hdt/project.yaml")
    named = served_devices(["technosoft-ipos", "samples/hdt/project.yaml", "samples/esi/etg2001_cia402.xml"])
    assert [n for n, _ in named[1:1 + len(project)]] == [n for n, _ in project]
    assert named[0][0] == "technosoft-ipos" and len(named) == len(project) + 2
    assert all(isinstance(d, RunningDevice) for _, d in named)


def test_a_profiles_model_is_chosen_by_product() -> None:
    ((name, device),) = served_devices(["hdt"], product="tomcat")
    assert name == "hdt tomcat" and device.vendor_id


def test_project_files_are_told_by_their_yaml_suffix() -> None:
    assert is_project_file("machine.YAML") and is_project_file("a.yml")
    assert not is_project_file("hdt") and not is_project_file("drive.xml")


def test_an_unknown_source_is_one_error() -> None:
    with pytest.raises(SelectionError, match="unknown drive profile"):
        served_devices(["no-such-profile"])
