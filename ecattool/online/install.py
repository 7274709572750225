"""The former home of installing a project's startup list in a master program: now ``Machine.install(master)``
(``ecattool.project.machine``) over :mod:`ecattool.startup.install`, which sits below the project layer. These
two functions keep the old calls working: ``project`` is a project file (linted; errors refuse it) or the list of
``SlaveConfig`` it gives."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from types import ModuleType
from typing import Any

from ecattool.startup import install as _install
from ecattool.startup.config import SlaveConfig
from ecattool.startup.install import check_identity

__all__ = ["check_identity", "install_kickcat", "install_pysoem"]


def _configs(project: str | Path | Sequence[SlaveConfig]) -> list[SlaveConfig]:
    if isinstance(project, (str, Path)):
        from ecattool.project.machine import load_machine

        return load_machine(project).configs()
    return list(project)


def install_pysoem(project: str | Path | Sequence[SlaveConfig], master: Any, *, exact_revision: bool = False,
                   pysoem_module: ModuleType | None = None) -> list[int]:
    """:func:`ecattool.startup.install.install_pysoem` of the project's slave configurations."""
    return _install.install_pysoem(_configs(project), master, exact_revision=exact_revision,
                                   pysoem_module=pysoem_module)


def install_kickcat(project: str | Path | Sequence[SlaveConfig], bus: Any, *, exact_revision: bool = False,
                    kickcat_module: ModuleType | None = None) -> list[int]:
    """:func:`ecattool.startup.install.install_kickcat` of the project's slave configurations."""
    return _install.install_kickcat(_configs(project), bus, exact_revision=exact_revision,
                                    kickcat_module=kickcat_module)
