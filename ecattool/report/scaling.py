"""The factor-group derivation as a page: the mechanics as a chain encoder → gear → transmission → user unit.

The chain is read from the object values (608Fh encoder resolution, 6091h gear ratio, 6092h feed constant,
6093h position factor, 60A8h position unit) as :func:`ecattool.scaling.explain` reads them; where the values
lack a link (HDT and the obsolete Technosoft set carry only 6093h), the missing links are shown as one
derived link "gear × transmission" when encoder and position factor are known. With the mechanics the
values were computed from (``scale compute --html``), each link also names the part (a 500-line encoder, a
5 mm ball screw).
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING

from ecattool import __version__
from ecattool.report.extra import environment

if TYPE_CHECKING:
    from ecattool.scaling.explain import Explanation

Values = dict[tuple[int, int], int]


@dataclass(frozen=True, slots=True)
class Link:
    """One link of the chain: what it is, its value, the objects it comes from, and the part (mechanics)."""

    title: str
    value: str
    objects: str
    part: str = ""
    kind: str = "known"  # "known" | "derived" | "unknown" | "result"


def _num(x: Fraction) -> str:
    if x.denominator == 1:
        return str(x.numerator)
    return f"{float(x):.10g} ({x.numerator}/{x.denominator})" if max(x.numerator, x.denominator) < 10**7 \
        else f"{float(x):.10g}"


def _ratio(values: Values, index: int) -> Fraction | None:
    if (index, 1) not in values and (index, 2) not in values:
        return None
    num, den = values.get((index, 1), 1), values.get((index, 2), 1)
    return Fraction(num, den) if num and den else None


def chain(explanation: Explanation, values: Values, mechanics: dict[str, str] | None = None) -> list[Link]:
    """The links encoder → gear → transmission → user unit, from ``values`` and (optionally) the mechanics."""
    m = mechanics or {}
    unit = str(explanation.data.get("0x60A8", m.get("position unit", "position unit")))
    pf = explanation.data.get("counts per position unit")
    pf = pf if isinstance(pf, Fraction) else None
    cpr = _ratio(values, 0x608F)
    cpr_from = "608Fh"
    from ecattool.scaling.compute import fixed_counts_per_rev

    fixed = fixed_counts_per_rev(explanation.family)
    if fixed is not None:
        cpr, cpr_from = Fraction(fixed), f"{explanation.family.upper()}: {fixed} internal units per motor revolution, always"
    gear, feed = _ratio(values, 0x6091), _ratio(values, 0x6092)
    links = [Link("Encoder", f"{_num(cpr)} counts / motor rev" if cpr else "counts per motor rev not known",
                  cpr_from if cpr else "608Fh absent (give --counts-per-rev)", m.get("feedback", ""),
                  "known" if cpr else "unknown")]
    if gear is not None or feed is not None:
        links.append(Link("Gear", f"{_num(gear)} motor rev : 1 shaft rev" if gear else "1 : 1 (not given)",
                          "6091h" if gear else "6091h absent", m.get("gear (motor:load)", ""),
                          "known" if gear else "unknown"))
        links.append(Link("Transmission", f"{_num(feed)} {unit} / shaft rev" if feed else "not given",
                          "6092h" if feed else "6092h absent", m.get("transmission", ""),
                          "known" if feed else "unknown"))
    elif cpr and pf:
        links.append(Link("Gear × transmission", f"1 motor rev = {_num(cpr / pf)} {unit}",
                          "derived: encoder ÷ position factor (6091h/6092h not in the values)",
                          " · ".join(x for x in (m.get("gear (motor:load)", ""), m.get("transmission", "")) if x),
                          "derived"))
    else:
        links.append(Link("Gear × transmission", "not known", "neither 6091h/6092h nor encoder and 6093h", "",
                          "unknown"))
    if pf is not None:
        frm = "6093h" if (0x6093, 1) in values else "608Fh × 6091h ÷ 6092h"
        links.append(Link("User unit", f"1 {unit} = {_num(pf)} counts", frm,
                          f"1 count = {_num(1 / pf)} {unit}", "result"))
    else:
        links.append(Link("User unit", "not known", "6093h absent", "", "unknown"))
    return links


def check(values: Values, pf: Fraction | None) -> str | None:
    """'608Fh × 6091h ÷ 6092h = …' against the position factor, where every link is in the values."""
    cpr, gear, feed = _ratio(values, 0x608F), _ratio(values, 0x6091), _ratio(values, 0x6092)
    if cpr is None or gear is None or feed is None or pf is None:
        return None
    product = cpr * gear / feed
    verdict = "agrees with" if product == pf else "DIFFERS from"
    return f"608Fh × 6091h ÷ 6092h = {_num(product)} counts per unit: {verdict} the position factor {_num(pf)}"


def scaling_html(explanation: Explanation, values: Values, mechanics: dict[str, str] | None = None,
                 title: str = "") -> str:
    """The scaling page: the chain, what each unit means, the object values and the findings."""
    pf = explanation.data.get("counts per position unit")
    rows = [(f"0x{i:04X}:{s:02X}", v) for (i, s), v in sorted(values.items())]
    return str(environment().get_template("scaling.html.j2").render(
        e=explanation, links=chain(explanation, values, mechanics), rows=rows, mechanics=mechanics or {},
        check=check(values, pf if isinstance(pf, Fraction) else None), title=title, version=__version__))
