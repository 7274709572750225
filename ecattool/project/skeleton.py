"""A new project file that lints clean for the device it names (``ecattool project new``).

The device is resolved first (a built-in family and product, or an ESI device), so that a typo in a profile,
product, ESI path or selector is reported now rather than by the first lint, and so that the skeleton only
asks for what the drive can do: profile position mode and a short PP move where the drive supports mode 1,
otherwise a comment naming the modes it does support (a Digitax ST has no profile position mode; CSP needs
distributed clocks and a 607Ah PDO, which a skeleton cannot guess).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

from ecattool import profiles
from ecattool.errors import EcatToolError, InputError
from ecattool.esi.model import Device, Direction
from ecattool.findings import Finding, Severity
from ecattool.od.model import EcState
from ecattool.profiles.rules import FamilyRules

_PLAIN = re.compile(r"[A-Za-z_][A-Za-z0-9_.\-/]*")
_YAML_WORDS = {"true", "false", "yes", "no", "on", "off", "null", "y", "n", "~"}

#: CiA-402 names of the modes a skeleton comment lists
MODE_NAMES = {1: "pp", 2: "vl", 3: "pv", 4: "tq", 6: "hm", 7: "ip", 8: "csp", 9: "csv", 10: "cst"}


def _scalar(text: str) -> str:
    """``text`` as a YAML scalar: bare where that reads back as the same string, else double-quoted."""
    if _PLAIN.fullmatch(text) and text.lower() not in _YAML_WORDS:
        return text
    return json.dumps(text, ensure_ascii=False)  # a JSON string is a YAML double-quoted scalar


def resolve(profile: str | None, product: str | None, esi: str | None, select: str | None,
            base_dir: Path, policy: str = "exact") -> Device:
    """The device a skeleton is for (raises the usual located errors for unknown names and files)."""
    if profile is not None:
        from ecattool.project.cache import load_profile_cached

        return load_profile_cached(profile, product, None)
    from ecattool.project.cache import load_device_cached

    assert esi is not None
    path = base_dir / esi
    from ecattool.fileio import named_file_problem

    problem = named_file_problem(path)  # a FIFO, a device, a directory, a name too long: never opened
    if problem is not None:
        if problem == "not found":
            raise InputError(f"ESI file {esi!r} not found (looked in {path}; --esi is relative to the project file)")
        from ecattool.project.resolve import _shown

        raise InputError(f"ESI file {_shown(esi)}: {problem}")
    return load_device_cached(path, select, policy)


def esi_flaws(esi: str, select: str | None, base_dir: Path, policy: str = "exact") -> list[Finding]:
    """The structural findings of the ESI device, as lint will report them."""
    from ecattool.project.cache import esi_findings_cached

    return esi_findings_cached(base_dir / esi, select, policy)


def new_project(device: Device, *, name: str | None = None, profile: str | None = None, product: str | None = None,
                esi: str | None = None, select: str | None = None, policy: str = "exact",
                findings: list[Finding] | None = None) -> str:
    """The text of a minimal project with one drive of ``device``, named as the user named it; ``findings``:
    the ESI's structural findings (:func:`esi_flaws`), pointed out where they concern the PDOs in use."""
    from ecattool.project.slave import is_axis

    if name is None:  # a CiA-402 axis or an I/O slave (docs/project.md, "Axes and I/O slaves")
        name = "axis1" if is_axis(device) else "io1"
    if profile is not None:
        ref = f"      profile: {_scalar(profile)}\n" + (f"      product: {_scalar(product)}\n" if product else "")
    else:
        ref = (f"      esi: {_scalar(str(esi))}\n" + (f"      select: {json.dumps(select)}\n" if select else "")
               + (f"      policy: {policy}\n" if policy != "exact" else ""))
    motion = _motion(device, profiles.rules_for(device))
    # the skeleton's parameters are written in PS: an ESI command for the same object gives way to them
    replaced = {(int(a, 16), int(b, 16)) for a, b in re.findall(r'\{object: "([0-9A-F]{4}):([0-9A-F]{2})"', motion)}
    body = (_dc(device) + _pdo(device) + (_esi_init(device, replaced) if esi is not None else "") + motion
            + _accept_flaws(device, findings or []))
    return ("# ecattool project file (format 1). Docs: docs/project.md\n"
            "ecattool: 1\n"
            "name: my-machine\n"
            "drives:\n"
            f"  - name: {_scalar(name)}\n"
            "    device:\n"
            f"{ref}{body}")


def _pdo(device: Device) -> str:
    """``pdo:`` for a device whose dictionary's mapping objects hold another power-on mapping than its ESI's PDO
    list (lint PRJ027): the PDO list of each such direction, the differing PDOs with their entries, so that
    commission programs the mapping lint checks; with a comment saying why. Nothing where they agree."""
    from ecattool.pdo import MappedPdo, check, default_mapping, entry_text
    from ecattool.project.steps import dictionary_mapping_differences

    mapping = default_mapping(device)
    diffs = dictionary_mapping_differences(device, mapping)
    if not diffs:
        return ""
    differing = {d.index for d in diffs}
    # the PDO list, given: commission programs it; where it could not (Fixed PDOs, a list longer than the
    # mapping object), lint keeps reporting PRJ027 and the skeleton leaves the mapping alone
    given = type(mapping)(source=mapping.source, given={d.direction for d in diffs})
    for direction in Direction:
        given.set_pdos(direction, [MappedPdo(p.index, list(p.entries), p.index in differing, p.name, p.location)
                                   for p in mapping.pdos(direction)])
    if dictionary_mapping_differences(device, given) or any(f.severity is Severity.ERROR for f in check(device, given)):
        return ""
    lines = []
    for d in diffs:
        line = f", line {d.location.line}" if d.location is not None and d.location.line else ""
        lines.append(f"    # the ESI's dictionary gives {d.index:04X}h another power-on mapping than its PDO list{line}:")
        lines.append(f"    #   dictionary {' '.join(f'{v:08X}' for v in d.held) or 'nothing'}, "
                     f"PDO list {' '.join(f'{v:08X}' for v in d.listed) or 'nothing'}")
    lines.append("    # The slave would run the dictionary's; pdo: programs the PDO list that lint checks (PRJ027).")
    lines.append("    pdo:")
    for direction in sorted({d.direction for d in diffs}, key=lambda x: x.value):
        lines.append(f"      {direction.value}:")
        for p in mapping.pdos(direction):
            if p.index in differing:
                entries = ", ".join(_scalar(entry_text(e)) for e in p.entries)
                lines.append(f"        - {{index: 0x{p.index:04X}, entries: [{entries}]}}")
            else:
                lines.append(f"        - {{index: 0x{p.index:04X}}}")
    return "\n".join(lines) + "\n"


def _esi_init(device: Device, replaced: set[tuple[int, int]]) -> str:
    """The ESI's init commands as comments (commission sends them; lint checks them), and a commented-out
    ``esi_init_cmds`` that skips those the ESI's own dictionary says the drive refuses (PRJ021)."""
    from ecattool.project.initcmds import esi_startup, refusal, skip_hint

    cmds = esi_startup(device)
    if not cmds:
        return ""
    lines = ["    # The ESI's init commands, sent after the PDO assignment and before the parameters (as TwinCAT does):"]
    for c in cmds:
        where = f", ESI line {c.source.line}" if c.source is not None and c.source.line else ""
        value = f"hex:{c.data.hex()}" if c.value is None else c.value
        gone = "; the PS parameter below replaces it" if c.transition == "PS" and (c.index, c.subindex) in replaced else ""
        lines.append(f"    #   {c.transition} {c.index:04X}:{c.subindex:02X} = {value} ({_comment(c.comment)}{where}{gone})")
    lines.append('    # Change one with esi_init_cmds: [{object: "6060:00", value: 1}], or leave it out with skip: true.')
    refused = [c for c in cmds if refusal(device, c) is not None]
    if refused:
        lines += ["    # The ESI's own dictionary says the drive refuses some of them (PRJ021; `ecattool lint` says why).",
                  "    # If the drive refuses them too, skip them:",
                  "    # esi_init_cmds:"]
        lines += [f"    #   - {skip_hint(c)}" for c in refused]
    return "\n".join(lines) + "\n"


def dc_only_mode(device: Device) -> str | None:
    """The DC OpMode of an ESI that offers no other synchronisation (no free-run or SM-synchronous mode, whose
    AssignActivate is 0): such a drive runs only with distributed clocks. None where there is a choice."""
    modes = list(device.dc_opmodes)
    if modes and all(m.assign_activate for m in modes):
        return modes[0].name
    return None


def _dc(device: Device) -> str:
    """``dc:`` for a drive whose ESI offers only DC modes: the first of them, at a 1 ms SYNC0 cycle."""
    mode = dc_only_mode(device)
    if mode is None:
        return ""
    return (f"    # the ESI offers only distributed-clock synchronisation ({_comment(mode)}); set cycle_ns to your bus cycle\n"
            f"    dc: {{opmode: {_scalar(mode)}, cycle_ns: 1000000}}\n")


def _accept_flaws(device: Device, findings: list[Finding]) -> str:
    """Commented-out ``disable_rules`` for the vendor ESI's own flaws in the PDOs this drive uses by default
    (lint reports them as errors; only the user can say the drive has the objects the file leaves out)."""
    from ecattool.pdo import default_mapping

    mapping = default_mapping(device)
    used = {p.index for p in (*mapping.rx, *mapping.tx)}
    rules = sorted({f.rule for f in findings if f.severity is Severity.ERROR and f.data.get("pdo") in used})
    if not rules:
        return ""
    lines = [f"    # the vendor ESI has flaws in PDOs this drive uses ({', '.join(rules)}; `ecattool lint` shows where).",
             "    # If the drive itself is right (the file's dictionary is incomplete), accept them knowingly:",
             "    # disable_rules:"]
    lines += [f"    #   - {{rule: {r}, reason: \"the vendor ESI is incomplete; the drive has the objects\"}}" for r in rules]
    return "\n".join(lines) + "\n"


#: profile velocity, acceleration, deceleration for a first move where the device leaves them at 0 or unknown
#: (the drive would not move at all): slow, in the drive's own units until a scaling: section sets user units
_PROFILE = ((0x6081, 10_000, "profile velocity, slow (drive units until a scaling section sets user units)"),
            (0x6083, 100_000, "profile acceleration"), (0x6084, 100_000, "profile deceleration"))


def _motion(device: Device, rules: FamilyRules) -> str:
    """The parameters: and move: lines (or a comment saying why there are none)."""
    modes = tuple(rules.supported_modes or ())
    from ecattool.pdo import default_mapping
    from ecattool.project.slave import is_axis

    mode = device.dictionary.entry(0x6060, 0)
    if not is_axis(device):
        return ("    # an I/O slave, not a CiA-402 axis (no 6040h/6041h of a drive profile 402): commission proves its\n"
                "    # identity, every state to OP with its mapping and one cycle of process data; add parameters: as needed\n")
    if mode is None:
        return "    # no modes of operation (6060h): commission enables the drive without a move; add parameters: as needed\n"
    if modes and 1 not in modes:
        listed = ", ".join(f"{m} ({MODE_NAMES.get(m, '?')})" for m in modes)
        head = f"    # {_comment(device.type_name)} has no profile position mode; it supports {listed}.\n"
        if 8 not in modes:  # Commander SK, Affinity: no position mode a commissioning move could use
            return head + "    # No position mode for a commissioning move: commission enables the drive without one.\n"
        return (head + "    # For a CSP move: parameters 6060:00 = 8, an RxPDO with 607Ah, "
                + ("dc: (this drive needs distributed\n    # clocks for CSP)"
                   if 8 in rules.dc_required_modes else "dc: where the drive needs\n    # it")
                + ", and move: {distance: 1, mode: csp} (docs/project.md, samples/controltechniques).\n")
    rx = {(e.index, e.subindex) for p in default_mapping(device).pdos(Direction.RX) for e in p.entries}
    for index, what in ((0x6060, "modes of operation"), (0x607A, "target position")):
        e = device.dictionary.entry(index, 0)
        if (index, 0) not in rx and (e is None or EcState.OP not in e.access.write):
            return (f"    # {what} {index:04X}h is neither writable by SDO nor in the default RxPDOs: map it (pdo:)\n"
                    "    # before adding move: {distance: 1}\n")
    # where 6060h is in an RxPDO, the commissioning move sets the mode through it (a startup write would be
    # overwritten by the PDO every cycle)
    params = [] if (0x6060, 0) in rx or EcState.PREOP not in mode.access.write else [
        '{object: "6060:00", value: 1, comment: profile position mode}']
    for index, value, comment in _PROFILE:
        e = device.dictionary.entry(index, 0)
        if e is None or (index, 0) in rx or EcState.PREOP not in e.access.write:
            continue
        if e.default_zero_or_unknown:
            params.append(f'{{object: "{index:04X}:00", value: {value}, comment: {_scalar(comment)}}}')
    factor, asked = _factor_parts(device, rx, rules)
    params += factor
    lines = "".join(f"      - {p}\n" for p in params)
    if asked:  # a move would fail lint (PRJ023): the skeleton leaves it out and says why
        return ((f"    parameters:\n{lines}" if lines else "") + asked
                + "    # No commissioning move until then (the drive could not convert the target): add\n"
                  "    # move: {distance: 1} once the value is set.\n")
    return (f"    parameters:\n{lines}" if lines else "") + asked + "    move: {distance: 1}\n"


#: the parts of the position factor a skeleton can set: revolution counts, 1 (a pair of 1:1 is the CiA-402
#: default); the encoder increments (608Fh:01) and the feed (6092h:01) are the machine's, so it asks for them
_ONE = {(0x608F, 2), (0x6091, 1), (0x6091, 2), (0x6092, 2)}


def _factor_parts(device: Device, rx: set[tuple[int, int]], rules: FamilyRules) -> tuple[list[str], str]:
    """Parameters for the zero parts of the position factor the ESI's defaults leave (lint PRJ023) that the
    skeleton can set, and a comment asking for those it cannot."""
    from ecattool.project.steps import zero_factor_parts

    if rules.family not in ("generic", "controltechniques"):
        return [], ""

    def read(index: int, sub: int) -> int | None:
        e = device.dictionary.entry(index, sub)
        if e is None or not e.access.writable() or (index, sub) in rx or not e.default or e.datatype is None:
            return None
        try:
            return int(e.decode(e.default))
        except (EcatToolError, TypeError, ValueError):
            return None

    params, asked = [], ""
    for index, sub in zero_factor_parts(read):
        e = device.dictionary.entry(index, sub)
        assert e is not None
        line = e.location.line if e.location is not None else None
        if (index, sub) in _ONE:
            params.append(f'{{object: "{index:04X}:{sub:02X}", value: 1, comment: '
                          f'{_scalar(f"{_comment(e.name)}: the ESI leaves 0 (line {line}), the factor would be 0")}}}')
        else:
            asked += (f"    # {index:04X}:{sub:02X} ({_comment(e.name)}) is 0 in the ESI (line {line}): the drive cannot convert\n"
                      f"    # positions. Add your drive's value under parameters:, e.g. {{object: \"{index:04X}:{sub:02X}\", "
                      "value: 4096}, or a scaling: section.\n")
    return params, asked


def _comment(text: str) -> str:
    return " ".join(text.split())
