"""Parsing PDO mappings: entries, the whole-mapping CLI syntax, dict/YAML data with locations."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from ecattool.errors import InputError, Location
from ecattool.esi.model import Direction, PdoEntry
from ecattool.pdo import Mapping, default_mapping, entry_text, parse_entry
from tests.pdo.test_pdo_support import make_device

DEV = make_device()


@pytest.mark.parametrize(
    "text, expected",
    [
        ("0x6040:00/16", (0x6040, 0, 16)),
        ("6040:0/16", (0x6040, 0, 16)),
        ("#x6040:00/16", (0x6040, 0, 16)),
        ("6040h:00h/16", (0x6040, 0, 16)),
        ("6040h", (0x6040, 0, 16)),
        ("0x6040:00", (0x6040, 0, 16)),
        ("0x6040", (0x6040, 0, 16)),
        ("controlword", (0x6040, 0, 16)),
        ("Control word", (0x6040, 0, 16)),
        ("statusword/16", (0x6041, 0, 16)),
        ("Digital outputs/Physical outputs", (0x60FE, 1, 32)),
        ("digital outputs.bit mask/32", (0x60FE, 2, 32)),
        ("0x60400010", (0x6040, 0, 16)),
        ("0x60FE0220", (0x60FE, 2, 32)),
        ("gap/8", (0, 0, 8)),
        ("0/3", (0, 0, 3)),
        ("0x0000:00/16", (0, 0, 16)),
        ("0x5000:01/8", (0x5000, 1, 8)),  # unknown objects parse; the checker reports them (PDO004)
    ],
)
def test_parse_entry_forms(text: str, expected: tuple[int, int, int]) -> None:
    e = parse_entry(text, DEV)
    assert (e.index, e.subindex, e.bit_len) == expected


def test_parse_entry_integer_forms() -> None:
    assert parse_entry(0x60400010, DEV).mapping_value == 0x60400010
    assert (parse_entry(0x6064, DEV).index, parse_entry(0x6064, DEV).bit_len) == (0x6064, 32)


def test_parse_entry_names_come_from_dictionary() -> None:
    e = parse_entry("0x6040:00/16", DEV)
    assert e.name == "Controlword" and e.data_type == "UINT"


@pytest.mark.parametrize(
    "text, message",
    [
        ("nosuchobject", "no object named"),
        ("0x5000:01", "bit length is unknown"),
        ("gap", "a gap needs a length"),
        ("0x6040:00/300", "outside 1..255"),
        ("", "empty PDO entry"),
    ],
)
def test_parse_entry_errors_are_located(text: str, message: str) -> None:
    loc = Location("m.yaml", 7, 3)
    with pytest.raises(InputError) as exc:
        parse_entry(text, DEV, loc)
    assert message in str(exc.value)
    assert exc.value.location == loc


@pytest.mark.parametrize(
    "text, message",
    [
        # Synapticon's ESI has no 60F4h: the hint said /16 for a 32-bit object and did not say it is missing
        ("0x60F4:00", "no such object in the dictionary of Test Drive, so its bit length is unknown; "
                      "write it as 0x60F4:00/32"),
        ("0x607B:00", "write it as 0x607B:00/8"),     # the count of a standard ARRAY
        ("0x607B:01", "write it as 0x607B:01/32"),
        ("0x6060:00", "write it as 0x6060:00/8"),
        ("0x5000:01", "write it as 0x5000:01/16"),    # not a standard object: any length, the user knows it
    ],
)
def test_unknown_length_names_the_missing_object_and_the_standard_size(text: str, message: str) -> None:
    from ecattool.esi.model import Device, Identity
    from ecattool.od.model import ObjectDictionary

    bare = Device(Identity(1, 2, 3), "Test Drive", dictionary=ObjectDictionary())
    with pytest.raises(InputError, match=message.replace("(", r"\(").replace(")", r"\)")):
        parse_entry(text, bare)


def test_unknown_sub_index_of_a_known_object_is_named() -> None:
    with pytest.raises(InputError, match="no such sub-index in the dictionary"):
        parse_entry("0x6040:07", DEV)


def test_names_need_a_device() -> None:
    with pytest.raises(InputError, match="names need a device"):
        parse_entry("controlword")


@given(st.integers(1, 0xFFFF), st.integers(0, 0xFF), st.integers(1, 0xFF))
def test_entry_text_roundtrip(index: int, sub: int, bits: int) -> None:
    e = PdoEntry(index, sub, bits)
    back = parse_entry(entry_text(e))
    assert (back.index, back.subindex, back.bit_len) == (index, sub, bits)
    assert PdoEntry.from_mapping_value(e.mapping_value).mapping_value == e.mapping_value
    raw = parse_entry(f"0x{e.mapping_value:08X}")
    assert (raw.index, raw.subindex, raw.bit_len) == (index, sub, bits)


@given(st.integers(1, 0xFF))
def test_gap_roundtrip(bits: int) -> None:
    e = parse_entry(entry_text(PdoEntry(0, 0, bits)))
    assert e.is_gap and e.bit_len == bits


@given(st.text(max_size=30))
def test_parse_entry_never_crashes(text: str) -> None:
    try:
        e = parse_entry(text, DEV)
    except InputError:
        return
    assert 0 <= e.index <= 0xFFFF and 0 <= e.subindex <= 0xFF and 1 <= e.bit_len <= 255


def test_whole_mapping_syntax() -> None:
    m = Mapping.from_text(rx="0x1600=controlword,0x607A:00/32;0x1601", tx="0x1A00=statusword,0x6064:00/32", device=DEV)
    assert [p.index for p in m.rx] == [0x1600, 0x1601]
    assert m.rx[0].explicit and not m.rx[1].explicit
    assert [(e.index, e.bit_len) for e in m.rx[1].entries] == [(0x60FE, 32)]  # kept from the device
    assert m.given == {Direction.RX, Direction.TX}
    assert m.to_json()["tx"][0]["entries"] == ["0x6041:00/16", "0x6064:00/32"]


def test_entries_only_go_to_the_first_default_pdo() -> None:
    m = Mapping.from_text(rx="controlword,0x60FF:00/32", device=DEV)
    assert [p.index for p in m.rx] == [0x1600]
    assert [p.index for p in m.tx] == [0x1A00]  # tx not given: the device default
    assert m.given == {Direction.RX}


def test_repeated_options_and_empty_assignment() -> None:
    m = Mapping.from_text(rx=["0x1600=controlword", "0x1601=0x60FE:01/32"], tx="", device=DEV)
    assert [p.index for p in m.rx] == [0x1600, 0x1601]
    assert m.tx == [] and Direction.TX in m.given


def test_default_mapping_from_sm_attribute() -> None:
    m = default_mapping(DEV)
    assert [p.index for p in m.rx] == [0x1600] and [p.index for p in m.tx] == [0x1A00]
    assert not m.given


def test_default_mapping_from_dictionary_defaults() -> None:
    dev = make_device()
    for p in (*dev.rx_pdos, *dev.tx_pdos):
        p.sm = None
    m = default_mapping(dev)
    assert [p.index for p in m.rx] == [0x1600]
    assert [(e.index, e.subindex, e.bit_len) for e in m.tx[0].entries] == [(0x6041, 0, 16), (0x6064, 0, 32)]


def test_from_data_with_locations() -> None:
    data = {"rx": [{"index": "0x1600", "entries": ["controlword", "0x607A:00/32"]}, {"index": 0x1601}],
            "complete_access": True}
    locs = {("rx", 0): Location("p.yaml", 10, 5), ("rx", 0, "entries", 1): Location("p.yaml", 12, 9),
            ("rx", 1, "index"): Location("p.yaml", 13, 12)}
    m = Mapping.from_data(data, device=DEV, locations=locs, source="p.yaml")
    assert m.rx[0].entries[1].location == Location("p.yaml", 12, 9)
    assert m.rx[0].entries[0].location == Location("p.yaml", 10, 5)  # closest located parent
    assert m.rx[1].location == Location("p.yaml", 13, 12) and not m.rx[1].explicit
    assert [p.index for p in m.tx] == [0x1A00]


@pytest.mark.parametrize(
    "data, path, message",
    [
        ({"rx": [{"entries": ["controlword"]}]}, ("rx", 0), "needs an 'index'"),
        ({"rx": [{"index": "0x16zz"}]}, ("rx", 0, "index"), "not a valid PDO index"),
        ({"rx": [{"index": "0x1600", "entries": ["nothing here"]}]}, ("rx", 0, "entries", 0), "no object named"),
        ({"rx": {"index": 1}}, ("rx",), "must be a list"),
        ({"rxx": []}, ("rxx",), "unknown key"),
        ({"rx": [{"index": 0x16000}]}, ("rx", 0, "index"), "is not a PDO index"),
        ({"rx": [{"index": "0x1600", "entries": [1 << 32]}]}, ("rx", 0, "entries", 0), "is not a PDO entry"),
        ({"rx": [{"index": "0x1600", "entry": []}]}, ("rx", 0, "entry"), "unknown key"),
    ],
)
def test_from_data_errors_point_at_the_value(data: dict, path: tuple, message: str) -> None:
    loc = Location("p.yaml", 42, 7)
    with pytest.raises(InputError) as exc:
        Mapping.from_data(data, device=DEV, locations={path: loc})
    assert message in str(exc.value) and exc.value.location == loc


def test_from_yaml_file_with_line_numbers(tmp_path) -> None:
    from ecattool.yamlloc import load_yaml

    text = "rx:\n  - index: 0x1600\n    entries:\n      - controlword\n      - 6060:00/8\n"
    doc = load_yaml(text, "map.yaml")
    m = Mapping.from_data(doc.data, device=DEV, locations=doc.locations, source="map.yaml")
    assert m.rx[0].entries[1].location.line == 5
    assert (m.rx[0].entries[1].index, m.rx[0].entries[1].bit_len) == (0x6060, 8)


_ENTRY_TEXTS = ["controlword", "0x607A:00/32", "0x60FF:00/32", "0x6060:00/8", "gap/8", "0x60FE:01/32", "0x5000:01/16",
                "0x60400010", "statusword", "0x2000:00/1"]


@st.composite
def _mappings(draw: st.DrawFn) -> dict:
    out: dict = {}
    for d, pool in (("rx", [0x1600, 0x1601, 0x1605]), ("tx", [0x1A00, 0x1A01, 0x1A02])):
        if draw(st.booleans()):
            continue
        pdos = []
        for index in draw(st.lists(st.sampled_from(pool), max_size=3)):
            if draw(st.booleans()):
                pdos.append({"index": f"0x{index:04X}", "entries": draw(st.lists(st.sampled_from(_ENTRY_TEXTS),
                                                                                 max_size=6))})
            else:
                pdos.append({"index": index})
        out[d] = pdos
    return out


def _shape(m: Mapping) -> list:
    return [(d, [(p.index, p.explicit, [(e.index, e.subindex, e.bit_len) for e in p.entries]) for p in m.pdos(d)])
            for d in Direction]


@given(_mappings())
def test_data_and_text_forms_roundtrip(data: dict) -> None:
    m = Mapping.from_data(data, device=DEV)
    assert m.given == {Direction(k) for k in data}
    again = Mapping.from_data(m.to_data(), device=DEV)
    assert _shape(again) == _shape(m) and again.given == m.given
    text = {d: m.to_text(d) for d in m.given}
    back = Mapping.from_text(rx=text.get(Direction.RX), tx=text.get(Direction.TX), device=DEV)
    assert _shape(back) == _shape(m)


@given(st.text(max_size=40))
def test_whole_mapping_syntax_never_crashes(text: str) -> None:
    try:
        m = Mapping.from_text(rx=text, device=DEV)
    except InputError:
        return
    assert all(0 < p.index <= 0xFFFF for p in m.rx)


def test_a_mapping_file_is_read_by_the_library_with_located_errors(tmp_path) -> None:
    """``map … --mapping FILE`` reads through ``Mapping.from_file``: rx/tx at the top or under a project drive's
    ``pdo:``; a file with neither is an error at its line (it would silently keep the device's default)."""
    from ecattool import profiles

    device = profiles.load("technosoft-ipos")
    top, nested, empty = tmp_path / "top.yaml", tmp_path / "nested.yaml", tmp_path / "empty.yaml"
    top.write_text("rx:\n  - index: 0x1600\n    entries: [controlword, 0x607A:00/32]\n")
    nested.write_text("name: x\npdo:\n  rx:\n    - index: 0x1600\n      entries: [controlword, 0x607A:00/32]\n")
    empty.write_text("name: x\nother: 1\n")
    a, b = Mapping.from_file(str(top), device), Mapping.from_file(str(nested), device)
    assert [e.index for e in a.rx[0].entries] == [e.index for e in b.rx[0].entries] == [0x6040, 0x607A]
    with pytest.raises(InputError) as bad:
        Mapping.from_file(str(empty), device)
    assert "needs rx: and/or tx:" in bad.value.message and bad.value.location.file == str(empty)
    nested.write_text("pdo:\n  rx:\n    - index: 0x1600\n      entries: [no_such_object]\n")
    with pytest.raises(InputError) as bad:
        Mapping.from_file(str(nested), device)
    assert bad.value.location.line == 4, bad.value
