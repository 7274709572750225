"""``ecattool esi export`` / ``ecattool.esi.export.device_to_esi``: an ESI from a built-in profile that validates
against the ETG.2000 v1.14 and v1.17 schemas, reads back to the same device model and builds the same SII."""

from __future__ import annotations

import json

import pytest
from lxml import etree

from ecattool import esi, profiles, sii
from ecattool.esi.export import device_to_esi
from tests.conftest import corpus_path, run

SCHEMAS = ("v1.14_ETG2000_1.0.10", "v1.17")
PRODUCTS = [(info.name, p.name) for info in profiles.list_profiles() for p in info.products]
#: ARRAY objects of the profiles that ESI's ArrayInfo cannot state (elements of different types or flags, or
#: sub-indices with gaps): written as records, they read back as RECORD (docs/esi.md, "Writing an ESI")
AS_RECORD = {"technosoft-ipos": {0x60C2}, "hdt": set(), "controltechniques": {0x203C, 0x203D}}


@pytest.fixture(scope="module")
def schemas():
    out = {}
    for version in SCHEMAS:
        xsd = corpus_path("xsd", version, "EtherCATInfo.xsd")
        assert xsd.is_file(), xsd
        out[version] = etree.XMLSchema(etree.parse(str(xsd)))
    return out


def _vendor(name: str) -> str:
    return next(i.vendor_name for i in profiles.list_profiles() if i.name == name)


def _entry(obj, e):
    dt = e.datatype
    return (e.subindex, obj.name if obj.object_code.value == "VAR" else e.name,
            (dt.code, dt.kind) if dt is not None else None, e.bit_size, e.access.read, e.access.write,
            e.pdo_mapping, e.default, e.minimum, e.maximum, e.enum, e.category if e.category in ("m", "o", "c") else "",
            e.backup, e.setting)


def facts(d, as_record=frozenset()):
    """What an ESI states about a device (docs/esi.md, "Writing an ESI", lists what it cannot)."""
    mb = d.mailbox
    return {
        "identity": d.identity, "type": d.type_name, "name": d.name, "group": (d.group_type, d.group_name),
        "physics": d.physics, "profile_no": d.profile_no, "url": d.url, "ebus": d.ebus_current_ma,
        "fmmus": d.fmmus, "eeprom": d.eeprom, "dc": d.dc_opmodes,
        "sms": [(s.number, s.kind, s.start_address, s.default_size, s.min_size, s.max_size, s.control_byte,
                 s.enable, s.virtual, s.op_only) for s in d.sync_managers],
        "pdos": [(p.direction, p.index, p.name, p.sm, p.fixed, p.mandatory, p.excludes,
                  [(e.index, e.subindex, e.bit_len, e.name, e.data_type) for e in p.entries])
                 for p in (*d.rx_pdos, *d.tx_pdos)],
        "mailbox": None if mb is None else (sorted(mb.protocols), mb.coe, mb.data_link_layer,
                    [(c.protocol, c.transitions, c.index, c.subindex, c.data, c.comment, c.fixed, c.complete_access)
                     for c in mb.init_cmds]),
        "objects": {o.index: (o.name, "RECORD" if o.index in as_record else o.object_code.value,
                              [_entry(o, e) for e in o]) for o in d.dictionary},
    }


@pytest.mark.parametrize(("name", "product"), PRODUCTS, ids=[f"{n}-{p}" for n, p in PRODUCTS])
def test_export_validates_and_reads_back_to_the_same_device(schemas, name, product):
    device = profiles.load(name, product=product)
    data = device_to_esi(device, vendor_name=_vendor(name))
    doc = etree.fromstring(data)
    for version, schema in schemas.items():
        assert schema.validate(doc), f"{version}: {schema.error_log.last_error}"
    back = esi.load_bytes(data, f"{name}.xml")
    assert back.warnings == [] and back.vendor_name == _vendor(name) and len(back.devices) == 1
    read = back.devices[0]
    assert facts(read) == facts(device, AS_RECORD[name])
    assert {o.index for o in read.dictionary if o.object_code.value == "RECORD"} >= AS_RECORD[name]
    # the same SII image as the wire simulator builds from the profile
    assert sii.build(read).to_bytes() == sii.build(device).to_bytes()
    assert profiles.rules_for(read) == profiles.rules_for(device)


def test_revision_and_enum_types_are_written(tmp_path):
    device = profiles.load("technosoft-ipos", revision="F515I")
    doc = etree.fromstring(device_to_esi(device))
    dev = doc.find("Descriptions/Devices/Device")
    assert dev.find("Type").get("RevisionNo") == "#x35313549" and dev.find("Type").text == device.type_name
    # the value names of 6060h as an enum data type over its base type
    obj = next(o for o in dev.iterfind("Profile/Dictionary/Objects/Object") if o.findtext("Index") == "#x6060")
    dt = next(t for t in dev.iterfind("Profile/Dictionary/DataTypes/DataType") if t.findtext("Name") == obj.findtext("Type"))
    assert dt.findtext("BaseType") == "SINT" and {int(e.findtext("Enum")) for e in dt.iterfind("EnumInfo")} >= {1, 8}
    # writable in PRE-OP only: WriteRestrictions
    assert any(o.findtext("Index") == "#x1C12" for o in dev.iterfind("Profile/Dictionary/Objects/Object"))
    assert dev.find("Mailbox/CoE/InitCmd/Index").text == "#x6060"


def test_cli_export_then_read_build_and_commission(capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("ECATTOOL_CACHE_DIR", str(tmp_path / "cache"))
    out = tmp_path / "ipos.xml"
    code, stdout, err = run(capsys, "esi", "export", "technosoft-ipos", "--product", "ipos4808-bx-cat",
                            "--revision", "F515I", "-o", str(out))
    assert code == 0 and stdout == "", err
    code, stdout, _ = run(capsys, "esi", "devices", str(out), "--json")
    summary = json.loads(stdout)[0]
    assert code == 0 and (summary["product_code"], summary["revision"]) == (0x019F418D, 0x35313549)
    code, stdout, err = run(capsys, "esi", "validate", str(out), "--schema-dir", str(corpus_path("xsd", "v1.17")))
    assert code == 0 and "0 error(s), 0 warning(s)" in stdout, stdout + err
    code, _, err = run(capsys, "sii", "build", str(out), "-o", str(tmp_path / "ipos.bin"))
    device = profiles.load("technosoft-ipos", product="ipos4808-bx-cat", revision="F515I")
    assert code == 0 and (tmp_path / "ipos.bin").read_bytes() == sii.build(device).to_bytes()
    project = tmp_path / "project.yaml"
    project.write_text("ecattool: 1\nname: from-export\ndrives:\n  - name: z\n    device: {esi: ipos.xml}\n"
                       "    parameters:\n      - {object: '0x6081:00', value: 100000}\n"
                       "      - {object: '0x6083:00', value: 1000}\n    move: {distance: 1000, mode: pp}\n")
    code, stdout, err = run(capsys, "commission", str(project))
    assert code == 0 and "1 of 1 drive(s) commissioned" in stdout, stdout + err


def test_cli_export_to_stdout_and_errors(capsys, tmp_path):
    code, stdout, _ = run(capsys, "esi", "export", "hdt", "--product", "dgfox", "-o", "-")
    assert code == 0 and stdout.startswith("<?xml") and "<EtherCATInfo" in stdout
    out = tmp_path / "x.xml"
    out.write_bytes(b"before")
    for args in (("nope",), ("technosoft-ipos", "--revision", "F999Z"), ("hdt", "--product", "nope")):
        code, stdout, err = run(capsys, "esi", "export", *args, "-o", str(out))
        assert code == 1 and stdout == "" and len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert out.read_bytes() == b"before" and sorted(p.name for p in tmp_path.iterdir()) == ["x.xml"]


#: vendor files re-exported: (file, facts that differ from the source and why)
VENDOR_FILES = {
    "esi/elmo_Elmo_ECAT_00010420_V11.xml": {},
    "esi/copley_XE2_4.60.xml": {},  # octet-string blobs (arrays of records), enums, Eeprom
    "esi/inovance_SV660_EOE_1Axis_V9.12.xml": {"objects": "2002h.6 MinValue -3 is no UINT value: not written"},
    "esi/synapticon_Somanet_CiA402-single.xml": {},  # ARRAYs with sub-index 0 only (1C10h, 1C11h)
    "esi/weidmueller_UR20_FBC.xml": {},  # a STRING default padded with NULs (DefaultData, byte-exact)
    "esi/weidmueller_UR20_FBC_from_IgH.xml": {"group": "no group in the IgH file: 'Devices'",
                                              "physics": "no Physics in the IgH file (the schema requires it): YY"},
    "eds/technosoft_iPOS.D.v1.04.eds": {},
}


@pytest.mark.parametrize("path", sorted(VENDOR_FILES))
def test_vendor_devices_and_an_eds_export_to_a_valid_esi_that_reads_back(schemas, path):
    from tests.conftest import corpus_path

    doc = esi.load(corpus_path(*path.split("/")))
    device = doc.devices[0]
    data = device_to_esi(device, vendor_name=doc.vendor_name)
    parsed = etree.fromstring(data)
    for version, schema in schemas.items():
        assert schema.validate(parsed), f"{version}: {schema.error_log.last_error}"
    back = esi.load_bytes(data, "x.xml")
    assert back.warnings == []
    source, read = facts(device), facts(back.devices[0])
    assert {k for k in source if source[k] != read[k]} == set(VENDOR_FILES[path])


def test_cli_export_of_an_eds_and_option_misuse(capsys, tmp_path):
    from tests.conftest import corpus_path

    eds = corpus_path("eds", "technosoft_iPOS.D.v1.04.eds")
    out = tmp_path / "ipos.xml"
    code, _, err = run(capsys, "esi", "export", str(eds), "-o", str(out))
    assert code == 0, err
    assert facts(esi.load(out).devices[0]) == facts(esi.load(eds).devices[0])
    code, _, err = run(capsys, "esi", "export", str(eds), "--revision", "F515K", "-o", str(tmp_path / "a.xml"))
    assert code == 2 and "--device" in err and not (tmp_path / "a.xml").exists()
    code, _, err = run(capsys, "esi", "export", "hdt", "--device", "0", "-o", str(tmp_path / "b.xml"))
    assert code == 2 and not (tmp_path / "b.xml").exists()
    code, _, err = run(capsys, "esi", "export", str(out), "-o", str(out))  # never over its input
    assert code == 1 and "input" in err


def _eds_with_shared_names(tmp_path):
    """The corpus EDS with two sub-items of 1018h named "Reserved", as EDS files often have them."""
    text = corpus_path("eds", "technosoft_iPOS.D.v1.04.eds").read_text(encoding="latin-1")
    for sub in ("Revision number", "Serial number"):
        text = text.replace(f"ParameterName={sub}", "ParameterName=Reserved", 1)
    path = tmp_path / "shared_names.eds"
    path.write_text(text, encoding="latin-1")
    return path


def test_an_eds_whose_sub_items_share_a_name_exports_a_valid_esi(tmp_path, schemas, capsys):
    """Issue 27: the names are the schema's key of a DataType's SubItems; a repeat made an invalid ESI, exit 0."""
    path = _eds_with_shared_names(tmp_path)
    out = tmp_path / "x.xml"
    code, _, err = run(capsys, "esi", "export", str(path), "-o", str(out))
    assert code == 0, err
    tree = etree.parse(str(out))
    for version, schema in schemas.items():
        assert schema.validate(tree), (version, schema.error_log)
    dt = next(d for d in tree.iter("DataType") if d.findtext("Name") == "DT1018")
    assert [si.findtext("Name") for si in dt.iter("SubItem")][3:] == ["Reserved", "Reserved_04"]
    obj = next(o for o in tree.iter("Object") if o.findtext("Index") == "#x1018")
    assert [si.findtext("Name") for si in obj.find("Info").iter("SubItem")][3:] == ["Reserved", "Reserved_04"]
    dev = esi.select(esi.load(str(out)), None)
    assert [e.name for e in dev.dictionary.get(0x1018)][3:] == ["Reserved", "Reserved_04"]


def test_esi_export_refuses_to_return_an_esi_that_breaks_a_schema_key():
    from ecattool.errors import EncodeError
    from ecattool.esi.export import check_own_output

    device = profiles.load("hdt")
    root = etree.fromstring(device_to_esi(device))
    dt = next(root.iter("DataType"))
    for si in list(dt.iter("SubItem"))[:2]:
        si.find("Name").text = "Reserved"
    if len(list(dt.iter("SubItem"))) >= 2:
        with pytest.raises(EncodeError, match="SubItemKey"):
            check_own_output(root, device)
    next(root.iter("Object")).find("Type").text = "NOPE"
    with pytest.raises(EncodeError, match="'NOPE' names no DataType"):
        check_own_output(root, device)
