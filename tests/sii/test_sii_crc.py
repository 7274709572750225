"""SII preamble CRC-8 (poly 0x07, init 0xFF, bytes 0-13 → byte 14)."""

from __future__ import annotations


import pytest
from hypothesis import given
from hypothesis import strategies as st

from ecattool.sii import crc8, load, preamble_crc
from tests.conftest import corpus_files, corpus_path


def test_check_value_123456789() -> None:
    assert crc8(b"123456789") == 0xFB


def test_siitool_example_header_vector() -> None:
    assert crc8(bytes.fromhex("080e0288") + bytes(10)) == 0x2F


def test_siitool_example_image_carries_0x2f() -> None:
    raw = corpus_path("sii", "synapticon_siitool_sii_example.bin").read_bytes()
    assert raw[14] == 0x2F == preamble_crc(raw)


@pytest.mark.parametrize("path", corpus_files("sii/*.bin", form="str"))
def test_every_corpus_image_has_a_valid_crc(path: str) -> None:
    raw = open(path, "rb").read()
    assert raw[14] == preamble_crc(raw)
    assert crc8(raw[:16]) == 0  # the CRC over bytes 0..15 is zero
    assert load(path).crc_ok


def _augmented_igh_form(data: bytes) -> int:
    """IgH's shift-in form: init 0x48, data bits shifted through, then 8 zero bits."""
    crc = 0x48
    for bit in [(b >> (7 - i)) & 1 for b in data for i in range(8)] + [0] * 8:
        top = crc & 0x80
        crc = ((crc << 1) | bit) & 0xFF
        if top:
            crc ^= 0x07
    return crc


@given(st.binary(min_size=14, max_size=14))
def test_equals_the_augmented_form_with_init_0x48(data: bytes) -> None:
    assert crc8(data) == _augmented_igh_form(data)


@given(st.binary(max_size=64))
def test_appending_the_crc_gives_zero(data: bytes) -> None:
    assert crc8(data + bytes([crc8(data)])) == 0
