"""The ``ecattool esi`` commands: devices / show / validate, tables and JSON."""

from __future__ import annotations

import json
import shutil

from click.testing import CliRunner
from lxml import etree

from ecattool.cli import cli
from tests.conftest import ROOT, corpus_path

SAMPLE = ROOT / "samples" / "esi" / "etg2001_cia402.xml"


def run(*args: str) -> tuple[int, str]:
    res = CliRunner().invoke(cli, list(args), catch_exceptions=False)
    return res.exit_code, res.output


def test_sample_is_the_corpus_file():
    assert SAMPLE.read_bytes() == corpus_path("esi", "etg_ETG2001_ModulesSlots_CiA402.xml").read_bytes()


def test_devices_json_keys_and_counts():
    path = corpus_path("esi", "elmo_Elmo_ECAT_00010420_V11.xml")
    code, out = run("esi", "devices", str(path), "--json")
    assert code == 0
    rows = json.loads(out)
    tree = etree.parse(str(path))
    devs = tree.xpath("//Devices/Device")
    assert len(rows) == len(devs) == 4
    for row, el in zip(rows, devs):
        assert {"type", "name", "product_code", "revision", "rx_pdo_count", "tx_pdo_count", "object_count"} <= set(row)
        assert isinstance(row["product_code"], int) and isinstance(row["revision"], int)
        assert row["product_code"] == int(el.find("Type").get("ProductCode")[2:], 16)
        assert row["rx_pdo_count"] == len(el.xpath("RxPdo")) and row["tx_pdo_count"] == len(el.xpath("TxPdo"))
        assert row["object_count"] == len(el.xpath("Profile/Dictionary/Objects/Object"))


def test_devices_table():
    code, out = run("esi", "devices", str(SAMPLE))
    assert code == 0 and "Drive1" in out and "0x00010000" in out and "CoE,FoE" in out


def test_show_sections_tables():
    code, out = run("esi", "show", str(corpus_path("esi", "beckhoff_EL1xxx.xml")), "--device", "EL1258:0x00100000",
                    "--pdos", "--objects", "--sm", "--dc", "--init-cmds")
    assert code == 0
    for text in ("EL1258", "Sync managers", "RxPDOs", "TxPDOs", "Objects:", "Identity", "DC op modes", "Init commands",
                 "0x1018", "7000:01"):
        assert text in out, text


def test_show_module_pdos_and_json():
    code, out = run("esi", "show", str(SAMPLE), "--pdos")
    assert code == 0 and "Module Position Mode (ident 0x00000100)" in out and "607A:00" in out
    code, out = run("esi", "show", str(SAMPLE), "--json", "--objects", "--dc", "--pdos")
    data = json.loads(out)
    assert data["type"] == "Drive1" and len(data["module_pdos"]) == 8 and len(data["objects"]) == 14
    assert data["dc_opmodes"][1]["assign_activate"] == 0x300
    assert data["slots"][0]["default_module"] == 0x100


def test_show_selection_error_lists_candidates():
    res = CliRunner().invoke(cli, ["esi", "show", str(corpus_path("esi", "beckhoff_EL1xxx.xml")), "--device", "EL1008"])
    assert res.exit_code != 0
    assert "matches 3 devices" in str(res.exception)
    code, out = run("esi", "show", str(corpus_path("esi", "beckhoff_EL1xxx.xml")), "--device", "EL1008", "--policy",
                    "newest", "--json")
    assert json.loads(out)["revision"] == 0x00120000


def test_init_cmds_json():
    code, out = run("esi", "show", str(corpus_path("esi", "beckhoff_AX2xxx.xml")), "--init-cmds", "--json")
    data = json.loads(out)
    assert code == 0 and data["init_cmds"] and all("transitions" in c for c in data["init_cmds"])


def test_validate_ok_and_schema(tmp_path):
    code, out = run("esi", "validate", str(SAMPLE))
    assert code == 0 and "0 error(s)" in out
    xsd = corpus_path("xsd", "v1.14_ETG2000_1.0.10")
    code, out = run("esi", "validate", str(corpus_path("esi", "beckhoff_EK11xx.xml")), "--schema-dir", str(xsd), "--json")
    assert code == 0 and json.loads(out)["ok"] is True


def test_validate_reports_xsd_errors_with_lines():
    xsd = corpus_path("xsd", "v1.17")
    code, out = run("esi", "validate", str(corpus_path("esi", "copley_XE2_4.60.xml")), "--schema-dir", str(xsd), "--json")
    data = json.loads(out)
    assert code == 1 and not data["ok"]
    xsd_errors = [f for f in data["findings"] if f["rule"] == "esi-xsd"]
    assert any("hexBinary" in f["message"] and f["line"] for f in xsd_errors)


def test_validate_module_and_dict_roots_pick_their_schema():
    xsd = corpus_path("xsd", "v1.14_ETG2000_1.0.10")
    for name in ("weidmueller_UR20_IO.xml", "beckhoff_AX5021-xxxx-0001_Dict.xml"):
        code, out = run("esi", "validate", str(corpus_path("esi", name)), "--schema-dir", str(xsd), "--json")
        data = json.loads(out)
        assert not [f for f in data["findings"] if f["rule"] == "esi-xsd"], name


def test_validate_missing_schema_file_is_an_error(tmp_path):
    res = CliRunner().invoke(cli, ["esi", "validate", str(SAMPLE), "--schema-dir", str(tmp_path)])
    assert res.exit_code != 0 and "EtherCATInfo.xsd" in str(res.exception)


def test_validate_structural_errors_exit_1(tmp_path):
    src = corpus_path("esi", "synapticon_Somanet_CiA402-single.xml")
    path = tmp_path / "s.xml"
    shutil.copy(src, path)
    code, out = run("esi", "validate", str(path))
    assert code == 1 and "esi-pdo-object-missing" in out and "s.xml:" in out


def test_help_has_examples():
    for cmd in ("devices", "show", "validate"):
        code, out = run("esi", cmd, "--help")
        assert code == 0 and "Examples:" in out and "ecattool esi " + cmd in out


def test_devices_from_stdin():
    res = CliRunner().invoke(cli, ["esi", "devices", "-", "--json"], input=SAMPLE.read_bytes())
    assert res.exit_code == 0 and json.loads(res.output)[0]["type"] == "Drive1"


def test_devices_table_names_stdin_as_elsewhere():
    # docs/cli.md: standard input is named <stdin> (as in 'esi show': "defined at <stdin>:20"), not '-'
    res = CliRunner().invoke(cli, ["esi", "devices", "-"], input=SAMPLE.read_bytes())
    assert res.exit_code == 0 and res.output.startswith("<stdin>: 1 device(s)"), res.output


def test_sample_validates_against_all_three_schema_sets():
    for version in ("v1.3_etg2001_example_bundled", "v1.14_ETG2000_1.0.10", "v1.17"):
        code, out = run("esi", "validate", str(SAMPLE), "--schema-dir", str(corpus_path("xsd", version)), "--json")
        assert code == 0 and json.loads(out)["findings"] == [], version


def test_validate_igh_file_reports_vendor_without_name_both_ways():
    code, out = run("esi", "validate", str(corpus_path("esi", "weidmueller_UR20_FBC_from_IgH.xml")), "--schema-dir",
                    str(corpus_path("xsd", "v1.14_ETG2000_1.0.10")), "--json")
    rules = {(f["rule"], f["line"]) for f in json.loads(out)["findings"]}
    assert code == 1 and ("esi-vendor-name", 4) in rules and ("esi-xsd", 4) in rules
