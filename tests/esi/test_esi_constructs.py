"""Issue 34, the file side: the ETG.2000 constructs of the Beckhoff families added to the corpus (virtual PDOs and
sync managers, partial entries, standard objects a dictionary leaves out, mapping objects that differ from the PDO
list, slaves without a mailbox, identifiers written with two prefixes), each through lint, ``project new`` and
the in-process simulator, on the corpus files themselves (../shared/corpus/esi, SOURCES.md section "Added")."""

from __future__ import annotations

from pathlib import Path

import pytest

from ecattool.commission import commission
from ecattool.errors import SdoTimeout
from ecattool.esi.checks import check_device
from ecattool.esi.model import Direction
from ecattool.findings import Finding, Severity
from ecattool.od.model import EcState
from ecattool.pdo import Mapping, check, default_mapping, layout, program
from ecattool.project.cache import load_device_cached, load_esi_cached
from ecattool.project.machine import Machine, load_machine
from ecattool.project.skeleton import esi_flaws, new_project, resolve
from ecattool.sim import Drive
from tests.conftest import CORPUS, need_corpus

need_corpus()
ESI = CORPUS / "esi"

EL1252 = (ESI / "beckhoff_EL1xxx.xml", "0x2:0x4E43052:0x110000")  # latch PDOs 1A10h-1A15h, virtual SM1/SM2
EL4712 = (ESI / "beckhoff_EL47xx.xml", "0x2:0x12683052:0x0")  # its only Inputs SM is virtual (0998h)
EQ2339 = (ESI / "beckhoff_EQ2xxx.xml", "0x2:0x9234452:0x100016")  # outputs over SM0 and SM1, one byte each
ER5101 = (ESI / "beckhoff_ER5xxx.xml", "0x2:0x13ED4852:0x130002")  # 16-bit entries of 32-bit 6000h:11/7000h:11
EJ3202 = (ESI / "beckhoff_EJ3xxx.xml", "0x2:0xC822852:0x130000")  # maps 1800h:07/09, which its dictionary lacks
EL6692 = (ESI / "beckhoff_EL66xx.xml", "0x2:0x1A243052:0x100000")  # 1600h: a gap of 8 bits against an empty PDO
EL6695_2 = (ESI / "beckhoff_EL66xx.xml", "0x2:0x1A273052:0x20002")  # 1A01h: the dictionary's layout differs
EX260 = (ESI / "smc_EX260-SECx_V11.xml", "0")  # no mailbox: a fixed process image


def _project(tmp_path: Path, esi: Path, select: str, extra: str = "") -> Path:
    """The skeleton ``project new`` writes for the device (plus ``extra`` lines), saved in ``tmp_path``."""
    device = resolve(None, None, str(esi), select, tmp_path)
    text = new_project(device, esi=str(esi), select=select, findings=esi_flaws(str(esi), select, tmp_path))
    path = tmp_path / "project.yaml"
    path.write_text(text + extra, encoding="utf-8")
    return path


def _errors(machine: Machine) -> list[Finding]:
    return [f for f in machine.findings if f.severity is Severity.ERROR]


def _rules(findings: list[Finding]) -> set[str]:
    return {f.rule for f in findings}


# --- 1. virtual PDOs and sync managers --------------------------------------------------------------------


def test_a_virtual_pdo_without_a_real_sm_is_never_assigned_nor_a_duplicate() -> None:
    device = load_device_cached(*EL1252, "exact")
    virtual = {p.index for p in device.tx_pdos if p.virtual}
    assert virtual == {0x1A10, 0x1A11, 0x1A12, 0x1A13, 0x1A14, 0x1A15}
    # 1A13h names Sm="1", which is Virtual="true" (beckhoff_EL1xxx.xml: <Sm StartAddress="#x09ae" Virtual="true">)
    assert device.sm(1) is not None and device.sm(1).virtual
    assert all(device.esc_registers(p) for p in device.tx_pdos if p.virtual)
    assert not {p.index for p in default_mapping(device).tx} & virtual
    assert device.process_sm(Direction.TX) is not None and device.process_sm(Direction.TX).number == 0
    raw = load_esi_cached(EL1252[0])
    structural = check_device(next(d for d in raw.devices if d.location == device.location))
    assert not [f for f in structural if f.severity is Severity.ERROR], structural


def test_a_virtual_sm_is_no_process_data_sm() -> None:
    device = load_device_cached(*EL4712, "exact")
    assert [s.number for s in device.sync_managers if s.virtual] == [2]
    assert device.process_sm(Direction.TX) is None  # its inputs are ESC registers only
    assert default_mapping(device).tx == []


def test_the_sii_built_from_the_device_lists_no_register_window_pdo() -> None:
    """A master without CoE lays out its SMs from the SII's PDO categories (SOEM sums every PDO with an SM number):
    the EL4712's virtual TxPDO 1A82h on its virtual SM2 made SOEM lay out 4 input bytes over register 0998h that
    the mapping leaves out (the whole-bus wire sweep: "the input image is 4 byte(s), the mapping lays out 0").
    The virtual SM stays in the SyncM category (SM numbers unchanged), flagged virtual (enable bit 2)."""
    from ecattool.sii.builder import build
    from ecattool.sii.model import CategoryType, PdoCategory, SyncMCategory

    for ref, kept in ((EL4712, set()), (EL1252, {0x1A00, 0x1A01, 0x1A02})):
        device = load_device_cached(*ref, "exact")
        image = build(device)
        tx = {p.index for c in image.categories if isinstance(c, PdoCategory) and c.type == CategoryType.TXPDO
              for p in c.pdos}
        assert tx == {p.index for p in device.tx_pdos if not device.esc_registers(p)}, ref
        assert kept <= tx and not tx & {p.index for p in device.tx_pdos if p.virtual}, ref
        sms = next(c for c in image.categories if isinstance(c, SyncMCategory)).sync_managers
        assert [n for n, sm in enumerate(sms) if sm.enable & 0x04] == [s.number for s in device.sync_managers
                                                                      if s.virtual], ref


def test_a_project_that_selects_a_virtual_pdo_gets_it_left_out_with_a_note(tmp_path: Path) -> None:
    device = load_device_cached(*EL1252, "exact")
    tx = ";".join(f"0x{p.index:04X}" for p in default_mapping(device).tx) + ";0x1A13"
    mapping = Mapping.from_text(tx=tx, device=device)
    findings = check(device, mapping)
    assert [f.rule for f in findings if f.rule != "PDO024"] == ["PDO029"]  # 1A02h has no entries: PDO024
    assert 0x1A13 not in layout(device, mapping).inputs.pdos
    assert not [c for c in program(device, mapping).commands if c.value == 0x1A13]
    # lint, the startup list and the simulator agree: the project commissions with the PDO left out
    entries = "".join(f"        - {{index: 0x{p.index:04X}}}\n" for p in default_mapping(device).tx)
    path = _project(tmp_path, *EL1252, "    pdo:\n      tx:\n" + entries + "        - {index: 0x1A13}\n")
    machine = load_machine(path)
    assert not _errors(machine) and "PDO029" in _rules(machine.findings)
    assert machine.slaves[0].mapping is not None and 0x1A13 not in {p.index for p in machine.slaves[0].mapping.tx}
    from ecattool.project.export import slave_configs
    from ecattool.startup.formats import eni

    (config,) = slave_configs(machine)
    assert not [c for c in config.commands if c.value == 0x1A13 or c.index == 0x1A13]
    exported = eni.export([config]).upper()  # the ENI's process data: the default PDOs, not the latch window
    assert "#X1A00" in exported and "#X1A13" not in exported
    assert commission(machine).ok


def test_outputs_over_two_sync_managers_are_sized_per_sync_manager(tmp_path: Path) -> None:
    """EQ2339-0022: 1600h-1607h on SM0 and 1608h-160Fh on SM1 (MaxSize 1 each). The simulator refused SAFE-OP
    with '2 bytes exceed SM0 maximum 1' while lint, sizing each SM by the PDOs its Sm attribute names, was clean."""
    machine = load_machine(_project(tmp_path, *EQ2339))
    assert not _errors(machine)
    report = commission(machine)
    assert report.ok, report.drives[0].error


# --- 2. partial entries ------------------------------------------------------------------------------------


def test_a_compact_entry_is_a_note_and_the_simulator_serves_its_low_bits(tmp_path: Path) -> None:
    device = load_device_cached(*ER5101, "exact")
    notes = [f for f in esi_flaws(str(ER5101[0]), ER5101[1], tmp_path) if f.rule == "esi-pdo-partial"]
    assert notes and all(f.severity is Severity.INFO for f in notes)
    assert not [f for f in esi_flaws(str(ER5101[0]), ER5101[1], tmp_path) if f.rule == "esi-pdo-bitlen"]
    machine = load_machine(_project(tmp_path, *ER5101))
    assert not _errors(machine)
    assert commission(machine).ok
    drive = Drive.from_device(device)
    for state in (EcState.PREOP, EcState.SAFEOP, EcState.OP):
        drive.request_state(state)
    lay = layout(device, default_mapping(device))
    counter = next(e for e in lay.inputs.entries if (e.index, e.subindex) == (0x6000, 0x11))
    assert counter.bit_len == 16 and device.dictionary.entry(0x6000, 0x11).bit_size == 32
    drive._store[(0x6000, 0x11)] = (0x12345678).to_bytes(4, "little")
    inputs = drive.exchange(bytes(lay.outputs.byte_size))
    assert inputs[counter.byte:counter.byte + 2] == (0x5678).to_bytes(2, "little")
    # an output entry of 16 bits replaces the low half of its 32-bit object, the high half stays
    out = next(e for e in lay.outputs.entries if (e.index, e.subindex) == (0x7000, 0x11))
    drive._store[(0x7000, 0x11)] = (0xABCD0000).to_bytes(4, "little")
    image = bytearray(lay.outputs.byte_size)
    image[out.byte:out.byte + 2] = (0x1234).to_bytes(2, "little")
    drive.exchange(bytes(image))
    assert drive._store[(0x7000, 0x11)] == (0xABCD1234).to_bytes(4, "little")


# --- 3. standard objects a dictionary leaves out -----------------------------------------------------------


def test_txpdo_state_and_toggle_are_standard_objects_the_simulator_serves(tmp_path: Path) -> None:
    flaws = esi_flaws(str(EJ3202[0]), EJ3202[1], tmp_path)
    standard = [f for f in flaws if f.rule == "esi-pdo-standard-object"]
    assert {"0x1800:07", "0x1800:09"} <= {f.message.split(" maps ")[1].split(" ")[0] for f in standard}
    assert all(f.severity is Severity.INFO for f in standard)
    assert "esi-pdo-object-missing" not in _rules(flaws)
    machine = load_machine(_project(tmp_path, *EJ3202))
    assert not _errors(machine)
    assert commission(machine).ok
    drive = Drive.from_device(load_device_cached(*EJ3202, "exact"))
    drive.request_state(EcState.PREOP)
    assert drive.sdo_upload(0x1800, 7) == b"\x00"  # the TxPDO state, by SDO too


def test_an_object_outside_the_communication_area_stays_an_error(tmp_path: Path) -> None:
    """Synapticon's 607Ah:04: 607Ah is a VAR (CiA 402), no device has a sub-index 4 of it."""
    esi = ESI / "synapticon_Somanet_CiA402-single.xml"
    flaws = esi_flaws(str(esi), None, tmp_path)
    assert any(f.rule == "esi-pdo-object-missing" and "0x607A:04" in f.message for f in flaws)


# --- 4. the dictionary's mapping objects against the PDO list ----------------------------------------------


def test_trailing_padding_is_the_same_mapping(tmp_path: Path) -> None:
    """EL6692: its dictionary's 1600h maps 0x00000008 (a gap), its RxPdo 1600h nothing; it was PRJ027."""
    device = load_device_cached(*EL6692, "exact")
    rx = default_mapping(device).rx
    assert [(p.index, [e.mapping_value for e in p.entries]) for p in rx] == [(0x1600, [0x00000008])]
    machine = load_machine(_project(tmp_path, *EL6692))
    assert "PRJ027" not in _rules(machine.findings)
    assert not _errors(machine)
    assert commission(machine).ok


def test_project_new_programs_the_pdo_list_where_the_dictionary_differs(tmp_path: Path) -> None:
    """EL6695-0002: the dictionary's 1A01h holds a gap of 11 bits, toggle, state, a gap of 2, the ESI's TxPdo a
    gap of 12, toggle, state, a gap of 1. In the file 1A01h is Fixed and read-only, so the slave keeps its own
    (PRJ027, a documented refusal; a pdo: would not program it: PDO023); made configurable (not Fixed, rw),
    ``project new`` writes the PDO list as pdo: and commission programs it."""
    machine = load_machine(_project(tmp_path, *EL6695_2))
    assert "PRJ027" in _rules(_errors(machine))
    assert "pdo:" not in (tmp_path / "project.yaml").read_text(encoding="utf-8")
    device = load_device_cached(*EL6695_2, "exact")
    line = next(p for p in device.tx_pdos if p.index == 0x1A01).location.line
    lines = EL6695_2[0].read_text(encoding="utf-8").splitlines(keepends=True)
    assert lines[line - 1].strip() == '<TxPdo Fixed="1" Sm="3">'
    lines[line - 1] = lines[line - 1].replace(' Fixed="1"', "")
    # the object and its data type DT1A01 (the device's own, before its objects) are read-only: made rw
    obj = device.dictionary.get(0x1A01).location.line
    dt = next(k for k in range(obj, device.location.line, -1) if "<Name>DT1A01</Name>" in lines[k])
    end = next(k for k in range(obj, len(lines)) if "</Object>" in lines[k])
    dt_end = next(k for k in range(dt, obj) if "</DataType>" in lines[k])
    for k in (*range(dt, dt_end), *range(obj, end)):
        lines[k] = lines[k].replace("<Access>ro</Access>", "<Access>rw</Access>")
    esi = tmp_path / "el6695.xml"
    esi.write_text("".join(lines), encoding="utf-8")
    text_path = _project(tmp_path, esi, EL6695_2[1])
    text = text_path.read_text(encoding="utf-8")
    assert "another power-on mapping than its PDO list" in text and "pdo:" in text
    assert '[gap/12, "0x1801:09/1", "0x1801:07/1", gap/1, "0x10F4:10/1"]' in text
    machine = load_machine(text_path)
    assert not _errors(machine), _errors(machine)
    report = commission(machine)
    assert report.ok, report.drives[0].error


# --- 5. slaves without a mailbox ---------------------------------------------------------------------------


def test_a_slave_without_a_mailbox_is_never_sent_an_sdo(tmp_path: Path) -> None:
    device = load_device_cached(*EX260, "exact")
    assert device.mailbox is None
    drive = Drive.from_device(device)
    drive.request_state(EcState.PREOP)
    with pytest.raises(SdoTimeout):
        drive.sdo_upload(0x1018, 1)
    machine = load_machine(_project(tmp_path, *EX260))
    assert not _errors(machine)
    report = commission(machine)
    assert report.ok, report.drives[0].error
    steps = {s.name: s.detail for s in report.drives[0].steps}
    assert steps["identity"].endswith("(EEPROM)")
    assert "read back by SDO" not in steps["process data"]


def test_lint_refuses_a_parameter_for_a_slave_without_a_mailbox(tmp_path: Path) -> None:
    path = _project(tmp_path, *EX260, '    parameters:\n      - {object: "3101:01", value: 1}\n')
    machine = load_machine(path)
    assert "PRJ028" in _rules(_errors(machine))
    assert not commission(machine).ok  # what lint said: nothing answers the SDO


def test_dummies_name_no_object() -> None:
    from ecattool.esi.model import Pdo, PdoEntry

    device = load_device_cached(*EJ3202, "exact")
    pdo = Pdo(Direction.RX, 0x1700, "padded", [PdoEntry(0x0005, 0, 8), PdoEntry(0x0002, 0, 8)])
    probe = type(device)(device.identity, "probe", rx_pdos=[pdo], dictionary=device.dictionary)
    assert not [f for f in check_device(probe) if f.rule == "esi-pdo-object-missing"]


# --- 6. identifiers with two prefixes ----------------------------------------------------------------------


def test_lint_reports_an_index_read_with_two_prefixes(tmp_path: Path) -> None:
    text = EX260[0].read_text(encoding="latin-1")
    esi = tmp_path / "ex260.xml"
    esi.write_text(text.replace("<Index>#x3101</Index>", "<Index>#x0x3101</Index>", 1), encoding="latin-1")
    machine = load_machine(_project(tmp_path, esi, "0"))
    hits = [f for f in machine.findings if f.rule == "esi-number-0x"]
    assert hits and hits[0].location is not None and hits[0].location.line == 31
    assert "read as hex" in hits[0].message


# --- 7. project new never writes a skeleton that fails its own lint ---------------------------------------


def test_a_skeleton_leaves_out_the_move_where_the_encoder_resolution_is_0() -> None:
    """An ESI whose 608Fh:01 (encoder increments) defaults to 0 beside a motor revolution of 1: a move would be
    PRJ023 (the drive cannot convert positions); the skeleton asks for the value and leaves the move out."""
    import copy

    device = copy.deepcopy(load_device_cached(ESI / "copley_XE2_4.60.xml", None, "exact"))
    device.dictionary.entry(0x608F, 1).default = (0).to_bytes(4, "little")
    device.dictionary.entry(0x608F, 2).default = (1).to_bytes(4, "little")
    text = new_project(device, esi="copley_XE2_4.60.xml")
    assert "608F:01" in text and "is 0 in the ESI" in text
    assert "    move:" not in text and "No commissioning move until then" in text
    plain = new_project(load_device_cached(ESI / "copley_XE2_4.60.xml", None, "exact"), esi="copley_XE2_4.60.xml")
    assert "    move: {distance: 1}" in plain


def test_devices_sharing_product_and_revision_are_picked_by_type_name_or_index(tmp_path: Path) -> None:
    """Two end caps with product 0 (EJ9400-0000 and EJ9404-0000 of beckhoff_EJ9xxx.xml given product 0, as bus-end
    terminals are): a product selector no longer picks the first by chance; type name and list index do."""
    from ecattool.errors import SelectionError

    text = (ESI / "beckhoff_EJ9xxx.xml").read_text(encoding="utf-8")
    esi = tmp_path / "caps.xml"
    esi.write_text(text.replace('ProductCode="#x24B82851"', 'ProductCode="#x0"')
                   .replace('ProductCode="#x24BC2851"', 'ProductCode="#x0"'), encoding="utf-8")
    for select in ("0x0", "0x0:0x0"):
        with pytest.raises(SelectionError, match="choose one by type name or list index"):
            resolve(None, None, str(esi), select, tmp_path)
    for select, name in (("EJ9404-0000", "EJ9404-0000"), ("1", "EJ9400-0000")):
        assert resolve(None, None, str(esi), select, tmp_path).type_name == name
        machine = load_machine(_project(tmp_path, esi, select))
        assert not _errors(machine) and commission(machine).ok


def test_a_read_only_mapping_object_the_dictionary_fills_is_not_rewritable(tmp_path: Path) -> None:
    """EL6695-0002 with 1A01h not Fixed but read-only (its DT1A01 as the file has it): the slave holds its
    dictionary's mapping, so a pdo: that lists the PDO list's entries would be written and refused (abort
    06010002); lint says so (PDO023, against the mapping the slave powers on with), and the skeleton writes no pdo:."""
    device = load_device_cached(*EL6695_2, "exact")
    line = next(p for p in device.tx_pdos if p.index == 0x1A01).location.line
    lines = EL6695_2[0].read_text(encoding="utf-8").splitlines(keepends=True)
    lines[line - 1] = lines[line - 1].replace(' Fixed="1"', "")
    esi = tmp_path / "el6695.xml"
    esi.write_text("".join(lines), encoding="utf-8")
    path = _project(tmp_path, esi, EL6695_2[1])
    assert "pdo:" not in path.read_text(encoding="utf-8")
    assert "PRJ027" in _rules(_errors(load_machine(path)))
    given = _project(tmp_path, esi, EL6695_2[1], '    pdo:\n      tx:\n        - {index: 0x1A01, entries: '
                     '[gap/12, "0x1801:09/1", "0x1801:07/1", gap/1, "0x10F4:10/1"]}\n        - {index: 0x1A08}\n')
    machine = load_machine(given)
    assert "PDO023" in _rules(_errors(machine))
    assert not commission(machine, allow_errors=True).ok  # the slave refuses the write lint warned of
