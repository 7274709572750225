"""The supervision's memory from cycle to cycle (:mod:`.supervision` decides with it). Apart from the decisions
so that the drive's core can hold it without importing them."""

from __future__ import annotations

__all__ = ["Supervision"]


class Supervision:
    """What the supervision remembers from cycle to cycle (seconds outside the following-error window, inside the
    position window), and the largest figures of the running move for commissioning."""

    __slots__ = ("outside_s", "inside_s", "limits")

    def __init__(self) -> None:
        self.outside_s = 0.0
        self.inside_s = 0.0
        #: (the stored 6065h, 6066h and the store's version they were read at, :func:`_limits` of them)
        self.limits: tuple[tuple[bytes | None, bytes | None, int], float | None, float] | None = None

    def state(self) -> tuple[float, float]:
        return self.outside_s, self.inside_s
