"""User units <-> internal units, the way each drive family's firmware converts them.

This module is the simulator's own reading of the manuals (it does not use ``ecattool.scaling``, which
computes factor groups for the user): the drive reads its factor objects from its dictionary and converts
every target value written by the master into internal units, and every actual value back.

* Technosoft iPOS, CiA-402-2 firmware (F515K / FA0xx and newer, §5.2): the drive applies the *encoder*
  factors 6093h (position IU / PU), 6094h (velocity IU / VU) and 210Fh (acceleration IU / AU).  Internal
  velocity is 16.16 fixed point increments per slow-loop sample, acceleration 16.16 increments per sample².
  :meth:`TechnosoftUnits.derived_factors` computes what those encoder factors must be from 608Fh, 6091h,
  6092h, 6096h, 6097h and the slow-loop period T (IU_vel = VU·PF/VF·T·2^16, IU_acc = AU·VEF/AF·T).
* Technosoft before F515K (§5.1): obsolete 6093h/6094h/6097h numerator/divisor pairs, each active only
  while its dimension index (608Ah/608Ch/608Eh) is non-zero (decision in docs/decisions.md).
* HDT: 65536 counts per motor revolution; counts = user × 6093h.1 / 6093h.2; counts/s = v × 6094h.1 /
  6094h.2; counts/s² = a × 6097h.1 / 6097h.2.
* Control Techniques and generic CiA-402: increments per user unit = 608Fh·6091h / 6092h (CiA-402 formula,
  default 1); velocities are position units per second.

Internal values are exact :class:`fractions.Fraction`; the drive truncates towards minus infinity when it
stores an integer (``floor``), as the Technosoft IU examples do (0x28F for 655.36). The process data cycle
computes with the same rationals carried as integer numerator and denominator (:meth:`Units.ratios`,
:func:`floor_ratio`): the same values and the same floor, without a ``Fraction`` object per operation.
"""

from __future__ import annotations

from collections.abc import Callable
from fractions import Fraction
from math import floor, gcd

#: reads (index, subindex) from the drive's dictionary as an integer, or None when the entry is missing
Reader = Callable[[int, int], int | None]

#: what the cyclic conversions multiply by, as integers (numerator, denominator > 0): the position factor, the
#: velocity factor, and increments per second per internal velocity unit (see :meth:`Units.ratios`)
Ratios = tuple[int, int, int, int, int, int]

#: every object a conversion factor (or the cycle, 60C2h) is derived from: a write to one of them changes the
#: store's version, so the factors are computed once per change instead of on every cycle
FACTOR_OBJECTS = frozenset({0x608A, 0x608C, 0x608E, 0x608F, 0x6091, 0x6092, 0x6093, 0x6094, 0x6096, 0x6097,
                            0x210F, 0x60C2})


def _ratio(read: Reader, index: int, default: Fraction = Fraction(1)) -> Fraction:
    """num/den of a factor pair; ``default`` where the drive lacks it or both parts are 0 (not configured); a
    0 denominator beside a non-zero numerator makes the factor 0, as a 0 numerator does (no motion)."""
    num, den = read(index, 1), read(index, 2)
    if num is None or den is None or (num == 0 and den == 0):
        return default
    if den == 0:
        return Fraction(0)
    return Fraction(num, den)


def _div(a: Fraction, b: Fraction) -> Fraction:
    """a / b, 0 where b is 0 (a factor pair with a 0 part: nothing converts)."""
    return a / b if b else Fraction(0)


class Units:
    """Generic CiA-402 (and Control Techniques): increments per user unit = 608Fh × 6091h / 6092h; velocities
    and accelerations through 6096h and 6097h where the drive has them."""

    #: physical meaning of one internal velocity unit, in increments per second
    family = "generic"

    def __init__(self, read: Reader, cycle_s: Fraction = Fraction(1, 1000)) -> None:
        self.read = read
        self.cycle_s = cycle_s
        #: where set, a number that changes whenever an object of FACTOR_OBJECTS changes (the drive's store)
        self.version: Callable[[], int] | None = None
        self._cache: dict[str, Fraction] = {}
        self._cached_version = -1
        self._ratios: tuple[int, Ratios] | None = None

    def _factor(self, name: str) -> Fraction:
        """``position_factor()`` & co. by name, computed once per version of the factor objects."""
        if self.version is None:
            return getattr(self, name)()  # type: ignore[no-any-return]
        v = self.version()
        if v != self._cached_version:
            self._cache.clear()
            self._cached_version = v
        f = self._cache.get(name)
        if f is None:
            f = self._cache[name] = getattr(self, name)()
        return f

    def ratios(self) -> Ratios:
        """(position factor num, den, velocity factor num, den, increments/s per internal velocity unit num,
        den), each denominator > 0: what the process data cycle converts by in integers, computed once per
        version of the factor objects. The last pair is ``increments_per_second(1)``: every family's
        conversion of internal velocity is a multiplication by a constant (and its inverse the division)."""
        v = self.version() if self.version is not None else None
        cached = self._ratios
        if cached is not None and v is not None and cached[0] == v:
            return cached[1]
        pf, vf = self._factor("position_factor"), self._factor("velocity_factor")
        speed = Fraction(self.increments_per_second(Fraction(1)))
        out = (pf.numerator, pf.denominator, vf.numerator, vf.denominator, speed.numerator, speed.denominator)
        if v is not None:
            self._ratios = (v, out)
        return out

    # --- factors (internal units per user unit) -----------------------------------------------
    def position_factor(self) -> Fraction:
        if self.read(0x6093, 1) is not None and self.read(0x608F, 1) is None:
            return _ratio(self.read, 0x6093)
        enc = _ratio(self.read, 0x608F)
        gear = _ratio(self.read, 0x6091)
        feed = _ratio(self.read, 0x6092)
        return enc * gear / feed if feed else Fraction(0)  # a feed of 0 per revolution: no position converts

    def velocity_factor(self) -> Fraction:
        """Position units per second per velocity unit: 6096h is velocity units per (position unit/s),
        1 where the drive has no 6096h (Control Techniques, Inovance)."""
        return _div(self.position_factor(), _ratio(self.read, 0x6096))

    def acceleration_factor(self) -> Fraction:
        """6097h is acceleration units per (velocity unit/s), 1 where the drive has none."""
        return _div(self.velocity_factor(), _ratio(self.read, 0x6097))

    # --- conversions --------------------------------------------------------------------------
    def position_to_internal(self, user: int | Fraction) -> Fraction:
        return self._factor("position_factor") * user  # Fraction * int: no Fraction(user) made

    def position_to_user(self, internal: Fraction) -> Fraction:
        f = self._factor("position_factor")
        return internal / f if f else Fraction(0)

    def position_to_user_int(self, internal: Fraction) -> int:
        """``to_int(position_to_user(internal))`` without the intermediate fraction (every cycle)."""
        return floor_div(internal, self._factor("position_factor"))

    def velocity_to_internal(self, user: int | Fraction) -> Fraction:
        return self._factor("velocity_factor") * user  # Fraction * int: no Fraction(user) made

    def velocity_to_user(self, internal: Fraction) -> Fraction:
        f = self._factor("velocity_factor")
        return internal / f if f else Fraction(0)

    def velocity_to_user_int(self, internal: Fraction) -> int:
        """``to_int(velocity_to_user(internal))`` without the intermediate fraction (every cycle)."""
        return floor_div(internal, self._factor("velocity_factor"))

    def acceleration_to_internal(self, user: int | Fraction) -> Fraction:
        return self._factor("acceleration_factor") * user  # Fraction * int: no Fraction(user) made

    # --- physics of internal units ------------------------------------------------------------
    def increments_per_second(self, velocity_internal: Fraction) -> Fraction:
        """Internal velocity -> increments per second (generic: internal velocity is increments/s)."""
        return velocity_internal

    def velocity_from_increments_per_second(self, inc_per_s: Fraction) -> Fraction:
        return inc_per_s

    def increments_per_second2(self, acceleration_internal: Fraction) -> Fraction:
        return acceleration_internal


class HdtUnits(Units):
    """HDT: internal position 65536 pulses per motor revolution; factors 6093h/6094h/6097h as num/div."""

    family = "hdt"
    COUNTS_PER_REV = 65536

    def position_factor(self) -> Fraction:
        return _ratio(self.read, 0x6093)

    def velocity_factor(self) -> Fraction:
        return _ratio(self.read, 0x6094, Fraction(65536, 60))

    def acceleration_factor(self) -> Fraction:
        return _ratio(self.read, 0x6097, Fraction(65536, 60))


class TechnosoftUnits(Units):
    """Technosoft iPOS: IU (encoder counts), 16.16 velocity per slow-loop sample, 16.16 acceleration."""

    family = "technosoft-ipos"

    def __init__(self, read: Reader, cycle_s: Fraction = Fraction(1, 1000), *, cia402_2: bool = True,
                 slow_loop_s: Fraction = Fraction(1, 1000)) -> None:
        super().__init__(read, cycle_s)
        self.cia402_2 = cia402_2
        self.slow_loop_s = slow_loop_s

    def _obsolete_active(self, dimension_index: int) -> bool:
        v = self.read(dimension_index, 0)
        return bool(v)

    def position_factor(self) -> Fraction:
        if self.cia402_2:
            return _ratio(self.read, 0x6093)
        return _ratio(self.read, 0x6093) if self._obsolete_active(0x608A) else Fraction(1)

    def velocity_factor(self) -> Fraction:
        if self.cia402_2:
            return _ratio(self.read, 0x6094)
        return _ratio(self.read, 0x6094) if self._obsolete_active(0x608C) else Fraction(1)

    def acceleration_factor(self) -> Fraction:
        if self.cia402_2:
            return _ratio(self.read, 0x210F)
        return _ratio(self.read, 0x6097) if self._obsolete_active(0x608E) else Fraction(1)

    def increments_per_second(self, velocity_internal: Fraction) -> Fraction:
        return velocity_internal / 65536 / self.slow_loop_s

    def velocity_from_increments_per_second(self, inc_per_s: Fraction) -> Fraction:
        return inc_per_s * self.slow_loop_s * 65536

    def increments_per_second2(self, acceleration_internal: Fraction) -> Fraction:
        return acceleration_internal / 65536 / (self.slow_loop_s * self.slow_loop_s)

    def derived_factors(self) -> dict[str, Fraction]:
        """The encoder factors §5.2 derives from 608Fh/6091h/6092h/6096h/6097h and T (CiA-402-2 firmware).

        position (6093h) = 608F · 6091 / 6092; velocity (6094h) = position / 6096 · T · 2^16;
        acceleration (210Fh) = velocity / 6097 · T.
        """
        position = _div(_ratio(self.read, 0x608F) * _ratio(self.read, 0x6091), _ratio(self.read, 0x6092))
        velocity = _div(position, _ratio(self.read, 0x6096)) * self.slow_loop_s * 65536
        acceleration = _div(velocity, _ratio(self.read, 0x6097)) * self.slow_loop_s
        return {"position": position, "velocity": velocity, "acceleration": acceleration}


def to_int(value: Fraction) -> int:
    """How the drive stores a converted value: truncation towards minus infinity."""
    return floor(value)


def floor_div(value: Fraction | int, factor: Fraction) -> int:
    """``to_int(value / factor)``, 0 where the factor is 0 (as the conversions to user units), in integers."""
    return floor_ratio(value.numerator, value.denominator, factor.numerator, factor.denominator)


def floor_ratio(num: int, den: int, factor_num: int, factor_den: int) -> int:
    """``floor((num / den) / (factor_num / factor_den))`` for ``den``, ``factor_den`` > 0, and 0 where the factor
    is 0: :func:`floor_div` on integer numerators and denominators (Python's ``//`` floors for either sign)."""
    if not factor_num:
        return 0
    return (num * factor_den) // (den * factor_num)


def reduced(num: int, den: int) -> tuple[int, int]:
    """``num / den`` in lowest terms with a positive denominator (``den`` != 0): what ``Fraction(num, den)``
    holds, so that equal values compare equal as pairs."""
    g = gcd(num, den)
    if den < 0:
        g = -g
    return num // g, den // g


def technosoft_cia402_2(revision: int, has_210f: bool) -> bool:
    """Whether a Technosoft firmware implements CiA-402-2 (F515K / FA0xx and newer).

    The revision is the firmware name in ASCII, MSB first ("515K" = 0x3531354B). Unknown encodings fall
    back to whether the dictionary has the CiA-402-2 acceleration encoder factor 210Fh.
    """
    raw = revision.to_bytes(4, "big")
    try:
        text = raw.decode("ascii")
    except UnicodeDecodeError:
        return has_210f
    if text.startswith("515") and text[3].isalpha():
        return text[3].upper() >= "K"
    if text.startswith("A0"):
        return True
    return has_210f


def units_for(model: str, read: Reader, *, revision: int = 0, has_210f: bool = False,
              cycle_s: Fraction = Fraction(1, 1000)) -> Units:
    """The unit conversions of a drive whose manual defines them as ``model`` (``Behaviour.units``):
    "technosoft" (§5, CiA-402-2 from F515K or the obsolete factors), "hdt" (65536 counts/rev, 6093h/6094h/6097h),
    anything else CiA-402 (608Fh, 6091h/6092h, 6096h, 6097h)."""
    if model == "technosoft":
        return TechnosoftUnits(read, cycle_s, cia402_2=technosoft_cia402_2(revision, has_210f))
    if model == "hdt":
        return HdtUnits(read, cycle_s)
    return Units(read, cycle_s)
