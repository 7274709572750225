"""The parameter type of a file a command reads.

Existence and "is a directory" are not checked by click: the file is checked where it is read, so a
missing or unreadable file is invalid input like any other (one line naming the file, exit status 1)
instead of a three-line click usage error with exit status 2. See docs/cli.md, "Exit codes and errors".
"""

from __future__ import annotations

import os
from typing import Any

import click


class InputFile(click.Path):
    """``click.Path(dir_okay=False)`` (metavar FILE, file completion) without click's existence checks."""

    def __init__(self, allow_dash: bool = False) -> None:
        super().__init__(dir_okay=False, allow_dash=allow_dash)

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> Any:
        return self.coerce_path_result(os.fsdecode(value) if isinstance(value, bytes) else value)
