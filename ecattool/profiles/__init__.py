"""Built-in drive families and the rules of every drive family.

Public API (others code against it):

- :func:`list_profiles` — the built-in families, their models, product codes and revisions;
- :func:`load` — a complete :class:`~ecattool.esi.model.Device` for ``"technosoft-ipos"``, ``"hdt"`` or
  ``"controltechniques"`` (optionally a product and a revision);
- :func:`rules_for` — the :class:`FamilyRules` of any device (built-in family by vendor id, else derived
  from its ESI); :func:`family_of` — the family name;
- :func:`family_rules` — a family's rules by name, without a device;
- :func:`complete_generic` — an ESI device with the communication objects its ESI leaves out (the rule; what
  callers use is :mod:`ecattool.profiles.running`, the one resolver of the device as it runs).

Example::

    from ecattool import profiles
    dev = profiles.load("technosoft-ipos", product="ipos4808-my-cat-sto", revision="F515K")
    rules = profiles.rules_for(dev)          # 64-bit PDOs, 8 entries, dummies only in RxPDOs …
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import replace
from types import ModuleType

from ecattool.errors import SelectionError
from ecattool.esi.model import Device
from ecattool.profiles._common import ProductInfo, ProfileInfo
from ecattool.profiles.generic import complete_generic, generic_rules, supported_modes_of
from ecattool.profiles.rules import NO_RULES, FamilyRules

__all__ = [
    "FamilyRules", "ProductInfo", "ProfileInfo", "complete_generic", "family_of", "family_rules", "list_profiles",
    "load", "rules_for", "PROFILE_NAMES",
]

#: profile name → module name (imported lazily: each family reads its data file on first use)
_MODULES = {
    "technosoft-ipos": "technosoft",
    "hdt": "hdt",
    "controltechniques": "controltechniques",
}
PROFILE_NAMES = tuple(_MODULES)
_ALIASES = {
    "technosoft": "technosoft-ipos", "ipos": "technosoft-ipos", "tml": "technosoft-ipos",
    "hdt-tomcat": "hdt", "tomcat": "hdt", "dgfox": "hdt", "ntt": "hdt",
    "ct": "controltechniques", "control-techniques": "controltechniques", "sm-ethercat": "controltechniques",
    "nidec": "controltechniques",
}


def _module(name: str) -> ModuleType:
    return importlib.import_module(f"ecattool.profiles.{_MODULES[name]}")


def _resolve(name: str) -> str:
    key = name.strip().lower()
    key = _ALIASES.get(key, key)
    if key not in _MODULES:
        raise SelectionError(f"unknown drive profile {name!r}; choose one of: {', '.join(PROFILE_NAMES)}")
    return key


def list_profiles() -> list[ProfileInfo]:
    """The built-in families with their models (product codes, known revisions)."""
    return [_module(n).INFO for n in PROFILE_NAMES]


def load(name: str, product: str | None = None, revision: str | int | None = None) -> Device:
    """A complete device of a built-in family.

    ``name``: ``technosoft-ipos`` / ``hdt`` / ``controltechniques`` (a few aliases such as ``technosoft``,
    ``ct`` are accepted). ``product``: one of the family's model keys (see :func:`list_profiles`; default
    the first). ``revision``: Technosoft firmware (``F515K``, ``F515I``, ``0x3531354B``…), Control Techniques
    SM-EtherCAT firmware (``01.02.00``); HDT has none. Raises :class:`SelectionError` for unknown names.

    HDT's product names (``tomcat``, ``dgfox``, ``ntt``) are accepted as profile names too.
    """
    key = _resolve(name)
    low = name.strip().lower()
    if key == "hdt" and product is None and low in ("tomcat", "dgfox", "ntt"):
        product = low
    loader: Callable[..., Device] = _module(key).load
    return loader(product, revision)


_BY_VENDOR = {0x000001A3: "technosoft-ipos", 0x00000289: "hdt", 0x000000F9: "controltechniques"}


def family_rules(name: str) -> FamilyRules:
    """The rules of a family by name, without a device: a built-in family's (its defaults where they depend on
    the model) or, for ``generic``, :data:`~ecattool.profiles.rules.NO_RULES` (a generic device's rules come
    from its ESI: :func:`rules_for`). Raises :class:`SelectionError` for an unknown name."""
    if name.strip().lower() == "generic":
        return NO_RULES
    rules: Callable[[], FamilyRules] = _module(_resolve(name)).rules
    return rules()


def family_of(device: Device) -> str:
    """``technosoft-ipos``, ``hdt``, ``controltechniques`` (by vendor id) or ``generic``."""
    if device.source.startswith("profile:") and device.source[8:] in _MODULES:
        return device.source[8:]
    return _BY_VENDOR.get(device.vendor_id, "generic")


def rules_for(device: Device) -> FamilyRules:
    """The family rules of ``device``: built-in family by vendor id (and product), else derived from its ESI."""
    fam = family_of(device)
    if fam == "generic":
        return generic_rules(device)
    rules: Callable[[Device], FamilyRules] = _module(fam).rules
    return own_modes(device, rules(device))


def own_modes(device: Device, rules: FamilyRules) -> FamilyRules:
    """A built-in family's rules for a device read from a CANopen EDS/DCF, with the modes its own 6502h
    (supported drive modes) lists: the family's list is what the family's firmware can do, the EDS says what this
    drive does. Standard modes (1-10) are kept where 6502h sets their bit; the family's manufacturer-specific
    (negative) modes where 6502h sets any of its manufacturer bits 16-31. Other devices, and an EDS without a
    6502h default, keep the family's list."""
    if device.extra.get("format") not in ("EDS", "DCF"):
        return rules
    e = device.dictionary.entry(0x6502, 0)
    value = e.default_value if e is not None else None
    if not isinstance(value, int) or not value:
        return rules
    standard = set(supported_modes_of(device.dictionary))
    modes = tuple(m for m in rules.supported_modes if m in standard or (m < 0 and value >> 16))
    return replace(rules, supported_modes=modes, dc_required_modes=tuple(m for m in rules.dc_required_modes
                                                                           if m in modes))
