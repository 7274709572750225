"""Targets: where commands go (the embedded simulator by default; a real master as an optional extra)."""

from ecattool.target.base import SlaveTarget, Target

__all__ = ["SlaveTarget", "Target"]
