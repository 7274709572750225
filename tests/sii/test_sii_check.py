"""``sii check``: every corpus image passes or fails as it should; repairs; image against ESI."""

from __future__ import annotations

import os

import pytest
from hypothesis import given
from hypothesis import strategies as st

from ecattool.esi import load as load_esi
from ecattool.findings import Severity, has_errors
from ecattool.sii import check_against, check_file, fix_crc, load, parse, set_alias
from tests.conftest import corpus_files, corpus_path

#: images that must fail, with the rule that fails them and why
FAILING = {
    # EasyCAT wrote 4320 bytes into a 4096-byte EEPROM: the last categories and the END marker are lost
    "easycat_FEI_256.bin": "sii.size",
    # generated from another project (RTL_ATO): DC mode 1 names string 6 of 2
    "soes_xmc4300_slavedemo.bin": "sii.strings",
}


@pytest.mark.parametrize("path", corpus_files("sii/*.bin", form="str"))
def test_corpus_image_passes_or_fails_as_it_should(path: str) -> None:
    image, findings = check_file(path)
    assert image is not None
    errors = {f.rule for f in findings if f.severity is Severity.ERROR}
    name = os.path.basename(path)
    if name in FAILING:
        assert errors == {FAILING[name]}
    else:
        assert not errors, [str(f) for f in findings]


def test_fei_256_reports_the_missing_end_marker_too() -> None:
    _, findings = check_file(corpus_path("sii", "easycat_FEI_256.bin"))
    assert any(f.rule == "sii.end" and f.data["offset"] == 4320 for f in findings)


def test_pollen_vendor_zero_is_a_warning() -> None:
    _, findings = check_file(corpus_path("sii", "pollen_Orbita2d.bin"))
    assert [f.rule for f in findings] == ["sii.vendor"]


def test_empty_file_fails_with_a_located_reason(tmp_path) -> None:
    p = tmp_path / "empty.bin"
    p.write_bytes(b"")
    image, findings = check_file(p)
    assert image is None and [f.rule for f in findings] == ["sii.parse"]
    assert findings[0].location.file == str(p) and "empty" in findings[0].message


def test_blank_eeprom_fails(tmp_path) -> None:
    p = tmp_path / "blank.bin"
    p.write_bytes(b"\xff" * 2048)  # like ethercrab's issue-286 "empty EEPROM" dump
    _, findings = check_file(p)
    rules = {f.rule for f in findings if f.severity is Severity.ERROR}
    assert rules == {"sii.blank", "sii.crc"}
    assert all(f.location.file == str(p) for f in findings)


def test_truncated_image_fails_with_offset(tmp_path) -> None:
    p = tmp_path / "cut.bin"
    p.write_bytes(corpus_path("sii", "ni9144.bin").read_bytes()[:420])
    image, findings = check_file(p)
    assert image is None and findings[0].rule == "sii.parse"
    assert "TXPDO" not in findings[0].message and "0x0032 at byte 0x0190" in findings[0].message
    assert str(findings[0]).startswith(str(p))


def test_odd_length_and_bad_crc(tmp_path) -> None:
    raw = bytearray(corpus_path("sii", "soes_rtl_xmc4_dynpdo.bin").read_bytes())
    raw[8] ^= 1  # reserved word 4 (alias) changed without the CRC
    image = parse(bytes(raw) + b"\xff", "odd.bin")
    rules = {f.rule for f in check_from(image) if f.severity is Severity.ERROR}
    assert rules == {"sii.crc", "sii.length"}


def check_from(image):
    from ecattool.sii import check

    return check(image)


def test_fix_crc_repairs_and_changes_nothing_else() -> None:
    raw = bytearray(corpus_path("sii", "ni9144.bin").read_bytes())
    raw[14] = 0x00
    image = fix_crc(parse(bytes(raw)))
    fixed = image.to_bytes()
    assert fixed[14] == 0x0A and fixed[:14] == raw[:14] and fixed[15:] == raw[15:]


def test_set_alias_updates_word_4_and_the_crc() -> None:
    image = set_alias(load(corpus_path("sii", "ni9144.bin")), 0x1234)
    raw = image.to_bytes()
    assert raw[8:10] == b"\x34\x12"
    assert not has_errors(check_from(image))
    from ecattool.sii import crc8

    assert raw[14] == crc8(raw[:14])


def test_set_alias_out_of_range() -> None:
    from ecattool.errors import InputError

    with pytest.raises(InputError, match="out of range"):
        set_alias(load(corpus_path("sii", "ni9144.bin")), 0x10000)


def test_sm_overlap_and_pdo_sm_type_are_errors() -> None:
    image = load(corpus_path("sii", "easycat_FEI_2.bin"))
    sms = image.sync_managers
    sms[1].start = sms[0].start + 1
    sms[0].length = sms[1].length = 16
    image.rx_pdos[0].sm = 3
    rules = {f.rule for f in check_from(image) if f.severity is Severity.ERROR}
    assert rules == {"sii.sm", "sii.pdo"}


def test_dangling_string_reference_in_a_pdo_entry() -> None:
    image = load(corpus_path("sii", "easycat_FEI_2.bin"))
    image.tx_pdos[0].entries[0].name_idx = 200
    assert any(f.rule == "sii.strings" and "entry 0 name refers to string 200" in f.message
               for f in check_from(image))


# -- against an ESI -----------------------------------------------------------------------------------
PAIRS = ["ni9144", "easycat_FEI_1", "easycat_FEI_2", "easycat_FEI_5", "soes_linux_lan9252demo",
         "soes_rtl_lwip_eoe_slave30", "soes_rtl_xmc4_dynpdo", "soes_tiesc_am335xice", "metalmusings_EaserCAT_2000",
         "metalmusings_EaserCAT_3000", "asix_AX58100_EVB_DIO", "easycat_FEI_256"]


def _against(stem: str, bin_stem: str | None = None):
    image = load(corpus_path("sii", f"{bin_stem or stem}.bin"))
    esi = load_esi(corpus_path("sii", f"{stem}.xml"))
    h = image.header
    dev = next(d for d in esi.devices if (d.product_code, d.revision) == (h.product_code, h.revision))
    return check_against(dev, image)


@pytest.mark.parametrize("stem", PAIRS)
def test_generated_images_agree_with_their_esi(stem: str) -> None:
    findings = _against(stem)
    assert not has_errors(findings), [str(f) for f in findings]


def test_lan9252_coe_details_differ_from_the_esi() -> None:
    findings = _against("soes_linux_lan9252demo")
    assert [f.data["field"] for f in findings if f.severity is Severity.WARNING] == ["general.coe_details"]


def test_ni9144_rev1_dump_against_the_rev2_device_is_a_pdo_mismatch() -> None:
    image = load(corpus_path("sii", "ni9144_rev1.bin"))
    esi = load_esi(corpus_path("sii", "ni9144.xml"))
    rev2 = next(d for d in esi.devices if d.revision == 2)
    findings = check_against(rev2, image)
    assert {f.rule for f in findings if f.severity is Severity.ERROR} == {"sii.esi.identity", "sii.esi.pdo"}


def test_pollen_vendor_id_mismatch_is_named() -> None:
    findings = _against("pollen_Orbita2d")
    errors = [f for f in findings if f.severity is Severity.ERROR]
    # siitool wrote SM2/SM3 as unused because the ESI names them 'OrbitaIn'/'OrbitaOut'; their ControlBytes
    # (#x64, #x20) make them Outputs and Inputs (ETG.2000), and a master that finds its process-data sync
    # managers by the SII type (SOEM) would map none: a real difference of the image
    assert [f.data["field"] for f in errors] == ["header.vendor_id", "sm[2].type", "sm[3].type"]
    assert "0xF3F in the ESI" in errors[0].message


@given(st.integers(0, 0xFFFF))
def test_oracle_controltechniques_21_alias_n_is_sii_word_4(alias: int) -> None:
    """reference/controltechniques/oracles.md #21: after storing alias N (0-65535), SII word 0x0004 = N."""
    from ecattool.sii import crc8

    raw = set_alias(load(corpus_path("sii", "soes_tiesc_am335xice.bin")), alias).to_bytes()
    assert int.from_bytes(raw[2 * 0x0004:2 * 0x0004 + 2], "little") == alias
    assert raw[14] == crc8(raw[:14])
