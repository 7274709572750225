"""``project new --from-bus``: a project file written from what a live bus holds. Per slave: the device it
matches (a library ESI/EDS or a built-in family), the PDO assignment (1C12h/1C13h) and the mapping of each
assigned PDO as read over SDO, DC as the device description requires it, and the current values of the objects a
project usually sets (mode of operation, profile velocity and accelerations, following error window, quick stop
deceleration). The project lints clean and, sent back to the same bus, commissions it as it is."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

from ecattool.errors import EcatToolError, InputError, SdoAbort, TargetError
from ecattool.od.model import EcState
from ecattool.online.dictionary import identify
from ecattool.online.library import Library, Match, family_device
from ecattool.online.live import LiveBus, describe_slave, sii_facts

#: the objects a project usually sets, written as parameters with the value the drive holds now
USUAL_OBJECTS = ((0x6060, 0), (0x6065, 0), (0x6081, 0), (0x6083, 0), (0x6084, 0), (0x6085, 0))


def _u(slave: Any, index: int, sub: int) -> int:
    return int.from_bytes(slave.sdo_upload(index, sub), "little")


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


def _device_ref(match: Match, base: Path) -> str:
    if match.kind == "family":
        return f"      profile: {match.profile}\n      product: {match.product}\n"
    rel = os.path.relpath(Path(match.source).resolve(), base.resolve())
    return f"      esi: {_q(Path(rel).as_posix())}\n      select: {_q(match.selector)}\n"


def drive_yaml(slave: Any, name: str, match: Match, device: Any, base: Path) -> str:
    """The project lines of one slave. A slave without a CoE mailbox (its SII says so: a coupler, a digital
    terminal) is never sent an SDO: its process image is the fixed one of its device description."""
    from ecattool.project.skeleton import dc_only_mode

    lines = [f"  - name: {_q(name)}", f"    position: {slave.position}", "    device:" ]
    text = "\n".join(lines) + "\n" + _device_ref(match, base)
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
    mode = dc_only_mode(device)
    if mode is not None:
        text += f"    dc: {{opmode: {_q(mode)}, cycle_ns: 1000000}}  # the device runs only with DC; set your cycle\n"
    params = []
    for index, sub in USUAL_OBJECTS if coe else ():
        e = device.dictionary.entry(index, sub)
        if e is None or not e.access.writable(EcState.PREOP) or e.datatype is None or (index, sub) in rx_mapped:
            continue  # an object the outputs carry is set every cycle, not by a parameter
        try:
            value = e.decode(slave.sdo_upload(index, sub))
        except EcatToolError:
            continue
        if (index, sub) == (0x6060, 0) and value == 0:
            continue  # no mode selected: nothing to keep
        comment = _q(f"{e.name}, as read from the bus")
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
        sii_facts(slave)  # the SII first: whether the slave has a mailbox, and its name for any message
        try:
            ident, match = identify(slave, library)
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
        device = library.device(match) if match.kind == "esi" and library is not None else family_device(match)
        stem = "axis" if is_axis(device) else "io"
        try:
            drives.append(drive_yaml(slave, f"{stem}{slave.position + 1}", match, device, base))
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
