"""Issue 17: every export fed to its consumer's own rules.

- ethercat_driver_ros2 reads an sdo entry with yaml-cpp ``value.as<int>()`` into a C ``int`` and writes
  ``static_cast<type>(value)`` (ethercat_interface/ec_sdo_manager.hpp): emulated by :func:`ros2_driver_bytes`.
- IgH: the C file is compiled with gcc against an ecrt.h-shaped header (the prototypes of ecrt.h 1.5/1.6).
- ENI: element structure (no ENI XSD is in the corpus; ETG.2100 element names and TwinCAT's DC commands).
- ecmc: the command patterns of ecmc's ``Cfg.Ec…`` parser (argument counts and forms).
- pysoem: the generated module executed against tests/target/fake_pysoem.py and checked against pysoem's surface.
"""

from __future__ import annotations

import re
import struct

import pytest
import yaml
from lxml import etree

from ecattool.errors import EncodeError
from ecattool.esi.model import Identity
from ecattool.startup import SlaveConfig, StartupCommand, StartupList, export, import_bytes, import_file
from ecattool.startup.model import is_pdo_programming
from tests.conftest import ROOT, corpus_files, corpus_path, run
from tests.startup.test_startup_export import ECRT_H, _gcc, _run_pysoem_module

SAMPLES = sorted(p.parent.name for p in (ROOT / "samples").glob("*/project.yaml"))
ROS2_SIZES = {"int8": 1, "uint8": 1, "int16": 2, "uint16": 2, "int32": 4, "uint32": 4, "int64": 8, "uint64": 8}
CORPUS_CONFIGS = corpus_files("configs/*", form="name", keep=lambda p: (
    p.suffix in (".yaml", ".xml", ".cmd") and not p.name.startswith("hwdevmgr")
    and p.name not in ("lcec_initcmds_AX5206-AM8032-async.xml", "ecmc_ecmciPOS4808.cmd")))


def _sample_configs(name: str) -> list[SlaveConfig]:
    from ecattool.project.export import slave_configs

    return slave_configs(ROOT / "samples" / name / "project.yaml")


def ros2_driver_bytes(entry: dict) -> bytes:
    """What ethercat_driver_ros2 sends for one ``sdo`` entry, by its own rules: ``as<int>()`` throws for a
    non-integer or a value outside int32; ``buffer_write`` knows the eight integer types only."""
    kind, value = entry["type"], entry["value"]
    assert kind in ROS2_SIZES, f"the driver has no sdo type {kind!r}"
    assert isinstance(value, int) and not isinstance(value, bool), f"as<int>() throws for {value!r}"
    assert -(1 << 31) <= value < (1 << 31), f"as<int>() throws for {value} (above INT32_MAX)"
    size = ROS2_SIZES[kind]
    return (value & ((1 << (8 * size)) - 1)).to_bytes(size, "little")  # static_cast<type>(int), little-endian


def _ros2_sent(cfg: SlaveConfig) -> list[StartupCommand]:
    # once-writes are written as startup writes (a loss the export lists); a reset is left out
    return [c for c in cfg.commands if c.kind != "reset" and not (cfg.has_pdo_info and is_pdo_programming(c.index))]


def _check_ros2(cfg: SlaveConfig) -> str:
    from ecattool.startup import losses

    text = export(cfg, "ros2", lossy=True)
    if any(c.one_shot for c in cfg.commands):
        assert any("one-shot" in loss for loss in losses(cfg, "ros2"))
        with pytest.raises(EncodeError, match="ros2 cannot carry"):
            export(cfg, "ros2")
    doc = yaml.safe_load(text)
    assert isinstance(doc["vendor_id"], int) and isinstance(doc["product_id"], int)
    sent = [(int(e["index"]), int(e["sub_index"]), ros2_driver_bytes(e)) for e in doc.get("sdo") or []]
    assert sent == [(c.index, c.subindex, c.data) for c in _ros2_sent(cfg)]
    return text


# --- 1. ros2 values the driver can read ------------------------------------------------------------------

@pytest.mark.parametrize("sample", SAMPLES)
def test_ros2_export_of_every_sample_is_what_the_driver_sends(sample):
    for cfg in _sample_configs(sample):
        _check_ros2(cfg)


def test_ros2_technosoft_factor_above_int32_max_is_written_as_its_signed_value():
    (cfg,) = _sample_configs("technosoft_ipos")
    text = _check_ros2(cfg)
    # 6093h:01 = 0xC0000000 = 3221225472 would stop the driver; the same four bytes as a signed int
    assert "{index: 0x6093, sub_index: 1, type: uint32, value: -1073741824}" in text
    assert "3221225472" not in text
    (back,) = import_bytes(text.encode(), "again.yaml")
    assert [c.data for c in back.commands] == [c.data for c in _ros2_sent(cfg)]
    assert not back.notes  # nothing in the file the driver would refuse


@pytest.mark.parametrize("name", CORPUS_CONFIGS)
def test_ros2_export_of_every_corpus_config_is_what_the_driver_sends(name):
    for cfg in import_file(corpus_path("configs", name)):
        if cfg.identity is None:
            with pytest.raises(EncodeError, match="no vendor id/product code"):
                export(cfg, "ros2", lossy=True)
            continue
        try:
            _check_ros2(cfg)
        except EncodeError as exc:  # only what ros2 has no form for, said with the command named
            assert re.search(r"complete-access|data bytes have no|does not fit the 32-bit int", exc.message), exc


def test_ros2_floats_and_64_bit_values_are_written_as_their_bytes():
    cmds = [StartupCommand("PS", 0x2000, 1, struct.pack("<f", 2.5), type_name="REAL", value=2.5),
            StartupCommand("PS", 0x2000, 2, struct.pack("<d", 0.0), type_name="LREAL", value=0.0),
            StartupCommand("PS", 0x2000, 3, (2**64 - 2).to_bytes(8, "little"), type_name="ULINT", value=2**64 - 2),
            StartupCommand("PS", 0x2000, 4, (7).to_bytes(8, "little"), type_name="LINT", value=7)]
    cfg = SlaveConfig(StartupList(cmds), identity=Identity(0x1A3, 1))
    text = _check_ros2(cfg)
    assert "type: int32, value: 1075838976}" in text and "written as its bytes" in text
    big = SlaveConfig(StartupList([StartupCommand("PS", 0x2000, 5, (1 << 40).to_bytes(8, "little"))]),
                      identity=Identity(0x1A3, 1))
    with pytest.raises(EncodeError, match=r"0x2000:05.*32-bit int"):
        export(big, "ros2")


def test_ros2_import_reports_values_the_driver_would_stop_on():
    text = b"vendor_id: 0x1a3\nproduct_id: 0x1\nsdo:\n  - {index: 0x6093, sub_index: 1, type: uint32, value: 3221225472}\n"
    (cfg,) = import_bytes(text, "old.yaml")
    assert cfg.commands[0].data == (3221225472).to_bytes(4, "little")
    assert [n.rule for n in cfg.notes] == ["startup.ros2.driver"] and "old.yaml:4" in str(cfg.notes[0])


# --- 2. one-shot writes are no startup writes ------------------------------------------------------------

def _with_reset() -> SlaveConfig:
    from ecattool.sw.plan import reset_command

    cmds = [StartupCommand("PS", 0x6060, 0, b"\x08", type_name="SINT", value=8, comment="csp"), reset_command()]
    return SlaveConfig(StartupList(cmds, name="ipos"), name="ipos", position=0, identity=Identity(0x1A3, 0x019F418D))


#: IgH 1.5 before 2014: ecrt_master_sdo_download takes a non-const ``uint8_t *data`` (a const array passed to it is a
#: warning, an error under -Werror or in C++)
ONCE_H = ECRT_H + ("int ecrt_master_sdo_download(ec_master_t *master, uint16_t slave_position, uint16_t index, "
                   "uint8_t subindex, uint8_t *data, size_t data_size, uint32_t *abort_code);\n")


def test_one_shot_reset_is_no_igh_startup_sdo(tmp_path):
    text = export(_with_reset(), "igh")
    configure = text[text.index("int ipos_configure("):]
    assert "0x2080" not in configure and "ecrt_slave_config_sdo8(sc, 0x6060" in configure
    once = text[text.index("int ipos_once("):text.index("int ipos_configure(")]
    assert "(void)ecrt_master_sdo_download(master, 0, 0x2080, 0x00," in once  # the reset's missing reply is expected
    assert "static uint8_t ipos_once0[]" in once  # not const: IgH 1.5 before 2014 takes uint8_t *
    # the real ecrt.h, and IgH 1.5's older non-const prototype, both without a warning
    assert _gcc(text, tmp_path).returncode == 0, _gcc(text, tmp_path).stderr
    result = _gcc(text, tmp_path, header=ONCE_H)
    assert result.returncode == 0, result.stderr


def test_one_shot_reset_is_no_ros2_eni_twincat_or_ecmc_startup_write():
    cfg = _with_reset()
    for fmt in ("ros2", "eni", "twincat"):  # refused, the reset named; --lossy leaves it out, named in a comment
        with pytest.raises(EncodeError, match=rf"{fmt} cannot carry 1 part.*1 reset write\(s\) \(0x2080:00\) left out"):
            export(cfg, fmt)
    ros = yaml.safe_load(export(cfg, "ros2", lossy=True))
    assert [e["index"] for e in ros["sdo"]] == [0x6060]
    assert "0x2080:00 := 0x1" in export(cfg, "ros2", lossy=True)  # named in a comment, not dropped silently
    root = etree.fromstring(export(cfg, "eni", lossy=True).encode())
    assert [ic.findtext("Index") for ic in root.iter("InitCmd") if ic.find("Index") is not None] == ["24672"]
    assert any("2080" in str(c.text) for c in root.iter(etree.Comment))
    tc = export(cfg, "twincat", lossy=True)
    (back,) = import_bytes(tc.encode(), "x.txt", "twincat")
    assert [c.index for c in back.commands] == [0x6060] and "# not a startup line: 0x2080:00" in tc
    ecmc = export(cfg, "ecmc")
    startup = re.findall(r'ecmcConfigOrDie "Cfg\.EcAddSdo\((\w+),(0x[0-9A-F]+),', ecmc)
    assert startup == [("0", "0x6060")]
    # written once when the script runs, its failure (no reply) tolerated: as ecmccfg's EEPROM scripts do
    assert 'ecmcConfig "Cfg.EcWriteSdo(0,0x2080,0x0,0x1,2)"' in ecmc
    (back,) = import_bytes(ecmc.encode(), "x.cmd")
    assert [(c.index, c.one_shot) for c in back.commands] == [(0x6060, False), (0x2080, True)]


def _eeprom_script():
    (cfg,) = import_file(corpus_path("configs", "ecmc_ecmciPOS4808-EEPROM-BaseConfig-StepperOpenLoopCSV.cmd"))
    cfg.identity = Identity(0x1A3, 0x019F418D)  # set by the device script ecmccfg runs before it
    return cfg


def _writes(cmds):
    return [(c.kind, c.index, c.subindex, c.data) for c in cmds]


def test_the_ecmc_eeprom_script_stays_one_shot_in_order_with_the_reset_last_in_every_format(tmp_path):
    """Issue 27, done when: 2064h, 1,081 x 2065h (EcWriteSdo, once) and the 2080h reset (ecmcConfig, no reply)
    converted to ecmc, IgH, pysoem, JSON and CSV (and back where the format is read) stay one-shot, in order,
    the reset last."""
    cfg = _eeprom_script()
    want = _writes(cfg.commands)
    assert len(want) == 1083 and {k for k, *_ in want[:-1]} == {"once"} and want[-1][:2] == ("reset", 0x2080)
    assert [i for _, i, _, _ in want[:2]] == [0x2064, 0x2065]
    for fmt in ("ecmc", "json", "csv"):
        (back,) = import_bytes(export(cfg, fmt).encode(), f"x.{fmt}", fmt)
        assert _writes(back.commands) == want, fmt
    ecmc = export(cfg, "ecmc")
    assert "EcAddSdo(" not in ecmc and ecmc.count('ecmcConfigOrDie "Cfg.EcWriteSdo(') == 1082
    assert ecmc.rstrip().splitlines()[-1] == 'ecmcConfig "Cfg.EcWriteSdo(${ECMC_EC_SLAVE_NUM},0x2080,0x0,0x1,2)"'
    # IgH: every write in <slave>_once(), in order, none in the startup configuration; compiled with ecrt.h
    igh = export(cfg, "igh")
    once = igh[igh.index("_once(ec_master_t *master)"):igh.index("_configure(ec_master_t *master)")]
    arrays = dict(re.findall(r"static uint8_t (\w+)\[\] = \{([^}]*)\};", once))
    calls = re.findall(r"(\(void\)|if \()ecrt_master_sdo_download\(master, \w+, (0x[0-9a-f]+), (0x[0-9a-f]+), (\w+),",
                       once)
    assert [("reset" if v == "(void)" else "once", int(i, 16), int(sub, 16),
             bytes(int(b, 16) for b in arrays[name].split(","))) for v, i, sub, name in calls] == want
    assert "ecrt_slave_config_sdo" not in igh[igh.index("_configure(ec_master_t *master)"):]
    from tests.startup.test_startup_export import _gcc

    assert _gcc(igh, tmp_path).returncode == 0
    # pysoem (the real module for WkcError): once(master) writes them in order; config_func writes none
    import pysoem

    sent = []

    class Slave:
        def sdo_write(self, index, sub, data, ca=False):
            sent.append((index, sub, data))
            if index == 0x2080:
                raise pysoem.WkcError("no reply: the drive resets")

    class Master:
        slaves = [Slave()]

    ns: dict = {}
    exec(compile(export(cfg, "pysoem"), "startup_pysoem.py", "exec"), ns)
    ns["once"](Master())
    assert sent == [(i, sub, d) for _, i, sub, d in want]
    sent.clear()
    for _, func, *_ in ns["SLAVES"]:
        func(Slave())
    assert sent == []


# --- 7. identity ---------------------------------------------------------------------------------------

@pytest.mark.parametrize("fmt", ["igh", "ros2"])
def test_unknown_identity_is_refused_not_written_as_zero(fmt):
    cfg = SlaveConfig(StartupList([StartupCommand("PS", 0x6060, 0, b"\x08")]), name="x")
    with pytest.raises(EncodeError, match="x: no vendor id/product code"):
        export(cfg, fmt)


def test_cli_refuses_identity_less_igh_with_one_line(tmp_path, capsys):
    src = tmp_path / "list.txt"
    src.write_text("<PS>,CoE,0x6060:00,0x08 (8),csp\n")
    code, out, err = run(capsys, "startup", "convert", str(src), "--format", "igh", "-o", str(tmp_path / "x.c"))
    assert code == 1 and "no vendor id/product code" in err and err.strip().count("\n") == 0
    assert not (tmp_path / "x.c").exists()


# --- 8. sync managers and watchdog from the source ----------------------------------------------------

def _syncs(text: str) -> list[str]:
    block = text[text.index("_syncs[] = {"):]
    return re.findall(r"\{(\d+, EC_DIR_\w+, \d+, [^,]+, EC_WD_\w+)\}", block[:block.index("{0xff}")])


def test_igh_sync_managers_follow_the_ros2_sm_section(tmp_path):
    (cfg,) = import_file(corpus_path("configs", "ros2_beckhoff_el3104.yaml"))  # sm: {index: 3, input, watchdog: enable}
    text = export(cfg, "igh")
    assert _syncs(text) == ["0, EC_DIR_OUTPUT, 0, NULL, EC_WD_DISABLE", "1, EC_DIR_INPUT, 0, NULL, EC_WD_DISABLE",
                            "3, EC_DIR_INPUT, 4, ros2_beckhoff_el3104_pdos + 0, EC_WD_ENABLE"]
    assert _gcc(text, tmp_path).returncode == 0


def test_igh_sync_managers_follow_lcec_and_esi(tmp_path, everest):
    configs = import_file(corpus_path("configs", "lcec_generic-complex_ethercat-conf.xml"))
    el6751 = next(c for c in configs if c.identity is not None)
    assert [s.split(",")[0] for s in _syncs(export(el6751, "igh"))] == ["0", "1", "2", "3"]
    cfg = SlaveConfig.from_device(everest, position=0)
    text = export(cfg, "igh")
    by_number = {sm.number: sm for sm in everest.sync_managers}
    for line in _syncs(text):
        n = int(line.split(",")[0])
        if by_number[n].kind in ("Outputs", "Inputs"):
            assert line.endswith("EC_WD_ENABLE" if by_number[n].control_byte & 0x40 else "EC_WD_DISABLE"), line
    assert _gcc(text, tmp_path).returncode == 0


def test_ros2_sm_section_says_what_the_source_does(everest):
    # SMConfig::load_from_config: index (uint8), type input/output, pdo rpdo/tpdo, watchdog enable/disable
    cfg = SlaveConfig.from_device(everest, position=0)
    sms = yaml.safe_load(export(cfg, "ros2"))["sm"]
    by_number = {sm.number: sm for sm in everest.sync_managers}
    for entry in sms:
        sm = by_number[entry["index"]]
        assert entry["type"] == {"Outputs": "output", "Inputs": "input"}[sm.kind]
        assert entry["pdo"] == {"output": "rpdo", "input": "tpdo"}[entry["type"]]
        assert entry["watchdog"] == ("enable" if sm.control_byte & 0x40 else "disable")
    # a source that says nothing about sync managers keeps the driver's defaults: no sm section
    (elmo,) = import_file(corpus_path("configs", "ros2_elmo_gold.yaml"))
    assert "sm" not in yaml.safe_load(export(elmo, "ros2"))


# --- 6. ENI distributed clocks ---------------------------------------------------------------------------

def test_eni_dc_is_cycle_start_and_activation_never_cycle_zero():
    (cfg,) = import_file(corpus_path("configs", "ros2_elmo_gold.yaml"))
    with pytest.raises(EncodeError, match="no SYNC0 cycle"):
        export(cfg, "eni")
    cfg.dc_cycle_ns = 2_000_000
    slave = etree.fromstring(export(cfg, "eni").encode()).find("Config/Slave")
    ados = [(ic.findtext("Transition"), int(ic.findtext("Ado"))) for ic in slave.findall("InitCmds/InitCmd")]
    assert ados == [("PS", 0x09A0), ("PS", 0x0990), ("PS", 0x0980), ("IP", 0x0980)]
    assert slave.findtext("DC/CycleTime0") == "2000000"
    (back,) = import_bytes(etree.tostring(slave.getroottree()), "x.xml", "eni")
    assert (back.dc_assign_activate, back.dc_cycle_ns) == (0x0300, 2_000_000)


def test_cli_sync0_cycle_option_fills_the_missing_cycle(tmp_path, capsys):
    out = tmp_path / "elmo.xml"
    src = str(corpus_path("configs", "ros2_elmo_gold.yaml"))
    code, _, err = run(capsys, "startup", "convert", src, "--format", "eni", "-o", str(out))
    assert code == 1 and "--sync0-cycle" in err
    code, _, _ = run(capsys, "startup", "convert", src, "--format", "eni", "--sync0-cycle", "1000000", "-o", str(out))
    assert code == 0 and "<CycleTime0>1000000</CycleTime0>" in out.read_text()


# --- 9. convert/export say what the import did not use ----------------------------------------------------

def test_convert_prints_every_import_note(tmp_path, capsys):
    src = corpus_path("configs", "ecmc_ecmciPOS4808-EEPROM-BaseConfig-StepperOpenLoopCSV.cmd")
    configs = import_file(src)
    notes = [str(n) for c in configs for n in c.notes]
    assert notes
    code, _, err = run(capsys, "startup", "convert", str(src), "--format", "json", "-o", str(tmp_path / "x.json"))
    assert code == 0
    for n in notes:
        assert n in err
    code, _, err2 = run(capsys, "startup", "export", "--from", str(src), "--format", "twincat")
    assert code == 1 and "twincat cannot carry 2 part(s)" in err2 and "--lossy" in err2  # EEPROM writes, reset
    code, out, err2 = run(capsys, "startup", "export", "--from", str(src), "--format", "twincat", "--lossy")
    assert code == 0 and all(n in err2 for n in notes)
    assert "not written (twincat): " in err2 and "1082 once-write(s)" in err2 and "2 part(s) of the configuration" in err2
    assert out.count("<PS>,CoE,0x2065:00") == 1080 and "# not a startup line: 0x2080:00" in out


def test_convert_of_an_empty_result_is_an_error(tmp_path, capsys):
    src = tmp_path / "empty.cmd"
    src.write_text('epicsEnvSet("ECMC_EC_HWTYPE" "nothing")\nsomethingElse()\n')
    out = tmp_path / "x.json"
    code, _, err = run(capsys, "startup", "convert", str(src), "--format", "json", "-o", str(out))
    assert code == 1 and "nothing to import" in err and not out.exists()
    assert "somethingElse()" in err  # the line that was not used is named


@pytest.fixture(scope="module")
def everest():
    from ecattool import esi

    return esi.load_device(str(corpus_path("esi", "ingenia_eve-xcr-e_esi.xml")))



# --- 3/4. ecmc: entry sizes, unique names, the command forms ecmc's parser takes ---------------------------

#: ecmcCmdParser's forms of the commands ecattool writes (sscanf patterns as regexes)
ECMC_ENTRY = re.compile(r'^ecmcConfigOrDie "Cfg\.EcAddEntryComplete\((\w+|\$\{\w+\}),(\$\{\w+\}|0x[0-9a-f]+),'
                        r'(\$\{\w+\}|0x[0-9a-f]+),([12]),(\d+),0x([0-9a-f]+),0x([0-9a-f]+),0x([0-9a-f]+),(\d+),'
                        r'(?:([01]),)?([^,)]+)\)"$')


def _ecmc_entries(text: str) -> list[tuple]:
    out = []
    for line in text.splitlines():
        if "EcAddEntryComplete" in line:
            m = ECMC_ENTRY.match(line)
            assert m, f"not a form ecmc parses: {line}"
            out.append(m.groups())
    return out


def test_ecmc_entries_are_sizes_ecmc_maps_with_unique_names():
    (cfg,) = import_file(corpus_path("configs", "ros2_beckhoff_el3104.yaml"))  # 5-bit gaps, names repeat
    text = export(cfg, "ecmc")
    entries = _ecmc_entries(text)
    assert {int(e[8]) for e in entries} <= {1, 2, 3, 4, 8, 16, 32, 64}
    names = [e[10].lower() for e in entries]
    assert len(names) == len(set(names))  # a duplicate name stops the IOC
    # same bits per PDO as the source (the 5-bit gap is a 4-bit and a 1-bit gap), sync manager 3 from sm:
    for p in cfg.tx_pdos:
        assert sum(int(e[8]) for e in entries if int(e[5], 16) == p.index) == p.bit_size
    assert {e[4] for e in entries} == {"3"}
    (back,) = import_bytes(text.encode(), "x.cmd")
    assert [p.bit_size for p in back.tx_pdos] == [p.bit_size for p in cfg.tx_pdos]


def test_ecmc_refuses_an_object_entry_of_a_size_it_cannot_map():
    from ecattool.esi.model import Direction, Pdo, PdoEntry

    cfg = SlaveConfig(identity=Identity(2, 3), tx_pdos=[Pdo(Direction.TX, 0x1A00, entries=[PdoEntry(0x6000, 1, 6)])])
    with pytest.raises(EncodeError, match="0x6000:01 has 6 bits"):
        export(cfg, "ecmc")


def test_ecmc_reads_the_dt_forms_and_the_realtime_flag_form():
    script = b"""epicsEnvSet("ECMC_EC_VENDOR_ID" "0x2")
epicsEnvSet("ECMC_EC_PRODUCT_ID" "0x4eb3052")
ecmcConfigOrDie "Cfg.EcAddEntryDT(3,${ECMC_EC_VENDOR_ID},${ECMC_EC_PRODUCT_ID},1,2,0x1603,0x7001,0x1,B4,BO01_Ctrl)"
ecmcConfigOrDie "Cfg.EcAddEntryDT(3,${ECMC_EC_VENDOR_ID},${ECMC_EC_PRODUCT_ID},1,2,0x1603,0x7001,0x9,S16,BO01_Cnt,1)"
ecmcConfigOrDie "Cfg.EcAddEntryComplete(3,0x2,0x4eb3052,2,3,0x1a00,0x6000,0x11,16,position,1)"
ecmcConfigOrDie "Cfg.EcAddEntryComplete(3,0x2,0x4eb3052,2,3,0x1a00,0x6064,0x0,32,1,pos)"
ecmcConfigOrDie "Cfg.EcAddSdoDT(3,0x8010,0x1,1000.0,F32)"
ecmcConfigOrDie "Cfg.EcAddSdoDT(3,0x8030,0x8,-1234,S64)"
"""
    (cfg,) = import_bytes(script, "el.cmd")
    assert [(e.index, e.bit_len, e.data_type, e.name) for e in cfg.rx_pdos[0].entries] == [
        (0x7001, 4, "BIT4", "BO01_Ctrl"), (0x7001, 16, "INT", "BO01_Cnt")]
    # ...,bits,name,updateInRealtime): the last number is the realtime flag, not a sign
    assert [(e.subindex, e.name, e.data_type) for e in cfg.tx_pdos[0].entries] == [
        (0x11, "position", ""), (0, "pos", "DINT")]
    assert [(c.index, c.data) for c in cfg.commands] == [(0x8010, struct.pack("<f", 1000.0)),
                                                         (0x8030, (-1234).to_bytes(8, "little", signed=True))]
    assert not cfg.notes


# --- issue 14 item 5: nothing dropped silently -------------------------------------------------------

def test_ecmc_reports_every_line_it_does_not_use():
    src = corpus_path("configs", "ecmc_ecmciPOS4808-EEPROM-BaseConfig-StepperOpenLoopCSV.cmd")
    (cfg,) = import_file(src)
    lines = {n.location.line: n for n in cfg.notes}
    # ecmcConfig "EcReadSdo(...)" (no Cfg. prefix) and the verify after it are named, not skipped silently
    assert "EcReadSdo(${ECMC_EC_SLAVE_NUM},0x206A,0x0,2)" in lines[2185].message
    assert "EcVerifySdo" in lines[2186].message
    script = b'ecmcConfigOrDie "Cfg.EcAddSdo(0,0x6060,0x0,8,1)"\nsomeIocCommand(1,2)\n' \
             b'ecmcConfigOrDie "Cfg.EcSomethingNew(0,1)"\nepicsThreadSleep(0.1)\n'
    (cfg,) = import_bytes(script, "x.cmd")
    assert [(n.location.line, n.rule) for n in cfg.notes] == [(2, "startup.ecmc.unused"), (3, "startup.ecmc.unused")]


# --- 5. pysoem: PDO tables programmed, SAFE-OP only after DC ------------------------------------------------

def _technosoft_from_ros2() -> SlaveConfig:
    """The Technosoft sample through a ros2 file: its PDO mapping is now only the rpdo/tpdo tables."""
    (cfg,) = _sample_configs("technosoft_ipos")
    (back,) = import_bytes(export(cfg, "ros2").encode(), "ipos.yaml")
    assert back.has_pdo_info and not any(is_pdo_programming(c.index) for c in back.commands)
    back.position = 0
    return back


def _run_module(code: str, drives, **kwargs):
    """The module run as its docstring says (tests.startup.test_startup_export), recording each slave's AL state at
    the moment dc_sync starts its SYNC0."""
    states_at_dc: list[int] = []

    def watch_dc(master) -> None:
        for s in master.slaves:
            original = s.dc_sync
            s.dc_sync = lambda *a, _s=s, _o=original: (states_at_dc.append(_s.state & 0x0F), _o(*a))[1]

    return _run_pysoem_module(code, drives, before_safe_op=watch_dc, **kwargs), states_at_dc


def test_pysoem_programs_a_mapping_given_only_as_tables():
    from ecattool.sim import Drive

    cfg = _technosoft_from_ros2()
    drive = Drive.from_profile("technosoft-ipos", product="ipos4808-bx-cat-sto", revision="F515K")
    master, _ = _run_module(export(cfg, "pysoem"), [drive])
    slave = master.slaves[0]

    def read(index):
        n = slave.sdo_read(index, 0)[0]
        return [int.from_bytes(slave.sdo_read(index, k)[:2 if index < 0x1600 else 4], "little") for k in range(1, n + 1)]

    assert read(0x1C12) == [p.index for p in cfg.rx_pdos] and read(0x1C13) == [p.index for p in cfg.tx_pdos]
    for p in (*cfg.rx_pdos, *cfg.tx_pdos):
        assert read(p.index) == [(e.index << 16) | (e.subindex << 8) | e.bit_len for e in p.entries]
    # the IO map config_map laid out is the tables' size, and the slave reached SAFE-OP
    assert len(slave.output) * 8 >= sum(p.bit_size for p in cfg.rx_pdos)
    assert slave.state & 0x0F == 4


def test_pysoem_writes_nothing_where_the_slave_already_holds_the_tables():
    from ecattool.sim import Drive

    cfg = _technosoft_from_ros2()
    drive = Drive.from_profile("technosoft-ipos", product="ipos4808-bx-cat-sto", revision="F515K")
    code = export(cfg, "pysoem")
    _run_module(code, [drive])  # programs the drive
    writes = []
    original = drive.sdo_download
    drive.sdo_download = lambda i, s, d, *a, **k: (writes.append(i), original(i, s, d, *a, **k))[1]
    from tests.target.fake_pysoem import make_module

    namespace: dict = {}
    exec(compile(code, "m.py", "exec"), namespace)
    master = make_module([drive]).Master()
    master.open("eth0")
    master.config_init()
    namespace["install"](master)
    master.config_map()
    assert not [i for i in writes if is_pdo_programming(i)]


def test_pysoem_starts_dc_before_safe_op():
    from ecattool.sim import Drive

    drives = [Drive.from_profile("hdt")]
    ident = drives[0].identity()
    cfg = SlaveConfig(StartupList([StartupCommand("PS", 0x6060, 0, b"\x08")]), name="x", position=0,
                      identity=Identity(ident.vendor_id, ident.product_code), dc_assign_activate=0x0300,
                      dc_cycle_ns=1_000_000)
    master, states_at_dc = _run_module(export(cfg, "pysoem"), drives)
    assert states_at_dc == [2]  # dc_sync while the slave was still in PRE-OP: config_map requested nothing
    assert master.slaves[0].state & 0x0F == 4 and master.slaves[0].dc == (0x03, 1_000_000, 0, None)


def test_pysoem_module_uses_only_names_pysoem_has(monkeypatch):
    """Every pysoem attribute the generated module touches is in the fake's surface, which
    tests/target/test_pysoem_surface.py holds against the real module; with pysoem installed, checked here too."""
    import sys

    from tests.target import fake_pysoem

    try:
        import pysoem
    except ImportError:
        pysoem = None
        monkeypatch.setitem(sys.modules, "pysoem", fake_pysoem.make_module([]))
    code = export([_technosoft_from_ros2(), _with_reset()], "pysoem")
    used = set(re.findall(r"(?:slave|master)\.(\w+)", code)) - {"slaves"}
    fake_master = fake_pysoem.make_module([]).Master()
    fake_slave_attrs = set(dir(fake_pysoem.CdefSlave)) | {"config_func"}
    for name in used:
        assert hasattr(fake_master, name) or name in fake_slave_attrs, name
    namespace: dict = {}
    exec(compile(code, "m.py", "exec"), namespace)
    assert namespace["SAFEOP_STATE"] == fake_pysoem.SAFEOP_STATE
    if pysoem is None:
        return
    assert namespace["SAFEOP_STATE"] == pysoem.SAFEOP_STATE
    for name in used:
        assert hasattr(pysoem.Master(), name) or hasattr(pysoem.CdefSlave, name), name


# --- 6 (lcec) and issue 14 item 5: lcec and ENI say what they did not use ------------------------------------

def test_lcec_keeps_the_app_period_cycle_and_reports_sync1_watchdog_and_the_rest(tmp_path):
    configs = import_file(corpus_path("configs", "lcec_generic-complex_ethercat-conf.xml"))
    el7342 = [c for c in configs if c.extra.get("lcec_type") == "EL7342"]
    assert [c.dc_cycle_ns for c in el7342] == [1_000_000, 1_000_000]  # sync0Cycle="*1" x appTimePeriod 1 ms
    assert all(any("<watchdog divider=\"2498\"" in n.message for n in c.notes) for c in el7342)
    configs = import_file(corpus_path("configs", "lcec_initcmds_ethercat-conf.xml"))
    ax = next(c for c in configs if c.identity is not None)
    assert (ax.dc_cycle_ns, ax.dc_shift_ns, ax.dc_sync1_cycle_ns, ax.dc_sync1_shift_ns) == \
        (250_000, 50_000, 750_000, 250_000)
    el7211 = next(c for c in configs if c.extra.get("lcec_type") == "EL7211")  # sync1Cycle="*1" of 1 ms
    assert (el7211.dc_cycle_ns, el7211.dc_sync1_cycle_ns, el7211.dc_sync1_shift_ns) == (1_000_000, 1_000_000, 1000)
    # appTimePeriod and configPdos are named with their lines, not passed over
    notes = [n for c in configs for n in c.notes]
    assert any("appTimePeriod='1000000'" in n.message and n.location.line == 2 for n in notes)
    assert any(n.rule == "startup.lcec.configpdos" and 'configPdos="true"' in n.message for n in ax.notes)
    conf = tmp_path / "conf.xml"
    conf.write_text('<masters><master idx="0" appTimePeriod="500000"><slave idx="0" type="generic" vid="2" pid="3">'
                    '<dcConf assignActivate="300" sync0Cycle="*2"/><modParam name="enableFB2" value="true"/>'
                    '<idnConfig drive="0" idn="S-0-0015" state="PREOP"><idnDataRaw data="0700"/></idnConfig>'
                    '</slave></master></masters>')
    (c,) = import_file(conf)
    assert c.dc_cycle_ns == 1_000_000
    assert sorted(n.message.split(" ")[0] for n in c.notes if n.rule == "startup.lcec.unused") == \
        ["<idnConfig", "<modParam"]


def test_eni_reports_every_element_it_does_not_convert():
    configs = import_file(corpus_path("configs", "eni_kpierczy_test_eni.xml"))
    notes = [n for c in configs for n in c.notes]
    text = "\n".join(n.message for n in notes)
    for part in ("<Physics>", "<BootStrap>", "<PreviousPort>", "<Master>", "<Cyclic>", "<ProcessImage>"):
        assert part in text, part
    assert all(any(n.rule == "startup.eni.register" for n in c.notes) for c in configs)


# --- 10. an ESI that offers only DC: DC in the project and in every export --------------------------------------

def _dc_in_every_export(configs: list[SlaveConfig]) -> None:
    (c,) = configs
    assert c.dc_assign_activate == 0x0300 and c.dc_cycle_ns == 1_000_000
    assert "ecrt_slave_config_dc(sc, 0x0300, 1000000U, 0, 0U, 0);" in export(c, "igh")
    assert yaml.safe_load(export(c, "ros2"))["assign_activate"] == 0x0300
    slave = etree.fromstring(export(c, "eni").encode()).find("Config/Slave")
    assert slave.findtext("DC/CycleTime0") == "1000000"
    assert re.search(r'Cfg\.EcSlaveConfigDC\(\w+,0x300,1000000,0,0,0\)', export(c, "ecmc"))
    assert "(True, 1000000, 0)" in export(c, "pysoem")
    (back,) = import_bytes(export(c, "json").encode(), "x.json")
    assert (back.dc_assign_activate, back.dc_cycle_ns) == (0x0300, 1_000_000)


def test_generic_esi_sample_has_dc_in_every_export():
    _dc_in_every_export(_sample_configs("generic_esi"))


def test_project_new_gives_a_dc_only_esi_dc_and_lint_is_clean(tmp_path, capsys):
    import shutil

    from ecattool.project.machine import load_machine

    esi = tmp_path / "sv660.xml"
    shutil.copy(ROOT / "samples" / "generic_esi" / "inovance_SV660_EOE_1Axis_V9.12.xml", esi)
    out = tmp_path / "machine.yaml"
    code, _, err = run(capsys, "project", "new", "--esi", "sv660.xml", "--select", "InoSV660N", "-o", str(out))
    assert code == 0, err
    text = out.read_text()
    assert "dc: {opmode: DC, cycle_ns: 1000000}" in text
    # the same drive with a csp move: DC is there, so no PRJ045; without it, the warning
    with_move = text.replace("move: {distance: 1}", "move: {distance: 100, mode: csp}")
    assert "mode: csp" in with_move
    out.write_text(with_move)
    assert "PRJ045" not in {f.rule for f in load_machine(out).findings}
    out.write_text(with_move.replace("    dc: {opmode: DC, cycle_ns: 1000000}\n", ""))
    assert "PRJ045" in {f.rule for f in load_machine(out).findings}


def test_project_new_leaves_dc_to_the_user_where_the_esi_offers_free_run(tmp_path):
    from ecattool import esi
    from ecattool.project.skeleton import dc_only_mode

    everest = esi.load_device(str(corpus_path("esi", "ingenia_eve-xcr-e_esi.xml")))  # Synchron (0) and DCSync
    assert [m.assign_activate for m in everest.dc_opmodes] == [0, 0x0300] and dc_only_mode(everest) is None
    sv660 = esi.load_device(str(ROOT / "samples" / "generic_esi" / "inovance_SV660_EOE_1Axis_V9.12.xml"))
    assert dc_only_mode(sv660) == "DC"


# --- SYNC1 in every format that carries DC (issue 27) --------------------------------------------------------

def test_sync1_cycle_and_shift_are_the_same_in_every_format_that_carries_dc(tmp_path):
    """The lcec AX5206 slave: SYNC0 250 us shifted 50 us, SYNC1 750 us shifted 250 us (AssignActivate 0x0730)."""
    from ecattool.errors import EncodeError
    from ecattool.startup import losses

    configs = import_file(corpus_path("configs", "lcec_initcmds_ethercat-conf.xml"))
    ax = next(c for c in configs if c.identity is not None and c.soe_commands)
    ax.rx_pdos, ax.tx_pdos, ax.soe_commands = [], [], []  # DC only here (SoE and IDN tables: tested above)
    want = (0x0730, 250_000, 50_000, 750_000, 250_000)
    assert (ax.dc_assign_activate, ax.dc_cycle_ns, ax.dc_shift_ns, ax.dc_sync1_cycle_ns, ax.dc_sync1_shift_ns) == want
    for fmt in ("json", "ecmc"):  # all five values, read back
        (back,) = import_bytes(export(ax, fmt).encode(), f"x.{fmt}", fmt)
        assert (back.dc_assign_activate, back.dc_cycle_ns, back.dc_shift_ns, back.dc_sync1_cycle_ns,
                back.dc_sync1_shift_ns) == want, fmt
    igh = export(ax, "igh")
    assert "ecrt_slave_config_dc(sc, 0x0730, 250000U, 50000, 750000U, 250000);" in igh
    from tests.startup.test_startup_export import _gcc

    assert _gcc(igh, tmp_path).returncode == 0
    # ENI: SYNC1 cycle in DC/CycleTime1 and the 0x09A4 half of the cycle register; it has no SYNC1 shift
    with pytest.raises(EncodeError, match="SYNC1 shift 250000 ns: an ENI has no SYNC1 shift"):
        export(ax, "eni")
    root = etree.fromstring(export(ax, "eni", lossy=True).encode())
    assert root.findtext(".//DC/CycleTime1") == "750000" and root.findtext(".//DC/ShiftTime") == "50000"
    cycle = next(ic for ic in root.iter("InitCmd") if ic.findtext("Ado") == "2464")
    assert cycle.findtext("Data") == (250_000).to_bytes(4, "little").hex() + (750_000).to_bytes(4, "little").hex()
    (back,) = import_bytes(etree.tostring(root), "x.xml", "eni")
    assert (back.dc_cycle_ns, back.dc_shift_ns, back.dc_sync1_cycle_ns) == (250_000, 50_000, 750_000)
    # pysoem: dc_sync(act, sync0, shift, sync1) (SYNC0 + SYNC1; the latch bits are not pysoem's); no SYNC1 shift
    assert [x for x in losses(ax, "pysoem") if "SYNC1" in x] == [f"{ax.label}: SYNC1 shift 250000 ns: pysoem has no "
                                                                 "SYNC1 shift"]
    ns: dict = {}
    exec(compile(export(ax, "pysoem", lossy=True), "m.py", "exec"), ns)
    assert ns["DC"][0][1] == (True, 250_000, 50_000, 750_000)
    # ros2: the driver sets only assign_activate; shift and SYNC1 are listed losses
    lost = " ".join(losses(ax, "ros2"))
    assert "SYNC0 shift 50000 ns" in lost and "SYNC1 cycle 750000 ns" in lost and "SYNC1 shift 250000 ns" in lost
