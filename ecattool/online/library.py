"""A device library: a folder of ESI (and EDS) files, matched to the slaves of a live bus by identity, with the
project's ESI cache (:mod:`ecattool.project.cache`) so a second scan does not parse the files again."""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TypeVar

from ecattool.errors import EcatToolError, InputError, Location
from ecattool.esi.model import Device, Identity

SUFFIXES = (".xml", ".eds", ".dcf")
T = TypeVar("T")


@dataclass(frozen=True, slots=True)
class LibraryDevice:
    """One device description in the library: its file, its identity and the selector that picks it."""

    path: str
    identity: Identity
    name: str

    @property
    def selector(self) -> str:
        return f"0x{self.identity.product_code:08X}:0x{self.identity.revision:08X}"

    def load(self) -> Device:
        from ecattool.project.cache import load_device_cached

        return load_device_cached(self.path, self.selector, "exact")


@dataclass(frozen=True, slots=True)
class Match:
    """What a slave's identity matched: ``kind`` is ``esi`` (a library file), ``family`` (a built-in profile) or
    ``device`` (one given); ``exact`` is False where only vendor and product match."""

    kind: str
    source: str
    name: str
    exact: bool
    selector: str = ""
    profile: str = ""
    product: str = ""

    def to_json(self) -> dict[str, object]:
        return {"kind": self.kind, "source": self.source, "name": self.name, "exact": self.exact,
                "selector": self.selector, "profile": self.profile, "product": self.product}


class Library:
    """The devices of the ESI/EDS files in ``folder`` (and its sub-folders), by identity."""

    def __init__(self, folder: str | Path | None) -> None:
        self.devices: list[LibraryDevice] = []
        #: files that did not load: (path, why)
        self.skipped: list[tuple[str, str]] = []
        if folder is None:
            return
        root = Path(folder)
        if not os.path.isdir(root):  # (Path.is_dir raises on a name too long)
            raise InputError(f"device library {str(root)!r} is not a folder", Location(str(root)))
        from ecattool.project.cache import load_esi_cached

        for path in sorted(p for p in root.rglob("*") if p.suffix.lower() in SUFFIXES and p.is_file()):
            try:
                esi = load_esi_cached(path)
                heads = getattr(esi, "device_heads", None) or esi.devices
                for h in heads:
                    self.devices.append(LibraryDevice(str(path), Identity(h.vendor_id, h.product_code,
                                                                          h.revision), str(getattr(h, "type_name", ""))))
            except EcatToolError as exc:
                self.skipped.append((str(path), str(exc)))

    def match(self, identity: Identity, name: str = "") -> Match | None:
        """The library device of ``identity``: exact, else the newest revision of the same product; among devices
        of the same identity, the one the SII's ``name`` names."""
        same = [d for d in self.devices if (d.identity.vendor_id, d.identity.product_code)
                == (identity.vendor_id, identity.product_code)]
        exact = named([d for d in same if d.identity.revision == identity.revision], name, lambda d: (d.name,))
        pick = exact[0] if exact else max(same, key=lambda d: d.identity.revision, default=None)
        if pick is None:
            return None
        return Match("esi", pick.path, pick.name, bool(exact), selector=pick.selector)

    def device(self, match: Match) -> Device:
        from ecattool.project.cache import load_device_cached

        return load_device_cached(match.source, match.selector, "exact")


def _words(text: str) -> str:
    return " ".join("".join(c if c.isalnum() else " " for c in text.lower()).split())


def named(candidates: list[T], name: str, names: Callable[[T], tuple[str, ...]]) -> list[T]:
    """``candidates`` with the ones the SII's ``name`` string names first (a name of theirs, e.g. "Digitax ST +
    SM-EtherCAT" or the key "digitax-st", found in it word for word; the longest such name first), the others
    after them in their order: models that share a product code (Control Techniques' SM-EtherCAT hosts) are told
    apart by what the slave calls itself."""
    said = f" {_words(name)} "
    if not said.strip():
        return list(candidates)

    def score(c: T) -> int:
        return max((len(w) for n in names(c) if (w := _words(n)) and f" {w} " in said), default=0)

    return sorted(candidates, key=lambda c: -score(c))


def family_match(identity: Identity, name: str = "") -> Match | None:
    """The built-in family model of ``identity`` (vendor and product code; the revision is the family's); among
    the models that share the product code, the one the SII's ``name`` names (else the first)."""
    from ecattool import profiles

    for info in profiles.list_profiles():
        if info.vendor_id != identity.vendor_id:
            continue
        models = named([p for p in info.products if p.product_code == identity.product_code], name,
                       lambda p: (p.title, p.name))
        if models:
            p = models[0]
            return Match("family", f"profile:{info.name}", p.title or p.name, False, profile=info.name,
                         product=p.name)
    return None


def family_device(match: Match) -> Device:
    from ecattool.project.cache import load_profile_cached

    return load_profile_cached(match.profile, match.product, None)
