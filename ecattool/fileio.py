"""File input/output helpers shared by every writer: atomic writes that never clobber an input."""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path

from ecattool.errors import InputError, Location


def read_bytes(path: str | Path, max_bytes: int | None = None) -> bytes:
    p = Path(path)
    try:
        if max_bytes is not None and p.stat().st_size > max_bytes:
            raise InputError(f"file is larger than {max_bytes} bytes", Location(str(p)))
        return p.read_bytes()
    except OSError as exc:
        raise InputError(f"cannot read file: {exc.strerror or exc}", Location(str(p))) from None


def refuse_input(path: str | Path, inputs: Iterable[str | Path]) -> None:
    """Raise :class:`InputError` when ``path`` is one of ``inputs`` (checked before long work that ends in a write)."""
    target = Path(path)
    for src in inputs:
        try:
            if target.exists() and Path(src).exists() and os.path.samefile(target, src):
                raise InputError("refusing to overwrite an input file; choose another output", Location(str(target)))
        except OSError:
            pass


def write_atomic(path: str | Path, data: bytes | str, inputs: Iterable[str | Path] = ()) -> None:
    """Write ``data`` to ``path`` through a temporary file and a rename.

    Either the complete new content is there afterwards or the old file is untouched. Refuses to
    overwrite any of ``inputs`` (the files the output was made from).
    """
    target = Path(path)
    refuse_input(target, inputs)
    payload = data.encode("utf-8") if isinstance(data, str) else data
    # An exclusive temporary name beside the target (same file system, so the rename is atomic). Not
    # tempfile.mkstemp: importing tempfile costs ~15 ms of a CLI run, and mkstemp makes 0600 files where an
    # output should get the user's umask like any other file.
    for _ in range(16):
        tmp = target.with_name(f".{target.name}.{os.getpid()}.{os.urandom(4).hex()}.tmp")
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0), 0o666)
            break
        except FileExistsError:
            continue
        except OSError as exc:
            raise InputError(f"cannot write file: {exc.strerror or exc}", Location(str(target))) from None
    else:  # pragma: no cover - 16 collisions of 32 random bits
        raise InputError("cannot create a temporary file beside the output", Location(str(target)))
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(payload)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, target)
    except BaseException as exc:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        if isinstance(exc, OSError):
            raise InputError(f"cannot write file: {exc.strerror or exc}", Location(str(target))) from None
        raise
