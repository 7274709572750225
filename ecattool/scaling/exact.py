"""Exact quantities with a symbolic power of pi, and rational approximation within integer field bounds.

Every factor is carried as ``coef * pi**k`` with ``coef`` a :class:`fractions.Fraction`: degrees, inches and
gear ratios stay exact, and pi (radians, belt pulleys by diameter) stays symbolic until a 32-bit numerator
and divisor must be chosen. Only then is pi replaced by a 100-digit rational, which makes the reported
approximation error exact to far below one part in 10^60.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import Literal, Union

from ecattool.errors import EncodeError, Location

#: pi to 100 decimal places, as an exact fraction (used only to measure and choose approximations)
PI = Fraction(
    "3.1415926535897932384626433832795028841971693993751058209749445923078164062862089986280348253421170679"
)

Number = Union[int, Fraction, "Exact"]


def _g(x: Fraction) -> str:
    """``x`` for a message, like ``{:.6g}``, also where it is too large (or small) for a float."""
    try:
        return f"{float(x):.6g}"
    except OverflowError:
        digits = len(str(abs(x.numerator))) - len(str(x.denominator))
        return f"{'-' if x < 0 else ''}~1e{digits}"


@dataclass(frozen=True, slots=True)
class Exact:
    """``coef * pi**pi_power`` — an exact positive or negative real of the form scaling needs."""

    coef: Fraction
    pi_power: int = 0

    @staticmethod
    def of(value: Number | str) -> "Exact":
        if isinstance(value, Exact):
            return value
        return Exact(Fraction(value))

    @property
    def is_rational(self) -> bool:
        return self.pi_power == 0 or self.coef == 0

    @property
    def rational(self) -> Fraction:
        """The value as a Fraction: exact when :attr:`is_rational`, else to 100 digits of pi."""
        if self.is_rational:
            return self.coef
        return self.coef * PI**self.pi_power

    def __mul__(self, other: Number) -> "Exact":
        o = Exact.of(other)
        return Exact(self.coef * o.coef, self.pi_power + o.pi_power)

    __rmul__ = __mul__

    def __truediv__(self, other: Number) -> "Exact":
        o = Exact.of(other)
        if o.coef == 0:
            raise ZeroDivisionError("division by zero in a scaling factor")
        return Exact(self.coef / o.coef, self.pi_power - o.pi_power)

    def __rtruediv__(self, other: Number) -> "Exact":
        return Exact.of(other) / self

    def __float__(self) -> float:
        return float(self.rational)

    def __eq__(self, other: object) -> bool:
        if isinstance(other, (int, Fraction)):
            other = Exact(Fraction(other))
        if not isinstance(other, Exact):
            return NotImplemented
        if self.coef == 0 or other.coef == 0:
            return self.coef == other.coef
        return self.coef == other.coef and self.pi_power == other.pi_power

    def __hash__(self) -> int:
        return hash((self.coef, self.pi_power if self.coef else 0))

    def __str__(self) -> str:
        c = self.coef
        text = str(c.numerator) if c.denominator == 1 else f"{c.numerator}/{c.denominator}"
        if self.pi_power == 0 or c == 0:
            return text
        p = "π" if abs(self.pi_power) == 1 else f"π^{abs(self.pi_power)}"
        if self.pi_power > 0:
            return f"{c.numerator}{p}" + ("" if c.denominator == 1 else f"/{c.denominator}")
        return f"{c.numerator}/" + (p if c.denominator == 1 else f"({c.denominator}{p})")


Strategy = Literal["best", "max-scale"]


@dataclass(frozen=True, slots=True)
class Approximation:
    """An integer pair ``numerator / denominator`` chosen for an exact ratio, with its error.

    ``error`` is (pair - exact) in the ratio's own unit (e.g. counts per user unit); ``bound`` is an
    a-priori bound of ``abs(error)`` guaranteed by the method; ``ppm`` is the relative error in parts per
    million; ``drift`` is the error accumulated over 10^6 user units (e.g. counts after 10^6 mm).
    """

    numerator: int
    denominator: int
    exact_value: Exact
    exact: bool
    error: Fraction
    bound: Fraction
    method: str

    @property
    def value(self) -> Fraction:
        return Fraction(self.numerator, self.denominator)

    @property
    def ppm(self) -> Fraction:
        x = self.exact_value.rational
        return self.error / x * 1_000_000 if x else Fraction(0)

    @property
    def drift(self) -> Fraction:
        return self.error * 1_000_000


def _round(x: Fraction) -> int:
    """Round half away from zero (the manual rounds 13493037.70 to 13493038)."""
    n = (abs(x.numerator) * 2 + x.denominator) // (2 * x.denominator)
    return n if x >= 0 else -n


def _scale_up(p: int, q: int, max_num: int, max_den: int) -> tuple[int, int]:
    """Multiply an exact pair by the largest power of two that keeps both inside their fields."""
    k = 1
    while p * k * 2 <= max_num and q * k * 2 <= max_den:
        k *= 2
    return p * k, q * k


def _best(x: Fraction, max_num: int, max_den: int) -> tuple[int, int]:
    """Best rational approximation p/q of x > 0 with p <= max_num, q <= max_den (convergents + semiconvergents)."""
    p0, q0, p1, q1 = 0, 1, 1, 0  # convergents h(-2)/k(-2), h(-1)/k(-1)
    rest = x
    best: tuple[int, int] | None = None
    while True:
        a = rest.numerator // rest.denominator
        p2, q2 = a * p1 + p0, a * q1 + q0
        if p2 > max_num or q2 > max_den:
            # largest semiconvergent that fits
            lim = []
            if p1:
                lim.append((max_num - p0) // p1)
            if q1:
                lim.append((max_den - q0) // q1)
            t = min(lim) if lim else 0
            candidates = [(p1, q1)] if q1 else []
            if t > 0:
                candidates.append((t * p1 + p0, t * q1 + q0))
            candidates = [(p, q) for p, q in candidates if q > 0 and p <= max_num and q <= max_den]
            if candidates:
                best = min(candidates, key=lambda c: abs(Fraction(c[0], c[1]) - x))
            break
        p0, q0, p1, q1 = p1, q1, p2, q2
        best = (p1, q1)
        frac = rest - a
        if frac == 0:
            break
        rest = 1 / frac
    # never worse than plain rounding at the largest usable denominator (this makes `bound` hold)
    qc = _q_cap(x, max_num, max_den)
    if qc > 0:
        cand = (_round(x * qc), qc)
        if 0 < cand[0] <= max_num and (best is None or abs(Fraction(*cand) - x) < abs(Fraction(*best) - x)):
            best = cand
    if best is None or best[0] == 0:
        raise EncodeError(f"ratio {_g(x)} cannot be represented with numerator <= {max_num} and denominator <= {max_den}")
    return best


def _q_cap(x: Fraction, max_num: int, max_den: int) -> int:
    """Largest q <= max_den whose rounded numerator round(x*q) still fits max_num."""
    if x <= 0:
        return max_den
    q = min(max_den, int((Fraction(max_num) + Fraction(1, 2)) / x))
    while q > 0 and _round(x * q) > max_num:
        q -= 1
    return q


def approximate(
    value: Exact | Fraction | int,
    max_num: int = 0xFFFFFFFF,
    max_den: int = 0xFFFFFFFF,
    strategy: Strategy = "best",
    scale_exact: bool = False,
    what: str = "factor",
    location: Location | None = None,
) -> Approximation:
    """Choose ``numerator/denominator`` (1..max) for a positive exact ratio.

    Exact ratios that fit are written reduced (or, with ``scale_exact``, multiplied by the largest power of
    two that fits: Technosoft's "prefer large numerators and divisors"). Others are approximated: ``best``
    gives the best rational approximation within the bounds; ``max-scale`` is the Technosoft manual's
    method (the larger field gets its maximum, the other is rounded: 4294967295 / 13493038 for radians on a
    2000-count axis).
    """
    ex = Exact.of(value)
    x = ex.rational
    if x <= 0:
        raise EncodeError(f"{what} must be positive, got {ex}", location)
    if ex.is_rational and x.numerator <= max_num and x.denominator <= max_den:
        p, q = x.numerator, x.denominator
        if scale_exact:
            p, q = _scale_up(p, q, max_num, max_den)
        return Approximation(p, q, ex, True, Fraction(0), Fraction(0), "exact")
    if x > max_num + Fraction(1, 2) or x < Fraction(1, 2 * max_den):
        raise EncodeError(
            f"{what} {_g(x)} is out of reach of numerator <= {max_num} and divisor <= {max_den}", location)
    if strategy == "max-scale":
        # the field that limits the ratio gets its maximum, the other is rounded (Technosoft §5.1.10.1)
        if x * max_den >= max_num:
            p, q = max_num, _round(Fraction(max_num) / x)
            bound = x / (2 * q) if q else Fraction(0)
        else:
            p, q = _round(x * max_den), max_den
            bound = Fraction(1, 2 * max_den)
        method = "max-scale"
        if not (0 < p <= max_num and 0 < q <= max_den):
            strategy = "best"  # rounding left the field (or the ratio is out of reach): fall through
    if strategy != "max-scale":
        try:
            p, q = _best(x, max_num, max_den)
        except EncodeError as exc:
            raise EncodeError(f"{what}: {exc.message}", location) from None
        qc = _q_cap(x, max_num, max_den)
        bound = Fraction(1, 2 * qc) if qc else abs(Fraction(p, q) - x)
        method = "best rational approximation"
    err = Fraction(p, q) - x
    return Approximation(p, q, ex, False, err, bound, method)
