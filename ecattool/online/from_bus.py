"""``project new --from-bus``: a project file written from what a live bus holds. Per slave: the device it
matches (a library ESI/EDS or a built-in family; among the models that share a product code, the one the SII's
name names), pinned to the revision found with the revision policy written, the PDO assignment (1C12h/1C13h)
and the mapping of each assigned PDO as read over SDO, DC as the slave runs it (its ESC's activation and SYNC0
cycle registers, read before the master reset the bus: :mod:`ecattool.online.bus_state`), and the current values
of the objects a project usually sets (mode of operation, profile velocity and accelerations, following error
window, quick stop deceleration). Paths are written as the user gave them (a symlink is not resolved), relative
to the project file. The project lints clean and, sent back to the same bus, commissions it as it is."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ecattool.errors import EcatToolError, InputError, SdoAbort, TargetError
from ecattool.esi.model import Device, Identity
from ecattool.od.model import EcState
from ecattool.online.library import Library, Match, family_device, family_match
from ecattool.online.live import LiveBus, describe_slave, sii_facts
from ecattool.target.base import entry_size

#: the objects a project usually sets, written as parameters with the value the drive holds now; the
#: interpolation period 60C2h (its unit, sub 2, before its value: a drive checks the period they make) that a
#: cyclic synchronous mode takes its set-points by (lint's PRJ044 against the SYNC0 cycle)
USUAL_OBJECTS = ((0x6060, 0), (0x6065, 0), (0x6081, 0), (0x6083, 0), (0x6084, 0), (0x6085, 0), (0x60C2, 2),
                 (0x60C2, 1))
#: the cyclic synchronous modes (CiA 402: csp, csv, cst): set-points taken on SYNC0
CYCLIC_SYNC_MODES = (8, 9, 10)


@dataclass(frozen=True)
class DcFound:
    """A slave's DC as it runs: the activation word (ESC 0x0980-0x0981, the ESI's AssignActivate) and the SYNC0
    and SYNC1 cycle times (0x09A0, 0x09A4) in ns."""

    assign_activate: int
    sync0_cycle_ns: int
    sync1_cycle_ns: int = 0


def dc_found(bus: LiveBus, slave: Any) -> DcFound | None:
    """The DC registers of ``slave`` as found: read with a raw frame before a real master reset the bus
    (``bus.found``), or the simulated drive's own (``dc_activation``); None where they could not be read."""
    f = bus.found_at(slave.position)
    if getattr(f, "assign_activate", None) is not None:
        return DcFound(int(f.assign_activate), int(f.sync0_cycle_ns or 0), int(f.sync1_cycle_ns or 0))
    read = getattr(slave, "dc_activation", None)
    if callable(read):
        act, sync0, sync1 = read()
        return DcFound(int(act), int(sync0), int(sync1))
    return None


def sii_found(bus: LiveBus, slave: Any) -> bytes | None:
    """The SII image of ``slave`` read through its ESC before the master opened (``bus.found``: a master whose
    binding reads no SII, KickCAT's); None where none was read."""
    image = getattr(bus.found_at(slave.position), "sii", None)
    return bytes(image) if image else None


def identify_named(slave: Any, library: Library | None, sii: bytes | None = None) -> tuple[Identity, Match | None]:
    """The slave's identity and the library device or built-in family it matches (library first); among the
    devices or models that share the identity, the one the SII's name string names. Where the master reads no
    identity (KickCAT reads 1018h: a slave without a mailbox has none to give), the identity of the SII image
    ``sii`` read before the master opened."""
    try:
        ident: Identity = slave.identity()
    except EcatToolError:
        if sii is None:
            raise
        from ecattool.sii.image import parse

        h = parse(sii, source=f"slave {slave.position} SII").header
        ident = Identity(h.vendor_id, h.product_code, h.revision)
    name = sii_facts(slave, sii).name
    match = library.match(ident, name) if library is not None else None
    return ident, match or family_match(ident, name)


def _u(slave: Any, index: int, sub: int) -> int:
    return int.from_bytes(slave.sdo_upload(index, sub, size=4), "little")  # PDO assignment and mapping: 32 bits at most


def read_pdos(slave: Any, assign: int) -> list[tuple[int, list[str]]]:
    """The PDOs assigned in ``assign`` (1C12h/1C13h) with their entries as ``0xIIII:SS/bits``."""
    out = []
    for i in range(1, _u(slave, assign, 0) + 1):
        pdo = _u(slave, assign, i)
        entries = []
        for j in range(1, _u(slave, pdo, 0) + 1):
            e = _u(slave, pdo, j)
            entries.append(f"0x{e >> 16:04X}:{(e >> 8) & 0xFF:02X}/{e & 0xFF}")
        out.append((pdo, entries))
    return out


def _q(text: str) -> str:
    return json.dumps(text, ensure_ascii=False)


def _portable(path: str, base: Path) -> str:
    """``path`` relative to the project's folder ``base`` as the user reaches it: absolute by the working folder,
    symlinks kept (a library linked in from elsewhere stays the path the user gave, so the project is portable)."""
    return Path(os.path.relpath(os.path.abspath(path), os.path.abspath(base))).as_posix()


@dataclass
class Pinned:
    """The device a slave is written as, pinned to the revision found: the project's ``device:`` and
    ``identity:`` lines and the device they resolve to."""

    text: str
    device: Device


def pin_device(match: Match, ident: Identity, library: Library | None, base: Path) -> Pinned:
    """The ``device:`` of a slave (``match``) with the revision it reports (``ident``) kept and the revision
    policy written: a library ESI device of that revision (``policy: exact``), else the newest of the library's
    revisions not newer (``newest-not-newer``, identity ``at-least``) or, where the library has only newer ones,
    its newest (identity ``ignore``: said in a comment); a built-in family at the firmware revision found."""
    from ecattool.project.cache import load_device_cached

    found = f"0x{ident.revision:08X}"
    if match.kind == "family":
        try:
            device = family_device_at(match, ident.revision)
        except EcatToolError as exc:
            device = family_device(match)
            return Pinned(f"      profile: {match.profile}\n      product: {match.product}\n"
                          f"    # the slave reports revision {found}, which the family does not know ({exc.message})\n"
                          "    identity: {revision: ignore}\n", device)
        firmware = device.extra.get("firmware")
        rev = _q(firmware) if firmware else found
        return Pinned(f"      profile: {match.profile}\n      product: {match.product}\n      revision: {rev}\n"
                      "    identity: {revision: exact}  # the revision found on the bus\n", device)
    path = _q(_portable(match.source, base))
    selector = f"0x{ident.product_code:08X}:{found}"
    if match.exact or library is None:
        device = load_device_cached(match.source, selector, "exact")
        return Pinned(f"      esi: {path}\n      select: {_q(selector)}\n      policy: exact\n"
                      "    identity: {revision: exact}  # the revision found on the bus\n", device)
    older = any(d.identity.revision <= ident.revision for d in library.devices if d.path == match.source
                and (d.identity.vendor_id, d.identity.product_code) == (ident.vendor_id, ident.product_code))
    policy, check = ("newest-not-newer", "at-least") if older else ("newest", "ignore")
    device = load_device_cached(match.source, selector, policy)
    return Pinned(f"      esi: {path}\n      select: {_q(selector)}\n      policy: {policy}\n"
                  f"    # the slave reports revision {found}; the library's file describes revision "
                  f"0x{device.identity.revision:08X}\n"
                  f"    identity: {{revision: {check}}}\n", device)


def family_device_at(match: Match, revision: int) -> Device:
    """The built-in family model of ``match`` at the revision ``revision`` (1018h:03 as the slave reports it)."""
    from ecattool.project.cache import load_profile_cached

    return load_profile_cached(match.profile, match.product, revision)


def dc_yaml(bus: LiveBus, slave: Any, device: Device, mode: int | None) -> str:
    """The ``dc:`` of a slave as it runs: its activation and SYNC0 cycle registers (the ESI's DC OpMode with that
    AssignActivate, else the word itself). Where the registers could not be read, a comment says so and the
    device's DC OpMode stands in where the slave needs one (an ESI with only DC modes, or a cyclic synchronous
    mode found in 6060h/6061h)."""
    from ecattool.profiles import rules_for
    from ecattool.project.skeleton import dc_only_mode

    dc = dc_found(bus, slave)
    if dc is not None and dc.assign_activate:
        names = [m.name for m in device.dc_opmodes if m.assign_activate == dc.assign_activate]
        what = f"opmode: {_q(names[0])}" if names else f"assign_activate: 0x{dc.assign_activate:04X}"
        cycle = f", cycle_ns: {dc.sync0_cycle_ns}" if dc.sync0_cycle_ns else ""
        # SYNC1 where the activation word switches it on (bit 10, SYNC1 active): its cycle register as it runs
        from ecattool.project.steps import SYNC1_ACTIVE

        sync1_on = bool(dc.assign_activate & SYNC1_ACTIVE) and dc.sync1_cycle_ns is not None
        sync1 = f", sync1_cycle_ns: {dc.sync1_cycle_ns}" if sync1_on else ""
        seen = f", SYNC1 cycle {dc.sync1_cycle_ns} ns" if sync1_on else ""
        return (f"    dc: {{{what}{cycle}{sync1}}}  # as found: AssignActivate 0x{dc.assign_activate:04X}, "
                f"SYNC0 cycle {dc.sync0_cycle_ns} ns{seen}\n")
    only = dc_only_mode(device)
    if dc is not None:  # read: the slave runs without SYNC signals
        if only is None:
            return ""
        return (f"    # found without DC (AssignActivate 0), but {device.type_name} runs only with it; set your cycle\n"
                f"    dc: {{opmode: {_q(only)}, cycle_ns: 1000000}}\n")
    needs = rules_for(device).dc_required_modes
    wants = mode is not None and (mode in CYCLIC_SYNC_MODES or mode in needs)
    active = [m.name for m in device.dc_opmodes if m.assign_activate]
    name = only or (active[0] if wants and active else None)
    note = (f"    # DC not read: {bus.spec} gave no ESC register read (AssignActivate 0x0980, SYNC0 cycle 0x09A0)"
            + (f"; the ESI's DC OpMode {name} is assumed, set your cycle\n" if name else "\n"))
    if name is None:
        return note if wants or device.dc_opmodes else ""
    return note + f"    dc: {{opmode: {_q(name)}, cycle_ns: 1000000}}\n"


def mode_found(slave: Any, device: Device) -> int | None:
    """The mode of operation the drive runs: 6060h, else (where it reads 0: the master sets it through the
    process data, or not yet) its display 6061h; None where neither reads."""
    for index in (0x6060, 0x6061):
        e = device.dictionary.entry(index, 0)
        if e is None or e.datatype is None:
            continue
        try:
            value = e.decode(slave.sdo_upload(index, 0, size=entry_size(e)))
        except EcatToolError:
            continue
        if isinstance(value, int) and value:
            return value
    return None


def drive_yaml(bus: LiveBus, slave: Any, name: str, pinned: Pinned) -> str:
    """The project lines of one slave. A slave without a CoE mailbox (its SII says so: a coupler, a digital
    terminal) is never sent an SDO: its process image is the fixed one of its device description."""
    device = pinned.device
    lines = [f"  - name: {_q(name)}", f"    position: {slave.position}", "    device:" ]
    text = "\n".join(lines) + "\n" + pinned.text
    coe = sii_facts(slave).coe is not False
    if not coe:
        text += "    # no CoE mailbox (its SII): its fixed process image, as its device description gives it\n"
    pdo = []
    rx_mapped: set[tuple[int, int]] = set()
    for key, assign in (("rx", 0x1C12), ("tx", 0x1C13)) if coe else ():
        try:
            pdos = read_pdos(slave, assign)
        except SdoAbort:
            continue  # no CoE assignment object: the device's fixed default
        if key == "rx":
            rx_mapped = {(int(e[2:6], 16), int(e[7:9], 16)) for _, entries in pdos for e in entries}
        if pdos:
            pdo.append(f"      {key}:")
            for index, entries in pdos:
                pdo.append(f"        - index: 0x{index:04X}")
                pdo.append("          entries: [" + ", ".join(_q(e) for e in entries) + "]")
    if pdo:
        text += "    pdo:\n" + "\n".join(pdo) + "\n"
    mode = mode_found(slave, device) if coe else None
    text += dc_yaml(bus, slave, device, mode)
    params = []
    for index, sub in USUAL_OBJECTS if coe else ():
        e = device.dictionary.entry(index, sub)
        if e is None or not e.access.writable(EcState.PREOP) or e.datatype is None or (index, sub) in rx_mapped:
            continue  # an object the outputs carry is set every cycle, not by a parameter
        try:
            value = e.decode(slave.sdo_upload(index, sub, size=entry_size(e)))
        except EcatToolError:
            continue
        comment = _q(f"{e.name}, as read from the bus")
        if (index, sub) == (0x6060, 0) and value == 0:
            if mode is None:
                continue  # no mode selected: nothing to keep
            value, comment = mode, _q(f"{e.name}: the mode the drive runs (6061h), as read from the bus")
        params.append(f"      - {{object: \"{index:04X}:{sub:02X}\", value: {value!r}, comment: {comment}}}")
    if params:
        text += "    parameters:\n" + "\n".join(params) + "\n"
    return text


def project_from_bus(bus: LiveBus, library: Library | None, output: str | Path | None,
                     name: str = "from-bus", problems: list[str] | None = None) -> str:
    """The text of a project file for every slave of ``bus`` (paths relative to ``output``'s folder). A slave
    that does not answer is named (position, name, identity) in ``problems`` and in a comment of the project,
    which goes on with the others; a bus where no slave answers is an error."""
    from ecattool.project.slave import is_axis

    base = Path(output).parent if output not in (None, "-") else Path(".")
    drives = []
    unknown = []
    failed: list[str] = []
    for slave in bus.slaves:
        sii = sii_found(bus, slave)
        sii_facts(slave, sii)  # the SII first: whether the slave has a mailbox, and its name for any message
        try:
            ident, match = identify_named(slave, library, sii)
        except EcatToolError as exc:
            hint = "" if sii_facts(slave).protocols is not None else (
                f" ({bus.spec} gives no SII: a slave without a mailbox has no identity to read here; use pysoem:IF)")
            text = str(exc).removeprefix(f"slave {slave.position}, ").removeprefix(f"slave {slave.position}: ")
            failed.append(f"{describe_slave(slave)}: {text}{hint}")
            continue
        if match is None:
            unknown.append(f"slave {slave.position} (vendor 0x{ident.vendor_id:08X}, product "
                           f"0x{ident.product_code:08X})")
            continue
        try:
            pinned = pin_device(match, ident, library, base)
            stem = "axis" if is_axis(pinned.device) else "io"
            drives.append(drive_yaml(bus, slave, f"{stem}{slave.position + 1}", pinned))
        except EcatToolError as exc:
            failed.append(f"{describe_slave(slave)}: {exc}")
    if unknown:
        raise InputError(f"no library file or built-in family describes {', '.join(unknown)}; give --library with "
                         "its ESI")
    if failed and not drives:
        raise TargetError("no slave answered: " + "; ".join(failed))
    if problems is not None:
        problems.extend(f"not written: {f}" for f in failed)
    target = bus.spec if not bus.spec.startswith("sim") else "sim"
    notes = "".join(f"# not written: {f}\n" for f in failed)
    return ("# ecattool project file (format 1), written by 'ecattool project new --from-bus'. Docs: docs/project.md\n"
            + notes + f"ecattool: 1\nname: {_q(name)}\ntarget: {_q(target)}\ndrives:\n" + "".join(drives))
