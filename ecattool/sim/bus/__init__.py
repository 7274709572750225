"""EtherCAT on the wire: the frame codec, the datagram engine over a chain of ESCs, and the transports (an
in-process loop for tests, raw Ethernet on a Linux interface)."""

from typing import Any

__all__ = ["Bus", "Cmd", "Datagram", "Frame", "FrameError", "make_frame", "parse_frame"]


def __getattr__(name: str) -> Any:
    # imported on first use: the frame codec alone (ecattool.sim.bus.frame) stays light
    if name == "Bus":
        from ecattool.sim.bus.engine import Bus

        return Bus
    if name in __all__:
        from ecattool.sim.bus import frame

        return getattr(frame, name)
    raise AttributeError(name)
