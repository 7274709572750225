"""From a project drive to what it means for the device: the Device, its rules, and its startup list.

Each step returns what it resolves and the findings it made (a :class:`~ecattool.project.slave.Found`)
instead of stopping at the first problem, so that ``lint`` can report all of them; ``commission`` refuses to
run when any of them is an error. :func:`ecattool.project.machine.build_slave` assembles the frozen
:class:`~ecattool.project.slave.Slave` from the values.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ecattool.errors import EcatToolError, EncodeError, InputError, Location
from ecattool.esi.model import Device
from ecattool.fileio import named_file_problem
from ecattool.findings import Finding, Severity
from ecattool.od.model import EcState, Entry, normalize_name
from ecattool.od.numbers import parse_address, parse_int
from ecattool.od.types import Kind
from ecattool.profiles.rules import NO_RULES
from ecattool.project.loader import LoadedProject
from ecattool.project.model import Drive, Parameter
from ecattool.project.slave import Found, SlaveDc
from ecattool.startup.model import StartupCommand

if TYPE_CHECKING:
    from ecattool.profiles.rules import FamilyRules

#: the state a slave is in while the commands of a transition are sent
TRANSITION_STATE = {
    "IP": EcState.PREOP, "PS": EcState.PREOP, "PP": EcState.PREOP, "PI": EcState.PREOP,
    "SP": EcState.SAFEOP, "SO": EcState.SAFEOP, "SS": EcState.SAFEOP, "SI": EcState.SAFEOP,
    "OS": EcState.OP, "OP": EcState.OP, "OI": EcState.OP,
    "IB": EcState.INIT, "BI": EcState.BOOT, "II": EcState.INIT,
}


def resolve_dc(drive: Drive, device: Device) -> SlaveDc | None:
    """The DC of ``drive`` on ``device``; None where the project has no ``dc`` or names an OpMode the device does
    not have (lint's PRJ040)."""
    dc = drive.dc
    if dc is None:
        return None
    mode = next((m for m in device.dc_opmodes if m.name == dc.opmode), None) if dc.opmode is not None else None
    if dc.assign_activate is not None:
        act = parse_int(dc.assign_activate)
    elif mode is not None:
        act = mode.assign_activate
    else:
        return None
    cycle = dc.cycle_ns if dc.cycle_ns is not None else (mode.cycle_time_sync0 or None if mode is not None else None)
    shift = dc.shift_ns if dc.shift_ns is not None else (mode.shift_time_sync0 if mode is not None else None)
    # SYNC1 as SYNC0: the project's values where given, else the OpMode's (a SYNC1 cycle of 0 given by the
    # project is kept: the ESC then pulses SYNC1 with every SYNC0)
    if dc.sync1_cycle_ns is not None:
        sync1: int | None = dc.sync1_cycle_ns
    else:
        sync1 = mode.cycle_time_sync1 or None if mode is not None else None
    if dc.sync1_shift_ns is not None:
        sync1_shift: int | None = dc.sync1_shift_ns
    else:
        sync1_shift = mode.shift_time_sync1 if mode is not None and sync1 is not None else None
    return SlaveDc(act, dc.opmode, cycle, shift, sync1, sync1_shift)


def _shown(name: str) -> str:
    """A file name as a finding quotes it: whole up to 160 characters, else its start and its end (where the file's
    own name is) with the length between (a name of 4,000 is not repeated whole)."""
    if len(name) <= 160:
        return repr(name)
    return f"{name[:40]!r}…{name[-80:]!r} ({len(name)} characters)"


def resolve_device(lp: LoadedProject, i: int) -> tuple[Device | None, FamilyRules | None, Found]:
    """The device of drive ``i`` as it runs (a built-in profile, or its ESI with the default modules plugged in
    and the communication objects completed) and its family rules; None where it does not resolve (the
    findings say why)."""
    ref = lp.project.drives[i].device
    found = Found()
    try:
        if ref.profile is not None:
            from ecattool.project.cache import load_profile_cached

            device = load_profile_cached(ref.profile, ref.product, ref.revision)
        else:
            from ecattool.project.cache import load_device_cached

            assert ref.esi is not None
            path = lp.resolve(ref.esi)
            problem = named_file_problem(path)  # a FIFO, a device, a directory, a name too long: never opened
            if problem == "not found":
                found.error("PRJ002", f"ESI file {ref.esi!r} not found (looked in {path})", lp.drive_location(i, "device", "esi"))
                return None, None, found
            if problem is not None:
                found.error("PRJ005", f"ESI file {_shown(ref.esi)}: {problem}", lp.drive_location(i, "device", "esi"))
                return None, None, found
            # the device as it runs: default modules in its slots, synthesised mapping/assignment objects
            device = load_device_cached(path, None if ref.select is None else str(ref.select), ref.policy)
    except EcatToolError as exc:
        if exc.location and exc.location.line:
            found.error("PRJ005", exc.message, exc.location)
        else:  # at the device entry; the ESI file (a directory, unreadable) named in the message then
            where = exc.location.file if exc.location else None
            found.error("PRJ005", f"{where}: {exc.message}" if where else exc.message, lp.drive_location(i, "device"))
        return None, None, found
    try:
        from ecattool import profiles

        return device, profiles.rules_for(device), found
    except EcatToolError as exc:  # pragma: no cover - rules_for only raises for broken data
        found.error("PRJ005", exc.message, lp.drive_location(i, "device"))
        return device, None, found


def resolve_address(device: Device, text: str | int, location: Location) -> tuple[int, int]:
    """``6060:00``, ``0x6060``, or an object name (``modes of operation``) → (index, sub)."""
    if isinstance(text, int):
        return text, 0
    try:
        return parse_address(text, location)
    except InputError:
        pass
    found = device.dictionary.find(text)
    if found is None:
        raise InputError(f"no object named {text!r} in the device dictionary (write it as 6060:00)", location)
    return found


#: a value as a project writes it (``parameters:``, ``esi_init_cmds:``)
WrittenValue = int | float | str | bool | list[int] | None


def _coerce(entry: Entry, value: WrittenValue, location: Location) -> int | float | str | bool | bytes | None:
    """Turn an engineering-form value into what the entry's data type encodes (bytes: the data as given)."""
    dt = entry.datatype
    if isinstance(value, str):
        v = value.strip()
        if v.lower().startswith("hex:"):
            try:
                return bytes.fromhex(v[4:].replace(" ", ""))
            except ValueError:
                raise InputError(f"{value!r} is not hex bytes", location) from None
        if dt is not None and dt.kind in (Kind.STRING, Kind.UNICODE, Kind.OCTETS):
            return value
        if entry.enum:
            for k, name in entry.enum.items():
                if normalize_name(name) == normalize_name(v):
                    return k
        if dt is not None and dt.kind is Kind.REAL:
            try:
                return float(v)
            except ValueError:
                raise InputError(f"{value!r} is not a number", location) from None
        return parse_int(v, location, "value")
    if isinstance(value, list):
        if not all(isinstance(b, int) and not isinstance(b, bool) and 0 <= b <= 255 for b in value):
            raise InputError("a list value is bytes: each item an integer 0..255", location)
        return bytes(value)
    return value


def encode_parameter(device: Device, p: Parameter, location: Location, value_location: Location,
                     rules: FamilyRules | None = None) -> tuple[StartupCommand | None, list[Finding]]:
    """One parameter as a startup command, or the findings that refuse it (``rules``: the family's
    FamilyRules, for objects the family restricts beyond the dictionary)."""
    out: list[Finding] = []

    def err(rule: str, msg: str, loc: Location = location) -> tuple[None, list[Finding]]:
        out.append(Finding(rule, Severity.ERROR, msg, loc))
        return None, out

    try:
        index, sub = resolve_address(device, p.object, location)
    except InputError as exc:
        return err("PRJ010", exc.message)
    obj = device.dictionary.get(index)
    if obj is None:
        return err("PRJ010", f"object 0x{index:04X} does not exist in {device.type_name}'s dictionary")
    entry = obj.entry(sub)
    if entry is None:
        return err("PRJ011", f"0x{index:04X} ({obj.name}) has no sub-index {sub}")
    known = rules or NO_RULES
    if index in known.pdo_only_indices:
        return err("PRJ012", f"0x{index:04X}:{sub:02X} ({entry.name}) can only be accessed cyclically on this drive "
                             "(it refuses SDO access with 0601 0000h); map it in an RxPDO instead")
    state = TRANSITION_STATE.get(p.transition, EcState.PREOP)
    if not entry.access.writable(state):
        if entry.access.writable():
            states = ", ".join(s.value for s in sorted(entry.access.write, key=lambda s: s.code))
            return err("PRJ012", f"0x{index:04X}:{sub:02X} ({entry.name}) is not writable in {state.value} "
                                 f"(transition {p.transition}); writable in {states}")
        return err("PRJ012", f"0x{index:04X}:{sub:02X} ({entry.name}) is read-only")
    try:
        value = _coerce(entry, p.value, value_location)
        if isinstance(value, bytes):
            data = value
            if entry.datatype is not None and entry.datatype.bits is not None and len(data) != entry.byte_size:
                return err("PRJ013", f"{len(data)} bytes given, 0x{index:04X}:{sub:02X} ({entry.name}) takes "
                                     f"{entry.byte_size}", value_location)
        else:
            data = entry.encode(value)
    except (EncodeError, InputError) as exc:
        return err("PRJ013", f"0x{index:04X}:{sub:02X} ({entry.name}, {entry.type_name}): {exc.message}", value_location)
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        if entry.minimum is not None and value < entry.minimum:
            return err("PRJ014", f"{value} is below the minimum {entry.minimum} of 0x{index:04X}:{sub:02X} ({entry.name})", value_location)
        if entry.maximum is not None and value > entry.maximum:
            return err("PRJ014", f"{value} is above the maximum {entry.maximum} of 0x{index:04X}:{sub:02X} ({entry.name})", value_location)
        if entry.values is not None and value not in entry.values and (index, sub) != (0x6060, 0):
            # a printed value list (decision Profiles-2); modes of operation are PRJ017's
            return err("PRJ014", f"{value} is not one of the values {sorted(entry.values)} of 0x{index:04X}:{sub:02X} ({entry.name})", value_location)
        modes = known.supported_modes
        if (index, sub) == (0x6060, 0) and modes and isinstance(value, int) and value not in modes and value != 0:
            # HDT and Control Techniques abort an unsupported mode (0609 0030h); Technosoft accepts it and
            # answers with emergency FF04h (manual §4.2.3)
            lenient = known.unsupported_mode_accepted
            out.append(Finding("PRJ017", Severity.WARNING if lenient else Severity.ERROR,
                               f"mode {value} is not supported by {device.type_name} (supported: "
                               + ", ".join(str(m) for m in modes) + ")"
                               + ("; the drive accepts it and reports emergency FF04h" if lenient else ""),
                               value_location))
            if not lenient:
                return None, out
        elif entry.enum and isinstance(value, int) and value not in entry.enum:
            out.append(Finding("PRJ015", Severity.WARNING,
                               f"{value} is not one of the documented values of {entry.name}: "
                               + ", ".join(f"{k}={v}" for k, v in sorted(entry.enum.items())), value_location))
    cmd = StartupCommand(
        transition=p.transition, index=index, subindex=sub, data=data,
        comment=p.comment or entry.name, type_name=entry.type_name,
        value=value if not isinstance(value, bytes) else value.hex(), source=value_location,
    )
    return cmd, out


def resolve_parameters(lp: LoadedProject, i: int, device: Device,
                       rules: FamilyRules | None) -> tuple[list[StartupCommand], Found]:
    """The ``parameters:`` of drive ``i`` as startup commands on ``device``, with the findings that refuse some."""
    found = Found()
    cmds: list[StartupCommand] = []
    seen: dict[tuple[int, int, str], int] = {}
    for j, p in enumerate(lp.project.drives[i].parameters):
        loc = lp.drive_location(i, "parameters", j, "object")
        vloc = lp.drive_location(i, "parameters", j, "value")
        cmd, findings = encode_parameter(device, p, loc, vloc, rules)
        found.extend(findings)
        if cmd is None:
            continue
        key = (cmd.index, cmd.subindex, cmd.transition)
        if key in seen:
            found.warning("PRJ016", f"{cmd.address} is written twice in {cmd.transition} (also parameter {seen[key] + 1}); "
                                    "the last write wins", loc)
        seen[key] = j
        cmds.append(cmd)
    return cmds, found
