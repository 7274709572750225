"""Technosoft ``.sw`` EEPROM setup images: read, write, checksum, FoE image, download plans, apply.

>>> from ecattool import sw
>>> image = sw.read("axis1.sw")                     # doctest: +SKIP
>>> [hex(b.checksum_request) for b in image]        # doctest: +SKIP
>>> plan = sw.download_plan(image, mode=16)         # a StartupList           # doctest: +SKIP
>>> report = sw.download(image, target)             # only blocks that differ  # doctest: +SKIP
"""

from ecattool.sw.apply import BlockCheck, DownloadReport, download, verify
from ecattool.sw.build import build, load_image
from ecattool.sw.foe import check_foe_name, from_foe, read_foe, to_foe
from ecattool.sw.image import Block, SwImage, checksum, checksum_request, make_image, parse, read, write
from ecattool.sw.layout import BlockInfo, describe, fix_integrity, integrity_findings, setup_table
from ecattool.sw.params import ParameterTable, parse_parameters, read_parameters
from ecattool.sw.plan import config_value, download_plan
from ecattool.sw.setup import diff, patch, setup_values

#: every integrity word that does not hold, as findings (rule ids sw-…); the project lint uses it
check = integrity_findings

__all__ = [
    "Block", "BlockCheck", "BlockInfo", "DownloadReport", "ParameterTable", "SwImage",
    "build", "check", "check_foe_name", "checksum", "checksum_request", "config_value", "describe", "diff", "download",
    "download_plan", "fix_integrity", "from_foe", "integrity_findings", "load_image", "make_image", "parse",
    "parse_parameters", "patch", "read", "read_foe", "read_parameters", "setup_table", "setup_values", "to_foe",
    "verify", "write",
]
