"""The embedded drive simulator (an independent witness: it shares data with ``ecattool.pdo``, never its
decisions).

    from ecattool.sim import Drive
    drive = Drive.from_profile("technosoft-ipos", product=None, revision="F515K")
    drive.request_state(EcState.PREOP)
    drive.sdo_download(0x1C12, 0, b"\\x00")
"""

from typing import Any

__all__ = ["BEHAVIOURS", "Behaviour", "Cia402State", "Drive", "Emergency", "Event", "Faults", "FoeError",
           "decode_statusword"]

#: name -> (module, attribute): imported on first use, so that ``ecattool.sim.bus.frame`` (the frame codec the
#: live-bus commands use to read the AL states before a master opens the bus) does not import the whole drive
_LAZY = {"Cia402State": ("ecattool.sim.cia402", "State"), "decode_statusword": ("ecattool.sim.cia402", None),
         "BEHAVIOURS": ("ecattool.sim.drive", None), "Behaviour": ("ecattool.sim.drive", None),
         "Drive": ("ecattool.sim.drive", None), "Emergency": ("ecattool.sim.drive", None),
         "Event": ("ecattool.sim.drive", None), "FoeError": ("ecattool.sim.drive", None),
         "Faults": ("ecattool.sim.faults", None)}


def __getattr__(name: str) -> Any:
    if name not in _LAZY:
        raise AttributeError(name)
    import importlib

    module, attr = _LAZY[name]
    return getattr(importlib.import_module(module), attr or name)
