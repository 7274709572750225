"""Fault injection for tests: abort the Nth SDO, drop a reply, lose power during an EEPROM write, refuse
a state change. Counting is relative to the moment a fault is scheduled: ``nth=1`` is the next request."""

from __future__ import annotations

from dataclasses import dataclass, field

from ecattool.abort import AlStatus
from ecattool.od.model import EcState


@dataclass
class Faults:
    sdo_count: int = 0
    _sdo: dict[int, tuple[str, int]] = field(default_factory=dict)
    _states: dict[EcState, list[int]] = field(default_factory=dict)
    _slow: dict[EcState, list[int]] = field(default_factory=dict)
    #: EEPROM words that may still be written before the power fails (None = no power loss planned)
    eeprom_power_loss_after: int | None = None

    def abort_sdo(self, nth: int, code: int) -> None:
        """The ``nth`` SDO request from now (1 = the next) is answered with abort ``code``, not executed."""
        self._sdo[self.sdo_count + max(1, nth)] = ("abort", code)

    def drop_reply(self, nth: int = 1, *, execute: bool = True) -> None:
        """The ``nth`` SDO request from now gets no reply (SdoTimeout); ``execute`` = the drive still did it."""
        self._sdo[self.sdo_count + max(1, nth)] = ("drop", int(execute))

    def refuse_state(self, state: EcState, al_status: int = AlStatus.INVALID_STATE_CHANGE, times: int = 1) -> None:
        """The next ``times`` requests for ``state`` are refused with ``al_status``."""
        self._states.setdefault(state, []).extend([al_status] * times)

    def slow_mailbox(self, state: EcState, ms: int, times: int = 1) -> None:
        """The next ``times`` mailbox requests (SDOs) the drive receives in ``state`` are answered ``ms`` late, as
        by a drive busy storing its parameters. On the wire only: the slave's mailbox holds the answer back for
        that long (the in-process API has no time to wait)."""
        self._slow.setdefault(state, []).extend([ms] * times)

    def power_loss_during_eeprom_write(self, after_words: int = 0) -> None:
        """The power fails while writing EEPROM word number ``after_words + 1`` from now."""
        self.eeprom_power_loss_after = after_words

    # --- used by the drive -----------------------------------------------------------------------
    def next_sdo(self) -> tuple[str, int] | None:
        self.sdo_count += 1
        if not self._sdo:
            return None
        return self._sdo.pop(self.sdo_count, None)

    def state_refusal(self, state: EcState) -> int | None:
        return _next(self._states, state)

    def mailbox_delay_ms(self, state: EcState) -> int | None:
        return _next(self._slow, state)

    def clear(self) -> None:
        self._sdo.clear()
        self._states.clear()
        self._slow.clear()
        self.eeprom_power_loss_after = None


def _next(planned: dict[EcState, list[int]], state: EcState) -> int | None:
    """The next value planned for ``state`` (consumed), or None."""
    pending = planned.get(state)
    return pending.pop(0) if pending else None
