"""An ESI that contradicts itself (issue 35 item 7): a mapping object whose DefaultData in the dictionary lays out
other entries than its ``<RxPdo>``/``<TxPdo>`` element. It is a located finding (``esi-pdo-default-differs``) of
``esi validate`` and lint, and the SII builder, ``map layout`` and the served slave agree on one choice: the
dictionary's, which the slave powers on with and every CoE master reads (docs/decisions.md, "An ESI that
contradicts itself"). The crafted files derive from the Synapticon CiA402 ESI of the corpus; the sweep runs
every corpus ESI."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from ecattool.esi import load
from ecattool.esi import validate
from tests.conftest import ROOT, run

CORPUS = ROOT.parent / "shared" / "corpus" / "esi"
SOURCE = CORPUS / "synapticon_Somanet_CiA402-single.xml"
#: the dictionary's 1600h (line 511 of the corpus file) and its RxPdo element (line 875)
OBJECT_LINE, ELEMENT_LINE = 510, 874

pytestmark = pytest.mark.skipif(not SOURCE.is_file(), reason="../shared/corpus is not here")


def _agreeing(tmp_path: Path) -> Path:
    """The corpus file with its RxPdo element naming the sub-indices its dictionary's 1600h maps (the vendor's
    file maps 607Ah:04 and 60FFh:05 in the element, :00 in the object): both agree."""
    text = SOURCE.read_text(encoding="utf-8")
    for index, sub in (("607A", "4"), ("60FF", "5")):
        old = f"<Index>#x{index}</Index>\n\t\t\t\t\t\t<SubIndex>{sub}</SubIndex>"
        assert text.count(old) == 1, old
        text = text.replace(old, f"<Index>#x{index}</Index>\n\t\t\t\t\t\t<SubIndex>0</SubIndex>")
    path = tmp_path / "agree.xml"
    path.write_text(text, encoding="utf-8")
    return path


def _contradicting(tmp_path: Path) -> Path:
    """The agreeing file with the dictionary's 1600h entry 5 saying 60B8h:00/16 where the element says
    60FFh:00/32: the issue's case (a served slave of 11 output bytes, an element of 13)."""
    text = _agreeing(tmp_path).read_text(encoding="utf-8")
    old = "<DefaultData>2000FF60</DefaultData>"
    assert text.count(old) == 1
    path = tmp_path / "contra.xml"
    path.write_text(text.replace(old, "<DefaultData>1000B860</DefaultData>"), encoding="utf-8")
    return path


def test_esi_validate_locates_the_contradiction_and_says_nothing_where_both_agree(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert [f for f in validate(_agreeing(tmp_path)) if f.rule == "esi-pdo-default-differs"] == []
    path = _contradicting(tmp_path)
    (f,) = [f for f in validate(path) if f.rule == "esi-pdo-default-differs"]
    assert f.severity.name == "ERROR" and f.location is not None
    assert (f.location.file, f.location.line) == (str(path), OBJECT_LINE)
    assert f"RxPdo element (line {ELEMENT_LINE})" in f.message and "0x60B8:00/16" in f.message
    assert "0x60FF:00/32" in f.message and "88 bits against 104" in f.message
    _, out, _ = run(capsys, "esi", "validate", str(path))
    assert f"{path}:{OBJECT_LINE}: error:" in out and "[esi-pdo-default-differs]" in out


def test_lint_reports_it_once_where_the_project_keeps_the_power_on_mapping_and_not_where_it_programs_one(
        tmp_path: Path) -> None:
    from ecattool.project.machine import load_machine

    _contradicting(tmp_path)
    keep = tmp_path / "keep.yaml"
    keep.write_text("ecattool: 1\ndrives:\n  - name: a\n    device: {esi: contra.xml}\n", encoding="utf-8")
    # once, at the ESI's line: PRJ027 (the project keeps the mapping the ESI contradicts; pdo: programs one)
    found = [f for f in load_machine(keep).findings if f.location is not None and f.location.line == OBJECT_LINE]
    assert [(f.rule, f.severity.name) for f in found] == [("PRJ027", "ERROR")]
    # the same image with other objects: PRJ027 leaves it to the ESI finding, a warning
    same = tmp_path / "same.xml"
    same.write_text(SOURCE.read_text(encoding="utf-8"), encoding="utf-8")  # the vendor's 607Ah:00 against :04
    keep.write_text("ecattool: 1\ndrives:\n  - name: a\n    device: {esi: same.xml}\n", encoding="utf-8")
    found = [f for f in load_machine(keep).findings if f.rule in ("esi-pdo-default-differs", "PRJ027")]
    assert [(f.rule, f.severity.name, f.location.line) for f in found] == [  # type: ignore[union-attr]
        ("esi-pdo-default-differs", "WARNING", OBJECT_LINE)]
    given = tmp_path / "given.yaml"
    given.write_text("ecattool: 1\ndrives:\n  - name: a\n    device: {esi: contra.xml}\n    pdo:\n      rx:\n"
                     "        - {index: 0x1600, entries: [0x6040:00/16, 0x6060:00/8, 0x6071:00/16, 0x607A:00/32]}\n",
                     encoding="utf-8")
    assert [f for f in load_machine(given).findings if f.rule == "esi-pdo-default-differs"] == []


def test_the_sii_map_layout_and_the_served_slave_agree_on_the_dictionary(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from ecattool.od.model import EcState
    from ecattool.sii.builder import build
    from ecattool.sii.model import CategoryType
    from ecattool.sim.slave import drive_for_device

    device = load(_contradicting(tmp_path)).devices[0]
    held = [0x60400010, 0x60600008, 0x60710010, 0x607A0020, 0x60B80010]
    # the served slave: its 1600h as a master reads it over CoE
    drive = drive_for_device(device)
    drive.request_state(EcState.PREOP)
    count = drive.sdo_upload(0x1600, 0)[0]
    served = [int.from_bytes(drive.sdo_upload(0x1600, s), "little") for s in range(1, count + 1)]
    assert served == held
    # the SII's RXPDO category
    (sii_pdo,) = [p for p in build(device).pdos(CategoryType.RXPDO) if p.index == 0x1600]
    assert [(e.index << 16) | (e.subindex << 8) | e.bit_len for e in sii_pdo.entries] == held
    # map layout: 11 bytes (the element's 13 would be 104 bits)
    _, out, _ = run(capsys, "map", "layout", "--esi", str(tmp_path / "contra.xml"), "--json")
    doc = json.loads(out)
    outputs = doc["outputs"]
    assert doc["power_on_from_dictionary"] == ["0x1600"]
    assert outputs["bits"] == sum(v & 0xFF for v in held) == 88
    _, text, _ = run(capsys, "map", "layout", "--esi", str(tmp_path / "contra.xml"))
    assert "Outputs SM2 (11 bytes, 88 bits)" in text and "note: PDO 0x1600 is drawn as the slave powers on" in text


def test_the_corpus_sweep_finds_only_the_files_known_to_contradict_themselves() -> None:
    """Every mapping object of the corpus ESIs with its own complete default (885 PDOs at the time of writing)
    against its PDO element: only the known self-contradicting files are reported (the EM7004's 1601h-1609h
    shifted by one, the EL6688/EL6690/EL6695 bridge PDOs: docs/decisions.md, "Machine: the corpus sweep"; the
    Inovance SV660N's 1702h, the issue's 60B8h against 60FFh; the Synapticon file's 607Ah:00 against :04), and
    trailing padding (the EL6692's 1600h) is no difference."""
    from ecattool.esi.power_on import contradictions, own_mapping_values, without_trailing_padding

    known = {("beckhoff_EM7xxx.xml", "EM7004"), ("beckhoff_EL66xx.xml", "EL6688"), ("beckhoff_EL66xx.xml", "EL6690"),
             ("beckhoff_EL66xx.xml", "EL6695"), ("beckhoff_EL66xx.xml", "EL6695-0002"),
             ("inovance_SV660_EOE_1Axis_V9.12.xml", "InoSV660N"),
             ("synapticon_Somanet_CiA402-single.xml", "CiA402 Motor Control Device")}
    reported: set[tuple[str, str]] = set()
    own = padded = 0
    for path in sorted(CORPUS.glob("*.xml")):
        for device in load(path).devices:
            found = contradictions(device)
            reported |= {(path.name, device.type_name) for _ in found[:1]}
            differing = {c.pdo.index for c in found}
            for pdo in (*device.rx_pdos, *device.tx_pdos):
                held = own_mapping_values(device, pdo.index)
                if held is None or pdo.index in differing or device.esc_registers(pdo):
                    continue
                own += 1
                listed = [e.mapping_value for e in pdo.entries]
                padded += held != listed
                assert without_trailing_padding(held) == without_trailing_padding(listed)
    assert reported == known
    assert own > 800 and padded >= 1  # both agree in every other mapping object, the EL6692's padding included


def test_trailing_padding_is_no_finding_but_the_sii_holds_it_as_the_slave_does() -> None:
    """The EL6692's 1600h: a gap of 8 bits in the dictionary against an empty RxPdo element. No finding (the same
    data), and the SII's RXPDO category holds the gap, as the power-on mapping (``pdo.default_mapping``, ``map
    layout``) and the served slave do: a master without CoE lays out the same byte."""
    from ecattool.esi.power_on import contradictions
    from ecattool.pdo import default_mapping
    from ecattool.sii.builder import build
    from ecattool.sii.model import CategoryType

    device = next(d for d in load(CORPUS / "beckhoff_EL66xx.xml").devices if d.type_name == "EL6692")
    assert device.pdo(0x1600) is not None and device.pdo(0x1600).entries == []  # type: ignore[union-attr]
    assert contradictions(device) == []
    (mapped,) = [p for p in default_mapping(device).rx if p.index == 0x1600]
    (sii_pdo,) = [p for p in build(device).pdos(CategoryType.RXPDO) if p.index == 0x1600]
    assert [e.mapping_value for e in mapped.entries] == [(e.index << 16) | (e.subindex << 8) | e.bit_len
                                                         for e in sii_pdo.entries] == [0x00000008]
