"""The live bus through KickCAT's Python master (``kickcat`` 2.5).

What the binding allows: bus init (every slave to PRE-OP), SDO upload (``Bus.read_sdo``), SDO download (the
slave's mailbox ``write_sdo``, then ``process_mailboxes`` until it is done), the state of each slave. What it does
not: the SII EEPROM (no EEPROM access is bound, so no SII identity, ``sii read/write`` or mailbox protocol and DC
words; the identity is read from 1018h), the AL status code, and the SDO Information service's OD list (only
``read_object_description``/``read_entry_description`` of an index already known are bound). Those raise
:class:`~ecattool.online.live.Unsupported`.

The slave's SDO access and state are :class:`ecattool.target.kickcat.KickcatSlave`'s (SDO aborts through
KickCAT: see there).
"""

from __future__ import annotations

import ctypes
import os
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from types import ModuleType
from typing import TYPE_CHECKING

from ecattool.errors import TargetError
from ecattool.od.model import EcState, ObjectDictionary
from ecattool.online.live import LiveBus, Unsupported
from ecattool.target.kickcat import KickcatSlave, import_kickcat

if TYPE_CHECKING:
    from ecattool.target.timeouts import BusLimits

#: bus init timeouts (s): short first (KickCAT waits the whole timeout per SII read for a redundant port's copy)
INIT_TIMEOUTS_S = (0.02, 0.1)
LINK_TIMEOUT_S = 0.25
WATCHDOG_S = 1.0
_import = import_kickcat


class KickcatLiveSlave(KickcatSlave):
    """A KickCAT slave as a :class:`~ecattool.online.live.LiveSlave`: what the binding does not bind raises
    :class:`~ecattool.online.live.Unsupported`."""

    def al_status_code(self) -> int | None:
        return None  # not bound

    def sii_read(self) -> bytes:
        raise Unsupported("kickcat: the Python binding gives no SII EEPROM access (use pysoem:IF)")

    def sii_write(self, image: bytes) -> None:
        raise Unsupported("kickcat: the Python binding gives no SII EEPROM access (use pysoem:IF)")

    def sii_write_word(self, word: int, data: bytes) -> None:
        raise Unsupported("kickcat: the Python binding gives no SII EEPROM access (use pysoem:IF)")

    def request_state(self, state: EcState) -> None:
        raise Unsupported("kickcat: the Python binding requests a state for the whole bus, not for one slave (use "
                          "pysoem:IF)")

    def sdo_info(self) -> ObjectDictionary:
        raise Unsupported("kickcat: the Python binding has no SDO Information OD list (use pysoem:IF, or type the "
                          "objects with --library/--device)")


@contextmanager
def _quiet_stdout() -> Iterator[None]:
    """KickCAT prints "Opening nominal interface…" on the process's stdout (fd 1), where a command's --json
    document goes (and an error stays one line on stderr): while it opens the link, fd 1 is /dev/null."""
    sys.stdout.flush()
    saved = os.dup(1)
    null = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(null, 1)
        yield
    finally:
        try:
            ctypes.CDLL(None).fflush(None)  # the C library's buffer, before fd 1 is stdout again
        except (OSError, AttributeError):
            pass
        os.dup2(saved, 1)
        os.close(saved)
        os.close(null)


def open_kickcat(ifname: str, module: ModuleType | None = None, limits: BusLimits | None = None) -> LiveBus:
    """A KickCAT master on ``ifname``, every slave in PRE-OP; ``limits``: the slaves' timeouts (an SDO waits one
    mailbox window of theirs)."""
    kc = module or _import()
    try:
        with _quiet_stdout():
            link = kc.create_link(ifname, "")
    except Exception as exc:  # noqa: BLE001 - RuntimeError/OSError from the binding
        from ecattool.target.pysoem import open_advice

        raise TargetError(f"cannot open EtherCAT interface {ifname!r} with KickCAT: {exc}{open_advice(ifname)}") from None
    bus = kc.Bus(link)
    for attempt, timeout in enumerate(INIT_TIMEOUTS_S):
        link.set_timeout(timeout)
        try:
            bus.init(WATCHDOG_S)
            break
        except Exception as exc:  # noqa: BLE001
            if attempt == len(INIT_TIMEOUTS_S) - 1:
                raise TargetError(f"KickCAT bus init on {ifname!r} failed: {exc}") from None
    link.set_timeout(LINK_TIMEOUT_S)
    slaves = [KickcatLiveSlave(bus, s, i, kc, limits) for i, s in enumerate(bus.slaves())]
    if not slaves:
        raise TargetError(f"no EtherCAT slaves found on {ifname!r}")
    return LiveBus(f"kickcat:{ifname}", slaves)
