"""Startup-list formats: one module per format holding both directions where both exist.

Each module has ``NAME``, ``DESCRIPTION``, ``EXTENSIONS`` and some of ``export(configs) -> str``,
``load(data, source) -> list[SlaveConfig]`` and ``detect(data) -> bool``.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from types import ModuleType

#: format name -> module (in detection order)
_MODULES = {
    "eni": "ecattool.startup.formats.eni",
    "twincat": "ecattool.startup.formats.twincat",
    "igh": "ecattool.startup.formats.igh",
    "pysoem": "ecattool.startup.formats.pysoem",
    "ros2": "ecattool.startup.formats.ros2",
    "ecmc": "ecattool.startup.formats.ecmc",
    "json": "ecattool.startup.formats.jsonfmt",
    "csv": "ecattool.startup.formats.csvfmt",
    "lcec": "ecattool.startup.formats.lcec",
}


@dataclass(frozen=True, slots=True)
class Format:
    name: str
    module_name: str

    @property
    def module(self) -> ModuleType:
        return importlib.import_module(self.module_name)

    @property
    def description(self) -> str:
        return str(self.module.DESCRIPTION)

    @property
    def extensions(self) -> tuple[str, ...]:
        return tuple(self.module.EXTENSIONS)

    @property
    def can_export(self) -> bool:
        return hasattr(self.module, "export")

    @property
    def can_import(self) -> bool:
        return hasattr(self.module, "load")


FORMATS: dict[str, Format] = {name: Format(name, mod) for name, mod in _MODULES.items()}
