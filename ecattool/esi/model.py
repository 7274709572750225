"""The device model: what ESI files describe, and what built-in drive profiles produce too.

Everything downstream (PDO checks, the simulator, SII building, startup lists) works on :class:`Device`,
whether it came from a vendor ESI (``ecattool.esi.load``) or from a built-in family (``ecattool.profiles``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum

from typing import TYPE_CHECKING

from ecattool.errors import Location
from ecattool.od.model import ObjectDictionary

if TYPE_CHECKING:
    from ecattool.findings import Finding


@dataclass(frozen=True, slots=True)
class Identity:
    vendor_id: int
    product_code: int
    revision: int = 0
    serial: int = 0

    def __str__(self) -> str:
        return f"vendor 0x{self.vendor_id:08X} product 0x{self.product_code:08X} revision 0x{self.revision:08X}"


class Direction(str, Enum):
    """RX = outputs (master → slave, RxPDO, SM2); TX = inputs (slave → master, TxPDO, SM3)."""

    RX = "rx"
    TX = "tx"

    @property
    def assign_index(self) -> int:
        return 0x1C12 if self is Direction.RX else 0x1C13

    @property
    def sm_kind(self) -> str:
        return "Outputs" if self is Direction.RX else "Inputs"


@dataclass(slots=True)
class SyncManager:
    number: int
    kind: str  # "MBoxOut", "MBoxIn", "Outputs", "Inputs" or "" (unused)
    start_address: int = 0
    default_size: int | None = None
    min_size: int | None = None
    max_size: int | None = None
    control_byte: int = 0
    enable: bool = True
    virtual: bool = False
    location: Location | None = None
    #: ``Sm@OpOnly``: the SyncManager is enabled only in OP (SII SyncM enable byte bit 3)
    op_only: bool = False

    @property
    def direction(self) -> Direction | None:
        return {"Outputs": Direction.RX, "Inputs": Direction.TX}.get(self.kind)


@dataclass(slots=True)
class Fmmu:
    kind: str  # "Outputs", "Inputs", "MBoxState", "" (unused)
    sm: int | None = None
    su: int | None = None


@dataclass(slots=True)
class PdoEntry:
    index: int
    subindex: int
    bit_len: int
    name: str = ""
    data_type: str = ""  # type name as written in the source ("UINT", "DT0800", "BOOL" …)
    location: Location | None = None
    depend_on_slot: bool = False  # module PDO entry whose index moves with the slot (SlotIndexIncrement)

    @property
    def is_gap(self) -> bool:
        return self.index == 0

    @property
    def mapping_value(self) -> int:
        """The 32-bit value written into a mapping object sub-index: index<<16 | sub<<8 | bits."""
        return (self.index << 16) | (self.subindex << 8) | (self.bit_len & 0xFF)

    @classmethod
    def from_mapping_value(cls, value: int) -> "PdoEntry":
        return cls((value >> 16) & 0xFFFF, (value >> 8) & 0xFF, value & 0xFF)


@dataclass(slots=True)
class Pdo:
    direction: Direction
    index: int
    name: str = ""
    entries: list[PdoEntry] = field(default_factory=list)
    sm: int | None = None  # default sync manager (ESI @Sm); None = not assigned by default
    fixed: bool = False
    mandatory: bool = False
    virtual: bool = False
    excludes: list[int] = field(default_factory=list)
    su: int | None = None
    pdo_order: int | None = None
    os_fac: int | None = None
    os_min: int | None = None
    os_max: int | None = None
    os_index_inc: int | None = None
    depend_on_slot: bool = False
    overwritten_by_module: bool = False
    location: Location | None = None

    @property
    def bit_size(self) -> int:
        return sum(e.bit_len for e in self.entries)


@dataclass(slots=True)
class InitCmd:
    """A mailbox init command from the ESI (CoE: SDO download; SoE: IDN write)."""

    protocol: str  # "CoE" or "SoE"
    transitions: list[str]
    index: int
    subindex: int
    data: bytes
    comment: str = ""
    fixed: bool = False
    complete_access: bool = False
    overwritten_by_module: bool = False
    location: Location | None = None
    depend_on_slot: bool = False  # index moves with the slot (module InitCmds)


@dataclass(slots=True)
class CoeDetails:
    sdo_info: bool = False
    pdo_assign: bool = False
    pdo_config: bool = False
    pdo_upload: bool = False
    complete_access: bool = False
    segmented_sdo: bool = False
    eds_file: str = ""


@dataclass(slots=True)
class Mailbox:
    protocols: list[str] = field(default_factory=list)  # "AoE", "EoE", "CoE", "FoE", "SoE", "VoE"
    coe: CoeDetails | None = None
    data_link_layer: bool = False
    init_cmds: list[InitCmd] = field(default_factory=list)


@dataclass(slots=True)
class DcOpMode:
    name: str
    desc: str = ""
    assign_activate: int = 0
    cycle_time_sync0: int | None = None
    cycle_time_sync0_factor: int | None = None
    shift_time_sync0: int | None = None
    shift_time_sync0_factor: int | None = None
    cycle_time_sync1: int | None = None
    cycle_time_sync1_factor: int | None = None
    shift_time_sync1: int | None = None
    shift_time_sync1_factor: int | None = None


@dataclass(slots=True)
class EepromCategory:
    cat_no: int
    data: bytes


@dataclass(slots=True)
class Eeprom:
    byte_size: int | None = None
    config_data: bytes | None = None
    bootstrap: bytes | None = None
    categories: list[EepromCategory] = field(default_factory=list)
    data: bytes | None = None  # a complete raw image (Eeprom/Data)
    assign_to_pdi: bool = False


@dataclass(slots=True)
class Module:
    type_name: str
    name: str = ""
    ident: int | None = None  # ModuleIdent
    module_class: str = ""
    rx_pdos: list[Pdo] = field(default_factory=list)
    tx_pdos: list[Pdo] = field(default_factory=list)
    dictionary: ObjectDictionary = field(default_factory=ObjectDictionary)
    init_cmds: list[InitCmd] = field(default_factory=list)
    location: Location | None = None


@dataclass(slots=True)
class Slot:
    name: str
    min_instances: int = 0
    max_instances: int = 1
    slot_index_increment: int | None = None
    slot_pdo_increment: int | None = None
    module_idents: list[int] = field(default_factory=list)
    module_classes: list[str] = field(default_factory=list)
    default_module: int | None = None


@dataclass(slots=True)
class AlternativeSmMapping:
    """A vendor-specific alternative PDO assignment (``VendorSpecific/TwinCAT/AlternativeSmMapping``)."""

    name: str
    default: bool = False
    sms: dict[int, list[int]] = field(default_factory=dict)  # SM number -> PDO indices


class IdentityView:
    """``vendor_id``/``product_code``/``revision`` of an object with an ``identity`` (devices and device heads)."""

    __slots__ = ()
    identity: Identity

    @property
    def vendor_id(self) -> int:
        return self.identity.vendor_id

    @property
    def product_code(self) -> int:
        return self.identity.product_code

    @property
    def revision(self) -> int:
        return self.identity.revision


@dataclass(slots=True)
class Device(IdentityView):
    identity: Identity
    type_name: str
    name: str = ""
    group_type: str = ""
    group_name: str = ""
    physics: str = ""
    image: str = ""
    url: str = ""
    profile_no: int | None = None
    sync_managers: list[SyncManager] = field(default_factory=list)
    fmmus: list[Fmmu] = field(default_factory=list)
    rx_pdos: list[Pdo] = field(default_factory=list)
    tx_pdos: list[Pdo] = field(default_factory=list)
    dictionary: ObjectDictionary = field(default_factory=ObjectDictionary)
    mailbox: Mailbox | None = None
    dc_opmodes: list[DcOpMode] = field(default_factory=list)
    eeprom: Eeprom | None = None
    slots: list[Slot] = field(default_factory=list)
    modules: list[Module] = field(default_factory=list)  # modules usable in this device's slots
    ebus_current_ma: int | None = None
    source: str = ""  # file the device came from, or "profile:<name>"
    location: Location | None = None
    #: free-form facts the reader could keep but the model has no field for (never silently dropped)
    extra: dict[str, str] = field(default_factory=dict)
    alternative_sm_mappings: list[AlternativeSmMapping] = field(default_factory=list)

    def pdos(self, direction: Direction) -> list[Pdo]:
        return self.rx_pdos if direction is Direction.RX else self.tx_pdos

    def pdo(self, index: int) -> Pdo | None:
        for p in (*self.rx_pdos, *self.tx_pdos):
            if p.index == index:
                return p
        return None

    def sm(self, number: int) -> SyncManager | None:
        for s in self.sync_managers:
            if s.number == number:
                return s
        return None

    def process_sm(self, direction: Direction) -> SyncManager | None:
        """The sync manager that carries process data in ``direction`` (SM2 outputs / SM3 inputs usually)."""
        for s in self.sync_managers:
            if s.kind == direction.sm_kind:
                return s
        return None

    @property
    def has_coe(self) -> bool:
        return self.mailbox is not None and "CoE" in self.mailbox.protocols


@dataclass(slots=True)
class EsiFile:
    """One ESI document: vendor, groups, devices, and file-level modules."""

    source: str
    root: str  # "EtherCATInfo" or "EtherCATModule"
    vendor_id: int | None = None
    vendor_name: str = ""
    groups: dict[str, str] = field(default_factory=dict)  # GroupType -> name
    devices: list[Device] = field(default_factory=list)
    modules: list[Module] = field(default_factory=list)
    info_references: list[str] = field(default_factory=list)
    version: str = ""
    #: reader warnings (tolerated deviations such as ``0x`` numbers or unresolvable data types)
    warnings: list["Finding"] = field(default_factory=list)
    #: the dictionary of an ``EtherCATDict`` root (external dictionary files); None otherwise
    dictionary: ObjectDictionary | None = None
