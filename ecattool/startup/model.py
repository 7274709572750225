"""The startup-list model: the ordered SDO downloads a master sends on state transitions.

PDO programming (``pdo``), scaling (``scaling``), ``.sw`` download plans (``sw``) and project parameters
(``project``) all produce :class:`StartupCommand` lists; exporters turn them into ENI, TwinCAT, IgH, pysoem,
ros2, ecmc, JSON and CSV; the commissioning run sends them to a target.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

from ecattool.errors import Location

#: EtherCAT transitions in which a startup command may be sent (ETG.2100 names).
TRANSITIONS = ("IP", "PS", "SP", "SO", "OS", "OP", "PI", "SI", "OI", "IB", "BI", "II", "PP", "SS")


#: the kinds of write (:attr:`StartupCommand.kind`), in the words the formats use for them
KINDS = ("startup", "once", "reset")


def set_kind(cmd: "StartupCommand", kind: str) -> None:
    """Make ``cmd`` a write of ``kind`` (one of :data:`KINDS`)."""
    cmd.once = kind in ("once", "reset")
    cmd.expect_reply = kind != "reset"


def is_pdo_programming(index: int) -> bool:
    """Whether a write to ``index`` programs process data: 1C12h/1C13h or a mapping object 1600h-17FFh/1A00h-1BFFh.

    Masters that are given PDO tables (IgH ``ecrt_slave_config_pdos``, ethercat_driver_ros2 ``rpdo``/``tpdo``)
    write these objects themselves; exporters for them leave such startup commands out.
    """
    return index in (0x1C12, 0x1C13) or 0x1600 <= index <= 0x17FF or 0x1A00 <= index <= 0x1BFF


@dataclass(slots=True)
class StartupCommand:
    transition: str  # "PS" (PRE-OP → SAFE-OP) is the usual one
    index: int
    subindex: int
    data: bytes  # little-endian, exactly the object's size
    comment: str = ""
    complete_access: bool = False
    timeout_ms: int = 0  # 0 = the master's default
    type_name: str | None = None  # data type of the value, e.g. "UDINT"
    value: Any = None  # the value in engineering form, for people (e.g. 0x60400010, "FOESW_x", 2.5)
    expect_reply: bool = True  # False for writes a drive answers by resetting (Technosoft 2080h)
    verify: bool = True  # False where a read-back cannot return what was written (2065h data streams)
    source: Location | None = None
    once: bool = False  # True: written once, when the tool runs (ecmc EcWriteSdo), never at a transition

    @property
    def kind(self) -> str:
        """When the write happens: ``"startup"`` (at :attr:`transition`, every time the master configures the
        slave), ``"once"`` (once, when the tool or script runs, answered like any write) or ``"reset"`` (once,
        and the drive answers it by resetting: no reply). See :data:`KINDS`."""
        if not self.expect_reply:
            return "reset"
        return "once" if self.once else "startup"

    @property
    def address(self) -> str:
        return f"0x{self.index:04X}:{self.subindex:02X}"

    @property
    def one_shot(self) -> bool:
        """A write to send once, never as part of a startup list (kind ``once`` or ``reset``): masters re-send
        startup lists at every reconfiguration, so an EEPROM write would be repeated each time and a reset would
        reset the drive each time and abort the configuration that follows it."""
        return self.once or not self.expect_reply

    @property
    def int_value(self) -> int:
        """The data as an unsigned little-endian integer (what TwinCAT prints as the value)."""
        return int.from_bytes(self.data, "little") if self.data else 0


@dataclass(slots=True)
class StartupList:
    """Ordered startup commands for one slave."""

    commands: list[StartupCommand] = field(default_factory=list)
    name: str = ""
    vendor_id: int | None = None
    product_code: int | None = None
    revision: int | None = None

    def __iter__(self) -> Iterator[StartupCommand]:
        return iter(self.commands)

    def __len__(self) -> int:
        return len(self.commands)

    def extend(self, commands: "list[StartupCommand] | StartupList") -> None:
        self.commands.extend(commands)
