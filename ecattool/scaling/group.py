"""The result of a factor-group computation: objects with values, types, meaning and exactness."""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

from ecattool.errors import EncodeError, Location
from ecattool.findings import Finding
from ecattool.od import types as od_types
from ecattool.scaling.exact import Approximation, Exact
from ecattool.startup.model import StartupCommand, StartupList


def _num(f: Fraction) -> Any:
    """JSON form of an exact number: int when integral, else "num/den"."""
    return f.numerator if f.denominator == 1 else f"{f.numerator}/{f.denominator}"


@dataclass(slots=True)
class FactorObject:
    """One sub-index to write (or, with ``write`` False, to expect when read back, e.g. CT's RO 608Fh)."""

    index: int
    subindex: int
    name: str  # object name, e.g. "Position factor"
    part: str  # sub-index meaning, e.g. "Position internal units (IU)"
    value: int
    type_name: str = "UDINT"
    meaning: str = ""
    approximation: Approximation | None = None  # set on both subs of a ratio pair
    write: bool = True

    @property
    def exact(self) -> bool:
        return self.approximation is None or self.approximation.exact

    @property
    def address(self) -> str:
        return f"0x{self.index:04X}:{self.subindex:02X}"

    @property
    def hex(self) -> str:
        """The value as the drive stores it (two's complement for signed types), e.g. 0xFD for notation -3."""
        bits = od_types.require(self.type_name).bits or 32
        return f"0x{self.value & ((1 << bits) - 1):0{bits // 4}X}"

    def encode(self) -> bytes:
        dt = od_types.require(self.type_name)
        return dt.encode(self.value)

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "index": f"0x{self.index:04X}", "subindex": self.subindex, "name": self.name, "part": self.part,
            "value": self.value, "hex": self.hex,
            "type": self.type_name, "meaning": self.meaning, "exact": self.exact, "write": self.write,
        }
        a = self.approximation
        if a is not None:
            out["ratio_exact"] = str(a.exact_value)
            if not a.exact:
                out["method"] = a.method
                out["error_ppm"] = float(a.ppm)
                out["drift_per_1e6_units"] = float(a.drift)
                out["error_bound"] = float(a.bound)
        return out


@dataclass(slots=True)
class FactorGroup:
    """Every scaling object of one axis for one drive family, plus what the numbers mean."""

    family: str
    factor_set: str  # "cia402-2", "obsolete", "hdt", "controltechniques", "generic"
    objects: list[FactorObject] = field(default_factory=list)
    summary: dict[str, Any] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    findings: list[Finding] = field(default_factory=list)
    source: Location | None = None

    def add_pair(self, index: int, name: str, parts: tuple[str, str], approx: Approximation, meaning: str,
                 type_name: str = "UDINT", write: bool = True) -> None:
        for sub, part, value in ((1, parts[0], approx.numerator), (2, parts[1], approx.denominator)):
            self.objects.append(FactorObject(index, sub, name, part, value, type_name, meaning, approx, write))

    def add(self, index: int, subindex: int, name: str, value: int, meaning: str, type_name: str = "UDINT") -> None:
        self.objects.append(FactorObject(index, subindex, name, name, value, type_name, meaning))

    def get(self, index: int, subindex: int = 0) -> FactorObject | None:
        for o in self.objects:
            if o.index == index and o.subindex == subindex:
                return o
        return None

    def pair(self, index: int) -> tuple[int, int] | None:
        a, b = self.get(index, 1), self.get(index, 2)
        return (a.value, b.value) if a and b else None

    def ratio(self, index: int) -> Fraction | None:
        p = self.pair(index)
        return Fraction(p[0], p[1]) if p and p[1] else None

    @property
    def values(self) -> dict[tuple[int, int], int]:
        """``{(index, sub): value}`` — the form :func:`ecattool.scaling.explain` takes."""
        return {(o.index, o.subindex): o.value for o in self.objects}

    @property
    def mechanics(self) -> dict[str, str]:
        """The chain from encoder to user unit as the summary gives it (feedback, gear, transmission, position and
        velocity unit), as text: what the scaling page draws."""
        return {k: str(v) for k, v in self.summary.items()
                if k in ("feedback", "gear (motor:load)", "transmission", "position unit", "velocity unit")}

    @property
    def exact(self) -> bool:
        return all(o.exact for o in self.objects)

    def startup(self, transition: str = "PS") -> StartupList:
        """Startup commands writing every object (in the order computed), for the shared startup model."""
        out = StartupList(name=f"scaling ({self.family})")
        for o in self.objects:
            if not o.write:
                continue
            try:
                data = o.encode()
            except EncodeError as exc:
                raise EncodeError(f"{o.address} {o.name}: {exc.message}", self.source) from None
            comment = (o.name if o.part == o.name else f"{o.name}: {o.part}") + ("" if o.exact else " (approximated)")
            out.commands.append(StartupCommand(transition, o.index, o.subindex, data, comment, type_name=o.type_name,
                                               value=o.value, source=self.source))
        return out

    def to_json(self) -> dict[str, Any]:
        return {
            "family": self.family,
            "factor_set": self.factor_set,
            "exact": self.exact,
            "summary": {k: (_num(v) if isinstance(v, Fraction) else str(v) if isinstance(v, Exact) else v)
                        for k, v in self.summary.items()},
            "objects": [o.to_json() for o in self.objects],
            "notes": list(self.notes),
            "findings": [f.to_json() for f in self.findings],
        }
