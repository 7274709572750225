"""The optional libraries the pictures need (the ``report`` extra), checked before any work starts."""

from __future__ import annotations

import importlib
from typing import Any

from ecattool.errors import EcatToolError

EXTRA_HINT = "pip install 'ecattool[report]'"


class MissingExtra(EcatToolError):
    """An optional library is not installed."""


def require(*modules: str) -> None:
    """Raise :class:`MissingExtra` unless every one of ``modules`` (default: Jinja2 and matplotlib) imports."""
    missing = []
    for name in modules or ("jinja2", "matplotlib"):
        try:
            importlib.import_module(name)
        except ImportError:
            missing.append(name)
    if missing:
        raise MissingExtra(f"HTML/SVG output needs {' and '.join(missing)} (the report extra): {EXTRA_HINT}")


def environment() -> Any:
    """The Jinja2 environment of the package templates (autoescaped: names from ESI files are untrusted)."""
    require("jinja2")
    import jinja2

    env = jinja2.Environment(loader=jinja2.PackageLoader("ecattool.report", "templates"), autoescape=True,
                             undefined=jinja2.StrictUndefined, trim_blocks=True, lstrip_blocks=True,
                             keep_trailing_newline=True)
    return env
