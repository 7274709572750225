"""One "device as it runs" (issue 36.2): lint, ``map``, ``sdo … --device``, ``scale compute --esi``, ``sim serve``
and the simulator's constructors all get the device from one resolver (``ecattool.profiles.running``), so they
see one dictionary.

The example is the ETG.2001 modular drive (samples/esi/etg2001_cia402.xml, a copy of the corpus file): its
``Dictionary`` holds 14 objects; with the default modules of its two slots plugged in and the communication
objects synthesised it has 28 (1600h, 1A00h, 1C12h, 6040h, 6064h … come from the modules and the PDO list).
``sdo --device`` used to read the ESI alone and saw the 14.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from ecattool import esi
from ecattool.esi.model import Device
from ecattool.profiles import running
from ecattool.profiles.running import RunningDevice, as_running, device_from_file, resolve_device
from tests.conftest import ROOT, run

ETG2001 = ROOT / "samples" / "esi" / "etg2001_cia402.xml"
#: objects that only the default modules and the synthesised communication objects bring (issue 36)
FROM_MODULES = {0x1600, 0x1A00, 0x1C12, 0x1C13, 0x6040, 0x6041, 0x6064}


def _addresses(device: Device) -> set[tuple[int, int]]:
    return {(o.index, sub) for o in device.dictionary for sub in o.entries}


@pytest.fixture(scope="module")
def linted() -> Device:
    """The device lint resolves for a project naming the example."""
    import tempfile

    from ecattool.project.machine import load_machine

    with tempfile.TemporaryDirectory() as tmp:
        p = Path(tmp) / "project.yaml"
        p.write_text(f"ecattool: 1\ndrives:\n  - name: axis\n    device: {{esi: {ETG2001}}}\n")
        machine = load_machine(p)
    device = machine.slaves[0].device
    assert device is not None
    return device


def test_the_example_is_modular_and_its_file_lacks_the_module_objects(linted: Device) -> None:
    raw = esi.load_device(ETG2001)
    assert raw.slots and len(list(raw.dictionary)) == 14
    assert not FROM_MODULES & {o.index for o in raw.dictionary}
    assert len(list(linted.dictionary)) == 28 and FROM_MODULES <= {o.index for o in linted.dictionary}
    assert isinstance(linted, RunningDevice)


def test_sdo_device_sees_the_dictionary_lint_sees(capsys: pytest.CaptureFixture[str], linted: Device) -> None:
    code, out, err = run(capsys, "sdo", "info", "--target", f"sim:{ETG2001}", "--device", str(ETG2001), "--json")
    assert code == 0, err
    rows = json.loads(out)
    assert rows["dictionary"] == "device"
    seen = {(int(r["address"][2:6], 16), int(r["address"][7:9], 16)) for r in rows["entries"]}
    assert seen == _addresses(linted)


def test_sdo_read_device_types_a_module_object(capsys: pytest.CaptureFixture[str]) -> None:
    # 1C12h:01 exists only in the device as it runs; typed by it, the value is a number, not hex bytes
    code, out, err = run(capsys, "sdo", "read", "0x1C12:01", "--target", f"sim:{ETG2001}", "--device", str(ETG2001),
                         "--json")
    assert code == 0, err
    value = json.loads(out)
    assert value["type"] == "UINT" and value["value"] == 0x1600


def test_scale_compute_esi_sees_the_dictionary_lint_sees(capsys: pytest.CaptureFixture[str],
                                                         monkeypatch: pytest.MonkeyPatch, linted: Device) -> None:
    import ecattool.scaling

    seen: list[Any] = []
    real = ecattool.scaling.compute

    def spy(*args: Any, **kwargs: Any) -> Any:
        seen.append(kwargs.get("device"))
        return real(*args, **kwargs)

    monkeypatch.setattr(ecattool.scaling, "compute", spy)
    # the example has no factor group (608Fh/6091h…), so the command refuses the user units (exit 1) after it
    # computed them against the device
    code, _, err = run(capsys, "scale", "compute", str(ROOT / "samples" / "scaling" / "rotary_table.yaml"),
                       "--esi", str(ETG2001), "--json")
    assert code == 1 and "none of the scaling objects" in err
    (device,) = seen
    assert isinstance(device, RunningDevice) and _addresses(device) == _addresses(linted)


def test_map_and_the_simulator_see_the_dictionary_lint_sees(linted: Device) -> None:
    from ecattool.cli.map import _load_device
    from ecattool.sim import Drive
    from ecattool.sim.bus.serve import device_source

    assert _addresses(_load_device(str(ETG2001), None, None, None, None)) == _addresses(linted)
    assert _addresses(Drive.from_esi(ETG2001).device) == _addresses(linted)
    assert _addresses(Drive.from_device(esi.load_device(ETG2001)).device) == _addresses(linted)
    assert _addresses(device_source(str(ETG2001))[1]) == _addresses(linted)  # sim serve


def test_a_running_device_is_not_completed_again(monkeypatch: pytest.MonkeyPatch, linted: Device) -> None:
    from ecattool.sim import Drive
    from ecattool.sim.slave import drive_for_device

    def again(device: Device) -> Device:
        raise AssertionError("a device the resolver gave was completed again")

    monkeypatch.setattr(running, "complete_generic", again)
    assert as_running(linted) is linted
    assert Drive.from_device(linted).device is linted
    assert drive_for_device(linted).device is linted
    # the simulator opened on a built machine's devices (commission --target sim, bus --target sim)
    from ecattool.online import open_bus
    from ecattool.target import open_target

    target = open_target("sim", [linted, linted])
    assert [s.device for s in target.slaves()] == [linted, linted]  # type: ignore[attr-defined]
    with open_bus("sim", [linted]) as bus:
        assert len(bus.slaves) == 1


def test_the_resolver_marks_without_changing_its_input() -> None:
    raw = esi.load_device(ETG2001)
    done = as_running(raw)
    assert type(raw) is Device and len(list(raw.dictionary)) == 14  # the reader's device is left as it was
    assert as_running(done) is done
    profile = resolve_device("hdt", product="dgfox")
    assert isinstance(profile, RunningDevice) and profile.source == "profile:hdt"
    assert as_running(profile) is profile
    assert _addresses(device_from_file(ETG2001)) == _addresses(done)


def test_a_name_too_long_for_a_path_is_an_unknown_profile() -> None:
    from ecattool.errors import SelectionError

    with pytest.raises(SelectionError, match="unknown drive profile"):
        resolve_device("x" * 5000)  # Path.is_file() raises OSError (name too long) on such a name
