"""Importers against the real configurations in the corpus: every file imports, with asserted facts."""

from __future__ import annotations

import pytest

from ecattool.errors import InputError
from ecattool.esi.model import Direction
from ecattool.startup import detect_format, import_bytes, import_file
from tests.conftest import corpus_path

CONFIGS = [
    "ecmc_ecmciPOS4808-EEPROM-BaseConfig-StepperOpenLoopCSV.cmd", "ecmc_ecmciPOS4808.cmd", "ecmc_ecmciPOSXXXX.cmd",
    "eni_kpierczy_test_eni.xml", "lcec_generic-complex_ethercat-conf.xml", "lcec_initcmds_AX5206-AM8032-async.xml",
    "lcec_initcmds_ethercat-conf.xml", "ros2_beckhoff_el3104.yaml", "ros2_beckhoff_el5101.yaml", "ros2_elmo_gold.yaml",
    "ros2_epos4_config_with_gear_box.yaml", "ros2_maxon_epos3.yaml", "ros2_maxon_epos4_50_5_config.yaml",
    "ros2_schneider_atv320.yaml", "ros2_technosoft_ipos3604.yaml",
]
EXPECTED_FORMAT = {"ecmc": "ecmc", "eni": "eni", "lcec": "lcec", "ros2": "ros2"}


def test_corpus_list_is_complete(corpus):
    on_disk = {p.name for p in (corpus / "configs").iterdir()}
    assert on_disk == set(CONFIGS) | {"hwdevmgr_device_config.yaml"}


#: configurations that hold nothing of a startup list (an ecmc script that sets the identity and includes others)
NOTHING = {"ecmc_ecmciPOS4808.cmd"}


@pytest.mark.parametrize("name", CONFIGS)
def test_every_corpus_config_imports_with_locations(name):
    path = corpus_path("configs", name)
    if name in NOTHING:
        with pytest.raises(InputError, match="nothing to import"):
            import_file(path)
        return
    configs = import_file(path)
    assert configs
    for c in configs:
        for cmd in c.commands:
            assert cmd.source is not None and cmd.source.file == str(path) and cmd.source.line >= 1
            assert cmd.data, cmd
        for s in c.soe_commands:
            assert s.source is not None and s.source.line >= 1


@pytest.mark.parametrize("name", CONFIGS)
def test_format_detected_from_content(name):
    data = corpus_path("configs", name).read_bytes()
    expected = EXPECTED_FORMAT[name.split("_")[0]]
    if name == "lcec_initcmds_AX5206-AM8032-async.xml":
        expected = "eni"  # a TwinCAT EtherCATMailbox export, read by the ENI module
    assert detect_format(data, name) == expected


def test_hwdevmgr_config_is_refused_clearly():
    path = corpus_path("configs", "hwdevmgr_device_config.yaml")
    with pytest.raises(InputError) as err:
        import_file(path)
    assert "hw_device_mgr" in str(err.value) and "data types" in str(err.value)
    assert err.value.location.line == 6


def test_ros2_technosoft_ipos3604():
    (c,) = import_file(corpus_path("configs", "ros2_technosoft_ipos3604.yaml"))
    assert (c.identity.vendor_id, c.identity.product_code) == (0x1A3, 0x01AB46E5)
    assert c.dc_assign_activate == 0x0330
    assert [(x.index, x.subindex, x.data, x.type_name, x.value) for x in c.commands] == [
        (0x60C2, 1, b"\x0a", "SINT", 10), (0x60C2, 2, b"\xfd", "SINT", -3)]
    assert all(x.transition == "PS" for x in c.commands)
    assert c.commands[0].comment == "Set interpolation time for cyclic modes to 10 ms"
    assert c.commands[0].source.line == 7
    assert [p.index for p in c.rx_pdos] == [0x1600, 0x1601, 0x1602]
    assert [p.index for p in c.tx_pdos] == [0x1A00, 0x1A01, 0x1A02, 0x1A03]
    assert [(e.index, e.subindex, e.bit_len) for e in c.rx_pdos[2].entries] == [(0x2090, 2, 8), (0x2090, 1, 8)]
    assert c.channel_info[(0x1600, 0)] == {"command_interface": "control_word", "default": 0}
    assert c.extra == {"auto_fault_reset": False}


def test_ros2_elmo_gold_default_nan_and_period():
    (c,) = import_file(corpus_path("configs", "ros2_elmo_gold.yaml"))
    assert len(c.commands) == 3 and c.commands[2].data == bytes([35])
    assert c.extra["period"] == 100
    assert c.channel_info[(0x1607, 0)]["default"] != c.channel_info[(0x1607, 0)]["default"]  # .nan
    assert c.channel_info[(0x1607, 2)]["default"] == -5


def test_ros2_beckhoff_el3104_bit_types_and_gaps():
    (c,) = import_file(corpus_path("configs", "ros2_beckhoff_el3104.yaml"))
    assert not c.rx_pdos and len(c.tx_pdos) == 4
    pdo = c.tx_pdos[0]
    assert pdo.bit_size == 32
    assert [(e.index, e.bit_len, e.data_type) for e in pdo.entries[5:7]] == [(0, 1, "BOOL"), (0, 5, "BIT5")]
    assert c.extra["sm"] == [{"index": 3, "type": "input", "pdo": "tpdo", "watchdog": "enable"}]


def test_ros2_multiline_flow_mappings_keep_comments():
    (c,) = import_file(corpus_path("configs", "ros2_epos4_config_with_gear_box.yaml"))
    assert c.rx_pdos[0].entries[0].name == "Control word"
    assert c.channel_info[(0x1603, 1)]["factor"] == pytest.approx(8769.23076923077)


def test_eni_kpierczy_slaves_and_initcmds():
    configs = import_file(corpus_path("configs", "eni_kpierczy_test_eni.xml"))
    assert [c.name for c in configs] == ["Imu", "WheelRearLeft", "WheelRearRight", "WheelFrontLeft", "WheelFrontRight"]
    assert [c.position for c in configs] == [0, 1, 2, 3, 4]
    assert sum(len(c.commands) for c in configs) == 48
    imu, wheel = configs[0], configs[1]
    assert imu.commands == [] and imu.identity.vendor_id == 33 and imu.identity.revision == 65537
    assert (wheel.identity.vendor_id, wheel.identity.product_code) == (154, 198948)
    first = wheel.commands[0]
    assert (first.transition, first.index, first.subindex, first.data, first.comment) == (
        "PS", 0x1C12, 0, b"\x00", "clear sm pdos (0x1C12)")
    assign = wheel.commands[6]
    assert (assign.index, assign.subindex, assign.data) == (0x1C12, 1, b"\x01\x16")
    op_mode = next(x for x in wheel.commands if x.index == 0x6060)
    assert op_mode.data == b"\x08" and op_mode.comment == "Op mode"
    assert wheel.dc_assign_activate == 0x0300 and wheel.dc_cycle_ns == 10_000_000
    assert [p.index for p in wheel.rx_pdos] == [0x1601] and [p.index for p in wheel.tx_pdos] == [0x1A03]
    assert [p.index for p in imu.tx_pdos] == [0x1A00] and imu.tx_pdos[0].entries[0].name == "Acceleration X"
    assert not any(n.severity.value == "error" for c in configs for n in c.notes)


def test_twincat_mailbox_soe_export_kept_and_reported():
    (c,) = import_file(corpus_path("configs", "lcec_initcmds_AX5206-AM8032-async.xml"))
    assert c.commands == [] and len(c.soe_commands) == 87
    first = c.soe_commands[0]
    assert (first.transition, first.idn, first.drive_no, first.data, first.comment, first.fixed) == (
        "PS", 15, 0, b"\x07\x00", "Telegram type", True)
    feature = c.soe_commands[6]
    assert (feature.transition, feature.idn, feature.data) == ("IP", 32778, bytes.fromhex("ffff000000000000"))
    assert any(n.rule == "startup.soe" and "87" in n.message for n in c.notes)


def test_lcec_initcmds_config_follows_the_initcmds_file():
    configs = import_file(corpus_path("configs", "lcec_initcmds_ethercat-conf.xml"))
    assert [c.position for c in configs] == [0, 1, 2]
    el7211, generic = configs[1], configs[2]
    assert any(n.rule == "startup.lcec.initcmds" for n in el7211.notes)  # AM8121 file is not in the corpus
    assert el7211.dc_assign_activate == 0x700 and el7211.extra["sync0Cycle"] == "*1"
    assert (generic.identity.vendor_id, generic.identity.product_code) == (2, 0x14566012)
    assert len(generic.soe_commands) == 87
    assert generic.dc_assign_activate == 0x730 and generic.dc_cycle_ns == 250000 and generic.dc_shift_ns == 50000
    assert [p.index for p in generic.rx_pdos] == [0x0018, 0x1018]
    assert [(e.index, e.subindex, e.bit_len) for e in generic.tx_pdos[0].entries] == [(0x87, 0, 16), (0x33, 0, 32), (0x54, 0, 16)]
    assert generic.channel_info[(0x0018, 1)]["halPin"] == "srv0-vel-cmd"


def test_lcec_generic_complex_complete_access_sdos():
    configs = import_file(corpus_path("configs", "lcec_generic-complex_ethercat-conf.xml"))
    assert len(configs) == 11
    el6751 = configs[8]
    assert el6751.identity.product_code == 0x1A5F3052
    assert [(c.index, c.subindex, c.complete_access, len(c.data)) for c in el6751.commands] == [
        (0xF800, 0, True, 14), (0x8000, 0, True, 66), (0x8001, 0, True, 16), (0x8002, 0, True, 16)]
    assert el6751.commands[0].data[:4] == bytes([0x0A, 0x00, 0x05, 0x02])
    assert el6751.tx_pdos[1].bit_size == 40 and el6751.rx_pdos[0].bit_size == 64
    assert configs[6].dc_assign_activate == 0x300 and configs[6].dc_shift_ns == -25000


def test_ecmc_ipos_pdo_script():
    (c,) = import_file(corpus_path("configs", "ecmc_ecmciPOSXXXX.cmd"))
    assert len(c.commands) == 41 and all(x.transition == "PS" for x in c.commands)
    assert c.extra["ecmc_slave"] == "${ECMC_EC_SLAVE_NUM}"
    first = c.commands[0]
    assert (first.index, first.subindex, first.data, first.source.line) == (0x1C12, 0, b"\x00", 11)
    entry = c.commands[3]
    assert (entry.index, entry.subindex, entry.data) == (0x1A00, 1, (0x60410010).to_bytes(4, "little"))
    assert entry.comment == "download pdo 0x1A00 entry"  # the quoted TwinCAT line's comment field
    neg = next(x for x in c.commands if x.index == 0x60C2 and x.subindex == 2)
    assert neg.data == b"\xfd" and neg.value == -3
    assert [(p.index, len(p.entries)) for p in c.rx_pdos] == [(0x1600, 2), (0x1601, 2)]
    assert [p.index for p in c.tx_pdos] == [0x1A00, 0x1A01, 0x1A02, 0x1A03]
    assert c.rx_pdos[0].entries[1].name == "velocitySetpoint01"  # ${ECMC_CH_ID} expanded
    assert c.rx_pdos[0].direction is Direction.RX


def test_ecmc_sw_image_as_sdo_writes():
    (c,) = import_file(corpus_path("configs", "ecmc_ecmciPOS4808-EEPROM-BaseConfig-StepperOpenLoopCSV.cmd"))
    assert len(c.commands) == 1083
    assert (c.commands[0].index, c.commands[0].data) == (0x2064, (0x7B780008).to_bytes(4, "little"))
    assert sum(1 for x in c.commands if x.index == 0x2065) == 1080
    assert (c.commands[-1].index, c.commands[-1].data) == (0x2080, b"\x01\x00")
    assert any(n.rule == "startup.ecmc.read" for n in c.notes)


def test_ecmc_identity_from_macros():
    from ecattool.startup.formats import ecmc

    (c,) = ecmc.load(corpus_path("configs", "ecmc_ecmciPOS4808.cmd").read_bytes(), "ecmciPOS4808.cmd")
    assert (c.identity.vendor_id, c.identity.product_code) == (0x1A3, 0x019F418D)
    assert c.name == "iPOS4808"
    assert sum(n.rule == "startup.ecmc.include" for n in c.notes) == 2


def test_an_import_of_nothing_is_an_error_naming_what_was_not_followed():
    # the script sets the identity and includes two others: nothing of a startup list is in it (issue 27)
    with pytest.raises(InputError) as err:
        import_file(corpus_path("configs", "ecmc_ecmciPOS4808.cmd"))
    assert "nothing to import" in str(err.value) and ":23: included script not followed" in str(err.value)
    with pytest.raises(InputError, match="x.csv:1: nothing to import"):
        import_bytes(b"slave,position,transition,index,subindex,data,complete_access,timeout_ms,type,value,comment\n",
                     "x.csv")


def test_a_cmd_that_only_includes_scripts_is_ecmc_not_yaml():
    script = (b"#- hardware script\n${SCRIPTEXEC} ${ecmccfg_DIR}configureSlave.cmd, \"HW_DESC=EL7041\"\n"
              b"${SCRIPTEXEC} ${ecmccfg_DIR}applySlaveConfig.cmd\n")
    assert detect_format(script, "x.cmd") == "ecmc"
    with pytest.raises(InputError, match=r"x.cmd:1: nothing to import.*x.cmd:2: included script not followed"):
        import_bytes(script, "x.cmd")


def test_ecmc_header_date_is_no_comment():
    script = (b"#-########\n#     Date: 2018/01/24 09:40:21\n#  Author: someone\n"
              b'ecmcConfigOrDie "Cfg.EcAddSdo(0,0x6060,0x0,8,1)"\n# csp\necmcConfigOrDie "Cfg.EcAddSdo(0,0x6060,0x0,8,1)"\n')
    (c,) = import_bytes(script, "x.cmd")
    assert [cmd.comment for cmd in c.commands] == ["", "csp"]


def test_ecmc_undefined_macro_in_index_is_an_error_with_line():
    script = b'\n\necmcConfigOrDie "Cfg.EcAddSdo(${ECMC_EC_SLAVE_NUM},$(MY_INDEX),0x0,1,1)"\n'
    with pytest.raises(InputError) as err:
        import_bytes(script, "x.cmd")
    assert err.value.location.line == 3 and "MY_INDEX" in str(err.value)


def test_ecmc_value_too_big_for_size():
    with pytest.raises(InputError) as err:
        import_bytes(b'ecmcConfigOrDie "Cfg.EcAddSdo(0,0x6060,0x0,300,1)"\n', "x.cmd")
    assert "1 byte" in str(err.value) and err.value.location.line == 1


def test_eni_soem_style_ccs2_is_read_as_download_with_a_note():
    xml = b"""<EtherCATConfig><Config><Slave><Info><Name>d</Name><AutoIncAddr>65535</AutoIncAddr></Info>
<Mailbox><CoE><InitCmds><InitCmd><Transition>PS</Transition><Transition>SO</Transition><Ccs>2</Ccs>
<Index>24672</Index><SubIndex>0</SubIndex><Data>08</Data></InitCmd>
<InitCmd><Transition>IP</Transition><Ccs>2</Ccs><Index>4096</Index><SubIndex>0</SubIndex></InitCmd>
</InitCmds></CoE></Mailbox></Slave></Config></EtherCATConfig>"""
    (c,) = import_bytes(xml, "s.xml")
    assert c.position == 1
    assert [(x.transition, x.index, x.data) for x in c.commands] == [("PS", 0x6060, b"\x08"), ("SO", 0x6060, b"\x08")]
    assert {n.rule for n in c.notes} == {"startup.eni.ccs", "startup.eni.upload"}


def test_xml_with_doctype_is_refused():
    with pytest.raises(InputError):
        import_bytes(b'<?xml version="1.0"?><!DOCTYPE x [<!ENTITY a "b">]><EtherCATConfig/>', "bad.xml")


def test_unknown_content_is_a_clear_error():
    with pytest.raises(InputError) as err:
        import_bytes(b"just: text\n", "x.yaml")
    assert "ethercat_driver_ros2" in str(err.value)


def test_ecmc_tolerated_reset_write_expects_no_reply():
    (c,) = import_file(corpus_path("configs", "ecmc_ecmciPOS4808-EEPROM-BaseConfig-StepperOpenLoopCSV.cmd"))
    reset = c.commands[-1]
    assert reset.index == 0x2080 and reset.expect_reply is False
    assert all(x.expect_reply for x in c.commands[:-1])
    from ecattool.startup import export

    text = export(c, "ecmc")
    # a one-shot write: written once when the script runs (EcWriteSdo), not added to the startup list
    assert 'ecmcConfig "Cfg.EcWriteSdo(${ECMC_EC_SLAVE_NUM},0x2080,0x0,0x1,2)"' in text
    (back,) = import_bytes(text.encode(), "again.cmd")
    assert [x.expect_reply for x in back.commands] == [x.expect_reply for x in c.commands]


def test_a_source_that_maps_a_pdo_two_ways_is_a_finding_with_its_line():
    """ecmciPOSXXXX.cmd programs 1A00h with 2 entries (48 bits) by SDO and declares 3 (64 bits) as entries."""
    (c,) = import_file(corpus_path("configs", "ecmc_ecmciPOSXXXX.cmd"))
    found = {n.location.line: n.message for n in c.notes if n.rule == "startup.pdo.conflict"}
    assert set(found) == {162, 165}
    assert found[162].startswith("PDO 0x1A00 is declared with 3 entries (64 bits) but the startup writes (line(s) "
                                 "20, 23, 26, 29) map 2 (48 bits): 6041:00/16, 6064:00/32")
    assert "PDO 0x1A01 is declared with 2 entries (48 bits)" in found[165]


def test_soe_idns_in_pdo_tables_are_a_finding_and_pysoem_never_writes_them_into_1c12():
    from ecattool.errors import EncodeError
    from ecattool.startup import export, losses

    configs = import_file(corpus_path("configs", "lcec_initcmds_ethercat-conf.xml"))
    ax = next(c for c in configs if c.soe_commands and c.identity is not None)
    (note,) = [n for n in ax.notes if n.rule == "startup.pdo.soe"]
    assert note.message.startswith("PDO(s) 0x0018, 0x1018, 0x0010, 0x1010 are no CoE mapping objects")
    assert note.location.line == 16
    with pytest.raises(EncodeError, match="pysoem cannot carry"):
        export(ax, "pysoem")
    assert any("SoE IDNs" in x for x in losses(ax, "pysoem")) and any("SoE command" in x for x in losses(ax, "pysoem"))
    text = export(ax, "pysoem", lossy=True)
    assert "program_pdos(slave" not in text and "0x0018" not in text  # no IDN written into 1C12h/1C13h


def test_consistent_sources_have_no_contradiction():
    from ecattool.project.export import slave_configs
    from tests.conftest import ROOT

    for project in sorted((ROOT / "samples").glob("*/project.yaml")):
        from ecattool.startup import export, import_bytes

        back = import_bytes(export(slave_configs(project), "json").encode(), "x.json")
        assert not [n for c in back for n in c.notes if n.rule.startswith("startup.pdo")], project
