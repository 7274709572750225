"""Units as engineers write them (``mm``, ``um``, ``deg``, ``rad``, ``rev``, ``inch``, ``mm/s``, ``rpm``,
``deg/s^2`` …), an exact table, the CiA-303-2 SI unit words of objects 60A8h–60ABh, and the obsolete
CiA-402 dimension/notation indices (Technosoft manual, Appendix B).

A position unit has a *kind* — ``length`` (base: metre), ``angle`` (base: revolution), ``counts`` (the
drive's internal increments or microsteps) or ``label`` (a user-defined unit, e.g. bottles) — and a size in
its base. Velocity, acceleration and jerk units are a position unit divided by time to the power 1, 2, 3.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from fractions import Fraction

from ecattool.errors import InputError, Location
from ecattool.scaling.exact import Exact

_REV = Exact(Fraction(1))
_RAD = Exact(Fraction(1, 2), -1)  # 1 rad = 1/(2*pi) rev

#: position units: name -> (kind, size in the kind's base unit, SI numerator notation index or None)
_POSITION: dict[str, tuple[str, Exact, int | None]] = {
    "m": ("length", Exact(Fraction(1)), 0x01),
    "inch": ("length", Exact(Fraction(254, 10000)), None),
    "mil": ("length", Exact(Fraction(254, 10000000)), None),
    "ft": ("length", Exact(Fraction(3048, 10000)), None),
    "rad": ("angle", _RAD, 0x10),
    "deg": ("angle", Exact(Fraction(1, 360)), 0x41),
    "arcmin": ("angle", Exact(Fraction(1, 360 * 60)), None),
    "arcsec": ("angle", Exact(Fraction(1, 360 * 3600)), None),
    "gon": ("angle", Exact(Fraction(1, 400)), None),
    "rev": ("angle", _REV, 0xB4),
    "inc": ("counts", Exact(Fraction(1)), 0xB5),
    "step": ("counts", Exact(Fraction(1)), 0xAC),
}
_ALIASES = {
    "in": "inch", "inches": "inch", '"': "inch", "thou": "mil", "mils": "mil", "feet": "ft",
    "degree": "deg", "degrees": "deg", "°": "deg", "radian": "rad", "radians": "rad",
    "rot": "rev", "revs": "rev", "revolution": "rev", "revolutions": "rev", "turn": "rev", "turns": "rev", "r": "rev",
    "count": "inc", "counts": "inc", "cnt": "inc", "increments": "inc", "increment": "inc", "iu": "inc", "pulses": "inc",
    "steps": "step", "usteps": "step", "ustep": "step", "µstep": "step", "microsteps": "step", "microstep": "step",
    "metre": "m", "meter": "m", "grad": "gon", "newdegree": "gon",
}
#: SI prefixes accepted before m and rad (CiA-303-2 writes the exponent as a signed byte)
_PREFIX = {"k": 3, "c": -2, "d": -1, "m": -3, "u": -6, "µ": -6, "μ": -6, "n": -9}
_PREFIX_NAME = {3: "k", 0: "", -1: "d", -2: "c", -3: "m", -6: "µ", -9: "n", 6: "M", 9: "G", 2: "h", 1: "da", -12: "p"}
#: time units in seconds
_TIME = {"s": Fraction(1), "sec": Fraction(1), "ms": Fraction(1, 1000), "us": Fraction(1, 10**6),
         "µs": Fraction(1, 10**6), "min": Fraction(60), "h": Fraction(3600), "d": Fraction(86400)}
#: SI denominator notation indices (Technosoft Table 5.5): s, min, s², s³
_SI_DEN = {("s", 1): 0x03, ("min", 1): 0x47, ("s", 2): 0x57, ("s", 3): 0xA0}
_SI_NUM_NAME = {0x00: "", 0x01: "m", 0x10: "rad", 0x41: "deg", 0xB4: "rot", 0xB5: "inc", 0xAC: "step"}
_SI_DEN_NAME = {0x00: "", 0x01: "", 0x03: "/s", 0x47: "/min", 0x57: "/s²", 0xA0: "/s³"}


@dataclass(frozen=True, slots=True)
class PositionUnit:
    name: str  # canonical text, e.g. "mm", "deg", "bottle"
    kind: str  # "length" | "angle" | "counts" | "label"
    size: Exact  # in metres, revolutions, counts or label units
    si_prefix: int | None = None  # exponent when the SI word can say it
    si_numerator: int | None = None


@dataclass(frozen=True, slots=True)
class Unit:
    """A position unit divided by ``time_s`` seconds to the power ``order`` (0 position, 1 velocity …)."""

    text: str
    position: PositionUnit
    order: int = 0
    time_s: Fraction = Fraction(1)  # e.g. rpm: 60 (order 1); rpm/s: 60 (order 2: 60 s * 1 s)
    time_tokens: tuple[tuple[str, int], ...] = ()

    @property
    def kind(self) -> str:
        return self.position.kind

    def si_word(self) -> int | None:
        """The CiA-303-2 SI unit word (60A8h–60ABh layout) or None if the unit has no such encoding."""
        p = self.position
        if p.si_numerator is None or p.si_prefix is None:
            return None
        if self.order == 0:
            den = 0x01
        else:
            if len(self.time_tokens) != 1:
                return None
            time_den = _SI_DEN.get(self.time_tokens[0])
            if time_den is None:
                return None
            den = time_den
        return ((p.si_prefix & 0xFF) << 24) | (p.si_numerator << 16) | (den << 8)

    def __str__(self) -> str:
        return self.text


def _position_unit(token: str, labels: tuple[str, ...], location: Location | None) -> PositionUnit:
    t = token.strip()
    if t in labels:
        return PositionUnit(t, "label", Exact(Fraction(1)))
    low = _ALIASES.get(t.lower(), t.lower())
    if low in _POSITION:
        kind, size, si = _POSITION[low]
        return PositionUnit(low, kind, size, 0 if si is not None else None, si)
    for pre, exp in _PREFIX.items():
        if low.startswith(pre) and low[len(pre):] in ("m", "rad") and len(low) > len(pre):
            base = low[len(pre):]
            kind, size, si = _POSITION[base]
            canon = ("µ" if exp == -6 else pre) + base
            return PositionUnit(canon, kind, size * Exact(Fraction(10) ** exp), exp, si)
    raise InputError(
        f"unknown position unit {token!r} (use m, mm, um, nm, inch, mil, deg, rad, mrad, rev, counts, steps"
        + (", " + ", ".join(labels) if labels else "") + ")",
        location,
    )


_SHORTHANDS = {"rpm": "rev/min", "rps": "rev/s", "rpm/s": "rev/min/s", "rps/s": "rev/s/s", "rpm/s^2": "rev/min/s^2",
               "rps2": "rev/s^2", "rpm/s/s": "rev/min/s/s"}


def parse_unit(text: str, order: int | None = None, labels: tuple[str, ...] = (), location: Location | None = None) -> Unit:
    """Parse ``mm``, ``deg/s^2``, ``rpm``, ``rpm/s``, ``mm/s²``, ``inch/min``, ``bottle/min`` …

    ``order`` (0 position, 1 velocity, 2 acceleration, 3 jerk) is checked when given.
    """
    raw = str(text).strip()
    s = raw.replace("²", "^2").replace("³", "^3").replace(" ", "").replace("**", "^")
    s = re.sub(r"(?i)^rpm", "rev/min", s) if s.lower().startswith("rpm") else s
    s = re.sub(r"(?i)^rps", "rev/s", s) if s.lower().startswith("rps") else s
    s = _SHORTHANDS.get(s, s)
    parts = s.split("/")
    if not parts[0]:
        raise InputError(f"unit {raw!r} has no position part (write e.g. mm/s)", location)
    pos = _position_unit(parts[0], labels, location)
    tokens: list[tuple[str, int]] = []
    seconds = Fraction(1)
    total = 0
    for part in parts[1:]:
        m = re.fullmatch(r"([a-zA-Zµ]+)(?:\^?([123]))?", part)
        name = m.group(1) if m else ""
        if not m or name not in _TIME:
            raise InputError(f"unit {raw!r}: {part!r} is not a time unit (s, ms, us, min, h, with ^2 or ^3)", location)
        power = int(m.group(2) or 1)
        name = "s" if name == "sec" else name
        tokens.append((name, power))
        seconds *= _TIME[name] ** power
        total += power
    if order is not None and total != order:
        what = ("a position", "a velocity", "an acceleration", "a jerk")[order] if order < 4 else "a"
        raise InputError(f"unit {raw!r} is not {what} unit (it divides by time^{total}, needs ^{order})", location)
    merged: dict[str, int] = {}
    for name, power in tokens:
        merged[name] = merged.get(name, 0) + power
    return Unit(raw, pos, total, seconds, tuple(merged.items()))


# --- SI unit words (60A8h–60ABh) ---------------------------------------------------------------------


def encode_si_unit(unit: str | Unit, location: Location | None = None) -> int:
    """The SI unit word of ``unit``: prefix<<24 | numerator<<16 | denominator<<8 (mm → 0xFD010100)."""
    u = parse_unit(unit, location=location) if isinstance(unit, str) else unit
    word = u.si_word()
    if word is None:
        raise InputError(f"unit {u.text!r} has no CiA-303-2 SI notation (prefix + m/rad/deg/rot/inc/step over s, min, s², s³)", location)
    return word


def decode_si_unit(word: int) -> str:
    """Text of any SI unit word: 0xFD010100 → 'mm', 0x00B44700 → 'rot/min', 0x00B50100 → 'inc'."""
    if isinstance(word, bool) or not 0 <= word <= 0xFFFFFFFF:  # 60A8h..60ABh are UNSIGNED32: never wrapped
        raise InputError(f"SI unit word {word:#x} does not fit UNSIGNED32 (0..0xFFFFFFFF)")
    prefix = (word >> 24) & 0xFF
    exp = prefix - 256 if prefix >= 128 else prefix
    num = (word >> 16) & 0xFF
    den = (word >> 8) & 0xFF
    if word == 0:
        return "(none)"
    pre = _PREFIX_NAME.get(exp, f"10^{exp} ")
    num_name = _SI_NUM_NAME.get(num, f"<unit 0x{num:02X}>")
    den_name = _SI_DEN_NAME.get(den, f"/<unit 0x{den:02X}>")
    text = f"{pre}{num_name}{den_name}" if num_name else (f"{pre}{den_name}" if (pre or den_name) else "dimensionless")
    if word & 0xFF:
        text += f" (profile-specific 0x{word & 0xFF:02X})"
    return text or "dimensionless"


# --- obsolete CiA-402 dimension / notation indices (Technosoft Appendix B) -----------------------------

#: (kind, order, canonical unit) -> (dimension index, notation index)
_APPENDIX_B: dict[tuple[str, int, str], tuple[int, int]] = {
    ("length", 0, "m"): (1, 0), ("length", 0, "mm"): (1, -3), ("length", 0, "km"): (1, 3), ("length", 0, "µm"): (1, -6),
    ("angle", 0, "rad"): (12, 0), ("angle", 0, "arcsec"): (12, 75), ("angle", 0, "arcmin"): (12, 76),
    ("angle", 0, "deg"): (12, 77), ("angle", 0, "gon"): (12, 78),
    ("length", 1, "m/s"): (13, 0), ("length", 1, "mm/s"): (13, -3), ("length", 1, "mm/min"): (13, 79),
    ("length", 1, "m/min"): (13, 80), ("length", 1, "km/min"): (13, 81), ("length", 1, "mm/h"): (13, 82),
    ("length", 1, "m/h"): (13, 83), ("length", 1, "km/h"): (13, 84),
    ("angle", 1, "rev/s"): (11, 0), ("angle", 1, "rev/min"): (11, 73), ("angle", 1, "rev/h"): (11, 74),
    ("time", 0, "s"): (4, 0), ("time", 0, "min"): (4, 70), ("time", 0, "h"): (4, 74), ("time", 0, "ms"): (4, -3),
    ("time", 0, "us"): (4, -6), ("time", 0, "µs"): (4, -6), ("time", 0, "d"): (4, 77),
}
#: what ecattool writes for a custom unit: the manual says "set it to 1 instead of 0" (docs/decisions.md)
CUSTOM_INDEX = (1, 1)


def dimension_notation(unit: Unit | str) -> tuple[int, int, bool]:
    """(dimension index, notation index, listed) of a unit in Appendix B; custom units get (1, 1, False)."""
    if isinstance(unit, str):  # a time unit
        key = ("time", 0, unit)
    else:
        canon = unit.position.name + "".join(f"/{n}" + (f"^{p}" if p > 1 else "") for n, p in unit.time_tokens)
        key = (unit.kind, unit.order, canon)
    if key in _APPENDIX_B:
        d, n = _APPENDIX_B[key]
        return d, n, True
    return CUSTOM_INDEX[0], CUSTOM_INDEX[1], False


_NICE = {"d": "day", "h": "hour", "min": "minute", "arcmin": "minute (angle)", "arcsec": "second (angle)",
         "deg": "degree", "gon": "newdegree (gon)", "rev/min": "rpm", "rev/s": "rev/s"}


def describe_dimension(dimension: int, notation: int) -> str:
    """Text of an Appendix B dimension/notation pair (e.g. 1, -6 → 'µm')."""
    for (kind, order, canon), (d, n) in _APPENDIX_B.items():
        if d == dimension and n == notation:
            return _NICE.get(canon, canon)
    names = {0: "dimensionless", 1: "m", 2: "m²", 3: "m³", 4: "s", 9: "W", 10: "VA", 11: "rev/s", 12: "rad", 13: "m/s",
             16: "Nm", 17: "K", 21: "V", 22: "A", 24: "%", 28: "Hz", 32: "steps", 33: "steps/rev"}
    base = names.get(dimension, f"dimension {dimension}")
    if notation == 0:
        return base
    if notation < 64:
        pre = _PREFIX_NAME.get(notation)
        return f"{pre}{base}" if pre is not None and " " not in base else f"10^{notation} {base}"
    return f"{base} (notation {notation})"


def time_seconds(text: object, location: Location | None = None) -> Fraction:
    """``1 ms``, ``0.5ms``, ``250 us``, ``0.001`` (seconds) → seconds as a Fraction."""
    s = str(text).strip().replace(" ", "")
    m = re.fullmatch(r"([0-9]*\.?[0-9]+(?:[eE]-?[0-9]+)?)([a-zµ]*)", s)
    if not m or (m.group(2) and m.group(2) not in _TIME):
        raise InputError(f"{text!r} is not a time (write 1ms, 250us, 0.001s)", location)
    value = Fraction(m.group(1)) * _TIME[m.group(2) or "s"]
    if value <= 0:
        raise InputError(f"time {text!r} must be positive", location)
    return value


def quantity(text: object, kinds: tuple[str, ...] = ("length",), location: Location | None = None,
             what: str = "", meant: str | None = None) -> tuple[Exact, str]:
    """``5 mm``, ``0.2 inch``, ``12.5mm``, ``30 deg`` → (size in the kind's base, kind). Numbers are read exactly.

    A number without a unit is an error that names ``what`` it is and shows it with the unit it probably meant
    (``meant``: the axis's own length unit where there is one, else mm; deg for an angle)."""
    s = str(text).strip()
    m = re.fullmatch(r"([0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*(.*)", s)
    if not m:
        raise InputError(f"{text!r} is not a quantity (write e.g. 5 mm)", location)
    number = Fraction(m.group(1))
    if not m.group(2):  # a bare number is not silently millimetres (nor inches on an inch axis): ask for the unit
        meant = meant or ("mm" if "length" in kinds else "deg")
        raise InputError(f"{what + ' ' if what else ''}{s} has no unit: a {' or '.join(kinds)} needs one "
                         f"(did you mean {s} {meant}?)", location)
    unit_text = m.group(2)
    unit = parse_unit(unit_text, order=0, location=location)
    if unit.kind not in kinds:
        raise InputError(f"{text!r}: expected a {' or '.join(kinds)}, got {unit.kind}", location)
    return unit.position.size * number, unit.kind
