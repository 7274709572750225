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


def write_atomic(path: str | Path, data: bytes | str, inputs: Iterable[str | Path] = ()) -> None:
    """Write ``data`` to ``path`` through a temporary file and a rename.

    Either the complete new content is there afterwards or the old file is untouched. Refuses to
    overwrite any of ``inputs`` (the files the output was made from).
    """
    target = Path(path)
    for src in inputs:
        try:
            if target.exists() and Path(src).exists() and os.path.samefile(target, src):
                raise InputError("refusing to overwrite an input file; choose another output", Location(str(target)))
        except OSError:
            pass
    payload = data.encode("utf-8") if isinstance(data, str) else data
    directory = target.parent if str(target.parent) else Path(".")
    import tempfile  # here, not at module level: a few ms of every CLI start-up

    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=directory)
    except OSError as exc:
        raise InputError(f"cannot write file: {exc.strerror or exc}", Location(str(target))) from None
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
