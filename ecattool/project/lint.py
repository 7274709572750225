"""Lint orchestration: run every check ecattool has over a project and collect located findings."""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from ecattool.errors import EcatToolError, Location
from ecattool.fileio import read_bytes
from ecattool.findings import Finding, Severity, has_errors
from ecattool.project.loader import LoadedProject, parse_project
from ecattool.project.model import RuleOff
from ecattool.project.resolve import ResolvedDrive, resolve_device, resolve_parameters
from ecattool.startup.model import StartupList

#: the forms of rule ids: PRJ012 and PDO011 (catalogued in :func:`rule_descriptions`), esi-pdo-object-missing
#: (catalogued), scaling.small-pair (notes of the factor-group computation lint runs)
_RULE_ID = re.compile(r"^(?:[A-Z]{2,5}\d{3}|esi-[a-z0-9-]+|scaling\.[a-z0-9-]+)$")
#: families whose every rule is in :func:`rule_descriptions`: an id of theirs that is not there is a typo
_CATALOGUED = re.compile(r"^(?:PRJ|PDO)\d{3}$")

#: project-level rule catalogue (other packages document their own rules)
PROJECT_RULES: dict[str, str] = {
    "PRJ001": "the project file does not match the project schema",
    "PRJ002": "a file named in the project does not exist",
    "PRJ003": "a disabled rule id is not a rule lint reports",
    "PRJ004": "a rule is disabled without a reason",
    "PRJ005": "the device of a drive cannot be resolved (ESI error, selector or profile unknown)",
    "PRJ010": "a parameter names an object that does not exist",
    "PRJ011": "a parameter names a sub-index that does not exist",
    "PRJ012": "a parameter is not writable in the state of its transition",
    "PRJ013": "a parameter value does not fit the object's data type",
    "PRJ014": "a parameter value is outside the object's minimum/maximum",
    "PRJ015": "a parameter value is not one of the object's documented values",
    "PRJ016": "the same object is written twice in the same transition",
    "PRJ017": "a mode of operation (6060h) the drive does not support",
    "PRJ018": "the commissioning move needs an object the drive does not have (6060h, 607Ah, 6064h)",
    "PRJ019": "the commissioning PP move runs at a profile velocity or acceleration of 0 (not set, no default)",
    "PRJ020": "two drives share a bus position",
    "PRJ021": "an init command of the ESI writes an object the ESI's dictionary says the drive refuses",
    "PRJ022": "an esi_init_cmds entry matches none of the ESI's init commands",
    "PRJ023": "a zero part of the position factor (608Fh, 6091h, 6092h) makes positions impossible to convert",
    "PRJ030": "the .sw image of a drive cannot be read or fails its integrity checks",
    "PRJ031": "a .sw image is configured for a drive that is not a Technosoft drive",
    "PRJ032": "a .sw image was made for another Technosoft product or firmware than the drive's",
    "PRJ040": "the DC OpMode named does not exist in the ESI",
    "PRJ041": "the drive runs a mode that needs distributed clocks, and DC is not configured",
    "PRJ042": "a SYNC0 cycle time the drive does not accept",
    "PRJ043": "a write to the interpolation period (60C2h) leaves a period the drive does not accept",
    "PRJ044": "the interpolation period (60C2h) differs from the SYNC0 cycle of an interpolated mode",
    "PRJ045": "the drive runs cyclic synchronous position (csp) without distributed clocks",
    "PRJ050": "the scaling section cannot be computed",
}


def rule_descriptions() -> dict[str, str]:
    """Every rule id lint can report (project, PDO mapping, ESI structure) -> what it means."""
    from ecattool.esi.checks import RULES as ESI_RULES
    from ecattool.pdo.check import RULES as PDO_RULES

    return {**PROJECT_RULES, **{k: title for k, (_, title) in PDO_RULES.items()}, **ESI_RULES}


@dataclass(slots=True)
class ProjectResult:
    path: str
    drives: list[ResolvedDrive] = field(default_factory=list)
    findings: list[Finding] = field(default_factory=list)  # project-level and all drives', after disabling
    loaded: LoadedProject | None = None


def _disable(findings: list[Finding], offs: list[RuleOff], lp: LoadedProject, path: tuple[str | int, ...]) -> list[Finding]:
    out: list[Finding] = []
    disabled = set()
    known = rule_descriptions()
    for k, off in enumerate(offs):
        loc = lp.yaml.locate((*path, k, "rule"))
        if off.rule in known:
            pass
        elif not _RULE_ID.match(off.rule):
            out.append(Finding("PRJ003", Severity.WARNING, f"{off.rule!r} is not a rule id (like PDO011, "
                                                           "esi-pdo-object-missing or scaling.small-pair)", loc))
        elif _CATALOGUED.match(off.rule):
            out.append(Finding("PRJ003", Severity.WARNING, f"lint has no rule {off.rule} (the rules: "
                                                           "docs/project.md, docs/pdo-mapping.md)", loc))
        if not off.reason.strip():
            out.append(Finding("PRJ004", Severity.ERROR, f"rule {off.rule} is disabled without a reason",
                               lp.yaml.locate((*path, k, "reason"))))
            continue
        disabled.add(off.rule)
    return out + [f for f in findings if f.rule not in disabled]


def build_drive(lp: LoadedProject, i: int) -> ResolvedDrive:
    """Resolve one drive: device, rules, startup list (PDO, scaling, parameters), .sw image, with findings."""
    from ecattool.project import steps

    drive = lp.project.drives[i]
    rd = ResolvedDrive(i, drive)
    resolve_device(lp, i, rd)
    if rd.device is None:
        return rd
    startup = StartupList(name=drive.name, vendor_id=rd.device.vendor_id,
                          product_code=rd.device.product_code, revision=rd.device.revision)
    params = resolve_parameters(lp, i, rd)
    startup.extend(steps.pdo_commands(lp, i, rd, params))
    if drive.device.esi is not None:  # the ESI's init commands, as TwinCAT sends them: after the PDO assignment
        from ecattool.project.initcmds import resolve_esi_init

        startup.extend(resolve_esi_init(lp, i, rd, params))
    startup.extend(steps.scaling_commands(lp, i, rd))
    startup.extend(params)
    rd.startup = startup
    steps.check_sw(lp, i, rd)
    steps.check_move(lp, i, rd)
    steps.check_factor_defaults(lp, i, rd)
    steps.check_interpolation_period(lp, i, rd)
    steps.check_dc(lp, i, rd)
    if rd.device.source and not rd.device.source.startswith("profile:"):
        steps.check_esi(lp, i, rd)
    rd.findings = _disable(rd.findings, drive.disable_rules, lp, ("drives", i, "disable_rules"))
    return rd


def lint_project(path: str | Path) -> ProjectResult:
    p = Path(path)
    result = ProjectResult(str(p))
    try:
        project, doc, schema_findings = parse_project(read_bytes(p, 16 * 1024 * 1024), str(p))
    except EcatToolError as exc:
        result.findings.append(Finding("PRJ001", Severity.ERROR, exc.message, exc.location or Location(str(p))))
        return result
    result.findings.extend(schema_findings)
    if project is None:  # else the drives that are well-formed (schema errors in others) are still checked
        return result
    lp = LoadedProject(project, p, doc)
    result.loaded = lp
    positions: dict[int, str] = {}
    for i in range(len(project.drives)):
        rd = build_drive(lp, i)
        result.drives.append(rd)
        if rd.position in positions:
            rd.findings.append(Finding("PRJ020", Severity.ERROR,
                                       f"drive {rd.drive.name!r} has bus position {rd.position}, like {positions[rd.position]!r}",
                                       lp.drive_location(i, "position")))
        positions.setdefault(rd.position, rd.drive.name)
        result.findings.extend(rd.findings)
    result.findings = _disable(result.findings, project.disable_rules, lp, ("disable_rules",))
    # de-duplicate (ESI findings of a file shared by several drives)
    seen = set()
    unique = []
    for f in result.findings:
        key = (f.rule, f.message, str(f.location))
        if key not in seen:
            seen.add(key)
            unique.append(f)
    result.findings = unique
    return result


def lint(paths: list[str | Path], strict: bool = False) -> tuple[list[ProjectResult], bool]:
    """Lint several project files. Returns the results and whether the lint failed."""
    results = [lint_project(p) for p in paths]
    failed = any(has_errors(r.findings, strict) for r in results)
    return results, failed
