"""Issue 23 item 2 for the startup readers: whatever bytes a user gives ``startup import``/``convert``, the
result is slave configurations or one located :class:`EcatToolError`, never a raw exception or a hang.

Seeds are the real third-party configurations in ../shared/corpus/configs and every sample project exported in
each readable format; hypothesis mutates them (bytes: control characters, line breaks, brackets, huge numbers,
cut and copied spans; structure: a list where a mapping belongs, deep nesting, numbers beyond 64 bits, inf) and
every result is exported again in every format (``--lossy``), as ``convert`` would. Inputs
stay small (a seed plus a few edits), so each example is bounded work; no timing is asserted.
"""

from __future__ import annotations

import json
import re

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from ecattool.errors import EcatToolError
from ecattool.startup import FORMATS, export, import_bytes
from tests.conftest import ROOT, corpus_path

READERS = sorted(n for n, f in FORMATS.items() if f.can_import)
WRITERS = sorted(n for n, f in FORMATS.items() if f.can_export)
_TOKENS = [b"\x00", b"\x01", b"\x1b", b"\x7f", b"\n", b"\r", b'"', b",", b"'", b"[", b"]", b"{", b"}", b"<", b">",
           b"&", b"\t", b"- ", b": ", b"#", b"$(", b"${X}", b"-1", b"1e999", b"0x", b"9" * 4400, b"0x" + b"F" * 40,
           b"100000000", b"4294967296", b"18446744073709551616", b"[" * 3000, b'{"a":' * 3000, b"\xff", b"\xc3("]


def _seeds() -> dict[str, list[tuple[str, bytes]]]:
    from ecattool.project.export import slave_configs
    from ecattool.startup import detect_format

    out: dict[str, list[tuple[str, bytes]]] = {n: [] for n in READERS}
    for p in sorted(corpus_path("configs").iterdir()):
        data = p.read_bytes()
        try:
            out[detect_format(data, p.name)].append((p.name, data))
        except EcatToolError:
            pass  # the hw_device_mgr file: refused by design (tested in test_startup_import)
    for project in sorted((ROOT / "samples").glob("*/project.yaml")):
        configs = slave_configs(project)
        for fmt in READERS:
            if FORMATS[fmt].can_export:
                try:
                    text = export(configs if fmt not in ("twincat", "ros2") else configs[:1], fmt)
                except EcatToolError:
                    continue
                out[fmt].append((f"{project.parent.name}.{fmt}", text.encode()))
    return out


SEEDS = _seeds()


@st.composite
def _byte_mutation(draw, data: bytes) -> bytes:
    d = bytearray(data)
    for _ in range(draw(st.integers(1, 4))):
        i = draw(st.integers(0, max(0, len(d) - 1)))
        op = draw(st.integers(0, 4))
        if op == 0 and d:
            d[i] = draw(st.integers(0, 255))
        elif op == 1:
            d[i:i] = draw(st.sampled_from(_TOKENS))
        elif op == 2:
            del d[i:i + draw(st.integers(1, 60))]
        elif op == 3:
            j = draw(st.integers(0, max(0, len(d) - 1)))
            d[i:i] = d[j:j + draw(st.integers(1, 120))]
        else:
            numbers = list(re.finditer(rb"\d+", bytes(d)))
            if numbers:
                m = draw(st.sampled_from(numbers))
                d[m.start():m.end()] = draw(st.sampled_from([b"9" * 4400, b"9" * 30, b"100000000", b"4294967296"]))
    return bytes(d)


_ODD = [[], [1], {}, {"a": [1]}, "x", None, 2 ** 70, -(2 ** 70), float("inf"), 1e300, True, "\x01", [[[[[]]]]]]


@st.composite
def _tree_mutation(draw, doc: object) -> object:
    """Replace one node of a parsed JSON/YAML document with a value of another shape."""
    paths: list[tuple[object, object]] = []

    def walk(node: object) -> None:
        if isinstance(node, dict):
            for k, v in node.items():
                paths.append((node, k))
                walk(v)
        elif isinstance(node, list):
            for k, v in enumerate(node):
                paths.append((node, k))
                walk(v)

    walk(doc)
    for _ in range(draw(st.integers(1, 3))):
        if not paths:
            break
        parent, key = draw(st.sampled_from(paths))
        parent[key] = draw(st.sampled_from(_ODD))  # type: ignore[index]
    return doc


def _check(data: bytes, name: str, fmt: str | None) -> None:
    try:
        configs = import_bytes(data, name, fmt)
    except EcatToolError as exc:
        assert "\n" not in str(exc).strip(), f"a two-line error: {exc}"
        return
    for out in WRITERS:
        try:
            export(configs if out not in ("twincat", "ros2") else configs[:1], out, lossy=True)
        except EcatToolError:
            pass


SETTINGS = settings(max_examples=25, deadline=None, suppress_health_check=list(HealthCheck))


@pytest.mark.parametrize("fmt", READERS)
@SETTINGS
@given(data=st.data())
def test_mutated_bytes_give_a_result_or_one_located_error(fmt, data):
    assert SEEDS[fmt], f"no seed for {fmt}"
    name, seed = data.draw(st.sampled_from(SEEDS[fmt]))
    _check(data.draw(_byte_mutation(seed)), name, data.draw(st.sampled_from([None, fmt])))


@pytest.mark.parametrize("fmt", ["json", "ros2"])
@SETTINGS
@given(data=st.data())
def test_mutated_structure_gives_a_result_or_one_located_error(fmt, data):
    name, seed = data.draw(st.sampled_from(SEEDS[fmt]))
    doc = data.draw(_tree_mutation(json.loads(seed) if fmt == "json" else yaml.safe_load(seed)))
    text = json.dumps(doc, allow_nan=True) if fmt == "json" else yaml.safe_dump(doc)
    _check(text.encode(), name, fmt)


# --- each crash the mutation fuzzer found, at its cause ------------------------------------------------------

_HDR = "slave,position,transition,index,subindex,data,complete_access,timeout_ms,type,value,comment\n"
_JSON = '{"format": "ecattool-startup", "version": 1, "slaves": %s}'


@pytest.mark.parametrize("name, data, message", [
    ("nl.csv", _HDR + 'a,0,PS,0x6060,0x00,08,0,0,USINT,8,x\rb\n', "nl.csv:2: not CSV"),
    ("deep.json", _JSON % ("[" * 5000 + "]" * 5000), "deep.json:1: JSON nested deeper"),
    ("nest.json", _JSON % ("[" * 40 + "]" * 40), "nesting deeper than 32 levels"),
    ("digits.json", '{"format": "ecattool-startup",\n "version": ' + "9" * 4400 + "}", "digits.json:2: a number of more"),
    ("wide.json", _JSON % '[{"name": "a", "position": 0, "identity": {"vendor_id": %d, "product_code": 1}, '
     '"commands": []}]' % (1 << 80), "number of 81 bits"),
    ("inf.json", _JSON % '[{"name": "a", "dc": {"cycle_ns": 1e999}, "commands": []}]', "must be an integer"),
    ("hex.yaml", "vendor_id: 0x" + "F" * 5000 + "\nproduct_id: 2\n", "hex.yaml:1:12: number of 20000 bits"),
    ("digits.yaml", "vendor_id: 1\nproduct_id: " + "9" * 4400 + "\n", "digits.yaml:2:13: a number of more"),
    ("deep.yaml", "vendor_id: 1\nproduct_id: 2\nsdo: " + "[" * 3000 + "]" * 3000 + "\n", "deep.yaml"),
    ("sm.yaml", "vendor_id: 1\nproduct_id: 2\nsm: [[1]]\n", "sm.yaml:3:6: an sm entry is a mapping"),
    ("type.json", _JSON % '[{"name": "a", "commands": [{"transition": "PS", "index": 1, "subindex": 0, "data": "01", '
     '"type": [1]}]}]', "type must be text, got list"),
    ("sm2.yaml", "vendor_id: 1\nproduct_id: 2\nsm: {a: 1}\n", "sm2.yaml:3:5: sm must be a list"),
    ("gap.cmd", 'ecmcConfigOrDie "Cfg.EcAddEntryComplete(0,0x1,0x2,1,2,0x1600,0x0,0x0,100000000,Gap)"\n',
     "gap.cmd:1: PDO 0x1600: entry bit length 100000000 is out of range (0..255)"),
    ("bomb.cmd", "".join(f'epicsEnvSet("A{i + 1}" "$(A{i})$(A{i})")\n' for i in range(60)),
     "bomb.cmd:14: macros expand to more than 65536 characters"),
    ("big.cmd", 'ecmcConfigOrDie "Cfg.EcAddSdo(0,0x6060,0,0x' + "F" * 5000 + ',4)"\n',
     "big.cmd:1: value of 20000 bits does not fit in 4 byte(s)"),
    ("big.txt", "<PS>,CoE,0x6060:00,0x" + "00" * 70000 + " (0),x\n", "big.txt:1: 0x6060:00: 70000 data bytes"),
])
def test_each_found_crash_is_one_located_error(name, data, message):
    with pytest.raises(EcatToolError) as err:
        import_bytes(data.encode(), name)
    text = str(err.value)
    assert "\n" not in text and text.startswith(name)
    if message:
        assert message in text


def test_a_huge_count_in_a_mapping_object_is_replayed_boundedly():
    """The fuzzer: 1600h:00 := 0x99…99 (a long write) made the contradiction check build a list of 2^32 entries."""
    slave = ('[{"name": "a", "commands": [{"transition": "PS", "index": 5632, "subindex": 0, "data": "' + "ff" * 40 +
             '"}], "rx_pdos": [{"index": 5632, "entries": [{"index": 24640, "bit_len": 16}]}]}]')
    (cfg,) = import_bytes((_JSON % slave).encode(), "big.json")
    assert [n.rule for n in cfg.notes] == ["startup.pdo.conflict"]  # 255 zero entries, not 2^320


def test_an_xml_syntax_error_is_one_line_without_file_text():
    with pytest.raises(EcatToolError) as err:
        import_bytes(b"<EtherCATConfig><Config><![CDATA[abc\nmore file text", "x.xml", "eni")
    assert str(err.value) == "x.xml:2:15: not well-formed XML: CData section not finished"


def test_csv_value_that_is_no_scalar_stays_text():
    (cfg,) = import_bytes((_HDR + "a,0,PS,0x6060,0x00,08,0,0,USINT,[[1]],x\n").encode(), "v.csv")
    assert cfg.commands[0].value == "[[1]]"
    (deep,) = import_bytes((_HDR + "a,0,PS,0x6060,0x00,08,0,0,USINT," + "[" * 3000 + ",x\n").encode(), "d.csv")
    assert deep.commands[0].value == "[" * 3000
    export([cfg, deep], "json")


@pytest.mark.parametrize("fmt", ["twincat", "csv", "ecmc"])
def test_a_control_character_in_a_comment_gives_an_eni_that_shows_it(fmt):
    from lxml import etree

    text = {"twincat": "<PS>,CoE,0x6060:00,0x08 (8),a\x01b\x00c\n",
            "csv": _HDR + "a,0,PS,0x6060,0x00,08,0,0,USINT,8,a\x01b\x00c\n",
            "ecmc": '#a\x01b\x00c\necmcConfigOrDie "Cfg.EcAddSdo(0,0x6060,0,8,1)"\n'}[fmt]
    (cfg,) = import_bytes(text.encode(), "x", fmt)
    root = etree.fromstring(export(cfg, "eni", lossy=True).encode())  # lossy: the source names no identity
    assert root.findtext(".//InitCmd/Comment") == "a\\x01b\\x00c"


def test_an_lcec_initcmds_name_the_file_system_refuses_is_reported_as_missing(tmp_path):
    conf = tmp_path / "ethercat-conf.xml"
    conf.write_text('<masters><master idx="0" appTimePeriod="1000000"><slave idx="0" type="generic" vid="2" '
                    f'pid="3"><initCmds filename="{"x" * 5000}.xml"/><dcConf assignActivate="300" sync0Cycle="1000000"/>'
                    '</slave></master></masters>')
    from ecattool.startup import import_file

    (cfg,) = import_file(conf)
    assert any("not found beside the configuration" in n.message for n in cfg.notes)


def test_long_data_carries_no_number_past_pythons_digit_limit():
    """An lcec sdoDataRaw of 2 KiB had its bytes as an integer value: JSON and CSV could not write its decimal."""
    conf = ('<masters><master idx="0"><slave idx="0" type="generic" vid="2" pid="3"><sdoConfig idx="8000" '
            f'subIdx="1"><sdoDataRaw data="{"ff" * 2048}"/></sdoConfig></slave></master></masters>')
    (cfg,) = import_bytes(conf.encode(), "c.xml")
    assert cfg.commands[0].value is None and len(cfg.commands[0].data) == 2048
    for fmt in WRITERS:
        export(cfg, fmt, lossy=True) if fmt not in ("igh", "ros2") else None
    from ecattool.startup.formats.jsonfmt import json_value

    assert json_value(1 << 20000).startswith("0x1000")
