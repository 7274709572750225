"""Scaling spec files (YAML): one axis plus the family options, with located errors.

:class:`~ecattool.scaling.model.ScalingSection` is the shape of a spec (a spec file, or a project drive's ``scaling:`` section): the
project schema's ``scaling:`` is generated from it, and :func:`spec_from_dict` is its one validator (every value
checked with the file and line of its error; the project model passes the section through unvalidated).
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

from ecattool.errors import InputError, Location
from ecattool.scaling.exact import Strategy
from ecattool.scaling.model import Axis, Locate, ScalingSection, axis_from_dict



@dataclass(frozen=True, slots=True)
class Spec:
    axis: Axis
    family: str | None = None
    firmware: str | None = None
    approximation: Strategy | None = None
    vl_setpoint: tuple[int, int] = (1, 1)


def spec_from_dict(data: ScalingSection, locate: Locate | None = None, source: Location | None = None) -> Spec:
    """The :class:`Spec` of a spec mapping, every value checked (``locate(path)``: where a key's value is, for
    the errors; ``source``: where the mapping is)."""
    axis = axis_from_dict(data, locate, source)
    approx = data.get("approximation")
    if approx is not None and approx not in ("best", "max-scale"):
        raise InputError(f"approximation must be best or max-scale, got {approx!r}",
                         locate(("approximation",)) if locate else source)
    sp = data.get("vl_setpoint", "1/1")
    from ecattool.od.numbers import parse_fraction

    where = locate(("vl_setpoint",)) if locate else source
    try:
        f = parse_fraction(sp, where, "vl_setpoint")
    except InputError as exc:
        raise InputError(f"{exc.message} (a ratio, e.g. 1/10)", where) from None
    return Spec(axis, None if data.get("family") is None else str(data["family"]),
                None if data.get("firmware") is None else str(data["firmware"]), approx, (f.numerator, f.denominator))


def load_spec(path: str | Path, text: str | bytes | None = None) -> Spec:
    """Read a scaling spec YAML file (see docs/scaling.md)."""
    from ecattool.yamlloc import load_yaml

    src = str(path)
    if text is None:
        from ecattool.fileio import read_input
        from ecattool.yamlloc import MAX_YAML_BYTES

        # bytes from stdin too: load_yaml decodes, so bytes that are not UTF-8 are an InputError, not a crash
        text = read_input(src, MAX_YAML_BYTES)
    doc = load_yaml(text, src)
    return spec_from_dict(doc.data, doc.locate, Location(src, 1, 1))
