"""CiA-402 factor groups from mechanics and units, with exact rationals.

Public API::

    from ecattool.scaling import Axis, Feedback, Gear, Transmission, compute, explain
    axis = Axis(Feedback.lines(500), Transmission.ballscrew(Exact(Fraction(5, 1000))), Gear(3, 1),
                position="mm", velocity="mm/s", acceleration="mm/s^2")
    group = compute(axis, "technosoft-ipos")      # -> FactorGroup (.objects, .startup(), .to_json())
    explain(group.values, "technosoft-ipos")       # -> Explanation (what one unit is in counts)
    encode_si_unit("mm") == 0xFD010100; decode_si_unit(0x00B44700) == "rot/min"
"""

from ecattool.scaling.compute import FAMILIES, compute, resolve_family, technosoft_factor_set
from ecattool.scaling.exact import PI, Approximation, Exact, approximate
from ecattool.scaling.explain import Explanation, explain, read_values
from ecattool.scaling.group import FactorGroup, FactorObject
from ecattool.scaling.model import Axis, Feedback, Gear, Transmission, axis_from_dict
from ecattool.scaling.spec import load_spec
from ecattool.scaling.units import Unit, decode_si_unit, dimension_notation, encode_si_unit, parse_unit

Mechanics = Axis

__all__ = [
    "FAMILIES", "PI", "Approximation", "Axis", "Exact", "Explanation", "FactorGroup", "FactorObject", "Feedback",
    "Gear", "Mechanics", "Transmission", "Unit", "approximate", "axis_from_dict", "compute", "decode_si_unit",
    "dimension_notation", "encode_si_unit", "explain", "load_spec", "parse_unit", "read_values", "resolve_family",
    "technosoft_factor_set",
]
