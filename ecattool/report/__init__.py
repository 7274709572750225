"""Pictures for people: the HTML commissioning report, the process-image diagram (SVG) and the scaling page.

Public API::

    from ecattool import report
    svg = report.process_image_svg(pdo.layout(device, mapping))        # the diagram alone (needs Jinja2)

The pages are self-contained (inline CSS and SVG, no script, no network). Jinja2 and matplotlib are an
optional extra: ``pip install 'ecattool[report]'``; without it every function raises
:class:`MissingExtra` (one line, naming the extra) before any work is done.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ecattool.report.extra import MissingExtra, require

if TYPE_CHECKING:
    from ecattool.pdo.layout import Layout


def process_image_svg(layout: Layout, title: str = "") -> str:
    """The process image of ``layout`` as a standalone SVG document (see :mod:`ecattool.report.diagram`)."""
    from ecattool.report.diagram import process_image_svg as svg

    return svg(layout, title)


__all__ = ["MissingExtra", "process_image_svg", "require"]
