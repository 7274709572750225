"""One slave as the exporters and importers see it: identity, startup list, assigned PDOs, DC settings.

:class:`SlaveConfig` is what every importer returns and every exporter consumes. The PDO lists are the
*assigned* PDOs per direction (what IgH's ``ec_sync_info_t`` tables, ENI ``ProcessData`` and ros2's
``rpdo``/``tpdo`` describe); the startup list holds the SDO downloads (PDO programming included, when the
source had it). Things a format carries that the model has no field for are kept, never dropped:
SoE init commands in :attr:`SlaveConfig.soe_commands`, per-channel ros2 attributes in
:attr:`SlaveConfig.channel_info`, other top-level keys in :attr:`SlaveConfig.extra`, and anything skipped in
:attr:`SlaveConfig.notes` as findings.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from ecattool.errors import Location
from ecattool.esi.model import Direction, Identity, Pdo, SyncManager
from ecattool.findings import Finding, Severity
from ecattool.startup.model import StartupCommand, StartupList


@dataclass(slots=True)
class SoeCommand:
    """A SoE (servo profile over EtherCAT) init command: an IDN write, as TwinCAT exports them."""

    transition: str
    idn: int
    data: bytes
    drive_no: int = 0
    op_code: int = 3  # 3 = write
    elements: int = 64  # 0x40 = operation data
    attribute: int = 0
    comment: str = ""
    timeout_ms: int = 0
    fixed: bool = False
    source: Location | None = None

    @property
    def address(self) -> str:
        kind = "P" if self.idn & 0x8000 else "S"
        return f"{kind}-{(self.idn >> 12) & 7}-{self.idn & 0x0FFF:04d} (drive {self.drive_no})"


@dataclass(slots=True)
class SlaveConfig:
    """One slave: who it is, where it sits, what is sent to it at start-up, and its process data."""

    startup: StartupList = field(default_factory=StartupList)
    name: str = ""
    position: int | None = None  # bus position (auto-increment order), 0-based
    identity: Identity | None = None
    rx_pdos: list[Pdo] = field(default_factory=list)  # assigned outputs (SM2, 0x1C12)
    tx_pdos: list[Pdo] = field(default_factory=list)  # assigned inputs (SM3, 0x1C13)
    sync_managers: list[SyncManager] = field(default_factory=list)
    dc_assign_activate: int | None = None  # e.g. 0x0300 = SYNC0
    dc_cycle_ns: int | None = None  # SYNC0 cycle
    dc_shift_ns: int | None = None  # SYNC0 shift
    soe_commands: list[SoeCommand] = field(default_factory=list)
    #: per PDO entry attributes of the source format (ros2 command/state interfaces, defaults, factors),
    #: keyed by (PDO index, entry position within the PDO)
    channel_info: dict[tuple[int, int], dict[str, Any]] = field(default_factory=dict)
    extra: dict[str, Any] = field(default_factory=dict)
    notes: list[Finding] = field(default_factory=list)
    source: Location | None = None

    @property
    def commands(self) -> list[StartupCommand]:
        return self.startup.commands

    def pdos(self, direction: Direction) -> list[Pdo]:
        return self.rx_pdos if direction is Direction.RX else self.tx_pdos

    @property
    def has_pdo_info(self) -> bool:
        return bool(self.rx_pdos or self.tx_pdos)

    @property
    def label(self) -> str:
        """A short human name: the name, else ``slave <position>``."""
        if self.name:
            return self.name
        return f"slave {self.position}" if self.position is not None else "slave"

    def note(self, rule: str, message: str, location: Location | None = None,
             severity: Severity = Severity.WARNING) -> None:
        self.notes.append(Finding(rule, severity, message, location or self.source))

    @classmethod
    def from_list(cls, startup: StartupList) -> "SlaveConfig":
        ident = None
        if startup.vendor_id is not None and startup.product_code is not None:
            ident = Identity(startup.vendor_id, startup.product_code, startup.revision or 0)
        return cls(startup=startup, name=startup.name, identity=ident)
