"""The HTML commissioning report: one self-contained page for one or more ``commission`` runs.

Per drive: identity and result, every step, the process image (:mod:`ecattool.report.diagram`), the startup
list as sent with each write's result and read-back, the ``.sw`` blocks, the state timeline and plots of the
commissioning move (:mod:`ecattool.report.plots`); per project: the lint findings with file and line.
No script, no external resource: the page opens from disk and shows the same everywhere.
"""

from __future__ import annotations

import datetime as _dt
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from ecattool import __version__
from ecattool.report.extra import environment, require

if TYPE_CHECKING:
    from ecattool.commission.runner import CommissionReport, DriveReport
    from ecattool.commission.trace import DriveTrace


@dataclass(slots=True)
class DriveView:
    """What the template shows of one drive."""

    uid: str
    report: DriveReport
    trace: DriveTrace
    identity: str
    diagram: str | None
    timeline: str | None
    plots: list[tuple[str, str]] = field(default_factory=list)


@dataclass(slots=True)
class ProjectView:
    report: CommissionReport
    drives: list[DriveView]


def _identity(report: DriveReport) -> str:
    step = next((s for s in report.steps if s.name == "identity"), None)
    return step.detail if step is not None else "not read"


def drive_view(report: DriveReport, uid: str) -> DriveView:
    from ecattool.report.diagram import process_image_svg
    from ecattool.report.plots import move_svgs, timeline_svg

    trace = report.trace
    diagram = process_image_svg(trace.layout, standalone=False, uid=f"{uid}-pi") if trace.layout else None
    return DriveView(uid, report, trace, _identity(report), diagram, timeline_svg(trace, f"{uid}-tl"),
                     move_svgs(trace, f"{uid}-mv"))


def _generated() -> str:
    """When the page was made; SOURCE_DATE_EPOCH (the reproducible-builds convention) fixes it."""
    import os

    epoch = os.environ.get("SOURCE_DATE_EPOCH", "")
    when = (_dt.datetime.fromtimestamp(int(epoch), _dt.timezone.utc) if epoch.isdigit()
            else _dt.datetime.now(_dt.timezone.utc))
    return when.strftime("%Y-%m-%d %H:%M:%S UTC")


def commission_html(reports: list[CommissionReport]) -> str:
    """The report page of ``reports`` (one per project file)."""
    require()
    projects = [ProjectView(r, [drive_view(d, f"p{i}d{j}") for j, d in enumerate(r.drives)])
                for i, r in enumerate(reports)]
    total = sum(len(p.drives) for p in projects)
    failed = sum(1 for p in projects for d in p.drives if not d.report.ok)
    now = _generated()
    return str(environment().get_template("commission.html.j2").render(
        projects=projects, total=total, failed=failed, ok=bool(reports) and all(r.ok for r in reports),
        version=__version__, generated=now))
