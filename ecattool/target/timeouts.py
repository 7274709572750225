"""How long ecattool waits for a slave: from the slave's own timeouts where its ESI gives them, else documented
defaults (issue 37 item 6, issue 35 item 5; docs/at-the-machine.md, "How long ecattool waits").

An ESI names a device's timeouts in milliseconds (ETG.2000, ``Device/Info``)::

    <Mailbox><Timeout><RequestTimeout>100</RequestTimeout><ResponseTimeout>2000</ResponseTimeout></Timeout></Mailbox>
    <StateMachine><Timeout><PreopTimeout>3000</PreopTimeout><SafeopOpTimeout>10000</SafeopOpTimeout>
        <BackToInitTimeout>5000</BackToInitTimeout><BackToSafeopTimeout>200</BackToSafeopTimeout></Timeout>
    </StateMachine>

(the reader keeps them in ``Device.extra`` under ``Mailbox/Timeout/RequestTimeout`` … ``StateMachine/Timeout/…``).
From them, for a bus (the longest of its slaves' where several are known):

* one mailbox request: the master waits ``request + response`` for the answer (SOEM's ``sdo_read_timeout`` and
  ``sdo_write_timeout``, KickCAT's SDO timeout); an upload that got none is asked again (the next mailbox counter,
  ETG.1000.6) after that window has passed, :data:`REPEATS` times at the most;
* one SDO call through the isolated master (``target.isolated``): ``(REPEATS + 1) × (request + response)`` plus
  :data:`SEGMENT_MARGIN_S` for the segments of a segmented transfer; a master that has not answered by then is
  stopped (MasterHung);
* the bus init: :data:`LINK_WAIT_S` (a link just up drops frames) + the longest PRE-OP timeout + :data:`SII_S`
  per slave (the master reads each slave's SII; KickCAT: :data:`KICKCAT_SII_S`) + :data:`OPEN_MARGIN_S`; where the
  number of slaves is not known, :data:`DEFAULT_OPEN_SLAVES`.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from ecattool.record import FrozenRecord, set_field

#: the ESI elements (``Device/Info/…``) and the defaults where a slave's ESI gives none, in milliseconds: Beckhoff's
#: ESIs give 100/2000 for the mailbox (../shared/corpus/esi/beckhoff_EJ3xxx.xml:30-31), and 3000 ms for PRE-OP
#: (../shared/corpus/esi/beckhoff_EL66xx.xml); SOEM's own state timeout is 2000 ms (EC_TIMEOUTSTATE)
ELEMENTS = {
    "request_ms": ("Mailbox/Timeout/RequestTimeout", 100),
    "response_ms": ("Mailbox/Timeout/ResponseTimeout", 2000),
    "preop_ms": ("StateMachine/Timeout/PreopTimeout", 3000),
    "safeop_op_ms": ("StateMachine/Timeout/SafeopOpTimeout", 10000),
    "back_to_init_ms": ("StateMachine/Timeout/BackToInitTimeout", 5000),
    "back_to_safeop_ms": ("StateMachine/Timeout/BackToSafeopTimeout", 200),
}
#: how many times an upload that got no answer is asked again (each a new request, the next mailbox counter)
REPEATS = 2
#: what one SDO call may take beyond its mailbox windows (the segments of a segmented transfer, the pipe)
SEGMENT_MARGIN_S = 3.0
#: a link just brought up drops the first frames: the master asks an empty bus again for this long
LINK_WAIT_S = 2.0
#: reading one slave's SII during the bus init (SOEM reads the header and the categories it needs, word by word)
SII_S = 0.5
#: the same for KickCAT, whose bus init reads the whole EEPROM and waits its link timeout on every read (a redundant
#: port's copy that never comes): seconds per slave
KICKCAT_SII_S = 10.0
#: what the bus init takes besides (the socket, SOEM's own broadcast reads)
OPEN_MARGIN_S = 3.0
#: the slaves a bus init is budgeted for where the number is not known (no state read before the bus opened)
DEFAULT_OPEN_SLAVES = 16
#: no slave's timeout is taken above this (an ESI that says an hour is not waited for), in milliseconds
MAX_MS = 60_000


class SlaveTimeouts(FrozenRecord):
    """One slave's timeouts in milliseconds (its ESI's, else the defaults of :data:`ELEMENTS`); ``known``: whether
    they came from an ESI."""

    __slots__ = ("request_ms", "response_ms", "preop_ms", "safeop_op_ms", "back_to_init_ms", "back_to_safeop_ms",
                 "known")
    request_ms: int
    response_ms: int
    preop_ms: int
    safeop_op_ms: int
    back_to_init_ms: int
    back_to_safeop_ms: int
    known: bool

    def __init__(self, request_ms: int = ELEMENTS["request_ms"][1], response_ms: int = ELEMENTS["response_ms"][1],
                 preop_ms: int = ELEMENTS["preop_ms"][1], safeop_op_ms: int = ELEMENTS["safeop_op_ms"][1],
                 back_to_init_ms: int = ELEMENTS["back_to_init_ms"][1],
                 back_to_safeop_ms: int = ELEMENTS["back_to_safeop_ms"][1], known: bool = False) -> None:
        set_field(self, "request_ms", request_ms)
        set_field(self, "response_ms", response_ms)
        set_field(self, "preop_ms", preop_ms)
        set_field(self, "safeop_op_ms", safeop_op_ms)
        set_field(self, "back_to_init_ms", back_to_init_ms)
        set_field(self, "back_to_safeop_ms", back_to_safeop_ms)
        set_field(self, "known", known)


def _ms(text: str | None) -> int | None:
    if text is None:
        return None
    try:
        word = str(text).split(";")[0].strip()
        value = int("0x" + word[2:], 16) if word[:2].lower() == "#x" else int(word, 10)  # ESI numbers: 100, #x64
    except ValueError:
        return None
    return min(value, MAX_MS) if value > 0 else None


def of_device(device: Any) -> SlaveTimeouts:
    """The timeouts ``device``'s ESI gives (``Device.extra``), the defaults for the rest."""
    extra: dict[str, str] = getattr(device, "extra", None) or {}
    values: dict[str, int] = {}
    for field, (element, _default) in ELEMENTS.items():
        ms = _ms(extra.get(element))
        if ms is not None:
            values[field] = ms
    return SlaveTimeouts(**values, known=bool(values))


class BusLimits(FrozenRecord):
    """What ecattool waits for on one bus (see the module text): seconds, from the slaves' timeouts."""

    __slots__ = ("slaves", "count", "sii_s")
    slaves: tuple[SlaveTimeouts, ...]
    #: the number of slaves on the bus where known before it is opened
    count: int | None
    #: what the master's bus init takes to read one slave's SII (SII_S for SOEM, KICKCAT_SII_S for KickCAT)
    sii_s: float

    def __init__(self, slaves: tuple[SlaveTimeouts, ...] = (), count: int | None = None, sii_s: float = SII_S) -> None:
        set_field(self, "slaves", slaves)
        set_field(self, "count", count)
        set_field(self, "sii_s", sii_s)

    def longest(self, field: str) -> float:
        """The longest of the slaves' ``field`` (a :class:`SlaveTimeouts` field name), in seconds."""
        values: list[int] = [int(getattr(s, field)) for s in self.slaves] or [ELEMENTS[field][1]]
        return max(values) / 1000.0

    @property
    def mailbox_s(self) -> float:
        """One mailbox request's window: the slave's request and response timeouts."""
        return self.longest("request_ms") + self.longest("response_ms")

    @property
    def sdo_call_s(self) -> float:
        """One SDO call through the isolated master, its repeats included."""
        return (REPEATS + 1) * self.mailbox_s + SEGMENT_MARGIN_S

    @property
    def preop_s(self) -> float:
        return self.longest("preop_ms")

    @property
    def open_s(self) -> float:
        """The bus init: the link, every slave's SII, the way to PRE-OP."""
        n = self.count if self.count is not None else max(len(self.slaves), DEFAULT_OPEN_SLAVES)
        return LINK_WAIT_S + self.preop_s + self.sii_s * max(n, 1) + OPEN_MARGIN_S

    def describe(self) -> str:
        """The limits as a user reads them in an error."""
        source = "the slaves' ESI" if any(s.known for s in self.slaves) else "defaults"
        return (f"{self.mailbox_s:g} s per mailbox answer, {REPEATS} repeats, bus init {self.open_s:g} s "
                f"({source})")


def window_text(limits: BusLimits) -> str:
    """One mailbox window as an error says it: ``2.1 s (the slave's ESI: request 0.1 s + response 2 s)``."""
    source = "the slave's ESI" if any(s.known for s in limits.slaves) else "default"
    return (f"{limits.mailbox_s:g} s ({source}: request {limits.longest('request_ms'):g} s + response "
            f"{limits.longest('response_ms'):g} s)")


def bus_limits(devices: Iterable[Any] = (), count: int | None = None, sii_s: float = SII_S) -> BusLimits:
    """The limits of a bus of ``devices`` (a project's, a ``--device``; none: the defaults) with ``count`` slaves,
    whose master reads one slave's SII in ``sii_s``."""
    return BusLimits(tuple(of_device(d) for d in devices), count, sii_s)
