"""What the ETG schema accepts, the reader reads: variants of corpus ESIs, each proven schema-valid first.

Every variant here is made from a real file of ../shared/corpus with lxml, validated against the bundled
XSDs (v1.17 and v1.14), and then read. The typed attributes and elements come from the XSD itself
(:mod:`tests.xsd_types`); vendor-specific content (``xs:any``) never aborts a read, and one device's flaw never
blocks the other devices of a file.
"""

from __future__ import annotations

from functools import cache
from typing import Any

import pytest
from lxml import etree

from ecattool.esi import device_findings, file_findings, load_bytes, select
from ecattool.errors import InputError, SelectionError
from tests.conftest import corpus_path

XSD_DIRS = ("v1.17", "v1.14_ETG2000_1.0.10")


@cache
def schema(version: str, root: str = "EtherCATInfo") -> etree.XMLSchema:
    return etree.XMLSchema(etree.parse(str(corpus_path("xsd", version, f"{root}.xsd"))))


@cache
def corpus_tree(name: str) -> etree._ElementTree:
    return variant(name)


def variant(name: str) -> etree._ElementTree:
    """A fresh, editable copy of a corpus ESI (parsed again: a deep copy loses source lines above 65535)."""
    return etree.ElementTree(etree.fromstring(corpus_path("esi", name).read_bytes()))


def assert_schema_valid(tree: etree._ElementTree) -> None:
    root = etree.QName(tree.getroot()).localname
    for version in XSD_DIRS:
        s = schema(version, root)
        assert s.validate(tree), f"the variant is not valid against {version}: {s.error_log.last_error}"


def read(tree: etree._ElementTree, source: str = "variant.xml", lazy: bool = False) -> Any:
    return load_bytes(etree.tostring(tree, xml_declaration=True, encoding="UTF-8"), source, lazy=lazy)


@cache
def el1xxx() -> Any:
    """The corpus file as the variants serialize it (same lines), read once."""
    return read(corpus_tree("beckhoff_EL1xxx.xml"), "EL1xxx.xml")


# --- Sm@Enable is the SM enable byte (HexDecValue), not a boolean --------------------------------------------
@pytest.mark.parametrize("text", ["9", "#x9", "#x09", "+9", "009"])
def test_sm_enable_byte_is_read_and_written_to_the_sii_as_given(text: str) -> None:
    from ecattool.sii import build, parse

    tree = variant("synapticon_Somanet_CiA402-single.xml")
    sms = tree.getroot().findall(".//Device/Sm")
    assert [sm.get("Enable") for sm in sms] == ["1", "1", "1", "1"]
    sms[3].set("Enable", text)  # real files write Enable="9": enable | OP only
    assert_schema_valid(tree)
    esi = read(tree)
    dev = select(esi)
    assert [(s.enable, s.enable_byte) for s in dev.sync_managers] == [(True, 1)] * 3 + [(True, 9)]
    assert not dev.sync_managers[3].op_only and esi.warnings == []
    image = parse(build(dev).to_bytes())
    assert [s.enable for s in image.sync_managers] == [1, 1, 1, 9]


def test_sm_enable_byte_with_bit_0_clear_is_disabled_and_an_absent_enable_is_enabled() -> None:
    from ecattool.sii import build, parse

    tree = variant("synapticon_Somanet_CiA402-single.xml")
    sms = tree.getroot().findall(".//Device/Sm")
    sms[2].set("Enable", "#x08")
    del sms[3].attrib["Enable"]
    assert_schema_valid(tree)
    dev = select(read(tree))
    assert [(s.enable, s.enable_byte) for s in dev.sync_managers[2:]] == [(False, 8), (True, None)]
    assert [s.enable for s in parse(build(dev).to_bytes()).sync_managers][2:] == [8, 1]


def test_sm_enable_outside_a_byte_is_kept_to_its_low_byte_with_a_located_warning() -> None:
    tree = variant("synapticon_Somanet_CiA402-single.xml")
    sm = tree.getroot().findall(".//Device/Sm")[3]
    sm.set("Enable", "-1")  # the schema allows any integer
    assert_schema_valid(tree)
    esi = read(tree)
    assert esi.devices[0].sync_managers[3].enable_byte == 0xFF
    [w] = esi.warnings
    assert w.rule == "esi-number-range" and w.location.line == sm.sourceline


def test_sm_enable_as_a_boolean_word_is_read_with_a_warning() -> None:
    tree = variant("synapticon_Somanet_CiA402-single.xml")
    tree.getroot().findall(".//Device/Sm")[3].set("Enable", "true")
    assert not schema("v1.17").validate(tree)  # not schema-valid, but tools write it
    esi = read(tree)
    assert esi.devices[0].sync_managers[3].enable_byte == 1
    assert [w.rule for w in esi.warnings] == ["esi-sm-enable-boolean"]


# --- vendor-specific content (xs:any) ------------------------------------------------------------------------
def _el1xxx_with_alternative_mappings() -> tuple[etree._ElementTree, list[Any]]:
    tree = variant("beckhoff_EL1xxx.xml")
    alts = tree.getroot().findall(".//Device/Info/VendorSpecific/TwinCAT/AlternativeSmMapping")
    assert alts
    return tree, alts


def test_an_empty_pdo_in_an_alternative_sm_mapping_means_no_pdo_on_that_sm() -> None:
    tree, alts = _el1xxx_with_alternative_mappings()
    without_sm3 = [alt for alt in alts if not any(sm.get("No") == "3" for sm in alt.iter("Sm"))]
    assert len(without_sm3) == 24
    for alt in without_sm3:
        sm = etree.SubElement(alt, "Sm", No="3")
        etree.SubElement(sm, "Pdo")  # <Sm No="3"><Pdo/></Sm>: nothing on SM3 in this mapping
    assert_schema_valid(tree)
    base = el1xxx()
    esi = read(tree, "EL1xxx.xml")
    assert len(esi.devices) == len(base.devices) == 141
    assert esi.warnings == base.warnings
    mapped = [m for d in esi.devices for m in d.alternative_sm_mappings]
    before = [m for d in base.devices for m in d.alternative_sm_mappings]
    assert len(mapped) == len(before) == len(alts)
    changed = [(m, b) for m, b in zip(mapped, before) if m != b]
    assert len(changed) == len(without_sm3)
    assert all(m.sms[3] == [] and 3 not in b.sms and {k: v for k, v in m.sms.items() if k != 3} == b.sms
               for m, b in changed)


def _make_odd(target: Any, how: str) -> Any:
    """Change one AlternativeSmMapping in place (no line moves); returns the element changed."""
    if how == "sm-number":
        el = target.find("Sm")
        el.set("No", "three")
    elif how == "pdo-name":
        el = target.find("Sm/Pdo")
        el.text = "PDO 1"
    else:
        el = target
        el.set("Default", "yes")
    return el


def test_odd_devices_among_141_load_141_devices_with_one_located_warning_each() -> None:
    tree, alts = _el1xxx_with_alternative_mappings()
    targets = {}  # device line -> (how, element made odd): three devices, one oddity each
    for how, alt in zip(("sm-number", "pdo-name", "default"), (alts[5], alts[40], alts[90])):
        device_el = next(alt.iterancestors("Device"))
        assert device_el.sourceline not in targets
        targets[device_el.sourceline] = (how, _make_odd(alt, how))
    assert_schema_valid(tree)  # processContents="skip": anything goes under VendorSpecific
    base = el1xxx()
    for lazy in (False, True):
        esi = read(tree, "EL1xxx.xml", lazy=lazy)
        assert len(esi.devices) == 141
        new = [w for w in esi.warnings if w not in base.warnings]
        assert [w.rule for w in new] == ["esi-vendor-specific"] * 3
        for dev, was in zip(esi.devices, base.devices):
            mine = [w for w in device_findings(esi, dev) if w in new]
            if dev.location.line in targets:
                how, odd = targets[dev.location.line]
                assert [w.location.line for w in mine] == [odd.sourceline], how
                assert len(dev.alternative_sm_mappings) == len(was.alternative_sm_mappings) - 1
            else:
                assert mine == [] and dev.alternative_sm_mappings == was.alternative_sm_mappings


def test_unknown_vendor_specific_content_is_kept_not_dropped_and_never_aborts() -> None:
    tree = variant("beckhoff_EK11xx.xml")
    dev_el = tree.getroot().find(".//Device")
    vs = etree.SubElement(dev_el.find("Info"), "VendorSpecific")
    etree.SubElement(vs, "{urn:example:acme}Tuning", Gain="not a number").text = "x"
    tw = etree.SubElement(vs, "TwinCAT", Flag="1")
    etree.SubElement(tw, "AlternativeSmMapping").append(etree.fromstring('<Sm No="#xZZ"><Pdo/></Sm>'))
    assert_schema_valid(tree)
    esi = read(tree, "EK11xx.xml")
    assert len(esi.devices) == 19
    dev = esi.devices[0]
    assert dev.extra["VendorSpecific"] == "Tuning Gain=not a number x; TwinCAT Flag=1"
    [w] = device_findings(esi, dev)
    assert w.rule == "esi-vendor-specific" and "'#xZZ' is not a number" in w.message


# --- one device's flaw never blocks the others ----------------------------------------------------------------
def test_a_device_the_reader_cannot_use_is_skipped_with_a_located_error_and_the_others_load() -> None:
    tree = variant("beckhoff_EK11xx.xml")
    devices = tree.getroot().findall(".//Device")
    bad = devices[4].find("Type")
    bad.set("ProductCode", "#xNOPE")  # not schema-valid: the one thing that skips a device
    assert not schema("v1.17").validate(tree)
    for lazy in (False, True):
        esi = read(tree, "EK11xx.xml", lazy=lazy)
        assert len(esi.devices) == 18
        [err] = file_findings(esi)
        assert (err.rule, err.severity.value, err.location.line) == ("esi-device-skipped", "error", bad.sourceline)
        with pytest.raises(SelectionError, match="could not be read"):
            select(esi, "#x0000BEEF")
    only = variant("synapticon_Somanet_CiA402-single.xml")
    only.getroot().find(".//Device/Type").set("ProductCode", "#xNOPE")
    with pytest.raises(InputError, match="ProductCode '#xNOPE' is not a number"):
        read(only)  # no device can be read: the read fails


def test_esi_devices_and_show_surface_warnings_and_skipped_devices(tmp_path: Any) -> None:
    import json

    from click.testing import CliRunner

    from ecattool.cli import cli

    tree = variant("beckhoff_EK11xx.xml")
    devices = tree.getroot().findall(".//Device")
    k = next(i for i, d in enumerate(devices) if d.find("Sm") is not None)
    devices[k + 1].find("Type").set("ProductCode", "#xNOPE")
    sm = devices[k].find("Sm")
    sm.set("Enable", "#x1FF")  # schema-valid, wider than the byte: a warning inside device k
    path = tmp_path / "EK11xx.xml"
    tree.write(str(path), xml_declaration=True, encoding="UTF-8")
    res = CliRunner().invoke(cli, ["esi", "devices", str(path), "--json"])
    assert res.exit_code == 1  # a device was left out
    rows = json.loads(res.stdout)
    assert len(rows) == 18 and all(r["warnings"] == [] for i, r in enumerate(rows) if i != k)
    [w] = rows[k]["warnings"]
    assert (w["rule"], w["line"]) == ("esi-number-range", sm.sourceline)
    assert f"EK11xx.xml:{devices[k + 1].find('Type').sourceline}: error: device at line" in res.stderr
    res = CliRunner().invoke(cli, ["esi", "show", str(path), "--device", str(k), "--json", "--sm"])
    assert res.exit_code == 0
    data = json.loads(res.stdout)
    assert data["sync_managers"][0]["enable_byte"] == 0xFF
    assert {w["rule"] for w in data["warnings"]} == {"esi-number-range", "esi-device-skipped"}


@pytest.mark.parametrize("lcid", ["1033", "+1033", "01033", " 1033 "])
def test_the_english_name_is_found_by_its_lcid_in_every_integer_form(lcid: str) -> None:
    tree = variant("etg_ETG2001_ModulesSlots_CiA402.xml")
    root = tree.getroot()
    obj = root.find(".//Device/Profile/Dictionary/Objects/Object")
    named = [root.find(".//Device"), root.find(".//Descriptions/Modules/Module/RxPdo"),
             root.find(".//Descriptions/Modules/Module/RxPdo/Entry"), obj]
    for el in named:
        first = el.find("Name")
        first.set("LcId", "1031")  # the first name is another language; the English one follows
        english = etree.Element("Name", LcId=lcid)
        english.text = "English"
        first.addnext(english)
    assert_schema_valid(tree)
    esi = read(tree)
    pdo = esi.modules[0].rx_pdos[0]
    index = int(obj.findtext("Index")[2:], 16)
    assert esi.devices[0].name == pdo.name == pdo.entries[0].name == esi.devices[0].dictionary.get(index).name == "English"


def test_a_module_the_reader_cannot_use_is_skipped_and_the_device_and_other_modules_load() -> None:
    tree = variant("etg_ETG2001_ModulesSlots_CiA402.xml")
    modules = tree.getroot().findall("Descriptions/Modules/Module")
    bad = modules[1].find("RxPdo/Index")
    bad.text = "#xZZ"  # not schema-valid
    esi = read(tree)
    assert len(esi.devices) == 1 and len(esi.modules) == len(modules) - 1
    [err] = [w for w in esi.warnings if w.severity.value == "error"]
    assert (err.rule, err.location.line) == ("esi-module-skipped", bad.sourceline)
