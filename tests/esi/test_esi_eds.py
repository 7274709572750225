"""CANopen EDS/DCF files as a device source (ecattool.esi.eds, read by python-canopen), accepted wherever an ESI is.

The profile cross-check against the same EDS is in tests/profiles/test_profiles_technosoft.py.
"""

from __future__ import annotations

import json
import re
import shutil

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ecattool import esi
from ecattool.errors import InputError
from ecattool.esi.model import Direction
from tests.conftest import CORPUS, ROOT, run

EDS = CORPUS / "eds" / "technosoft_iPOS.D.v1.04.eds"  # tests that read it are marked corpus
TEXT = EDS.read_text(encoding="latin-1") if EDS.is_file() else ""


def _line(text: str, marker: str) -> int:
    return text.splitlines().index(marker) + 1


@pytest.fixture(scope="module")
def doc():
    return esi.load(EDS)


@pytest.mark.corpus
def test_corpus_eds_loads_into_the_device_model(doc):
    assert doc.root == "EDS" and doc.vendor_id == 0x1A3 and doc.vendor_name == "Technosoft"
    dev = doc.devices[0]
    assert dev.type_name == "iPOS" and dev.identity.vendor_id == 0x1A3 and dev.profile_no == 402
    assert len(dev.dictionary) == len(re.findall(r"^\[[0-9A-Fa-f]{4}\]$", TEXT, re.M)) == 175
    assert sum(len(o.entries) for o in dev.dictionary) > 300
    # types, access, defaults, limits as the file writes them
    e = dev.dictionary.entry(0x6060, 0)
    assert e.type_name == "SINT" and e.access.text == "rww" and e.pdo_mapping == "R"
    assert (e.minimum, e.maximum) == (-128, 127)
    assert dev.dictionary.entry(0x1000, 0).default_value == 0x60192
    assert dev.dictionary.entry(0x1600, 1).default_value == 0x60400010
    # every entry is located at its section
    assert e.location.line == _line(TEXT, "[6060]")
    assert dev.dictionary.entry(0x1A01, 2).location.line == _line(TEXT, "[1A01sub2]")
    assert doc.warnings == [] or all(w.severity.value == "info" for w in doc.warnings)


@pytest.mark.corpus
def test_pdos_derived_from_the_default_mapping_and_cob_id_validity(doc):
    dev = doc.devices[0]
    assert [p.index for p in dev.rx_pdos] == [0x1600, 0x1601, 0x1602, 0x1603]
    assert [(e.index, e.bit_len) for e in dev.pdo(0x1602).entries] == [(0x6040, 16), (0x607A, 32)]
    # RPDO1-4 are all valid ($NODEID+0x200 …) but all map 6040h: only the longest one is assigned;
    # TPDO3/TPDO4 are invalid (COB-ID bit 31 set), TPDO1 repeats 6041h of TPDO2
    assert [p.index for p in dev.rx_pdos if p.sm == 2] == [0x1602]
    assert [p.index for p in dev.tx_pdos if p.sm == 3] == [0x1A01]
    assert not any(p.fixed for p in (*dev.rx_pdos, *dev.tx_pdos))
    notes = [w.message for w in doc.warnings if "not assigned by default" in w.message]
    assert len(notes) == 4 and any("1600h" in n and "6040:00" in n for n in notes)
    # SMs: the standard layout; default = the assigned PDOs, max = 8 bytes (a CAN frame) per mapping object
    sm2, sm3 = dev.process_sm(Direction.RX), dev.process_sm(Direction.TX)
    assert (sm2.start_address, sm2.default_size, sm2.max_size) == (0x1100, 6, 32)
    assert (sm3.start_address, sm3.default_size, sm3.max_size) == (0x1400, 3, 32)
    # CoE with writable assignment and mapping; SYNC (1005h) on CANopen gives the DC SYNC0 op mode
    assert dev.mailbox.protocols == ["CoE"] and dev.mailbox.coe.pdo_assign and dev.mailbox.coe.pdo_config
    assert [(m.name, m.assign_activate) for m in dev.dc_opmodes] == [("FreeRun", 0), ("DC", 0x0300)]


def _mini(extra: str = "", vendor: str = "0x12345678") -> str:
    return (f"[DeviceInfo]\nVendorNumber={vendor}\nProductName=Mini\nProductNumber=0x42\nRevisionNumber=7\n"
            "[1000]\nParameterName=Device type\nObjectType=0x7\nDataType=0x0007\nAccessType=ro\n"
            "DefaultValue=0x00020192\n" + extra)


_MAPPING = """[1600]
ParameterName=RxPDO1
ObjectType=0x9
SubNumber=2
[1600sub0]
ParameterName=count
DataType=0x0005
AccessType=ro
DefaultValue=1
[1600sub1]
ParameterName=entry 1
DataType=0x0007
AccessType=ro
DefaultValue=0x60400010
[1601]
ParameterName=RxPDO2
ObjectType=0x9
SubNumber=2
[1601sub0]
ParameterName=count
DataType=0x0005
AccessType=rw
DefaultValue=1
[1601sub1]
ParameterName=entry 1
DataType=0x0007
AccessType=rw
DefaultValue=0x607A0020
[6040]
ParameterName=Controlword
DataType=0x0006
AccessType=rww
PDOMapping=1
[607A]
ParameterName=Target position
DataType=0x0004
AccessType=rww
PDOMapping=1
"""


def test_assignment_from_1c12_where_the_eds_has_it_and_fixed_pdos():
    text = _mini(_MAPPING + """[1C12]
ParameterName=RxPDO assign
ObjectType=0x8
SubNumber=2
[1C12sub0]
ParameterName=count
DataType=0x0005
AccessType=ro
DefaultValue=1
[1C12sub1]
ParameterName=PDO 1
DataType=0x0006
AccessType=ro
DefaultValue=0x1601
""")
    doc = esi.load_bytes(text.encode(), "mini.eds")
    dev = doc.devices[0]
    assert (dev.vendor_id, dev.product_code, dev.revision) == (0x12345678, 0x42, 7)
    assert [p.index for p in dev.rx_pdos if p.sm == 2] == [0x1601]
    assert dev.pdo(0x1600).fixed and not dev.pdo(0x1601).fixed  # 1600h sub 0 read-only
    # no 1005h (SYNC): free run only
    assert dev.mailbox.protocols == ["CoE"] and [m.name for m in dev.dc_opmodes] == ["FreeRun"]
    assert not dev.mailbox.coe.pdo_assign and dev.mailbox.coe.pdo_config  # 1C12h read-only, 1601h writable


def test_without_communication_parameters_every_mapping_pdo_counts_as_valid():
    dev = esi.load_bytes(_mini(_MAPPING).encode(), "mini.eds").devices[0]
    assert sorted(p.index for p in dev.rx_pdos if p.sm == 2) == [0x1600, 0x1601]


@pytest.mark.corpus
def test_dcf_parameter_values_and_compact_arrays():
    text = TEXT.replace("[6060]\nParameterName=Modes of Operation", "[6060]\nParameterName=Modes of Operation\n"
                        "ParameterValue=8") + "\n[DeviceComissioning]\nNodeID=5\nBaudrate=500\n"
    doc = esi.load_bytes(text.encode("latin-1"), "drive.dcf")
    dev = doc.devices[0]
    assert doc.root == "DCF" and dev.dictionary.entry(0x6060, 0).default_value == 8 and dev.extra["node_id"] == "5"
    compact = _mini("[2000]\nParameterName=Table\nObjectType=0x8\nDataType=0x0006\nAccessType=rw\n"
                    "CompactSubObj=3\nDefaultValue=9\n")
    obj = esi.load_bytes(compact.encode(), "c.eds").devices[0].dictionary.get(0x2000)
    assert sorted(obj.entries) == [0, 1, 2, 3] and obj.entries[0].default_value == 3
    assert obj.entries[3].default_value == 9


@pytest.mark.parametrize("body,line,fragment", [
    ("[DeviceInfo]\nVendorNumber=1\n[1000]\nParameterName=a\nObjectType=0x7\nDataType=0xZZ\nAccessType=ro\n", 6,
     "[1000] DataType=0xZZ is not a number"),
    ("[DeviceInfo]\nVendorNumber=1\n[1000]\nParameterName=a\nDataType=0x7\nAccessType=ro\n[1000]\n", 7,
     "section [1000] appears twice (first at line 3)"),
    ("[DeviceInfo]\nVendorNumber=1\n[1000]\nParameterName=a\nDataType=0x7\n", 3, "has no AccessType="),
    ("[DeviceInfo]\nVendorNumber=1\n[1000sub1]\nParameterName=a\nDataType=0x7\nAccessType=ro\n", 3,
     "sub-index of [1000], which the file does not define"),
    ("[DeviceInfo]\nVendorNumber=1\ngarbage line\n", 3, "not an EDS/DCF line"),
    ("[DeviceInfo]\nVendorNumber=zz\n", 2, "[DeviceInfo] VendorNumber=zz"),
    ("[DeviceInfo]\nVendorNumber=1\nVendorNumber=2\n", 3, "VendorNumber= appears twice"),
    ("[FileInfo]\nFileName=x\n", 1, "no [DeviceInfo] section"),
])
def test_malformed_eds_is_one_located_line(tmp_path, capsys, body, line, fragment):
    with pytest.raises(InputError) as info:
        esi.load_bytes(body.encode(), "bad.eds")
    assert info.value.location.line == line and fragment in info.value.message
    f = tmp_path / "bad.eds"
    f.write_text(body)
    code, out, err = run(capsys, "esi", "devices", str(f))
    assert code == 1 and out == "" and len(err.strip().splitlines()) == 1
    assert err.startswith(f"ecattool: error: {f}:{line}: ") and "Traceback" not in err


def test_unread_values_and_unused_sections_are_located_warnings():
    text = _mini("[2000]\nParameterName=a\nDataType=0x0005\nAccessType=rw\nDefaultValue=300\n"
                 "[2001]\nParameterName=b\nDataType=0x0005\nAccessType=rw\nDefaultValue=abc\n"
                 "[2001sub1]\nParameterName=c\nDataType=0x0005\nAccessType=rw\n")
    warnings = {(w.location.line, w.message.split(":")[0]) for w in esi.load_bytes(text.encode(), "w.eds").warnings}
    lines = text.splitlines()
    assert (lines.index("DefaultValue=300") + 1, "[2000] DefaultValue 300 does not fit USINT") in warnings
    assert any(n == lines.index("DefaultValue=abc") + 1 and "DefaultValue 'abc'" in m for n, m in warnings)
    assert any(n == lines.index("[2001sub1]") + 1 and "not used" in m for n, m in warnings)


@pytest.mark.corpus
def test_size_is_bounded(monkeypatch, tmp_path):
    import ecattool.esi.eds as eds

    monkeypatch.setattr(eds, "MAX_EDS_BYTES", 1000)
    with pytest.raises(InputError, match="larger than the 1000 byte limit"):
        esi.load_bytes(TEXT.encode("latin-1"), "big.eds")
    big = tmp_path / "big.eds"
    big.write_bytes(TEXT.encode("latin-1"))
    with pytest.raises(InputError, match="larger than the 1000 byte limit"):
        esi.load(big)


@pytest.mark.corpus
def test_cli_accepts_an_eds_wherever_an_esi_goes(capsys, tmp_path):
    code, out, _ = run(capsys, "esi", "devices", str(EDS), "--json")
    assert code == 0 and json.loads(out)[0]["vendor_id"] == 0x1A3
    code, out, _ = run(capsys, "esi", "show", str(EDS), "--objects", "--json")
    objects = {o["index"]: o for o in json.loads(out)["objects"]}
    assert code == 0 and objects[0x2050]["entries"][0]["pdo_mapping"] == "R"
    code, out, _ = run(capsys, "esi", "validate", str(EDS))
    assert code == 0 and "0 error(s)" in out
    code, out, err = run(capsys, "map", "check", "--esi", str(EDS), "--rx", "0x1600=controlword,0x607A:00/32",
                         "--tx", "0x1A00=statusword,0x6064:00/32")
    assert code == 0, err
    code, out, err = run(capsys, "map", "check", "--esi", str(EDS), "--tx", "0x1A00=statusword,0x2050:00/16")
    assert code == 1 and "PDO006" in out + err  # 2050h is rww in the EDS: RxPDO only
    script = tmp_path / "s.yaml"
    script.write_text('- state: PREOP\n- read: "1018:01"\n- write: "6060:00"\n  value: 1\n- state: SAFEOP\n'
                      '- state: OP\n')
    code, out, err = run(capsys, "sim", "run", str(EDS), str(script), "--json")
    assert code == 0, err


@pytest.mark.corpus
def test_project_drive_from_an_eds_commissions_on_the_simulator(capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("ECATTOOL_NO_CACHE", "1")
    shutil.copy(EDS, tmp_path / "ipos.eds")
    project = tmp_path / "project.yaml"
    project.write_text("""ecattool: 1
name: eds-drive
drives:
  - name: x
    device: {esi: ipos.eds}
    pdo:
      rx: [{index: 0x1600, entries: [controlword, "0x607A:00/32"]}]
      tx: [{index: 0x1A00, entries: [statusword, "0x6064:00/32"]}]
    parameters:
      - {object: "0x6081:00", value: 100000}
      - {object: "0x6083:00", value: 1000}
    move: {distance: 1000, mode: pp}
""")
    code, out, err = run(capsys, "lint", str(project))
    assert code == 0, out + err
    code, out, err = run(capsys, "commission", str(project))
    assert code == 0 and "1 of 1 drive(s) commissioned" in out, out + err


@pytest.mark.corpus
def test_stdin_and_xml_sniffing(capsys, monkeypatch):
    import io
    import sys

    monkeypatch.setattr(sys, "stdin", type("S", (), {"buffer": io.BytesIO(EDS.read_bytes())})())
    code, out, _ = run(capsys, "esi", "devices", "-", "--json")
    assert code == 0 and json.loads(out)[0]["type"] == "iPOS"
    assert esi.load_bytes(b"\xef\xbb\xbf; comment first\n" + EDS.read_bytes(), "x.eds").root == "EDS"
    assert esi.load(ROOT / "samples" / "esi" / "etg2001_cia402.xml").root == "EtherCATInfo"


_JUNK = ["x", "[", "]", "[1000sub9]", "DataType=0x9999", "ObjectType=0x8", "CompactSubObj=300", "DefaultValue=-1",
         "AccessType=zz", "PDOMapping=x", "[1C12]", "SubNumber=", "DefaultValue=$NODEID+0x80000000"]
_VALUES = ["", "0x", "-5", "99999999999999", "1.5", "$NODEID", "abc", "0x80000000", "#x10"]


@pytest.mark.corpus
@settings(max_examples=20, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(["del", "dup", "junk", "value"]), st.floats(0, 1, exclude_max=True),
                          st.integers(0, 1000)), min_size=1, max_size=4))
def test_mutated_eds_loads_or_is_one_located_line(ops):
    """Untrusted input: lines deleted, repeated, replaced or given odd values never escape as another exception."""
    from ecattool.profiles import complete_generic

    lines = TEXT.splitlines()
    for op, where, k in ops:
        i = int(where * len(lines))
        if op == "del":
            del lines[i]
        elif op == "dup":
            lines.insert(i, lines[k % len(lines)])
        elif op == "junk":
            lines.insert(i, _JUNK[k % len(_JUNK)])
        elif "=" in lines[i]:
            lines[i] = lines[i].split("=")[0] + "=" + _VALUES[k % len(_VALUES)]
    try:
        doc = esi.load_bytes("\n".join(lines).encode("latin-1"), "m.eds")
    except InputError as exc:
        assert "\n" not in str(exc) and str(exc).startswith("m.eds:")
        return
    complete_generic(doc.devices[0])  # what map/sim/project do with it next
