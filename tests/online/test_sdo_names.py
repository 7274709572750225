"""``sdo read``/``sdo write`` take an object by name wherever they take ``index:sub`` (issue 35 item 3; docs/cli.md
says names work, and ``sdo read controlword --device …`` said "'0xcontrolword' is not a valid object index")."""

from __future__ import annotations

import json

import pytest

from tests.conftest import run


def test_names_and_addresses_are_both_objects(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run(capsys, "sdo", "read", "controlword", "--target", "sim:hdt", "--device", "hdt", "--json")
    assert code == 0, err
    assert json.loads(out)["address"] == "0x6040:00" and json.loads(out)["type"] == "UINT"
    code, out, _ = run(capsys, "sdo", "read", "modes of operation", "--target", "sim:technosoft-ipos", "--json")
    assert code == 0 and json.loads(out)["address"] == "0x6060:00"
    code, out, _ = run(capsys, "sdo", "write", "profile velocity", "1234", "--target", "sim:technosoft-ipos", "--json")
    assert code == 0 and json.loads(out)["address"] == "0x6081:00"


def test_an_unknown_name_is_one_line_with_the_nearest(capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = run(capsys, "sdo", "read", "controlwrd", "--target", "sim:hdt")
    assert code == 1 and len(err.strip().splitlines()) == 1
    assert "'controlwrd' is neither an object address" in err and "did you mean 'Controlword'?" in err


def test_a_record_of_one_value_named_as_its_object_is_found_by_that_name(capsys: pytest.CaptureFixture[str]) -> None:
    """The ETG.2001 sample maps 6041h:01 "StatusWord" in its PDOs and declares no 6041h: the object ecattool makes
    of it is a record of sub-index 0 and one value with the object's name, which its name now finds (it said
    "did you mean 'StatusWord'?" for 'StatusWord'); a record of other entries is not found by its bare name."""
    target = ["--target", "sim:samples/esi/etg2001_cia402.xml", "--json"]
    code, out, err = run(capsys, "sdo", "read", "StatusWord", *target)
    assert code == 0, err
    assert json.loads(out)["address"] == "0x6041:01" and json.loads(out)["dictionary"] == "sdo-info"
    code, _, err = run(capsys, "sdo", "read", "Identity", *target)
    assert code == 1 and "'Identity' is neither an object address" in err
