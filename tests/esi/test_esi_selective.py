"""The selective ESI load (``load(path, lazy=True)``, ``load_device``): the same devices as a full load, built
one at a time; and the import cost of ``ecattool.esi``/``ecattool.sii``; and ``Sm@OpOnly``."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from ecattool.errors import EcatToolError, SelectionError
from ecattool.esi import load, load_bytes, load_device, select, select_index
from ecattool.esi.reader import LazyEsiFile
from ecattool.od.model import ObjectDictionary
from ecattool.record import Record
from tests.conftest import corpus_path

FILES = ["beckhoff_EL1xxx.xml", "weidmueller_UR20_FBC.xml", "beckhoff_AX5xxx.xml", "elmo_Elmo_ECAT_00010420_V11.xml",
         "etg_ETG2001_ModulesSlots_CiA402.xml"]


def _same(a: Any, b: Any, path: str = "device") -> None:
    """Field by field (dictionaries by their objects): the model has no value equality for dictionaries."""
    if isinstance(a, ObjectDictionary) or isinstance(b, ObjectDictionary):
        assert isinstance(a, ObjectDictionary) and isinstance(b, ObjectDictionary), path
        assert a.indices() == b.indices(), path
        for i in a.indices():
            _same(a.get(i), b.get(i), f"{path}[0x{i:04X}]")
    elif isinstance(a, Record):
        assert type(a) is type(b), path
        for name in a._fields:
            _same(getattr(a, name), getattr(b, name), f"{path}.{name}")
    elif isinstance(a, (list, tuple)):
        assert isinstance(b, (list, tuple)) and len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b)):
            _same(x, y, f"{path}[{i}]")
    elif isinstance(a, dict):
        assert isinstance(b, dict) and a.keys() == b.keys(), path
        for k in a:
            _same(a[k], b[k], f"{path}[{k!r}]")
    else:
        assert a == b, f"{path}: {a!r} != {b!r}"


def _outcome(esi: Any, selector: str | None, policy: str) -> tuple[str, Any]:
    try:
        index, dev = select_index(esi, selector, policy)
    except SelectionError as exc:
        return "error", str(exc)
    return "device", (index, dev)


@pytest.mark.parametrize("name", FILES)
def test_every_device_selected_lazily_equals_the_full_load(name: str) -> None:
    path = corpus_path("esi", name)
    full = load(path)
    lazy = load(path, lazy=True)
    assert isinstance(lazy, LazyEsiFile) and lazy.pending
    assert (lazy.vendor_id, lazy.vendor_name, lazy.groups, lazy.info_references) == \
        (full.vendor_id, full.vendor_name, full.groups, full.info_references)
    _same(lazy.modules, full.modules, "modules")
    assert full.devices
    selectors = {f"{d.type_name}:0x{d.revision:X}" for d in full.devices}
    selectors |= {f"#x{d.product_code:x}:{d.revision}" for d in full.devices}
    selectors |= {d.type_name for d in full.devices} | {"0", str(len(full.devices) - 1), "NoSuchDevice", "0x7fffffff"}
    for sel in sorted(selectors):
        for policy in ("exact", "newest-not-newer", "newest"):
            kind, got = _outcome(lazy, sel, policy)
            want_kind, want = _outcome(full, sel, policy)
            assert kind == want_kind, (sel, policy, got, want)
            if kind == "error":
                assert got == want  # same message, same candidate list
            else:
                assert got[0] == want[0], (sel, policy)
                _same(got[1], want[1], f"{name}[{sel} {policy}]")
    assert lazy.pending, "selection built every device"
    # listing afterwards builds the rest, keeping the devices already handed out
    handed_out = {i: lazy.device_at(i) for i in range(min(3, len(full.devices)))}
    assert len(lazy.devices) == len(full.devices) and not lazy.pending
    assert all(lazy.devices[i] is d for i, d in handed_out.items())
    for d_lazy, d_full in zip(lazy.devices, full.devices):
        _same(d_lazy, d_full, f"{name}:{d_full.type_name}")


def test_load_device_builds_only_the_selected_device() -> None:
    path = corpus_path("esi", "beckhoff_EL1xxx.xml")
    lazy = load(path, lazy=True)
    dev = select(lazy, "EL1008", "newest")
    assert lazy.pending and list(lazy._built) == [next(h.index for h in lazy.device_heads if h.element is not None
                                                        and h.type_name == "EL1008" and h.revision == dev.revision)]
    assert len(lazy.device_heads) == 141
    newest = max((d for d in load(path).devices if d.type_name == "EL1008"), key=lambda d: d.revision)
    _same(load_device(path, "EL1008", "newest"), newest)


def test_multi_revision_policies_match_the_full_load() -> None:
    path = corpus_path("sii", "ni9144.xml")
    full = load(path)
    revisions = sorted(d.revision for d in full.devices)
    assert len(revisions) >= 2
    for policy, sel in (("newest", None), ("newest", "1"), ("newest-not-newer", f"NI 9144:{revisions[0]}"),
                        ("exact", None), ("exact", f"0x{full.devices[0].product_code:X}:{revisions[-1]}")):
        assert _outcome(load(path, lazy=True), sel, policy)[0] == _outcome(full, sel, policy)[0]
        if _outcome(full, sel, policy)[0] == "device":
            _same(load_device(path, sel, policy), select(full, sel, policy))
        else:
            with pytest.raises(SelectionError) as lazy_err:
                load_device(path, sel, policy)
            with pytest.raises(SelectionError) as full_err:
                select(full, sel, policy)
            assert str(lazy_err.value) == str(full_err.value)


def test_a_bad_type_in_one_device_skips_that_device_in_both_loads() -> None:
    data = b"""<?xml version="1.0"?>
<EtherCATInfo><Vendor><Id>1</Id><Name>V</Name></Vendor><Descriptions><Devices>
<Device><Type ProductCode="#x1" RevisionNo="1">A</Type></Device>
<Device><Type ProductCode="#xZZ" RevisionNo="1">B</Type></Device>
</Devices></Descriptions></EtherCATInfo>"""
    full = load_bytes(data, "t.xml")
    lazy = load_bytes(data, "t.xml", lazy=True)
    assert select(lazy, "A").type_name == select(full, "A").type_name == "A"
    for esi in (full, lazy):
        [skipped] = [w for w in esi.warnings if w.rule == "esi-device-skipped"]
        assert skipped.location.line == 4 and "'#xZZ' is not a number" in skipped.message
        assert [d.type_name for d in esi.devices] == ["A"]
        with pytest.raises(SelectionError, match=r"1 device\(s\) of the file could not be read: t\.xml:4"):
            select(esi, "B")
    bad_only = data.replace(b'<Device><Type ProductCode="#x1" RevisionNo="1">A</Type></Device>', b"")
    with pytest.raises(EcatToolError) as full_err:
        load_bytes(bad_only, "t.xml")  # no device can be read: the read fails, as before
    with pytest.raises(EcatToolError) as lazy_err:
        load_bytes(bad_only, "t.xml", lazy=True)
    assert str(lazy_err.value) == str(full_err.value) and lazy_err.value.location.line == 4


def test_a_lazy_file_pickles_as_a_complete_file() -> None:
    import pickle

    esi = load(corpus_path("esi", "etg_ETG2001_ModulesSlots_CiA402.xml"), lazy=True)
    back = pickle.loads(pickle.dumps(esi))
    assert type(back).__name__ == "EsiFile"
    _same(back.devices, load(corpus_path("esi", "etg_ETG2001_ModulesSlots_CiA402.xml")).devices, "devices")


def _modules_after(code: str) -> set[str]:
    out = subprocess.run([sys.executable, "-c", code + "\nimport sys\nprint('\\n'.join(sys.modules))"],
                         check=True, capture_output=True, text=True, cwd=Path(__file__).resolve().parents[2])
    return set(out.stdout.split())


def test_import_esi_does_not_import_checks_validation_or_dictionaries() -> None:
    mods = _modules_after("import ecattool.esi")
    assert "ecattool.esi.model" in mods  # the probe works
    # the reader (and lxml) come with the first file read: the model alone (a live bus's identity) needs neither
    assert not {"ecattool.esi.checks", "ecattool.esi.validate", "ecattool.esi.dictionary", "ecattool.esi.reader",
                "lxml.etree"} & mods


def test_on_demand_names_still_work_after_the_submodule_is_imported() -> None:
    from ecattool import esi

    assert callable(esi.validate) and callable(esi.materialize) and callable(esi.check_structure)
    esi.materialize(load(corpus_path("esi", "etg_ETG2001_ModulesSlots_CiA402.xml")))
    assert callable(esi.validate)


def test_sii_build_path_does_not_import_comparison_or_esi_checks() -> None:
    mods = _modules_after("import ecattool.sii.builder, ecattool.esi")
    assert "ecattool.sii.builder" in mods
    assert not {"ecattool.sii.compare", "ecattool.esi.checks", "ecattool.esi.validate"} & mods


# -- Sm@OpOnly ------------------------------------------------------------------------------------------------
OP_ONLY = b"""<?xml version="1.0"?>
<EtherCATInfo><Vendor><Id>#x1234</Id><Name>V</Name></Vendor><Descriptions><Groups/><Devices>
<Device Physics="YY"><Type ProductCode="#x7" RevisionNo="1">OPO</Type><Name>OpOnly device</Name>
<Sm StartAddress="#x1000" ControlByte="#x26" Enable="1">MBoxOut</Sm>
<Sm StartAddress="#x1080" ControlByte="#x22" Enable="1">MBoxIn</Sm>
<Sm StartAddress="#x1100" ControlByte="#x64" Enable="1" DefaultSize="2" OpOnly="1">Outputs</Sm>
<Sm StartAddress="#x1400" ControlByte="#x20" Enable="1" DefaultSize="2" OpOnly="false">Inputs</Sm>
</Device></Devices></Descriptions></EtherCATInfo>"""


def test_op_only_is_read_and_written_as_syncm_enable_bit_3() -> None:
    from ecattool.findings import Severity
    from ecattool.sii import build, check_against, parse

    dev = select(load_bytes(OP_ONLY, "oponly.xml"))
    assert [sm.op_only for sm in dev.sync_managers] == [False, False, True, False]
    image = parse(build(dev).to_bytes())
    assert [sm.enable for sm in image.sync_managers] == [0x01, 0x01, 0x09, 0x01]
    assert check_against(dev, image) == []
    image.sync_managers[2].enable = 0x01  # a generator that ignores OpOnly: a warning, not an error
    findings = check_against(dev, image)
    assert [(f.rule, f.severity, f.data["field"]) for f in findings] == [("sii.esi.sm", Severity.WARNING, "sm[2].enable")]
    image.sync_managers[2].enable = 0x00  # disabled altogether: still an error
    assert [f.severity for f in check_against(dev, image)] == [Severity.ERROR]


def test_op_only_from_a_corpus_esi() -> None:
    dev = load_device(corpus_path("sii", "asix_AX58100_EVB_DIO.xml"))
    assert [sm.op_only for sm in dev.sync_managers if sm.kind == "Outputs"] == [True, True]
    assert not any(sm.op_only for sm in dev.sync_managers if sm.kind != "Outputs")


# -- the reader's parse options -------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["beckhoff_AX5xxx.xml", "weidmueller_UR20_FBC.xml", "inovance_SV660_EOE_1Axis_V9.12.xml"])
def test_dropping_blank_text_changes_nothing_in_the_model(name: str, monkeypatch: pytest.MonkeyPatch) -> None:
    from ecattool.esi import materialize, reader
    from ecattool.xmlsafe import parse_xml

    path = corpus_path("esi", name)
    fast = load(path)
    materialize(fast)
    monkeypatch.setattr(reader, "parse_xml", lambda data, source, **_: parse_xml(data, source))
    plain = load(path)
    materialize(plain)
    _same(fast.devices, plain.devices, name)
    _same(fast.modules, plain.modules, name)
    assert [str(w) for w in fast.warnings] == [str(w) for w in plain.warnings]


def test_the_fast_parse_keeps_the_protections() -> None:
    from ecattool.errors import XmlSecurityError
    from ecattool.xmlsafe import parse_xml

    for doc in (b'<!DOCTYPE a [<!ENTITY x "y">]><a>&x;</a>', b'<!DOCTYPE a SYSTEM "http://example.com/a.dtd"><a/>'):
        with pytest.raises(XmlSecurityError):
            parse_xml(doc, "t.xml", drop_blank_text=True)
    root = parse_xml(b"<a>\n  <b> </b>\n  <c>x</c>\n</a>", "t.xml", drop_blank_text=True).getroot()
    assert root.text is None and root[0].text == " " and root[1].text == "x" and root[1].sourceline == 3
