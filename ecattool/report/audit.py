"""The HTML page of an audit (``ecattool audit --html``): the drifts in one table."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ecattool import __version__
from ecattool.report.extra import environment

if TYPE_CHECKING:
    from ecattool.online.audit import AuditReport


def audit_html(report: "AuditReport") -> str:
    from ecattool.report.commission import _generated

    return str(environment().get_template("audit.html.j2").render(report=report, version=__version__,
                                                                   generated=_generated()))
