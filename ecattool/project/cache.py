"""Caches that keep linting a large project fast the second time, keyed by file content.

Entries live in ``$ECATTOOL_CACHE_DIR`` (default ``~/.cache/ecattool``) as pickles named by a SHA-256 of the
ESI bytes, the ecattool version, the code that decides what a cached object holds (:func:`code_digest`: the
source files of ``esi``, ``od`` and ``profiles``, ``record`` and this module, read once per process, so a
development checkout between two versions does not serve devices parsed by older code) and what else the entry
depends on:

- ``device/<key>.pickle``: a device selected from an ESI and completed for use (default modules in its
  slots, synthesised mapping and assignment objects), keyed also by the selector, the policy and the path
  (its locations name the file). Completing copies the whole dictionary: the expensive part of a cold lint.
- ``check/<key>.pickle``: the structural findings of the selected device (``esi.checks.check_device`` of the
  device as the ESI describes it, before completion), keyed also by the selector, the policy and the path.

An ESI that names other files (``DictionaryFile``, ``InfoReference``) is keyed also by the names, sizes and
modification times of the XML files beside it and one directory down, where the reader finds them.

With both, a warm lint does not read the ESI at all. The parsed ``EsiFile`` itself is kept in memory only:
the reader is lazy, so parsing an ESI costs about what unpickling it would (docs/performance.md, "Lint").
Within one process every ESI, device and built-in profile is computed once and shared by every drive that
uses it (callers treat devices as read-only). A damaged or foreign entry is ignored and rebuilt. Set
``ECATTOOL_NO_CACHE=1`` to disable the disk cache.
"""

from __future__ import annotations

import functools
import hashlib
import os
import pickle
from pathlib import Path
from typing import TYPE_CHECKING

from ecattool import __version__, esi
from ecattool.esi import model as esi_model
from ecattool.esi.model import EsiFile
from ecattool.fileio import read_bytes, write_atomic
from ecattool.findings import Finding
from ecattool.od import model as od_model
from ecattool.record import Record

if TYPE_CHECKING:
    from ecattool.profiles.running import RunningDevice

_MEMORY: dict[str, EsiFile] = {}
_DEVICES: dict[str, RunningDevice] = {}
_CHECKS: dict[str, list[Finding]] = {}
_PROFILES: dict[tuple[str, str | None, str | None], RunningDevice] = {}
#: path -> ((mtime_ns, size), content key): a file used by many drives is read and hashed once per process
_DIGESTS: dict[str, tuple[tuple[int, int], str]] = {}


def cache_dir() -> Path:
    env = os.environ.get("ECATTOOL_CACHE_DIR")
    if env:
        return Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "ecattool"


def _model_layout() -> bytes:
    """The field names of every model record a cache entry pickles: an entry written by a build whose model had
    other fields (a development checkout between versions) gets another key instead of unpickling into objects
    that lack a field."""
    classes = [c for m in (esi_model, od_model) for c in vars(m).values()
               if isinstance(c, type) and issubclass(c, Record) and c.__module__ == m.__name__]
    return repr(sorted((c.__qualname__, c._fields) for c in classes)).encode()


_LAYOUT = hashlib.sha256(_model_layout()).digest()
#: the ecattool package directory
PACKAGE = Path(__file__).resolve().parent.parent
#: what decides what a cached device or finding list holds: the reader (esi), the dictionary model (od), the
#: completion of a device (profiles), the record classes pickled, and this module
CODE = ("esi", "od", "profiles", "record.py", "project/cache.py")


def code_digest(root: Path = PACKAGE, parts: tuple[str, ...] = CODE) -> bytes:
    """A SHA-256 of the names and bytes of every file (sources and package data) under ``parts`` of ``root``,
    in sorted order; compiled and cached files (``__pycache__``) are left out."""
    h = hashlib.sha256()
    for part in parts:
        top = root / part
        files = [top] if top.is_file() else sorted(p for p in top.rglob("*")
                                                   if p.is_file() and "__pycache__" not in p.parts)
        for f in files:
            h.update(f.relative_to(root).as_posix().encode() + b"\0" + f.read_bytes() + b"\0")
    return h.digest()


@functools.cache
def _code() -> bytes:
    return code_digest()


def _key(*parts: bytes) -> str:
    return hashlib.sha256(b"\0".join((*parts, b"ecattool " + __version__.encode(), _LAYOUT, _code()))).hexdigest()


def _disk_get(kind: str, key: str, cls: type) -> object | None:
    if os.environ.get("ECATTOOL_NO_CACHE"):
        return None
    file = cache_dir() / kind / f"{key}.pickle"
    if not file.exists():
        return None
    try:
        with open(file, "rb") as fh:
            obj = pickle.load(fh)
    except Exception:  # a damaged cache entry is rebuilt
        return None
    return obj if isinstance(obj, cls) else None


def _disk_put(kind: str, key: str, obj: object) -> None:
    if os.environ.get("ECATTOOL_NO_CACHE"):
        return
    try:
        file = cache_dir() / kind / f"{key}.pickle"
        file.parent.mkdir(parents=True, exist_ok=True)
        write_atomic(file, pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL))
    except Exception:  # a read-only cache directory only costs speed
        pass


def _content_key(path: str | Path) -> tuple[str, bytes | None]:
    """The content key of the file at ``path``, and its bytes when they had to be read (else None)."""
    st = os.stat(path)
    sig = (st.st_mtime_ns, st.st_size)
    known = _DIGESTS.get(str(path))
    if known is not None and known[0] == sig:
        return known[1], None
    data = read_bytes(path)
    key = _key(data, _references_signature(path, data))
    _DIGESTS[str(path)] = (sig, key)
    return key, data


def _references_signature(path: str | Path, data: bytes) -> bytes:
    """What an ESI that names other files (DictionaryFile, InfoReference) also depends on: the XML files beside
    it and one directory down (where the reader looks for them), by name, size and modification time."""
    if b"DictionaryFile" not in data and b"InfoReference" not in data:
        return b""
    base = Path(path).parent
    items = []
    for p in sorted([*base.glob("*.xml"), *base.glob("*/*.xml")]):
        try:
            st = p.stat()
        except OSError:
            continue
        items.append(f"{p.relative_to(base)}:{st.st_size}:{st.st_mtime_ns}")
    return "\n".join(items).encode()


def _esi(path: str | Path) -> EsiFile:
    key, data = _content_key(path)
    # by path too: the file's locations (and the device and check entries derived from it) name its path; the
    # same content at another path (a copy) is another file
    hit = _MEMORY.get(f"{key}\0{path}")
    if hit is not None:
        return hit
    if data is None:
        data = read_bytes(path)
        key = _key(data, _references_signature(path, data))
    # lazy: a selected device is built alone
    obj = _MEMORY[f"{key}\0{path}"] = esi.load_bytes(data, str(path), base_dir=Path(path).parent, lazy=True)
    return obj


def load_esi_cached(path: str | Path) -> EsiFile:
    """``ecattool.esi.load_bytes`` once per process for each file content."""
    return _esi(path)


def load_device_cached(path: str | Path, select: str | None, policy: str) -> RunningDevice:
    """The device ``select`` of the ESI at ``path`` as it runs (``profiles.running.as_running``), with a
    memory and disk cache keyed by the ESI content, the selector, the policy and the path. Shared: do not
    modify the returned device."""
    from ecattool.profiles.running import RunningDevice, as_running

    content, _ = _content_key(path)
    key = _key(content.encode(), str(select).encode(), policy.encode(), str(path).encode())
    hit = _DEVICES.get(key)
    if hit is not None:
        return hit
    obj = _disk_get("device", key, RunningDevice)
    if not isinstance(obj, RunningDevice):
        obj = as_running(esi.select(_esi(path), select, policy=policy))
        _disk_put("device", key, obj)
    _DEVICES[key] = obj
    return obj


def esi_findings_cached(path: str | Path, select: str | None, policy: str) -> list[Finding]:
    """The reader's findings about numbers inside the device ``select`` of the ESI at ``path`` (``esi-number-*`` of
    ``esi.device_findings``: identifiers read with a tolerated spelling) and its structural findings (``esi.checks.check_device``), not those of the file's other devices, with a memory and disk cache (content, selector, policy and path)."""
    from ecattool.esi.checks import check_device

    content, _ = _content_key(path)
    key = _key(content.encode(), b"check", str(select).encode(), policy.encode(), str(path).encode())
    hit = _CHECKS.get(key)
    if hit is not None:
        return hit
    obj = _disk_get("check", key, list)
    if not isinstance(obj, list) or not all(isinstance(f, Finding) for f in obj):
        doc = _esi(path)
        device = esi.select(doc, select, policy=policy)
        # the reader's findings about numbers inside the device (an entry Index '#x0x6040' read as 6040h: what
        # commission will use), then the structural ones
        numbers = [f for f in esi.device_findings(doc, device) if f.rule.startswith("esi-number")]
        obj = [*numbers, *check_device(device)]
        _disk_put("check", key, obj)
    _CHECKS[key] = obj
    return obj


def load_profile_cached(name: str, product: str | None, revision: str | int | None) -> RunningDevice:
    """A built-in family's device as it runs (``profiles.running.device_from_profile``) once per process for
    each (profile, product, revision). Shared: do not modify."""
    from ecattool.profiles.running import device_from_profile

    key = (name, product, None if revision is None else str(revision))
    hit = _PROFILES.get(key)
    if hit is None:
        hit = _PROFILES[key] = device_from_profile(name, product=product, revision=revision)
    return hit
