"""The setup-table structure worked out from the corpus, parameters.cfg, patch, diff, build, CAM tables."""

from __future__ import annotations

import struct
from fractions import Fraction

import pytest
from hypothesis import given
from hypothesis import strategies as st

from ecattool.errors import InputError
from ecattool.sw import (build, describe, diff, fix_integrity, integrity_findings, parse_parameters, patch,
                         read, read_foe, read_parameters, setup_table, setup_values, write)
from ecattool.sw.layout import (IDENT_START, SETUP_LAST_ADDRESS, cam_table_words, cam_tables, decode_section3,
                                parse_identification)
from ecattool.sw.setup import decode, encode
from tests.conftest import ROOT, corpus_path, sample_sw_spec

SETUP_FILES = [
    "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.sw", "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A_plusTML.sw",
    "ecmc_ipos8020_DC48V_TRQ_MODE_40A.sw", "ecmc_old_DC48V.sw", "march_imc_left_ankle.sw",
    "march_imc_left_hip_aa.sw", "march_imc_right_knee.sw",
    "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.bin", "ecmc_ipos8020BX_FOESW_8020.bin", "ecmc_ipos8020_FOESW_DC48V_TRQ.bin",
]
SW4808 = "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.sw"
PARAMS = "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.ems_parameters.cfg"


def _load(name):
    path = corpus_path("sw", name)
    return read_foe(path) if name.endswith(".bin") else read(path)


@pytest.fixture(scope="module")
def image4808():
    return read(corpus_path("sw", SW4808))


@pytest.fixture(scope="module")
def params():
    return read_parameters(corpus_path("sw", PARAMS))


@pytest.mark.parametrize("name", SETUP_FILES)
def test_every_corpus_image_has_the_same_structure(name):
    image = _load(name)
    kinds = {i.kind: i.block for i in describe(image)}
    table = setup_table(image)
    assert table.block.words[0] == 0x649C
    assert 5 + sum(table.sizes) + 1 == table.block.count
    assert table.stored_checksum == table.computed_checksum  # last word = sum of the words before it
    assert table.block.end == SETUP_LAST_ADDRESS  # every corpus table ends at 0x7FAF
    assert image.word_at(0x7FFF) == table.block.start  # the pointer
    ident = kinds["identification"]
    assert ident.start == IDENT_START and ident.count == 34 and ident.checksum == 0xFFFF
    assert ident.words[31] == sum(ident.words[:31]) & 0xFFFF
    assert integrity_findings(image) == []
    assert fix_integrity(image) == image


def test_configuration_id_and_identification_match_the_easymotion_setup_cfg(image4808):
    cfg = corpus_path("sw", "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.ems_setup.cfg").read_text("latin-1")
    fields = dict(line.split("\t= ", 1) for line in cfg.splitlines() if "\t= " in line)
    assert setup_table(image4808).config_id == int(fields["ConfigurationID"], 16) == 0x2E63
    ident = parse_identification(image4808.block_at(IDENT_START))
    assert ident.product_id == fields["ProductID"] == "P027.314.E221"
    assert ident.firmware_id == fields["FirmwareID"] == "F515K"


def test_march_identification_without_product_id():
    ident = parse_identification(_load("march_imc_left_ankle.sw").block_at(IDENT_START))
    assert (ident.text, ident.product_id, ident.firmware_id) == ("F6FGA", None, "F6FGA")


def test_pwmper_example_and_every_section_1_and_2_value_match_parameters_cfg(image4808, params):
    _, values = setup_values(image4808, params)
    by_name = {v.name: v for v in values}
    assert by_name["PWMPER"].entry.address == 0x0252 and by_name["PWMPER"].entry.raw == 0x08CA
    assert by_name["PWMPER"].value == 2250
    checked = 0
    for v in values:
        p = params.by_address(v.entry.address)
        assert p is not None, hex(v.entry.address)
        if v.entry.section in (1, 2):
            assert p.raw == v.entry.raw, p.name
            checked += 1
    assert checked == 184 + 136
    assert by_name["CACC"].value == Fraction(0x32EE0, 0x10000)
    assert by_name["I2TINTLIM_D"].value == 6036849


def test_section_3_decodes_completely_with_parameters_cfg(image4808, params):
    table = setup_table(image4808)
    entries = decode_section3(table, params)
    assert sum(1 + len(e.words) for e in entries) == table.sizes[2] == 485
    by_addr = {e.address: e for e in entries}
    dsp = by_addr[params.by_name("DSP_freq").address]
    assert struct.unpack("<f", struct.pack("<HH", *dsp.words))[0] == 9e7


def test_section_3_without_the_address_in_parameters_is_refused(image4808):
    partial = parse_parameters("UINT\tPWMPER\t@0x0252\t=2250(0x08CA)\n", "p.cfg")
    with pytest.raises(InputError, match="cannot be decoded"):
        decode_section3(setup_table(image4808), partial)


# ----------------------------------------------------------------------------------------------- patch
def test_patch_changes_the_value_and_every_integrity_word(image4808, params):
    new = patch(image4808, [("PWMPER", "2251"), ("ERRMAXL", "0x7D0"), ("CACC", "3.5")], params)
    assert integrity_findings(new) == []
    _, values = setup_values(new, params)
    by_name = {v.name: v for v in values}
    assert (by_name["PWMPER"].value, by_name["ERRMAXL"].value, by_name["CACC"].value) == (2251, 2000, Fraction(7, 2))
    changed = {d.name for d in diff(image4808, new, params)}
    assert changed == {"PWMPER", "ERRMAXL", "CACC"}
    table = setup_table(new)
    assert table.stored_checksum == table.computed_checksum != setup_table(image4808).stored_checksum
    # the whole-block checksum the drive computes changes by twice the change of the values
    assert [b.start for b in new] == [b.start for b in image4808]


def test_patch_by_address_without_parameters(image4808):
    new = patch(image4808, [("0x0252", "2000")])
    table = setup_table(new)
    assert table.entry(0x0252).words == (2000,)
    assert new.word_at(table.block.start + table.entry(0x0252).offset) == 2000
    assert integrity_findings(new) == []


@pytest.mark.parametrize(
    ("key", "value", "needle"),
    [
        ("L", "2.2", "cannot be patched"),  # FLOAT: stored in SI units, cfg shows mH
        ("PWMPER", "70000", "outside the UINT range"),
        ("CLPER", "-40000", "outside the INT range"),
        ("NOSUCH", "1", "is not a parameter"),
        ("SSI_freq", "1", "is not in the setup table"),  # a RAM-only 0xC0xx variable
        ("CACC", "abc", "is not a number"),
    ],
)
def test_patch_refuses_what_the_evidence_cannot_establish(image4808, params, key, value, needle):
    with pytest.raises(InputError, match=needle):
        patch(image4808, [(key, value)], params)


def test_patch_by_name_needs_parameters(image4808):
    with pytest.raises(InputError, match="needs --parameters"):
        patch(image4808, [("PWMPER", "1")])


@given(st.sampled_from(["INT", "UINT", "LONG", "ULONG"]), st.data())
def test_encode_decode_round_trip_integers(ptype, data):
    lo, hi = {"INT": (-0x8000, 0x7FFF), "UINT": (0, 0xFFFF), "LONG": (-2**31, 2**31 - 1), "ULONG": (0, 2**32 - 1)}[ptype]
    value = data.draw(st.integers(lo, hi))
    assert decode(ptype, encode(ptype, str(value), "x")) == value


@given(st.integers(-2**31, 2**31 - 1))
def test_encode_decode_round_trip_fixed(raw):
    value = Fraction(raw, 0x10000)
    assert decode("FIXED", encode("FIXED", f"{value.numerator}/{value.denominator}", "x")) == value
    assert decode("FIXED", encode("FIXED", f"0x{raw & 0xFFFFFFFF:08X}", "x")) == value


# ------------------------------------------------------------------------------------------------- diff
def test_diff_of_the_8020_variants_names_the_setup_variables():
    a, b = _load("ecmc_ipos8020_DC48V_TRQ_MODE_40A.sw"), _load("ecmc_old_DC48V.sw")
    diffs = diff(a, b)
    assert diffs and all(d.kind == "parameter" for d in diffs)
    assert {d.address for d in diffs} >= {0x0265, 0x0814}
    assert diff(a, a) == []


def test_diff_by_address_outside_the_setup_table():
    a = _load("ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.sw")
    b = _load("ecmc_ipos4808_BRUSHDC_VOLT_48V_20A_plusTML.sw")
    diffs = diff(a, b)
    assert len(diffs) == 39 and {d.a for d in diffs} == {None} and diffs[0].address == 0x4000


# ------------------------------------------------------------------------------------------------ build
def test_sample_build_spec(tmp_path):
    image = build(sample_sw_spec(tmp_path))
    kinds = [i.kind for i in describe(image)]
    assert kinds == ["setup", "identification", "pointer", "tml", "cam"]
    assert integrity_findings(image) == []
    assert parse_back(image) == image


def parse_back(image):
    from ecattool.sw import parse

    return parse(write(image))


def test_build_identification_and_replace(tmp_path, corpus):
    spec = tmp_path / "s.yaml"
    sw = corpus / "sw" / SW4808
    spec.write_text(f"base: {sw}\nidentification: P027314E221F515L\nblocks:\n"
                    f"  - start: 0x7FFF\n    words: [0]\n    replace: true\n")
    image = build(spec)
    ident = parse_identification(image.block_at(IDENT_START))
    assert ident.firmware_id == "F515L"
    assert image.word_at(0x7FFF) == 0x7ABD  # the pointer is recomputed
    assert integrity_findings(image) == []


@pytest.mark.parametrize(
    ("body", "line", "needle"),
    [
        ("blocks:\n  - start: 0x4000\n    words: [1, 0x10000]\n", 3, "not a 16-bit word"),
        ("blocks:\n  - start: 0x4000\n    words: [1]\n  - start: 0x4000\n    words: [2]\n", 4, "overlaps"),
        ("bogus: 1\n", 1, "unknown key"),
        ("blocks:\n  - from: nothere.sw\n", 2, "file not found"),
        ("blocks:\n  - start: 0x4000\n    cam: {step: 3, points: [1]}\n", 3, "power of 2"),
        ("blocks:\n  - start: 0x4000\n    words: [1]\nsetup:\n  values: {PWMPER: 1}\n", 5, "no setup table"),
    ],
)
def test_bad_build_specs_are_located(tmp_path, body, line, needle):
    spec = tmp_path / "s.yaml"
    spec.write_text(body)
    with pytest.raises(InputError) as err:
        build(spec)
    assert needle in err.value.message
    assert err.value.location.file == str(spec)
    assert err.value.location.line == line


# -------------------------------------------------------------------------------------------------- CAM
def test_cam_header_step_4_with_10_points():  # oracle G68 (derived)
    assert cam_table_words(4, list(range(10)))[0] == 0x4009


def test_cam_header_step_64_with_11_points():  # oracle G68 (derived)
    words = cam_table_words(64, [4000] * 11)
    assert words[0] == 0xC00A
    assert words[-1] == sum(words[:-1]) & 0xFFFF  # checksum = sum of all other table words
    assert len(words) == 5 + 22 + 1


def test_cam_points_low_word_first_and_detection():
    from ecattool.sw import make_image

    words = cam_table_words(64, [4000, -1], master_start=640)
    assert words[1:3] == (640, 0) and words[5:9] == (4000, 0, 0xFFFF, 0xFFFF)
    image = make_image([(0x5638, words)])
    assert cam_tables(image.blocks[0]) == [(0, 2)]
    assert describe(image)[0].kind == "cam"
    broken = make_image([(0x5638, words[:-1] + ((words[-1] + 1) & 0xFFFF,))])
    assert describe(broken)[0].kind == "data"


def test_wrong_integrity_words_are_found(image4808):
    table = setup_table(image4808)
    bad = image4808.with_words({table.block.end: 0, 0x7FFF: 0x1234, IDENT_START + 31: 0})
    rules = sorted(f.rule for f in integrity_findings(bad))
    assert rules == ["sw-ident-complement", "sw-ident-sum", "sw-pointer", "sw-setup-checksum"]
    assert fix_integrity(bad) == image4808
