"""FoE setup images: the corpus pair byte for byte, the other corpus images, the name rules, round trips."""

from __future__ import annotations

import struct

import pytest
from hypothesis import given
from hypothesis import strategies as st

from ecattool.errors import EcatToolError, InputError
from ecattool.sw import check_foe_name, from_foe, integrity_findings, read, read_foe, to_foe, write
from tests.conftest import corpus_path
from tests.sw.test_sw_image import images


def test_corpus_sw_converts_to_the_corpus_bin_byte_for_byte():
    image = read(corpus_path("sw", "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.sw"))
    data = corpus_path("sw", "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.bin").read_bytes()
    assert len(data) == 2616
    assert to_foe(image) == data


def test_corpus_bin_converts_back_to_the_corpus_sw_byte_for_byte():
    image = read_foe(corpus_path("sw", "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.bin"))
    assert write(image) == corpus_path("sw", "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.sw").read_bytes()


@pytest.mark.parametrize(
    ("name", "layout"),
    [
        ("ecmc_ipos8020BX_FOESW_8020.bin", [(0x7ADC, 1236), (0x7FBF, 34), (0x7FFF, 1)]),
        ("ecmc_ipos8020_FOESW_DC48V_TRQ.bin", [(0x7ABF, 1265), (0x7FBF, 34), (0x7FFF, 1)]),
        ("ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.bin", [(0x7ABD, 1267), (0x7FBF, 34), (0x7FFF, 1)]),
    ],
)
def test_every_corpus_bin_parses_with_consistent_integrity_words(name, layout):
    image = read_foe(corpus_path("sw", name))
    assert [(b.start, b.count) for b in image] == layout
    assert integrity_findings(image) == []
    assert to_foe(image) == corpus_path("sw", name).read_bytes()


def test_near_pair_8020_differs_from_its_sw_as_the_sources_say():
    sw = read(corpus_path("sw", "ecmc_ipos8020_DC48V_TRQ_MODE_40A.sw"))
    foe = read_foe(corpus_path("sw", "ecmc_ipos8020_FOESW_DC48V_TRQ.bin"))
    assert [(b.start, b.count) for b in sw] == [(b.start, b.count) for b in foe]
    assert to_foe(sw) != corpus_path("sw", "ecmc_ipos8020_FOESW_DC48V_TRQ.bin").read_bytes()


# ---------------------------------------------------------------------------- name rules (§17.4.3.1)
def test_foe_name_of_twelve_characters_is_accepted():  # oracle A11 (derived)
    assert check_foe_name("out/FOESW_AXIS01.bin") == "FOESW_AXIS01.bin"
    assert check_foe_name("FOESW_12345678.efw") == "FOESW_12345678.efw"


@pytest.mark.parametrize(
    ("name", "needle"),
    [
        ("FOESW_AXIS0123X.bin", "longer than 14"),  # oracle A11: 15 characters
        ("AXIS01.bin", "start with 'FOESW_'"),
        ("foesw_axis.bin", "start with 'FOESW_'"),
        ("FOESW_AXIS.sw", ".bin or .efw"),
        ("FOESW_AXIS", ".bin or .efw"),
        ("FOESW_A B.bin", "ASCII letters"),
    ],
)
def test_foe_names_the_drive_rejects_are_refused(name, needle):
    with pytest.raises(InputError) as err:
        check_foe_name(name)
    assert needle in err.value.message


# ------------------------------------------------------------------------------------- bad binaries
@pytest.mark.parametrize(
    ("data", "needle"),
    [
        (b"", "empty"),
        (b"\x00\x40\x01", "odd"),
        (b"\x00\x40", "truncated block header at byte offset 0"),
        (b"\x00\x40\x00\x00", "word count of 0"),
        (b"\x00\x40\x03\x00\x01\x00", "announces 3 words"),
        (b"\xff\xff\x02\x00\x01\x00\x02\x00", "past 0xFFFF"),
        (b"\x00\x40\x02\x00\x01\x00\x02\x00\x01\x40\x01\x00\x05\x00", "overlaps"),
    ],
)
def test_bad_foe_images_are_refused_with_the_file(data, needle):
    with pytest.raises(InputError) as err:
        from_foe(data, "FOESW_X.bin")
    assert needle in err.value.message
    assert err.value.location.file == "FOESW_X.bin"


@given(images())
def test_foe_round_trip(image):
    data = to_foe(image)
    assert len(data) == 2 * sum(2 + b.count for b in image)
    back = from_foe(data, final_blank_line=image.final_blank_line)
    assert back == image
    first = image.blocks[0]
    assert struct.unpack("<HH", data[:4]) == (first.start, first.count)


@given(st.binary(max_size=64))
def test_random_bytes_never_raise_anything_but_input_errors(data):
    try:
        from_foe(data, "f.bin")
    except EcatToolError as exc:
        assert exc.location is not None
