"""The machine as a project sets it up: one :class:`Machine` of :class:`Slave` objects, built once.

>>> from ecattool.project.machine import load_machine
>>> m = load_machine("samples/hdt/project.yaml")                  # doctest: +SKIP
>>> [(s.name, s.kind, s.device.type_name) for s in m.in_bus_order()]  # doctest: +SKIP

``load_machine`` reads the project file and resolves every slave: the device as it runs (ESI default modules
plugged in, communication objects completed: :func:`ecattool.project.cache.load_device_cached`), its family
rules, the PDO mapping, the startup list (PDO programming, ESI init commands, scaling objects, parameters, in
that order), DC, and for an axis the factor group and the ``.sw`` image; every check lint has adds its findings
on the way. Every action consumes the result instead of resolving the project again: ``lint`` prints its
findings, ``commission`` runs it, ``startup export`` writes it, ``sim serve`` puts its devices on a bus,
``sw verify/download --project`` and ``scale explain --project`` take one slave of it, and the HTML report
shows it. A command acts on a project with lint errors only when told to (:meth:`Machine.refuse_errors`,
the ``--allow-errors`` option).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from types import ModuleType

from ecattool.errors import EcatToolError, InputError, Location
from ecattool.esi.model import Device
from ecattool.fileio import named_file_problem, read_bytes
from ecattool.findings import Finding, Severity
from ecattool.project import familycycle
from ecattool.project.loader import LoadedProject, parse_project
from ecattool.project.model import DeviceRef, Drive, Project
from ecattool.project.resolve import resolve_dc, resolve_device, resolve_parameters
from ecattool.project.rules import disable
from ecattool.project.slave import Slave, SlaveDc, SlaveKind, is_axis
from ecattool.startup.config import SlaveConfig
from ecattool.startup.install import KickcatBus, MasterKind, PysoemMaster, install
from ecattool.startup.model import StartupCommand, StartupList
from ecattool.yamlloc import LocatedYaml

__all__ = ["ALLOW_ERRORS_HELP", "FLAGS_SOURCE", "Machine", "Slave", "SlaveDc", "SlaveKind", "device_entry", "is_axis",
           "load_machine", "one_slave_machine", "slave_config"]

#: the help of the ``--allow-errors`` option every command that acts on a project has
ALLOW_ERRORS_HELP = ("Act on the project even when lint reports errors (by default a project with lint errors is "
                     "refused, naming the first error's file and line).")


@dataclass(frozen=True, slots=True)
class Machine:
    """The slaves of one project file, resolved (in file order), and every finding lint reports about them.
    Frozen: :func:`load_machine` builds it once, and every command consumes it."""

    path: str
    slaves: tuple[Slave, ...] = ()
    #: project-level findings and every slave's, after ``disable_rules``, de-duplicated
    findings: tuple[Finding, ...] = ()
    #: the project as loaded; None where the file does not load (its findings say why: :meth:`require_loaded`)
    loaded: LoadedProject | None = None

    @property
    def target(self) -> str:
        """The project's default target spec (``sim`` where the project does not load)."""
        return self.loaded.project.target if self.loaded is not None else "sim"

    @classmethod
    def from_device_flags(cls, *, source: str | Path | None = None, esi: str | Path | None = None,
                          select: str | int | None = None, policy: str = "exact", profile: str | None = None,
                          product: str | None = None, revision: str | int | None = None) -> Machine:
        """The one-slave machine the device flags of a command name: the project entry :func:`device_entry`
        makes of them, built by :func:`one_slave_machine`; the command acts on ``machine.slaves[0]``.

        >>> m = Machine.from_device_flags(esi="samples/esi/etg2001_modular.xml")   # doctest: +SKIP
        >>> m.slaves[0].device.type_name, m.slaves[0].mapping                       # doctest: +SKIP
        """
        return one_slave_machine(device_entry(source=source, esi=esi, select=select, policy=policy, profile=profile,
                                              product=product, revision=revision))

    def in_bus_order(self) -> list[Slave]:
        return sorted(self.slaves, key=lambda s: s.position)

    def slave(self, name: str | None) -> Slave:
        """The slave called ``name``; without a name the only slave (an InputError lists the names)."""
        chosen = [s for s in self.slaves if s.name == name] if name is not None else self.slaves
        if len(chosen) != 1:
            names = ", ".join(s.name for s in self.slaves)
            why = f"has no drive {name!r}" if name is not None else "has several drives"
            raise InputError(f"the project {why}; choose one ({names})", Location(self.path))
        return chosen[0]

    def slave_to_act_on(self, name: str | None, verb: str, *, allow_errors: bool = False) -> Slave:
        """The slave ``name`` (see :meth:`slave`) for a command that acts on one drive of the project (``scale
        explain --project``, ``sw … --project``): refused as :meth:`refuse_errors` says, for the project-level
        errors and the slave's own (``cannot {verb} drive 'x': …``)."""
        self.require_loaded()
        chosen = self.slave(name)
        self.refuse_errors(f"{verb} drive {chosen.name!r}", allow_errors=allow_errors, slaves=[chosen])
        return chosen

    def sw_drive(self, name: str | None, *, allow_errors: bool = False) -> Slave:
        """The drive ``sw verify/download/upload --project`` acts on: ``name``, else the only slave, else the only one
        with an ``sw:``. One whose ``sw:`` is configured but does not read is refused with lint's reason (PRJ002,
        PRJ030); then as :meth:`slave_to_act_on` says."""
        self.require_loaded()
        if name is None:
            with_sw = [s for s in self.slaves if s.drive.sw_config is not None]
            name = with_sw[0].name if len(with_sw) == 1 else None
        chosen = self.slave(name)
        if chosen.drive.sw_config is not None and chosen.sw_image is None:  # configured but unreadable: lint's why
            why = next((f for f in chosen.findings if f.rule in ("PRJ002", "PRJ030") and f.severity is Severity.ERROR),
                       None)
            if why is not None:
                raise InputError(f"drive {chosen.name!r}: {why.message}", why.location)
        return self.slave_to_act_on(chosen.name, "use", allow_errors=allow_errors)

    def errors(self, slaves: Sequence[Slave] | None = None) -> list[Finding]:
        """The error findings of the project (or only those of ``slaves``, with the project-level ones)."""
        errs = [f for f in self.findings if f.severity is Severity.ERROR]
        if slaves is None:
            return errs

        def key(f: Finding) -> tuple[str, str, str]:
            return f.rule, f.message, str(f.location)

        mine = {key(f) for s in slaves for f in s.findings}
        anyone = {key(f) for s in self.slaves for f in s.findings}
        return [f for f in errs if key(f) in mine or key(f) not in anyone]

    def require_loaded(self) -> LoadedProject:
        """The loaded project, or the InputError of why it does not load (file and line)."""
        if self.loaded is not None:
            return self.loaded
        first = self.findings[0]
        raise InputError(first.message, first.location or Location(self.path))

    def refuse_errors(self, what: str, *, allow_errors: bool = False, slaves: Sequence[Slave] | None = None) -> None:
        """The one policy for acting on a project with lint errors: refuse (an InputError at the first error,
        naming its rule and how many more there are) unless ``allow_errors``. A project that does not load,
        or a slave whose device does not resolve, is refused even then: there is nothing to act on."""
        self.require_loaded()
        self._refuse_unresolved(what, slaves if slaves is not None else self.slaves)
        errors = self.errors(slaves)
        if allow_errors or not errors:
            return
        first = errors[0]
        more = f" (and {len(errors) - 1} more)" if len(errors) > 1 else ""
        raise InputError(f"cannot {what}: the project has lint errors, first: {first.message} [{first.rule}]{more}; "
                         f"run `ecattool lint {self.path}`, or --allow-errors to act anyway",
                         first.location or Location(self.path))

    @staticmethod
    def _refuse_unresolved(what: str, slaves: Sequence[Slave]) -> None:
        for s in slaves:
            if s.device is None:
                why = next((f for f in s.findings if f.severity is Severity.ERROR), None)
                raise InputError(f"cannot {what}: drive {s.name!r}'s device did not resolve"
                                 + (f": {why.message} [{why.rule}]" if why else " (see `ecattool lint`)"),
                                 why.location if why else None)

    def devices(self) -> list[tuple[str, Device]]:
        """(name, device as it runs) of every slave in bus order (an InputError for one that did not resolve)."""
        self._refuse_unresolved("put the project's devices on a bus", self.slaves)
        return [(s.name, s.device) for s in self.in_bus_order() if s.device is not None]

    def configs(self, *, allow_errors: bool = False) -> list[SlaveConfig]:
        """One slave configuration per slave, in bus order (refused on lint errors unless ``allow_errors``)."""
        self.refuse_errors("export the startup configuration", allow_errors=allow_errors)
        return [slave_config(s) for s in self.in_bus_order()]

    def install(self, master: PysoemMaster | KickcatBus, *, kind: MasterKind | None = None,
                exact_revision: bool = False, allow_errors: bool = False,
                module: ModuleType | None = None) -> list[int]:
        """Attach every slave's startup list to ``master`` in a master program, with the identity check
        (:func:`ecattool.startup.install.install`): a ``pysoem.Master`` after ``config_init()`` gets a
        ``config_func`` per slave; a ``kickcat.Bus`` after ``init()`` is written at once. Returns the positions
        configured; refused on lint errors unless ``allow_errors``."""
        self.refuse_errors("install the startup list", allow_errors=allow_errors)
        return install([slave_config(s) for s in self.in_bus_order()], master, kind=kind,
                       exact_revision=exact_revision, module=module)


def slave_config(s: Slave) -> SlaveConfig:
    """The slave configuration (identity, startup list, assigned PDOs, sync managers, DC) of one resolved slave."""
    if s.device is None:
        raise InputError(f"drive {s.drive.name!r}: the device did not resolve (see lint)")
    cfg = SlaveConfig.from_device(s.device, s.startup, mapping=s.mapping, position=s.position, name=s.drive.name)
    if s.dc is not None:
        cfg.dc_assign_activate, cfg.dc_cycle_ns, cfg.dc_shift_ns = s.dc.assign_activate, s.dc.cycle_ns, s.dc.shift_ns
        cfg.dc_sync1_cycle_ns, cfg.dc_sync1_shift_ns = s.dc.sync1_cycle_ns, s.dc.sync1_shift_ns
    return cfg


def build_slave(lp: LoadedProject, i: int) -> Slave:
    """Resolve one slave: device, rules, startup list (PDO, ESI init commands, scaling, parameters), .sw image,
    with the findings of every check. The one place a :class:`Slave` is assembled: each step returns what it
    resolves, the slave is made from those values, and the checks read it."""
    from ecattool.project import steps

    drive = lp.project.drives[i]
    device, rules, found = resolve_device(lp, i)
    if device is None:
        return Slave(i, drive, findings=tuple(found))
    dc = resolve_dc(drive, device)
    params, params_found = resolve_parameters(lp, i, device, rules)
    pdo = steps.pdo_commands(lp, i, device, rules, params)
    init: list[StartupCommand] = []
    init_found: list[Finding] = []
    if drive.device.esi is not None:  # the ESI's init commands, as TwinCAT sends them: after the PDO assignment
        from ecattool.project.initcmds import resolve_esi_init

        init, init_found = resolve_esi_init(lp, i, device, rules, params)
    scaling = steps.scaling_commands(lp, i, device)
    sw_image, sw_found = steps.resolve_sw(lp, i, device)
    startup = StartupList(name=drive.name, vendor_id=device.vendor_id,
                          product_code=device.product_code, revision=device.revision)
    for commands in (pdo.commands, init, scaling.commands, params):
        startup.extend(commands)
    slave = Slave(i, drive, device=device, rules=rules, startup=startup, mapping=pdo.mapping,
                  factor_group=scaling.factor_group, counts_per_unit=scaling.counts_per_unit, sw_image=sw_image, dc=dc)
    findings = [*found, *params_found, *pdo.found, *init_found, *scaling.found,
                *steps.check_mailbox(lp, i, slave), *steps.check_kind(lp, i, slave),
                *steps.check_pdo_objects(lp, i, slave), *sw_found, *steps.check_move(lp, i, slave),
                *steps.check_factor_defaults(lp, i, slave), *steps.check_interpolation_period(lp, i, slave),
                *steps.check_dc(lp, i, slave), *familycycle.check_dc_cycle(lp, i, slave)]
    if device.source and not device.source.startswith("profile:"):
        findings.extend(steps.check_esi(lp, i, slave))
    return replace(slave, findings=tuple(disable(findings, drive.disable_rules, lp, ("drives", i, "disable_rules"))))


#: the source a machine built from command-line flags names (its drive has no file and line)
FLAGS_SOURCE = "<command line>"


def device_entry(*, source: str | Path | None = None, esi: str | Path | None = None, select: str | int | None = None,
                 policy: str = "exact", profile: str | None = None, product: str | None = None,
                 revision: str | int | None = None) -> DeviceRef:
    """The project entry ``device: {...}`` that command-line device flags mean: ``esi`` (with ``select`` and
    ``policy``; a ``revision`` narrows ``select`` to ``select:revision``, as ``--device SEL --revision R`` does),
    or a built-in ``profile`` (``product``, ``revision``), or ``source``, which is either: an ESI/EDS file (a
    ``.xml``/``.eds``/``.dcf`` name or an existing file) or else a profile name. Paths stay as given: relative
    to the current directory. Bad combinations are an InputError (one line)."""
    from pydantic import ValidationError

    from ecattool.profiles.running import is_device_file

    if source is not None:
        if is_device_file(source):
            esi = source
        else:
            profile = str(source)
    if esi is not None:
        if select not in (None, "") and revision not in (None, ""):
            select = f"{select}:{revision}"
        fields: dict[str, object] = {"esi": str(esi), "select": None if select == "" else select, "policy": policy}
    else:
        fields = {"profile": profile, "product": product, "revision": revision}
    try:
        return DeviceRef.model_validate(fields)
    except ValidationError as exc:
        first = exc.errors()[0]
        where = ".".join(str(p) for p in first.get("loc", ()))
        msg = first.get("msg", "invalid device").removeprefix("Value error, ")
        raise InputError(f"device {where}: {msg}" if where else f"device: {msg}") from None


def one_slave_machine(device: DeviceRef, name: str = "device") -> Machine:
    """The machine a project with one drive ``{name: ..., device: device}`` is: built by the same steps as
    :func:`load_machine` (the device as it runs, rules, mapping, startup list, the findings lint has for it),
    so a command given device flags acts on ``machine.slaves[0]`` exactly as on a project's slave. A device that
    does not resolve raises its error (InputError, at the file and line where the problem is in a named file)
    instead of being a finding: there is nothing to act on. Relative paths are relative to the current
    directory. A named file that cannot be read is that file's one-line error (``FILE: not found``), as every
    command that reads a file says it."""
    problem = named_file_problem(device.esi) if device.esi is not None else None
    if problem is not None:
        raise InputError(problem, Location(device.esi))
    project = Project(ecattool=1, drives=[Drive(name=name, device=device)])
    doc = LocatedYaml(project.model_dump(mode="json", exclude_defaults=True), {(): Location()}, FLAGS_SOURCE)
    lp = LoadedProject(project, Path(FLAGS_SOURCE), doc)  # base: the current directory
    slave = build_slave(lp, 0)
    if slave.device is None:
        why = next((f for f in slave.findings if f.severity is Severity.ERROR), None)
        if why is None:  # pragma: no cover - a device that does not resolve always says why
            raise InputError("the device did not resolve")
        loc = why.location
        raise InputError(why.message, loc if loc is not None and loc.file else None)
    return Machine(FLAGS_SOURCE, (slave,), slave.findings, lp)


def load_machine(path: str | Path) -> Machine:
    """Build the machine of the project file at ``path``. Never raises for a bad project: a file that does not
    load is a Machine without slaves whose findings say why (PRJ001, at the file and line)."""
    p = Path(path)
    try:
        project, doc, schema_findings = parse_project(read_bytes(p, 16 * 1024 * 1024), str(p))
    except EcatToolError as exc:
        return Machine(str(p), (), (Finding("PRJ001", Severity.ERROR, exc.message, exc.location or Location(str(p))),))
    if project is None:  # else the drives that are well-formed (schema errors in others) are still checked
        return Machine(str(p), (), tuple(schema_findings))
    lp = LoadedProject(project, p, doc)
    findings = list(schema_findings)
    built: list[Slave] = []
    positions: dict[int, str] = {}
    for i in range(len(project.drives)):
        s = build_slave(lp, i)
        if s.position in positions:
            s = replace(s, findings=(*s.findings, Finding(
                "PRJ020", Severity.ERROR, f"drive {s.name!r} has bus position {s.position}, like {positions[s.position]!r}",
                lp.drive_location(i, "position"))))
        positions.setdefault(s.position, s.name)
        built.append(s)
        findings.extend(s.findings)
    findings = disable(findings, project.disable_rules, lp, ("disable_rules",))
    off = {o.rule for o in project.disable_rules if o.reason.strip()}
    # a project-wide disable holds for each slave too (commission checks a slave's own)
    slaves = tuple(replace(s, findings=tuple(f for f in s.findings if f.rule not in off)) for s in built)
    # de-duplicate (ESI findings of a file shared by several drives)
    seen = set()
    unique = []
    for f in findings:
        key = (f.rule, f.message, str(f.location))
        if key not in seen:
            seen.add(key)
            unique.append(f)
    return Machine(str(p), slaves, tuple(unique), lp)
