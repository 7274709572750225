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
