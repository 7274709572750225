"""Exporters, each checked structurally: ENI element order, IgH C through gcc, pysoem executed against a fake
master, ros2/JSON/CSV/TwinCAT/ecmc read back by their importers."""

from __future__ import annotations

import math
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from ecattool.startup.model import is_pdo_programming
from lxml import etree

from ecattool.errors import EncodeError, InputError
from ecattool.esi.model import Direction, Identity, Pdo, PdoEntry
from ecattool.startup import FORMATS, SlaveConfig, SoeCommand, StartupCommand, StartupList, export, import_bytes, import_file
from ecattool.startup.formats import eni
from tests.conftest import ROOT, corpus_path


def _u(size: int, value: int) -> bytes:
    return value.to_bytes(size, "little")


def technosoft_rxpdo3_list() -> StartupList:
    """Technosoft oracle 15 (RxPDO3 example, §2.5), as a startup list."""
    seq = [(0x1C12, 0, 1, 0), (0x1602, 0, 1, 0), (0x1602, 1, 4, 0x60400010), (0x1602, 2, 4, 0x60600008),
           (0x1602, 0, 1, 2), (0x1C12, 3, 2, 0x1602), (0x1C12, 0, 1, 3)]
    return StartupList([StartupCommand("PS", i, s, _u(n, v), comment=f"step {k}") for k, (i, s, n, v) in enumerate(seq)],
                       name="iPOS", vendor_id=0x1A3, product_code=0x019F418D)


def technosoft_csv_list() -> StartupList:
    """Technosoft oracle 18 (CSV mapping, §14.2)."""
    seq = [(0x1C12, 0, 1, 0), (0x1603, 0, 1, 0), (0x1603, 1, 4, 0x60FF0020), (0x1603, 0, 1, 1),
           (0x1C12, 3, 2, 0x1603), (0x1C12, 0, 1, 3)]
    return StartupList([StartupCommand("PS", i, s, _u(n, v)) for i, s, n, v in seq])


def sample_config() -> SlaveConfig:
    rx = [Pdo(Direction.RX, 0x1600, "RxPDO1", [PdoEntry(0x6040, 0, 16, "Controlword", "UINT"),
                                               PdoEntry(0x607A, 0, 32, "Target position", "DINT")]),
          Pdo(Direction.RX, 0x1602, "RxPDO3", [PdoEntry(0x6060, 0, 8, "Modes of operation", "SINT"),
                                               PdoEntry(0, 0, 8)])]
    tx = [Pdo(Direction.TX, 0x1A00, "TxPDO1", [PdoEntry(0x6041, 0, 16, "Statusword", "UINT"),
                                               PdoEntry(0x6064, 0, 32, "Position actual value", "DINT")])]
    cmds = [StartupCommand("PS", 0x1C12, 0, b"\x00", comment="clear sm pdos (0x1C12)", type_name="USINT", value=0),
            StartupCommand("PS", 0x1600, 1, _u(4, 0x60400010), comment="download pdo 0x1600 entry"),
            StartupCommand("PS", 0x1C12, 0, bytes.fromhex("020000160216"), complete_access=True,
                           comment="assign (complete access)"),
            StartupCommand("PS", 0x6060, 0, b"\x08", type_name="SINT", value=8, comment="CSP"),
            StartupCommand("PS", 0x60C2, 2, b"\xfd", type_name="SINT", value=-3),
            StartupCommand("SO", 0x2010, 0, bytes(range(10)), comment="a 10-byte domain", timeout_ms=500),
            StartupCommand("IP", 0x6098, 0, b"\x23", comment="homing method 35")]
    return SlaveConfig(StartupList(cmds, name="Axis 1"), name="Axis 1", position=2,
                       identity=Identity(0x1A3, 0x019F418D, 0x10), rx_pdos=rx, tx_pdos=tx,
                       dc_assign_activate=0x0300, dc_cycle_ns=1_000_000, dc_shift_ns=0)


def _key(cmd: StartupCommand) -> tuple:
    return (cmd.transition, cmd.index, cmd.subindex, cmd.data, cmd.complete_access)


# --- ENI -----------------------------------------------------------------------------------------------

def _children(el, tag_filter=None) -> list[str]:
    return [c.tag for c in el if isinstance(c.tag, str)]


def _in_order(tags: list[str], order: tuple[str, ...]) -> bool:
    """Every tag is in ``order`` and tags appear in that order (repeats allowed)."""
    positions = [order.index(t) for t in tags]
    return positions == sorted(positions)


def test_eni_structure_follows_the_written_down_order():
    root = etree.fromstring(export(sample_config(), "eni").encode())
    assert root.tag == "EtherCATConfig"
    (slave,) = root.findall("Config/Slave")
    assert _children(slave) == ["Info", "ProcessData", "Mailbox", "InitCmds", "DC"]
    assert _children(slave.find("Info")) == list(eni.INFO_ORDER)
    assert slave.findtext("Info/AutoIncAddr") == str((-2) & 0xFFFF) and slave.findtext("Info/PhysAddr") == "1003"
    assert _in_order(_children(slave.find("Mailbox")), eni.MAILBOX_ORDER)
    cmds = slave.findall("Mailbox/CoE/InitCmds/InitCmd")
    assert len(cmds) == 7
    for ic in cmds:
        assert _children(ic) == list(eni.COE_INITCMD_ORDER)
        assert ic.findtext("Ccs") == "1"
    first = cmds[0]
    assert (first.findtext("Index"), first.findtext("SubIndex"), first.findtext("Data")) == ("7186", "0", "00")
    assert cmds[1].findtext("Data") == "10004060"  # 0x60400010 little-endian
    assert cmds[2].get("CompleteAccess") == "true" and cmds[0].get("CompleteAccess") is None
    assert cmds[5].findtext("Timeout") == "500" and cmds[5].findtext("Transition") == "SO"
    pd = slave.find("ProcessData")
    assert _children(pd) == ["Sm2", "Sm3", "TxPdo", "RxPdo", "RxPdo"]
    assert [p.text for p in pd.findall("Sm2/Pdo")] == ["5632", "5634"]
    for pdo in pd.findall("RxPdo") + pd.findall("TxPdo"):
        assert _in_order(_children(pdo), eni.PDO_ORDER)
        for entry in pdo.findall("Entry"):
            assert _in_order(_children(entry), eni.ENTRY_ORDER)
    dc_cmds = slave.findall("InitCmds/InitCmd")
    for dc_cmd in dc_cmds:
        assert _children(dc_cmd) == list(eni.ECAT_INITCMD_ORDER)
    # as TwinCAT writes DC: cycle times (0x09A0), start time (0x0990), activation (0x0980) in PS
    assert [(c.findtext("Transition"), c.findtext("Ado"), c.findtext("Data"), c.findtext("Adp")) for c in dc_cmds] == [
        ("PS", "2464", "40420f0000000000", "1003"), ("PS", "2448", "0000000000000000", "1003"),
        ("PS", "2432", "0003", "1003"), ("IP", "2432", "0000", "1003")]


def test_eni_round_trip_keeps_commands_pdos_identity_dc():
    cfg = sample_config()
    (back,) = import_bytes(export(cfg, "eni").encode(), "x.xml")
    assert [_key(c) for c in back.commands] == [_key(c) for c in cfg.commands]
    assert [c.comment for c in back.commands] == [c.comment for c in cfg.commands]
    assert [c.timeout_ms for c in back.commands] == [c.timeout_ms for c in cfg.commands]
    assert back.identity == cfg.identity and back.position == 2 and back.name == "Axis 1"
    assert back.dc_assign_activate == 0x0300 and back.dc_cycle_ns == 1_000_000
    assert [(p.index, [(e.index, e.subindex, e.bit_len) for e in p.entries]) for p in back.rx_pdos] == \
        [(p.index, [(e.index, e.subindex, e.bit_len) for e in p.entries]) for p in cfg.rx_pdos]


def test_eni_corpus_round_trip():
    path = corpus_path("configs", "eni_kpierczy_test_eni.xml")
    configs = import_file(path)
    back = import_bytes(export(configs, "eni").encode(), "again.xml")
    assert [[_key(c) for c in s.commands] for s in back] == [[_key(c) for c in s.commands] for s in configs]
    assert [s.identity for s in back] == [s.identity for s in configs]
    assert [s.dc_assign_activate for s in back] == [s.dc_assign_activate for s in configs]


def test_eni_carries_soe_commands():
    (c,) = import_file(corpus_path("configs", "lcec_initcmds_AX5206-AM8032-async.xml"))
    with pytest.raises(EncodeError, match="no vendor id/product code: an ENI slave needs VendorId"):
        export(c, "eni")  # a TwinCAT mailbox export names no device: an ENI without identity is refused
    text = export(c, "eni", lossy=True)
    root = etree.fromstring(text.encode())
    soe = root.findall("Config/Slave/Mailbox/SoE/InitCmds/InitCmd")
    assert len(soe) == 87 and _children(soe[0]) == list(eni.SOE_INITCMD_ORDER)
    (back,) = import_bytes(text.encode(), "x.xml")
    assert [(s.transition, s.idn, s.drive_no, s.data) for s in back.soe_commands] == \
        [(s.transition, s.idn, s.drive_no, s.data) for s in c.soe_commands]


# --- IgH C ---------------------------------------------------------------------------------------------

#: the prototypes of IgH 1.5 before 2014 (ecrt_master_sdo_download took ``uint8_t *data``, not const)
ECRT_H = """
#include <stdint.h>
#include <stddef.h>
typedef struct ec_master ec_master_t;
typedef struct ec_slave_config ec_slave_config_t;
typedef enum { EC_DIR_INVALID, EC_DIR_OUTPUT, EC_DIR_INPUT, EC_DIR_COUNT } ec_direction_t;
typedef enum { EC_WD_DEFAULT, EC_WD_ENABLE, EC_WD_DISABLE } ec_watchdog_mode_t;
typedef enum { EC_AL_STATE_INIT = 1, EC_AL_STATE_PREOP = 2, EC_AL_STATE_SAFEOP = 4, EC_AL_STATE_OP = 8 } ec_al_state_t;
typedef struct { uint16_t index; uint8_t subindex; uint8_t bit_length; } ec_pdo_entry_info_t;
typedef struct { uint16_t index; unsigned int n_entries; ec_pdo_entry_info_t const *entries; } ec_pdo_info_t;
typedef struct { uint8_t index; ec_direction_t dir; unsigned int n_pdos; ec_pdo_info_t const *pdos;
                 ec_watchdog_mode_t watchdog_mode; } ec_sync_info_t;
#define EC_END ~0U
ec_slave_config_t *ecrt_master_slave_config(ec_master_t *master, uint16_t alias, uint16_t position,
                                            uint32_t vendor_id, uint32_t product_code);
int ecrt_slave_config_pdos(ec_slave_config_t *sc, unsigned int n_syncs, const ec_sync_info_t syncs[]);
int ecrt_slave_config_sdo(ec_slave_config_t *sc, uint16_t index, uint8_t subindex, const uint8_t *data, size_t size);
int ecrt_slave_config_sdo8(ec_slave_config_t *sc, uint16_t sdo_index, uint8_t sdo_subindex, uint8_t value);
int ecrt_slave_config_sdo16(ec_slave_config_t *sc, uint16_t sdo_index, uint8_t sdo_subindex, uint16_t value);
int ecrt_slave_config_sdo32(ec_slave_config_t *sc, uint16_t sdo_index, uint8_t sdo_subindex, uint32_t value);
int ecrt_slave_config_complete_sdo(ec_slave_config_t *sc, uint16_t index, const uint8_t *data, size_t size);
int ecrt_slave_config_idn(ec_slave_config_t *sc, uint8_t drive_no, uint16_t idn, ec_al_state_t state,
                          const uint8_t *data, size_t size);
void ecrt_slave_config_dc(ec_slave_config_t *sc, uint16_t assign_activate, uint32_t sync0_cycle, int32_t sync0_shift,
                          uint32_t sync1_cycle, int32_t sync1_shift);
"""


#: IgH's own ecrt.h (../shared/consumers/igh, see its README): the exports are compiled against the real header
IGH_INCLUDE = ROOT.parent / "shared" / "consumers" / "igh"


def _gcc(source: str, tmp_path: Path, *defines: str, header: str | None = None) -> subprocess.CompletedProcess:
    """Compile ``source`` against IgH's real ``ecrt.h`` (or ``header``, an older API's prototypes)."""
    gcc = shutil.which("gcc")
    if not gcc:
        pytest.skip("gcc is not installed: the IgH C exports cannot be compiled here")
    if header is None and not (IGH_INCLUDE / "ecrt.h").is_file():
        pytest.skip(f"IgH's ecrt.h is missing ({IGH_INCLUDE}; see ../shared/consumers/README.md)")
    include = IGH_INCLUDE
    if header is not None:
        (tmp_path / "ecrt.h").write_text(header)
        include = tmp_path
    c = tmp_path / "config.c"
    c.write_text(source)
    return subprocess.run([gcc, "-std=c99", "-Wall", "-Wextra", "-Werror", "-Wno-missing-field-initializers",
                           "-fsyntax-only", *(f"-D{d}" for d in defines), "-I", str(include), str(c)],
                          capture_output=True, text=True)


def test_igh_c_compiles(tmp_path):
    text = export(sample_config(), "igh")
    result = _gcc(text, tmp_path)
    assert result.returncode == 0, result.stderr
    # with PDO tables, IgH programs 1C12h/1C13h and the mapping objects itself: not again as SDOs
    assert "0x1c12" not in text and "0x1600, 0x01" not in text
    assert "PDO assignment/mapping writes of the startup list are done by ecrt_slave_config_pdos()" in text
    assert "ecrt_slave_config_sdo(sc, 0x2010, 0x00," in text
    # the source gives no sync manager watchdog: the slave's own setting (EC_WD_DEFAULT)
    assert "{2, EC_DIR_OUTPUT, 2, axis_1_pdos + 0, EC_WD_DEFAULT}" in text
    assert "{3, EC_DIR_INPUT, 1, axis_1_pdos + 2, EC_WD_DEFAULT}" in text
    assert "ecrt_slave_config_dc(sc, 0x0300, 1000000U, 0, 0U, 0);" in text


def test_igh_c_without_pdo_tables_keeps_every_write_with_exact_sizes(tmp_path):
    cfg = sample_config()
    cfg.rx_pdos, cfg.tx_pdos = [], []
    text = export(cfg, "igh")
    assert _gcc(text, tmp_path).returncode == 0
    assert "ecrt_slave_config_pdos(" not in text
    assert "ecrt_slave_config_sdo8(sc, 0x1c12, 0x00, 0x00U)" in text
    assert "ecrt_slave_config_sdo32(sc, 0x1600, 0x01, 0x60400010U)" in text
    assert "ecrt_slave_config_complete_sdo(sc, 0x1c12," in text


def test_igh_c_of_every_corpus_config_compiles(tmp_path):
    sources = []
    for name in ("eni_kpierczy_test_eni.xml", "ros2_technosoft_ipos3604.yaml", "ecmc_ecmciPOSXXXX.cmd",
                 "lcec_generic-complex_ethercat-conf.xml", "lcec_initcmds_ethercat-conf.xml"):
        configs = import_file(corpus_path("configs", name))
        # IgH needs vendor and product: slaves whose source does not name them (lcec built-in types, the
        # ecmc script without the device's identity script) are refused, so leave them out here
        for c in configs:
            if c.identity is None:
                with pytest.raises(EncodeError, match="no vendor id/product code"):
                    export(c, "igh")
        sources.append(export([c for c in configs if c.identity is not None] or
                              [SlaveConfig(c.startup, name=c.name, identity=Identity(0x1A3, 0x019F418D))
                               for c in configs], "igh"))
    for i, src in enumerate(sources):
        sub = tmp_path / str(i)
        sub.mkdir()
        result = _gcc(src, sub, "SYNC0_CYCLE_NS=1000000U")  # the ros2 file has DC but no cycle
        assert result.returncode == 0, result.stderr


def test_igh_dc_without_a_cycle_does_not_compile_until_the_program_gives_one(tmp_path):
    # SYNC0 activated with a cycle of 0 would be a silent misconfiguration: the C file asks for the cycle
    src = export(import_file(corpus_path("configs", "ros2_technosoft_ipos3604.yaml")), "igh")
    assert "ecrt_slave_config_dc(sc, 0x0330, SYNC0_CYCLE_NS, 0, 0U, 0);" in src
    result = _gcc(src, tmp_path)
    assert result.returncode != 0 and "define SYNC0_CYCLE_NS" in result.stderr
    assert _gcc(src, tmp_path, "SYNC0_CYCLE_NS=2000000U").returncode == 0


def test_igh_c_compiler_catches_a_broken_table(tmp_path):
    # the check can fail: a wrong type name in the generated text is reported by gcc
    text = export(sample_config(), "igh").replace("ec_pdo_info_t", "ec_pdo_inf_t", 1)
    assert _gcc(text, tmp_path).returncode != 0


def test_igh_uses_exact_sizes_for_technosoft_rxpdo3_oracle():
    text = export(technosoft_rxpdo3_list(), "igh")
    calls = [line.strip() for line in text.splitlines() if "ecrt_slave_config_sdo" in line]
    sizes = [c.split("ecrt_slave_config_sdo")[1].split("(")[0] for c in calls]
    assert sizes == ["8", "8", "32", "32", "8", "16", "8"]


def test_igh_soe_commands_become_idn_configs(tmp_path):
    (c,) = import_file(corpus_path("configs", "lcec_initcmds_AX5206-AM8032-async.xml"))
    c.identity = Identity(2, 0x14566012)  # the TwinCAT export holds only the commands; lcec's config names it
    text = export(c, "igh")
    assert _gcc(text, tmp_path).returncode == 0
    assert "ecrt_slave_config_idn(sc, 0, 15, EC_AL_STATE_PREOP," in text
    assert text.count("ecrt_slave_config_idn(") == sum(1 for s in c.soe_commands if s.transition in ("PS", "SO"))


def test_igh_refuses_complete_access_from_sub_one():
    cfg = SlaveConfig(StartupList([StartupCommand("PS", 0x1C12, 1, b"\x01\x16", complete_access=True)]))
    with pytest.raises(EncodeError):
        export(cfg, "igh")


# --- pysoem --------------------------------------------------------------------------------------------

class FakeSlave:
    def __init__(self, man: int, ident: int) -> None:
        self.man, self.id = man, ident
        self.writes: list[tuple] = []
        self.config_func = None
        self.od: dict[tuple[int, int], bytes] = {}  # what sdo_read answers (unset: 0)

    def sdo_write(self, index, subindex, data, ca=False):
        self.writes.append((index, subindex, bytes(data), ca))

    def sdo_read(self, index, subindex, size=0, ca=False):
        return self.od.get((index, subindex), bytes(4))

    def holding(self, cfg: SlaveConfig) -> "FakeSlave":
        """The slave already holds the PDO assignment and mapping of ``cfg`` (SM2 outputs, SM3 inputs)."""
        for assign, pdos in ((0x1C12, cfg.rx_pdos), (0x1C13, cfg.tx_pdos)):
            self.od[(assign, 0)] = bytes([len(pdos)])
            for k, p in enumerate(pdos, 1):
                self.od[(assign, k)] = p.index.to_bytes(2, "little")
                self.od[(p.index, 0)] = bytes([len(p.entries)])
                for j, e in enumerate(p.entries, 1):
                    self.od[(p.index, j)] = ((e.index << 16) | (e.subindex << 8) | e.bit_len).to_bytes(4, "little")
        return self


class FakeMaster:
    def __init__(self, slaves):
        self.slaves = slaves


def test_pysoem_module_writes_every_command():
    cfg = sample_config()
    code = export(cfg, "pysoem")
    namespace: dict = {}
    exec(compile(code, "startup_pysoem.py", "exec"), namespace)
    slaves = [FakeSlave(0, 0), FakeSlave(0, 0), FakeSlave(0x1A3, 0x019F418D)]
    namespace["install"](FakeMaster(slaves))
    assert slaves[0].config_func is None
    slaves[2].config_func(2)
    assert slaves[2].writes == [(c.index, c.subindex, c.data, c.complete_access) for c in cfg.commands]


def test_pysoem_install_checks_identity():
    namespace: dict = {}
    exec(compile(export(sample_config(), "pysoem"), "m.py", "exec"), namespace)
    with pytest.raises(RuntimeError, match="expected 0x000001A3"):
        namespace["install"](FakeMaster([FakeSlave(0, 0)] * 3))



def _run_pysoem_module(code: str, drives, before_safe_op=None, **dc_kwargs):
    """Execute an exported pysoem module the way its docstring says, on the fake pysoem bus of ``drives``;
    ``before_safe_op(master)`` runs between config_map() and to_safe_op()."""
    from tests.target.fake_pysoem import make_module

    namespace: dict = {}
    exec(compile(code, "startup_pysoem.py", "exec"), namespace)
    master = make_module(drives).Master()
    master.open("eth0")
    master.config_init()
    namespace["install"](master)
    assert master.manual_state_change == 1  # config_map() must not request SAFE-OP before DC runs
    master.config_map()
    if before_safe_op is not None:
        before_safe_op(master)
    namespace["to_safe_op"](master, **dc_kwargs)
    return master


def test_pysoem_module_starts_the_distributed_clocks():
    """A drive in CSP needs SYNC0: the pysoem module wrote no DC at all (IgH, ecmc, ros2 and ENI did)."""
    from ecattool.sim import Drive

    drives = [Drive.from_profile("hdt"), Drive.from_profile("hdt")]
    ident = drives[1].identity()
    cfg = SlaveConfig(StartupList([StartupCommand("PS", 0x6060, 0, b"\x08")]), name="x", position=1,
                      identity=Identity(ident.vendor_id, ident.product_code),
                      dc_assign_activate=0x0330, dc_cycle_ns=2_000_000, dc_shift_ns=500)
    master = _run_pysoem_module(export(cfg, "pysoem"), drives)
    assert master.dc_configured
    assert master.slaves[0].dc is None
    assert master.slaves[1].dc == (0x03, 2_000_000, 500, None)  # the latch bits 0x30 are not pysoem's


def test_pysoem_module_dc_without_cycle_or_unsupported_activation():
    from ecattool.sim import Drive

    no_cycle = SlaveConfig(StartupList([]), name="ros2 drive", position=0, dc_assign_activate=0x0300)
    code = export(no_cycle, "pysoem")
    with pytest.raises(RuntimeError, match="give the SYNC0 cycle"):
        _run_pysoem_module(code, [Drive.from_profile("hdt")])
    master = _run_pysoem_module(code, [Drive.from_profile("hdt")], sync0_cycle_ns=1_000_000)
    assert master.slaves[0].dc == (0x03, 1_000_000, 0, None)
    odd = SlaveConfig(StartupList([]), name="odd", position=0, dc_assign_activate=0x0100)
    with pytest.raises(RuntimeError, match="AssignActivate 0x0100"):
        _run_pysoem_module(export(odd, "pysoem", lossy=True), [Drive.from_profile("hdt")])
    with pytest.raises(EncodeError, match="AssignActivate 0x0100: pysoem can only activate"):
        export(odd, "pysoem")
    off = _run_pysoem_module(export(SlaveConfig(StartupList([]), position=0), "pysoem"), [Drive.from_profile("hdt")])
    assert not off.dc_configured and off.slaves[0].dc is None

# --- ros2 ----------------------------------------------------------------------------------------------

ROS2 = ["ros2_beckhoff_el3104.yaml", "ros2_beckhoff_el5101.yaml", "ros2_elmo_gold.yaml",
        "ros2_epos4_config_with_gear_box.yaml", "ros2_maxon_epos3.yaml", "ros2_maxon_epos4_50_5_config.yaml",
        "ros2_schneider_atv320.yaml", "ros2_technosoft_ipos3604.yaml"]


def _same_channel_info(a: dict, b: dict) -> bool:
    if a.keys() != b.keys():
        return False
    for k in a:
        x, y = a[k], b[k]
        for key in x.keys() | y.keys():
            u, v = x.get(key), y.get(key)
            if isinstance(u, float) and math.isnan(u):
                if not (isinstance(v, float) and math.isnan(v)):
                    return False
            elif u != v:
                return False
    return True


@pytest.mark.parametrize("name", ROS2)
def test_ros2_corpus_reimports_equal(name):
    (c,) = import_file(corpus_path("configs", name))
    (back,) = import_bytes(export(c, "ros2").encode(), name)
    assert back.identity == c.identity and back.dc_assign_activate == c.dc_assign_activate
    assert [(x.index, x.subindex, x.data, x.type_name, x.value, x.comment) for x in back.commands] == \
        [(x.index, x.subindex, x.data, x.type_name, x.value, x.comment) for x in c.commands]
    for mine, theirs in ((back.rx_pdos, c.rx_pdos), (back.tx_pdos, c.tx_pdos)):
        assert [(p.index, p.name, [(e.index, e.subindex, e.bit_len, e.name, e.data_type) for e in p.entries]) for p in mine] == \
            [(p.index, p.name, [(e.index, e.subindex, e.bit_len, e.name, e.data_type) for e in p.entries]) for p in theirs]
    assert _same_channel_info(back.channel_info, c.channel_info)
    assert back.extra == c.extra


def test_ros2_from_eni_types_by_size_and_marks_transitions():
    cfg = sample_config()
    cfg.commands[:] = [c for c in cfg.commands if not c.complete_access and len(c.data) in (1, 2, 4, 8)]
    with pytest.raises(EncodeError, match=r"the transition of 1 write\(s\) \(IP 0x6098:00…\)"):
        export(cfg, "ros2")  # the driver sends every sdo entry in PRE-OP: a listed loss
    text = export(cfg, "ros2", lossy=True)
    assert "{index: 0x60C2, sub_index: 2, type: int8, value: -3}" in text
    assert "transition IP" in text
    # the mapping travels as rpdo/tpdo, which the driver programs: not again as sdo writes
    assert "{index: 0x1600, sub_index: 1" not in text and "done by the driver from rpdo/tpdo" in text
    (back,) = import_bytes(text.encode(), "r.yaml")
    assert [(c.index, c.subindex, c.data) for c in back.commands] == \
        [(c.index, c.subindex, c.data) for c in cfg.commands if not is_pdo_programming(c.index)]
    cfg.rx_pdos, cfg.tx_pdos = [], []  # without PDO tables every write stays an sdo entry
    assert "{index: 0x1600, sub_index: 1, type: uint32, value: 1614807056}" in export(cfg, "ros2", lossy=True)


def test_ros2_from_ecmc_writes_no_ecmc_bookkeeping_keys():
    # the ecmc importer keeps its slave reference in extra; it is no ethercat_driver_ros2 key
    (cfg,) = import_file(corpus_path("configs/ecmc_ecmciPOSXXXX.cmd"))
    assert cfg.extra == {"ecmc_slave": "${ECMC_EC_SLAVE_NUM}"}
    cfg.identity = Identity(0x1A3, 0x019F418D)  # set by ecmciPOS4808.cmd, which includes this script
    text = export(cfg, "ros2", lossy=True)  # its EcWriteSdo once-writes become sdo entries (a listed loss)
    assert "ecmc_slave" not in text and "ECMC" not in text
    (back,) = import_bytes(text.encode(), "x.yaml", "ros2")
    assert back.extra == {}


def test_ros2_refuses_complete_access_and_odd_sizes():
    with pytest.raises(EncodeError, match="complete-access"):
        export(SlaveConfig(StartupList([StartupCommand("PS", 0x1C12, 0, b"\x01\x00\x16", complete_access=True)]),
                           identity=Identity(1, 2)), "ros2")
    with pytest.raises(EncodeError, match="3 data bytes"):
        export(SlaveConfig(StartupList([StartupCommand("PS", 0x2000, 1, b"\x01\x02\x03")]), identity=Identity(1, 2)),
               "ros2")


def test_ros2_bad_type_is_located():
    with pytest.raises(InputError) as err:
        import_bytes(b"vendor_id: 1\nproduct_id: 2\nsdo:\n  - {index: 0x6060, sub_index: 0, type: int9, value: 1}\n", "r.yaml")
    assert err.value.location.line == 4 and "int9" in str(err.value)


# --- JSON, CSV, TwinCAT, ecmc ----------------------------------------------------------------------------

def test_json_round_trip_is_lossless():
    cfg = sample_config()
    cfg.soe_commands.append(SoeCommand("PS", 15, b"\x07\x00", drive_no=1, comment="Telegram type", fixed=True))
    cfg.channel_info[(0x1600, 1)] = {"command_interface": "position", "factor": 2.5}
    cfg.extra["period"] = 100
    (back,) = import_bytes(export(cfg, "json").encode(), "x.json")
    for a, b in zip(back.commands, cfg.commands):
        assert (a.transition, a.index, a.subindex, a.data, a.comment, a.complete_access, a.timeout_ms, a.type_name,
                a.value, a.expect_reply, a.verify) == (b.transition, b.index, b.subindex, b.data, b.comment,
                                                       b.complete_access, b.timeout_ms, b.type_name, b.value,
                                                       b.expect_reply, b.verify)
    assert len(back.commands) == len(cfg.commands)
    assert back.commands[3].source.line > 1
    assert back.identity == cfg.identity and back.position == 2 and back.name == "Axis 1"
    assert (back.dc_assign_activate, back.dc_cycle_ns, back.dc_shift_ns) == (0x300, 1_000_000, 0)
    assert [(p.index, p.name, [(e.index, e.subindex, e.bit_len, e.name, e.data_type) for e in p.entries]) for p in back.rx_pdos] == \
        [(p.index, p.name, [(e.index, e.subindex, e.bit_len, e.name, e.data_type) for e in p.entries]) for p in cfg.rx_pdos]
    assert [(s.idn, s.drive_no, s.data, s.fixed) for s in back.soe_commands] == [(15, 1, b"\x07\x00", True)]
    assert back.channel_info == cfg.channel_info and back.extra == {"period": 100}


def test_json_wrong_version_and_tag_are_errors():
    with pytest.raises(InputError, match="version"):
        import_bytes(b'{"format": "ecattool-startup", "version": 9, "slaves": []}', "x.json", "json")
    with pytest.raises(InputError, match="ecattool startup"):
        import_bytes(b'{"slaves": []}', "x.json")


def test_csv_round_trip():
    cfg = sample_config()
    cfg.commands[0].comment = 'with, comma and "quotes"'
    text = export(cfg, "csv", lossy=True)  # CSV has no DC
    (back,) = import_bytes(text.encode(), "x.csv")
    assert [(c.transition, c.index, c.subindex, c.data, c.complete_access, c.timeout_ms, c.type_name, c.value, c.comment)
            for c in back.commands] == \
        [(c.transition, c.index, c.subindex, c.data, c.complete_access, c.timeout_ms, c.type_name, c.value, c.comment)
         for c in cfg.commands]
    assert back.name == "Axis 1" and back.position == 2
    assert back.commands[1].source.line == 3


def test_twincat_lines_reparse():
    text = export(sample_config(), "twincat", lossy=True)  # a TwinCAT startup list has no DC
    lines = text.splitlines()
    assert lines[0] == "<PS>,CoE,0x1C12:00,0x00 (0),clear sm pdos (0x1C12)"
    assert lines[1] == "<PS>,CoE,0x1600:01,0x60400010 (1614807056),download pdo 0x1600 entry"
    assert lines[2].startswith("<PS>,CoE,0x1C12:00 CA,")
    assert lines[5] == "<SO>,CoE,0x2010:00,00 01 02 03 04 05 06 07 08 09,a 10-byte domain"
    (back,) = import_bytes(text.encode(), "x.txt")
    assert [_key(c) for c in back.commands] == [_key(c) for c in sample_config().commands]
    assert [c.comment for c in back.commands] == [c.comment for c in sample_config().commands]


def test_twincat_oracle_rxpdo3_lines():
    lines = export(technosoft_rxpdo3_list(), "twincat").splitlines()
    assert lines[2] == "<PS>,CoE,0x1602:01,0x60400010 (1614807056),step 2"
    assert lines[5] == "<PS>,CoE,0x1C12:03,0x1602 (5634),step 5"
    assert lines[6] == "<PS>,CoE,0x1C12:00,0x03 (3),step 6"


def test_twincat_oracle_csv_mapping_lines_reparse():
    sl = technosoft_csv_list()
    (back,) = import_bytes(export(sl, "twincat").encode(), "t.txt")
    assert [(c.index, c.subindex, c.data) for c in back.commands] == [(c.index, c.subindex, c.data) for c in sl]
    assert back.commands[2].data == (0x60FF0020).to_bytes(4, "little")


def test_twincat_reads_ecmc_style_spaced_values():
    (c,) = import_bytes(b"<PS>,CoE,0x1600:02,0x60FF 0020 (1627324448),download pdo 0x1600 entry\n", "t.txt")
    assert c.commands[0].data == (0x60FF0020).to_bytes(4, "little")


def test_twincat_bad_line_is_located():
    with pytest.raises(InputError) as err:
        import_bytes(b"<PS>,CoE,0x1C12:00,0x00 (0),ok\n<XX>,CoE,0x1C12:00,0x00 (0),bad\n", "t.txt", "twincat")
    assert err.value.location.line == 2


def test_ecmc_round_trip():
    cfg = sample_config()
    cfg.commands[:] = [c for c in cfg.commands if c.transition == "PS"]
    text = export(cfg, "ecmc")
    assert 'ecmcConfigOrDie "Cfg.EcAddSdo(2,0x1C12,0x0,0x0,1)"' in text
    assert 'Cfg.EcAddSdoComplete(2,0x1C12,02 00 00 16 02 16,6)' in text
    (back,) = import_bytes(text.encode(), "x.cmd")
    assert [_key(c) for c in back.commands] == [_key(c) for c in cfg.commands]
    assert [c.comment for c in back.commands] == [c.comment for c in cfg.commands]
    assert back.position == 2 and back.identity.vendor_id == 0x1A3
    assert [(p.index, [(e.index, e.subindex, e.bit_len) for e in p.entries]) for p in back.rx_pdos] == \
        [(p.index, [(e.index, e.subindex, e.bit_len) for e in p.entries]) for p in cfg.rx_pdos]
    assert 'ecmcConfigOrDie "Cfg.EcSlaveConfigDC(2,0x300,1000000,0,0,0)"' in text
    assert (back.dc_assign_activate, back.dc_cycle_ns, back.dc_shift_ns) == (0x0300, 1_000_000, 0)


def test_ecmc_dc_without_cycle_runs_at_the_ecmc_sample_rate():
    # a ros2 file has assign_activate but no cycle: ecmc gets SYNC0 at its sample rate, as ecmccfg scripts do
    (cfg,) = import_file(corpus_path("configs/ros2_technosoft_ipos3604.yaml"))
    text = export(cfg, "ecmc")
    assert "Cfg.EcSlaveConfigDC(${ECMC_EC_SLAVE_NUM},0x330,${ECMC_TEMP_PERIOD_NANO_SECS},0,0,0)" in text
    assert text.index("ecmcEpicsEnvSetCalc(\"ECMC_TEMP_PERIOD_NANO_SECS\"") < text.index("EcSlaveConfigDC")
    (back,) = import_bytes(text.encode(), "x.cmd")
    assert (back.dc_assign_activate, back.dc_cycle_ns) == (0x0330, None)


def test_ecmc_reads_and_writes_dc_with_sync1():
    script = b'ecmcConfigOrDie "Cfg.EcSlaveConfigDC(2,0x720,1000000,500000,750000,250000)"\n'
    (cfg,) = import_bytes(script, "dc.cmd", "ecmc")
    assert (cfg.position, cfg.dc_assign_activate, cfg.dc_cycle_ns, cfg.dc_shift_ns) == (2, 0x720, 1_000_000, 500_000)
    assert (cfg.dc_sync1_cycle_ns, cfg.dc_sync1_shift_ns) == (750_000, 250_000) and not cfg.notes
    assert 'Cfg.EcSlaveConfigDC(2,0x720,1000000,500000,750000,250000)"' in export(cfg, "ecmc")
    with pytest.raises(InputError) as err:
        import_bytes(b'ecmcConfigOrDie "Cfg.EcSlaveConfigDC(2,0x300)"\n', "dc.cmd", "ecmc")
    assert err.value.location.line == 1


def test_signedness_survives_ecmc_and_reaches_ros2():
    """ecmc's EcAddEntryComplete has an optional signed flag; without it, a standard CiA-402 object keeps its
    standard type: a ros2 driver must read a negative position as negative, not as 4 billion."""
    (cfg,) = import_file(corpus_path("configs/ecmc_ecmciPOSXXXX.cmd"))
    types = {(e.index, e.subindex): e.data_type for p in (*cfg.rx_pdos, *cfg.tx_pdos) for e in p.entries}
    assert types[(0x60FF, 0)] == "DINT"  # the script's flag: ...,32,1,velocitySetpoint
    assert types[(0x6064, 0)] == "DINT" and types[(0x6077, 0)] == "INT"  # CiA-402 standard types, no flag
    assert types[(0x6040, 0)] == "UINT" and types[(0x2046, 0)] == ""  # vendor object: unknown stays unknown
    cfg.identity = Identity(0x1A3, 0x019F418D)  # set by ecmciPOS4808.cmd, which includes this script
    ros = export(cfg, "ros2", lossy=True)
    assert "{index: 0x60ff, sub_index: 0x00, type: int32}" in ros and "{index: 0x6064, sub_index: 0x00, type: int32}" in ros
    # and back out to ecmc, the flag is written where the type is known
    (elmo,) = import_file(corpus_path("configs/ros2_elmo_gold.yaml"))
    text = export(elmo, "ecmc")
    assert ",0x1607,0x607a,0x0,32,1,Target_position)" in text
    (back,) = import_bytes(text.encode(), "x.cmd", "ecmc")
    assert [e.data_type for p in back.rx_pdos for e in p.entries] == [e.data_type for p in elmo.rx_pdos for e in p.entries]


def test_single_slave_formats_refuse_several_slaves():
    two = [sample_config(), sample_config()]
    for fmt in ("twincat", "ros2"):
        with pytest.raises(EncodeError, match="one"):
            export(two, fmt, lossy=True)


def test_every_format_is_registered_with_its_directions():
    assert {n for n, f in FORMATS.items() if f.can_export} == {"eni", "twincat", "igh", "pysoem", "ros2", "ecmc", "json", "csv"}
    assert {n for n, f in FORMATS.items() if f.can_import} == {"eni", "twincat", "ros2", "ecmc", "json", "csv", "lcec"}
    with pytest.raises(InputError, match="only be read"):
        export(sample_config(), "lcec")
    with pytest.raises(InputError, match="unknown startup format"):
        export(sample_config(), "xls")


def test_several_slaves_of_unknown_position_stay_apart():
    configs = import_file(corpus_path("configs", "ros2_elmo_gold.yaml")) + \
        import_file(corpus_path("configs", "ros2_maxon_epos3.yaml"))
    assert all(c.position is None for c in configs)
    for c in configs:
        c.dc_cycle_ns = c.dc_cycle_ns or (1_000_000 if c.dc_assign_activate else None)  # an ENI needs the cycle
    for fmt in ("ecmc", "eni", "json", "csv"):
        back = import_bytes(export(configs, fmt, lossy=True).encode(), f"x.{fmt}", fmt)
        assert [[_key(c) for c in s.commands] for s in back] == [[_key(c) for c in s.commands] for s in configs], fmt


def test_pysoem_tolerates_no_reply_writes(monkeypatch):
    """pysoem raises WkcError when the mailbox answer does not come; only that is tolerated (an abort is not)."""
    from tests.target import fake_pysoem

    monkeypatch.setitem(sys.modules, "pysoem", fake_pysoem.make_module([]))
    cfg = SlaveConfig(StartupList([StartupCommand("PS", 0x2080, 0, b"\x01\x00", expect_reply=False, comment="reset"),
                                   StartupCommand("PS", 0x6060, 0, b"\x08")]), position=0)

    class Resetting(FakeSlave):
        error: Exception = fake_pysoem.WkcError(wkc=0)

        def sdo_write(self, index, subindex, data, ca=False):
            super().sdo_write(index, subindex, data, ca)
            if index == 0x2080:
                raise self.error

    namespace: dict = {}
    exec(compile(export(cfg, "pysoem"), "m.py", "exec"), namespace)
    slave = Resetting(0, 0)
    master = FakeMaster([slave])
    namespace["once"](master)  # the reset is one-shot: once(master), never the config function
    namespace["install"](master)
    slave.config_func(0)
    assert [w[0] for w in slave.writes] == [0x2080, 0x6060]
    slave.error = fake_pysoem.SdoError(1, 0x2080, 0, 0x06010002, "read only")
    with pytest.raises(fake_pysoem.SdoError):
        namespace["once"](master)