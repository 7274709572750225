"""Commissioning on the embedded simulator: the four samples succeed with the internal-unit results the
manuals give; injected faults (SDO abort, refused state change, wrong identity, corrupted .sw, lost reply)
are reported precisely, leave the drive safe and never report success; a second run converges."""

from __future__ import annotations

from pathlib import Path

import pytest

from ecattool.commission import commission
from ecattool.commission.runner import open_target
from ecattool.od.model import EcState
from ecattool.project.machine import load_machine
from ecattool.sim import Drive
from ecattool.target.sim import SimTarget
from tests.project.project_helpers import SAMPLES, copy_sample, sample

ENABLED = "operation enabled"


def sim_drives(path: Path, **profile: str) -> list[Drive]:
    """One simulated drive per project drive, as `commission` builds them (bus order); ``profile`` replaces the
    built-in profile device of a single-drive project (another firmware on the bus)."""
    if profile:
        return [Drive.from_profile(**profile)]  # type: ignore[arg-type]
    return open_target("sim", load_machine(path).slaves)[0].slaves()  # type: ignore[return-value]


def run(path: Path, drives: list[Drive]):
    report = commission(path, target=SimTarget(drives))
    assert len(report.drives) == len(drives)
    return report, report.drives[0]


def step(dr, name: str):
    return next(s for s in dr.steps if s.name == name)


def sdo_writes(drive: Drive) -> list:
    return [e for e in drive.events if e.kind == "sdo_download"]


# --- the samples --------------------------------------------------------------------------------------------

@pytest.mark.parametrize("name", SAMPLES)
def test_sample_commissions_on_the_default_target(name):
    report = commission(sample(name))
    assert report.ok and report.target == "sim"
    (dr,) = report.drives
    assert dr.ok and dr.error is None and dr.final_state == "OP"
    names = [s.name for s in dr.steps]
    assert names[:2] == ["state PREOP", "identity"] and names[-1] == "move"
    assert names.index("state SAFEOP") < names.index("state OP") < names.index("enable")
    assert all(s.ok for s in dr.steps)


def test_technosoft_1000_um_is_1200_counts():
    # 500 lines (2000 counts/rev) x 3:1 gear / 5 mm pitch: 1 mm = 1200 counts (digest of the iPOS manual §5)
    path = sample("technosoft_ipos")
    drives = sim_drives(path)
    _, dr = run(path, drives)
    assert dr.ok, dr.error
    assert "1000 user units" in step(dr, "move").detail and "= 1200 counts" in step(dr, "move").detail
    assert drives[0].internal_position == 1200
    assert int.from_bytes(drives[0].sdo_upload(0x6064, 0), "little", signed=True) == 1000
    assert "3 block(s) written" in step(dr, "sw download").detail


def test_hdt_90_deg_is_81920_counts():
    # 65536 counts/rev x 5:1 gear: 90 deg of the table = 1.25 motor revolutions = 81920 counts
    path = sample("hdt")
    drives = sim_drives(path)
    _, dr = run(path, drives)
    assert dr.ok, dr.error
    assert "= 81920 counts" in step(dr, "move").detail and drives[0].internal_position == 81920


def test_controltechniques_csp_5000_um_on_dc():
    # 65536 counts/rev x 3:1 / 10 mm: 5 mm = 1.5 motor revolutions = 98304 counts; CSP needs SYNC0
    path = sample("controltechniques")
    drives = sim_drives(path)
    _, dr = run(path, drives)
    assert dr.ok, dr.error
    assert step(dr, "dc").detail.startswith("AssignActivate 0x0300")
    assert step(dr, "move").detail.startswith("CSP move of 5000 user units")
    assert drives[0].internal_position == 98304
    assert step(dr, "scaling").detail == "drive reports 0x608F:01 = 65536, 0x608F:02 = 1"


def test_controltechniques_csp_move_without_a_mode_parameter_sets_the_mode_before_enabling(tmp_path):
    # SM-EtherCAT refuses a change of 6060h in OPERATION ENABLED (7.3.6, abort 0800 0022h): a CSP move whose
    # mode is not a startup parameter must select it before the enable sequence, not after
    path = copy_sample("controltechniques", tmp_path)
    text = path.read_text()
    path.write_text(text.replace("      - {object: modes of operation, value: 8, "
                                 "comment: cyclic synchronous position}\n", ""))
    assert "modes of operation" not in path.read_text()
    drives = sim_drives(path)
    _, dr = run(path, drives)
    assert dr.ok, dr.error
    assert step(dr, "move").detail.startswith("CSP move of 5000 user units")
    assert drives[0].internal_position == 98304


def test_controltechniques_encoder_resolution_other_than_the_project_is_refused():
    # 608Fh is read-only on SM-EtherCAT: with another encoder resolution than the project's feedback the
    # drive would move 5000 um as 307 counts; commissioning refuses instead of reporting success
    path = sample("controltechniques")
    (drive,) = sim_drives(path)
    drive._put(0x608F, 1, 4096)  # the encoder configuration sets the read-only 608Fh (as the sim tests do)
    _, dr = run(path, [drive])
    assert not dr.ok and dr.steps[-1].name == "scaling"
    assert "0x608F:01 (Position encoder resolution: Encoder increments) reads 4096" in dr.error
    assert "expects 65536" in dr.error and dr.final_state == "PREOP"


def test_generic_esi_default_mapping_csp():
    path = sample("generic_esi")
    drives = sim_drives(path)
    _, dr = run(path, drives)
    assert dr.ok and drives[0].internal_position == 10000
    # default mapping: nothing to program; the one write is the ESI's init command (PS 6060h := 8)
    assert [s.detail for s in dr.steps if s.name.startswith("startup")] == ["1 write(s) verified"]


# --- faults ---------------------------------------------------------------------------------------------------

def test_sdo_abort_on_a_startup_write_is_reported_and_the_drive_left_safe():
    path = sample("hdt")
    drives = sim_drives(path)
    drives[0].faults.abort_sdo(4, 0x06090030)  # 3 identity reads, then the first startup write
    report, dr = run(path, drives)
    assert not report.ok and not dr.ok
    failed = dr.steps[-1]
    assert failed.name == "write 0x6093:01" and not failed.ok and failed.abort_code == 0x06090030
    assert failed.to_json()["abort_code"] == "0x06090030"
    assert "0x6093:01" in dr.error and "0x06090030" in dr.error
    assert dr.final_state == "PREOP" and drives[0].state() is EcState.PREOP
    assert drives[0].cia402_state.name.lower().replace("_", " ") != ENABLED
    # nothing was written after the failing command; only the drive's error code 603Fh was read for the report
    events = drives[0].events
    k = max(i for i, e in enumerate(events) if e.kind == "sdo_abort")
    assert (events[k].data["index"], events[k].data["subindex"]) == (0x6093, 1)
    assert [(e.kind, e.data.get("index")) for e in events[k + 1:]] == [("sdo_upload", 0x603F)]
    assert not any(s.name in ("state SAFEOP", "state OP", "move") for s in dr.steps)


def test_abort_in_the_middle_names_that_command():
    path = sample("hdt")
    drives = sim_drives(path)
    drives[0].faults.abort_sdo(3 + 2 * 3 + 1, 0x08000022)  # the 4th write (each write is read back)
    _, dr = run(path, drives)
    lint = load_machine(path).slaves[0]
    fourth = [c for c in lint.startup if c.transition in ("IP", "PS")][3]
    assert dr.steps[-1].name == f"write {fourth.address}" and dr.steps[-1].abort_code == 0x08000022


def test_second_run_after_a_fault_converges():
    path = sample("hdt")
    drives = sim_drives(path)
    drives[0].faults.abort_sdo(4, 0x06090030)
    first, _ = run(path, drives)
    second, dr = run(path, drives)
    assert not first.ok and second.ok and dr.final_state == "OP"
    third, _ = run(path, drives)  # and again: idempotent
    assert third.ok


def test_refused_state_change_reports_the_al_status():
    path = sample("hdt")
    drives = sim_drives(path)
    drives[0].faults.refuse_state(EcState.SAFEOP, 0x001D)
    report, dr = run(path, drives)
    assert not report.ok
    failed = dr.steps[-1]
    assert failed.name == "state SAFEOP" and failed.al_status == 0x001D and failed.abort_code is None
    assert failed.to_json()["al_status"] == "0x001D" and "0x001D" in dr.error
    assert dr.final_state == "PREOP"
    assert run(path, drives)[0].ok  # converges


def test_refused_op_after_safeop_goes_back_to_preop():
    path = sample("technosoft_ipos")
    drives = sim_drives(path)
    drives[0].faults.refuse_state(EcState.OP, 0x001B)
    _, dr = run(path, drives)
    assert dr.steps[-1].name == "state OP" and dr.steps[-1].al_status == 0x001B
    assert dr.final_state == "PREOP" and drives[0].state() is EcState.PREOP


def test_lost_sdo_reply_is_a_failed_step():
    path = sample("controltechniques")
    drives = sim_drives(path)
    drives[0].faults.drop_reply(4)
    _, dr = run(path, drives)
    assert not dr.ok and dr.steps[-1].name.startswith("write 0x") and dr.final_state == "PREOP"
    assert run(path, drives)[0].ok


def test_wrong_firmware_is_refused_with_revision_exact():
    # the project names F515K exactly; the drive on the bus runs F515L
    path = sample("technosoft_ipos")
    drives = sim_drives(path, name="technosoft-ipos", product="ipos4808-bx-cat-sto", revision="F515L")
    report, dr = run(path, drives)
    assert not report.ok and dr.steps[-1].name == "identity"
    assert "revision 0x3531354C (expected exactly 0x3531354B)" in dr.error
    assert sdo_writes(drives[0]) == []  # nothing was written to the wrong device
    assert dr.final_state == "PREOP"


def _with_identity(tmp_path: Path, name: str, policy: str) -> Path:
    p = copy_sample(name, tmp_path)
    text = p.read_text()
    if "identity:" in text:
        text = "\n".join(line for line in text.splitlines() if not line.strip().startswith("identity:"))
    p.write_text(text.replace("    device:\n", f"    identity: {{revision: {policy}}}\n    device:\n", 1))
    return p


def test_newer_firmware_is_accepted_with_revision_at_least(tmp_path):
    path = _with_identity(tmp_path, "technosoft_ipos", "at-least")
    drives = sim_drives(path, name="technosoft-ipos", product="ipos4808-bx-cat-sto", revision="F515L")
    report, dr = run(path, drives)
    assert report.ok, dr.error
    assert "revision 0x3531354C" in step(dr, "identity").detail


def test_older_firmware_is_refused_with_revision_at_least(tmp_path):
    path = _with_identity(tmp_path, "technosoft_ipos", "at-least")
    drives = sim_drives(path, name="technosoft-ipos", product="ipos4808-bx-cat-sto", revision="F515J")
    _, dr = run(path, drives)
    assert dr.steps[-1].name == "identity" and "expected at least 0x3531354B" in dr.error


def test_revision_ignore_accepts_other_firmware(tmp_path):
    path = _with_identity(tmp_path, "technosoft_ipos", "ignore")
    drives = sim_drives(path, name="technosoft-ipos", product="ipos4808-bx-cat-sto", revision="F515L")
    _, dr = run(path, drives)
    assert step(dr, "identity").ok


def test_another_product_is_refused_whatever_the_revision_policy(tmp_path):
    path = _with_identity(tmp_path, "technosoft_ipos", "ignore")
    drives = sim_drives(path, name="technosoft-ipos", product="ipos4808-my-cat-sto", revision="F515K")
    _, dr = run(path, drives)
    assert dr.steps[-1].name == "identity" and "product 0x" in dr.error and "expected 0x01A0C82D" in dr.error


def test_corrupted_sw_on_the_drive_is_repaired_by_download():
    path = sample("technosoft_ipos")
    drives = sim_drives(path)
    assert run(path, drives)[0].ok
    # second run: the EEPROM holds the setup, nothing to download
    _, dr = run(path, drives)
    assert dr.ok and step(dr, "sw verify").ok and not any(s.name == "sw download" for s in dr.steps)
    # flip one word of the setup in the drive's EEPROM
    lint = load_machine(path).slaves[0]
    block = lint.sw_image.blocks[0]
    address = block.start + 1
    drives[0].memory.eeprom[address] ^= 0x5A5A
    _, dr = run(path, drives)
    assert dr.ok, dr.error
    assert "1 block(s) written and verified" in step(dr, "sw download").detail
    assert drives[0].eeprom_words(address, 1) == [block.words[1]]


def test_sw_verify_only_fails_when_download_is_disabled(tmp_path):
    p = copy_sample("technosoft_ipos", tmp_path)
    p.write_text(p.read_text().replace("sw: setup.sw", "sw: {file: setup.sw, download: false}"))
    drives = sim_drives(p)
    _, dr = run(p, drives)
    assert not dr.ok and dr.steps[-1].name == "sw verify" and "download disabled" in dr.error


def test_a_drive_missing_from_the_bus_fails_that_drive_only(tmp_path):
    p = copy_sample("hdt", tmp_path)
    p.write_text(p.read_text().replace("  - name: table\n", "  - name: table\n    position: 1\n"))
    report = commission(p, target=SimTarget([]))
    (dr,) = report.drives
    assert not report.ok and dr.steps == [dr.steps[0]] and dr.steps[0].name == "bus"
    assert "no slave at bus position 1" in dr.error


def test_a_target_passed_in_is_not_closed():
    path = sample("hdt")
    tgt = SimTarget(sim_drives(path))
    assert commission(path, target=tgt).ok
    assert len(tgt.slaves()) == 1 and commission(path, target=tgt).ok


def test_project_with_lint_errors_is_never_commissioned(tmp_path):
    p = copy_sample("hdt", tmp_path)
    p.write_text(p.read_text().replace('value: 90, comment', 'value: -1, comment'))
    drives = sim_drives(p)
    report, dr = run(p, drives)
    assert not report.ok and dr.steps[-1].name == "lint" and drives[0].events == []


def test_power_loss_during_sw_download_fails_and_the_next_run_repairs():
    path = sample("technosoft_ipos")
    drives = sim_drives(path)
    drives[0].faults.power_loss_during_eeprom_write(after_words=100)
    report, dr = run(path, drives)
    assert not report.ok and dr.steps[-1].name == "sw download"
    assert dr.error.count("0x7ABD") == 1 and "SDO timeout on 0x2065:00" in dr.error
    _, dr = run(path, drives)
    assert dr.ok and "1 block(s) written and verified" in step(dr, "sw download").detail
    assert "= 1200 counts" in step(dr, "move").detail


def test_a_drive_in_fault_is_reset_through_the_state_machine():
    path = sample("technosoft_ipos")
    drives = sim_drives(path)
    assert run(path, drives)[0].ok
    drives[0].inject_fault(0x2310)  # continuous over-current
    _, dr = run(path, drives)
    assert dr.ok and step(dr, "enable").detail.startswith("fault -> fault reset sent -> switch on disabled")


def test_a_drive_fault_during_the_move_is_named_in_the_report(tmp_path):
    """The report says what the drive says: 603Fh, named from the family's error table (HDT §2.08.2)."""
    path = copy_sample("hdt", tmp_path)
    (drive,) = sim_drives(path)
    real_exchange, cycles = drive.exchange, [0]

    def exchange(outputs: bytes) -> bytes:  # a following error trips the drive in the middle of the move
        cycles[0] += 1
        if cycles[0] == 40:
            drive.inject_fault(0x8611)
        return real_exchange(outputs)

    drive.exchange = exchange  # type: ignore[method-assign]
    _, dr = run(path, [drive])
    assert not dr.ok
    assert dr.error.endswith("; the drive reports error 603Fh = 0x8611 (following error: position error (FA_13))")


def test_a_failure_without_a_drive_error_adds_nothing(tmp_path):
    path = copy_sample("hdt", tmp_path)
    (drive,) = sim_drives(path)
    drive.faults.refuse_state(EcState.SAFEOP, 0x001D)  # refused by the ESM: no drive fault behind it
    _, dr = run(path, [drive])
    assert not dr.ok and "603Fh" not in dr.error


def test_csp_move_starts_where_the_axis_stands(tmp_path):
    # an axis that does not stand at 0 (absolute encoder, a previous run): in CSP the drive follows 607Ah from
    # the first enabled cycle, so the set-point it sees on enabling must be the actual position, not the 607Ah
    # it held (0): otherwise the axis jumps to 0 before the commanded move
    path = sample("controltechniques")
    drives = sim_drives(path)
    from fractions import Fraction

    drives[0].cia.position = Fraction(196608)  # 2 x the move: 10 mm
    drives[0]._refresh_inputs()
    _, dr = run(path, drives)
    assert dr.ok, dr.error
    assert step(dr, "move").detail.startswith("CSP move of 5000 user units: position 10000 -> 15000")
    assert drives[0].internal_position == 196608 + 98304


def test_a_set_point_the_drive_still_holds_is_not_fed_back_to_it(tmp_path):
    # HDT maps the vl target velocity 6042h in its default RxPDO: a value left from an earlier run must not be
    # what the first cycles send (it would act as soon as a velocity mode is enabled); profile values are kept
    path = copy_sample("hdt", tmp_path)
    (drive,) = sim_drives(path)
    drive._put(0x6042, 0, 300)
    drive._put(0x6084, 0, 777)  # a profile deceleration the drive holds: kept (HDT maps 6084h too)
    _, dr = run(path, [drive])
    assert dr.ok, dr.error
    assert drive.value(0x6042, 0) == 0 and drive.value(0x6084, 0) == 777
