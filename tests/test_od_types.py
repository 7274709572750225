import struct

import pytest
from hypothesis import given
from hypothesis import strategies as st

from ecattool.errors import EncodeError, InputError
from ecattool.od import parse_address, parse_int
from ecattool.od.types import BY_CODE, Kind, lookup


@pytest.mark.parametrize(
    "name,code,bits",
    [
        ("BOOL", 0x01, 1), ("USINT", 0x05, 8), ("UINT", 0x06, 16), ("DINT", 0x04, 32), ("UDINT", 0x07, 32),
        ("DINT32", 0x04, 32), ("UINT32", 0x07, 32), ("UNSIGNED16", 0x06, 16), ("INTEGER8", 0x02, 8),
        ("REAL32", 0x08, 32), ("LREAL", 0x11, 64), ("ULINT", 0x1B, 64), ("INT24", 0x10, 24),
        ("UINT40", 0x18, 40), ("INT48", 0x13, 48), ("UINT56", 0x1A, 56), ("BIT2", 0x31, 2), ("BIT8", 0x37, 8),
        ("BITARR16", 0x2E, 16), ("BYTE", 0x1E, 8), ("WORD", 0x1F, 16), ("DWORD", 0x20, 32),
    ],
)
def test_lookup_names(name, code, bits):
    dt = lookup(name)
    assert dt is not None and dt.code == code and dt.bits == bits
    assert lookup(name.lower()) == dt


def test_string_with_length():
    dt = lookup("STRING(8)")
    assert dt.kind is Kind.STRING and dt.bits == 64
    assert dt.encode("abc") == b"abc\x00\x00\x00\x00\x00"
    with pytest.raises(EncodeError):
        dt.encode("123456789")


def test_encode_exact_sizes_and_ranges():
    assert lookup("USINT").encode(255) == b"\xff"
    assert lookup("UINT").encode(0x1A00) == b"\x00\x1a"
    assert lookup("UDINT").encode(0x60400010) == bytes.fromhex("10004060")
    assert lookup("DINT").encode(-1) == b"\xff\xff\xff\xff"
    assert lookup("INT24").encode(-2) == b"\xfe\xff\xff"
    assert lookup("REAL").encode(1.5) == struct.pack("<f", 1.5)
    for name, bad in [("USINT", 256), ("USINT", -1), ("INT", 32768), ("SINT", -129), ("BIT2", 4)]:
        with pytest.raises(EncodeError):
            lookup(name).encode(bad)
    with pytest.raises(EncodeError):
        lookup("UINT").encode("x")


def test_decode_checks_size():
    with pytest.raises(EncodeError):
        lookup("UDINT").decode(b"\x00\x00")


@given(st.sampled_from([dt for dt in BY_CODE.values() if dt.kind in (Kind.SIGNED, Kind.UNSIGNED, Kind.BITS, Kind.BOOL)]), st.data())
def test_integer_roundtrip(dt, data):
    lo, hi = dt.range()
    v = data.draw(st.integers(lo, hi))
    raw = dt.encode(v)
    assert len(raw) == (dt.bits + 7) // 8
    assert dt.decode(raw) == v


@pytest.mark.parametrize("text,value", [("0x1C12", 0x1C12), ("#x1C12", 0x1C12), ("7186", 7186), ("1C12h", 0x1C12), ("-5", -5), ("#xFFFFFFFF", 0xFFFFFFFF)])
def test_parse_int(text, value):
    assert parse_int(text) == value


@pytest.mark.parametrize("text,addr", [("6060:00", (0x6060, 0)), ("0x6060:0", (0x6060, 0)), ("#x1A00:3", (0x1A00, 3)), ("0x607A", (0x607A, 0)), ("6060h:00h", (0x6060, 0))])
def test_parse_address(text, addr):
    assert parse_address(text) == addr


def test_bad_numbers_raise_input_error():
    with pytest.raises(InputError):
        parse_int("0xZZ")
    with pytest.raises(InputError):
        parse_address("hello")


def test_error_code_tables_of_the_manuals():
    """HDT oracle 18 (§2.08.2): every listed code with its alarm; Technosoft §3.1.3; classes for the rest."""
    from ecattool.od.emcy import HDT, TECHNOSOFT, error_text

    hdt_listed = [0x7600, 0xFF01, 0x2340, 0x3210, 0xFF0B, 0xFF08, 0x7120, 0x7110, 0x3220, 0x8611, 0xFF02, 0xFF03,
                  0xFF04, 0xFF05, 0xFF09, 0x8130, 0xFF07, 0xFF0A, 0xFF0D, 0x4310, 0xFF0C, 0x8400]
    assert list(HDT) == hdt_listed
    assert error_text(0x3220, "hdt") == "DC bus undervoltage (FA_12)"
    assert error_text(0xFF04, "hdt") == "warning I2t motor (FA_16)"
    assert error_text(0xFF04, "technosoft-ipos") == "a wrong mode is set in 6060h"  # same code, other family
    assert len(TECHNOSOFT) == 28 and error_text(0x5443, "technosoft-ipos") == "positive limit switch active"
    assert error_text(0x2311, "controltechniques") == "current, device output side"  # CiA-301 class
    assert error_text(0x8611) == "position control" and error_text(0xA001) == "unknown error code"
