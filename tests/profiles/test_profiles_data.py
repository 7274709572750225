"""The generated data files against the reference CSVs, the build script's parsers, and the public API."""

from __future__ import annotations

import csv
import json
import re
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from ecattool import profiles
from ecattool.errors import SelectionError
from ecattool.profiles import _build_data as build
from ecattool.profiles._common import load_data
from tests.conftest import reference_path

DATA = Path(build.__file__).resolve().parent / "data"


def reference(*parts: str) -> Path:
    return reference_path(*parts)


def csv_subs(family: str) -> tuple[int, dict[int, set[int]]]:
    rows = list(csv.DictReader(reference(family, "objects.csv").open(encoding="utf-8")))
    out: dict[int, set[int]] = {}
    for r in rows:
        if not r["index"].startswith("0x") or "+" in r["index"] or not r["subindex"].strip():
            continue
        m = re.fullmatch(r"(\d+)-(\d+)", r["subindex"].strip())
        subs = set(range(int(m.group(1)), int(m.group(2)) + 1)) if m else {int(r["subindex"])}
        out.setdefault(int(r["index"], 16), set()).update(subs)
    return len(rows), out


def json_subs(family_file: str) -> dict[int, set[int]]:
    return {o["index"]: {e["sub"] for e in o["entries"]} for o in load_data(family_file)["objects"]}


@pytest.mark.parametrize("name,family", [("technosoft", "technosoft"), ("hdt", "hdt"), ("controltechniques", "controltechniques")])
def test_data_files_are_what_the_build_script_makes(name, family):
    fn = {"technosoft": build.build_technosoft, "hdt": build.build_hdt, "controltechniques": build.build_controltechniques}[name]
    fresh = json.loads(json.dumps(fn(reference_path())))
    assert fresh == json.loads((DATA / f"{name}.json").read_text(encoding="utf-8")), \
        "data file out of date: run python -m ecattool.profiles._build_data"


def test_technosoft_counts_match_csv():
    rows, subs = csv_subs("technosoft")
    data = load_data("technosoft")
    assert data["csv_rows"] == rows == 291
    got = json_subs("technosoft")
    assert set(got) == set(subs) and len(got) == 188
    for index, s in subs.items():
        expected = s | (set(range(9)) if 0x1600 <= index <= 0x1A03 and (index & 0xFF) < 4 else set())
        assert got[index] == expected, hex(index)
    # every object appears in at least one firmware's dictionary, and gates split the factor sets
    union = set()
    for rev in ("F515K", "F515I", "FA00G", "FA00C"):
        union |= set(profiles.load("technosoft", revision=rev).dictionary.indices())
    assert union == set(subs)


def test_hdt_counts_match_csv():
    rows, subs = csv_subs("hdt")
    assert load_data("hdt")["csv_rows"] == rows == 516
    got = json_subs("hdt")
    assert set(got) == set(subs)
    data = {o["index"]: o for o in load_data("hdt")["objects"]}
    for index, s in subs.items():
        expected = set(s)
        if index == 0x1010:
            expected.discard(4)  # ambiguity 1: sub0 = 3 with three named sub-indices
        if data[index]["object_code"] != "VAR":
            expected.add(0)  # decision Profiles-1: sub-index 0 for every ARRAY/RECORD
        assert got[index] == expected, hex(index)
    ntt = profiles.load("ntt").dictionary
    assert set(ntt.indices()) == set(subs)


def test_controltechniques_counts_match_csv():
    rows, subs = csv_subs("controltechniques")
    assert load_data("controltechniques")["csv_rows"] == rows == 141
    got = json_subs("controltechniques")
    for index, s in subs.items():
        if index in (0x2012, 0x2014, 0x203D):
            assert s <= got[index]  # parameter examples, part of the parameter menus
            continue
        if index in (0x1615, 0x1A15):
            s = set(range(6))  # CF = 5 (decision CT-3)
        if index in (0x1C12, 0x1C13):
            s = {0, 1, 2}  # at most two PDOs assigned (decision CT-3)
        if 0x1600 <= index <= 0x1BFF:
            s = set(range(6))
        assert got[index] == s, hex(index)
    listed_only = {0x605D, 0x6065, 0x6067}
    menus = {i for i in got if 0x2000 <= i <= 0x2063}
    assert set(got) == set(subs) | listed_only | menus
    params = list(csv.DictReader(reference("controltechniques", "parameters.csv").open(encoding="utf-8")))
    assert load_data("controltechniques")["parameter_rows"] == len(params)
    od = profiles.load("controltechniques").dictionary
    for r in params:
        menu, _, par = r["menu.param"].partition(".")
        if int(par) == 0:
            continue
        for m in ((15, 60) if menu == "MM" else (int(menu),)):
            assert od.entry(0x2000 + m, int(par)) is not None, r["menu.param"]


# --- build-script parsers ----------------------------------------------------------------------------------

@given(st.integers(min_value=0, max_value=2**32 - 1))
def test_parse_number_hex_forms(n):
    assert build.parse_number(f"0x{n:X}") == n
    assert build.parse_number(f"{n:X}h") == n
    assert build.parse_number(str(n)) == n
    assert build.parse_default(f"0x{n:08X} (comment)") == n


@given(st.integers(min_value=-(2**31), max_value=2**31 - 1), st.integers(min_value=0, max_value=2**31 - 1))
def test_parse_range_forms(lo, span):
    hi = lo + span
    for sep in (" ... ", "..", " to "):
        assert build.parse_range(f"{lo}{sep}{hi}") == (lo, hi)


@given(st.text(max_size=30))
def test_parsers_never_crash(text):
    build.parse_number(text)
    build.parse_default(text)
    build.parse_range(text)


def test_parse_number_power_expressions():
    assert build.parse_number("2^31-1") == 2**31 - 1
    assert build.parse_number("-2^31") == -(2**31)
    assert build.parse_range("0 ... 2^32-1") == (0, 2**32 - 1)
    assert build.parse_range("±7FFFFFFFh") == (-0x7FFFFFFF, 0x7FFFFFFF)
    assert build.parse_range("-32768..+32767 (printed -32678..+32677)") == (-32768, 32767)


def test_fit_default_twos_complement():
    assert build.fit_default("DINT", 32, 0x80000000) == -(2**31)
    assert build.fit_default("USINT", 8, 300) is None


# --- the public API ---------------------------------------------------------------------------------------------

def test_list_profiles():
    infos = profiles.list_profiles()
    assert [i.name for i in infos] == ["technosoft-ipos", "hdt", "controltechniques"]
    assert [i.vendor_id for i in infos] == [0x1A3, 0x289, 0xF9]
    ct = infos[2]
    assert {p.name for p in ct.products} == {"unidrive-sp", "digitax-st", "commander-sk", "mentor-mp", "affinity"}
    assert infos[0].product("IPOS360X-VX-CAT").product_code == 28002021
    assert all(i.product(i.default_product) is not None for i in infos)


@pytest.mark.parametrize("alias,name", [("technosoft", "technosoft-ipos"), ("CT", "controltechniques"),
                                        ("tomcat", "hdt"), ("Technosoft-iPOS", "technosoft-ipos")])
def test_aliases(alias, name):
    assert profiles.family_of(profiles.load(alias)) == name


def test_unknown_profile_raises_selection_error():
    with pytest.raises(SelectionError, match="technosoft-ipos"):
        profiles.load("beckhoff")


@pytest.mark.parametrize("name", ["technosoft-ipos", "hdt", "controltechniques"])
def test_profile_devices_are_complete(name):
    dev = profiles.load(name)
    assert dev.has_coe and dev.mailbox.coe.pdo_assign and dev.mailbox.coe.pdo_config
    assert [s.kind for s in dev.sync_managers] == ["MBoxOut", "MBoxIn", "Outputs", "Inputs"]
    assert dev.source == f"profile:{name}" and dev.profile_no == 402
    assert {m.name for m in dev.dc_opmodes} == {"FreeRun", "DC"}
    for p in (*dev.rx_pdos, *dev.tx_pdos):
        for e in p.entries:
            target = dev.dictionary.entry(e.index, e.subindex)
            assert target is not None and target.bit_size == e.bit_len
            assert (target.rx_mappable if p.direction.value == "rx" else target.tx_mappable)
    for direction, sm in (("rx", 2), ("tx", 3)):
        pdos = dev.rx_pdos if direction == "rx" else dev.tx_pdos
        size = sum(p.bit_size for p in pdos if p.sm == sm) // 8
        assert dev.sm(sm).default_size == size and dev.sm(sm).max_size >= size
    # default values decode with their own type everywhere
    for obj in dev.dictionary:
        for e in obj:
            if e.default is not None and e.datatype is not None and e.datatype.bits is not None:
                assert len(e.default) == e.byte_size, (hex(obj.index), e.subindex)


def test_loads_are_independent():
    a = profiles.load("hdt")
    a.dictionary.get(0x6060).entries[0].default = b"\x07"
    assert profiles.load("hdt").dictionary.entry(0x6060, 0).default_value == 2
