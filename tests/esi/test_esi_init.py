"""The ESI's init commands (issue 14, item 3): the ``Mailbox/CoE/InitCmd``s of every corpus ESI that has them
reach the drive's startup list in transition order after the PDO programming and before the parameters, at
their ESI line; ``project new`` lists them; ``esi_init_cmds:`` changes or skips them; every exporter carries
them and ``commission`` writes them to the (simulated) drive."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from lxml import etree

from ecattool.commission import commission
from ecattool.findings import Severity
from ecattool.project.export import slave_configs
from ecattool.project.machine import load_machine
from ecattool.startup import export, import_bytes
from ecattool.startup.formats import FORMATS
from ecattool.target.sim import SimTarget
from tests.conftest import corpus_path, run

#: (ESI, selector, device index in the file) of every corpus ESI whose device has CoE init commands
WITH_INIT = [("elmo_Elmo_ECAT_00010420_V11.xml", "2", 2), ("inovance_SV660_EOE_1Axis_V9.12.xml", None, 0),
             ("beckhoff_AX2xxx.xml", None, 0), ("weidmueller_UR20_FBC.xml", "0", 0)]
#: drives whose skeleton commissions with ESI commands left in it (AX2000: its dictionary contradicts its init
#: commands, see below; the SV660N's one command, 6060h := 8, gives way to the skeleton's PP mode parameter, so
#: its project is the generic ESI sample, a CSP move)
DRIVES = [("elmo_Elmo_ECAT_00010420_V11.xml", "2"), ("copley_XE2_4.60.xml", None)]


def _expected(name: str, device_no: int) -> list[tuple[str, int, int, bytes, int]]:
    """The device's CoE InitCmds read straight from the XML (not through ecattool's reader)."""
    root = etree.parse(str(corpus_path("esi", name))).getroot()
    device = root.findall("Descriptions/Devices/Device")[device_no]
    out = []
    for ic in device.findall("Mailbox/CoE/InitCmd"):
        for t in ic.findall("Transition"):
            out.append((t.text.strip(), int(ic.findtext("Index").strip().replace("#x", ""), 16),
                        int(ic.findtext("SubIndex").strip()), bytes.fromhex(ic.findtext("Data").strip()), ic.sourceline))
    return out


def _project(tmp: Path, name: str, select: str | None, body: str = "") -> Path:
    shutil.copy(corpus_path("esi", name), tmp / name)
    p = tmp / "m.yaml"
    sel = f", select: {select!r}" if select else ""
    p.write_text(f"ecattool: 1\ndrives:\n  - name: a\n    device: {{esi: {name}{sel}}}\n{body}")
    return p


@pytest.mark.parametrize(("name", "select", "device_no"), WITH_INIT, ids=[w[0].split("_")[0] for w in WITH_INIT])
def test_the_init_commands_of_each_corpus_esi_are_in_the_startup_list(tmp_path, name, select, device_no):
    want = _expected(name, device_no)
    assert want
    (rd,) = load_machine(_project(tmp_path, name, select)).slaves
    got = [(c.transition, c.index, c.subindex, c.data, c.source.line) for c in rd.startup if c.source.file.endswith(name)]
    assert got == want
    assert all(c.source.file.endswith(name) for c in rd.startup)  # no parameters: nothing else


def test_module_init_commands_follow_their_slot(tmp_path):
    """Copley XE2: each axis slot's default module (CSP) writes its own 6060h: 6060h and, one SlotIndexIncrement
    (0x800) on, 6860h; both from the module's one InitCmd."""
    (rd,) = load_machine(_project(tmp_path, "copley_XE2_4.60.xml", None)).slaves
    assert [(c.transition, c.index, c.data) for c in rd.startup] == [("PS", 0x6060, b"\x08"), ("PS", 0x6860, b"\x08")]
    assert rd.startup.commands[0].source.line == rd.startup.commands[1].source.line == 16661


def test_order_pdo_programming_then_esi_then_parameters(tmp_path):
    """PDO programming, the ESI's commands, the parameters; a parameter for the same object and transition
    replaces the ESI's command (the project's value, written once)."""
    body = ("    pdo: {rx: [{index: 0x1600}], tx: [{index: 0x1A00}]}\n"
            "    parameters:\n      - {object: \"6060:00\", value: 1}\n")
    (rd,) = load_machine(_project(tmp_path, "elmo_Elmo_ECAT_00010420_V11.xml", "2", body)).slaves
    addrs = [(c.index, c.subindex) for c in rd.startup]
    esi = addrs.index((0x60C2, 1))
    assert all(a[0] in (0x1C12, 0x1C13, 0x1600, 0x1A00) for a in addrs[:esi]) and esi > 0
    # the parameter writes 6060h in PS too: it replaces the ESI's command (one write, the project's value)
    assert addrs[esi:] == [(0x60C2, 1), (0x6060, 0)] and rd.startup.commands[-1].data == b"\x01"


def test_esi_init_cmds_change_or_skip_one(tmp_path):
    body = ("    esi_init_cmds:\n      - {object: \"6060:00\", value: 1, comment: pp instead}\n"
            "      - {object: \"60C2:01\", transition: PS, skip: true}\n")
    result = load_machine(_project(tmp_path, "elmo_Elmo_ECAT_00010420_V11.xml", "2", body))
    assert [str(f) for f in result.findings] == []
    (rd,) = result.slaves
    assert [(c.index, c.data, c.comment) for c in rd.startup] == [(0x6060, b"\x01", "pp instead")]
    assert rd.startup.commands[0].source.line == 6  # the project's value, located in the project


@pytest.mark.parametrize(("entry", "rule", "words"), [
    ('{object: "6061:00", skip: true}', "PRJ022", "no init command writing 6061:00"),
    ('{object: "6060:00", transition: SO, skip: true}', "PRJ022", "6060:00 in SO"),
    ('{object: "6060:00", value: 300}', "PRJ013", "300 is out"),
])
def test_an_entry_that_changes_nothing_or_writes_nonsense_is_an_error(tmp_path, entry, rule, words):
    body = f"    esi_init_cmds:\n      - {entry}\n"
    found = [f for f in load_machine(_project(tmp_path, "elmo_Elmo_ECAT_00010420_V11.xml", "2", body)).findings
             if f.severity is Severity.ERROR]
    assert [f.rule for f in found] == [rule] and words in found[0].message and found[0].location.line == 6, found


def test_init_commands_the_esi_dictionary_refuses_are_named_at_their_line(tmp_path):
    """AX2000: its InitCmds write 6060h (read-only in its own dictionary) and 60C2h (not in it)."""
    found = [f for f in load_machine(_project(tmp_path, "beckhoff_AX2xxx.xml", None)).findings if f.rule == "PRJ021"]
    assert [(f.location.line, f.severity) for f in found] == [(11020, Severity.ERROR), (11027, Severity.ERROR),
                                                             (11034, Severity.ERROR)]
    assert "read-only" in found[0].message and "does not have" in found[1].message
    assert all(f.location.file.endswith("beckhoff_AX2xxx.xml") for f in found)


def _skeleton(capsys, tmp: Path, name: str, select: str | None) -> Path:
    shutil.copy(corpus_path("esi", name), tmp / name)
    out = tmp / "m.yaml"
    code, _, err = run(capsys, "project", "new", "--esi", name, *(["--select", select] if select else []), "-o", str(out))
    assert code == 0, err
    return out


def test_project_new_lists_them_and_proposes_skipping_what_the_dictionary_refuses(capsys, tmp_path):
    text = _skeleton(capsys, tmp_path, "beckhoff_AX2xxx.xml", None).read_text()
    assert "    #   PS 6060:00 = 254 (Op mode, ESI line 11020)\n" in text
    assert "    #   PS 60C2:01 = hex:02 (Cycle time, ESI line 11027)\n" in text
    out = tmp_path / "m.yaml"
    out.write_text(text.replace("    # esi_init_cmds:", "    esi_init_cmds:").replace("    #   - {object", "      - {object"))
    assert not [f for f in load_machine(out).findings if f.rule in ("PRJ021", "PRJ022")]


@pytest.fixture(scope="module")
def drive_projects(tmp_path_factory):
    """Skeletons of the drives with init commands, as `project new` writes them (they commission)."""
    from ecattool.cli import main

    out = []
    for name, select in DRIVES:
        tmp = tmp_path_factory.mktemp(name.split("_")[0])
        shutil.copy(corpus_path("esi", name), tmp / name)
        try:
            main(["project", "new", "--esi", name, *(["--select", select] if select else []), "-o", str(tmp / "m.yaml")])
        except SystemExit as exc:
            assert not exc.code
        out.append(tmp / "m.yaml")
    from tests.project.project_helpers import sample

    return [*out, sample("generic_esi")]


def _esi_commands(path: Path) -> list[tuple[str, int, int, bytes]]:
    (rd,) = load_machine(path).slaves
    return [(c.transition, c.index, c.subindex, c.data) for c in rd.startup
            if c.source is not None and c.source.file.endswith(".xml")]


@pytest.mark.parametrize("fmt", [f for f, x in FORMATS.items() if x.can_export])
def test_every_exporter_carries_them(drive_projects, fmt):
    for path in drive_projects:
        want = _esi_commands(path)
        assert want, path
        text = export(slave_configs(path), fmt, lossy=True)  # the tables TwinCAT/CSV have no place for: not tested here
        if FORMATS[fmt].can_import:
            (cfg,) = import_bytes(text.encode(), f"out.{fmt}", fmt)
            got = {(c.transition, c.index, c.subindex, c.data) for c in cfg.commands}
            assert set(want) <= got, (fmt, path)
        else:  # written for a compiler or an interpreter: the index and the value are in the text
            for _, index, sub, data in want:
                assert f"0x{index:04X}".lower() in text.lower() and str(int.from_bytes(data, "little")) in text, fmt


def test_commission_writes_them_in_pre_op_before_the_parameters(drive_projects):
    for path in drive_projects:
        (rd,) = load_machine(path).slaves
        target = SimTarget.from_devices([rd.device])
        report = commission(path, target)
        assert report.ok, [s.detail for d in report.drives for s in d.steps if not s.ok]
        events = [e for e in target.slaves()[0].events if e.kind in ("sdo_download", "state")]
        safeop = next(k for k, e in enumerate(events) if e.kind == "state" and e.data["state"] == "SAFEOP")
        writes = [(e.data["index"], e.data["subindex"], e.data["data"]) for e in events[:safeop] if e.kind == "sdo_download"]
        firsts = [writes.index((i, s, d.hex())) for _, i, s, d in _esi_commands(path)]  # all in PRE-OP
        assert firsts == sorted(firsts)
        params = [(c.index, c.subindex, c.data.hex()) for c in rd.startup if c.source.file == str(path)]
        assert all(writes.index(p) > max(firsts) for p in params)


def test_the_pysoem_target_sends_them_too():
    """The same startup list through the pysoem target (a fake pysoem whose slave is a simulated drive): the
    generic ESI sample's SV660N gets its ESI's PS 6060h := 8 as the first SDO download."""
    from tests.project.project_helpers import sample
    from tests.commission.test_commission_pysoem import pysoem_on, sim_drives

    path = sample("generic_esi")
    drives = sim_drives(path)
    target, _ = pysoem_on(drives)
    assert commission(path, target=target).ok
    writes = [(e.data["index"], e.data["subindex"], e.data["data"]) for e in drives[0].events if e.kind == "sdo_download"]
    assert writes[0] == (0x6060, 0, "08")
