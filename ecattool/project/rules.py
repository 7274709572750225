"""The rule catalogue of lint and the ``disable_rules`` of a project (the findings a project switches off)."""

from __future__ import annotations

import re

from ecattool.findings import Finding, Severity
from ecattool.project import familycycle
from ecattool.project.loader import LoadedProject
from ecattool.project.model import RuleOff

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
    "PRJ024": "the commissioning move's target does not fit the target position's type (607Ah) or position limits (607Dh)",
    "PRJ025": "enable: true on a slave that is not a CiA-402 axis",
    "PRJ026": "a SoE drive's PDO is not a CoE mapping object: ecattool configures CoE slaves only",
    "PRJ027": "a mapping object of the device's dictionary differs from its ESI PDO list, and the project keeps the power-on mapping",
    "PRJ028": "a startup SDO (parameter, PDO mapping, init command) for a slave without a CoE mailbox",
    "PRJ030": "the .sw image of a drive cannot be read or fails its integrity checks",
    "PRJ031": "a .sw image is configured for a drive that is not a Technosoft drive",
    "PRJ032": "a .sw image was made for another Technosoft product or firmware than the drive's",
    "PRJ040": "the DC OpMode named does not exist in the ESI",
    "PRJ041": "the drive runs a mode that needs distributed clocks, and DC is not configured",
    "PRJ042": "a SYNC0 cycle time the drive does not accept",
    "PRJ043": "a write to the interpolation period (60C2h) leaves a period the drive does not accept",
    "PRJ044": "the interpolation period (60C2h) differs from the SYNC0 cycle of an interpolated mode",
    "PRJ045": "the drive runs cyclic synchronous position (csp) without distributed clocks",
    "PRJ046": "SYNC1 values are given but AssignActivate does not switch SYNC1 on",
    "PRJ050": "the scaling section cannot be computed",
    familycycle.RULE: familycycle.DESCRIPTION,
}


def rule_descriptions() -> dict[str, str]:
    """Every rule id lint can report (project, PDO mapping, ESI structure) -> what it means."""
    from ecattool.esi.checks import RULES as ESI_RULES
    from ecattool.pdo.check import RULES as PDO_RULES

    return {**PROJECT_RULES, **{k: title for k, (_, title) in PDO_RULES.items()}, **ESI_RULES}


def disable(findings: list[Finding], offs: list[RuleOff], lp: LoadedProject, path: tuple[str | int, ...]) -> list[Finding]:
    """``findings`` without those of the rules ``offs`` disables, after the findings about ``offs`` itself
    (PRJ003 unknown rule, PRJ004 no reason)."""
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
