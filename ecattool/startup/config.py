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

from ecattool.errors import Location, SelectionError
from ecattool.esi.model import Device, Direction, Identity, Pdo, SyncManager
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
    dc_sync1_cycle_ns: int | None = None  # SYNC1 cycle (ETG: added to the SYNC0 cycle, IgH/ecmc "sync1_cycle")
    dc_sync1_shift_ns: int | None = None  # SYNC1 shift (IgH/ecmc; ENI and TwinCAT have none)
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
    def from_device(cls, device: Device, startup: StartupList | None = None, *, mapping: Any = None,
                    position: int | None = None, name: str | None = None, dc_opmode: str | None = None,
                    dc_cycle_ns: int | None = None, dc_shift_ns: int | None = None) -> "SlaveConfig":
        """A slave configuration for ``device``: its identity and sync managers, the assigned PDOs of
        ``mapping`` (an :class:`ecattool.pdo.Mapping`) or else the device's default assignment (PDOs with an
        ``Sm``), and DC from the named ESI ``OpMode`` (its SYNC0 cycle unless ``dc_cycle_ns`` is given)."""
        def copy(p: Any, direction: Direction) -> Pdo:
            return Pdo(direction, p.index, p.name, list(p.entries), sm=2 if direction is Direction.RX else 3)

        if mapping is not None:
            rx = [copy(p, Direction.RX) for p in mapping.rx]
            tx = [copy(p, Direction.TX) for p in mapping.tx]
        else:
            rx = [p for p in device.rx_pdos if p.sm is not None]
            tx = [p for p in device.tx_pdos if p.sm is not None]
        sl = startup if startup is not None else StartupList()
        cfg = cls(startup=sl, name=name or sl.name or device.name or device.type_name, position=position,
                  identity=device.identity, rx_pdos=rx, tx_pdos=tx, sync_managers=list(device.sync_managers),
                  dc_cycle_ns=dc_cycle_ns, dc_shift_ns=dc_shift_ns)
        if dc_opmode is not None:
            mode = next((m for m in device.dc_opmodes if m.name.lower() == dc_opmode.lower()), None)
            if mode is None:
                names = ", ".join(m.name for m in device.dc_opmodes) or "none"
                raise SelectionError(f"device {device.type_name} has no DC OpMode {dc_opmode!r} (has: {names})",
                                     device.location)
            cfg.dc_assign_activate = mode.assign_activate
            if cfg.dc_cycle_ns is None and mode.cycle_time_sync0:
                cfg.dc_cycle_ns = mode.cycle_time_sync0
            if cfg.dc_shift_ns is None and mode.shift_time_sync0 is not None:
                cfg.dc_shift_ns = mode.shift_time_sync0
        if sl.vendor_id is None:
            sl.vendor_id, sl.product_code, sl.revision = device.vendor_id, device.product_code, device.revision
        return cfg

    @classmethod
    def from_list(cls, startup: StartupList) -> "SlaveConfig":
        ident = None
        if startup.vendor_id is not None and startup.product_code is not None:
            ident = Identity(startup.vendor_id, startup.product_code, startup.revision or 0)
        return cls(startup=startup, name=startup.name, identity=ident)
