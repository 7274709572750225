"""Targets: where commands go (the embedded simulator by default; a real master as an optional extra)."""

from typing import Any

from ecattool.target.base import SlaveTarget, Target

__all__ = ["SlaveTarget", "Target", "SimTarget", "open_target"]


def __getattr__(name: str) -> Any:
    # the simulator is imported only when asked for
    if name in ("SimTarget", "open_target"):
        from ecattool.target import sim

        return getattr(sim, name)
    raise AttributeError(name)
