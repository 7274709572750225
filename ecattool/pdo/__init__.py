"""PDO mappings: the model and its parsers, static checks (rule ids PDO0nn), process-image layout, and the
SDO sequence that programs a mapping.

    >>> from ecattool import pdo
    >>> m = pdo.Mapping.from_text(rx="0x1600=controlword,0x607A:00/32", device=device)   # doctest: +SKIP
    >>> pdo.check(device, m)            # list[Finding]                                   # doctest: +SKIP
    >>> pdo.layout(device, m).to_json() # byte.bit offsets per sync manager               # doctest: +SKIP
    >>> pdo.program(device, m)          # StartupList: 1C12:00=0, 1600:00=0, …            # doctest: +SKIP
"""

from ecattool.pdo.check import RULES, check, check_config, input_finding, rule_ids
from ecattool.pdo.layout import ImageEntry, Layout, SmImage, layout
from ecattool.pdo.model import (
    MappedPdo,
    Mapping,
    default_assignment,
    default_mapping,
    entry_text,
    declared_mapping,
    mapping_from_config,
    mapping_from_startup,
    parse_direction,
    parse_entry,
    pdo_direction,
    powered_on,
)
from ecattool.pdo.program import ORDERS, program, resolve_rules

__all__ = [
    "ImageEntry", "Layout", "MappedPdo", "Mapping", "ORDERS", "RULES", "SmImage", "check", "check_config", "declared_mapping", "default_assignment",
    "default_mapping", "entry_text", "input_finding", "layout", "mapping_from_config", "mapping_from_startup", "parse_direction", "parse_entry", "pdo_direction", "powered_on", "program",
    "resolve_rules", "rule_ids",
]
