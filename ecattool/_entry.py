"""The ``ecattool`` console entry point.

``ecattool --version`` is answered here, before click (~30 ms of imports) is loaded, so that it costs little
more than starting Python; every other command line goes to :func:`ecattool.cli.main`.
"""

from __future__ import annotations

import sys
from typing import Any

from ecattool import __version__


def main(argv: list[str] | None = None) -> Any:
    args = sys.argv[1:] if argv is None else argv
    if args in (["--version"], ["-V"]):
        print(f"ecattool, version {__version__}")  # the text click's version option prints
        return 0
    from ecattool.cli import main as cli_main

    return cli_main(argv)
