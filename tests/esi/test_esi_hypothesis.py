"""Mutated real ESI files (truncated, junk attributes, wrong types, removed elements) either load or give an
ecattool error with a location — never another exception. Also HexDecValue/boolean parsers round-trip."""

from __future__ import annotations

import copy

import pytest
from hypothesis import given
from hypothesis import strategies as st
from lxml import etree

from ecattool.errors import EcatToolError, InputError
from ecattool.esi import check_structure, load_bytes, materialize, select
from ecattool.esi.values import Context
from tests.conftest import corpus_path

FILES = ["synapticon_Somanet_CiA402-single.xml", "etg_ETG2001_ModulesSlots_CiA402.xml"]
ATTRS = ["Fixed", "Mandatory", "Sm", "Su", "ProductCode", "RevisionNo", "Default", "DependOnSlot", "StartAddress",
         "DefaultSize", "MaxSize", "ControlByte", "Enable", "ModuleIdent", "LcId", "WriteRestrictions", "CompleteAccess"]
JUNK = st.sampled_from(["", " ", "-1", "#x", "#xG1", "0x", "0x10", "abc", "1e9", "99999999999999999999", "true", "2",
                        "#xFFFFFFFF", "\u00e9", "#x-1", "1.5", "-"])


@pytest.fixture(scope="module", params=FILES)
def doc(request):
    data = corpus_path("esi", request.param).read_bytes()
    tree = etree.fromstring(data, etree.XMLParser(remove_comments=True, resolve_entities=False))
    return data, tree


def _exercise(data: bytes) -> None:
    try:
        esi = load_bytes(data, "mutated.xml")
        materialize(esi)
        check_structure(esi)
        if esi.devices:
            select(esi, None, "newest") if len(esi.devices) == 1 else select(esi, "0")
    except EcatToolError as exc:
        assert exc.location is not None and exc.location.file == "mutated.xml", str(exc)


def _serialize(root) -> bytes:
    return etree.tostring(root, xml_declaration=True, encoding="UTF-8")


@given(st.data())
def test_truncated(doc, data):
    raw, _ = doc
    cut = data.draw(st.integers(0, len(raw)))
    _exercise(raw[:cut])


@given(st.data())
def test_junk_attributes(doc, data):
    _, tree = doc
    root = copy.deepcopy(tree)
    elements = [e for e in root.iter() if isinstance(e.tag, str)]
    for _ in range(data.draw(st.integers(1, 4))):
        el = elements[data.draw(st.integers(0, len(elements) - 1))]
        el.set(data.draw(st.sampled_from(ATTRS)), data.draw(JUNK))
    _exercise(_serialize(root))


@given(st.data())
def test_wrong_types_in_text(doc, data):
    _, tree = doc
    root = copy.deepcopy(tree)
    leaves = [e for e in root.iter() if isinstance(e.tag, str) and len(e) == 0]
    for _ in range(data.draw(st.integers(1, 4))):
        leaves[data.draw(st.integers(0, len(leaves) - 1))].text = data.draw(JUNK)
    _exercise(_serialize(root))


@given(st.data())
def test_removed_elements(doc, data):
    _, tree = doc
    root = copy.deepcopy(tree)
    for _ in range(data.draw(st.integers(1, 4))):
        elements = [e for e in root.iter() if isinstance(e.tag, str) and e.getparent() is not None]
        if not elements:
            break
        el = elements[data.draw(st.integers(0, len(elements) - 1))]
        el.getparent().remove(el)
    _exercise(_serialize(root))


@given(st.integers(min_value=-(2**63), max_value=2**64))
def test_hexdec_round_trip(n):
    ctx = Context("n.xml")
    assert ctx.number(str(n), None, "n") == n
    if n >= 0:
        assert ctx.number(f"#x{n:X}", None, "n") == n
        assert ctx.number(f"0x{n:x}", None, "n") == n and ctx.warnings[-1].rule == "esi-number-0x"


@given(st.text(max_size=12))
def test_number_parser_never_crashes(text):
    try:
        Context("n.xml").number(text, None, "n")
    except InputError as exc:
        assert exc.location.file == "n.xml"


@given(st.binary(max_size=16))
def test_hexbin_round_trip(raw):
    ctx = Context("h.xml")
    assert ctx.hexbin(raw.hex(), None, "d") == raw
    assert ctx.hexbin(raw.hex().upper(), None, "d") == raw


@given(st.one_of(st.text(max_size=10), st.integers(0, 2**40).map(lambda n: f"#x{n:x}"), st.integers(0, 2**40).map(str)))
def test_fast_number_path_agrees_with_the_checked_parser(text):
    from ecattool.esi.reader import _fast_number

    fast = _fast_number(text)
    if fast is not None:
        assert Context("f.xml").number(text, None, "n") == fast
