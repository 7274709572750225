"""One slave of the machine (:class:`Slave`), frozen, and the values it is made of.

This module is below the steps that resolve a project's drive (:mod:`ecattool.project.resolve`,
:mod:`ecattool.project.steps`, :mod:`ecattool.project.initcmds`, :mod:`ecattool.project.familycycle`): each
step returns what it resolves (a device, a mapping, startup commands …) and the findings it made (a
:class:`Found`); :func:`ecattool.project.machine.build_slave` assembles the :class:`Slave` from them, once.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from typing import TYPE_CHECKING, Literal

from ecattool.errors import InputError, Location
from ecattool.esi.model import Device
from ecattool.findings import Finding, Severity
from ecattool.project.model import Drive
from ecattool.startup.model import StartupList

if TYPE_CHECKING:
    from ecattool.pdo.model import Mapping
    from ecattool.profiles.rules import FamilyRules
    from ecattool.scaling.group import FactorGroup
    from ecattool.sw.image import SwImage


class Found(list[Finding]):
    """The findings one step made, in the order it made them (what the step returns beside its value)."""

    def error(self, rule: str, message: str, location: Location | None) -> None:
        self.append(Finding(rule, Severity.ERROR, message, location))

    def warning(self, rule: str, message: str, location: Location | None) -> None:
        self.append(Finding(rule, Severity.WARNING, message, location))


#: what a slave is: a CiA-402 axis (enabled and moved by commission) or an I/O slave (terminals, couplers,
#: gateways: states, mapping and process data only)
SlaveKind = Literal["axis", "io"]


def is_axis(device: Device) -> bool:
    """Whether ``device`` is a CiA-402 axis: its dictionary has the controlword 6040h and the statusword 6041h,
    and it says it is a drive (profile 402 in the ESI ``<Profile>`` or the EDS/1000h device type) or has the
    modes of operation 6060h. A terminal that uses 6041h for something else (a diagnostics channel) or lacks
    6040h is an I/O slave (docs/decisions.md, "Machine: axis or I/O slave")."""
    od = device.dictionary
    if od.entry(0x6040, 0) is None or od.entry(0x6041, 0) is None:
        return False
    dtype = od.entry(0x1000, 0)
    declared = device.profile_no == 402
    if not declared and dtype is not None and dtype.default:
        declared = int.from_bytes(dtype.default[:2], "little") == 402
    return declared or od.entry(0x6060, 0) is not None


@dataclass(frozen=True, slots=True)
class SlaveDc:
    """Distributed clocks of a slave as the project sets them, resolved once (:func:`resolve_dc`): the
    AssignActivate word (the project's, else its ESI OpMode's), the SYNC0 cycle and shift (the project's, else
    the OpMode's), and SYNC1 where the OpMode gives a cycle for it."""

    assign_activate: int
    opmode: str | None = None
    cycle_ns: int | None = None
    shift_ns: int | None = None
    sync1_cycle_ns: int | None = None
    sync1_shift_ns: int | None = None

    @property
    def active(self) -> bool:
        """Whether the slave's SYNC signals are activated (a non-zero AssignActivate)."""
        return bool(self.assign_activate)



@dataclass(frozen=True, slots=True)
class Slave:
    """One slave of the machine as the project sets it up: the device as it runs (default modules plugged in,
    communication objects completed), its family rules, PDO mapping, startup list, DC, and for an axis the
    factor group and ``.sw`` image; plus the findings that concern it. Frozen: the steps
    (:mod:`ecattool.project.resolve`, :mod:`ecattool.project.steps` …) return what they resolve, and
    :func:`ecattool.project.machine.build_slave` assembles the slave from those values in one place."""

    index: int
    drive: Drive
    device: Device | None = None
    rules: FamilyRules | None = None
    startup: StartupList = field(default_factory=StartupList)
    findings: tuple[Finding, ...] = ()
    mapping: Mapping | None = None  # when the pdo section (or the device default) resolved
    factor_group: FactorGroup | None = None  # when the scaling section resolved
    counts_per_unit: Fraction | None = None  # internal position units per position user unit (ideal)
    sw_image: SwImage | None = None  # when an image is configured and readable
    dc: SlaveDc | None = None  # when the project's dc section resolves on the device

    @property
    def position(self) -> int:
        return self.drive.position if self.drive.position is not None else self.index

    @property
    def name(self) -> str:
        return self.drive.name

    @property
    def kind(self) -> SlaveKind:
        """``axis`` where the device is a CiA-402 drive (:func:`is_axis`), else ``io``."""
        return "axis" if self.device is not None and is_axis(self.device) else "io"

    @property
    def enables(self) -> bool:
        """Whether commission enables the slave (CiA-402): the project's ``enable:``, by default for an axis."""
        return self.drive.enable if self.drive.enable is not None else self.kind == "axis"

    def require_device(self) -> Device:
        """The device as it runs; an InputError where it did not resolve (the slave's findings say why)."""
        if self.device is None:
            raise InputError(f"drive {self.name!r}: the device did not resolve (see `ecattool lint`)")
        return self.device

    @property
    def family(self) -> str:
        return self.rules.family if self.rules is not None else "generic"

    def object_values(self, indices: range | tuple[int, ...]) -> dict[tuple[int, int], int]:
        """What the objects at ``indices`` hold once the startup list ran: the last write of the startup list,
        else the device's default (unsigned, as startup files print them); for ``scale explain --project``."""
        out: dict[tuple[int, int], int] = {}
        if self.device is not None:
            for index in indices:
                obj = self.device.dictionary.get(index)
                if obj is None:
                    continue
                for sub, e in obj.entries.items():
                    if e.default is not None and e.datatype is not None and e.datatype.bits and (sub or len(obj.entries) == 1):
                        out[(index, sub)] = int.from_bytes(e.default, "little")
        for c in self.startup:
            if c.index in indices and not c.complete_access:
                out[(c.index, c.subindex)] = c.int_value
        return out
