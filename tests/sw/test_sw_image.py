"""The .sw text format: every corpus file, the manual's rules and examples, located errors, round trips."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from ecattool.errors import EcatToolError, InputError
from ecattool.sw import Block, SwImage, checksum, checksum_request, make_image, parse, read, write
from tests.conftest import corpus_path

GOOD = [
    "ecmc_TMLCode.sw",
    "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.sw",
    "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A_plusTML.sw",
    "ecmc_ipos8020_DC48V_TRQ_MODE_40A.sw",
    "ecmc_old_DC48V.sw",
    "march_imc_left_ankle.sw",
    "march_imc_left_hip_aa.sw",
    "march_imc_right_knee.sw",
]


def test_every_corpus_sw_file_is_listed(corpus):
    names = {p.name for p in (corpus / "sw").glob("*.sw")}
    assert names == set(GOOD) | {"march_imc_rotational_joint.sw"}


@pytest.mark.parametrize("name", GOOD)
def test_corpus_file_rewrites_byte_identical(name):
    raw = corpus_path("sw", name).read_bytes()
    image = parse(raw, name)
    assert write(image) == raw


@pytest.mark.parametrize("name", GOOD)
def test_corpus_file_read_as_lf_and_lower_case_gives_same_image(name):
    raw = corpus_path("sw", name).read_bytes()
    lf = raw.replace(b"\r\n", b"\n").lower()
    assert parse(lf) == parse(raw)
    assert write(parse(lf)) == raw


def test_corrupt_corpus_file_is_refused_at_line_207():
    path = corpus_path("sw", "march_imc_rotational_joint.sw")
    with pytest.raises(InputError) as err:
        read(path)
    assert err.value.location.line == 207
    assert str(err.value).startswith(f"{path}:207: ")
    assert "9E9(E(" in str(err.value)


def test_setup_only_file_blocks_and_checksums_match_ecmc_offline_values():
    # ecmc's .cmd prints "Offline calculated checksum: 0x4a2a ... 0xffff ... 0x7abd" for this image
    image = read(corpus_path("sw", "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.sw"))
    assert [(b.start, b.end, b.count, b.checksum) for b in image] == [
        (0x7ABD, 0x7FAF, 1267, 0x4A2A), (0x7FBF, 0x7FE0, 34, 0xFFFF), (0x7FFF, 0x7FFF, 1, 0x7ABD)]
    assert [b.checksum_request for b in image] == [0x7FAF7ABD, 0x7FE07FBF, 0x7FFF7FFF]


def test_file_without_final_blank_line_keeps_it_that_way():
    raw = corpus_path("sw", "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A_plusTML.sw").read_bytes()
    assert not raw.endswith(b"\r\n\r\n")
    image = parse(raw)
    assert image.final_blank_line is False
    assert [b.start for b in image] == [0x7ABD, 0x7FBF, 0x7FFF, 0x4000]


# ---------------------------------------------------------------------------- manual §17.3 / §17.4.1
def test_right_justified_word_92_is_0x0092():  # oracle G57
    image = parse("5E06\r\n92\r\n\r\n")
    assert image.blocks[0].words == (0x0092,)


def test_checksum_request_for_0x5e06_to_0x5eff_is_0x5eff5e06():  # oracle G60
    assert checksum_request(0x5E06, 0x5EFF) == 0x5EFF5E06


def test_block_5e06_with_four_words_checksum_and_inclusive_end():  # oracle G65 (derived)
    image = parse("5E06\n1234\n5678\n09AB\nCDEF\n\n")
    b = image.blocks[0]
    assert (b.count, b.end, b.checksum, b.checksum_request) == (4, 0x5E09, 0x4046, 0x5E095E06)


def test_checksum_mismatch_example_is_a_mismatch():  # oracle G61: file 0x1234 vs drive 0x2345
    b = Block(0x5E06, (0x1234,))
    assert b.checksum == 0x1234 and b.checksum != 0x2345


def test_checksum_wraps_mod_65536():
    assert checksum([0xFFFF, 0x0002]) == 0x0001


def test_several_blank_lines_and_blanks_around_words_are_accepted():
    image = parse("  4000 \n1\n\n\n\n4002\n 2\n")
    assert [(b.start, b.words) for b in image] == [(0x4000, (1,)), (0x4002, (2,))]


# -------------------------------------------------------------------------------------- located errors
@pytest.mark.parametrize(
    ("text", "line", "needle"),
    [
        ("4000\n12345\n", 2, "at most 4 digits"),
        ("4000\n0x12\n", 2, "at most 4 digits"),
        ("4000\n1\n\n4100\n\n4200\n5\n", 4, "empty block"),
        ("4000\n", 1, "empty block"),
        ("FFFE\n1\n2\n3\n", 4, "past address 0xFFFF"),
        ("4000\n1\n2\n3\n\n4001\n9\n", 6, "overlaps"),
        ("4000\n1\n\n3FFF\n9\n9\n", 4, "overlaps"),
        ("\n\n", 1, "no data blocks"),
        ("4000\n1 2\n", 2, "at most 4 digits"),
    ],
)
def test_bad_files_give_file_and_line(text, line, needle):
    with pytest.raises(InputError) as err:
        parse(text, "x.sw")
    assert err.value.location.file == "x.sw"
    assert err.value.location.line == line
    assert needle in err.value.message


def test_non_ascii_byte_is_located():
    with pytest.raises(InputError) as err:
        parse(b"4000\n1\n\xe9\n", "x.sw")
    assert err.value.location.line == 3


def test_built_blocks_are_validated():
    with pytest.raises(ValueError):
        Block(0xFFFF, (1, 2))
    with pytest.raises(ValueError):
        Block(0x10, ())
    with pytest.raises(InputError):
        make_image([(0x10, [1, 2]), (0x11, [3])])


# ----------------------------------------------------------------------------------------- properties
@st.composite
def images(draw) -> SwImage:
    n = draw(st.integers(1, 5))
    starts = sorted(draw(st.lists(st.integers(0, 0xFF00), min_size=n, max_size=n, unique=True)))
    blocks = []
    for i, s in enumerate(starts):
        limit = (starts[i + 1] - s) if i + 1 < len(starts) else 0x10000 - s
        count = draw(st.integers(1, min(limit, 40)))
        blocks.append((s, draw(st.lists(st.integers(0, 0xFFFF), min_size=count, max_size=count))))
    order = draw(st.permutations(blocks))
    return make_image(order, draw(st.booleans()))


@given(images())
def test_text_round_trip(image):
    raw = write(image)
    assert parse(raw) == image
    assert write(parse(raw)) == raw
    assert b"\n" not in raw.replace(b"\r\n", b"")


@given(images(), st.data())
def test_mutated_files_give_located_errors_never_exceptions(image, data):
    raw = bytearray(write(image))
    for _ in range(data.draw(st.integers(1, 3))):
        pos = data.draw(st.integers(0, len(raw) - 1))
        op = data.draw(st.sampled_from(["replace", "delete", "insert"]))
        byte = data.draw(st.sampled_from(list(b"0123456789ABCDEFXg \r\n(\xff")))
        if op == "replace":
            raw[pos] = byte
        elif op == "delete":
            del raw[pos]
        else:
            raw.insert(pos, byte)
    try:
        parse(bytes(raw), "m.sw")
    except EcatToolError as exc:
        assert exc.location is not None and exc.location.file == "m.sw"
        assert exc.location.line is not None or "overlap" in exc.message
