"""File input/output helpers shared by every reader and writer.

Reading: every input is bounded by the bytes actually read (``/dev/zero``, a FIFO or an endless standard input
ends in an error at the limit, never fills the memory); the size a file claims on disk is not trusted.

Writing (:func:`write_atomic`):

- a regular file is replaced through a temporary file and a rename: either the complete new content is there
  afterwards or the old file is untouched;
- a path that is not a regular file (a device such as ``/dev/null``, a FIFO, ``/dev/stdout``) is written
  *through*, as a stream: it is never replaced by a regular file; a UNIX socket is refused (an output is a file
  or a stream, never a message to whatever listens there);
- a symbolic link to an existing file is followed: the file it points to gets the content, the link stays; a
  *dangling* link (its file does not exist) is followed only with ``overwrite=True``: without it, creating a file
  wherever a link points is refused (resolved in user space, the kernel's ``protected_symlinks`` cannot stop it);
- an existing file is replaced only with ``overwrite=True`` (the CLI's ``--force``), and never when it is one of
  the command's inputs (by identity of the file, not by name); the replacement keeps the replaced file's mode
  (and its owner and group where the process may set them);
- without ``overwrite``, "the output does not exist yet" is decided atomically: the complete temporary file is
  hard-linked to the output's name, which fails when the name exists, so of two writers racing for one absent
  output only one succeeds (on a file system without hard links: an exclusive create of the name, then the
  rename);
- the temporary file is removed when the process is interrupted (SIGINT, SIGTERM) while writing, and the
  temporary files of ecattool writers that died (SIGKILL, power loss) are removed at the next write into the same
  folder: ``.NAME.PID.RANDOM.tmp`` whose PID no longer runs.
"""

from __future__ import annotations

import os
import re
import stat
import sys
from collections.abc import Iterable
from pathlib import Path
from typing import Any, BinaryIO

from ecattool.errors import InputError, Location

#: Largest input ecattool reads when a reader names no smaller limit (the largest real ESI files are a few MB).
DEFAULT_MAX_BYTES = 64 * 1024 * 1024

#: the name of a temporary file beside an output: ``.NAME.PID.RANDOM.tmp``
_TMP_NAME = re.compile(r"^\..+\.(\d+)\.[0-9a-f]{8}\.tmp$")


def _too_large(limit: int, where: Location) -> InputError:
    return InputError(f"input is larger than the {limit} byte limit (reading stopped there)", where)


def read_stream(fh: BinaryIO, source: str, max_bytes: int | None = None) -> bytes:
    """At most ``max_bytes`` (default :data:`DEFAULT_MAX_BYTES`) bytes of an open binary stream; an
    :class:`InputError` naming ``source`` when there is more (the stream is not read further)."""
    limit = DEFAULT_MAX_BYTES if max_bytes is None else max_bytes
    chunks: list[bytes] = []
    total = 0
    while True:
        chunk = fh.read(min(1 << 20, limit + 1 - total))
        if not chunk:
            return b"".join(chunks)
        chunks.append(chunk)
        total += len(chunk)
        if total > limit:
            raise _too_large(limit, Location(source))


def read_stdin(max_bytes: int | None = None, source: str = "<stdin>") -> bytes:
    """Standard input as bytes, bounded like :func:`read_bytes`."""
    return read_stream(sys.stdin.buffer, source, max_bytes)


def read_bytes(path: str | Path, max_bytes: int | None = None) -> bytes:
    """The bytes of ``path``, at most ``max_bytes`` (default :data:`DEFAULT_MAX_BYTES`) of them, counted as they
    are read (a device or FIFO has no size on disk); every failure is an :class:`InputError` naming the file."""
    p = Path(path)
    if str(path) == "":
        raise InputError("empty file name", Location("''"))
    try:
        with open(p, "rb") as fh:
            return read_stream(fh, str(p), max_bytes)
    except OSError as exc:
        raise InputError(f"cannot read file: {exc.strerror or exc}", Location(str(p))) from None


def named_file_problem(path: str | Path) -> str | None:
    """Why the file a project (or another input) names cannot be read as a file, in a few words, or None when it
    is a regular file (links followed). Checked before a named file is opened, so that a FIFO never blocks the
    reader, a device is never read, and a name longer than the system allows, a directory or a loop of links are
    one-line findings, never a traceback. Says nothing of the file's content."""
    import errno

    name = str(path)
    if name == "":
        return "empty file name"
    try:
        st = os.stat(name)
    except ValueError:
        return "the file name holds a NUL character"
    except OSError as exc:
        if exc.errno == errno.ENAMETOOLONG:
            longest = max((len(part.encode("utf-8", "surrogateescape")) for part in Path(name).parts), default=0)
            return (f"the file name is longer than the system allows ({len(name.encode('utf-8', 'surrogateescape'))} "
                    f"bytes, the longest part {longest})")
        if exc.errno in (errno.ENOENT, errno.ENOTDIR):
            return "not found"
        if exc.errno == errno.ELOOP:
            return "too many levels of symbolic links"
        return f"cannot read file: {exc.strerror or exc}"
    mode = st.st_mode
    if stat.S_ISREG(mode):
        return None
    kind = ("a directory" if stat.S_ISDIR(mode) else "a FIFO (named pipe)" if stat.S_ISFIFO(mode)
            else "a character device" if stat.S_ISCHR(mode) else "a block device" if stat.S_ISBLK(mode)
            else "a socket" if stat.S_ISSOCK(mode) else "not a regular file")
    return f"is {kind}, not a file"


def read_input(path: str | Path, max_bytes: int | None = None) -> bytes:
    """:func:`read_bytes`, or standard input when ``path`` is '-'."""
    return read_stdin(max_bytes) if str(path) == "-" else read_bytes(path, max_bytes)


def _identity(path: str | Path) -> tuple[int, int] | None:
    try:
        st = os.stat(path)
    except (OSError, ValueError):
        return None
    return (st.st_dev, st.st_ino)


def refuse_input(path: str | Path, inputs: Iterable[str | Path]) -> None:
    """Raise :class:`InputError` when ``path`` is one of ``inputs`` — the same file (device and inode, links
    followed), whatever name either is given by (checked before long work that ends in a write)."""
    target = _identity(path)
    if target is None:
        return
    for src in inputs:
        if src is None or str(src) in ("", "-"):
            continue
        if _identity(src) == target:
            st = os.stat(path)
            if stat.S_ISREG(st.st_mode) or stat.S_ISDIR(st.st_mode):
                raise InputError("refusing to overwrite an input file; choose another output",
                                 Location(str(path)))


def refuse_existing(path: str | Path, overwrite: bool, flag: str = "--force") -> None:
    """Raise :class:`InputError` when ``path`` is an existing regular file (a link to one counts) and ``overwrite``
    is false, or a symbolic link whose file does not exist (a dangling link is followed only with ``overwrite``);
    devices and FIFOs are streams and never refused; a UNIX socket is always refused."""
    if str(path) in ("", "-"):
        return
    try:
        st = os.stat(path)
    except (OSError, ValueError):
        st = None
    if st is not None and stat.S_ISSOCK(st.st_mode):
        raise InputError("is a UNIX socket, not a file or a stream: choose another output", Location(str(path)))
    if overwrite:
        return
    if st is None:
        if _dangling(path):
            raise InputError(f"is a symbolic link to {os.readlink(path)!r}, which does not exist; use {flag} to "
                             "create the file it points to", Location(str(path)))
        return
    if stat.S_ISREG(st.st_mode) and not _is_stream_path(path):
        raise InputError(f"file exists; use {flag} to overwrite it", Location(str(path)))


def _dangling(path: str | Path) -> bool:
    """Whether ``path`` is a symbolic link whose file (at the end of the chain) does not exist."""
    try:
        return stat.S_ISLNK(os.lstat(path).st_mode) and not os.path.exists(path)
    except (OSError, ValueError):
        return False


def check_output(path: str | Path, inputs: Iterable[str | Path] = (), overwrite: bool = False,
                 flag: str = "--force") -> None:
    """Everything :func:`write_atomic` would refuse, checked up front (before long work that ends in a write)."""
    if str(path) == "":
        raise InputError("empty output file name", Location("''"))
    refuse_input(path, inputs)
    refuse_existing(path, overwrite, flag)


_STREAM_NAME = re.compile(r"^/(?:dev/(?:stdout|stderr|stdin|fd/\d+)|proc/(?:self|thread-self|\d+)/fd/\d+)$")


def _is_stream_path(path: str | Path) -> bool:
    """A path that names a process's stream rather than a file on disk (``/dev/stdout``, ``/dev/fd/1``,
    ``/proc/self/fd/1``): written through even when it ends in a regular file (the shell opened it, maybe for
    appending)."""
    return bool(_STREAM_NAME.match(os.path.normpath(str(path))))


def _stream_write(target: str, payload: bytes) -> None:
    """Write through a device, FIFO, socket or process stream without replacing it."""
    try:
        own = _own_descriptor(target)
        if own is not None:  # /dev/stdout, /dev/fd/N: the descriptor itself, at its offset (shell '>' and '>>')
            for stream in (sys.stdout, sys.stderr):
                try:
                    if stream is not None and stream.fileno() == own:
                        stream.flush()
                except (OSError, ValueError, AttributeError):
                    pass
            _write_all(own, payload)
            return
        st = os.stat(target)
        if stat.S_ISSOCK(st.st_mode):  # refused before (refuse_existing); a socket that appeared since too
            raise InputError("is a UNIX socket, not a file or a stream: choose another output", Location(target))
        # another process's descriptor that ends in a regular file: appended to, never truncated
        flags = os.O_WRONLY | getattr(os, "O_BINARY", 0) | (os.O_APPEND if stat.S_ISREG(st.st_mode) else 0)
        fd = os.open(target, flags)
        try:
            _write_all(fd, payload)
        finally:
            os.close(fd)
    except OSError as exc:
        raise InputError(f"cannot write file: {exc.strerror or exc}", Location(target)) from None


def _write_all(fd: int, payload: bytes) -> None:
    view = memoryview(payload)
    while view:
        n = os.write(fd, view)
        view = view[n:]


def _own_descriptor(target: str) -> int | None:
    """The descriptor number when ``target`` names one of this process's own (``/dev/stdout``, ``/dev/fd/3``,
    ``/proc/self/fd/1``), and it is open."""
    path = os.path.normpath(target)
    m = re.match(r"^/(?:dev/fd|proc/(?:self|thread-self|(\d+))/fd)/(\d+)$", path)
    if m and m.group(1) is not None and int(m.group(1)) != os.getpid():
        return None
    number = int(m.group(2)) if m else {"/dev/stdout": 1, "/dev/stderr": 2}.get(path)
    if number is None:
        return None
    try:
        os.fstat(number)
    except OSError:
        return None
    return number


def clean_stale_temporaries(folder: str | Path) -> list[Path]:
    """Remove the temporary files of ecattool writers that no longer run (``.NAME.PID.RANDOM.tmp`` in ``folder``,
    owned by this user, whose PID is not a running process); returns what was removed."""
    removed: list[Path] = []
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return removed
    uid = os.getuid() if hasattr(os, "getuid") else None
    for entry in entries:
        m = _TMP_NAME.match(entry.name)
        if not m:
            continue
        pid = int(m.group(1))
        if pid == os.getpid() or _running(pid):
            continue
        try:
            st = entry.stat(follow_symlinks=False)
            if not stat.S_ISREG(st.st_mode) or (uid is not None and st.st_uid != uid):
                continue
            os.unlink(entry.path)
            removed.append(Path(entry.path))
        except OSError:
            continue
    return removed


def _running(pid: int) -> bool:
    if pid <= 0:
        return True  # not a PID this naming produces: leave it alone
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError, OSError):
        return True
    return True


#: temporary files being written now, removed by the signal handler
_LIVE: set[str] = set()


def _on_signal(signum: int, frame: Any) -> None:
    import signal

    for tmp in list(_LIVE):
        try:
            os.unlink(tmp)
        except OSError:
            pass
        _LIVE.discard(tmp)
    previous = _PREVIOUS.pop(signum, signal.SIG_DFL)
    signal.signal(signum, previous)
    if callable(previous):  # Python's own SIGINT handler raises KeyboardInterrupt, as without this one
        previous(signum, frame)
    else:  # the default action (SIGTERM: end the process), now that the temporary file is gone
        os.kill(os.getpid(), signum)


_PREVIOUS: dict[int, Any] = {}


def _guard_signals() -> list[int]:
    """Route SIGTERM (and SIGINT when it has no Python handler) through :func:`_on_signal` while a temporary file
    exists; returns the signals to restore."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        return []
    installed: list[int] = []
    for signum in (signal.SIGTERM, signal.SIGINT):
        try:
            previous = signal.getsignal(signum)
            if previous is signal.SIG_IGN or previous is _on_signal:
                continue
            _PREVIOUS[signum] = previous
            signal.signal(signum, _on_signal)
            installed.append(signum)
        except (ValueError, OSError):  # pragma: no cover - not the main interpreter
            continue
    return installed


def _restore_signals(installed: list[int]) -> None:
    import signal

    for signum in installed:
        previous = _PREVIOUS.pop(signum, None)
        if previous is not None:
            signal.signal(signum, previous)


def write_atomic(path: str | Path, data: bytes | str, inputs: Iterable[str | Path] = (),
                 overwrite: bool = True, flag: str = "--force") -> None:
    """Write ``data`` to ``path``: a regular file through a temporary file and a rename, anything else (device,
    FIFO, socket, ``/dev/stdout``) as a stream; a symbolic link is followed.

    Refuses to write over any of ``inputs`` (the files the output was made from) and, unless ``overwrite``, over an
    existing regular file (``flag`` names the option that allows it in the error)."""
    if str(path) == "":
        raise InputError("empty output file name", Location("''"))
    check_output(path, inputs, overwrite, flag)
    payload = data.encode("utf-8") if isinstance(data, str) else data
    name = str(path)
    try:
        st: os.stat_result | None = os.stat(name)
    except FileNotFoundError:
        st = None
    except OSError as exc:
        raise InputError(f"cannot write file: {exc.strerror or exc}", Location(name)) from None
    if (st is not None and not stat.S_ISREG(st.st_mode)) or _is_stream_path(name):
        if st is not None and stat.S_ISDIR(st.st_mode):
            raise InputError("cannot write file: is a directory", Location(name))
        if st is None:  # /dev/fd/N of a descriptor that is not open: no file is created there
            raise InputError("cannot write file: no such stream", Location(name))
        _stream_write(name, payload)
        return
    # a symbolic link (or a chain of them) is followed: the file it points to is replaced, the link stays
    target = Path(os.path.realpath(name)) if os.path.islink(name) else Path(name)
    clean_stale_temporaries(target.parent if str(target.parent) else ".")
    # An exclusive temporary name beside the target (same file system, so the rename is atomic). Not
    # tempfile.mkstemp: importing tempfile costs ~15 ms of a CLI run, and mkstemp makes 0600 files where an
    # output should get the user's umask like any other file.
    installed = _guard_signals()
    try:
        for _ in range(16):
            tmp = target.with_name(f".{target.name}.{os.getpid()}.{os.urandom(4).hex()}.tmp")
            try:
                fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0), 0o666)
                _LIVE.add(str(tmp))
                break
            except FileExistsError:
                continue
            except OSError as exc:
                raise InputError(f"cannot write file: {exc.strerror or exc}", Location(name)) from None
        else:  # pragma: no cover - 16 collisions of 32 random bits
            raise InputError("cannot create a temporary file beside the output", Location(name))
        try:
            with os.fdopen(fd, "wb") as fh:
                if st is not None:
                    _keep_mode(fh.fileno(), st)
                fh.write(payload)
                fh.flush()
                os.fsync(fh.fileno())
            if overwrite:
                os.replace(tmp, target)
            else:
                _link_new(tmp, target, name, flag)
        except BaseException as exc:
            try:
                os.unlink(tmp)
            except OSError:
                pass
            if isinstance(exc, OSError):
                raise InputError(f"cannot write file: {exc.strerror or exc}", Location(name)) from None
            raise
        finally:
            _LIVE.discard(str(tmp))
    finally:
        _restore_signals(installed)


def _keep_mode(fd: int, old: os.stat_result) -> None:
    """Give the temporary file (open as ``fd``) the owner, group and mode of the file it replaces: the owner first
    (a change of owner clears set-user-ID bits), where this process may set them (root; a group it is in)."""
    if hasattr(os, "fchown"):
        for uid, gid in ((old.st_uid, old.st_gid), (-1, old.st_gid)):
            try:
                os.fchown(fd, uid, gid)
                break
            except OSError:
                continue
    try:
        os.fchmod(fd, stat.S_IMODE(old.st_mode))
    except OSError:
        pass


def _link_new(tmp: Path, target: Path, name: str, flag: str) -> None:
    """Give the complete temporary file the name ``target`` only if that name does not exist (a hard link fails
    then, atomically: of two writers racing for one absent output one succeeds), then drop the temporary name."""
    import errno

    try:
        os.link(tmp, target)
    except FileExistsError:
        raise InputError(f"file exists; use {flag} to overwrite it", Location(name)) from None
    except OSError as exc:
        if exc.errno not in (errno.EPERM, errno.EOPNOTSUPP, errno.ENOTSUP, errno.EMLINK, errno.EXDEV,
                             errno.ENOSYS):
            raise
        # a file system without hard links (vfat, some FUSE): claim the name exclusively, then rename over it
        try:
            os.close(os.open(target, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
        except FileExistsError:
            raise InputError(f"file exists; use {flag} to overwrite it", Location(name)) from None
        os.replace(tmp, target)
        return
    os.unlink(tmp)
