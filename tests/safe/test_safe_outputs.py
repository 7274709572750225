"""Outputs never harm anything (issue 28.1; docs/cli.md, "Output files").

A device, a FIFO or /dev/stdout is written through, never replaced by a regular file; a UNIX socket is refused; a
symbolic link is followed and stays a link (a dangling one only with --force); --force keeps the replaced file's
mode and owner; two writers racing for one absent output never both succeed; no command writes over one of its inputs, whatever name it is given by; an existing file
is replaced only with --force; the temporary file of an interrupted writer is removed, and a dead writer's is
removed at the next write into the same folder.
"""

from __future__ import annotations

import os
import signal
import socket
import stat
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from ecattool.errors import InputError
from ecattool.fileio import clean_stale_temporaries, write_atomic
from tests.conftest import ROOT, run

SII_XML = ROOT / "samples" / "sii" / "custom_slave.xml"


def _reader(path: Path, got: list[bytes]) -> threading.Thread:
    def read() -> None:
        with open(path, "rb") as fh:
            got.append(fh.read())

    t = threading.Thread(target=read, daemon=True)
    t.start()
    return t


def test_dev_null_stays_a_device(capsys: pytest.CaptureFixture[str]) -> None:
    before = os.stat("/dev/null")
    code, _, err = run(capsys, "sii", "build", str(SII_XML), "-o", "/dev/null")
    after = os.stat("/dev/null")
    assert code == 0, err
    assert stat.S_ISCHR(after.st_mode) and (after.st_ino, after.st_rdev) == (before.st_ino, before.st_rdev)


def test_a_fifo_gets_the_data_and_stays_a_fifo(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    got: list[bytes] = []
    reader = _reader(fifo, got)
    code, _, err = run(capsys, "sii", "build", str(SII_XML), "-o", str(fifo))
    reader.join(30)
    assert code == 0, err
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    assert got and got[0] == (ROOT / "samples" / "sii" / "custom_slave.bin").read_bytes()[:len(got[0])] and got[0]


def test_a_unix_socket_is_refused_and_gets_nothing(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    """Issue 37.5: an output is a file or a stream, never a message to whatever listens on a socket."""
    path = tmp_path / "sock"
    server = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    server.bind(str(path))
    server.listen(1)
    server.setblocking(False)
    try:
        with pytest.raises(InputError, match="UNIX socket"):
            write_atomic(path, b"through the socket", overwrite=False)
        for force in ((), ("--force",)):
            code, _, err = run(capsys, "sii", "build", str(SII_XML), "-o", str(path), *force)
            assert code == 1 and "is a UNIX socket" in err and len(err.strip().splitlines()) == 1, err
        with pytest.raises(BlockingIOError):
            server.accept()  # nobody connected
    finally:
        server.close()
    assert stat.S_ISSOCK(os.lstat(path).st_mode)


def test_a_symlink_is_followed_and_stays_a_link(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    real = tmp_path / "real.bin"
    link = tmp_path / "link.bin"
    link.symlink_to(real.name)
    # a dangling link: its file is created only with --force (issue 37.5)
    code, _, err = run(capsys, "sii", "build", str(SII_XML), "-o", str(link))
    assert code == 1 and "symbolic link to 'real.bin', which does not exist; use --force" in err, err
    assert not real.exists() and link.is_symlink()
    code, _, err = run(capsys, "sii", "build", str(SII_XML), "-o", str(link), "--force")
    assert code == 0, err
    assert link.is_symlink() and real.is_file() and real.stat().st_size > 0
    code, _, err = run(capsys, "sii", "build", str(SII_XML), "-o", str(link))
    assert code == 1 and "file exists; use --force" in err  # the file it points to exists now
    code, _, err = run(capsys, "sii", "build", str(SII_XML), "-o", str(link), "--force")
    assert code == 0, err
    assert link.is_symlink() and os.readlink(link) == real.name
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.bin", "real.bin"]


def test_dev_stdout_is_written_through(tmp_path: Path) -> None:
    """/dev/stdout is a symbolic link to the process's descriptor: the data goes to whatever stdout is (here a file
    the shell opened for appending), and neither the link nor that file is replaced."""
    sink = tmp_path / "captured.txt"
    sink.write_bytes(b"first line\n")
    inode = sink.stat().st_ino
    with open(sink, "ab") as fh:
        proc = subprocess.run([sys.executable, "-m", "ecattool", "project", "new", "--profile", "hdt",
                               "-o", "/dev/stdout"], stdout=fh, stderr=subprocess.PIPE, cwd=tmp_path, timeout=120)
    assert proc.returncode == 0, proc.stderr
    text = sink.read_text()
    assert text.startswith("first line\n") and "drives:" in text and sink.stat().st_ino == inode
    assert os.path.islink("/dev/stdout")


def test_empty_output_name_is_a_usage_error(capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = run(capsys, "sii", "build", str(SII_XML), "-o", "")
    assert code == 2 and "empty" in err and "Traceback" not in err


def test_project_new_never_writes_over_its_esi(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    esi = tmp_path / "drive.xml"
    original = (ROOT / "samples" / "generic_esi" / "inovance_SV660_EOE_1Axis_V9.12.xml").read_bytes()
    esi.write_bytes(original)
    for force in ((), ("--force",)):  # not even with --force
        code, _, err = run(capsys, "project", "new", "--esi", "drive.xml", "-o", str(esi), *force)
        assert code == 1 and "refusing to overwrite an input file" in err, err
        assert esi.read_bytes() == original


def test_an_input_is_known_by_identity_not_by_name(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    """A hard link and a symbolic link to the input are the input."""
    src = tmp_path / "in.xml"
    src.write_bytes(SII_XML.read_bytes())
    hard = tmp_path / "hard.xml"
    os.link(src, hard)
    soft = tmp_path / "soft.xml"
    soft.symlink_to(src)
    for out in (hard, soft, tmp_path / "." / "in.xml"):
        code, _, err = run(capsys, "sii", "build", str(src), "-o", str(out), "--force")
        assert code == 1 and "refusing to overwrite an input file" in err, (out, err)
    assert src.read_bytes() == SII_XML.read_bytes()


def test_second_project_new_needs_force(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    out = tmp_path / "machine.yaml"
    assert run(capsys, "project", "new", "--profile", "hdt", "-o", str(out))[0] == 0
    out.write_text("# mine\n")
    code, _, err = run(capsys, "project", "new", "--profile", "hdt", "-o", str(out))
    assert code == 1 and err.strip().endswith("file exists; use --force to overwrite it") and str(out) in err
    assert out.read_text() == "# mine\n"
    assert run(capsys, "project", "new", "--profile", "hdt", "-o", str(out), "--force")[0] == 0
    assert "drives:" in out.read_text()


def test_map_sdo_force_also_allows_overwriting(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    """map sdo has one --force (print despite mapping errors); it is also the overwrite flag."""
    out = tmp_path / "sdo.json"
    out.write_text("old")
    args = ("map", "sdo", "--profile", "technosoft-ipos", "-o", str(out))
    assert run(capsys, *args)[0] == 1 and out.read_text() == "old"
    assert run(capsys, *args, "--force")[0] == 0 and out.read_text().startswith("[")


def test_library_write_atomic_refuses_existing_without_overwrite(tmp_path: Path) -> None:
    out = tmp_path / "o.txt"
    write_atomic(out, "one", overwrite=False)
    with pytest.raises(InputError, match="file exists"):
        write_atomic(out, "two", overwrite=False)
    write_atomic(out, "three")  # the library's default replaces, like open(..., 'w')
    assert out.read_text() == "three"


def test_stale_temporaries_of_dead_writers_are_cleaned(tmp_path: Path) -> None:
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True,
                          check=True).stdout.strip()
    stale = tmp_path / f".out.bin.{dead}.0123abcd.tmp"
    stale.write_bytes(b"x" * 1000)
    alive = tmp_path / f".out.bin.{os.getppid()}.0123abcd.tmp"  # a running writer's: kept
    alive.write_bytes(b"y")
    foreign = tmp_path / f".notes.{dead}.tmp"  # not ecattool's naming: kept
    foreign.write_bytes(b"z")
    write_atomic(tmp_path / "other.txt", "data")
    assert not stale.exists() and alive.exists() and foreign.exists()
    assert clean_stale_temporaries(tmp_path) == []


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT])
def test_signal_while_writing_leaves_no_temporary(tmp_path: Path, signum: int) -> None:
    """A writer interrupted between creating its temporary file and renaming it removes the file."""
    script = (
        "import os, signal, sys\n"
        "from ecattool import fileio\n"
        "real = os.fsync\n"
        "def slow(fd):\n"
        f"    os.kill(os.getpid(), {int(signum)})\n"
        "    real(fd)\n"
        "os.fsync = slow\n"
        "fileio.write_atomic(sys.argv[1], b'x' * 100000)\n"
    )
    out = tmp_path / "big.bin"
    # the default disposition in the child: a test runner's worker may ignore SIGINT, and a child inherits that
    proc = subprocess.run([sys.executable, "-c", script, str(out)], cwd=ROOT, capture_output=True, timeout=120,
                          preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    assert proc.returncode != 0
    assert list(tmp_path.iterdir()) == []


def test_a_dangling_link_is_not_followed_out_of_the_folder(tmp_path: Path) -> None:
    """Issue 37.5: a link left in a shared folder pointing anywhere (here: another folder) is never a way to make
    ecattool create a file there without --force; the library refuses it up front too (check_output)."""
    from ecattool.fileio import check_output

    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    link = tmp_path / "out.bin"
    link.symlink_to(elsewhere / "planted")
    with pytest.raises(InputError, match="does not exist; use --force"):
        check_output(link)
    with pytest.raises(InputError, match="does not exist; use --force"):
        write_atomic(link, b"data", overwrite=False)
    assert list(elsewhere.iterdir()) == []
    write_atomic(link, b"data", overwrite=True)
    assert (elsewhere / "planted").read_bytes() == b"data" and link.is_symlink()


def test_force_keeps_the_replaced_files_mode(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    """Issue 37.5: --force replaces the content, not the permissions someone gave the file."""
    out = tmp_path / "slave.bin"
    out.write_bytes(b"old")
    os.chmod(out, 0o640)
    code, _, err = run(capsys, "sii", "build", str(SII_XML), "-o", str(out), "--force")
    assert code == 0, err
    assert stat.S_IMODE(out.stat().st_mode) == 0o640 and out.read_bytes() != b"old"
    os.chmod(out, 0o755)
    write_atomic(out, b"new")
    assert stat.S_IMODE(out.stat().st_mode) == 0o755 and out.read_bytes() == b"new"


@pytest.mark.skipif(os.geteuid() != 0, reason="changing a file's owner needs root")
def test_force_keeps_the_replaced_files_owner_where_it_can(tmp_path: Path) -> None:
    out = tmp_path / "owned.bin"
    out.write_bytes(b"old")
    os.chown(out, 1234, 5678)
    write_atomic(out, b"new")
    st = out.stat()
    assert (st.st_uid, st.st_gid, out.read_bytes()) == (1234, 5678, b"new")


def test_two_writers_racing_for_one_absent_output_one_wins(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Issue 37.5: "the output does not exist" is decided atomically. The second writer is let in exactly between
    the first one's check and its final step (its fsync): without --force only one of them may succeed, and the
    file holds the winner's content whole."""
    from ecattool import fileio

    out = tmp_path / "out.txt"
    real_fsync = os.fsync
    results: list[str] = []

    def racing_fsync(fd: int) -> None:
        monkeypatch.setattr(fileio.os, "fsync", real_fsync)  # the second writer runs unhindered
        try:
            write_atomic(out, b"second", overwrite=False)
            results.append("second")
        except InputError as exc:
            results.append(f"second refused: {exc.message}")
        real_fsync(fd)

    monkeypatch.setattr(fileio.os, "fsync", racing_fsync)
    try:
        write_atomic(out, b"first", overwrite=False)
        results.append("first")
    except InputError as exc:
        results.append(f"first refused: {exc.message}")
    assert results == ["second", "first refused: file exists; use --force to overwrite it"]
    assert out.read_bytes() == b"second"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.txt"]  # no temporary file left behind
