"""Parsing SII images: every corpus image, Intel HEX, located errors, lossless round trips."""

from __future__ import annotations


import pytest
from hypothesis import given
from hypothesis import strategies as st

from ecattool.errors import InputError
from ecattool.sii import (
    CategoryType,
    DcCategory,
    FmmuCategory,
    GeneralCategory,
    PdoCategory,
    RawCategory,
    SiiDcOpMode,
    SiiHeader,
    SiiImage,
    SiiPdo,
    SiiPdoEntry,
    SiiSyncManager,
    StringsCategory,
    SyncMCategory,
    check,
    load,
    parse,
    write_intel_hex,
)
from ecattool.sii.image import read_intel_hex
from tests.conftest import corpus_files, corpus_path

IMAGES = corpus_files("sii/*.bin", form="str")


def test_corpus_has_all_sixteen_images() -> None:
    corpus_path("sii")
    assert len(IMAGES) == 16


@pytest.mark.parametrize("path", IMAGES)
def test_corpus_image_round_trips_byte_for_byte(path: str) -> None:
    raw = open(path, "rb").read()
    image = load(path)
    assert image.to_bytes() == raw
    again = parse(image.to_bytes())
    assert again == image  # parse -> serialize -> parse is lossless on the model too
    assert not [c for c in image.categories if isinstance(c, RawCategory) and c.problem]


EXPECTED_CATEGORIES = {
    "ni9144.bin": "STRINGS GENERAL FMMU SYNCM FMMUX TXPDO DC END",
    "ni9144_rev1.bin": "STRINGS GENERAL FMMU SYNCM FMMUX TXPDO DC END",
    "easycat_FEI_256.bin": "STRINGS GENERAL FMMU SYNCM TXPDO RXPDO DC",  # runs to the end of the data
    "pollen_Orbita2d.bin": "STRINGS GENERAL SYNCM TXPDO TXPDO RXPDO DC DC END",
    "soes_linux_lan9252demo.bin": "STRINGS GENERAL FMMU SYNCM END",
    "asix_AX58100_EVB_DIO.bin": "STRINGS GENERAL FMMU SYNCM END",  # END marker without a length word
}


@pytest.mark.parametrize("name", sorted(EXPECTED_CATEGORIES))
def test_category_chains(name: str) -> None:
    image = load(corpus_path("sii", name))
    got = [CategoryType(c.cat_type).name for c in image.categories] + (["END"] if image.end_marker else [])
    assert " ".join(got) == EXPECTED_CATEGORIES[name]


def test_ni9144_fields() -> None:
    image = load(corpus_path("sii", "ni9144.bin"))
    h = image.header
    assert (h.vendor_id, h.product_code, h.revision) == (0x1F9, 0x23B8, 2)
    assert (h.std_rx_offset, h.std_rx_size, h.std_tx_offset, h.std_tx_size) == (0x1F00, 0x100, 0x1C00, 0x300)
    assert h.protocols == ["AoE", "CoE", "FoE"] and h.eeprom_bytes == 2048
    g = image.general
    assert g is not None and image.string(g.name_idx) == "NI 9144" and image.string(g.group_name_idx) == \
        "NI 9144 EtherCAT Slave"
    assert g.physical_port == 0x11
    assert [p.index for p in image.tx_pdos] == [0x1A00, 0x1A01, 0x1A02]
    e = image.tx_pdos[0].entries[0]
    assert (e.index, e.subindex, e.bit_len, image.string(e.name_idx)) == (0x6000, 1, 16, "IN 1.1")
    assert [image.string(o.name_idx) for o in image.dc_opmodes] == ["DcOff", "DcSync"]
    assert image.dc_opmodes[1].assign_activate == 0x300


def test_easycat_dc_shift_time() -> None:
    ops = load(corpus_path("sii", "easycat_FEI_1.bin")).dc_opmodes
    assert ops[1].shift_time0 == 2000200000 and ops[1].assign_activate == 0x300 and ops[1].sync0_cycle_factor == 1


# -- errors -------------------------------------------------------------------------------------------
def test_empty_file_is_a_located_error(tmp_path) -> None:
    p = tmp_path / "empty.bin"
    p.write_bytes(b"")
    with pytest.raises(InputError) as exc:
        load(p)
    assert "empty" in exc.value.message and exc.value.location.file == str(p)


def test_truncated_fixed_area_is_a_located_error() -> None:
    with pytest.raises(InputError, match="truncated: 100 bytes") as exc:
        parse(bytes(100), "x.bin")
    assert str(exc.value).startswith("x.bin: ")


def test_truncated_category_names_offset_and_length() -> None:
    raw = corpus_path("sii", "easycat_FEI_1.bin").read_bytes()[:600]
    with pytest.raises(InputError, match=r"category 0x0032 at byte 0x021A .* declares 68 words .* ends at byte 0x0258"):
        parse(raw, "cut.bin")


def test_cut_category_header_is_an_error() -> None:
    raw = corpus_path("sii", "soes_linux_lan9252demo.bin").read_bytes()
    with pytest.raises(InputError, match="cut off"):
        parse(raw[:0x80] + b"\x0a\x00", "cut.bin")  # a type word, no length word
    assert parse(raw[:0x80]).categories == []  # a bare 64-word header parses: no categories


# -- Intel HEX ----------------------------------------------------------------------------------------
def test_intel_hex_input_equals_binary(tmp_path) -> None:
    raw = corpus_path("sii", "metalmusings_EaserCAT_2000.bin").read_bytes()
    p = tmp_path / "eeprom.hex"
    p.write_text(write_intel_hex(raw))
    assert load(p).to_bytes() == raw


def test_intel_hex_bad_checksum_is_located_at_its_line(tmp_path) -> None:
    lines = write_intel_hex(bytes(range(64))).splitlines()
    lines[2] = lines[2][:-2] + ("00" if lines[2][-2:] != "00" else "01")
    p = tmp_path / "bad.hex"
    p.write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError, match="checksum") as exc:
        load(p)
    assert exc.value.location.line == 3


def test_intel_hex_overrun_is_located_at_the_record_line(tmp_path) -> None:
    raw = corpus_path("sii", "easycat_FEI_1.bin").read_bytes()[:600]
    p = tmp_path / "cut.hex"
    p.write_text(write_intel_hex(raw))
    with pytest.raises(InputError) as exc:
        load(p)
    assert exc.value.location.line == 0x21A // 16 + 1


@pytest.mark.parametrize(("text", "what"), [
    (":10000000ZZ\n", "non-hex characters"),        # typo in a record: was read as a 12-byte binary
    (":10000000\n", "does not match its count byte"),
    (":020000040000FA\nhello\n", "must start with ':'"),
])
def test_malformed_intel_hex_is_located_not_read_as_binary(tmp_path, text: str, what: str) -> None:
    p = tmp_path / "bad.hex"
    p.write_text(text)
    with pytest.raises(InputError, match=what) as exc:
        load(p)
    assert exc.value.location.line is not None


def test_binary_image_starting_with_a_colon_byte_is_binary() -> None:
    raw = bytearray(corpus_path("sii", "metalmusings_EaserCAT_2000.bin").read_bytes())
    raw[0] = ord(":")  # PDI control low byte 0x3A: still a binary image
    assert load("x.bin", bytes(raw)).to_bytes() == bytes(raw)


def test_an_esi_given_as_image_says_what_to_do_instead() -> None:
    esi = corpus_path("sii", "metalmusings_EaserCAT_2000.xml")
    with pytest.raises(InputError, match=r"XML file .*not an SII image .*sii build ESI") as exc:
        load(esi)
    assert exc.value.location.line == 1


@given(st.binary(max_size=300))
def test_intel_hex_writer_reader_round_trip(data: bytes) -> None:
    assert read_intel_hex(write_intel_hex(data).encode())[0] == data


@given(st.text(alphabet=":0123456789ABCDEF\n", max_size=200))
def test_random_intel_hex_text_never_crashes(text: str) -> None:
    try:
        read_intel_hex(text.encode())
    except InputError:
        pass


# -- property tests -----------------------------------------------------------------------------------
def _parse_check_round_trip(data: bytes) -> None:
    try:
        image = parse(data)
    except InputError:
        return
    assert image.to_bytes() == data
    check(image)


@given(st.binary(max_size=600))
def test_random_bytes_never_crash_and_round_trip(data: bytes) -> None:
    _parse_check_round_trip(data)


@given(st.binary(min_size=128, max_size=128), st.binary(max_size=400))
def test_random_category_area_never_crashes(head: bytes, body: bytes) -> None:
    _parse_check_round_trip(head + body)


u8, u16, u32 = (st.integers(0, 2 ** n - 1) for n in (8, 16, 32))
i16 = st.integers(-0x8000, 0x7FFF)

headers = st.builds(
    SiiHeader, u16, u16, u16, u16, u16, u16, u16, u16, u32, u32, u32, u32, st.binary(min_size=8, max_size=8),
    u16, u16, u16, u16, u16, u16, u16, u16, u16, st.binary(min_size=66, max_size=66), u16, u16)
strings_cats = st.builds(StringsCategory, st.lists(st.text(st.characters(max_codepoint=255), max_size=20),
                                                     max_size=12))
generals = st.builds(GeneralCategory, *([u8] * 12), i16, u8, u8, u16, u16, st.binary(min_size=12, max_size=12),
                     st.sampled_from([b"", b"\x01\x02"]))
fmmus = st.builds(FmmuCategory, st.lists(u8, max_size=9).filter(lambda u: len(u) % 2 or not u or u[-1] != 0))
syncms = st.builds(SyncMCategory, st.lists(st.builds(SiiSyncManager, u16, u16, u8, u8, u8, u8), max_size=6))
entries = st.builds(SiiPdoEntry, u16, u8, u8, u8, u8, u16)
pdos = st.builds(SiiPdo, u16, u8, u8, u8, u16, st.lists(entries, max_size=5))
pdo_cats = st.builds(PdoCategory, st.sampled_from([CategoryType.TXPDO, CategoryType.RXPDO]),
                     st.lists(pdos, max_size=4))
dcs = st.builds(DcCategory, st.lists(st.builds(SiiDcOpMode, u32, u32, u32, i16, u16, i16, u8, u8,
                                               st.binary(min_size=4, max_size=4)), max_size=3))
raws = st.builds(RawCategory, st.integers(0, 0xFFFE).filter(lambda t: t not in (10, 30, 40, 41, 50, 51, 60)),
                 st.binary(max_size=40).map(lambda b: b + b"\x00" * (len(b) % 2)))
images = st.builds(
    lambda h, cats, end, tail: SiiImage(h, cats, end, tail if end else b""), headers,
    st.lists(st.one_of(strings_cats, generals, fmmus, syncms, pdo_cats, dcs, raws), max_size=8),
    st.booleans(), st.binary(max_size=20))


@given(images)
def test_random_models_round_trip(image: SiiImage) -> None:
    again = parse(image.to_bytes())
    assert again == image
    assert again.to_bytes() == image.to_bytes()


def test_out_of_range_fields_are_input_errors() -> None:
    bad = SiiImage(SiiHeader(vendor_id=1 << 32))
    with pytest.raises(InputError, match="out of range"):
        bad.to_bytes()
    bad = SiiImage(SiiHeader(), [DcCategory([SiiDcOpMode(sync0_cycle_factor=0x8000)])])
    with pytest.raises(InputError, match="out of range"):
        bad.to_bytes()
