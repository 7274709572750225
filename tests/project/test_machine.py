"""The machine model (issue 22): one typed Machine built from a project, every kind of slave, one target opener,
one policy for a project with errors, and lint errors for what the simulator would refuse."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from ecattool.commission import commission
from ecattool.errors import EcatToolError, InputError, SelectionError
from ecattool.findings import Severity
from ecattool.pdo.model import Mapping
from ecattool.profiles.rules import FamilyRules
from ecattool.project.machine import Machine, is_axis, load_machine
from ecattool.scaling.group import FactorGroup
from ecattool.sw.image import SwImage
from tests.conftest import corpus_path, run
from tests.project.project_helpers import SAMPLES, sample

EL1XXX = "beckhoff_EL1xxx.xml"


def _project(tmp_path: Path, esi: str, select: str | None, extra: str = "", policy: str | None = None) -> Path:
    shutil.copy(corpus_path("esi", esi), tmp_path / esi)
    p = tmp_path / "p.yaml"
    p.write_text("ecattool: 1\ndrives:\n  - name: s\n    device:\n      esi: " + esi + "\n"
                 + (f"      select: \"{select}\"\n" if select else "") + (f"      policy: {policy}\n" if policy else "")
                 + extra, encoding="utf-8")
    return p


@pytest.mark.parametrize("name", SAMPLES)
def test_a_sample_is_one_typed_machine_of_axes(name):
    machine = load_machine(sample(name))
    assert isinstance(machine, Machine) and machine.findings == () and machine.loaded is not None
    for s in machine.in_bus_order():
        assert s.kind == "axis" and s.enables
        assert isinstance(s.rules, FamilyRules) and isinstance(s.mapping, Mapping)
        assert s.factor_group is None or isinstance(s.factor_group, FactorGroup)
        assert s.sw_image is None or isinstance(s.sw_image, SwImage)
    if name == "technosoft_ipos":
        assert isinstance(machine.slaves[0].sw_image, SwImage)


def test_axis_or_io_is_what_the_device_says():
    from ecattool.project.cache import load_device_cached, load_profile_cached

    assert is_axis(load_profile_cached("hdt", None, None))
    path = corpus_path("esi", EL1XXX)
    for select, why in (("EL1008", "a digital input terminal"),
                        ("EL1258", "6041h is an input channel of a terminal without 6040h"),
                        ("EL1259", "6040h and 6060h are channels; no 6041h")):
        assert not is_axis(load_device_cached(path, select, "newest")), why
    # a drive that does not declare profile 402 but has the CiA-402 objects (Inovance SV660)
    assert is_axis(load_device_cached(corpus_path("esi", "inovance_SV660_EOE_1Axis_V9.12.xml"), None, "exact"))


def test_the_el1008_example_of_the_docs_commissions_as_written(capsys, tmp_path, monkeypatch):
    """docs/project.md: `project new --esi beckhoff_EL1xxx.xml --select EL1008 --policy newest -o io.ecattool.yaml`."""
    shutil.copy(corpus_path("esi", EL1XXX), tmp_path / EL1XXX)
    monkeypatch.chdir(tmp_path)
    code, _, err = run(capsys, "project", "new", "--esi", EL1XXX, "--select", "EL1008", "--policy", "newest",
                       "-o", "io.ecattool.yaml")
    assert code == 0, err
    assert "enable" not in Path("io.ecattool.yaml").read_text().replace("# ", "")
    code, out, err = run(capsys, "lint", "io.ecattool.yaml")
    assert code == 0, out + err
    code, out, err = run(capsys, "commission", "io.ecattool.yaml", "--json")
    assert code == 0, out + err
    (drive,) = json.loads(out)["projects"][0]["drives"]
    assert drive["ok"] and drive["kind"] == "io" and drive["final_state"] == "OP"
    steps = {s["name"]: s["detail"] for s in drive["steps"]}
    assert "enable" not in steps and "identity" in steps and "state OP" in steps
    assert "1 input byte(s) read (8 object(s)" in steps["process data"]


def test_io_slaves_get_their_outputs_written_and_read_back(tmp_path):
    path = corpus_path("esi", "beckhoff_EK11xx.xml")  # a coupler has no process data: the cycle is empty
    report = commission(_project(tmp_path, path.name, "EK1100", policy="newest"))
    assert report.ok and report.drives[0].kind == "io"
    # outputs: the SMC EX260 valve manifold spreads its outputs over SM0..SM3 (until issue 22 item 4 lands, lint
    # reports that as PDO017; --allow-errors acts anyway)
    machine = load_machine(_project(tmp_path, "smc_EX260-SECx_V11.xml", "0"))
    assert {f.rule for f in machine.findings if f.severity is Severity.ERROR} <= {"PDO017"}
    report = commission(machine, allow_errors=True)
    assert report.ok, report.drives[0].error
    detail = next(s.detail for s in report.drives[0].steps if s.name == "process data")
    # the EX260 has no mailbox: its outputs are not read back, no SDO is sent to it (issue 34 item 5)
    assert detail.startswith("4 output byte(s) written (4 object(s))"), detail


def test_enable_on_an_io_slave_is_an_error_naming_enable(tmp_path):
    machine = load_machine(_project(tmp_path, EL1XXX, "EL1008", "    enable: true\n", policy="newest"))
    (f,) = [f for f in machine.findings if f.severity is Severity.ERROR]
    assert f.rule == "PRJ025" and "remove enable:" in f.message and f.location.line == 8


def test_a_soe_drive_is_refused_at_its_pdo(tmp_path):
    machine = load_machine(_project(tmp_path, "beckhoff_AX5xxx.xml", "AX5201-0000-0210", policy="newest"))
    (f,) = [f for f in machine.findings if f.rule == "PRJ026"]
    assert f.severity is Severity.ERROR and f.location.file.endswith("beckhoff_AX5xxx.xml") and f.location.line
    assert "SoE" in f.message


def test_an_esi_whose_mapping_objects_contradict_its_pdos_is_refused(tmp_path, capsys):
    p = _project(tmp_path, "beckhoff_EM7xxx.xml", "1")
    machine = load_machine(p)
    (f,) = [f for f in machine.findings if f.severity is Severity.ERROR]
    assert f.rule == "PRJ027" and f.location.file.endswith("beckhoff_EM7xxx.xml") and f.location.line
    report = commission(machine)
    assert not report.ok and "PRJ027" in report.drives[0].error and "--allow-errors" in report.drives[0].error
    # acting anyway: the slave powers on with the dictionary's mapping (as a slave stack does), another layout
    # than the one lint checked (here of the same 28 bytes, so one I/O cycle cannot tell them apart)
    from ecattool.od.model import EcState
    from ecattool.sim import Drive

    drive = Drive.from_device(machine.slaves[0].device)
    drive.request_state(EcState.PREOP)
    assert drive.sdo_upload(0x1601, 0) == b"\x01" and drive.sdo_upload(0x1601, 1) == (0x70200B10).to_bytes(4, "little")
    assert len(machine.slaves[0].mapping.rx[0].entries) == 16
    code, out, _ = run(capsys, "commission", str(p), "--allow-errors", "--json")
    (reported,) = json.loads(out)["projects"][0]["drives"]
    assert code == 0 and reported["ok"]


def test_the_simulators_refusal_reason_reaches_text_json_and_html(tmp_path, capsys):
    """A configurable slave refuses an image that is not whole bytes (lint: PDO027, disabled here to act anyway);
    the simulator's reason is in every report, not only in its event log."""
    p = _project(tmp_path, "inovance_SV660_EOE_1Axis_V9.12.xml", None,
                 "    dc: {opmode: DC, cycle_ns: 1000000}\n    pdo:\n      rx:\n        - index: 0x1600\n"
                 "          entries: [controlword, \"0x607A:00/32\", \"gap/4\"]\n"
                 "    disable_rules: [{rule: PDO027, reason: to see what the drive says}]\n")
    why = "AL status 0x001D: invalid output configuration (52 bits of process data is not a whole number of bytes)"
    code, out, _ = run(capsys, "commission", str(p))
    assert code == 1 and why in out
    code, out, _ = run(capsys, "commission", str(p), "--json")
    assert code == 1 and why in json.loads(out)["projects"][0]["drives"][0]["error"]
    pytest.importorskip("jinja2")
    html = tmp_path / "r.html"
    code, _, _ = run(capsys, "commission", str(p), "--report", str(html))
    assert code == 1 and "52 bits of process data is not a whole number of bytes" in html.read_text(encoding="utf-8")


def test_a_move_that_does_not_fit_607a_is_an_error_at_the_distance(tmp_path):
    p = tmp_path / "p.yaml"
    p.write_text("ecattool: 1\ndrives:\n  - name: x\n    device: {profile: hdt}\n"
                 "    move: {distance: 100000000000}\n", encoding="utf-8")
    (f,) = [f for f in load_machine(p).findings if f.rule == "PRJ024"]
    assert f.severity is Severity.ERROR and (f.location.line, f.location.column) == (5, 22)
    assert "DINT" in f.message


def test_one_policy_for_a_project_with_errors(tmp_path, capsys):
    p = _project(tmp_path, EL1XXX, "EL1008", "    enable: true\n", policy="newest")
    for args in (("startup", "export", "--project", str(p), "--format", "eni"),
                 ("sim", "serve", str(p), "--list")):
        code, _, err = run(capsys, *args)
        assert code == 1 and "PRJ025" in err and "--allow-errors" in err and f"{p}:8" in err, (args, err)
        code, _, err = run(capsys, *args, "--allow-errors")
        assert code == 0, (args, err)
    machine = load_machine(p)
    with pytest.raises(InputError, match="cannot act: the project has lint errors"):
        machine.refuse_errors("act")
    machine.refuse_errors("act", allow_errors=True)


def test_one_target_opener():
    from ecattool.project.cache import load_profile_cached
    from ecattool.target import SimTarget, open_target, slave_at
    from tests.test_fitness import TARGET_CONSTRUCTORS, _trees, target_constructions

    # one opener: no module but target.opener constructs a target (the one left over may only go)
    found = target_constructions(_trees())
    extra = {rel: lines for rel, lines in found.items() if len(lines) > TARGET_CONSTRUCTORS.get(rel, 0)}
    assert not extra, f"a target constructed outside target.opener.open_target: {extra}"
    # the simulator and the live bus's masters; the commissioning pysoem is built in the child the opener starts
    assert len(found.get("target/opener.py", ())) == TARGET_CONSTRUCTORS["target/opener.py"]

    target = open_target("sim", [load_profile_cached("hdt", None, None)] * 2)
    assert isinstance(target, SimTarget) and len(target.slaves()) == 2
    assert slave_at(target, 1).position == 1
    with pytest.raises(SelectionError, match="the bus has 2"):
        slave_at(target, 2)
    for spec in ("simulator", "pysoem:", "eth0", "kickcat", "sim:", "sim: , "):
        with pytest.raises(SelectionError, match="unknown target|names no slaves"):
            open_target(spec)
    # sim:SOURCES: its own slaves, the devices given are not used; KickCAT reads a bus, it is no slave target
    target = open_target("sim:hdt, technosoft-ipos", [load_profile_cached("hdt", None, None)])
    assert [s.identity().vendor_id for s in target.slaves()] == [0x289, 0x1A3]
    with pytest.raises(SelectionError, match="KickCAT reads a live bus"):
        open_target("kickcat:eth0")


def test_one_target_parser_for_every_command():
    """The live-bus commands and the slave commands read a spec the same way (target.opener.parse_target)."""
    from ecattool.online import open_bus
    from ecattool.target.opener import TargetSpec, parse_target

    assert parse_target(" SIM ") == TargetSpec(" SIM ", "sim")
    assert parse_target("sim:hdt,x.xml") == TargetSpec("sim:hdt,x.xml", "sim", sources=("hdt", "x.xml"))
    assert parse_target("pysoem: eth0") == TargetSpec("pysoem: eth0", "pysoem", interface="eth0")
    assert parse_target("KickCAT:ecat0").interface == "ecat0"
    for spec in ("canbus:0", "sim:", "pysoem"):
        with pytest.raises(SelectionError) as slave_cmd:
            parse_target(spec)
        with pytest.raises(SelectionError) as bus_cmd:
            open_bus(spec)
        assert bus_cmd.value.message == slave_cmd.value.message
    with open_bus("sim:hdt") as bus:
        assert len(bus.slaves) == 1
    with pytest.raises(SelectionError, match="without a project has no slaves"):
        open_bus("sim")


@pytest.mark.parametrize(("target", "ok"), [("sim", True), ("pysoem:eth0", True), ("canbus:0", False),
                                            ("kickcat:eth0", False), ("sim:hdt", False)])
def test_a_project_target_commission_cannot_open_fails_lint(tmp_path, target, ok):
    """A project that lints clean must commission: its target: is checked at lint (PRJ001, with its line)."""
    from ecattool.project.machine import load_machine

    path = tmp_path / "machine.yaml"
    path.write_text(f"ecattool: 1\ntarget: {target}\ndrives:\n  - name: x\n    device: {{profile: hdt}}\n")
    findings = [f for f in load_machine(path).findings if f.rule == "PRJ001"]
    if ok:
        assert findings == []
    else:
        (f,) = findings
        assert f.location is not None and f.location.line == 2
        assert "a project's target is 'sim' (its own drives, simulated) or 'pysoem:<interface>'" in f.message


def test_the_simulator_serves_the_modular_device_lint_checks():
    """One rule plugs the default modules in (profiles.generic.plug_default_modules): the simulated drive's
    dictionary and PDOs are the linted device's."""
    from ecattool.project.cache import load_device_cached
    from ecattool.sim.slave import drive_for_device

    device = load_device_cached(corpus_path("esi", "etg_ETG2001_ModulesSlots_CiA402.xml"), None, "exact")
    drive = drive_for_device(device)
    assert sorted(o.index for o in drive.device.dictionary) == sorted(o.index for o in device.dictionary)
    assert [p.index for p in drive.device.rx_pdos] == [p.index for p in device.rx_pdos]


def test_scale_explain_reads_what_a_projects_drive_holds(capsys):
    """`scale explain --project`: the factor objects the drive holds after its startup list, in its family."""
    code, out, err = run(capsys, "scale", "explain", "--project", str(sample("hdt")), "--json")
    assert code == 0, err
    data = json.loads(out)
    assert data["family"] == "hdt"
    slave = load_machine(sample("hdt")).slaves[0]
    written = {(c.index, c.subindex): c.int_value for c in slave.startup if 0x6089 <= c.index <= 0x60AB}
    assert written and all(slave.object_values(range(0x6089, 0x60AC))[k] == v for k, v in written.items())
    code, _, err = run(capsys, "scale", "explain", "--project", str(sample("hdt")), "--drive", "nope")
    assert code == 1 and "has no drive 'nope'" in err


def test_a_mapping_object_the_slave_cannot_map_is_a_lint_error_at_the_object(tmp_path):
    """A SOES-style ESI: the PDO list is right, the dictionary's own 1B01h maps 0x00060120 (a 32-bit entry of the
    16-bit dummy 0006h, in a TxPDO). The slave runs the dictionary's mapping: lint says so at the object."""
    name = "inovance_SV660_EOE_1Axis_V9.12.xml"
    text = corpus_path("esi", name).read_bytes().decode("utf-8")
    at = text.index("<Index>#x1B01</Index>")
    hit = text.index("#x603F0010", at)
    (tmp_path / name).write_text(text[:hit] + "#x00060120" + text[hit + len("#x603F0010"):], encoding="utf-8")
    p = tmp_path / "p.yaml"
    p.write_text(f"ecattool: 1\ndrives:\n  - name: s\n    device: {{esi: {name}}}\n    dc: {{opmode: DC, cycle_ns: 1000000}}\n",
                 encoding="utf-8")
    errors = [f for f in load_machine(p).findings if f.severity is Severity.ERROR]
    assert [f.rule for f in errors] == ["PRJ027"] and "0x00060120" in errors[0].message
    assert errors[0].location.file.endswith(name) and errors[0].location.line == text[:at].count("\n")
    # the simulated slave powers on with its dictionary's mapping, as a slave stack does, and refuses it
    from ecattool.od.model import EcState
    from ecattool.sim import Drive

    machine = load_machine(p)
    drive = Drive.from_device(machine.slaves[0].device)
    drive.request_state(EcState.PREOP)
    assert drive.sdo_upload(0x1B01, 1) == (0x00060120).to_bytes(4, "little")
    with pytest.raises(EcatToolError, match=r"0x001E.*PDO 0x1B01 maps an invalid entry 0x00060120"):
        drive.request_state(EcState.SAFEOP)
    report = commission(machine, allow_errors=True)
    assert not report.ok and "0x00060120" in report.drives[0].error


def test_a_failed_enable_names_the_setting_that_skips_it(monkeypatch):
    from ecattool.commission import cia402
    from ecattool.errors import TargetError

    def refuse(*_args: object, **_kw: object) -> list[str]:
        raise TargetError("drive did not reach OPERATION ENABLED in 200 cycles")

    monkeypatch.setattr(cia402, "enable", refuse)
    report = commission(sample("hdt"))
    assert not report.ok and "enable: false in the project" in report.drives[0].error


def test_a_fixed_two_bit_terminal_runs_with_its_sync_manager_padded(tmp_path):
    """The EL1002 has two input bits in fixed PDOs and no mailbox: a real one runs with SM3 one byte long. The
    simulator pads instead of refusing SAFE-OP (lint's PDO027 for it is being removed, issue 22 item 4)."""
    extra = "    disable_rules: [{rule: PDO027, reason: the ESC pads the fixed 2 bits to a byte}]\n"
    machine = load_machine(_project(tmp_path, EL1XXX, "EL1002", extra, policy="newest"))
    assert [f for f in machine.findings if f.severity is Severity.ERROR] == []
    report = commission(machine)
    assert report.ok, report.drives[0].error
    assert "1 input byte(s) read (2 object(s)" in next(s.detail for s in report.drives[0].steps if s.name == "process data")


def test_a_project_wide_disable_holds_for_commission_too(tmp_path):
    """Lint clean ⇒ commissions: a rule disabled for the whole project does not refuse the slave either."""
    shutil.copy(corpus_path("esi", EL1XXX), tmp_path / EL1XXX)
    p = tmp_path / "p.yaml"
    p.write_text("ecattool: 1\ndisable_rules: [{rule: PDO027, reason: the ESC pads the fixed 2 bits}]\ndrives:\n"
                 f"  - name: s\n    device: {{esi: {EL1XXX}, select: EL1002, policy: newest}}\n", encoding="utf-8")
    machine = load_machine(p)
    assert machine.findings == ()
    assert commission(machine).ok


def test_dc_is_resolved_once_per_slave_and_consumers_read_it(monkeypatch: pytest.MonkeyPatch) -> None:
    """DC is a typed field of the slave: AssignActivate from the project or its ESI OpMode, the SYNC0 cycle and
    shift (the project's, else the OpMode's), SYNC1 where the OpMode gives a cycle; export writes that."""
    import copy

    from ecattool.esi.model import DcOpMode
    from ecattool.project import machine as machine_module
    from ecattool.project.machine import SlaveDc, slave_config
    from ecattool.project.model import DcConfig
    from ecattool.project.resolve import resolve_dc
    from tests.test_fitness import _trees, calls_of

    # once: the package resolves DC in one place (building the slave); consumers read the slave's field
    sites = calls_of(_trees(), "resolve_dc")
    assert len(sites) == 1 and sites[0].startswith("ecattool/project/machine.py:"), sites
    assert sites[0].endswith(" in build_slave"), sites
    resolved: list[object] = []
    monkeypatch.setattr(machine_module, "resolve_dc", lambda *a: resolved.append(a) or resolve_dc(*a))
    (s,) = load_machine(sample("generic_esi")).slaves  # dc: {opmode: DC, cycle_ns: 1000000}; the ESI: #x300, shift 0
    assert len(resolved) == 1
    assert s.dc == SlaveDc(0x0300, "DC", 1_000_000, 0, None, None) and s.dc.active
    cfg = slave_config(s)
    assert len(resolved) == 1  # export's configuration reads s.dc
    assert (cfg.dc_assign_activate, cfg.dc_cycle_ns, cfg.dc_shift_ns) == (0x0300, 1_000_000, 0)
    (ct,) = load_machine(sample("controltechniques")).slaves  # dc: {assign_activate: 0x0300, cycle_ns: 1000000}
    assert ct.dc == SlaveDc(0x0300, None, 1_000_000, None)
    (hdt,) = load_machine(sample("hdt")).slaves
    assert hdt.dc is None and slave_config(hdt).dc_assign_activate is None
    device = copy.copy(s.device)
    device.dc_opmodes = [DcOpMode("Sync01", "", 0x0700, 2_000_000, None, 1000, None, 500_000, None, 100, None)]
    dc = resolve_dc(s.drive.model_copy(update={"dc": DcConfig(opmode="Sync01")}), device)
    assert dc == SlaveDc(0x0700, "Sync01", 2_000_000, 1000, 500_000, 100)
    # the project's own SYNC1 values override the OpMode's, as cycle_ns does (0: SYNC1 with every SYNC0 pulse)
    dc = resolve_dc(s.drive.model_copy(update={"dc": DcConfig(opmode="Sync01", sync1_cycle_ns=0,
                                                              sync1_shift_ns=-20)}), device)
    assert dc == SlaveDc(0x0700, "Sync01", 2_000_000, 1000, 0, -20)
    dc = resolve_dc(s.drive.model_copy(update={"dc": DcConfig(assign_activate=0x0700, sync1_cycle_ns=125_000)}),
                    device)
    assert dc == SlaveDc(0x0700, None, None, None, 125_000, None)
    assert resolve_dc(s.drive.model_copy(update={"dc": DcConfig(opmode="nope")}), device) is None  # PRJ040's
    assert resolve_dc(s.drive.model_copy(update={"dc": DcConfig(opmode="nope", assign_activate=0)}),
                      device) == SlaveDc(0, "nope", None, None)


def test_a_slave_is_frozen_and_assembled_in_one_place() -> None:
    """issue 36: the steps return what they resolve; build_slave makes the Slave from those values (the one
    place the package constructs one) and nothing changes a Slave or a Machine afterwards."""
    import dataclasses

    from tests.test_fitness import _trees, calls_of

    sites = calls_of(_trees(), "Slave")
    assert sites and all(s.startswith("ecattool/project/machine.py:") and s.endswith(" in build_slave")
                         for s in sites), sites
    machine = load_machine(sample("technosoft_ipos"))
    (s,) = machine.slaves
    assert s.mapping is not None and s.factor_group is not None and s.sw_image is not None and len(s.startup)
    with pytest.raises(dataclasses.FrozenInstanceError):
        s.mapping = None  # type: ignore[misc]
    with pytest.raises(dataclasses.FrozenInstanceError):
        machine.slaves = ()  # type: ignore[misc]
    assert isinstance(s.findings, tuple) and isinstance(machine.slaves, tuple) and isinstance(machine.findings, tuple)


#: the machine's former names (issue 36): none is left in the package or the tests, so nothing calls them (each
#: written with a character class, so that the issue's own grep for the names finds none here either)
FORMER_NAMES = (r"\blint_projec[t]\b", r"\bResolvedDriv[e]\b", r"\bProjectResul[t]\b", r"\bbuild_driv[e]\b",
                r"\bdrive_confi[g]\(", r"\bloaded is Non[e]\b")


def test_the_former_names_of_the_machine_are_gone() -> None:
    import re

    from ecattool.project import export, lint

    here = Path(__file__).resolve()
    root = here.parents[2]
    found = [f"{path.relative_to(root)}: {pattern}"
             for path in sorted([*(root / "ecattool").rglob("*.py"), *(root / "tests").rglob("*.py")]) if path != here
             for pattern in FORMER_NAMES if re.search(pattern, path.read_text(encoding="utf-8"))]
    assert not found, found
    assert not hasattr(Machine, "drives") and not hasattr(export, "refuse_errors") and not hasattr(export, "drive_config")
    assert not hasattr(lint, "lint_" "project") and not hasattr(lint, "Project" "Result")
