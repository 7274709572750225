"""ecattool: commissioning toolchain for EtherCAT CoE servo drives.

Import the subpackages you need (``ecattool.esi``, ``ecattool.od``, ``ecattool.pdo`` …); this top-level
module stays tiny so that ``ecattool --version`` is fast.
"""

__version__ = "0.1.0"

from ecattool.errors import EcatToolError, Location  # noqa: E402

__all__ = ["EcatToolError", "Location", "__version__"]
