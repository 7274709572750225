"""Download plans: write for write against the corpus .cmd, the manual's 16/32-bit examples, odd blocks."""

from __future__ import annotations

import re

import pytest
from hypothesis import given
from hypothesis import strategies as st

from ecattool.startup.model import StartupList
from ecattool.sw import config_value, download_plan, make_image, parse, read
from ecattool.sw.plan import eeprom_writes
from tests.conftest import corpus_path
from tests.sw.test_sw_image import images

_WRITE = re.compile(r"EcWriteSdo\(\$\{ECMC_EC_SLAVE_NUM\},(0x[0-9A-Fa-f]+),0x0,(0x[0-9A-Fa-f]+|\d+),(\d)\)")


def _cmd_writes(name: str) -> list[tuple[int, int, int]]:
    text = corpus_path("sw", name).read_text()
    return [(int(i, 16), int(v, 0), int(n)) for i, v, n in _WRITE.findall(text)]


def test_16bit_plan_equals_the_corpus_cmd_write_for_write():
    image = read(corpus_path("sw", "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A_plusTML.sw"))
    ref = [(i, v) for i, v, _ in _cmd_writes("ecmc_ipos4808_BRUSHDC_VOLT_48V_20A_plusTML.cmd") if i in (0x2064, 0x2065)]
    ours = [(c.index, c.int_value) for c in download_plan(image, 16) if c.index in (0x2064, 0x2065)]
    assert len(ref) == 4 + 1341
    assert ours == ref


def test_plan_checksum_requests_agree_with_the_cmd_and_cover_the_last_block_too():
    image = read(corpus_path("sw", "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A_plusTML.sw"))
    ref = [v for i, v, _ in _cmd_writes("ecmc_ipos4808_BRUSHDC_VOLT_48V_20A_plusTML.cmd") if i == 0x2069]
    ours = [c.int_value for c in download_plan(image) if c.index == 0x2069]
    # the other tool never closes the last block (the file has no final blank line); ecattool does
    assert ours[:3] == ref == [0x7FAF7ABD, 0x7FE07FBF, 0x7FFF7FFF]
    assert ours[3] == 0x40264000


def test_plan_ends_with_the_reset_that_gets_no_reply():
    image = read(corpus_path("sw", "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.sw"))
    plan = download_plan(image)
    assert isinstance(plan, StartupList)
    last = plan.commands[-1]
    cmd_reset = [(i, v, n) for i, v, n in _cmd_writes("ecmc_ipos4808_BRUSHDC_VOLT_48V_20A_plusTML.cmd") if i == 0x2080]
    assert (last.index, last.int_value, len(last.data)) == cmd_reset[0] == (0x2080, 1, 2)
    assert last.expect_reply is False
    assert sum(c.index == 0x2080 for c in plan) == 1
    assert all(not c.verify for c in plan if c.index == 0x2065)


def test_16bit_example_block_5638():  # oracle G58 (§17.4, Fig. 17.4.1)
    plan = download_plan(parse("5638\nC400\n0\n\n"), 16, reset=False)
    assert [(c.index, c.int_value) for c in plan] == [
        (0x2064, 0x56380008), (0x2065, 0x0000C400), (0x2065, 0x00000000), (0x2069, 0x56395638)]
    assert [c.data for c in plan][:2] == [bytes.fromhex("08003856"), bytes.fromhex("00C40000")]


def test_cam_download_config_value():  # oracle G59: 2064h <- 0xXXXX0008
    assert config_value(0x5638) == 0x56380008


def test_32bit_example_block_5e06():  # oracle G62 (§17.4.1)
    plan = download_plan(parse("5E06\n1234\n5678\n09AB\nCDEF\n"), 32, reset=False)
    assert [(c.index, c.int_value) for c in plan] == [
        (0x2064, 0x5E060009), (0x2065, 0x56781234), (0x2065, 0xCDEF09AB), (0x2069, 0x5E095E06)]


def test_32bit_odd_block_never_writes_past_its_end():
    plan = download_plan(parse("5E06\n1234\n5678\n09AB\n"), 32, reset=False)
    assert [(c.index, c.int_value) for c in plan] == [
        (0x2064, 0x5E060009), (0x2065, 0x56781234), (0x2064, 0x5E080008), (0x2065, 0x000009AB), (0x2069, 0x5E085E06)]
    assert set(eeprom_writes(plan)) == {0x5E06, 0x5E07, 0x5E08}


def test_single_word_block_in_32bit_mode():
    # issue 27: one 2064h per one-word block (16-bit at once), not a 32-bit selection undone by the 16-bit one
    plan = download_plan(parse("7FFF\n7ABD\n"), 32, reset=False)
    assert [(c.index, c.int_value) for c in plan] == [(0x2064, 0x7FFF0008), (0x2065, 0x7ABD), (0x2069, 0x7FFF7FFF)]
    assert eeprom_writes(plan) == {0x7FFF: 0x7ABD}


def test_a_32bit_plan_of_one_word_blocks_selects_the_address_once_per_block():
    plan = download_plan(parse("0010\n1111\n\n0020\n2222\n\n0030\n3333\n4444\n"), 32, reset=True)
    assert [c.int_value for c in plan if c.index == 0x2064] == [0x00100008, 0x00200008, 0x00300009]
    assert eeprom_writes(plan) == {0x10: 0x1111, 0x20: 0x2222, 0x30: 0x3333, 0x31: 0x4444}
    # EEPROM programming is written once, the reset last and without a reply
    assert all(c.one_shot for c in plan) and [c.kind for c in plan][-2:] == ["once", "reset"]


def test_2069_value_is_zero_padded_in_the_comment_and_data():
    plan = download_plan(parse("0010\n1\n"), 16, reset=False)
    req = plan.commands[-1]
    assert req.data == bytes.fromhex("10001000") and req.int_value == 0x00100010


@pytest.mark.parametrize("mode", [16, 32])
def test_corpus_plans_write_exactly_the_image(mode, corpus):
    for path in sorted((corpus / "sw").glob("*.sw")):
        if path.name == "march_imc_rotational_joint.sw":
            continue
        image = read(path)
        assert eeprom_writes(download_plan(image, mode)) == image.words()


def test_bad_mode_is_refused():
    with pytest.raises(ValueError):
        download_plan(make_image([(0, [1])]), 8)


@given(images(), st.sampled_from([16, 32]))
def test_plans_round_trip_to_the_image(image, mode):
    plan = download_plan(image, mode)
    assert eeprom_writes(plan) == image.words()
    per_write = 2 if mode == 32 else 1
    writes = [c for c in plan if c.index == 0x2065]
    assert len(writes) == sum(b.count // per_write + b.count % per_write for b in image)
    assert [c.int_value for c in plan if c.index == 0x2069] == [b.checksum_request for b in image]
    assert all(len(c.data) == 4 for c in plan if c.index != 0x2080)
