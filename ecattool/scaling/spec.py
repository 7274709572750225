"""Scaling spec files (YAML): one axis plus the family options, with located errors.

:class:`~ecattool.scaling.model.ScalingSection` is the shape of a spec (a spec file, or a project drive's ``scaling:`` section): the
project schema's ``scaling:`` is generated from it, and :func:`spec_from_dict` is its one validator (every value
checked with the file and line of its error; the project model passes the section through unvalidated).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from fractions import Fraction
from pathlib import Path
from typing import Any, Literal

from ecattool.errors import InputError, Location
from ecattool.od.numbers import parse_fraction
from ecattool.scaling.exact import Strategy
from ecattool.scaling.model import (
    Axis,
    FeedbackSection,
    Locate,
    ScalingSection,
    UnitsSection,
    axis_from_dict,
    feedback_from,
    gear_from,
    slow_loop_from,
    transmission_from,
)


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


@dataclass(frozen=True, slots=True)
class AxisOptions:
    """What a command line says of an axis, each field None where it says nothing: the feedback (counts per
    revolution, encoder lines, or stepper steps and microsteps; where it sits), gear, transmission, the units of
    each order, the Technosoft slow loop and the direction. The same words a spec file's keys take."""

    counts_per_rev: str | None = None
    lines: str | None = None
    steps: tuple[str, str] | None = None
    feedback_on: Literal["motor", "load"] | None = None
    gear: str | None = None
    transmission: str | None = None
    position: str | None = None
    velocity: str | None = None
    acceleration: str | None = None
    jerk: str | None = None
    slow_loop: str | None = None
    reverse: bool | None = None

    def feedback(self) -> FeedbackSection:
        """The feedback keys said, as a spec file writes them."""
        fb: FeedbackSection = {}
        if self.counts_per_rev:
            fb["counts_per_rev"] = self.counts_per_rev
        if self.lines:
            fb["lines"] = self.lines
        if self.steps:
            fb["steps"], fb["microsteps"] = self.steps
        if self.feedback_on:
            fb["on"] = self.feedback_on
        return fb

    def units(self) -> UnitsSection:
        units: UnitsSection = {}
        if self.position:
            units["position"] = self.position
        if self.velocity:
            units["velocity"] = self.velocity
        if self.acceleration:
            units["acceleration"] = self.acceleration
        if self.jerk:
            units["jerk"] = self.jerk
        return units


def spec_with(base: Spec | None, options: AxisOptions) -> Spec:
    """The spec ``base`` (a spec file read; None: none) with what ``options`` says over it; without a base the
    options must give the feedback. Every unit is checked (an InputError naming what is wrong)."""
    fb = options.feedback()
    counted = any(k in fb for k in ("counts_per_rev", "lines", "steps"))
    if base is None:
        if not counted:
            raise InputError("give a SPEC file or the feedback (--counts-per-rev, --lines or --steps)")
        data: ScalingSection = {"feedback": fb, "gear": options.gear, "transmission": options.transmission,
                                "units": options.units(), "reverse": bool(options.reverse)}
        if options.slow_loop:
            data["slow_loop"] = options.slow_loop
        return spec_from_dict(data)

    ax = base.axis
    changes: dict[str, Any] = dict(options.units())
    if fb:
        changes["feedback"] = feedback_from(fb) if counted else replace(ax.feedback, on=fb["on"])
    if options.gear:
        changes["gear"] = gear_from(options.gear)
    if options.transmission:
        changes["transmission"] = transmission_from(options.transmission)
    if options.slow_loop:
        changes["slow_loop"] = slow_loop_from(options.slow_loop)
    if options.reverse is not None:
        changes["reverse"] = options.reverse
    spec = replace(base, axis=replace(ax, **changes))
    for order in range(4):
        spec.axis.unit(order)
    return spec
