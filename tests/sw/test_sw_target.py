"""verify/download against the simulator (an independent implementation of the iPOS EEPROM objects)."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ecattool.od.model import EcState
from ecattool.sim import Drive
from ecattool.sw import download, download_plan, make_image, read, verify
from tests.conftest import corpus_path
from tests.sw.test_sw_image import images

PLUS_TML = "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A_plusTML.sw"


def sim() -> Drive:
    d = Drive.from_profile("technosoft-ipos")
    d.request_state(EcState.PREOP)
    return d


@pytest.fixture(scope="module")
def image():
    return read(corpus_path("sw", PLUS_TML))


def _programmed(image, drive):
    return all(drive.eeprom_words(b.start, b.count) == list(b.words) for b in image)


def test_blank_drive_differs_in_every_block(image):
    checks = verify(image, sim())
    assert [c.block.start for c in checks] == [0x7ABD, 0x7FBF, 0x7FFF, 0x4000]
    assert not any(c.ok for c in checks)


def test_download_writes_verifies_and_resets(image):
    d = sim()
    seen = []
    report = download(image, d, progress=lambda done, total, b: seen.append((done, total, b.start)))
    assert report.ok and report.reset
    assert _programmed(image, d)
    assert [e for e in d.events if e.kind == "reset"]
    assert seen[-1][:2] == (1341, 1341) and all(a <= b for (a, _, _), (b, _, _) in zip(seen, seen[1:]))
    assert all(c.ok for c in verify(image, d))


def test_second_download_writes_nothing(image):
    d = sim()
    download(image, d)
    writes_before = d.memory.words_written
    report = download(image, d)
    assert report.ok and report.written == [] and not report.reset
    assert d.memory.words_written == writes_before


def test_only_the_differing_block_is_rewritten(image):
    d = sim()
    download(image, d)
    d.memory.eeprom[0x4005] ^= 0x0001  # one bit flips in the TML block
    checks = verify(image, d)
    assert [c.ok for c in checks] == [True, True, True, False]
    before = d.memory.words_written
    report = download(image, d, mode=32)
    assert [b.start for b in report.written] == [0x4000]
    assert d.memory.words_written - before == 39 and report.ok


def test_plan_replayed_on_the_simulator_programs_the_image(image):
    d = sim()
    for c in download_plan(image, 32):
        d.sdo_download(c.index, c.subindex, c.data, expect_reply=c.expect_reply)
    d.request_state(EcState.PREOP)
    assert _programmed(image, d)


# ---------------------------------------------------------------------------------------- faults
def _fault_then_repair(image, inject):
    d = sim()
    inject(d)
    report = download(image, d)
    assert not report.ok and not report.reset
    bad = [c for c in report.after if not c.ok]
    assert [c.block.start for c in bad] == [0x7ABD]  # reported with the block
    assert "0x7ABD" in bad[0].describe()
    assert [c.block.start for c in verify(image, d) if not c.ok] == [0x7ABD]
    again = download(image, d)
    assert again.ok and again.reset and [b.start for b in again.written] == [0x7ABD]
    assert _programmed(image, d)
    return report


def test_lost_write_is_detected_and_repaired(image):
    # the 2065h request for the 101st word of the setup table never reaches the drive
    report = _fault_then_repair(image, lambda d: d.faults.drop_reply(4 * 2 + 2 + 100, execute=False))
    assert "timeout" in report.write_errors[0x7ABD].lower()


def test_power_loss_mid_block_is_detected_and_repaired(image):
    report = _fault_then_repair(image, lambda d: d.faults.power_loss_during_eeprom_write(after_words=600))
    assert 0x7ABD in report.write_errors


def test_sdo_abort_is_detected_and_repaired(image):
    report = _fault_then_repair(image, lambda d: d.faults.abort_sdo(4 * 2 + 2 + 700, 0x08000020))
    assert "0x08000020" in report.write_errors[0x7ABD]


def test_locked_eeprom_is_reported_not_hidden(image):
    d = sim()
    d.sdo_download(0x2091, 0, b"\x01")
    report = download(image, d)
    assert not report.ok and set(report.write_errors) == {0x7ABD, 0x7FBF, 0x7FFF, 0x4000}


def test_verify_reports_an_unreachable_drive_per_block(image):
    d = sim()
    d.faults.abort_sdo(1, 0x06020000)
    checks = verify(image, d)
    assert checks[0].error and "0x06020000" in checks[0].error and checks[0].actual is None
    assert not checks[0].ok


@settings(max_examples=15)
@given(images(), st.sampled_from([16, 32]))
def test_random_images_download_through_the_simulator(img, mode):
    d = sim()
    report = download(img, d, mode=mode)
    assert report.ok
    assert _programmed(img, d)
    assert all(c.ok for c in verify(img, d))


def test_odd_block_in_32bit_mode_leaves_the_next_word_alone():
    d = sim()
    d.memory.eeprom[0x5E09] = 0xBEEF
    report = download(make_image([(0x5E06, [0x1234, 0x5678, 0x09AB])]), d, mode=32)
    assert report.ok and d.eeprom_words(0x5E06, 4) == [0x1234, 0x5678, 0x09AB, 0xBEEF]
