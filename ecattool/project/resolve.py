"""From a project drive to what it means for the device: the Device, its rules, and its startup list.

Each function returns findings instead of stopping at the first problem, so that ``lint`` can report all of
them; ``commission`` refuses to run when any of them is an error.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Literal

from ecattool.errors import EcatToolError, EncodeError, InputError, Location
from ecattool.esi.model import Device
from ecattool.fileio import named_file_problem
from ecattool.findings import Finding, Severity
from ecattool.od.model import EcState, Entry
from ecattool.od.numbers import parse_address, parse_int
from ecattool.od.types import Kind
from ecattool.project.loader import LoadedProject
from ecattool.project.model import Drive, Parameter
from ecattool.profiles.rules import NO_RULES
from ecattool.startup.model import StartupCommand, StartupList

if TYPE_CHECKING:
    from ecattool.pdo.model import Mapping
    from ecattool.profiles.rules import FamilyRules
    from ecattool.scaling.group import FactorGroup
    from ecattool.sw.image import SwImage

#: the state a slave is in while the commands of a transition are sent
TRANSITION_STATE = {
    "IP": EcState.PREOP, "PS": EcState.PREOP, "PP": EcState.PREOP, "PI": EcState.PREOP,
    "SP": EcState.SAFEOP, "SO": EcState.SAFEOP, "SS": EcState.SAFEOP, "SI": EcState.SAFEOP,
    "OS": EcState.OP, "OP": EcState.OP, "OI": EcState.OP,
    "IB": EcState.INIT, "BI": EcState.BOOT, "II": EcState.INIT,
}


#: what a slave is: a CiA-402 axis (enabled and moved by commission) or an I/O slave (terminals, couplers,
#: gateways: states, mapping and process data only)
SlaveKind = Literal["axis", "io"]


def is_axis(device: Device) -> bool:
    """Whether ``device`` is a CiA-402 axis: its dictionary has the controlword 6040h and the statusword 6041h,
    and it says it is a drive (profile 402 in the ESI ``<Profile>`` or the EDS/1000h device type) or has the
    modes of operation 6060h. A terminal that uses 6041h for something else (a diagnostics channel) or lacks
    6040h is an I/O slave (docs/decisions.md, "Machine: axis or I/O slave")."""
    od = device.dictionary
    if od.entry(0x6040, 0) is None or od.entry(0x6041, 0) is None:
        return False
    dtype = od.entry(0x1000, 0)
    declared = device.profile_no == 402
    if not declared and dtype is not None and dtype.default:
        declared = int.from_bytes(dtype.default[:2], "little") == 402
    return declared or od.entry(0x6060, 0) is not None


@dataclass(frozen=True, slots=True)
class SlaveDc:
    """Distributed clocks of a slave as the project sets them, resolved once (:func:`resolve_dc`): the
    AssignActivate word (the project's, else its ESI OpMode's), the SYNC0 cycle and shift (the project's, else
    the OpMode's), and SYNC1 where the OpMode gives a cycle for it."""

    assign_activate: int
    opmode: str | None = None
    cycle_ns: int | None = None
    shift_ns: int | None = None
    sync1_cycle_ns: int | None = None
    sync1_shift_ns: int | None = None

    @property
    def active(self) -> bool:
        """Whether the slave's SYNC signals are activated (a non-zero AssignActivate)."""
        return bool(self.assign_activate)


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
    sync1 = mode.cycle_time_sync1 or None if mode is not None else None
    sync1_shift = mode.shift_time_sync1 if mode is not None and sync1 else None
    return SlaveDc(act, dc.opmode, cycle, shift, sync1, sync1_shift)


@dataclass(slots=True)
class Slave:
    """One slave of the machine as the project sets it up: the device as it runs (default modules plugged in,
    communication objects completed), its family rules, PDO mapping, startup list, DC, and for an axis the
    factor group and ``.sw`` image; plus the findings that concern it. Built by
    :func:`ecattool.project.machine.load_machine`; never changed by the commands that consume it."""

    index: int
    drive: Drive
    device: Device | None = None
    rules: FamilyRules | None = None
    startup: StartupList = field(default_factory=StartupList)
    findings: list[Finding] = field(default_factory=list)
    mapping: Mapping | None = None  # when the pdo section (or the device default) resolved
    factor_group: FactorGroup | None = None  # when the scaling section resolved
    counts_per_unit: Fraction | None = None  # internal position units per position user unit (ideal)
    sw_image: SwImage | None = None  # when an image is configured and readable
    dc: SlaveDc | None = None  # when the project's dc section resolves on the device

    @property
    def position(self) -> int:
        return self.drive.position if self.drive.position is not None else self.index

    @property
    def name(self) -> str:
        return self.drive.name

    @property
    def kind(self) -> SlaveKind:
        """``axis`` where the device is a CiA-402 drive (:func:`is_axis`), else ``io``."""
        return "axis" if self.device is not None and is_axis(self.device) else "io"

    @property
    def enables(self) -> bool:
        """Whether commission enables the slave (CiA-402): the project's ``enable:``, by default for an axis."""
        return self.drive.enable if self.drive.enable is not None else self.kind == "axis"

    @property
    def family(self) -> str:
        return self.rules.family if self.rules is not None else "generic"

    def object_values(self, indices: range | tuple[int, ...]) -> dict[tuple[int, int], int]:
        """What the objects at ``indices`` hold once the startup list ran: the last write of the startup list,
        else the device's default (unsigned, as startup files print them); for ``scale explain --project``."""
        out: dict[tuple[int, int], int] = {}
        if self.device is not None:
            for index in indices:
                obj = self.device.dictionary.get(index)
                if obj is None:
                    continue
                for sub, e in obj.entries.items():
                    if e.default is not None and e.datatype is not None and e.datatype.bits and (sub or len(obj.entries) == 1):
                        out[(index, sub)] = int.from_bytes(e.default, "little")
        for c in self.startup:
            if c.index in indices and not c.complete_access:
                out[(c.index, c.subindex)] = c.int_value
        return out

    def error(self, rule: str, message: str, location: Location | None) -> None:
        self.findings.append(Finding(rule, Severity.ERROR, message, location))

    def warning(self, rule: str, message: str, location: Location | None) -> None:
        self.findings.append(Finding(rule, Severity.WARNING, message, location))


#: the former name of :class:`Slave`
ResolvedDrive = Slave


def _shown(name: str) -> str:
    """A file name as a finding quotes it: whole up to 160 characters, else its start and its end (where the file's
    own name is) with the length between (a name of 4,000 is not repeated whole)."""
    if len(name) <= 160:
        return repr(name)
    return f"{name[:40]!r}…{name[-80:]!r} ({len(name)} characters)"


def resolve_device(lp: LoadedProject, i: int, rd: ResolvedDrive) -> None:
    ref = rd.drive.device
    try:
        from ecattool import profiles

        if ref.profile is not None:
            from ecattool.project.cache import load_profile_cached

            rd.device = load_profile_cached(ref.profile, ref.product, ref.revision)
        else:
            from ecattool.project.cache import load_device_cached

            assert ref.esi is not None
            path = lp.resolve(ref.esi)
            problem = named_file_problem(path)  # a FIFO, a device, a directory, a name too long: never opened
            if problem == "not found":
                rd.error("PRJ002", f"ESI file {ref.esi!r} not found (looked in {path})", lp.drive_location(i, "device", "esi"))
                return
            if problem is not None:
                rd.error("PRJ005", f"ESI file {_shown(ref.esi)}: {problem}", lp.drive_location(i, "device", "esi"))
                return
            # the device as it runs: default modules in its slots, synthesised mapping/assignment objects
            rd.device = load_device_cached(path, None if ref.select is None else str(ref.select), ref.policy)
    except EcatToolError as exc:
        if exc.location and exc.location.line:
            rd.error("PRJ005", exc.message, exc.location)
        else:  # at the device entry; the ESI file (a directory, unreadable) named in the message then
            where = exc.location.file if exc.location else None
            rd.error("PRJ005", f"{where}: {exc.message}" if where else exc.message, lp.drive_location(i, "device"))
        return
    try:
        from ecattool import profiles

        rd.rules = profiles.rules_for(rd.device)
    except EcatToolError as exc:  # pragma: no cover - rules_for only raises for broken data
        rd.error("PRJ005", exc.message, lp.drive_location(i, "device"))


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


def _coerce(entry: Entry, value: Any, location: Location) -> Any:
    """Turn an engineering-form value into what the entry's data type encodes."""
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
            from ecattool.od.model import normalize_name

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


def resolve_parameters(lp: LoadedProject, i: int, rd: ResolvedDrive) -> list[StartupCommand]:
    assert rd.device is not None
    cmds: list[StartupCommand] = []
    seen: dict[tuple[int, int, str], int] = {}
    for j, p in enumerate(rd.drive.parameters):
        loc = lp.drive_location(i, "parameters", j, "object")
        vloc = lp.drive_location(i, "parameters", j, "value")
        cmd, findings = encode_parameter(rd.device, p, loc, vloc, rd.rules)
        rd.findings.extend(findings)
        if cmd is None:
            continue
        key = (cmd.index, cmd.subindex, cmd.transition)
        if key in seen:
            rd.warning("PRJ016", f"{cmd.address} is written twice in {cmd.transition} (also parameter {seen[key] + 1}); "
                                 "the last write wins", loc)
        seen[key] = j
        cmds.append(cmd)
    return cmds
