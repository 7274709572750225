"""The mechanics input model: feedback, gearbox, transmission, units, slow-loop period — exact Fractions.

Everything the factor group needs reduces to three exact numbers:

* ``travel_per_motor_rev`` — how far the load moves for one motor revolution (metres, load revolutions,
  or label units), symbolic in pi where a diameter is involved;
* ``counts_per_motor_rev`` — feedback increments per motor revolution (a load-side encoder or linear scale
  is referred to the motor through the gear and transmission);
* the user units.

A linear motor is modelled as a "motor revolution" of one pole pitch.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from fractions import Fraction
from typing import Annotated, Any, Literal, Union

from pydantic import ConfigDict, Field, with_config
from typing_extensions import TypedDict

from ecattool.errors import InputError, Location, did_you_mean
from ecattool.od.numbers import check_exponent, parse_fraction
from ecattool.scaling.exact import Exact
from ecattool.scaling.units import Unit, parse_unit, quantity, time_seconds

TRANSMISSIONS = ("rotary", "belt", "ballscrew", "rack", "linear_motor", "hollow_shaft", "label")


# --- domain limits of the mechanics: far beyond any real machine, and far inside what the exact arithmetic and
# the 32-bit factors can carry (a zero, negative or absurd value is a located error where it is read, never a
# ZeroDivisionError or an OverflowError later). See docs/scaling.md, "Limits".
#: counts per revolution: 608Fh:01 (encoder increments) is UNSIGNED32
MAX_COUNTS = 2**32
#: lengths (pitch, diameter, tooth pitch, module, pole pitch, scale resolution), metres: 1 pm .. 1 km
MIN_LENGTH, MAX_LENGTH = Fraction(1, 10**12), Fraction(1000)
#: plain ratios and counts (gear parts, pulley stages, custom-label units): 10^-9 .. 10^12
MIN_NUMBER, MAX_NUMBER = Fraction(1, 10**9), Fraction(10**12)
#: the drive's slow-loop (position loop) period, seconds: 1 µs .. 10 s
MIN_SLOW_LOOP, MAX_SLOW_LOOP = Fraction(1, 10**6), Fraction(10)
def _bounded(f: Fraction, shown: object, what: str, location: Location | None, lo: Fraction, hi: Fraction,
             unit: str = "") -> None:
    if f <= 0:
        raise InputError(f"{what} must be positive, got {shown!r}", location)
    if not lo <= f <= hi:
        raise InputError(f"{what} {shown!r} is out of range ({_plain(lo)}{unit} .. {_plain(hi)}{unit})", location)


def _plain(f: Fraction) -> str:
    return str(f) if f.denominator == 1 or f.numerator != 1 else f"1e-{len(str(f.denominator)) - 1}" \
        if str(f.denominator).strip("0") == "1" else str(f)


def _frac(value: object, what: str, location: Location | None, positive: bool = True,
          lo: Fraction = MIN_NUMBER, hi: Fraction = MAX_NUMBER) -> Fraction:
    f = parse_fraction(value, location, what)  # a boolean is never a number; 1e999 is refused before it is exact
    if positive:
        _bounded(f, value, what, location, lo, hi)
    return f


def _length(value: object, what: str, location: Location | None, meant: str | None = None) -> Exact:
    """A length from a spec or an option, within :data:`MIN_LENGTH` .. :data:`MAX_LENGTH` (a bare number is an
    error that shows it with ``meant``, the unit it probably meant)."""
    if isinstance(value, bool):
        raise InputError(f"{what} must be a length, not {str(value).lower()}", location)
    check_exponent(value, location, what)
    q = quantity(value, ("length",), location, what=what, meant=meant)[0]
    _bounded(q.coef, value, what, location, MIN_LENGTH, MAX_LENGTH, " m")
    return q


def _integer(value: object, what: str, location: Location | None, hi: int) -> int:
    f = _frac(value, what, location, lo=Fraction(1), hi=Fraction(hi))
    if f.denominator != 1:
        raise InputError(f"{what} must be an integer, got {value!r}", location)
    return int(f)


@dataclass(frozen=True, slots=True)
class Feedback:
    """Position feedback: increments per feedback revolution (or a linear scale's increment length).

    ``on`` is ``motor`` or ``load``. For a linear scale, ``resolution`` is the length of one increment
    (metres) and the scale is on the load.
    """

    counts_per_rev: Fraction | None = None
    on: str = "motor"
    resolution: Exact | None = None  # linear scale: metres per increment
    description: str = ""

    @staticmethod
    def encoder(counts_per_rev: int | Fraction, on: str = "motor") -> "Feedback":
        return Feedback(Fraction(counts_per_rev), on, None, f"{counts_per_rev} increments/rev on {on}")

    @staticmethod
    def lines(lines: int, on: str = "motor") -> "Feedback":
        return Feedback(Fraction(4 * lines), on, None, f"{lines}-line quadrature encoder = {4 * lines} counts/rev on {on}")

    @staticmethod
    def stepper(steps: int, microsteps: int) -> "Feedback":
        return Feedback(Fraction(steps * microsteps), "motor", None, f"{steps} steps x {microsteps} microsteps = {steps * microsteps}/rev")

    @staticmethod
    def linear_scale(resolution: Exact) -> "Feedback":
        return Feedback(None, "load", resolution, f"linear scale, {float(resolution.rational) * 1e6:g} µm per increment")


@dataclass(frozen=True, slots=True)
class Gear:
    """Gearbox ratio as motor revolutions : load (driving shaft) revolutions, e.g. 3:1."""

    motor: Fraction = Fraction(1)
    load: Fraction = Fraction(1)

    @property
    def ratio(self) -> Fraction:
        return self.motor / self.load

    def __str__(self) -> str:
        return f"{self.motor}:{self.load}"


@dataclass(frozen=True, slots=True)
class Transmission:
    """What one revolution of the driving (load) shaft does: ``travel`` in metres, revolutions or labels."""

    kind: str
    travel: Exact  # per driving-shaft revolution (linear motor: per pole pitch)
    output: str  # "length" | "angle" | "label"
    description: str
    label: str | None = None

    @staticmethod
    def rotary(driving: Fraction | int = 1, driven: Fraction | int = 1) -> "Transmission":
        """A rotary table or disk; optional belt/gear stage by teeth or diameters (driving : driven)."""
        r = Fraction(driving) / Fraction(driven)
        desc = "rotary load" + ("" if r == 1 else f", pulley stage {driving}:{driven} (driving:driven)")
        return Transmission("rotary", Exact(r), "angle", desc)

    @staticmethod
    def ballscrew(pitch: Exact) -> "Transmission":
        return Transmission("ballscrew", pitch, "length", f"ball screw, lead {_mm(pitch)} per rev")

    @staticmethod
    def hollow_shaft(pitch: Exact) -> "Transmission":
        return Transmission("hollow_shaft", pitch, "length", f"hollow-shaft motor on a screw, lead {_mm(pitch)} per rev")

    @staticmethod
    def belt_diameter(diameter: Exact) -> "Transmission":
        return Transmission._circumference("belt", diameter, "belt/pulley, pulley diameter")

    @staticmethod
    def belt_teeth(teeth: int, tooth_pitch: Exact) -> "Transmission":
        return Transmission._toothed("belt", teeth, tooth_pitch, "toothed belt")

    @staticmethod
    def rack_diameter(pitch_diameter: Exact) -> "Transmission":
        return Transmission._circumference("rack", pitch_diameter, "rack and pinion, pitch diameter")

    @staticmethod
    def rack_teeth(teeth: int, tooth_pitch: Exact) -> "Transmission":
        return Transmission._toothed("rack", teeth, tooth_pitch, "rack and pinion")

    @staticmethod
    def _circumference(kind: str, diameter: Exact, what: str) -> "Transmission":
        return Transmission(kind, diameter * Exact(Fraction(1), 1), "length", f"{what} {_mm(diameter)} (travel pi*D)")

    @staticmethod
    def _toothed(kind: str, teeth: int, tooth_pitch: Exact, what: str) -> "Transmission":
        return Transmission(kind, tooth_pitch * teeth, "length", f"{what}, {teeth} teeth x {_mm(tooth_pitch)} pitch")

    @staticmethod
    def linear_motor(pole_pitch: Exact) -> "Transmission":
        return Transmission("linear_motor", pole_pitch, "length", f"linear motor, pole pitch {_mm(pole_pitch)}")

    @staticmethod
    def custom_label(name: str, units: Fraction | int, motor_revs: Fraction | int = 1) -> "Transmission":
        """HDT "custom label": ``units`` label units correspond to ``motor_revs`` motor revolutions."""
        return Transmission("label", Exact(Fraction(units) / Fraction(motor_revs)), "label",
                            f"custom unit {name!r}: {units} per {motor_revs} motor rev", label=name)


def _mm(length: Exact) -> str:
    v = length * 1000
    return f"{v} mm" if v.is_rational else f"{float(v.rational):.6g} mm"


@dataclass(frozen=True, slots=True)
class Axis:
    """One axis: mechanics plus the user units the engineer wants the drive to speak."""

    feedback: Feedback
    transmission: Transmission = field(default_factory=Transmission.rotary)
    gear: Gear = field(default_factory=Gear)
    position: str = "rev"
    velocity: str | None = None  # default: position unit per second
    acceleration: str | None = None  # default: velocity unit per second
    jerk: str | None = None  # default: acceleration unit per second
    time: str = "ms"  # time unit of the obsolete 2071h time factor
    slow_loop: Fraction = Fraction(1, 1000)  # seconds (Technosoft T)
    reverse: bool = False  # polarity 607Eh (positions and velocities x -1)
    name: str = ""
    source: Location | None = None

    # --- units -------------------------------------------------------------------------------------
    @property
    def labels(self) -> tuple[str, ...]:
        return (self.transmission.label,) if self.transmission.label else ()

    def unit(self, order: int) -> Unit:
        texts = [self.position, self.velocity, self.acceleration, self.jerk]
        text = texts[order]
        if text is None:
            base = self.unit(order - 1).text
            text = f"{base}/s" if order == 1 or "/" not in base else (
                base + "^2" if order == 2 and base.endswith("/s") else base + "/s")
            if order == 3 and base.endswith("/s^2"):
                text = base[:-1] + "3"
        return parse_unit(text, order, self.labels, self.source)

    @property
    def units(self) -> tuple[Unit, Unit, Unit, Unit]:
        return self.unit(0), self.unit(1), self.unit(2), self.unit(3)

    # --- mechanics -----------------------------------------------------------------------------------
    @property
    def travel_per_motor_rev(self) -> Exact:
        """Load travel per motor revolution (metres, load revolutions or label units)."""
        if self.transmission.kind == "label":
            return self.transmission.travel
        return self.transmission.travel / self.gear.ratio

    @property
    def counts_per_motor_rev(self) -> Exact:
        """Feedback increments per motor revolution (exact; symbolic in pi for a scale on a pulley axis)."""
        fb = self.feedback
        if fb.resolution is not None:
            if self.transmission.output != "length":
                raise InputError("a linear scale needs a linear transmission", self.source)
            return self.travel_per_motor_rev / fb.resolution
        assert fb.counts_per_rev is not None
        if fb.on == "load" and self.transmission.kind not in ("linear_motor", "label"):
            return Exact(fb.counts_per_rev) / self.gear.ratio
        return Exact(fb.counts_per_rev)

    def internal_per_unit(self, unit: Unit, internal_per_motor_rev: Exact) -> Exact:
        """Internal position units per one ``unit`` of position (the velocity/acceleration time part excluded)."""
        pos = unit.position
        if pos.kind == "counts":
            return Exact(Fraction(1)) * pos.size
        out = self.transmission.output
        if pos.kind == "angle" and (out != "angle"):
            # an angle on a linear axis is an angle of the motor shaft (e.g. motor rpm)
            return internal_per_motor_rev * pos.size
        if pos.kind != out:
            raise InputError(
                f"unit {unit.text!r} is {_article(pos.kind)} but the {self.transmission.kind} axis moves its load as "
                f"{_article(out)}; choose {_article(out)} unit", self.source)
        return internal_per_motor_rev * pos.size / self.travel_per_motor_rev

    def with_(self, **changes: Any) -> "Axis":
        return replace(self, **changes)


# --- the shape of a spec (a spec file, a project drive's scaling: section) ---------------------------------

#: a spec's mappings take only their own keys (the project schema says so; :func:`axis_from_dict` reports others)
_SPEC_CONFIG = ConfigDict(extra="forbid")
#: a number as a spec writes it: an integer, a decimal, or a string read exactly (``"12.7"``, ``"1/3"``)
Number = Union[int, float, str]
#: a length or a time with its unit (``5 mm``, ``1 ms``)
Quantity = str


@with_config(_SPEC_CONFIG)
class FeedbackSection(TypedDict, total=False):
    """``feedback:``: the position sensor, one of counts_per_rev, lines, steps (+ microsteps) or resolution."""

    counts_per_rev: Annotated[Number, Field(description="Encoder counts per revolution")]
    lines: Annotated[Number, Field(description="Encoder lines per revolution (4 counts per line)")]
    steps: Annotated[Number, Field(description="Stepper full steps per revolution")]
    microsteps: Annotated[Number, Field(description="Microsteps per full step (with steps)")]
    resolution: Annotated[Quantity, Field(description="Linear scale resolution, with its unit (1 um)")]
    on: Annotated[Literal["motor", "load"], Field(description="Where the sensor sits (default motor)")]


@with_config(_SPEC_CONFIG)
class GearSection(TypedDict, total=False):
    """``gear:`` as a mapping: motor revolutions per load (driving shaft) revolutions."""

    motor: Number
    load: Number


@with_config(_SPEC_CONFIG)
class TransmissionSection(TypedDict, total=False):
    """``transmission:``: the mechanics from the driving shaft to the load (docs/scaling.md, Transmissions)."""

    type: Annotated[str, Field(description="rotary, ballscrew, hollow_shaft, belt, rack, linear_motor or label")]
    pitch: Quantity
    lead: Quantity
    driving_teeth: Number
    driven_teeth: Number
    driving_diameter: Quantity
    driven_diameter: Quantity
    teeth: Number
    tooth_pitch: Quantity
    module: Quantity
    diameter: Quantity
    pitch_diameter: Quantity
    pulley_diameter: Quantity
    pole_pitch: Quantity
    name: str
    units: Number
    motor_revs: Number


@with_config(_SPEC_CONFIG)
class UnitsSection(TypedDict, total=False):
    """``units:``: the user units (docs/scaling.md: ``mm``, ``deg``, ``mm/s`` …)."""

    position: str
    velocity: str
    acceleration: str
    jerk: str
    time: Annotated[str, Field(description="Time unit of the obsolete 2071h factor (s, ms, us, min)")]


@with_config(_SPEC_CONFIG)
class ScalingSection(TypedDict, total=False):
    """A scaling spec: mechanics and units for the factor group (docs/scaling.md, "The spec file")."""

    name: str
    family: Annotated[str, Field(description="technosoft-ipos, hdt, controltechniques or generic "
                                             "(default: the device's)")]
    firmware: Annotated[Union[str, int], Field(description="Technosoft firmware (before F515K: the obsolete "
                                                           "factor objects)")]
    feedback: Annotated[Union[Number, FeedbackSection], Field(description="The position sensor (a number: counts "
                                                                          "per revolution)")]
    gear: Annotated[Union[Number, GearSection, None], Field(description="Motor : load revolutions (\"3:1\" or "
                                                                        "{motor: 3, load: 1})")]
    transmission: Annotated[Union[str, TransmissionSection, None],
                            Field(description="Mechanics (a mapping, or 'ballscrew pitch=5mm')")]
    units: UnitsSection
    slow_loop: Annotated[Union[Quantity, Number], Field(description="Technosoft slow loop period (1 ms)")]
    polarity: Annotated[Literal["normal", "reversed", "reverse", "inverted"],
                        Field(description="reversed: 607Eh = 0xC0")]
    reverse: bool
    approximation: Annotated[Literal["best", "max-scale"], Field(description="Technosoft default max-scale, "
                                                                              "others best")]
    vl_setpoint: Annotated[Union[str, int], Field(description="Control Techniques 604Bh ratio (1/1)")]
    device: Annotated[str, Field(description="Accepted for spec files that name their device; not read")]


#: the keys a spec may have (:class:`ScalingSection`): any other is an error naming the nearest
SPEC_KEYS = frozenset(ScalingSection.__annotations__)


# --- loading from a mapping (YAML spec files, CLI options) ---------------------------------------------


#: where the value at a path of a spec mapping is (``("transmission", "pitch")`` → file:line:column), for errors
Locate = Callable[[tuple[str, ...]], Location | None]


def _loc(locate: Locate | None, *path: str) -> Location | None:
    return locate(path) if locate else None


def feedback_from(data: Number | FeedbackSection, locate: Locate | None = None) -> Feedback:
    loc = _loc(locate, "feedback")
    if isinstance(data, (int, str)) and not isinstance(data, bool):
        return Feedback.encoder(_frac(data, "feedback counts_per_rev", loc, lo=Fraction(1), hi=Fraction(MAX_COUNTS)))
    if not isinstance(data, dict):
        raise InputError("feedback must be a mapping (counts_per_rev, lines, steps/microsteps or resolution)", loc)
    on = str(data.get("on", "motor"))
    if on not in ("motor", "load"):
        raise InputError(f"feedback 'on' must be motor or load, got {on!r}", _loc(locate, "feedback", "on"))
    if "counts_per_rev" in data:
        return Feedback.encoder(_frac(data["counts_per_rev"], "counts_per_rev", _loc(locate, "feedback", "counts_per_rev"),
                                      lo=Fraction(1), hi=Fraction(MAX_COUNTS)), on)
    if "lines" in data:  # four counts per line: 4 x lines within UNSIGNED32
        return Feedback.lines(_integer(data["lines"], "encoder lines", _loc(locate, "feedback", "lines"),
                                       MAX_COUNTS // 4), on)
    if "steps" in data:
        steps = _integer(data["steps"], "steps", _loc(locate, "feedback", "steps"), 2**16)
        micro = _integer(data.get("microsteps", 1), "microsteps", _loc(locate, "feedback", "microsteps"), 2**16)
        return Feedback.stepper(steps, micro)
    if "resolution" in data:
        return Feedback.linear_scale(_length(data["resolution"], "resolution", _loc(locate, "feedback", "resolution")))
    raise InputError("feedback needs counts_per_rev, lines, steps (+ microsteps) or resolution (linear scale)", loc)


def gear_from(data: Number | GearSection | None, locate: Locate | None = None) -> Gear:
    loc = _loc(locate, "gear")
    if data is None:
        return Gear()
    if isinstance(data, str) and ":" in data:
        a, b = data.split(":", 1)
        return Gear(_frac(a, "gear motor revolutions", loc), _frac(b, "gear load revolutions", loc))
    if isinstance(data, dict):
        return Gear(_frac(data.get("motor", 1), "gear motor", _loc(locate, "gear", "motor")),
                    _frac(data.get("load", 1), "gear load", _loc(locate, "gear", "load")))
    return Gear(_frac(data, "gear ratio", loc))


def transmission_from(section: str | TransmissionSection | None, locate: Locate | None = None,
                      meant: str | None = None) -> Transmission:
    """The transmission of a spec mapping or a ``type key=value …`` string. Every length needs its unit; an error
    for a bare number suggests ``meant`` (the axis's length unit), else mm."""
    loc = _loc(locate, "transmission")
    if section is None:
        return Transmission.rotary()
    data: Mapping[str, object] = parse_kv(section, loc) if isinstance(section, str) else section
    if not isinstance(data, dict):
        raise InputError("transmission must be a mapping with a 'type'", loc)
    kind = str(data.get("type", "rotary")).replace("-", "_").replace(" ", "_").lower()
    kind = {"ball_screw": "ballscrew", "screw": "ballscrew", "leadscrew": "ballscrew", "lead_screw": "ballscrew",
            "pulley": "belt", "conveyor": "belt", "rack_and_pinion": "rack", "rotary_table": "rotary", "disk": "rotary",
            "linear": "linear_motor", "hollow": "hollow_shaft", "custom_label": "label"}.get(kind, kind)

    def q(key: str) -> Exact:
        return _length(data[key], key, _loc(locate, "transmission", key), meant)

    def n(key: str, default: object = None) -> Fraction:
        return _frac(data.get(key, default), key, _loc(locate, "transmission", key))

    if kind == "rotary":
        if "driving_teeth" in data or "driven_teeth" in data:
            return Transmission.rotary(n("driving_teeth", 1), n("driven_teeth", 1))
        if "driving_diameter" in data or "driven_diameter" in data:
            return Transmission.rotary(q("driving_diameter").coef, q("driven_diameter").coef)
        return Transmission.rotary()
    if kind in ("ballscrew", "hollow_shaft"):
        if "pitch" not in data and "lead" not in data:
            raise InputError(f"{kind} needs pitch (e.g. pitch: 5 mm)", loc)
        pitch = q("pitch" if "pitch" in data else "lead")
        return Transmission.ballscrew(pitch) if kind == "ballscrew" else Transmission.hollow_shaft(pitch)
    if kind in ("belt", "rack"):
        if "teeth" in data and ("tooth_pitch" in data or "module" in data):
            teeth = _integer(data["teeth"], "teeth", _loc(locate, "transmission", "teeth"), 10**6)
            pitch = q("tooth_pitch") if "tooth_pitch" in data else q("module") * Exact(Fraction(1), 1)
            return (Transmission.belt_teeth if kind == "belt" else Transmission.rack_teeth)(int(teeth), pitch)
        key = next((k for k in ("diameter", "pitch_diameter", "pulley_diameter") if k in data), None)
        if key is None:
            raise InputError(f"{kind} needs teeth + tooth_pitch (or module), or diameter", loc)
        d = q(key)
        return Transmission.belt_diameter(d) if kind == "belt" else Transmission.rack_diameter(d)
    if kind == "linear_motor":
        if "pole_pitch" not in data:
            raise InputError("linear_motor needs pole_pitch (e.g. pole_pitch: 32 mm)", loc)
        return Transmission.linear_motor(q("pole_pitch"))
    if kind == "label":
        name = str(data.get("name", "unit"))
        return Transmission.custom_label(name, n("units"), n("motor_revs", 1))
    raise InputError(f"unknown transmission type {kind!r} (one of {', '.join(TRANSMISSIONS)})", _loc(locate, "transmission", "type"))


def parse_kv(text: str, location: Location | None = None) -> dict[str, str]:
    """``ballscrew pitch=5mm`` / ``belt teeth=20 tooth_pitch=5mm`` → {'type': ..., key: value}."""
    parts = text.replace(",", " ").split()
    if not parts:
        raise InputError("empty transmission", location)
    out: dict[str, str] = {}
    start = 0
    if "=" not in parts[0]:
        out["type"] = parts[0]
        start = 1
    for p in parts[start:]:
        if "=" not in p:
            raise InputError(f"{p!r}: write key=value (e.g. pitch=5mm)", location)
        k, v = p.split("=", 1)
        out[k.strip()] = v.strip()
    return out


def axis_from_dict(data: ScalingSection, locate: Locate | None = None, source: Location | None = None) -> Axis:
    """Build an :class:`Axis` from a spec mapping (see docs/scaling.md); ``locate(path)`` gives locations."""
    if not isinstance(data, dict):
        raise InputError("a scaling spec must be a mapping", source)
    known = SPEC_KEYS
    for key in data:
        if key not in known:
            hint = did_you_mean(str(key), known) or f" (expected one of {', '.join(sorted(known))})"
            raise InputError(f"unknown key {key!r}{hint}", _loc(locate, key) or source)
    if "feedback" not in data:
        raise InputError("spec needs 'feedback' (e.g. feedback: {lines: 500})", source)
    units = data.get("units") or {}
    if not isinstance(units, dict):
        raise InputError("units must be a mapping (position, velocity, acceleration, jerk, time)", _loc(locate, "units"))
    slow = data.get("slow_loop", "1ms")
    polarity = str(data.get("polarity", "normal")).lower()
    if polarity not in ("normal", "reversed", "reverse", "inverted"):
        raise InputError(f"polarity must be normal or reversed, got {polarity!r}", _loc(locate, "polarity"))
    axis = Axis(
        feedback=feedback_from(data["feedback"], locate),
        transmission=transmission_from(data.get("transmission"), locate, length_unit(units.get("position"))),
        gear=gear_from(data.get("gear"), locate),
        position=str(units.get("position", "rev")),
        velocity=None if units.get("velocity") is None else str(units["velocity"]),
        acceleration=None if units.get("acceleration") is None else str(units["acceleration"]),
        jerk=None if units.get("jerk") is None else str(units["jerk"]),
        time=_time_unit(units.get("time", "ms"), _loc(locate, "units", "time") or source),
        slow_loop=slow_loop_from(slow, _loc(locate, "slow_loop")),
        reverse=polarity != "normal" or bool(data.get("reverse", False)),
        name=str(data.get("name", "")),
        source=source,
    )
    for order, key in enumerate(("position", "velocity", "acceleration", "jerk")):
        try:
            axis.unit(order)
        except InputError as exc:
            raise InputError(exc.message, _loc(locate, "units", key) or source) from None
    return axis


def _time_unit(value: object, location: Location | None) -> str:
    """The time unit of the obsolete 2071h factor: a unit name (ms, s, us, min), checked where it is read."""
    text = str(value).strip()
    if isinstance(value, bool) or not text.isalpha():
        raise InputError(f"units time must be a time unit (s, ms, us, min), got {str(value)[:40]!r}", location)
    time_seconds("1" + text, location)  # an unknown name is refused here, not when the factor is computed
    return text


def slow_loop_from(value: object, location: Location | None = None) -> Fraction:
    """The slow-loop period (``1ms``, ``250 us``), within :data:`MIN_SLOW_LOOP` .. :data:`MAX_SLOW_LOOP`."""
    if isinstance(value, bool):
        raise InputError(f"slow_loop must be a time, not {str(value).lower()}", location)
    check_exponent(value, location, "slow_loop")
    t = time_seconds(value, location)
    _bounded(t, value, "slow_loop", location, MIN_SLOW_LOOP, MAX_SLOW_LOOP, " s")
    return t


def length_unit(text: object) -> str | None:
    """The name of ``text`` when it is a length unit (``inch``, ``mm``): what a bare length probably meant."""
    try:
        unit = parse_unit(str(text), order=0) if text is not None else None
    except InputError:
        return None
    return unit.position.name if unit is not None and unit.kind == "length" else None


def _article(kind: str) -> str:
    return ("an " if kind[:1] in "aeiou" else "a ") + kind
