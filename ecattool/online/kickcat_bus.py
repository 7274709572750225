"""The live bus through KickCAT's Python master (``kickcat`` 2.5).

What the binding allows: bus init (every slave to PRE-OP), SDO upload (``Bus.read_sdo``), SDO download (the
slave's mailbox ``write_sdo``, then ``process_mailboxes`` until it is done), the state of each slave. What it does
not: the SII EEPROM (no EEPROM access is bound, so no SII identity, ``sii read/write`` or mailbox protocol and DC
words; the identity is read from 1018h), the AL status code, and the SDO Information service's OD list (only
``read_object_description``/``read_entry_description`` of an index already known are bound). Those raise
:class:`~ecattool.online.live.Unsupported`.

SDO aborts: against the virtual bus (whose abort frames SOEM decodes with their codes), KickCAT 2.5's ``read_sdo``
raises ``RuntimeError("… Error while reading SDO - Timeout")`` for an aborted upload, and the message of a refused
download stays RUNNING; so through KickCAT an abort shows as an SDO timeout, without its code. A message status
that does carry an abort code is reported as one.
"""

from __future__ import annotations

import ctypes
import os
import re
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from types import ModuleType
from typing import Any

from ecattool.errors import SdoAbort, SdoTimeout, TargetError
from ecattool.esi.model import Identity
from ecattool.od.model import EcState, ObjectDictionary
from ecattool.online.live import LiveBus, Unsupported

#: bus init timeouts (s): short first (KickCAT waits the whole timeout per SII read for a redundant port's copy)
INIT_TIMEOUTS_S = (0.02, 0.1)
LINK_TIMEOUT_S = 0.25
WATCHDOG_S = 1.0
SDO_TIMEOUT_S = 3.0
#: mailbox polls one SDO download may take (each is one exchange of frames)
POLLS = 5000
#: KickCAT's read buffer for one SDO upload
READ_BUFFER = 1024
_ABORT = re.compile(r"0x([0-9a-fA-F]{8})")


def _import() -> ModuleType:
    try:
        import kickcat  # type: ignore[import-not-found, import-untyped, unused-ignore]
    except ImportError:
        raise TargetError("the kickcat target needs the kickcat package: pip install kickcat") from None
    module: ModuleType = kickcat
    return module


class KickcatLiveSlave:
    def __init__(self, bus: Any, slave: Any, position: int, module: ModuleType) -> None:
        self._bus = bus
        self._slave = slave
        self._mod = module
        self.position = position

    def _error(self, exc: Exception, index: int, subindex: int) -> TargetError:
        text = str(exc)
        m = _ABORT.search(text)
        if m:
            return SdoAbort(index, subindex, int(m.group(1), 16))
        if "timeout" in text.lower():
            return SdoTimeout(index, subindex)
        return TargetError(f"slave {self.position}, 0x{index:04X}:{subindex:02X}: {text}")

    def identity(self) -> Identity:
        v, p, r = (int.from_bytes(self.sdo_upload(0x1018, s), "little") for s in (1, 2, 3))
        return Identity(v, p, r)

    def sdo_upload(self, index: int, subindex: int, complete_access: bool = False) -> bytes:
        access = self._mod.Access.COMPLETE if complete_access else self._mod.Access.PARTIAL
        try:
            return bytes(self._bus.read_sdo(self._slave, index, subindex, access, READ_BUFFER, SDO_TIMEOUT_S))
        except Exception as exc:  # noqa: BLE001 - ErrorCoE, RuntimeError: KickCAT's only exception types
            raise self._error(exc, index, subindex) from None

    def sdo_download(self, index: int, subindex: int, data: bytes, complete_access: bool = False,
                     expect_reply: bool = True) -> None:
        from kickcat.mailbox.request import MessageStatus  # type: ignore[import-not-found, import-untyped, unused-ignore]

        try:
            msg = self._slave.mailbox.write_sdo(index, subindex, complete_access, bytes(data), SDO_TIMEOUT_S)
            for _ in range(POLLS):
                if msg.status() != MessageStatus.RUNNING:
                    break
                self._bus.process_mailboxes()
        except Exception as exc:  # noqa: BLE001
            raise self._error(exc, index, subindex) from None
        status = int(msg.status())
        if status == int(MessageStatus.RUNNING) or status == int(getattr(MessageStatus, "TIMEDOUT", -1)):
            if expect_reply:
                raise SdoTimeout(index, subindex)
        elif status > 0xFFFF:  # KickCAT keeps the slave's abort code as the message status
            raise SdoAbort(index, subindex, status)
        elif status != int(MessageStatus.SUCCESS):
            names = {int(getattr(MessageStatus, n)): n for n in dir(MessageStatus) if n.isupper()}
            raise TargetError(f"slave {self.position}, 0x{index:04X}:{subindex:02X}: KickCAT mailbox status "
                              f"{names.get(status, status)}")

    def state(self) -> EcState:
        s = self._bus.get_state(self._slave)
        names = {self._mod.State.INIT: EcState.INIT, self._mod.State.PREOP: EcState.PREOP,
                 self._mod.State.SAFE_OP: EcState.SAFEOP, self._mod.State.OPERATIONAL: EcState.OP}
        for k, v in names.items():
            if s == k:
                return v
        raise TargetError(f"slave {self.position}: KickCAT reports state {s!r}")

    def al_status_code(self) -> int | None:
        return None  # not bound

    def sii_read(self) -> bytes:
        raise Unsupported("kickcat: the Python binding gives no SII EEPROM access (use pysoem:IF)")

    def sii_write(self, image: bytes) -> None:
        raise Unsupported("kickcat: the Python binding gives no SII EEPROM access (use pysoem:IF)")

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


def open_kickcat(ifname: str, module: ModuleType | None = None) -> LiveBus:
    """A KickCAT master on ``ifname``, every slave in PRE-OP."""
    kc = module or _import()
    try:
        with _quiet_stdout():
            link = kc.create_link(ifname, "")
    except Exception as exc:  # noqa: BLE001 - RuntimeError/OSError from the binding
        raise TargetError(f"cannot open EtherCAT interface {ifname!r} with KickCAT: {exc}") from None
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
    slaves = [KickcatLiveSlave(bus, s, i, kc) for i, s in enumerate(bus.slaves())]
    if not slaves:
        raise TargetError(f"no EtherCAT slaves found on {ifname!r}")
    return LiveBus(f"kickcat:{ifname}", slaves)
