"""The EtherCAT slave controller (ESC) model: registers, sync managers, FMMUs, SII EEPROM interface, DC.

    from ecattool.sim.esc import Esc
    esc = Esc(sii_image_bytes)
"""

from ecattool.sim.esc.core import Esc, EscApplication
from ecattool.sim.esc.dc import Clock
from ecattool.sim.esc.eeprom import SiiEeprom

__all__ = ["Clock", "Esc", "EscApplication", "SiiEeprom"]
