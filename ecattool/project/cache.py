"""A cache of parsed ESI files keyed by file content, so linting a large project is fast the second time.

Entries live in ``$ECATTOOL_CACHE_DIR`` (default ``~/.cache/ecattool``) as pickles named by the SHA-256 of
the ESI bytes and the ecattool version. A damaged or foreign entry is ignored and rebuilt. Set
``ECATTOOL_NO_CACHE=1`` to disable the cache.
"""

from __future__ import annotations

import hashlib
import os
import pickle
from pathlib import Path

from ecattool import __version__
from ecattool.esi.model import EsiFile
from ecattool.fileio import read_bytes, write_atomic

_MEMORY: dict[str, EsiFile] = {}


def cache_dir() -> Path:
    env = os.environ.get("ECATTOOL_CACHE_DIR")
    if env:
        return Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "ecattool"


def load_esi_cached(path: str | Path) -> EsiFile:
    """``ecattool.esi.load_bytes`` with a content-keyed memory and disk cache."""
    from ecattool import esi

    data = read_bytes(path)
    key = hashlib.sha256(data + b"\0ecattool " + __version__.encode()).hexdigest()
    hit = _MEMORY.get(key)
    if hit is not None:
        return hit
    use_disk = not os.environ.get("ECATTOOL_NO_CACHE")
    file = cache_dir() / "esi" / f"{key}.pickle"
    if use_disk and file.exists():
        try:
            with open(file, "rb") as fh:
                obj = pickle.load(fh)
            if isinstance(obj, EsiFile):
                obj.source = str(path)
                _MEMORY[key] = obj
                return obj
        except Exception:  # a damaged cache entry is rebuilt
            pass
    obj = esi.load_bytes(data, str(path))
    _MEMORY[key] = obj
    if use_disk:
        try:
            file.parent.mkdir(parents=True, exist_ok=True)
            write_atomic(file, pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL))
        except Exception:  # a read-only cache directory only costs speed
            pass
    return obj
