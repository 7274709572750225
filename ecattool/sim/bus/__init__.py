"""EtherCAT on the wire: the frame codec, the datagram engine over a chain of ESCs, and the transports (an
in-process loop for tests, raw Ethernet on a Linux interface)."""

from ecattool.sim.bus.engine import Bus
from ecattool.sim.bus.frame import Cmd, Datagram, Frame, FrameError, make_frame, parse_frame

__all__ = ["Bus", "Cmd", "Datagram", "Frame", "FrameError", "make_frame", "parse_frame"]
