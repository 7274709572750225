"""The embedded drive simulator (an independent witness: it shares data with ``ecattool.pdo``, never its
decisions).

    from ecattool.sim import Drive
    drive = Drive.from_profile("technosoft-ipos", product=None, revision="F515K")
    drive.request_state(EcState.PREOP)
    drive.sdo_download(0x1C12, 0, b"\\x00")
"""

from ecattool.sim.cia402 import State as Cia402State
from ecattool.sim.cia402 import decode_statusword
from ecattool.sim.drive import BEHAVIOURS, Behaviour, Drive, Emergency, Event, FoeError
from ecattool.sim.faults import Faults

__all__ = ["BEHAVIOURS", "Behaviour", "Cia402State", "Drive", "Emergency", "Event", "Faults", "FoeError",
           "decode_statusword"]
