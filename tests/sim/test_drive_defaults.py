"""Defaults that break a drive are caught before the drive (issue 14, item 4).

Done when: a project made by ``project new`` from ANY corpus drive ESI either commissions on the simulator or
lint names the blocking value with its line. The corpus files as they are (tests/project/test_project_new.py) and, here,
each corpus drive ESI given the defaults that stop a drive — profile velocity 0, a gear ratio with a zero part,
encoder increments 0 beside a non-zero revolution count — wherever it has those objects: ``project new`` writes
what it can (velocity, the gear's revolution count), asks for what only the machine knows (the encoder
increments), lint names that at the ESI's line (PRJ023), and once the value is given the drive commissions.
Without the value, commission names the object instead of "did not reach its target", and so does the
simulated drive (emergency 6320h naming it, a ``motion_blocked`` event).
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest
from lxml import etree

from ecattool.commission import commission
from ecattool.findings import Severity
from ecattool.project.machine import load_machine
from tests.conftest import corpus_path, run
from tests.project.test_project_new import ESIS

#: the defaults given: (index, sub, value); sub-index 0 of a VAR
BREAKING = [(0x6081, 0, 0), (0x6091, 1, 1), (0x6091, 2, 0), (0x608F, 1, 0), (0x608F, 2, 1)]


def _index(text: str | None) -> int | None:
    t = (text or "").strip().lower().replace("#x", "0x")
    try:
        return int(t, 0)
    except ValueError:
        return None


def _set_default(obj: etree._Element, sub: int, value: int) -> None:
    info = obj.find("Info")
    if info is None:
        info = etree.Element("Info")
        flags = obj.find("Flags")
        (flags.addprevious(info) if flags is not None else obj.append(info))
    if obj.find("Info/SubItem") is not None or sub:
        items = info.findall("SubItem")
        while len(items) <= sub:  # Elmo's records have no Info: one SubItem per sub-index, in order
            item = etree.SubElement(info, "SubItem")
            etree.SubElement(item, "Name").text = f"SubIndex {len(items):03d}"
            etree.SubElement(item, "Info")
            items.append(item)
        info = items[sub].find("Info")
        if info is None:
            info = etree.SubElement(items[sub], "Info")
    for old in info.findall("DefaultData") + info.findall("DefaultValue"):
        info.remove(old)
    el = etree.Element("DefaultValue")
    el.text = f"#x{value:X}"
    # Info = MinValue?, MaxValue?, DefaultValue? — after the limits, before anything else
    limits = info.findall("MinValue") + info.findall("MaxValue")
    (limits[-1].addnext(el) if limits else info.insert(0, el))


def _variant(name: str, tmp: Path) -> tuple[Path, set[int]]:
    """The corpus ESI with the breaking defaults set in every device's dictionary that has the objects."""
    tree = etree.parse(str(corpus_path("esi", name)))
    touched = set()
    for obj in tree.iter("Object"):
        index = _index(obj.findtext("Index"))
        for i, sub, value in BREAKING:
            if index == i:
                _set_default(obj, sub, value)
                touched.add(i)
    out = tmp / name
    tree.write(str(out), xml_declaration=True, encoding="utf-8")
    return out, touched


#: every corpus drive ESI (those of project new's test), and whether project new leaves a value to ask for
ASKED = {"elmo_Elmo_ECAT_00010420_V11.xml", "copley_XE2_4.60.xml"}  # the two with 608Fh


@pytest.mark.parametrize(("name", "select", "flaws"), ESIS, ids=[c[0].split("_")[0] for c in ESIS])
def test_project_new_from_a_drive_esi_with_breaking_defaults(capsys, tmp_path, name, select, flaws):
    esi, touched = _variant(name, tmp_path)
    out = tmp_path / "m.yaml"
    code, _, err = run(capsys, "project", "new", "--esi", esi.name, *(["--select", select] if select else []),
                       "-o", str(out))
    assert code == 0, err
    text = out.read_text()
    # accept the vendor file's own flaws as test_project_new does (they are not defaults)
    text = (text.replace("    # disable_rules:", "    disable_rules:").replace("    #   - {rule", "      - {rule")
            .replace("    # esi_init_cmds:", "    esi_init_cmds:").replace("    #   - {object", "      - {object"))
    out.write_text(text)
    errors = [f for f in load_machine(out).findings if f.severity is Severity.ERROR]
    # project new never writes a skeleton that fails its own lint (issue 34 item 7)
    assert errors == [], [str(f) for f in errors]
    report = commission(out)
    assert report.ok, [s.detail for d in report.drives for s in d.steps if not s.ok]
    if name not in ASKED:
        return
    # the encoder increments only the machine knows: project new names the object and the ESI's line, and leaves
    # the commissioning move out until the value is set (the drive could not convert the target)
    assert "608F:01" in text and "is 0 in the ESI" in text and "No commissioning move" in text
    assert "\n    move:" not in text and not any(s.name == "move" for d in report.drives for s in d.steps)
    # with the value and the move the comment proposes, the drive commissions with the move
    text = re.sub(r"(\n    parameters:\n)", '\\1      - {object: "608F:01", value: 4096}\n', text, count=1)
    out.write_text(text + "    move: {distance: 1}\n")
    assert [str(f) for f in load_machine(out).findings if f.severity is Severity.ERROR] == []
    report = commission(out)
    assert report.ok and any(s.name == "move" for d in report.drives for s in d.steps), \
        [s.detail for d in report.drives for s in d.steps if not s.ok]


def test_the_variants_really_carry_the_breaking_defaults(tmp_path):
    """The test above must be able to fail: each variant's device has the defaults set."""
    from ecattool.project.cache import load_device_cached

    esi, touched = _variant("copley_XE2_4.60.xml", tmp_path)
    assert touched == {0x6081, 0x6091, 0x608F}
    d = load_device_cached(esi, None, "exact")
    assert [d.dictionary.entry(i, s).default_value for i, s, _ in BREAKING] == [0, 1, 0, 0, 1]


def test_the_simulated_drive_names_the_blocking_object():
    """A PP set-point at profile velocity 0: the drive stands still and says why (EMCY 6320h, 6081h:00)."""
    from ecattool.od.model import EcState
    from ecattool.sim import Drive

    d = Drive.from_esi(corpus_path("esi", "inovance_SV660_EOE_1Axis_V9.12.xml"))
    for state in (EcState.PREOP, EcState.SAFEOP, EcState.OP):
        d.request_state(state)
    d.sdo_download(0x6060, 0, bytes([1]))
    d.sdo_download(0x6081, 0, (0).to_bytes(4, "little"))
    for cw in (0x06, 0x07, 0x0F):
        d.sdo_download(0x6040, 0, cw.to_bytes(2, "little"))
    d.sdo_download(0x607A, 0, (100).to_bytes(4, "little"))
    d.sdo_download(0x6040, 0, (0x1F).to_bytes(2, "little"))
    (m,) = [m for m in d.emergencies if m.code == 0x6320]
    assert m.to_bytes()[3:6] == bytes([0x81, 0x60, 0x00])
    assert [e.data for e in d.events if e.kind == "motion_blocked"][0]["index"] == 0x6081
