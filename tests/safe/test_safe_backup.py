"""Back-ups that never destroy and never lie; `sii read` and `sdo read` that never save or print what they cannot
vouch for (issue 37, items 2 and 3; docs/at-the-machine.md, "Back-up").

The slaves are the in-process simulator's (`--target sim`, as tests/online/test_online.py uses them), with one
misbehaviour switched on by replacing what the slave answers: a blank or all-zero SII, an SII without its end
marker, a 64-byte or empty "UDINT", a slave in INIT, another device than the project's.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from ecattool.errors import TargetError
from ecattool.od.model import EcState
from ecattool.online import open_bus
from ecattool.online.backup import MANIFEST, backup
from ecattool.project.machine import load_machine
from ecattool.sii.crc import preamble_crc
from ecattool.target.sim import SimLiveSlave
from tests.conftest import ROOT, run

HDT = "samples/hdt/project.yaml"


def _copy_project(tmp_path: Path) -> Path:
    """The Technosoft sample (project file + the .sw it names) in a folder of its own."""
    folder = tmp_path / "machine"
    shutil.copytree(ROOT / "samples" / "technosoft_ipos", folder)
    text = (folder / "project.yaml").read_text().replace("../../schemas/", str(ROOT / "schemas") + "/")
    (folder / "project.yaml").write_text(text)
    return folder


def _snapshot(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


# ------------------------------------------------------------------------------------------ never destroy
def test_an_output_that_is_holds_or_lies_inside_an_input_is_refused_even_with_force(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    """Today `backup --force -o DIR` replaced whatever DIR was: the project's folder, the project file (by a
    folder), the folder that holds them."""
    proj = _copy_project(tmp_path)
    before = _snapshot(tmp_path)
    project = str(proj / "project.yaml")
    for out in (proj, proj / "project.yaml", proj / "setup.sw", tmp_path, proj / "setup.sw" / "inside"):
        for force in ((), ("--force",)):
            code, _, err = run(capsys, "backup", project, "--target", "sim", "-o", str(out), *force)
            assert code == 1 and len(err.strip().splitlines()) == 1 and "Traceback" not in err, (out, err)
            assert "input" in err or "project's folder" in err, (out, err)
    monkeypatch.chdir(proj)  # `-o .` in the project's folder (a traceback at online/backup.py:79 before)
    code, _, err = run(capsys, "backup", "project.yaml", "--target", "sim", "-o", ".", "--force")
    assert code == 1 and "is the project's folder" in err and "Traceback" not in err
    assert _snapshot(tmp_path) == before


def test_force_replaces_only_a_back_up(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                       monkeypatch: pytest.MonkeyPatch) -> None:
    other = tmp_path / "photos"
    other.mkdir()
    (other / "keep.jpg").write_bytes(b"precious")
    a_file = tmp_path / "notes.txt"
    a_file.write_text("mine")
    for out in (other, a_file):
        code, _, err = run(capsys, "backup", HDT, "--target", "sim", "-o", str(out), "--force")
        assert code == 1 and "not a back-up folder" in err and len(err.strip().splitlines()) == 1, err
    assert (other / "keep.jpg").read_bytes() == b"precious" and a_file.read_text() == "mine"
    monkeypatch.chdir(other)  # `-o .`: a folder that is no back-up, not the project's
    code, _, err = run(capsys, "backup", str(ROOT / HDT), "--target", "sim", "-o", ".", "--force")
    assert code == 1 and "not a back-up folder" in err and "Traceback" not in err
    monkeypatch.chdir(tmp_path)
    done = tmp_path / "b"
    assert run(capsys, "backup", str(ROOT / HDT), "--target", "sim", "-o", str(done))[0] == 0
    assert (done / MANIFEST).is_file()
    (done / "00-table.dict.json").write_text("{}")  # a back-up (its manifest): --force replaces it whole
    code, _, err = run(capsys, "backup", str(ROOT / HDT), "--target", "sim", "-o", str(done), "--force")
    assert code == 0, err
    assert (done / "00-table.dict.json").read_text() != "{}"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["b", "notes.txt", "photos"]


# --------------------------------------------------------------------------------------------- never lie
def _hdt_bus():  # type: ignore[no-untyped-def]
    result = load_machine(HDT)
    return open_bus("sim", [rd.device for rd in result.slaves])


def _blank_end(sii: bytes) -> bytes:
    """The image with its category chain running into a category that never ends (no 0xFFFF end marker)."""
    data = bytearray(sii[:128]) + bytes([0x0A, 0x00, 0x00, 0x00]) * 1000
    return bytes(data)


@pytest.mark.parametrize("what, sii, message", [
    ("blank SII", lambda good: b"\xff" * 256, "blank"),
    ("all-zero SII", lambda good: bytes(4096), "all zero"),
    ("bad CRC", lambda good: good[:14] + bytes([good[14] ^ 0x55]) + good[15:], "CRC-8"),
    ("no end marker", _blank_end, "no end marker"),
])
def test_a_back_up_of_an_sii_that_does_not_check_out_fails_and_writes_nothing(
        tmp_path: Path, what: str, sii, message: str) -> None:  # type: ignore[no-untyped-def]
    with _hdt_bus() as bus:
        slave = bus.slaves[0]
        slave.sii = sii(slave.sii)
        with pytest.raises(TargetError, match=f"slave 0: the SII read does not check out: .*{message}"):
            backup(load_machine(HDT), bus, tmp_path / "b")
    assert list(tmp_path.iterdir()) == []


def test_a_slave_in_init_with_a_blank_sii_is_exit_1_and_no_folder(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    """Today: exit 0, a dictionary file with 0 objects and a blank .sii.bin."""
    real = SimLiveSlave.sii_read

    def blank_in_init(self: SimLiveSlave) -> bytes:
        self.drive.request_state(EcState.INIT)
        self.sii = b"\xff" * 256
        return real(self)

    monkeypatch.setattr(SimLiveSlave, "sii_read", blank_in_init)
    code, out, err = run(capsys, "backup", HDT, "--target", "sim", "-o", str(tmp_path / "b"))
    assert code == 1 and "blank" in err and len(err.strip().splitlines()) == 1, (out, err)
    assert list(tmp_path.iterdir()) == []


def test_a_slave_that_gives_no_object_fails_the_back_up(tmp_path: Path) -> None:
    with _hdt_bus() as bus:
        bus.slaves[0].drive.request_state(EcState.INIT)  # its SII is fine; no object is readable in INIT
        with pytest.raises(TargetError, match=r"slave 0 \(table\) is in INIT: its mailbox does not answer"):
            backup(load_machine(HDT), bus, tmp_path / "b")
    assert list(tmp_path.iterdir()) == []


def test_a_slave_that_refuses_every_object_fails_the_back_up(tmp_path: Path,
                                                             monkeypatch: pytest.MonkeyPatch) -> None:
    """In PRE-OP, its identity right, but every other object aborted: a snapshot of aborts vouches for nothing."""
    from ecattool.errors import SdoAbort

    real = SimLiveSlave.sdo_upload

    def refuse(self: SimLiveSlave, index: int, subindex: int, complete_access: bool = False,
               size: int | None = None) -> bytes:
        if index == 0x1018:
            return real(self, index, subindex, complete_access)
        raise SdoAbort(index, subindex, 0x08000000)

    monkeypatch.setattr(SimLiveSlave, "sdo_upload", refuse)
    with _hdt_bus() as bus:
        with pytest.raises(TargetError, match=r"slave 0 \(table\) gave no object to back up \(state PREOP, \d+ "
                                              r"object\(s\) read, none with a value beyond the identity 1018h\)"):
            backup(load_machine(HDT), bus, tmp_path / "b")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("size", [64, 0])
def test_a_udint_of_the_wrong_size_fails_the_back_up_and_sdo_read(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch, size: int) -> None:
    """A slave answering 64 (or 0) bytes to every UDINT: backed up as such, and printed by `sdo read`, before."""
    real = SimLiveSlave.sdo_upload

    def odd(self: SimLiveSlave, index: int, subindex: int, complete_access: bool = False,
            **bound: int | None) -> bytes:  # an adapter that ignores the bound (``size``): read_value checks again
        data = real(self, index, subindex, complete_access)
        entry = self.drive.device.dictionary.entry(index, subindex)
        return bytes(size) if entry is not None and entry.type_name == "UDINT" else data

    monkeypatch.setattr(SimLiveSlave, "sdo_upload", odd)
    code, _, err = run(capsys, "backup", HDT, "--target", "sim", "-o", str(tmp_path / "b"))
    assert code == 1 and f"answered {size} byte(s), a UDINT has 4" in err and "slave 0: 0x" in err, err
    assert list(tmp_path.iterdir()) == []
    code, out, err = run(capsys, "sdo", "read", "0x6081:00", "--target", "sim:technosoft-ipos")
    assert code == 1 and out == "" and len(err.strip().splitlines()) == 1
    assert f"slave 0: 0x6081:00 Profile velocity: answered {size} byte(s), a UDINT has 4" in err, err
    code, out, _ = run(capsys, "sdo", "read", "0x6060:00", "--target", "sim:technosoft-ipos")
    assert code == 0 and "0x6060:00" in out  # a SINT: its size is right
    snapshot = tmp_path / "axis.dict.json"
    code, _, err = run(capsys, "sdo", "dump", "--target", "sim:technosoft-ipos", "-o", str(snapshot))
    assert code == 1 and f"answered {size} byte(s)" in err and not snapshot.exists()


def test_a_back_up_of_another_device_than_the_projects_fails(tmp_path: Path) -> None:
    with open_bus("sim:technosoft-ipos") as bus:
        with pytest.raises(TargetError, match="slave 0 is not drive 'table' of the project: its vendor_id is"):
            backup(load_machine(HDT), bus, tmp_path / "b")
    assert list(tmp_path.iterdir()) == []


# ----------------------------------------------------------------------------------------------- sii read
@pytest.mark.parametrize("image, message", [(bytes(4096), "all zero"), (b"\xff" * 130, "blank")])
def test_sii_read_saves_nothing_it_cannot_vouch_for(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                    monkeypatch: pytest.MonkeyPatch, image: bytes,
                                                    message: str) -> None:
    """Today: under working-counter faults an all-zero 4,096-byte image was saved, exit 0."""
    monkeypatch.setattr(SimLiveSlave, "sii_read", lambda self: image)
    out = tmp_path / "slave.bin"
    code, _, err = run(capsys, "sii", "read", "--target", "sim:hdt", "-o", str(out))
    assert code == 1 and f"slave 0: the SII read does not check out: {message}" in err, err
    assert len(err.strip().splitlines()) == 1 and list(tmp_path.iterdir()) == []
    code, _, err = run(capsys, "sii", "read", "--target", "sim:hdt", "-o", str(out), "--unchecked")
    assert code == 0 and out.read_bytes() == image and "does not check out" in err  # said, even when saved


def test_sii_read_of_a_good_slave_checks_out(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "slave.bin"
    code, _, err = run(capsys, "sii", "read", "--target", "sim:hdt", "-o", str(out))
    data = out.read_bytes()
    assert code == 0 and err == "" and data[14] == preamble_crc(data)
    code, _, _ = run(capsys, "sii", "check", str(out))
    assert code == 0



# ---------------------------------------------------------------------------------------------- sii write
def _other_image(good: bytes) -> bytes:
    """A valid image with another header and other categories: the station alias (word 4) and the first
    category's payload changed, the CRC fixed."""
    new = bytearray(good)
    new[8:10] = b"\x34\x12"
    new[0x84] ^= 0x01  # inside the first category (after its type and size words)
    new[14] = preamble_crc(bytes(new))
    return bytes(new)


def test_a_sii_write_cut_anywhere_never_leaves_an_image_that_checks_out() -> None:
    """Issue 37.3: 2 of 20 kills during `sii write` left a mixed EEPROM (new header with a valid CRC, old
    categories) that `sii check` passes. Cut after every single word write of the sequence: the EEPROM is the old
    image whole, the new one whole, or fails its CRC."""
    from ecattool.online.sii_access import read_problems
    from ecattool.sii.eeprom import write_sequence

    with open_bus("sim:technosoft-ipos") as bus:
        old = bus.slaves[0].sii
    categories_only = bytearray(old)
    categories_only[0x84] ^= 0x01  # words 0-7 as they are: the old checksum stays valid for the new header, so
    # writing the header last alone would leave old-header-plus-half-new-categories checking out
    for new in (_other_image(old), bytes(categories_only)):
        seq = write_sequence(new, old)
        assert sorted({w for w, _ in seq}) == list(range(len(new) // 2)) and len(seq) == len(new) // 2 + 1
        for n in range(len(seq) + 1):
            eeprom = bytearray(old)
            for word, data in seq[:n]:
                eeprom[2 * word:2 * word + 2] = data
            problems = read_problems(bytes(eeprom))
            if n == 0:
                assert bytes(eeprom) == old
            elif n == len(seq):
                assert bytes(eeprom[:len(new)]) == new and problems == []
            else:
                assert any("CRC-8" in p for p in problems), (n, seq[n - 1][0], problems)


def test_sii_write_sends_that_sequence_word_by_word_and_a_cut_write_fails_the_crc(tmp_path: Path) -> None:
    """The same through a master (the fake pysoem module, word by word): the writes are the sequence, and a write
    cut half-way (the master's EEPROM write fails) leaves an EEPROM whose CRC fails."""
    from ecattool.online.sii_access import read_problems, sii_write
    from ecattool.online.targets import open_live
    from ecattool.sii.eeprom import write_sequence
    from ecattool.sim import Drive
    from tests.target import fake_pysoem

    for cut in (None, 3, 200):
        bus = open_live("pysoem", "eth0", fake_pysoem.make_module([Drive.from_profile("technosoft-ipos")]))
        try:
            raw = bus.slaves[0].raw  # type: ignore[attr-defined]
            old = bytes(raw.sii)
            new = _other_image(old)
            real_write = raw.eeprom_write

            def write(word_address: int, data: bytes, timeout: int = 20000) -> None:
                if cut is not None and len(raw.sii_writes) == cut:
                    raise KeyboardInterrupt  # the process is stopped here
                real_write(word_address, data, timeout)

            raw.eeprom_write = write
            if cut is None:
                assert sii_write(bus.slaves[0], new, "new.bin", tmp_path / "old.bin") == []
                assert raw.sii_writes == write_sequence(new, old) and bytes(raw.sii[:len(new)]) == new
            else:
                with pytest.raises(KeyboardInterrupt):
                    sii_write(bus.slaves[0], new, "new.bin", tmp_path / f"old-{cut}.bin")
                assert len(raw.sii_writes) == cut
                assert any("CRC-8" in p for p in read_problems(bytes(raw.sii)))
        finally:
            bus.close()


def test_sii_write_force_only_overwrites_files_and_any_identity_is_its_own_flag(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    with open_bus("sim:hdt") as bus:
        good = bus.slaves[0].sii_read()
    other = bytearray(good)
    other[0x10:0x14] = (0x1234).to_bytes(4, "little")
    other[14] = preamble_crc(bytes(other))  # a valid image of another vendor
    path, backup_file = tmp_path / "new.bin", tmp_path / "old.bin"
    path.write_bytes(bytes(other))
    code, _, err = run(capsys, "sii", "write", str(path), "--target", "sim:hdt", "--backup", str(backup_file),
                       "--force")
    assert code == 1 and "vendor_id 0x00001234 is not the slave's" in err and "--any-identity" in err, err
    assert not backup_file.exists()  # --force no longer skips the identity check
    code, out, err = run(capsys, "sii", "write", str(path), "--target", "sim:hdt", "--backup", str(backup_file),
                         "--any-identity")
    assert code == 0 and "written" in out, err
    code, _, err = run(capsys, "sii", "write", str(path), "--target", "sim:hdt", "--backup", str(backup_file),
                       "--any-identity")
    assert code == 1 and err.strip().endswith("file exists; use --force to overwrite it"), err
    code, out, err = run(capsys, "sii", "write", str(path), "--target", "sim:hdt", "--backup", str(backup_file),
                         "--any-identity", "--force")
    assert code == 0 and "written" in out, err


def test_sii_write_through_the_masters_child_process(tmp_path: Path) -> None:
    """``sii write`` on a real master goes through the master's child process (ecattool.target.isolated): the
    child's slave is the one adapter's, every capability of the slave protocol is served there, the word writes of
    the sequence included (the remote slave had no ``sii_write_word`` before the bus layer was one)."""
    from ecattool.online.sii_access import sii_write
    from ecattool.online.targets import isolated_bus, open_live
    from ecattool.sim import Drive
    from tests.target import fake_pysoem

    module = fake_pysoem.make_module([Drive.from_profile("technosoft-ipos")])
    with isolated_bus("pysoem:eth0", lambda: open_live("pysoem", "eth0", module)) as bus:
        slave = bus.slave(0)
        old = slave.sii_read()
        new = _other_image(old)
        assert sii_write(slave, new, "new.bin", tmp_path / "old.bin") == []
        assert slave.sii_read()[:len(new)] == new and (tmp_path / "old.bin").read_bytes() == old
