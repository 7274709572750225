"""Startup lists: the model, and exporters/importers for the masters people use.

>>> from ecattool.startup import StartupCommand, StartupList, export
>>> sl = StartupList([StartupCommand("PS", 0x1C12, 0, b"\\x00", comment="clear sm pdos")])
>>> print(export(sl, "twincat"), end="")
<PS>,CoE,0x1C12:00,0x00 (0),clear sm pdos
"""

from ecattool.startup.api import (
    as_configs,
    describe_slaves,
    detect_format,
    export,
    import_bytes,
    import_file,
    losses,
    select_one,
    select_slaves,
)
from ecattool.startup.config import SlaveConfig, SoeCommand
from ecattool.startup.formats import FORMATS, Format
from ecattool.startup.model import KINDS, TRANSITIONS, StartupCommand, StartupList

__all__ = ["FORMATS", "Format", "KINDS", "SlaveConfig", "SoeCommand", "StartupCommand", "StartupList", "TRANSITIONS",
           "as_configs", "describe_slaves", "detect_format", "export", "import_bytes", "import_file", "losses",
           "select_one", "select_slaves"]
