"""The per-drive steps of lint/commission that call the other packages (pdo, scaling, sw, esi).

Each step adds located findings to the Slave and returns the startup commands it contributes.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING, NamedTuple

from ecattool import pdo
from ecattool.errors import EcatToolError, EncodeError, Location
from ecattool.esi.model import Device, Direction
from ecattool.esi.power_on import without_trailing_padding
from ecattool.fileio import named_file_problem
from ecattool.findings import Finding, Severity
from ecattool.pdo.model import Mapping, without_virtual
from ecattool.pdo.program import rewritten
from ecattool.profiles.rules import NO_RULES, FamilyRules, interpolation_period_ns
from ecattool.project.loader import LoadedProject
from ecattool.project.model import Drive
from ecattool.project.slave import Found, Slave
from ecattool.startup.model import StartupCommand

if TYPE_CHECKING:
    from ecattool.scaling.group import FactorGroup
    from ecattool.sw.image import SwImage


def _relocate(f: Finding, fallback: Location | None) -> Finding:
    if f.location is None or f.location.line is None:
        return Finding(f.rule, f.severity, f.message, fallback, f.data)
    return f


class PdoResolved(NamedTuple):
    """What :func:`pdo_commands` resolves: the mapping the slave runs with (None where the ``pdo:`` section does
    not resolve), the startup commands that program it, and the findings."""

    mapping: Mapping | None
    commands: list[StartupCommand]
    found: Found


def pdo_commands(lp: LoadedProject, i: int, device: Device, rules: FamilyRules | None,
                 params: list[StartupCommand]) -> PdoResolved:
    """Check the drive's PDO configuration (or its default) and program it."""
    found = Found()
    cfg = lp.project.drives[i].pdo
    loc = lp.drive_location(i, "pdo")
    try:
        if cfg is None or (cfg.rx is None and cfg.tx is None):
            mapping = pdo.default_mapping(device)
        else:
            data = cfg.model_dump(mode="python", exclude_none=True)
            locations = {path[3:]: l for path, l in lp.yaml.locations.items()
                         if len(path) > 3 and path[:3] == ("drives", i, "pdo")}
            mapping = pdo.Mapping.from_data(data, device=device, locations=locations, default=pdo.default_mapping(device))
    except EcatToolError as exc:
        found.error("PDO000", exc.message, exc.location or loc)
        return PdoResolved(None, [], found)
    findings = pdo.check(device, mapping, rules=rules, startup=params)
    # a virtual PDO is left out of what the slave is given (PDO029 says so): lint, startup export and
    # commission see the same mapping
    mapping = without_virtual(device, mapping)[0]
    found.extend(_relocate(f, loc) for f in findings)
    if cfg is None:
        return PdoResolved(mapping, [], found)  # the drive keeps its power-on mapping: nothing to program
    complete = bool(cfg.complete_access)
    return PdoResolved(mapping, list(pdo.program(device, mapping, complete_access=complete)), found)


class ScalingResolved(NamedTuple):
    """What :func:`scaling_commands` resolves: the factor group and the internal position units per user unit
    (None without a ``scaling:`` section or where it does not resolve), its startup commands, the findings."""

    factor_group: FactorGroup | None
    counts_per_unit: Fraction | None
    commands: list[StartupCommand]
    found: Found


def scaling_commands(lp: LoadedProject, i: int, device: Device) -> ScalingResolved:
    """Compute the drive's factor group from its mechanics and units (``scaling:`` section)."""
    found = Found()
    drive = lp.project.drives[i]
    if drive.scaling is None:
        return ScalingResolved(None, None, [], found)
    from ecattool import profiles, scaling
    from ecattool.scaling.spec import spec_from_dict

    base = ("drives", i, "scaling")
    loc = lp.drive_location(i, "scaling")
    try:
        spec = spec_from_dict(drive.scaling, lambda path: lp.yaml.locate((*base, *path)), loc)
        family = spec.family or profiles.family_of(device)
        firmware = spec.firmware
        if firmware is None and drive.device.revision is not None:
            firmware = str(drive.device.revision)
        group = scaling.compute(spec.axis, family, firmware=firmware, device=device,
                                strategy=spec.approximation, vl_setpoint=spec.vl_setpoint)
    except EcatToolError as exc:
        found.error("PRJ050", exc.message, exc.location if exc.location and exc.location.line else loc)
        return ScalingResolved(None, None, [], found)
    from ecattool.scaling.compute import fixed_counts_per_rev
    from ecattool.scaling.exact import Exact

    fixed = fixed_counts_per_rev(family)
    ipr = Exact.of(fixed) if fixed is not None else spec.axis.counts_per_motor_rev
    counts_per_unit = spec.axis.internal_per_unit(spec.axis.units[0], ipr).rational
    for note in group.findings:
        found.append(_relocate(note, loc))
    return ScalingResolved(group, counts_per_unit, list(group.startup()), found)


def resolve_sw(lp: LoadedProject, i: int, device: Device) -> tuple[SwImage | None, Found]:
    """The drive's ``.sw`` image (None without ``sw:`` or where it does not read) and the findings about it."""
    found = Found()
    drive = lp.project.drives[i]
    cfg = drive.sw_config
    if cfg is None:
        return None, found
    loc = lp.drive_location(i, "sw")
    if device.vendor_id != 0x1A3:
        found.warning("PRJ031", f".sw images are Technosoft setups; {device.type_name} is vendor 0x{device.vendor_id:X}", loc)
    path = lp.resolve(cfg.file)
    from ecattool.project.resolve import _shown

    problem = named_file_problem(path)  # a FIFO, a device, a directory, a name too long: never opened
    if problem == "not found":
        found.error("PRJ002", f".sw file {cfg.file!r} not found (looked in {path})", loc)
        return None, found
    if problem is not None:
        found.error("PRJ030", f".sw file {_shown(cfg.file)}: {problem}", loc)
        return None, found
    from ecattool import sw

    try:
        # the project names the file: no finding quotes a line of it (it may name any file, a secret too)
        image = sw.read(path, quote=False)
    except EcatToolError as exc:
        found.error("PRJ030", exc.message, exc.location or loc)
        return None, found
    for f in sw.check(image):
        found.append(Finding("PRJ030", f.severity, f"{cfg.file}: {f.message} [{f.rule}]", f.location or loc))
    if device.vendor_id == 0x1A3:
        found.extend(check_sw_identification(drive, device, image, cfg.file, loc))
    return image, found


def check_sw_identification(drive: Drive, device: Device, image: SwImage, file: str, loc: Location | None) -> Found:
    """PRJ032: the image's identification block (ProductID + FirmwareID it was made for, sw-format.md §6) names
    another product code than the drive's, or (where the project names the revision) another firmware."""
    from ecattool.sw.layout import describe

    found = Found()
    info = next((b for b in describe(image) if b.kind == "identification"), None)
    if info is None:
        return found
    product_id, firmware = info.details.get("product_id"), str(info.details.get("firmware_id") or "")
    made_for: list[str] = []
    if isinstance(product_id, str):  # P027.314.E221 -> 27314221 (manual §4.8.6)
        code = int("".join(ch for ch in product_id if ch.isdigit()))
        if code != device.product_code:
            made_for.append(f"product {product_id} (product code {code}), the drive is {device.type_name} "
                            f"(product code {device.product_code})")
    if drive.device.revision is not None and firmware:
        drive_fw = str(device.extra.get("firmware") or "")
        if drive_fw and firmware != drive_fw:
            made_for.append(f"firmware {firmware}, the drive has {drive_fw}")
    if made_for:
        found.warning("PRJ032", f"{file} was made for {'; '.join(made_for)} (identification {info.details['text']!r}); "
                      "its setup table may not fit this drive", loc)
    return found


#: modes of operation (6060h) of the commissioning move's modes
MOVE_MODE_CODES = {"pp": 1, "csp": 8}
#: what a profile position move runs at: profile velocity and acceleration (lint PRJ019)
PP_PROFILE = ((0x6081, 0), (0x6083, 0))


def move_mode(slave: Slave) -> str | None:
    """The mode of the commissioning move (``pp`` or ``csp``; ``pp`` becomes ``csp`` on a drive that has CSP
    but no PP, as commission runs it), None without a move."""
    move = slave.drive.move
    if move is None:
        return None
    modes = (slave.rules or NO_RULES).supported_modes
    if move.mode == "pp" and modes and 1 not in modes and 8 in modes:
        return "csp"
    return move.mode


def _modes_run(lp: LoadedProject, i: int, slave: Slave) -> list[tuple[int, Location]]:
    """The modes of operation the drive will run, with where the project sets them: the last 6060h write of
    the startup list (a parameter after the ESI's init command wins: the Elmo ESI's PS 6060h := 8 does not
    make a PP project a CSP one) and the commissioning move (which commission sets through the PDO or by SDO)."""
    writes = [c for c in slave.startup if (c.index, c.subindex) == (0x6060, 0) and len(c.data) == 1]
    out: list[tuple[int, Location]] = [(int.from_bytes(c.data, "little", signed=True), c.source or lp.drive_location(i))
                                  for c in writes[-1:]]
    mode = move_mode(slave) if slave.enables else None
    if mode is not None:
        out.append((MOVE_MODE_CODES[mode], lp.drive_location(i, "move")))
    here = lp.drive_location(i).file  # what the project sets first: a finding points where the user can change it
    return sorted(out, key=lambda m: m[1].file != here)


def check_move(lp: LoadedProject, i: int, slave: Slave) -> Found:
    """The commissioning move needs 6060h, 607Ah and 6064h, and a mode the drive has (a Commander SK has
    neither pp nor csp: it aborts 6060h = 8 with 0609 0030h)."""
    found = Found()
    mode = move_mode(slave) if slave.enables else None
    if mode is None:
        return found
    assert slave.device is not None
    loc = lp.drive_location(i, "move")
    lacking = [f"{index:04X}h" for index in (0x6060, 0x607A, 0x6064) if slave.device.dictionary.entry(index, 0) is None]
    if lacking:
        found.error("PRJ018", f"the {mode} move needs {', '.join(lacking)}, which {slave.device.type_name} does not have "
                              "(leave out move:)", loc)
        return found
    code = MOVE_MODE_CODES[mode]
    modes = (slave.rules or NO_RULES).supported_modes
    if modes and code not in modes:
        found.error("PRJ017", f"the {mode} move needs mode {code}, which {slave.device.type_name} does not support "
                              f"(supported: {', '.join(str(m) for m in modes)}); leave out move:", loc)
        return found
    if not _move_fits(lp, i, slave, mode, found):
        return found
    if mode != "pp" or slave.drive.sw_config is not None:  # a Technosoft setup image may hold them
        return found

    written = {(c.index, c.subindex) for c in slave.startup}
    mapped = {(e.index, e.subindex) for p in (slave.mapping.pdos(Direction.RX) if slave.mapping is not None else ())
              for e in p.entries}
    for index, name in ((0x6081, "profile velocity"), (0x6083, "profile acceleration")):
        e = slave.device.dictionary.entry(index, 0)
        if e is None or (index, 0) in written or (index, 0) in mapped:
            continue
        if e.default_zero_or_unknown:
            # where the vendor ESI documents the 0, point at its line: that default is what blocks the move
            esi_zero = e.default is not None and slave.drive.device.esi is not None and e.location is not None \
                and bool(e.location.line)
            found.error("PRJ019", f"the pp move runs at {name} {index:04X}h, which the project does not set and "
                                    f"{slave.device.type_name} leaves at 0 (or does not document): the drive would not "
                                    f"move; add a parameter {index:04X}:00", e.location if esi_zero else loc)
    return found


def _move_fits(lp: LoadedProject, i: int, slave: Slave, mode: str, found: Found) -> bool:
    """PRJ024: the move's target (the actual position, 0 after power-on, plus the distance) must be a value of
    the target position 607Ah's data type and lie within the software position limits 607Dh where the device
    sets them; commission would otherwise fail writing 607Ah (or the drive would stop at the limit)."""
    assert slave.device is not None and slave.drive.move is not None
    loc = lp.drive_location(i, "move", "distance")
    if loc.line is None:
        loc = lp.drive_location(i, "move")
    dist = Fraction(slave.drive.move.distance).limit_denominator(1)
    target = int(dist)
    entry = slave.device.dictionary.entry(0x607A, 0)
    if entry is not None and entry.datatype is not None:
        try:
            entry.encode(target)
        except EncodeError as exc:
            found.error("PRJ024", f"the {mode} move of {dist} user units goes to {target}, which the "
                                  f"target position 607Ah ({entry.type_name}) cannot hold: {exc.message}; "
                                  "move a shorter distance", loc)
            return False
    limits = [_effective(slave, 0x607D, sub)[0] for sub in (1, 2)]
    low, high = limits
    if low is not None and high is not None and low < high and not low <= target <= high:
        found.error("PRJ024", f"the {mode} move of {dist} user units goes to {target}, outside the "
                              f"software position limits 607Dh [{low}, {high}] of {slave.device.type_name}; move a shorter "
                              "distance or set 607Dh", loc)
        return False
    return True


def check_mailbox(lp: LoadedProject, i: int, slave: Slave) -> Found:
    """PRJ028: a startup SDO for a slave without a CoE mailbox (a fixed process image: an EL2008, an SMC EX260).
    Nothing receives it, and commission never sends such a slave an SDO; reported once, at the first command."""
    found = Found()
    assert slave.device is not None
    if slave.device.has_coe or slave.startup is None or not slave.startup.commands:
        return found
    cmd = slave.startup.commands[0]
    why = "the mailbox speaks " + ", ".join(slave.device.mailbox.protocols) if slave.device.mailbox else "it has no mailbox"
    found.error("PRJ028", f"{len(slave.startup.commands)} startup SDO(s) ({cmd.address} first) for {slave.device.type_name}, "
                          f"which has no CoE mailbox ({why}): a fixed process image that nothing can write; leave them "
                          "out", cmd.source or lp.drive_location(i, "device"))
    return found


def check_kind(lp: LoadedProject, i: int, slave: Slave) -> Found:
    """PRJ025: ``enable: true`` on a slave that is not a CiA-402 axis (no 6040h/6041h, no profile 402 or 6060h):
    commission would run the CiA-402 enable on a terminal, a coupler or a gateway."""
    found = Found()
    assert slave.device is not None
    if slave.drive.enable and slave.kind == "io":
        found.error("PRJ025", f"enable: true, but {slave.device.type_name} is not a CiA-402 axis (it has no controlword "
                              "6040h and statusword 6041h of a drive profile 402): commission proves an I/O slave's "
                              "states, mapping and process data; remove enable:", lp.drive_location(i, "enable"))
    if slave.drive.move is not None and slave.kind == "io" and slave.drive.enable is None:
        found.error("PRJ018", f"move: on {slave.device.type_name}, which is not a CiA-402 axis; leave out move:",
                    lp.drive_location(i, "move"))
    return found


#: the CoE PDO mapping object ranges (ETG.1000.6 / CiA 301): RxPDOs 1600h–17FFh, TxPDOs 1A00h–1BFFh
_COE_PDO_RANGES = {"rx": range(0x1600, 0x1800), "tx": range(0x1A00, 0x1C00)}


def _maps_validly(device: Device, value: int, direction: Direction) -> bool:
    """Whether a mapping entry value (index << 16 | sub << 8 | bits) is one the slave can map: a gap (index 0),
    a dummy of a standard data type (index below 20h; CiA 301: RxPDOs only), or an object of its dictionary of
    that size."""
    index, sub, bits = value >> 16, (value >> 8) & 0xFF, value & 0xFF
    if index == 0:
        return True
    if index < 0x20:
        return direction is Direction.RX
    entry = device.dictionary.entry(index, sub)
    return entry is not None and entry.bit_size == bits


def check_pdo_objects(lp: LoadedProject, i: int, slave: Slave) -> Found:
    """What the slave will run with, as its own dictionary says it, against what lint checked (the PDO list):

    * PRJ026: a SoE drive (mailbox without CoE) whose PDOs are not CoE mapping objects (the AX5000's
      IDN-numbered MDT/AT): ecattool configures and commissions CoE slaves; such a device cannot be set up by it;
    * PRJ027: where the project keeps the power-on mapping (no ``pdo:``), a mapping object of the device's
      dictionary whose default entries lay out another image than the ESI's PDO list (the EM7004 ESI's
      1601h–1609h are shifted by one against its RxPdo list): the slave runs with the dictionary's mapping, which
      lint never checked (the simulator refuses SAFE-OP with AL 001Dh/001Eh); or the same image where an entry
      of the dictionary's own mapping cannot be mapped (a SOES board's 1A00h mapping 0x00060120, a dummy in a
      TxPDO). Reported at the dictionary object's line; ``pdo:`` programs the mapping the project means."""
    found = Found()

    device = slave.device
    assert device is not None
    loc = lp.drive_location(i, "device")
    protocols = device.mailbox.protocols if device.mailbox is not None else []
    soe = device.mailbox is not None and device.mailbox.coe is None and "SoE" in protocols
    for d, key in ((Direction.RX, "rx"), (Direction.TX, "tx")):
        foreign = [p for p in device.pdos(d) if p.index not in _COE_PDO_RANGES[key]]
        if foreign and soe:  # without a mailbox the indices are only names: the master lays out the SMs
            p = foreign[0]
            found.error("PRJ026", f"{device.type_name}'s {'Rx' if key == 'rx' else 'Tx'}PDO 0x{p.index:04X} ({p.name}) "
                                  "is not a CoE mapping object (16xxh/1Axxh): the device is configured over SoE (its "
                                  f"mailbox speaks {', '.join(protocols)}, not CoE); ecattool configures "
                                  "and commissions CoE slaves only", p.location if p.location and p.location.line else loc)
            return found
    if slave.mapping is None:
        return found
    for diff in dictionary_mapping_differences(device, slave.mapping, slave.rules):
        found.error("PRJ027", f"the dictionary's mapping object 0x{diff.index:04X} maps "
                              f"{', '.join(f'0x{v:08X}' for v in diff.held) or 'nothing'}, the ESI's PDO list "
                              f"{', '.join(f'0x{v:08X}' for v in diff.listed) or 'nothing'}: {device.type_name} would run "
                              "with the dictionary's mapping, which differs from the one checked; give the mapping in pdo: "
                              "so that commission programs it", diff.location)
        return found
    return found


@dataclass(frozen=True, slots=True)
class MappingDifference:
    """A mapping object whose dictionary default differs from the ESI's PDO list (PRJ027)."""

    direction: Direction
    index: int
    held: list[int]  # the dictionary's default entries (mapping values)
    listed: list[int]  # the PDO list's
    location: Location | None


def dictionary_mapping_differences(device: Device, mapping: Mapping,
                                   rules: FamilyRules | None = None) -> list[MappingDifference]:
    """The PDOs of ``mapping`` that the slave keeps as it has them (not given with entries, or Fixed: commission
    does not program them, :func:`ecattool.pdo.program`) whose mapping object in the device's dictionary
    holds another default mapping than the ESI's PDO list: another image (the EM7004's 1601h–1609h shifted by one
    against its RxPdo list), or the same image where an entry of the dictionary's own mapping cannot be mapped
    (a SOES board's 1A00h mapping 0x00060120, a dummy in a TxPDO). Equal where they differ only by trailing
    padding (an EL6692's 1600h: a gap of 8 bits against an empty PDO). The slave powers on with the dictionary's
    mapping; ``project new`` writes such a PDO list as ``pdo:`` so that commission programs it, lint reports it
    (PRJ027) where the project keeps the power-on mapping."""
    out = []
    for direction, mp in [(Direction.RX, p) for p in mapping.rx] + [(Direction.TX, p) for p in mapping.tx]:
        if mp.explicit and rewritten(device, mp, rules):
            continue  # commission programs the entries the project gives
        obj = device.dictionary.get(mp.index)
        if obj is None or obj.location is None or not obj.location.line:
            continue  # synthesised from the PDO list: it agrees by construction
        count = obj.entry(0)
        if count is None or count.default is None:
            continue
        n = int.from_bytes(count.default, "little")
        held_or_none = []
        for sub in range(1, n + 1):
            e = obj.entry(sub)
            held_or_none.append(int.from_bytes(e.default, "little") if e is not None and e.default is not None else None)
        if None in held_or_none:
            continue
        held = [v for v in held_or_none if v is not None]
        listed = [e.mapping_value for e in mp.entries]
        if held == listed or without_trailing_padding(held) == without_trailing_padding(listed):
            continue
        same_layout = [v & 0xFF for v in held] == [v & 0xFF for v in listed]
        if same_layout and all(_maps_validly(device, v, direction) for v in held):
            continue  # the same image of valid entries: a PDO list entry named otherwise is esi-pdo-object-missing's
        out.append(MappingDifference(direction, mp.index, held, listed, obj.location))
    return out


def zero_factor_parts(read: Callable[[int, int], int | None]) -> list[tuple[int, int]]:
    """The parts of the CiA-402 position factor 608Fh (encoder increments / motor revolutions) x 6091h (gear)
    / 6092h (feed) that make it 0 or undefined: a 0 beside a non-zero partner (``read(index, sub)``: the value,
    None where unknown). Used by lint (PRJ023), ``project new`` and commission's report of a failed move. 0:0
    reads as not configured (the simulator takes it as 1:1), so it is not reported (docs/decisions.md, "ESI init
    commands and defaults that break a drive")."""
    out = []
    for index in (0x608F, 0x6091, 0x6092):
        a, b = read(index, 1), read(index, 2)
        if a is not None and b is not None and (a == 0) != (b == 0):
            out.append((index, 1 if a == 0 else 2))
    return out


def _effective(slave: Slave, index: int, sub: int) -> tuple[int | None, Location | None]:
    """The value an object holds after the PRE-OP startup writes (IP, PS), else its ESI default; with where
    it comes from (the write's location, else the dictionary entry's: the ESI's line)."""
    assert slave.device is not None
    entry = slave.device.dictionary.entry(index, sub)
    value: int | None = None
    where = entry.location if entry is not None else None
    if entry is not None and entry.default is not None and entry.datatype is not None and entry.datatype.bits:
        try:
            value = int(entry.decode(entry.default))
        except (EcatToolError, TypeError, ValueError):
            value = None
    for c in slave.startup:
        if (c.index, c.subindex) == (index, sub) and c.transition in ("IP", "PS") and not c.complete_access:
            value, where = int.from_bytes(c.data, "little"), c.source
    return value, where


def check_factor_defaults(lp: LoadedProject, i: int, slave: Slave) -> Found:
    """PRJ023: a zero part of the position factor (608Fh x 6091h / 6092h) that the ESI's default leaves (or the
    startup list writes): the drive cannot convert positions in user units. An error where the drive moves in
    commissioning, a warning otherwise; at the ESI's line (or the write's)."""
    found = Found()
    assert slave.device is not None
    if (slave.rules or NO_RULES).family not in ("generic", "controltechniques"):
        return found  # Technosoft and HDT scale through 6093h (from their setup or their own factors)
    sources: dict[tuple[int, int], Location | None] = {}

    def read(index: int, sub: int) -> int | None:
        entry = slave.device.dictionary.entry(index, sub) if slave.device is not None else None
        if entry is None or not entry.access.writable():
            return None  # a part the drive computes itself (Control Techniques 608Fh) is its business
        value, where = _effective(slave, index, sub)
        sources[(index, sub)] = where
        return value

    moves = move_mode(slave) is not None and slave.enables
    for index, sub in zero_factor_parts(read):
        entry = slave.device.dictionary.entry(index, sub)
        assert entry is not None
        other = 2 if sub == 1 else 1
        finding = Finding("PRJ023", Severity.ERROR if moves else Severity.WARNING,
                          f"{index:04X}:{sub:02X} ({entry.name}) is 0 beside a non-zero {index:04X}:{other:02X}: the "
                          f"position factor 608Fh x 6091h / 6092h is 0 or undefined, so {slave.device.type_name} cannot "
                          f"convert positions{' and the move cannot happen' if moves else ''}; write the drive's value "
                          f"with a parameter {index:04X}:{sub:02X} (or describe the mechanics in scaling:)",
                          sources.get((index, sub)) or lp.drive_location(i, "device"))
        found.append(finding)
    return found


def check_interpolation_period(lp: LoadedProject, i: int, slave: Slave) -> Found:
    """60C2h is sub1 x 10^sub2 s; a family that accepts only some periods (Control Techniques: 250 us, 500 us,
    k x 1 ms) refuses each write that leaves another, so the order of the two writes matters: follow the
    startup list from the device defaults."""
    found = Found()

    rules = slave.rules
    assert slave.device is not None
    if rules is None or (not rules.ip_periods_ns and not rules.ip_period_step_ns):
        return found
    state: dict[int, int] = {}
    for sub in (1, 2):
        e = slave.device.dictionary.entry(0x60C2, sub)
        if e is None:
            return found
        state[sub] = e.decode(e.default) if e.default else 0
    for cmd in slave.startup:
        if cmd.index != 0x60C2 or cmd.subindex not in (1, 2) or cmd.complete_access:
            continue
        state[cmd.subindex] = int.from_bytes(cmd.data, "little", signed=cmd.subindex == 2)
        ns = interpolation_period_ns(state[1], state[2])
        if rules.accepts_ip_period(ns):
            continue
        step = rules.ip_period_step_ns
        allowed = ", ".join(f"{p // 1000} us" for p in rules.ip_periods_ns) + (f", k x {step // 1000} us" if step else "")
        found.error("PRJ043", f"after this write 60C2h = {state[1]} x 10^{state[2]} s = {float(ns) / 1000:g} us, which "
                              f"{slave.device.type_name} refuses (it accepts {allowed}); write sub-index 2 first where "
                              "the unit changes (e.g. 60C2:02 = -3, then 60C2:01 = 1 for 1 ms)",
                    cmd.source or lp.drive_location(i, "parameters"))
        return found
    # the guide expects the interpolation cycle to equal the sync interval (Control Techniques 8.1); a 1 ms
    # SYNC0 with the 250 us default period interpolates each set-point as if it came four times as often
    period = interpolation_period_ns(state[1], state[2])
    cycle = slave.dc.cycle_ns if slave.dc is not None and slave.dc.active else None
    needs = rules.dc_required_modes
    if cycle and period != cycle and any(mode in needs for mode, _ in _modes_run(lp, i, slave)):
        hint = (f"60C2:02 = -3, then 60C2:01 = {cycle // 1_000_000}" if cycle % 1_000_000 == 0
                else "a period equal to the cycle")
        found.warning("PRJ044", f"interpolation period 60C2h = {float(period) / 1000:g} us differs from the SYNC0 cycle "
                                f"{cycle / 1000:g} us; {slave.device.type_name} expects the master's set-points once per "
                                f"interpolation period: set {hint}", lp.drive_location(i, "dc", "cycle_ns"))
    return found


#: AssignActivate bit 10 (ESC 0x0981 bit 2): the SYNC1 signal is generated
SYNC1_ACTIVE = 0x0400


def check_dc(lp: LoadedProject, i: int, slave: Slave) -> Found:
    """DC OpMode names; modes the drive runs only with distributed clocks (Control Techniques 7.4/8.1: ip and
    csp; without DC the drive stays in SAFE-OP, AL status 0x0030); SYNC0 cycle times the family accepts."""
    found = Found()
    dc = slave.drive.dc
    assert slave.device is not None
    if dc is not None and dc.opmode is not None:
        names = [m.name for m in slave.device.dc_opmodes]
        if dc.opmode not in names:
            found.error("PRJ040", f"DC OpMode {dc.opmode!r} is not in the device's ESI (has: {', '.join(names) or 'none'})",
                        lp.drive_location(i, "dc", "opmode"))
            return found
    rules = slave.rules or NO_RULES
    active = slave.dc is not None and slave.dc.active
    needs = rules.dc_required_modes
    if not active:
        for mode, loc in _modes_run(lp, i, slave):
            if mode in needs:
                found.error("PRJ041", f"mode {mode} needs distributed clocks on {slave.device.type_name} (the drive stays in "
                                      "SAFE-OP without them); add dc: {opmode: DC, cycle_ns: 1000000}", loc)
                break
            supported = rules.supported_modes
            if mode == 8 and (not supported or 8 in supported):  # csp: set-points taken on SYNC0 each cycle
                names = [m.name for m in slave.device.dc_opmodes if m.assign_activate]
                hint = (f"dc: {{opmode: {names[0]}, cycle_ns: 1000000}} (the ESI's DC modes: {', '.join(names)})"
                        if names else "dc: {assign_activate: 0x0300, cycle_ns: 1000000}")
                found.warning("PRJ045", f"cyclic synchronous position (csp) without distributed clocks: "
                                        f"{slave.device.type_name} would take the set-points unsynchronised (or refuse "
                                        f"SAFE-OP where it needs SYNC0); add {hint}", loc)
                break
        return found
    step, most = rules.dc_sync0_step_ns, rules.dc_sync0_max_steps
    assert dc is not None and slave.dc is not None
    given = "sync1_cycle_ns" if dc.sync1_cycle_ns is not None else "sync1_shift_ns" if dc.sync1_shift_ns is not None else None
    if given is not None and not slave.dc.assign_activate & SYNC1_ACTIVE:
        found.warning("PRJ046", f"dc: {given} is given but AssignActivate 0x{slave.dc.assign_activate:04X} does not "
                                "switch SYNC1 on (bit 10, 0x0400): the ESC generates no SYNC1 pulse; use an OpMode "
                                "or assign_activate with SYNC1 (e.g. 0x0700), or drop the SYNC1 values",
                      lp.drive_location(i, "dc", given))
    if step and most:
        cycle = slave.dc.cycle_ns or 0
        if cycle <= 0 or cycle % step or not 1 <= cycle // step <= most:
            what = f"SYNC0 cycle {cycle} ns" if slave.dc.cycle_ns is not None else "dc: gives no SYNC0 cycle_ns"
            found.error("PRJ042", f"{what}: {slave.device.type_name} accepts n x {step} ns for n = 1..{most} "
                                  f"(e.g. cycle_ns: 1000000)",
                        lp.drive_location(i, "dc", "cycle_ns") if dc.cycle_ns is not None else lp.drive_location(i, "dc"))
    return found


def check_esi(lp: LoadedProject, i: int, slave: Slave) -> Found:
    """The ESI's structural findings about the selected device (de-duplicated across drives by lint); the
    file's other devices are not the project's concern (``ecattool esi validate`` checks the whole file).

    A flaw in a PDO the drive's mapping does not use is a warning: real vendor files describe PDOs whose
    objects their dictionary leaves out (the AX2000 ESI maps 2901h, 6062h … and never lists them), and the
    project cannot repair the file. Where the mapping uses the PDO it stays an error (``disable_rules`` with a
    reason is the way to accept a vendor file's flaw knowingly).
    """
    found = Found()
    from ecattool.project.cache import esi_findings_cached

    ref = slave.drive.device
    if ref.esi is None:
        return found
    try:
        findings = esi_findings_cached(lp.resolve(ref.esi), None if ref.select is None else str(ref.select), ref.policy)
    except EcatToolError as exc:
        found.error("PRJ005", exc.message, exc.location)
        return found
    used = {p.index for p in (*slave.mapping.rx, *slave.mapping.tx)} if slave.mapping is not None else None

    assert slave.device is not None
    # a mapping object whose DefaultData contradicts its PDO element matters where the slave runs it as it holds
    # it: a PDO the mapping uses and commission does not program (docs/decisions.md, "An ESI that contradicts
    # itself"); where PRJ027 reports the project's mapping against it (its first such PDO, at the same line, with
    # what to do: give the mapping in pdo:), once is enough
    kept = ({p.index for p in (*slave.mapping.rx, *slave.mapping.tx)
             if not (p.explicit and rewritten(slave.device, p, slave.rules))} if slave.mapping is not None else set())
    if slave.mapping is not None:
        kept -= {d.index for d in dictionary_mapping_differences(slave.device, slave.mapping, slave.rules)}
    for f in findings:
        pdo_index = f.data.get("pdo")
        if f.rule == "esi-pdo-default-differs" and pdo_index not in kept:
            continue
        if used is not None and f.severity is Severity.ERROR and isinstance(pdo_index, int) and pdo_index not in used:
            f = Finding(f.rule, Severity.WARNING, f"{f.message} (a PDO this drive's mapping does not use)",
                        f.location, f.data)
        found.append(f)
    return found
