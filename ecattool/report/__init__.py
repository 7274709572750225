"""Pictures for people: the HTML commissioning report, the process-image diagram (SVG) and the scaling page.

Public API::

    from ecattool import report
    svg = report.process_image_svg(pdo.layout(device, mapping))        # the diagram alone (needs Jinja2)
    html = report.commission_html([commission("samples/hdt/project.yaml")])   # the report (Jinja2 + matplotlib)
    html = report.scaling_html(explain(values, "hdt"), values)          # the factor-group chain (Jinja2)

The pages are self-contained (inline CSS and SVG, no script, no network). Jinja2 and matplotlib are an
optional extra: ``pip install 'ecattool[report]'``; without it every function raises
:class:`MissingExtra` (one line, naming the extra) before any work is done.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ecattool.report.extra import MissingExtra, require

if TYPE_CHECKING:
    from ecattool.commission.runner import CommissionReport
    from ecattool.pdo.layout import Layout
    from ecattool.scaling.explain import Explanation


def process_image_svg(layout: Layout, title: str = "") -> str:
    """The process image of ``layout`` as a standalone SVG document (see :mod:`ecattool.report.diagram`)."""
    from ecattool.report.diagram import process_image_svg as svg

    return svg(layout, title)


def commission_html(reports: list[CommissionReport]) -> str:
    """One self-contained HTML page for commissioning runs (see :mod:`ecattool.report.commission`)."""
    from ecattool.report.commission import commission_html as html

    return html(reports)


def scaling_html(explanation: Explanation, values: dict[tuple[int, int], int],
                 mechanics: dict[str, str] | None = None, title: str = "") -> str:
    """The factor-group derivation as a chain encoder → gear → transmission → user unit (HTML page)."""
    from ecattool.report.scaling import scaling_html as html

    return html(explanation, values, mechanics, title)


__all__ = ["MissingExtra", "commission_html", "process_image_svg", "require", "scaling_html"]
