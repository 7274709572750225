"""ecattool.record: the plain slotted base classes of the model (what @dataclass gave, without its import cost)."""

from __future__ import annotations

import copy
import pickle
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from ecattool.errors import Location
from ecattool.esi import load, materialize
from ecattool.esi.model import Device, Identity, PdoEntry
from ecattool.findings import Finding, Severity
from ecattool.od.model import ObjectDictionary
from ecattool.record import FrozenRecord, FrozenRecordError, Record, set_field
from ecattool.sii.model import SiiHeader, SiiImage
from ecattool.xmlsafe import parse_xml
from tests.conftest import corpus_path


class Point(Record):
    __slots__ = ("x", "y")
    x: int
    y: list[int]

    def __init__(self, x: int, y: list[int] | None = None) -> None:
        self.x = x
        self.y = [] if y is None else y


class OtherPoint(Record):  # the same fields, another type
    __slots__ = ("x", "y")

    def __init__(self, x: int, y: list[int] | None = None) -> None:
        self.x = x
        self.y = [] if y is None else y


class SubPoint(Point):
    __slots__ = ("z",)

    def __init__(self, x: int, y: list[int] | None = None, z: int = 0) -> None:
        super().__init__(x, y)
        self.z = z


class Pair(FrozenRecord):
    __slots__ = ("a", "b")
    a: Any
    b: Any

    def __init__(self, a: Any, b: Any = None) -> None:
        set_field(self, "a", a)
        set_field(self, "b", b)


def test_fields_follow_slots_and_inheritance() -> None:
    assert Point._fields == ("x", "y")
    assert SubPoint._fields == ("x", "y", "z")
    assert Pair._fields == ("a", "b")
    assert Location._fields == ("file", "line", "column")


def test_equality_needs_the_same_type_and_equal_fields() -> None:
    assert Point(1, [2]) == Point(1, [2])
    assert Point(1, [2]) != Point(1, [3])
    assert Point(1) != OtherPoint(1)  # same fields, another class: like dataclasses, never equal
    assert Point(1) != SubPoint(1)  # a subclass is another type too
    assert SubPoint(1, z=1) != SubPoint(1, z=2)
    assert Point(1) != (1, [])
    assert Point(1).__eq__((1, [])) is NotImplemented


def test_uncompared_fields_are_left_out_of_equality() -> None:
    assert SiiImage(source="a.bin") == SiiImage(source="b.bin")
    assert SiiImage(tail=b"\xff") != SiiImage(tail=b"")


def test_mutable_defaults_are_created_per_instance() -> None:
    a, b = Point(1), Point(1)
    a.y.append(5)
    assert b.y == []
    assert Device(Identity(1, 2), "A").rx_pdos is not Device(Identity(1, 2), "A").rx_pdos


def test_repr_names_every_field_in_order() -> None:
    assert repr(Point(1, [2])) == "Point(x=1, y=[2])"
    assert repr(Location("f.xml", 3)) == "Location(file='f.xml', line=3, column=None)"
    assert repr(PdoEntry(0x6040, 0, 16)) == (
        "PdoEntry(index=24640, subindex=0, bit_len=16, name='', data_type='', location=None, depend_on_slot=False)")


def test_as_dict_converts_nested_records() -> None:
    f = Finding("r", Severity.ERROR, "m", Location("f", 1), {"k": [Location("g")]})
    assert f.as_dict() == {"rule": "r", "severity": Severity.ERROR, "message": "m",
                           "location": {"file": "f", "line": 1, "column": None},
                           "data": {"k": [{"file": "g", "line": None, "column": None}]}}


def test_mutable_records_are_unhashable_frozen_ones_hash_by_value() -> None:
    with pytest.raises(TypeError):
        hash(Point(1))
    assert hash(Location("f", 1)) == hash(Location("f", 1))
    assert len({Location("f", 1), Location("f", 1), Location("f", 2)}) == 2
    assert hash(Identity(2, 3, 4)) == hash(Identity(2, 3, 4))
    with pytest.raises(TypeError):  # a frozen record holding a dict is no more hashable than its dataclass was
        hash(Finding("r", Severity.INFO, "m", data={"a": 1}))


def test_frozen_records_refuse_assignment_and_deletion() -> None:
    loc = Location("f", 1)
    with pytest.raises(FrozenRecordError):
        loc.line = 2
    with pytest.raises(AttributeError):  # FrozenRecordError is an AttributeError, like FrozenInstanceError
        del loc.file
    with pytest.raises(FrozenRecordError):
        loc.other = 1  # type: ignore[attr-defined]
    assert loc == Location("f", 1)


@pytest.mark.parametrize("value", [Location("f.xml", 3, 7), Pair(Location("a"), {"k": [1, 2]}),
                                   Finding("esi-x", Severity.WARNING, "msg", Location("f", 2), {"n": 1})])
def test_frozen_records_pickle_and_copy(value: FrozenRecord) -> None:
    for back in (pickle.loads(pickle.dumps(value, protocol=pickle.HIGHEST_PROTOCOL)), pickle.loads(pickle.dumps(value, 2)),
                 copy.deepcopy(value), copy.copy(value)):
        assert type(back) is type(value) and back == value
    deep = copy.deepcopy(Pair([1], {"k": [2]}))
    assert deep == Pair([1], {"k": [2]})


def test_frozen_state_is_the_field_values_in_order() -> None:
    # what frozen dataclasses pickled (a list of the values) still loads, e.g. from an older cache entry
    loc = Location.__new__(Location)
    loc.__setstate__(["f.xml", 3, None])
    assert loc == Location("f.xml", 3) and Location("f.xml", 3).__getstate__() == ("f.xml", 3, None)


def test_mutable_records_pickle_and_copy() -> None:
    p = SubPoint(1, [2, 3], z=4)
    for back in (pickle.loads(pickle.dumps(p)), copy.deepcopy(p)):
        assert back == p and back.y is not p.y
    h = SiiHeader(vendor_id=2, reserved_10=bytes(range(8)))
    assert pickle.loads(pickle.dumps(h)) == h == copy.deepcopy(h)


def _same_device(a: Device, b: Device) -> None:
    """Every field equal; dictionaries (no value equality of their own) compared object by object."""
    assert type(a) is type(b)
    for name in Device._fields:
        x, y = getattr(a, name), getattr(b, name)
        if isinstance(x, ObjectDictionary):
            assert x.indices() == y.indices() and all(x.get(i) == y.get(i) for i in x.indices()), name
        elif name == "modules":
            assert len(x) == len(y)
            for mx, my in zip(x, y):
                for n in mx._fields:
                    if n != "dictionary":
                        assert getattr(mx, n) == getattr(my, n), f"modules.{n}"
                assert mx.dictionary.indices() == my.dictionary.indices()
        else:
            assert x == y, name


@pytest.mark.parametrize("name", ["etg_ETG2001_ModulesSlots_CiA402.xml", "elmo_Elmo_ECAT_00010420_V11.xml"])
def test_a_complete_corpus_device_pickles_and_deep_copies(name: str) -> None:
    esi = load(corpus_path("esi", name))
    assert materialize(esi) > 0
    dev = esi.devices[0]
    owner = dev if dev.rx_pdos else dev.modules[0]  # the ETG file's PDOs are in its modules
    assert len(dev.dictionary) > 0 and owner.rx_pdos[0].entries
    for back in (pickle.loads(pickle.dumps(dev, protocol=pickle.HIGHEST_PROTOCOL)), copy.deepcopy(dev)):
        _same_device(back, dev)
        back_owner = back if dev.rx_pdos else back.modules[0]
        assert back_owner.rx_pdos[0] is not owner.rx_pdos[0] and back_owner.rx_pdos[0] == owner.rx_pdos[0]
        assert back_owner.rx_pdos[0].entries[0].location == owner.rx_pdos[0].entries[0].location


def test_esi_file_devices_is_a_field() -> None:
    esi = load(corpus_path("esi", "etg_ETG2001_ModulesSlots_CiA402.xml"))
    assert "devices" in type(esi)._fields and "_devices" not in type(esi)._fields
    back = pickle.loads(pickle.dumps(esi))
    assert [d.type_name for d in back.devices] == [d.type_name for d in esi.devices]
    assert "devices=[Device(" in repr(esi)


def test_the_esi_and_sii_paths_do_not_import_dataclasses() -> None:
    # creating ~40 slotted dataclasses cost ~30 ms of every command (docs/performance.md); this guards the gain
    code = ("import sys\nimport ecattool.esi, ecattool.sii, ecattool.sii.builder\n"
            f"esi = ecattool.esi.load({str(corpus_path('esi', 'etg_ETG2001_ModulesSlots_CiA402.xml'))!r})\n"
            "ecattool.esi.materialize(esi)\n"
            "ecattool.sii.builder.build(esi.devices[0])\n"
            "print('ecattool.esi.reader' in sys.modules, 'dataclasses' in sys.modules)\n")
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True,
                         cwd=Path(__file__).resolve().parent.parent)
    assert out.stdout.split() == ["True", "False"]


class One(Record):
    __slots__ = ("v",)

    def __init__(self, v: Any) -> None:
        self.v = v


def test_records_compare_field_tuples_like_dataclasses() -> None:
    nan = float("nan")
    assert One(nan) == One(nan)  # the same object in both: tuples compare by identity first, as dataclasses did
    assert One(1) != One(2) and One(1) == One(1)
    assert Pair(nan, 1) == Pair(nan, 1)


def test_pdo_and_entry_locations_kept_as_lines_read_as_locations() -> None:
    # the reader gives PDOs and PDO entries their line only (esi.model._LineLocated); read, compared, printed,
    # pickled and assigned, location behaves as a plain Location field
    path = corpus_path("esi", "elmo_Elmo_ECAT_00010420_V11.xml")
    esi = load(path)
    pdo = esi.devices[0].rx_pdos[0]
    entry = pdo.entries[0]
    unread = pickle.loads(pickle.dumps(pdo))  # pickled before any location was read
    assert isinstance(unread.entries[0]._location, int)
    xml_entry = next(el for el in parse_xml(path.read_bytes(), str(path)).getroot().iter("RxPdo")).find("Entry")
    eager = PdoEntry(entry.index, entry.subindex, entry.bit_len, entry.name, entry.data_type,
                     Location(str(path), xml_entry.sourceline))
    assert unread.entries[0] == entry == eager and repr(entry) == repr(eager)
    assert type(entry.location) is Location and entry.location is entry.location
    assert entry.location == Location(str(path), xml_entry.sourceline) and unread.location == pdo.location
    assert pdo.location is not None and pdo.location.line is not None and pdo.location.line < xml_entry.sourceline
    entry.location = None
    assert entry.location is None and entry != eager
    entry.location = eager.location
    assert entry == eager and copy.copy(entry) == eager
