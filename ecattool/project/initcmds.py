"""The ESI's init commands in a drive's startup list, the way TwinCAT applies them.

A vendor ESI carries ``Mailbox/CoE/InitCmd`` elements (the device's, and those of the modules in its slots):
SDO downloads the configuration tool sends in the transitions they name, e.g. an Inovance SV660N's
``PS 6060:00 := 8``. TwinCAT lists them in the slave's startup list after the PDO assignment and before what
the user adds; ecattool does the same: after the PDO programming, in transition order, before the scaling
objects and the project's ``parameters:`` (a parameter writing the same object in the same transition
replaces the ESI's command). The drive's ``esi_init_cmds:`` entries change the value of one or skip it
(``project new`` lists them). ``ecattool lint`` reports (PRJ021) an ESI init command that the ESI's own
dictionary says the drive refuses (an object it lacks, read-only, or data of another size), at the ESI's line,
and (PRJ022) an ``esi_init_cmds`` entry that matches none of them.
"""

from __future__ import annotations

from ecattool.errors import EcatToolError, InputError
from ecattool.esi.model import Device
from ecattool.od.model import EcState
from ecattool.profiles.generic import init_cmds
from ecattool.profiles.rules import FamilyRules
from ecattool.project.loader import LoadedProject
from ecattool.project.model import Parameter
from ecattool.project.resolve import TRANSITION_STATE, encode_parameter, resolve_address
from ecattool.project.slave import Found
from ecattool.startup.model import TRANSITIONS, StartupCommand


def _rank(transition: str) -> int:
    return TRANSITIONS.index(transition) if transition in TRANSITIONS else len(TRANSITIONS)


def esi_startup(device: Device) -> list[StartupCommand]:
    """The CoE init commands of ``device`` (its own and its default modules', see
    :func:`ecattool.profiles.generic.init_cmds`) as startup commands: one per transition it names, in
    transition order (IP before PS before SO …), each located at its ESI line."""
    out: list[StartupCommand] = []
    for cmd in init_cmds(device):
        if cmd.protocol != "CoE":
            continue
        entry = device.dictionary.entry(cmd.index, cmd.subindex)
        value: object = None  # the data is all there is where the dictionary cannot decode it
        if entry is not None and entry.datatype is not None and entry.datatype.bits is not None \
                and len(cmd.data) == entry.byte_size:
            try:
                value = entry.decode(cmd.data)
            except (EcatToolError, ValueError):  # a value the type cannot show: the data says it
                pass
        for t in cmd.transitions:
            out.append(StartupCommand(
                transition=t.strip().upper(), index=cmd.index, subindex=cmd.subindex, data=cmd.data,
                comment=cmd.comment or (entry.name if entry is not None else ""), complete_access=cmd.complete_access,
                type_name=entry.type_name if entry is not None else None, value=value, source=cmd.location))
    out.sort(key=lambda c: _rank(c.transition))
    return out


def refusal(device: Device, cmd: StartupCommand) -> str | None:
    """Why the drive, as the ESI's dictionary describes it, would refuse ``cmd`` (None: it accepts it)."""
    what = f"{cmd.transition} {cmd.index:04X}:{cmd.subindex:02X} := {cmd.data.hex() or 'nothing'}"
    obj = device.dictionary.get(cmd.index)
    if obj is None:
        return f"the ESI's init command {what} writes object {cmd.index:04X}h, which the ESI's dictionary does not have"
    if cmd.complete_access:
        return None
    entry = obj.entry(cmd.subindex)
    if entry is None:
        return f"the ESI's init command {what} writes sub-index {cmd.subindex} of {cmd.index:04X}h ({obj.name}), " \
               "which the ESI's dictionary does not have"
    state = TRANSITION_STATE.get(cmd.transition, EcState.PREOP)
    if not entry.access.writable(state):
        how = "read-only" if not entry.access.writable() else f"not writable in {state.value}"
        return f"the ESI's init command {what} writes {entry.name}, which the ESI's dictionary makes {how}"
    if entry.datatype is not None and entry.datatype.bits is not None and len(cmd.data) != entry.byte_size:
        return f"the ESI's init command {what} carries {len(cmd.data)} byte(s); {entry.name} ({entry.type_name}) " \
               f"takes {entry.byte_size}"
    return None


def skip_hint(cmd: StartupCommand) -> str:
    return f'{{object: "{cmd.index:04X}:{cmd.subindex:02X}", transition: {cmd.transition}, skip: true}}'


def resolve_esi_init(lp: LoadedProject, i: int, device: Device, rules: FamilyRules | None,
                     params: list[StartupCommand] | None = None) -> tuple[list[StartupCommand], Found]:
    """The ESI's init commands of drive ``i`` as its project changes them (``esi_init_cmds:``), with findings.
    A command whose object a parameter writes in the same transition gives way to it (``params``: the
    drive's parameters): the parameter is the project's value, and the drive gets one write, not two."""
    found = Found()
    cmds: list[StartupCommand | None] = list(esi_startup(device))
    changed: set[int] = set()
    written = {(c.index, c.subindex, c.transition) for c in params or ()}
    for j, o in enumerate(lp.project.drives[i].esi_init_cmds):
        loc = lp.drive_location(i, "esi_init_cmds", j, "object")
        try:
            index, sub = resolve_address(device, o.object, loc)
        except InputError as exc:
            found.error("PRJ022", exc.message, loc)
            continue
        hits = [k for k, c in enumerate(cmds) if c is not None and (c.index, c.subindex) == (index, sub)
                and (o.transition is None or c.transition == o.transition)]
        if not hits:
            have = "; ".join(f"{c.transition} {c.index:04X}:{c.subindex:02X}" for c in esi_startup(device))
            where = f" in {o.transition}" if o.transition else ""
            found.error("PRJ022", f"the ESI has no init command writing {index:04X}:{sub:02X}{where} "
                                  f"(its init commands: {have or 'none'})", loc)
            continue
        for k in hits:
            old = cmds[k]
            assert old is not None
            changed.add(k)
            if o.skip:
                cmds[k] = None
                continue
            assert o.value is not None  # the model requires a value where it does not skip
            p = Parameter(object=f"{index:04X}:{sub:02X}", value=o.value, transition=old.transition,
                          comment=o.comment or old.comment)
            new, findings = encode_parameter(device, p, loc, lp.drive_location(i, "esi_init_cmds", j, "value"),
                                             rules)
            found.extend(findings)
            cmds[k] = new
    for k, c in enumerate(cmds):
        if c is not None and k not in changed and (c.index, c.subindex, c.transition) in written:
            cmds[k] = None
        if c is None or k in changed or cmds[k] is None:
            continue
        why = refusal(device, c)
        if why is not None:
            found.error("PRJ021", f"{why}: the drive would abort it; if it does, skip it under the drive's "
                                  f"esi_init_cmds: - {skip_hint(c)}", c.source)
    return [c for c in cmds if c is not None], found
