"""The corpus sweep (issue 22): every device of every ESI and EDS in ../shared/corpus goes through
``project new`` → ``lint`` → ``commission`` on the simulator, as a new user would run them.

All devices of all files are swept (no sampling: 520 devices since issue 34 added 14 Beckhoff families; the sweep
takes about 22 s on one core with a warm device cache, 50 s cold, most of it reading the EL1xxx and EL66xx files). A file without devices (a module file such as weidmueller_UR20_IO.xml, an external
dictionary such as beckhoff_AX5021-xxxx-0001_Dict.xml) is counted as such. The test fails on

* a device whose skeleton lints clean and does not commission (lint clean ⇒ commissions), and
* a device that is not usable for a reason the documented table does not name: every lint error rule that
  refuses a skeleton must be a row of the table "Machine: the corpus sweep" in docs/decisions.md, which says
  why such a device is refused; and
* a row of that table that no corpus device needs any more (a false finding fixed since).

The skeleton is made by the library calls ``ecattool project new`` makes, lint and commission are the
in-process library calls of ``ecattool lint`` and ``ecattool commission`` (one Machine built per device).
"""

from __future__ import annotations

import re
from collections import Counter
from pathlib import Path

from ecattool.commission import commission
from ecattool.errors import EcatToolError
from ecattool.findings import Severity
from ecattool.project.cache import load_esi_cached
from ecattool.project.machine import load_machine
from ecattool.project.skeleton import esi_flaws, new_project, resolve

ROOT = Path(__file__).resolve().parent.parent
from tests.conftest import CORPUS, need_corpus  # noqa: E402

need_corpus()
DECISIONS = ROOT / "docs" / "decisions.md"


def _documented_rules() -> dict[str, str]:
    """rule → reason, from the table of the decision "Machine: the corpus sweep"."""
    text = DECISIONS.read_text(encoding="utf-8")
    start = text.index("## Machine: the corpus sweep")
    end = text.find("\n## ", start + 1)
    section = text[start:end if end > 0 else None]
    rows = re.findall(r"^\| `?([A-Za-z0-9.\-]+)`? \| (.+?) \|", section, re.MULTILINE)
    return {rule: reason for rule, reason in rows if rule.lower() != "rule"}


def _selector(devices: list, k: int) -> str:
    d = devices[k]
    same = [x for x in devices if (x.vendor_id, x.product_code, x.revision) == (d.vendor_id, d.product_code, d.revision)]
    return f"0x{d.vendor_id or 0:X}:0x{d.product_code:X}:0x{d.revision:X}" if len(same) == 1 else str(k)


def test_every_corpus_device_is_usable_or_refused_for_a_documented_reason(tmp_path: Path) -> None:
    files = sorted((CORPUS / "esi").glob("*.xml")) + sorted((CORPUS / "eds").glob("*.eds"))
    assert len(files) >= 20, f"the corpus is missing: {CORPUS}"
    documented = _documented_rules()
    assert documented, "docs/decisions.md has no table of refusal reasons"
    counts: Counter[str] = Counter()
    refused_by: Counter[str] = Counter()
    clean_but_fails: list[str] = []
    undocumented: list[str] = []
    project = tmp_path / "project.yaml"
    for path in files:
        devices = list(load_esi_cached(path).devices)
        if not devices:
            counts["files without devices"] += 1
            continue
        for k in range(len(devices)):
            select = None if path.suffix.lower() == ".eds" else _selector(devices, k)
            what = f"{path.name} [{k}] {devices[k].type_name}"
            counts["devices"] += 1
            try:
                device = resolve(None, None, str(path), select, tmp_path)
                text = new_project(device, esi=str(path), select=select,
                                   findings=esi_flaws(str(path), select, tmp_path))
            except EcatToolError as exc:
                undocumented.append(f"{what}: project new fails: {exc}")
                continue
            project.write_text(text, encoding="utf-8")
            machine = load_machine(project)
            errors = [f for f in machine.findings if f.severity is Severity.ERROR]
            if errors:
                counts["refused by lint"] += 1
                refused_by.update({f.rule for f in errors})
                missing = sorted({f.rule for f in errors} - set(documented))
                if missing:
                    undocumented.append(f"{what}: {', '.join(missing)} (first: {errors[0]})")
                continue
            report = commission(machine)
            if report.ok:
                counts["commissioned"] += 1
                counts["commissioned as " + report.drives[0].kind] += 1
            else:
                clean_but_fails.append(f"{what}: {report.drives[0].error if report.drives else 'no report'}")
    print("\ncorpus sweep:", dict(counts), "refused by rule:", dict(refused_by))
    assert counts["devices"] >= 300
    assert not clean_but_fails, f"{len(clean_but_fails)} lint clean and do not commission:\n" + "\n".join(clean_but_fails[:20])
    assert not undocumented, (f"{len(undocumented)} refused without a documented reason (docs/decisions.md, "
                              "\"Machine: the corpus sweep\"):\n" + "\n".join(undocumented[:20]))
    stale = sorted(set(documented) - set(refused_by))
    assert not stale, (f"docs/decisions.md (\"Machine: the corpus sweep\") documents rules that refuse no corpus "
                       f"device any more: {', '.join(stale)}; remove their rows")
    assert counts["commissioned as io"] and counts["commissioned as axis"]
