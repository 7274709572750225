"""Project → startup export: every exporter's output for the four samples, checked structurally (ENI element
order, IgH C through gcc, pysoem compiled and run against a fake master, ros2/ecmc/TwinCAT/JSON/CSV read back
by the importers), the `startup export --project` CLI, and refusal of projects with lint errors."""

from __future__ import annotations

import pytest

from ecattool.startup.model import is_pdo_programming
from lxml import etree

from ecattool.errors import EncodeError, InputError
from ecattool.project.export import slave_configs
from ecattool.startup import StartupCommand, export, import_bytes
from ecattool.startup.formats import eni
from tests.conftest import ROOT
from tests.project.project_helpers import SAMPLES, run, sample, write_project
from tests.startup.test_startup_export import FakeMaster, FakeSlave, _children, _gcc, _in_order


def _key(cmd: StartupCommand) -> tuple:
    return (cmd.transition, cmd.index, cmd.subindex, cmd.data, cmd.complete_access)


def _pdos(pdos) -> list:
    return [(p.index, [(e.index, e.subindex, e.bit_len) for e in p.entries]) for p in pdos]


@pytest.fixture(scope="module", params=SAMPLES)
def configs(request):
    return request.param, slave_configs(sample(request.param))


# --- what the export contains ----------------------------------------------------------------------------

def test_technosoft_config_has_mapping_scaling_and_parameters_in_order():
    (c,) = slave_configs(sample("technosoft_ipos"))
    assert (c.name, c.position) == ("z_axis", 0)
    assert (c.identity.vendor_id, c.identity.product_code) == (0x1A3, 0x01A0C82D)
    assert _pdos(c.rx_pdos) == [(0x1600, [(0x6040, 0, 16), (0x6060, 0, 8)]), (0x1601, [(0x607A, 0, 32)])]
    assert _pdos(c.tx_pdos) == [(0x1A00, [(0x6041, 0, 16), (0x6061, 0, 8)]),
                                (0x1A01, [(0x6064, 0, 32), (0x6063, 0, 32)])]
    addrs = [(x.index, x.subindex) for x in c.commands]
    assert addrs[0] == (0x1C12, 0) and addrs[-2:] == [(0x6081, 0), (0x6083, 0)]
    # the PDO programming comes before the factor group, the parameters last
    assert addrs.index((0x6093, 1)) > max(i for i, a in enumerate(addrs) if a[0] in (0x1C12, 0x1C13))
    assert [(s.number, s.kind) for s in c.sync_managers][2:4] == [(2, "Outputs"), (3, "Inputs")]


def test_explicit_dc_values_are_exported():
    (c,) = slave_configs(sample("controltechniques"))
    assert (c.dc_assign_activate, c.dc_cycle_ns) == (0x0300, 1_000_000)


def test_default_mapping_is_exported_without_pdo_commands():
    (c,) = slave_configs(sample("generic_esi"))
    # only the ESI's init command (Inovance: PS 6060h := 8, CSP) is sent: the default mapping needs no programming
    assert [_key(x) for x in c.commands] == [("PS", 0x6060, 0, b"\x08", False)] and _pdos(c.rx_pdos) and _pdos(c.tx_pdos)
    assert [p.index for p in c.rx_pdos] == [0x1701] and [p.index for p in c.tx_pdos] == [0x1B01]


def test_drives_come_in_bus_order(tmp_path):
    root = ROOT / "samples"
    p = write_project(tmp_path, f"""ecattool: 1
drives:
  - name: b
    position: 1
    device: {{profile: hdt, product: tomcat}}
  - name: a
    position: 0
    device: {{esi: {root}/generic_esi/inovance_SV660_EOE_1Axis_V9.12.xml, select: InoSV660N}}
    dc: {{opmode: DC, cycle_ns: 1000000}}
""")
    cfgs = slave_configs(p)
    assert [(c.name, c.position) for c in cfgs] == [("a", 0), ("b", 1)]
    assert cfgs[0].dc_assign_activate is not None and cfgs[0].dc_assign_activate != 0
    root_el = etree.fromstring(export(cfgs, "eni").encode())
    assert [s.findtext("Info/Name") for s in root_el.findall("Config/Slave")] == ["a", "b"]


# --- every exporter, every sample ------------------------------------------------------------------------

def test_eni_element_order(configs):
    _, cfgs = configs
    root = etree.fromstring(export(cfgs, "eni").encode())
    assert root.tag == "EtherCATConfig"
    slaves = root.findall("Config/Slave")
    assert len(slaves) == len(cfgs)
    for el, c in zip(slaves, cfgs):
        assert _in_order(_children(el), eni.SLAVE_ORDER)
        assert _children(el.find("Info")) == list(eni.INFO_ORDER)
        assert int(el.findtext("Info/VendorId")) == c.identity.vendor_id
        assert int(el.findtext("Info/ProductCode")) == c.identity.product_code
        assert _in_order(_children(el.find("Mailbox")), eni.MAILBOX_ORDER)
        cmds = el.findall("Mailbox/CoE/InitCmds/InitCmd")
        assert len(cmds) == len(c.commands)
        for ic, cmd in zip(cmds, c.commands):
            assert _children(ic) == [t for t in eni.COE_INITCMD_ORDER if ic.find(t) is not None]
            assert _in_order(_children(ic), eni.COE_INITCMD_ORDER)
            assert ic.findtext("Ccs") == "1" and ic.findtext("Transition") == cmd.transition
            assert (int(ic.findtext("Index")), int(ic.findtext("SubIndex"))) == (cmd.index, cmd.subindex)
            assert bytes.fromhex(ic.findtext("Data")) == cmd.data
        pd = el.find("ProcessData")
        assert [int(x.text) for x in pd.findall("Sm2/Pdo")] == [p.index for p in c.rx_pdos]
        assert [int(x.text) for x in pd.findall("Sm3/Pdo")] == [p.index for p in c.tx_pdos]
        for pdo in pd.findall("RxPdo") + pd.findall("TxPdo"):
            assert _in_order(_children(pdo), eni.PDO_ORDER)
            for entry in pdo.findall("Entry"):
                assert _in_order(_children(entry), eni.ENTRY_ORDER)
    back = import_bytes(export(cfgs, "eni").encode(), "x.xml")
    assert [[_key(x) for x in b.commands] for b in back] == [[_key(x) for x in c.commands] for c in cfgs]
    assert [_pdos(b.rx_pdos) for b in back] == [_pdos(c.rx_pdos) for c in cfgs]
    assert [b.identity for b in back] == [c.identity for c in cfgs]
    assert [b.dc_assign_activate for b in back] == [c.dc_assign_activate for c in cfgs]


def test_igh_c_compiles(configs, tmp_path):
    name, cfgs = configs
    text = export(cfgs, "igh")
    result = _gcc(text, tmp_path)
    assert result.returncode == 0, result.stderr
    n = sum(line.count("ecrt_slave_config_sdo") + line.count("ecrt_slave_config_complete_sdo")
            for line in text.splitlines())
    # PDO assignment/mapping writes are left to ecrt_slave_config_pdos(); every other command is an SDO call
    assert n == sum(1 for c in cfgs for cmd in c.commands if not is_pdo_programming(cmd.index))
    assert "ecrt_slave_config_pdos(" in text
    if cfgs[0].dc_assign_activate:
        assert f"ecrt_slave_config_dc(sc, 0x{cfgs[0].dc_assign_activate:04x}" in text


def test_pysoem_module_compiles_and_writes_every_command(configs):
    _, cfgs = configs
    code = export(cfgs, "pysoem")
    namespace: dict = {}
    exec(compile(code, "startup_pysoem.py", "exec"), namespace)
    # the slaves hold the device's default mapping: where the project maps nothing itself, the module's
    # program_pdos() reads it, finds it equal and writes nothing of it
    slaves = [FakeSlave(c.identity.vendor_id, c.identity.product_code).holding(c) for c in cfgs]
    namespace["install"](FakeMaster(slaves))
    for s, c in zip(slaves, cfgs):
        s.config_func(c.position)
        assert s.writes == [(x.index, x.subindex, x.data, x.complete_access) for x in c.commands]


def test_ros2_yaml_reimports_equal(configs):
    _, cfgs = configs
    back = import_bytes(export(cfgs, "ros2").encode(), "slave.yaml", "ros2")
    assert len(back) == len(cfgs)
    for b, c in zip(back, cfgs):
        assert (b.identity.vendor_id, b.identity.product_code) == (c.identity.vendor_id, c.identity.product_code)
        # the mapping comes back as rpdo/tpdo (the driver programs it), every other write as sdo
        assert [_key(x) for x in b.commands] == [_key(x) for x in c.commands if not is_pdo_programming(x.index)]
        assert _pdos(b.rx_pdos) == _pdos(c.rx_pdos) and _pdos(b.tx_pdos) == _pdos(c.tx_pdos)
        assert b.dc_assign_activate == c.dc_assign_activate


def test_ecmc_lines_reimport_equal(configs):
    _, cfgs = configs
    text = export(cfgs, "ecmc")
    assert text.count("Cfg.EcAddSdo(") == sum(len(c.commands) for c in cfgs)
    back = import_bytes(text.encode(), "startup.cmd", "ecmc")
    for b, c in zip(back, cfgs):
        assert (b.identity.vendor_id, b.identity.product_code) == (c.identity.vendor_id, c.identity.product_code)
        assert [_key(x) for x in b.commands] == [_key(x) for x in c.commands]


def test_twincat_lines_reparse(configs):
    _, cfgs = configs
    if not any(c.commands for c in cfgs):  # nothing a TwinCAT startup list carries: refused, never an empty file
        with pytest.raises(EncodeError, match="nothing to write"):
            export(cfgs, "twincat", lossy=True)
        return
    text = export(cfgs, "twincat", lossy=True)  # DC and PDO tables have no TwinCAT line (listed, tested elsewhere)
    assert len(text.splitlines()) == sum(len(c.commands) for c in cfgs)
    back = import_bytes(text.encode(), "startup.txt", "twincat")
    assert [_key(x) for b in back for x in b.commands] == [_key(x) for c in cfgs for x in c.commands]
    assert [x.comment for b in back for x in b.commands] == [x.comment for c in cfgs for x in c.commands]


def test_json_round_trip(configs):
    _, cfgs = configs
    back = import_bytes(export(cfgs, "json").encode(), "x.json")
    assert [(b.name, b.position, b.identity, b.dc_assign_activate, b.dc_cycle_ns) for b in back] == \
        [(c.name, c.position, c.identity, c.dc_assign_activate, c.dc_cycle_ns) for c in cfgs]
    for b, c in zip(back, cfgs):
        assert [(*_key(x), x.comment, x.type_name, x.value) for x in b.commands] == \
            [(*_key(x), x.comment, x.type_name, x.value) for x in c.commands]
        assert _pdos(b.rx_pdos) == _pdos(c.rx_pdos) and _pdos(b.tx_pdos) == _pdos(c.tx_pdos)


def test_csv_round_trip(configs):
    _, cfgs = configs
    if not any(c.commands for c in cfgs):
        with pytest.raises(EncodeError, match="nothing to write"):
            export(cfgs, "csv", lossy=True)
        return
    text = export(cfgs, "csv", lossy=True)
    rows = text.splitlines()[1:]
    assert len(rows) == sum(len(c.commands) for c in cfgs)
    back = import_bytes(text.encode(), "x.csv", "csv")
    # CSV has one row per command: a drive without commands has no row (the generic sample)
    assert [(b.name, b.position) for b in back] == [(c.name, c.position) for c in cfgs if c.commands]
    assert [(*_key(x), x.comment, x.type_name) for b in back for x in b.commands] == \
        [(*_key(x), x.comment, x.type_name) for c in cfgs for x in c.commands]


# --- refusal and the CLI ---------------------------------------------------------------------------------

BROKEN = """ecattool: 1
drives:
  - name: x
    device: {profile: technosoft-ipos}
    parameters:
      - {object: "0x6041:00", value: 1}
"""


def test_export_refuses_a_project_with_lint_errors(tmp_path):
    p = write_project(tmp_path, BROKEN)
    with pytest.raises(InputError) as err:
        slave_configs(p)
    assert "PRJ012" in str(err.value) and "lint errors" in str(err.value)
    assert err.value.location.file == str(p) and err.value.location.line == 6


@pytest.mark.parametrize("fmt", ["eni", "twincat", "igh", "pysoem", "ros2", "ecmc", "json", "csv"])
def test_cli_export_project_writes_every_format(fmt, tmp_path, capsys):
    out = tmp_path / f"z.{fmt}"
    code, _, err = run(capsys, "startup", "export", "--project", str(sample("technosoft_ipos")), "--format", fmt,
                       "-o", str(out))
    assert code == 0, err
    assert out.read_text() == export(slave_configs(sample("technosoft_ipos")), fmt)


def test_cli_export_project_refused_on_lint_errors(tmp_path, capsys):
    p = write_project(tmp_path, BROKEN)
    code, out, err = run(capsys, "startup", "export", "--project", str(p), "--format", "eni")
    assert code == 1 and out == ""
    assert err.startswith("ecattool: error: ") and f"{p}:6" in err and "PRJ012" in err
    assert len(err.strip().splitlines()) == 1


def test_cli_export_needs_exactly_one_source(capsys, tmp_path):
    p = str(sample("hdt"))
    assert run(capsys, "startup", "export", "--format", "eni")[0] == 2
    assert run(capsys, "startup", "export", "--project", p, "--from", p, "--format", "eni")[0] == 2
    assert run(capsys, "startup", "export", "--project", p, "--from-format", "json", "--format", "eni")[0] == 2


def test_cli_export_never_overwrites_the_project(tmp_path, capsys):
    p = write_project(tmp_path, sample("hdt").read_text())
    before = p.read_text()
    code, _, err = run(capsys, "startup", "export", "--project", str(p), "--format", "json", "-o", str(p))
    assert code != 0 and p.read_text() == before


def test_igh_c_of_a_multi_drive_project_compiles(tmp_path):
    root = ROOT / "samples"
    p = write_project(tmp_path, f"""ecattool: 1
drives:
  - name: x-axis
    device: {{profile: hdt, product: tomcat}}
  - name: x axis 2
    device: {{esi: {root}/generic_esi/inovance_SV660_EOE_1Axis_V9.12.xml, select: InoSV660N}}
    dc: {{opmode: DC, cycle_ns: 2000000}}
  - name: feed
    device: {{profile: controltechniques, product: digitax-st}}
    dc: {{assign_activate: 0x0300, cycle_ns: 1000000}}
    parameters:
      - {{object: modes of operation, value: 8}}
""")
    cfgs = slave_configs(p)
    text = export(cfgs, "igh")
    result = _gcc(text, tmp_path)
    assert result.returncode == 0, result.stderr
    assert text.count("ecrt_master_slave_config(") == 3 and "2000000U" in text


def test_export_prints_the_identity_warnings_of_what_it_writes(capsys, tmp_path):
    """An EDS without ProductNumber: lint warns (esi-product-zero); the export writes product 0 and says so on
    stderr, one line, at the EDS's line."""
    from tests.conftest import corpus_path

    eds = corpus_path("eds", "technosoft_iPOS.D.v1.04.eds")
    p = tmp_path / "m.yaml"
    code, _, err = run(capsys, "project", "new", "--esi", str(eds), "-o", str(p))
    assert code == 0, err
    code, out, err = run(capsys, "startup", "export", "--project", str(p), "--format", "json")
    import json

    assert code == 0 and json.loads(out)["slaves"][0]["identity"]["product_code"] == 0
    lines = [line for line in err.splitlines() if "[esi-product-zero]" in line]
    assert len(lines) == 1 and "technosoft_iPOS.D.v1.04.eds:14" in lines[0], err
    # a sample with a real product code exports without a word
    code, _, err = run(capsys, "startup", "export", "--project", str(sample("hdt")), "--format", "json")
    assert code == 0 and "esi-product-zero" not in err


def test_sync1_from_the_project_overrides_the_opmode_and_reaches_the_exports(tmp_path):
    """``dc: {sync1_cycle_ns, sync1_shift_ns}`` (issue 35 item 2: the project format had no SYNC1): explicit values
    override the OpMode's as ``cycle_ns`` does, and flow into every export that carries SYNC1 (IgH's
    ecrt_slave_config_dc arguments 4 and 5, the ENI's CycleTime1)."""
    root = ROOT / "samples"
    p = write_project(tmp_path, f"""ecattool: 1
drives:
  - name: a
    device: {{esi: {root}/generic_esi/inovance_SV660_EOE_1Axis_V9.12.xml, select: InoSV660N}}
    dc: {{assign_activate: 0x0700, cycle_ns: 1000000, sync1_cycle_ns: 250000, sync1_shift_ns: -1000}}
""")
    (c,) = slave_configs(p)
    assert (c.dc_assign_activate, c.dc_cycle_ns, c.dc_sync1_cycle_ns, c.dc_sync1_shift_ns) == \
        (0x0700, 1_000_000, 250_000, -1000)
    assert "0x0700, 1000000U, 0, 250000U, -1000);" in export([c], "igh", lossy=True)
    dc = etree.fromstring(export([c], "eni", lossy=True).encode()).find("Config/Slave/DC")
    assert dc is not None and dc.findtext("CycleTime1") == "250000"
    (back,) = import_bytes(export([c], "json").encode(), "x.json")  # the round trip keeps both SYNC1 values
    assert (back.dc_sync1_cycle_ns, back.dc_sync1_shift_ns) == (250_000, -1000)


@pytest.mark.parametrize("dc, message", [
    ("{assign_activate: 0x0700, cycle_ns: 1000000, sync1_cycle_ns: -1}", "sync1_cycle_ns"),
    ("{assign_activate: 0x0700, cycle_ns: 1000000, sync1_cycle_ns: 4294967296}", "sync1_cycle_ns"),
    ("{assign_activate: 0x0700, cycle_ns: 1000000, sync1_shift_ns: 5}", "sync1_shift_ns without sync1_cycle_ns"),
    ("{assign_activate: 0x0700, cycle_ns: 1000000, sync1_cycle: 5}", "sync1_cycle"),
])
def test_a_wrong_sync1_value_is_one_located_line(tmp_path, capsys, dc, message):
    p = write_project(tmp_path, f"ecattool: 1\ndrives:\n  - name: a\n    device: {{profile: hdt}}\n    dc: {dc}\n")
    code, out, err = run(capsys, "lint", str(p))
    text = out + err
    assert code == 1 and message in text and "project.yaml:5" in text and "Traceback" not in text, text
