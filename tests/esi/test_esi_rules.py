"""Rules true to real ESIs (ETG.2000), each shown on the corpus file where it matters (issue 22, item 4):
sync-manager kinds from ``ControlByte``, outputs spread over several sync managers, no advice a fixed PDO or a
device without a mailbox cannot follow, no finding naming a sync manager the device lacks, and an EDS used as a
device checked with its own 6502h and its product code 0 pointed out."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from ecattool import esi, pdo, profiles
from ecattool.pdo.model import default_mapping
from ecattool.esi.checks import check_device
from ecattool.esi.model import Direction, with_article
from ecattool.esi.reader import sm_kind_from_control
from ecattool.findings import Severity
from ecattool.project.machine import load_machine
from tests.conftest import corpus_path, run


@pytest.fixture(autouse=True)
def _no_disk_cache(monkeypatch: pytest.MonkeyPatch) -> None:
    # devices cached by another checkout of the same version would hide the reader's rules
    monkeypatch.setenv("ECATTOOL_NO_CACHE", "1")


def _lint(capsys, tmp_path: Path, source: Path, select: str | None = None) -> list:
    out = tmp_path / "m.yaml"
    code, _, err = run(capsys, "project", "new", "--esi", str(source), *(["--select", select] if select else []),
                       "--policy", "newest", "-o", str(out))
    assert code == 0, err
    return load_machine(out).findings


def _default_check(dev) -> list:
    dev = profiles.complete_generic(dev) if profiles.family_of(dev) == "generic" else dev
    return pdo.check(dev, default_mapping(dev))


# --- sync-manager kind from ControlByte ---------------------------------------------------------------


@pytest.mark.parametrize(("control", "has_pdos", "kind"), [
    (0x26, False, "MBoxOut"), (0x22, False, "MBoxIn"), (0x64, False, "Outputs"), (0x20, False, "Inputs"),
    (0x22, True, "Inputs"),  # one-buffer process data (EL1252, EM7004)
    (0x26, True, "Outputs"), (0x28, False, None), (0x21, False, None),  # reserved direction / mode
])
def test_control_byte_gives_the_kind(control, has_pdos, kind):
    assert sm_kind_from_control(control, has_pdos) == kind


@pytest.mark.parametrize(("folder", "name", "texts"), [
    ("sii", "pollen_Orbita2d.xml", {2: "OrbitaIn", 3: "OrbitaOut"}),  # words of its own
    ("esi", "weidmueller_UR20_FBC_from_IgH.xml", {0: "", 1: "", 2: "", 3: ""}),  # no text (made from an SII)
])
def test_sm_kind_comes_from_control_byte_where_the_text_does_not_say(capsys, tmp_path, folder, name, texts):
    doc = esi.load(corpus_path(folder, name))
    dev = doc.devices[0]
    assert [s.kind for s in dev.sync_managers] == ["MBoxOut", "MBoxIn", "Outputs", "Inputs"]
    warned = {w.data["sm"]: w for w in doc.warnings if w.rule == "esi-sm-kind"}
    assert {n: w.data["text"] for n, w in warned.items()} == texts
    assert "ControlByte #x64 makes it Outputs (ETG.2000)" in warned[2].message
    assert warned[2].location.line == next(s.location.line for s in dev.sync_managers if s.number == 2)
    # esi validate: no structural error; lint of the skeleton: no PDO018 "no Outputs sync manager"
    assert not [f for f in check_device(dev) if f.severity is Severity.ERROR]
    findings = _lint(capsys, tmp_path, corpus_path(folder, name))
    assert not [f for f in findings if f.severity is Severity.ERROR], [str(f) for f in findings]


def test_one_buffer_process_data_keeps_its_kind():
    """EL1252: SM0 carries inputs in one-buffer (mailbox) mode, ControlByte #x22; it stays Inputs."""
    doc = esi.load(corpus_path("esi", "beckhoff_EL1xxx.xml"))
    dev = esi.select(doc, "EL1252", policy="newest")
    assert (dev.sync_managers[0].kind, dev.sync_managers[0].control_byte) == ("Inputs", 0x22)
    assert not [w for w in esi.device_findings(doc, dev) if w.rule == "esi-sm-kind"]


def test_a_vendor_word_of_the_same_direction_is_read_quietly():
    """AX5206 (revision 0210): SM4 'DynamicOutputs' #x24 and SM5 'DynamicInputs' #x20."""
    doc = esi.load(corpus_path("esi", "beckhoff_AX5xxx.xml"))
    dev = next(d for d in doc.devices if len(d.sync_managers) > 5)
    assert [(s.number, s.kind) for s in dev.sync_managers[4:6]] == [(4, "Outputs"), (5, "Inputs")]
    assert not [w for w in doc.warnings if w.rule == "esi-sm-kind"]


def test_sm_direction_message_is_grammatical():
    text = corpus_path("esi", "weidmueller_UR20_FBC_from_IgH.xml").read_bytes()
    # the first RxPdo's Sm moved to the input sync manager (the file as a careless edit would leave it)
    bad = text.replace(b'<RxPdo Sm="2" Fixed="1" Mandatory="1">', b'<RxPdo Sm="3" Fixed="1" Mandatory="1">', 1)
    assert bad != text
    dev = esi.load_bytes(bad, "ur20.xml").devices[0]
    f = next(f for f in check_device(dev) if f.rule == "esi-pdo-sm-direction")
    assert "(Inputs); an RxPdo belongs in an Outputs sync manager" in f.message
    assert (with_article("Inputs"), with_article("TxPdo"), with_article("MBoxIn")) == ("an Inputs", "a TxPdo",
                                                                                        "an MBoxIn")


# --- outputs on several sync managers, fixed PDOs, devices without a mailbox ----------------------------


@pytest.mark.parametrize(("name", "select", "spread"), [
    ("smc_EX260-SECx_V11.xml", "EX260-SEC1", (Direction.RX, [0, 1, 2, 3])),
    ("itegva_E7x_Series.xml", "E7.820.004", (Direction.RX, [0, 1, 2, 3])),
    ("beckhoff_EL1xxx.xml", "EL1262", (Direction.TX, [0, 1, 2])),
])
def test_process_data_over_several_sync_managers_is_no_error(capsys, tmp_path, name, select, spread):
    dev = esi.select(esi.load(corpus_path("esi", name)), select, policy="newest")
    direction, sms = spread
    assert sorted({p.sm for p in dev.pdos(direction)}) == sms  # by design, as the vendor wrote it
    findings = _lint(capsys, tmp_path, corpus_path("esi", name), select)
    assert not [f for f in findings if f.rule in ("PDO017", "PDO003", "PDO011", "PDO018", "PDO027")], \
        [str(f) for f in findings]


def test_wrong_sm_is_still_pdo017():
    """A PDO whose Sm names a sync manager of the other direction is still reported (the Sm text agrees)."""
    text = corpus_path("esi", "weidmueller_UR20_FBC_from_IgH.xml").read_bytes()
    bad = text.replace(b'<RxPdo Sm="2" Fixed="1" Mandatory="1">', b'<RxPdo Sm="3" Fixed="1" Mandatory="1">', 1)
    dev = esi.load_bytes(bad, "ur20.xml").devices[0]
    f = next(f for f in _default_check(dev) if f.rule == "PDO017")
    assert "SM3 (Sm attribute), an Inputs sync manager, not an Outputs one" in f.message


def test_a_two_bit_fixed_terminal_without_mailbox_gets_no_padding_advice(capsys, tmp_path):
    """EL1002: two input bits in a fixed PDO on SM0, no mailbox: nothing to pad, no SM2 or SM3 to name."""
    dev = esi.select(esi.load(corpus_path("esi", "beckhoff_EL1xxx.xml")), "EL1002", policy="newest")
    assert dev.mailbox is None and [s.number for s in dev.sync_managers] == [0]
    assert sum(p.bit_size for p in dev.tx_pdos if p.sm is not None) % 8
    findings = _lint(capsys, tmp_path, corpus_path("esi", "beckhoff_EL1xxx.xml"), "EL1002")
    assert not [f for f in findings if f.rule == "PDO027"], [str(f) for f in findings]


@pytest.mark.parametrize("name", ["beckhoff_EL1xxx.xml", "smc_EX260-SECx_V11.xml", "itegva_E7x_Series.xml",
                                  "beckhoff_EK11xx.xml"])
def test_no_finding_names_a_sync_manager_the_device_lacks(name):
    doc = esi.load(corpus_path("esi", name))
    for dev in doc.devices:
        have = {s.number for s in dev.sync_managers}
        for f in _default_check(dev):
            named = {int(n) for n in re.findall(r"\bSM(\d+)", f.message)}
            assert named <= have, f"{dev.type_name}: {f}"


def test_a_padding_advice_that_can_be_followed_stays():
    """A configurable drive whose mapping ends mid-byte still gets PDO027 with the gap to add."""
    dev = esi.load(corpus_path("esi", "inovance_SV660_EOE_1Axis_V9.12.xml")).devices[0]
    dev = profiles.complete_generic(dev)
    m = pdo.Mapping.from_text(rx="0x1600=0x6040:00/16,gap/3", device=dev)
    f = [f for f in pdo.check(dev, m) if f.rule == "PDO027"]
    assert len(f) == 1 and "output image (SM2) is 19 bits" in f[0].message and "gap/5" in f[0].message


# --- an EDS used as a device ----------------------------------------------------------------------------


def test_eds_device_uses_its_own_6502h():
    """iPOS EDS: 6502h = 0x001F0065 (pp, pv, hm, ip and manufacturer modes), not the family's CSP/CSV/CST."""
    dev = esi.load(corpus_path("eds", "technosoft_iPOS.D.v1.04.eds")).devices[0]
    assert profiles.family_of(dev) == "technosoft-ipos"
    modes = profiles.rules_for(dev).supported_modes
    assert set(m for m in modes if m > 0) == {1, 3, 6, 7} and 8 not in modes
    assert -1 in modes  # Technosoft's external-reference modes: 6502h sets manufacturer bits 16-20
    assert 8 in profiles.rules_for(profiles.load("technosoft-ipos")).supported_modes  # the family has CSP


def test_eds_csp_project_is_told_the_eds_modes(capsys, tmp_path):
    findings = _lint(capsys, tmp_path, corpus_path("eds", "technosoft_iPOS.D.v1.04.eds"))
    text = (tmp_path / "m.yaml").read_text().replace("value: 1, comment: profile position mode", "value: 8")
    (tmp_path / "m.yaml").write_text(text)
    findings = load_machine(tmp_path / "m.yaml").findings
    f = next(f for f in findings if f.rule == "PRJ017")
    assert "mode 8 is not supported" in f.message and "supported: 1, 3, 6, 7" in f.message


def test_eds_product_zero_is_a_warning_in_validate_and_lint(capsys, tmp_path):
    path = corpus_path("eds", "technosoft_iPOS.D.v1.04.eds")
    dev = esi.load(path).devices[0]
    assert dev.product_code == 0
    f = next(f for f in check_device(dev) if f.rule == "esi-product-zero")
    assert f.severity is Severity.WARNING and "no ProductNumber" in f.message and f.location.line == 14
    findings = _lint(capsys, tmp_path, path)
    assert any(f.rule == "esi-product-zero" for f in findings)
    code, out, _ = run(capsys, "esi", "validate", str(path))
    assert code == 0 and "[esi-product-zero]" in out
