"""Command-line device flags build the same objects a project entry does (issue 36.4): a one-slave
:class:`~ecattool.project.machine.Machine` made by :meth:`Machine.from_device_flags` through ``build_slave``, not a
second resolver. ``map``, ``scale compute --esi``, ``sim run``/``sim show`` and ``sdo … --device`` act on its
``slaves[0]``.

The examples: the ETG.2001 modular drive (samples/esi/etg2001_cia402.xml, a copy of the corpus file
etg_ETG2001_ModulesSlots_CiA402.xml: two slots whose default modules bring 1600h/1A00h/6040h …) and the built-in
HDT family (dgfox).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from ecattool.errors import EcatToolError, InputError
from ecattool.profiles import running
from ecattool.project import machine as machine_module
from ecattool.project.machine import Machine, Slave, load_machine
from tests.conftest import ROOT, run

ETG2001 = ROOT / "samples" / "esi" / "etg2001_cia402.xml"
SCRIPT = "- state: PREOP\n- read: \"6041:00\"\n"


def _project_slave(tmp_path: Path, device_yaml: str) -> Slave:
    p = tmp_path / "project.yaml"
    p.write_text(f"ecattool: 1\ndrives:\n  - name: axis\n    device: {device_yaml}\n")
    (slave,) = load_machine(p).slaves
    return slave


def _same_slave(a: Slave, b: Slave) -> None:
    """The device dictionary (every entry and its default), the rules, the mapping and the startup list."""
    da, db = a.require_device(), b.require_device()
    assert type(da) is type(db) is running.RunningDevice
    assert ({(o.index, s): (e.name, e.default) for o in da.dictionary for s, e in o.entries.items()}
            == {(o.index, s): (e.name, e.default) for o in db.dictionary for s, e in o.entries.items()})
    assert (da.vendor_id, da.product_code, da.revision, da.type_name) == (db.vendor_id, db.product_code,
                                                                          db.revision, db.type_name)
    assert a.rules == b.rules and a.rules is not None
    assert a.mapping is not None and b.mapping is not None and a.mapping.to_json() == b.mapping.to_json()
    assert [(c.transition, c.index, c.subindex, c.data) for c in a.startup] == \
        [(c.transition, c.index, c.subindex, c.data) for c in b.startup]
    assert a.kind == b.kind and a.dc == b.dc


def test_esi_flags_and_a_project_entry_give_the_same_slave(tmp_path: Path) -> None:
    flags = Machine.from_device_flags(esi=str(ETG2001))
    (slave,) = flags.slaves
    _same_slave(slave, _project_slave(tmp_path, f"{{esi: {ETG2001}}}"))
    # the device as it runs: the default modules of its slots are plugged in (the file's Dictionary lacks 6040h)
    assert slave.require_device().dictionary.entry(0x6040, 0) is not None
    assert slave.kind == "axis" and len(slave.mapping.rx) == 2  # type: ignore[union-attr]
    # and the findings are the ones lint has for that entry (the ESI's checks ran on the way)
    linted = _project_slave(tmp_path, f"{{esi: {ETG2001}}}")
    assert [(f.rule, f.message) for f in flags.findings] == [(f.rule, f.message) for f in linted.findings]


def test_profile_flags_and_a_project_entry_give_the_same_slave(tmp_path: Path) -> None:
    (slave,) = Machine.from_device_flags(profile="hdt", product="dgfox").slaves
    _same_slave(slave, _project_slave(tmp_path, "{profile: hdt, product: dgfox}"))
    assert slave.family == "hdt" and slave.require_device().source == "profile:hdt"
    # a SOURCE argument (sim run, sdo --device) that is not a file is a profile name
    (by_source,) = Machine.from_device_flags(source="hdt", product="dgfox").slaves
    _same_slave(by_source, slave)


def test_an_esi_path_is_relative_to_the_current_directory(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ETG2001.parent)
    (slave,) = Machine.from_device_flags(esi=ETG2001.name).slaves
    assert slave.require_device().type_name == "Drive1"
    (by_source,) = Machine.from_device_flags(source=ETG2001.name).slaves
    _same_slave(by_source, slave)


def _message(call: Any) -> str:
    with pytest.raises(EcatToolError) as info:
        call()
    return str(info.value)


def test_errors_keep_their_one_line_form(tmp_path: Path) -> None:
    """What does not resolve raises the message the resolver gave, with its file and line (not a finding at a
    project line, there is no project file)."""
    broken = tmp_path / "broken.xml"
    broken.write_text("<EtherCATInfo>\n  <Vendor><Id>#x2</Id></Vendor>\n  <Descriptions>\n")
    cases: list[tuple[Any, Any]] = [
        (lambda: Machine.from_device_flags(esi=str(broken)), lambda: running.device_from_file(broken)),
        (lambda: Machine.from_device_flags(esi=str(ETG2001), select="nosuch"),
         lambda: running.device_from_file(ETG2001, "nosuch")),
        (lambda: Machine.from_device_flags(profile="nope"), lambda: running.device_from_profile("nope")),
    ]
    for flags, resolver in cases:
        text = _message(flags)
        assert text == _message(resolver) and "\n" not in text, text
    # the file and the line where the XML breaks off (its end)
    assert _message(cases[0][0]).startswith(f"{broken}:4:1: not well-formed XML")
    with pytest.raises(InputError, match="'esi' .*or 'profile'"):
        Machine.from_device_flags()
    # a file that cannot be read: that file's error, as every reader says it (not lint's "ESI file … not found")
    absent = tmp_path / "absent.xml"
    assert _message(lambda: Machine.from_device_flags(esi=str(absent))) == f"{absent}: not found"
    assert _message(lambda: Machine.from_device_flags(esi=str(tmp_path))) == f"{tmp_path}: is a directory, not a file"


@pytest.mark.parametrize("args", [
    ("map", "check", "--esi", str(ETG2001), "--json"),
    ("map", "layout", "--profile", "hdt", "--json"),
    ("map", "sdo", "--profile", "hdt", "--rx", "0x1600=controlword", "--json"),
    ("scale", "compute", str(ROOT / "samples" / "scaling" / "rotary_table.yaml"), "--esi", str(ETG2001), "--json"),
    ("sim", "show", "hdt", "--json"),
    ("sim", "run", str(ETG2001), "SCRIPT", "--json"),
    ("sdo", "info", "--target", "sim:hdt", "--device", "hdt", "--json"),
])
def test_the_commands_act_on_the_one_slave_machine(args: tuple[str, ...], tmp_path: Path,
                                                   capsys: pytest.CaptureFixture[str],
                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    built: list[Machine] = []
    real = machine_module.one_slave_machine

    def spy(*a: Any, **kw: Any) -> Machine:
        built.append(real(*a, **kw))
        return built[-1]

    monkeypatch.setattr(machine_module, "one_slave_machine", spy)
    script = tmp_path / "steps.yaml"
    script.write_text(SCRIPT)
    code, out, err = run(capsys, *(str(script) if a == "SCRIPT" else a for a in args))
    # scale compute refuses the user units of a device without a factor group (exit 1), after computing them
    if args[0] == "scale":
        assert code == 1 and "none of the scaling objects" in err
    else:
        assert code == 0 and out, err
    assert len(built) == 1 and len(built[0].slaves) == 1
