"""The device model: what ESI files describe, and what built-in drive profiles produce too.

Everything downstream (PDO checks, the simulator, SII building, startup lists) works on :class:`Device`,
whether it came from a vendor ESI (``ecattool.esi.load``) or from a built-in family (``ecattool.profiles``).
"""

from __future__ import annotations

from enum import Enum
from typing import TYPE_CHECKING

from ecattool.errors import Location
from ecattool.od.model import ObjectDictionary
from ecattool.record import FrozenRecord, Record, set_field

if TYPE_CHECKING:
    from ecattool.findings import Finding


class Identity(FrozenRecord):
    __slots__ = ("vendor_id", "product_code", "revision", "serial")
    vendor_id: int
    product_code: int
    revision: int
    serial: int

    def __init__(self, vendor_id: int, product_code: int, revision: int = 0, serial: int = 0) -> None:
        set_field(self, "vendor_id", vendor_id)
        set_field(self, "product_code", product_code)
        set_field(self, "revision", revision)
        set_field(self, "serial", serial)

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


def with_article(word: str) -> str:
    """``word`` after ``a`` or ``an`` as it is spoken: an Inputs, an Outputs, an MBoxIn, an RxPDO, a TxPDO."""
    spoken_vowel = word[:1].lower() in "aeiou" or word.startswith(("MBox", "Rx", "SM"))
    return f"{'an' if spoken_vowel else 'a'} {word}"


class SyncManager(Record):
    __slots__ = ("number", "kind", "start_address", "default_size", "min_size", "max_size", "control_byte",
                 "enable", "virtual", "location", "op_only", "enable_byte")
    number: int
    kind: str  # "MBoxOut", "MBoxIn", "Outputs", "Inputs" or "" (unused)
    start_address: int
    default_size: int | None
    min_size: int | None
    max_size: int | None
    control_byte: int
    enable: bool
    virtual: bool
    location: Location | None
    #: ``Sm@OpOnly``: the SyncManager is enabled only in OP (SII SyncM enable byte bit 3)
    op_only: bool
    #: ``Sm@Enable`` as the file gives it (HexDecValue: the SII SyncM enable byte, e.g. 9 = enable | OP only);
    #: None when the attribute is absent. :attr:`enable` is its bit 0.
    enable_byte: int | None

    def __init__(self, number: int, kind: str, start_address: int = 0, default_size: int | None = None,
                 min_size: int | None = None, max_size: int | None = None, control_byte: int = 0,
                 enable: bool = True, virtual: bool = False, location: Location | None = None,
                 op_only: bool = False, enable_byte: int | None = None) -> None:
        self.number = number
        self.kind = kind
        self.start_address = start_address
        self.default_size = default_size
        self.min_size = min_size
        self.max_size = max_size
        self.control_byte = control_byte
        self.enable = enable
        self.virtual = virtual
        self.location = location
        self.op_only = op_only
        self.enable_byte = enable_byte

    @property
    def direction(self) -> Direction | None:
        return {"Outputs": Direction.RX, "Inputs": Direction.TX}.get(self.kind)


class Fmmu(Record):
    __slots__ = ("kind", "sm", "su")
    kind: str  # "Outputs", "Inputs", "MBoxState", "" (unused)
    sm: int | None
    su: int | None

    def __init__(self, kind: str, sm: int | None = None, su: int | None = None) -> None:
        self.kind = kind
        self.sm = sm
        self.su = su


class _LineLocated(Record):
    """A record whose ``location`` the ESI reader may give as a source and a line, made a :class:`Location` when
    first read.

    A large ESI file has thousands of PDOs and PDO entries and their locations are rarely read; one Location
    object each made ~20% of the objects the complete model of the largest corpus file holds, and every garbage
    collector pass over the model (one at interpreter exit at least) visits each of them. The field behaves as a
    plain ``location`` field otherwise: constructor argument, assignment, ``==``, ``repr`` and pickling.
    """

    __slots__ = ("_location", "_source")
    _location: Location | int | None  # an int: a line of _source, not yet made a Location
    _source: str

    @property
    def location(self) -> Location | None:
        loc = self._location
        if isinstance(loc, int):
            loc = self._location = Location(self._source, loc)
        return loc

    @location.setter
    def location(self, value: Location | None) -> None:
        self._location = value

    def at_line(self, source: str, line: int | None) -> None:
        """Set ``location`` to ``Location(source, line)``, made when first read."""
        if line is None:
            self._location = Location(source)
        else:
            self._location = line
            self._source = source


class PdoEntry(_LineLocated):
    __slots__ = ("index", "subindex", "bit_len", "name", "data_type", "depend_on_slot")
    _fields = ("index", "subindex", "bit_len", "name", "data_type", "location", "depend_on_slot")
    index: int
    subindex: int
    bit_len: int
    name: str
    data_type: str  # type name as written in the source ("UINT", "DT0800", "BOOL" …)
    depend_on_slot: bool  # module PDO entry whose index moves with the slot (SlotIndexIncrement)

    def __init__(self, index: int, subindex: int, bit_len: int, name: str = "", data_type: str = "",
                 location: Location | None = None, depend_on_slot: bool = False) -> None:
        self.index = index
        self.subindex = subindex
        self.bit_len = bit_len
        self.name = name
        self.data_type = data_type
        self._location = location
        self.depend_on_slot = depend_on_slot

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


class Pdo(_LineLocated):
    __slots__ = ("direction", "index", "name", "entries", "sm", "fixed", "mandatory", "virtual", "excludes",
                 "su", "pdo_order", "os_fac", "os_min", "os_max", "os_index_inc", "depend_on_slot",
                 "overwritten_by_module")
    _fields = ("direction", "index", "name", "entries", "sm", "fixed", "mandatory", "virtual", "excludes",
               "su", "pdo_order", "os_fac", "os_min", "os_max", "os_index_inc", "depend_on_slot",
               "overwritten_by_module", "location")
    direction: Direction
    index: int
    name: str
    entries: list[PdoEntry]
    sm: int | None  # default sync manager (ESI @Sm); None = not assigned by default
    fixed: bool
    mandatory: bool
    virtual: bool
    excludes: list[int]
    su: int | None
    pdo_order: int | None
    os_fac: int | None
    os_min: int | None
    os_max: int | None
    os_index_inc: int | None
    depend_on_slot: bool
    overwritten_by_module: bool

    def __init__(self, direction: Direction, index: int, name: str = "",
                 entries: list[PdoEntry] | None = None, sm: int | None = None, fixed: bool = False,
                 mandatory: bool = False, virtual: bool = False, excludes: list[int] | None = None,
                 su: int | None = None, pdo_order: int | None = None, os_fac: int | None = None,
                 os_min: int | None = None, os_max: int | None = None, os_index_inc: int | None = None,
                 depend_on_slot: bool = False, overwritten_by_module: bool = False,
                 location: Location | None = None) -> None:
        self.direction = direction
        self.index = index
        self.name = name
        self.entries = [] if entries is None else entries
        self.sm = sm
        self.fixed = fixed
        self.mandatory = mandatory
        self.virtual = virtual
        self.excludes = [] if excludes is None else excludes
        self.su = su
        self.pdo_order = pdo_order
        self.os_fac = os_fac
        self.os_min = os_min
        self.os_max = os_max
        self.os_index_inc = os_index_inc
        self.depend_on_slot = depend_on_slot
        self.overwritten_by_module = overwritten_by_module
        self._location = location

    @property
    def bit_size(self) -> int:
        return sum(e.bit_len for e in self.entries)


class InitCmd(Record):
    """A mailbox init command from the ESI (CoE: SDO download; SoE: IDN write)."""

    __slots__ = ("protocol", "transitions", "index", "subindex", "data", "comment", "fixed",
                 "complete_access", "overwritten_by_module", "location", "depend_on_slot")
    protocol: str  # "CoE" or "SoE"
    transitions: list[str]
    index: int
    subindex: int
    data: bytes
    comment: str
    fixed: bool
    complete_access: bool
    overwritten_by_module: bool
    location: Location | None
    depend_on_slot: bool  # index moves with the slot (module InitCmds)

    def __init__(self, protocol: str, transitions: list[str], index: int, subindex: int, data: bytes,
                 comment: str = "", fixed: bool = False, complete_access: bool = False,
                 overwritten_by_module: bool = False, location: Location | None = None,
                 depend_on_slot: bool = False) -> None:
        self.protocol = protocol
        self.transitions = transitions
        self.index = index
        self.subindex = subindex
        self.data = data
        self.comment = comment
        self.fixed = fixed
        self.complete_access = complete_access
        self.overwritten_by_module = overwritten_by_module
        self.location = location
        self.depend_on_slot = depend_on_slot


class CoeDetails(Record):
    __slots__ = ("sdo_info", "pdo_assign", "pdo_config", "pdo_upload", "complete_access", "segmented_sdo",
                 "eds_file")
    sdo_info: bool
    pdo_assign: bool
    pdo_config: bool
    pdo_upload: bool
    complete_access: bool
    segmented_sdo: bool
    eds_file: str

    def __init__(self, sdo_info: bool = False, pdo_assign: bool = False, pdo_config: bool = False,
                 pdo_upload: bool = False, complete_access: bool = False, segmented_sdo: bool = False,
                 eds_file: str = "") -> None:
        self.sdo_info = sdo_info
        self.pdo_assign = pdo_assign
        self.pdo_config = pdo_config
        self.pdo_upload = pdo_upload
        self.complete_access = complete_access
        self.segmented_sdo = segmented_sdo
        self.eds_file = eds_file


class Mailbox(Record):
    __slots__ = ("protocols", "coe", "data_link_layer", "init_cmds")
    protocols: list[str]  # "AoE", "EoE", "CoE", "FoE", "SoE", "VoE"
    coe: CoeDetails | None
    data_link_layer: bool
    init_cmds: list[InitCmd]

    def __init__(self, protocols: list[str] | None = None, coe: CoeDetails | None = None,
                 data_link_layer: bool = False, init_cmds: list[InitCmd] | None = None) -> None:
        self.protocols = [] if protocols is None else protocols
        self.coe = coe
        self.data_link_layer = data_link_layer
        self.init_cmds = [] if init_cmds is None else init_cmds


class DcOpMode(Record):
    __slots__ = ("name", "desc", "assign_activate", "cycle_time_sync0", "cycle_time_sync0_factor",
                 "shift_time_sync0", "shift_time_sync0_factor", "cycle_time_sync1", "cycle_time_sync1_factor",
                 "shift_time_sync1", "shift_time_sync1_factor")
    name: str
    desc: str
    assign_activate: int
    cycle_time_sync0: int | None
    cycle_time_sync0_factor: int | None
    shift_time_sync0: int | None
    shift_time_sync0_factor: int | None
    cycle_time_sync1: int | None
    cycle_time_sync1_factor: int | None
    shift_time_sync1: int | None
    shift_time_sync1_factor: int | None

    def __init__(self, name: str, desc: str = "", assign_activate: int = 0,
                 cycle_time_sync0: int | None = None, cycle_time_sync0_factor: int | None = None,
                 shift_time_sync0: int | None = None, shift_time_sync0_factor: int | None = None,
                 cycle_time_sync1: int | None = None, cycle_time_sync1_factor: int | None = None,
                 shift_time_sync1: int | None = None, shift_time_sync1_factor: int | None = None) -> None:
        self.name = name
        self.desc = desc
        self.assign_activate = assign_activate
        self.cycle_time_sync0 = cycle_time_sync0
        self.cycle_time_sync0_factor = cycle_time_sync0_factor
        self.shift_time_sync0 = shift_time_sync0
        self.shift_time_sync0_factor = shift_time_sync0_factor
        self.cycle_time_sync1 = cycle_time_sync1
        self.cycle_time_sync1_factor = cycle_time_sync1_factor
        self.shift_time_sync1 = shift_time_sync1
        self.shift_time_sync1_factor = shift_time_sync1_factor


class EepromCategory(Record):
    __slots__ = ("cat_no", "data")
    cat_no: int
    data: bytes

    def __init__(self, cat_no: int, data: bytes) -> None:
        self.cat_no = cat_no
        self.data = data


class Eeprom(Record):
    __slots__ = ("byte_size", "config_data", "bootstrap", "categories", "data", "assign_to_pdi")
    byte_size: int | None
    config_data: bytes | None
    bootstrap: bytes | None
    categories: list[EepromCategory]
    data: bytes | None  # a complete raw image (Eeprom/Data)
    assign_to_pdi: bool

    def __init__(self, byte_size: int | None = None, config_data: bytes | None = None,
                 bootstrap: bytes | None = None, categories: list[EepromCategory] | None = None,
                 data: bytes | None = None, assign_to_pdi: bool = False) -> None:
        self.byte_size = byte_size
        self.config_data = config_data
        self.bootstrap = bootstrap
        self.categories = [] if categories is None else categories
        self.data = data
        self.assign_to_pdi = assign_to_pdi


class Module(Record):
    __slots__ = ("type_name", "name", "ident", "module_class", "rx_pdos", "tx_pdos", "dictionary",
                 "init_cmds", "location")
    type_name: str
    name: str
    ident: int | None  # ModuleIdent
    module_class: str
    rx_pdos: list[Pdo]
    tx_pdos: list[Pdo]
    dictionary: ObjectDictionary
    init_cmds: list[InitCmd]
    location: Location | None

    def __init__(self, type_name: str, name: str = "", ident: int | None = None, module_class: str = "",
                 rx_pdos: list[Pdo] | None = None, tx_pdos: list[Pdo] | None = None,
                 dictionary: ObjectDictionary | None = None, init_cmds: list[InitCmd] | None = None,
                 location: Location | None = None) -> None:
        self.type_name = type_name
        self.name = name
        self.ident = ident
        self.module_class = module_class
        self.rx_pdos = [] if rx_pdos is None else rx_pdos
        self.tx_pdos = [] if tx_pdos is None else tx_pdos
        self.dictionary = ObjectDictionary() if dictionary is None else dictionary
        self.init_cmds = [] if init_cmds is None else init_cmds
        self.location = location


class Slot(Record):
    __slots__ = ("name", "min_instances", "max_instances", "slot_index_increment", "slot_pdo_increment",
                 "module_idents", "module_classes", "default_module")
    name: str
    min_instances: int
    max_instances: int
    slot_index_increment: int | None
    slot_pdo_increment: int | None
    module_idents: list[int]
    module_classes: list[str]
    default_module: int | None

    def __init__(self, name: str, min_instances: int = 0, max_instances: int = 1,
                 slot_index_increment: int | None = None, slot_pdo_increment: int | None = None,
                 module_idents: list[int] | None = None, module_classes: list[str] | None = None,
                 default_module: int | None = None) -> None:
        self.name = name
        self.min_instances = min_instances
        self.max_instances = max_instances
        self.slot_index_increment = slot_index_increment
        self.slot_pdo_increment = slot_pdo_increment
        self.module_idents = [] if module_idents is None else module_idents
        self.module_classes = [] if module_classes is None else module_classes
        self.default_module = default_module


class AlternativeSmMapping(Record):
    """A vendor-specific alternative PDO assignment (``VendorSpecific/TwinCAT/AlternativeSmMapping``)."""

    __slots__ = ("name", "default", "sms")
    name: str
    default: bool
    sms: dict[int, list[int]]  # SM number -> PDO indices

    def __init__(self, name: str, default: bool = False, sms: dict[int, list[int]] | None = None) -> None:
        self.name = name
        self.default = default
        self.sms = {} if sms is None else sms


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


class Device(IdentityView, Record):
    __slots__ = ("identity", "type_name", "name", "group_type", "group_name", "physics", "image", "url",
                 "profile_no", "sync_managers", "fmmus", "rx_pdos", "tx_pdos", "dictionary", "mailbox",
                 "dc_opmodes", "eeprom", "slots", "modules", "ebus_current_ma", "source", "location", "extra",
                 "alternative_sm_mappings", "end_line")
    identity: Identity
    type_name: str
    name: str
    group_type: str
    group_name: str
    physics: str
    image: str
    url: str
    profile_no: int | None
    sync_managers: list[SyncManager]
    fmmus: list[Fmmu]
    rx_pdos: list[Pdo]
    tx_pdos: list[Pdo]
    dictionary: ObjectDictionary
    mailbox: Mailbox | None
    dc_opmodes: list[DcOpMode]
    eeprom: Eeprom | None
    slots: list[Slot]
    modules: list[Module]  # modules usable in this device's slots
    ebus_current_ma: int | None
    source: str  # file the device came from, or "profile:<name>"
    #: the line where the next element after the device's ``<Device>`` starts (None: the file's end); with
    #: ``location.line``, the lines of the device (``ecattool.esi.device_findings`` attributes warnings by them)
    end_line: int | None
    location: Location | None
    #: free-form facts the reader could keep but the model has no field for (never silently dropped)
    extra: dict[str, str]
    alternative_sm_mappings: list[AlternativeSmMapping]

    def __init__(self, identity: Identity, type_name: str, name: str = "", group_type: str = "",
                 group_name: str = "", physics: str = "", image: str = "", url: str = "",
                 profile_no: int | None = None, sync_managers: list[SyncManager] | None = None,
                 fmmus: list[Fmmu] | None = None, rx_pdos: list[Pdo] | None = None,
                 tx_pdos: list[Pdo] | None = None, dictionary: ObjectDictionary | None = None,
                 mailbox: Mailbox | None = None, dc_opmodes: list[DcOpMode] | None = None,
                 eeprom: Eeprom | None = None, slots: list[Slot] | None = None,
                 modules: list[Module] | None = None, ebus_current_ma: int | None = None, source: str = "",
                 location: Location | None = None, extra: dict[str, str] | None = None,
                 alternative_sm_mappings: list[AlternativeSmMapping] | None = None,
                 end_line: int | None = None) -> None:
        self.identity = identity
        self.type_name = type_name
        self.name = name
        self.group_type = group_type
        self.group_name = group_name
        self.physics = physics
        self.image = image
        self.url = url
        self.profile_no = profile_no
        self.sync_managers = [] if sync_managers is None else sync_managers
        self.fmmus = [] if fmmus is None else fmmus
        self.rx_pdos = [] if rx_pdos is None else rx_pdos
        self.tx_pdos = [] if tx_pdos is None else tx_pdos
        self.dictionary = ObjectDictionary() if dictionary is None else dictionary
        self.mailbox = mailbox
        self.dc_opmodes = [] if dc_opmodes is None else dc_opmodes
        self.eeprom = eeprom
        self.slots = [] if slots is None else slots
        self.modules = [] if modules is None else modules
        self.ebus_current_ma = ebus_current_ma
        self.source = source
        self.location = location
        self.extra = {} if extra is None else extra
        self.alternative_sm_mappings = [] if alternative_sm_mappings is None else alternative_sm_mappings
        self.end_line = end_line

    def pdos(self, direction: Direction) -> list[Pdo]:
        return self.rx_pdos if direction is Direction.RX else self.tx_pdos

    def pdo(self, index: int) -> Pdo | None:
        """The PDO ``index``; where a window onto ESC registers (:meth:`esc_registers`) shares the index with a
        real PDO, the real one."""
        found = None
        for p in (*self.rx_pdos, *self.tx_pdos):
            if p.index == index:
                if not self.esc_registers(p):
                    return p
                found = found or p
        return found

    def esc_registers(self, pdo: Pdo) -> bool:
        """Whether ``pdo`` is a window onto ESC registers rather than a PDO of a sync manager: ``Virtual="true"``
        without a real sync manager of its direction (no ``Sm``, or a ``Sm Virtual="true"``). TwinCAT maps such a
        PDO's entries (1D09h:98h = register 0998h, a DC latch or start time) through an FMMU; the slave has no
        mapping object for it, so it is never assigned, programmed or counted against a sync manager. A virtual
        PDO on a real sync manager (an EL6692's bridge PDOs, whose entries the configuration tool makes) is a
        PDO of that sync manager."""
        if not pdo.virtual:
            return False
        sm = self.sm(pdo.sm) if pdo.sm is not None else None
        return sm is None or sm.virtual or sm.kind != pdo.direction.sm_kind

    def sm(self, number: int) -> SyncManager | None:
        for s in self.sync_managers:
            if s.number == number:
                return s
        return None

    def process_sm(self, direction: Direction) -> SyncManager | None:
        """The sync manager that carries process data in ``direction`` (SM2 outputs / SM3 inputs usually); a
        virtual one (``Sm Virtual="true"``: ESC registers through an FMMU, no sync manager of the slave) never."""
        for s in self.sync_managers:
            if s.kind == direction.sm_kind and not s.virtual:
                return s
        return None

    @property
    def has_coe(self) -> bool:
        return self.mailbox is not None and "CoE" in self.mailbox.protocols


class EsiFile(Record):
    """One ESI document: vendor, groups, devices, and file-level modules.

    ``devices`` is a property over a private slot so that :class:`ecattool.esi.reader.LazyEsiFile` can build
    the devices on first use; for a plain ``EsiFile`` it reads and sets the list.
    """

    __slots__ = ("source", "root", "vendor_id", "vendor_name", "groups", "_devices", "modules",
                 "info_references", "version", "warnings", "dictionary")
    _fields = ("source", "root", "vendor_id", "vendor_name", "groups", "devices", "modules", "info_references",
               "version", "warnings", "dictionary")
    source: str
    root: str  # "EtherCATInfo" or "EtherCATModule"
    vendor_id: int | None
    vendor_name: str
    groups: dict[str, str]  # GroupType -> name
    _devices: list[Device]
    modules: list[Module]
    info_references: list[str]
    version: str
    #: reader warnings (tolerated deviations such as ``0x`` numbers or unresolvable data types)
    warnings: list["Finding"]
    #: the dictionary of an ``EtherCATDict`` root (external dictionary files); None otherwise
    dictionary: ObjectDictionary | None

    def __init__(self, source: str, root: str, vendor_id: int | None = None, vendor_name: str = "",
                 groups: dict[str, str] | None = None, devices: list[Device] | None = None,
                 modules: list[Module] | None = None, info_references: list[str] | None = None,
                 version: str = "", warnings: list["Finding"] | None = None,
                 dictionary: ObjectDictionary | None = None) -> None:
        self.source = source
        self.root = root
        self.vendor_id = vendor_id
        self.vendor_name = vendor_name
        self.groups = {} if groups is None else groups
        self._devices = [] if devices is None else devices
        self.modules = [] if modules is None else modules
        self.info_references = [] if info_references is None else info_references
        self.version = version
        self.warnings = [] if warnings is None else warnings
        self.dictionary = dictionary

    @property
    def devices(self) -> list[Device]:
        return self._devices

    @devices.setter
    def devices(self, value: list[Device]) -> None:
        self._devices = value
