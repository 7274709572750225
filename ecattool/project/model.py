"""The project file: one reviewable YAML file per machine (pydantic models, format version 1).

See docs/project.md for the format with examples. Paths inside the file are relative to the file.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated, Any, Literal, get_args

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    GetJsonSchemaHandler,
    SkipValidation,
    ValidationInfo,
    field_validator,
    model_validator,
)
from pydantic.json_schema import JsonSchemaValue

from ecattool.errors import InputError, SelectionError

if TYPE_CHECKING:
    from ecattool.scaling.model import ScalingSection

    #: a drive's ``scaling:`` section: the scaling spec's own shape
    ScalingField = ScalingSection | None
else:
    class _ScalingSchema:
        """The JSON schema of ``scaling:``: the scaling spec's own model (``ScalingSection``), imported when the
        schema is generated, not when a project is read (linting a project without scaling stays as fast as it
        was: the scaling package is imported by the step that computes a factor group)."""

        @classmethod
        def __get_pydantic_json_schema__(cls, core_schema: object, handler: GetJsonSchemaHandler) -> JsonSchemaValue:
            from pydantic import TypeAdapter

            from ecattool.scaling.model import ScalingSection

            return handler(TypeAdapter(ScalingSection | None).core_schema)

    ScalingField = Annotated[dict[str, object] | None, _ScalingSchema]

#: The project file format version this ecattool writes and reads.
FORMAT_VERSION = 1

IntLike = Annotated[int | str, Field(description="An integer: 8, 0x1C12 or #x1C12")]


def _takes_bool(annotation: object) -> bool:
    """Whether a field's type admits true/false (``bool`` itself, or in a union)."""
    if annotation is bool:
        return True
    return any(_takes_bool(a) for a in get_args(annotation))


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", populate_by_name=True)

    @field_validator("*", mode="before")
    @classmethod
    def _no_boolean_numbers(cls, value: object, info: ValidationInfo) -> object:
        """A boolean is never a number: pydantic would take ``position: true`` as 1 (issue 28.3)."""
        if isinstance(value, bool) and info.field_name is not None:
            field = cls.model_fields.get(info.field_name)
            if field is not None and not _takes_bool(field.annotation):
                raise ValueError(f"{str(value).lower()} is a boolean; a number or text belongs here")
        return value


class DeviceRef(_Strict):
    """Which device a drive is: a vendor ESI file plus a selector, or a built-in family profile."""

    esi: str | None = Field(default=None, description="ESI file (or CANopen EDS/DCF file), relative to the project file")
    select: str | int | None = Field(
        default=None, description="Device in the ESI: type name, product_code[:revision] or list index"
    )
    policy: Literal["exact", "newest-not-newer", "newest"] = Field(
        default="exact", description="Revision selection policy when the selector names a revision"
    )
    profile: str | None = Field(
        default=None, description="Built-in family: technosoft-ipos, hdt, controltechniques"
    )
    product: str | None = Field(default=None, description="Model/product of the built-in family")
    revision: str | int | None = Field(
        default=None, description="Firmware revision of the built-in family (e.g. F515K)"
    )

    @model_validator(mode="after")
    def _one_source(self) -> "DeviceRef":
        if (self.esi is None) == (self.profile is None):
            raise ValueError("give exactly one of 'esi' (with 'select') or 'profile'")
        if self.profile is None and (self.product is not None or self.revision is not None):
            raise ValueError("'product' and 'revision' belong to a 'profile'; use 'select' with an ESI")
        return self


class IdentityCheck(_Strict):
    """What to check against the identity (1018h) the drive reports when commissioning."""

    vendor: bool = Field(default=True, description="Check the vendor id")
    product: bool = Field(default=True, description="Check the product code")
    revision: Literal["exact", "at-least", "ignore"] = Field(
        default="exact", description="How to check the revision"
    )


class PdoDef(_Strict):
    """One PDO of an assignment: its mapping object index and entries (`0x6040:00/16`, `controlword`…)."""

    index: IntLike = Field(description="Mapping object index, e.g. 0x1600")
    entries: list[str | IntLike] | None = Field(
        default=None, description="Entries; omit to keep the PDO's default (or fixed) mapping"
    )


class PdoConfig(_Strict):
    """PDO assignment and mapping per direction (rx = outputs/SM2/1C12h, tx = inputs/SM3/1C13h)."""

    rx: list[PdoDef] | None = Field(
        default=None, description="RxPDOs assigned to SM2, in order; omit for the default"
    )
    tx: list[PdoDef] | None = Field(
        default=None, description="TxPDOs assigned to SM3, in order; omit for the default"
    )
    complete_access: bool = Field(default=False, description="Program the mapping with SDO complete access")


class Parameter(_Strict):
    """One SDO parameter written at a state transition."""

    object: str | int = Field(description="Object as 6060:00, 0x6060:0, or by name (modes of operation)")
    value: int | float | str | bool | list[int] = Field(
        description="Value in engineering form (8, 0x10, -5, 2.5, 'text', enum name) or 'hex:0a0b' raw bytes"
    )
    transition: str = Field(default="PS", description="Transition it is written in: IP, PS, SO, …")
    comment: str = ""

    @field_validator("transition")
    @classmethod
    def _transition(cls, v: str) -> str:
        from ecattool.startup.model import TRANSITIONS

        t = v.strip().upper()
        if t not in TRANSITIONS:
            raise ValueError(f"unknown transition {v!r} (use one of {', '.join(TRANSITIONS)})")
        return t


class EsiInitCmd(_Strict):
    """A change to one of the init commands the drive's ESI sends (``Mailbox/CoE/InitCmd``): a new value, or
    not sent at all. ``project new`` lists the ESI's init commands; docs/project.md, "ESI init commands"."""

    object: str | int = Field(description="Object the ESI's init command writes, e.g. 6060:00")
    transition: str | None = Field(
        default=None, description="Only the command of this transition (default: every transition it names)"
    )
    value: int | float | str | bool | list[int] | None = Field(
        default=None, description="Value to write instead of the ESI's (engineering form, as in parameters)"
    )
    skip: bool = Field(default=False, description="Do not send the command")
    comment: str = ""

    @field_validator("transition")
    @classmethod
    def _transition(cls, v: str | None) -> str | None:
        return None if v is None else Parameter._transition(v)

    @model_validator(mode="after")
    def _one_change(self) -> "EsiInitCmd":
        if (self.value is None) == (not self.skip):
            raise ValueError("give either 'value' (the value to write instead) or 'skip: true'")
        return self


class DcConfig(_Strict):
    """Distributed clocks: an OpMode of the ESI by name, or explicit values."""

    opmode: str | None = Field(default=None, description="Name of an ESI Dc/OpMode (e.g. DC, DC-Synchron)")
    assign_activate: IntLike | None = Field(default=None, description="AssignActivate word, e.g. 0x0300")

    @field_validator("assign_activate")
    @classmethod
    def _a_word(cls, value: int | str | None) -> int | str | None:
        """AssignActivate is the 16-bit register 0x0980: checked where it is read."""
        if value is None:
            return value
        from ecattool.od.numbers import parse_int

        try:
            number = parse_int(value, what="AssignActivate word")
        except InputError as exc:
            raise ValueError(exc.message) from None
        if not 0 <= number <= 0xFFFF:
            raise ValueError(f"AssignActivate {value} does not fit 16 bits (0..0xFFFF)")
        return value
    cycle_ns: int | None = Field(default=None, ge=1, le=0xFFFFFFFF, description="SYNC0 cycle time in ns (UNSIGNED32)")
    shift_ns: int | None = Field(default=None, ge=-(2**31), le=2**31 - 1,
                                 description="SYNC0 shift time in ns (INTEGER32)")
    sync1_cycle_ns: int | None = Field(
        default=None, ge=0, le=0xFFFFFFFF,
        description="SYNC1 cycle time in ns (UNSIGNED32, the ESC's 0x09A4 and the ESI OpMode's CycleTimeSync1; "
                    "0: SYNC1 with every SYNC0 pulse); the SYNC1 signal itself is switched on by AssignActivate "
                    "bit 10 (0x0400)")
    sync1_shift_ns: int | None = Field(default=None, ge=-(2**31), le=2**31 - 1,
                                       description="SYNC1 shift time in ns (INTEGER32, the OpMode's ShiftTimeSync1)")

    @model_validator(mode="after")
    def _sync1_shift_needs_cycle(self) -> "DcConfig":
        if self.sync1_shift_ns is not None and self.sync1_cycle_ns is None and self.opmode is None:
            raise ValueError("sync1_shift_ns without sync1_cycle_ns (or an opmode that gives a SYNC1 cycle)")
        return self


class SwConfig(_Strict):
    """A Technosoft .sw setup image to verify (and download where it differs)."""

    file: str = Field(description=".sw file, relative to the project file")
    mode: Literal[16, 32] = Field(default=16, description="EEPROM write width for downloads")
    download: bool = Field(default=True, description="Download blocks that differ (else only verify)")


class RuleOff(_Strict):
    rule: str = Field(description="Rule id to disable for this drive or project, e.g. PDO011")
    reason: str = Field(description="Why: lint refuses a disabled rule without a reason")


class MoveTest(_Strict):
    """The short move of the commissioning run, in user units."""

    distance: float = Field(default=1.0, allow_inf_nan=False, description="Relative move in position user units")
    mode: Literal["pp", "csp"] = Field(
        default="pp", description="Profile position or cyclic synchronous position"
    )


class PlantConfig(_Strict):
    """The motor and load of a simulated drive (issue 33; docs/simulator.md "The plant"): what commission's
    simulator moves. Every field is optional: the family's default plant fills the rest."""

    motor_inertia: float | None = Field(default=None, gt=0, allow_inf_nan=False,
                                        description="Rotor inertia, kg·m² (motor datasheet J)")
    load_inertia: float | None = Field(default=None, ge=0, allow_inf_nan=False,
                                       description="Rotary load inertia at the load side, kg·m² (reflected "
                                       "through the scaling's gear)")
    load_mass: float | None = Field(default=None, ge=0, allow_inf_nan=False,
                                    description="Moved mass, kg (reflected through the scaling's screw, belt or "
                                    "rack and gear)")
    viscous_friction: float | None = Field(default=None, ge=0, allow_inf_nan=False,
                                           description="Viscous friction at the motor, N·m per rad/s")
    coulomb_friction: float | None = Field(default=None, ge=0, allow_inf_nan=False,
                                           description="Coulomb friction at the motor, N·m")
    rated_torque: float | None = Field(default=None, gt=0, allow_inf_nan=False,
                                       description="Rated (continuous) torque, N·m (6076h)")
    peak_torque: float | None = Field(default=None, gt=0, allow_inf_nan=False, description="Peak torque, N·m")
    max_speed: float | None = Field(default=None, gt=0, allow_inf_nan=False, description="Maximum speed, rpm")
    position_bandwidth: float | None = Field(default=None, gt=0, allow_inf_nan=False,
                                             description="Position loop natural frequency wn, rad/s")
    damping: float | None = Field(default=None, gt=0, allow_inf_nan=False,
                                  description="Position loop damping ratio zeta")
    velocity_feedforward: float | None = Field(default=None, ge=0, le=1, allow_inf_nan=False,
                                               description="Velocity feed-forward 0..1 (1: no steady lag)")
    velocity_tau: float | None = Field(default=None, gt=0, allow_inf_nan=False,
                                       description="Velocity loop time constant, s")


class Drive(_Strict):
    name: str = Field(description="Axis/drive name, unique in the project")
    position: int | None = Field(
        default=None, ge=0, le=0xFFFF, description="Position on the bus (default: order in the file)"
    )
    device: DeviceRef
    identity: IdentityCheck = Field(default_factory=IdentityCheck)
    pdo: PdoConfig | None = None
    # typed from scaling's own model; validated by it alone (scaling.spec.spec_from_dict: lint's PRJ050 at the
    # value's line), so the project model passes the mapping through as written
    scaling: SkipValidation[ScalingField] = Field(
        default=None, description="Mechanics and units for the factor group (see docs/scaling.md)"
    )
    parameters: list[Parameter] = Field(default_factory=list)
    esi_init_cmds: list[EsiInitCmd] = Field(
        default_factory=list, description="Changes to the init commands of the drive's ESI (sent before parameters)"
    )
    sw: SwConfig | str | None = Field(
        default=None, description="Technosoft .sw image (file name or settings)"
    )
    dc: DcConfig | None = None
    move: MoveTest | None = Field(default=None, description="Commissioning move; omit to skip the move")
    enable: bool | None = Field(
        default=None, description="Enable the drive through the CiA-402 state machine when commissioning "
        "(default: yes for a CiA-402 axis, no for an I/O slave; false commissions an axis without enabling it)"
    )
    disable_rules: list[RuleOff] = Field(default_factory=list)
    plant: Literal["ideal"] | PlantConfig | None = Field(
        default=None, description="The simulated motor and load (default: the family's); 'ideal': actual = demand")

    @field_validator("scaling", mode="before")
    @classmethod
    def _scaling_is_a_mapping(cls, value: object) -> object:
        """The section is a mapping (what the schema's type says, in pydantic's words); its keys and values are
        the scaling spec reader's to check (PRJ050, at their lines)."""
        if value is not None and not isinstance(value, (dict, bool)):  # a boolean is _no_boolean_numbers'
            raise ValueError("Input should be a valid dictionary")
        return value

    @property
    def sw_config(self) -> SwConfig | None:
        if isinstance(self.sw, str):
            return SwConfig(file=self.sw)
        return self.sw


class Project(_Strict):
    """An ecattool project: the drives of one machine and how to configure them."""

    ecattool: Literal[1] = Field(description="Project file format version (1)")
    name: str = ""
    description: str = ""
    target: str = Field(default="sim", description="Default target of commission: 'sim' (the project's drives, "
                                                   "simulated) or 'pysoem:<interface>'")
    drives: list[Drive] = Field(min_length=1)
    disable_rules: list[RuleOff] = Field(default_factory=list)

    @field_validator("target")
    @classmethod
    def _target(cls, v: str) -> str:
        """A spec commission can open for this project (ecattool.target.opener): its own drives simulated, or a
        real master; lint says so, not commission."""
        from ecattool.target.opener import parse_target

        try:
            spec = parse_target(v)
            ok = spec.kind == "pysoem" or spec.own_slaves
        except SelectionError:
            ok = False
        if not ok:
            raise ValueError(f"target {v!r}: a project's target is 'sim' (its own drives, simulated) or "
                             "'pysoem:<interface>'")
        return v

    @model_validator(mode="after")
    def _unique(self) -> "Project":
        names = [d.name for d in self.drives]
        dup = {n for n in names if names.count(n) > 1}
        if dup:
            raise ValueError(f"drive names must be unique: {', '.join(sorted(dup))}")
        return self


def json_schema() -> dict[str, Any]:
    schema = Project.model_json_schema()
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    schema["$id"] = "urn:ecattool:project-schema:1"  # an identifier, not an address: ecattool has no web site
    schema["title"] = "ecattool project file"
    return schema
