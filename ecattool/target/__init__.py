"""Targets: where commands go (the embedded simulator by default; a real master as an optional extra)."""

from typing import Any

from ecattool.target.base import AlStatusReport, LiveSlave, SdoInformation, SiiAccess, SlaveTarget, Target, Unsupported

__all__ = ["AlStatusReport", "LiveSlave", "SdoInformation", "SiiAccess", "SlaveTarget", "Target", "Unsupported",
           "SimTarget", "open_target", "slave_at"]


def __getattr__(name: str) -> Any:
    # the simulator is imported only when asked for
    if name == "SimTarget":
        from ecattool.target import sim

        return getattr(sim, name)
    if name in ("open_target", "slave_at"):  # the one opener of target specs (ecattool.target.opener)
        from ecattool.target import opener

        return getattr(opener, name)
    raise AttributeError(name)
