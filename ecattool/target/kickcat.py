"""A KickCAT slave reached through KickCAT's Python master (``kickcat`` 2.5): identity through 1018h, SDO upload
and download through the slave's mailbox, the state. The master-facing base of ``online.kickcat_bus`` (the live
bus) and of ``startup.install`` (a project's startup list written from a master program).

SDO aborts: against the virtual bus (whose abort frames SOEM decodes with their codes), KickCAT 2.5's ``read_sdo``
raises ``RuntimeError("… Error while reading SDO - Timeout")`` for an aborted upload, and the message of a refused
download stays RUNNING; so through KickCAT an abort shows as an SDO timeout, without its code. A message status
that does carry an abort code is reported as one.
"""

from __future__ import annotations

import re
from types import ModuleType
from typing import Any

from ecattool.errors import SdoAbort, SdoTimeout, SdoTooLarge, TargetError
from ecattool.esi.model import Identity
from ecattool.od.model import EcState
from ecattool.target.base import UNKNOWN_SIZE_FIRST, UNKNOWN_SIZE_MAX, check_upload
from ecattool.target.timeouts import BusLimits

SDO_TIMEOUT_S = 3.0
#: mailbox polls one SDO download may take (each is one exchange of frames)
POLLS = 5000
_ABORT = re.compile(r"0x([0-9a-fA-F]{8})")
#: what KickCAT says of a reply larger than the buffer it was given
_TOO_SMALL = re.compile(r"too (small|big|large)|buffer|size", re.IGNORECASE)


def _too_small(exc: Exception) -> bool:
    return bool(_TOO_SMALL.search(str(exc))) and "timeout" not in str(exc).lower()


def import_kickcat() -> ModuleType:
    try:
        import kickcat  # type: ignore[import-not-found, import-untyped, unused-ignore]
    except ImportError:
        raise TargetError("the kickcat target needs the kickcat package: pip install kickcat") from None
    module: ModuleType = kickcat
    return module


class KickcatSlave:
    """One slave of a KickCAT ``Bus``: identity (1018h), SDO upload/download, state."""

    def __init__(self, bus: Any, slave: Any, position: int, module: ModuleType, limits: BusLimits | None = None) -> None:
        #: how long one SDO waits for its answer: the slave's mailbox window (its ESI's request + response
        #: timeouts), never less than SDO_TIMEOUT_S
        self.sdo_timeout_s = max(SDO_TIMEOUT_S, (limits or BusLimits()).mailbox_s)
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
            return SdoTimeout(index, subindex, self.position)
        return TargetError(f"slave {self.position}, 0x{index:04X}:{subindex:02X}: {text}")

    def identity(self) -> Identity:
        v, p, r = (int.from_bytes(self.sdo_upload(0x1018, s, size=4), "little") for s in (1, 2, 3))
        return Identity(v, p, r)

    def sdo_upload(self, index: int, subindex: int, complete_access: bool = False, size: int | None = None) -> bytes:
        """The object's value read into a KickCAT buffer of ``size`` octets (the object's type's; not known:
        UNKNOWN_SIZE_FIRST, then once UNKNOWN_SIZE_MAX where KickCAT says the first was too small); whatever
        KickCAT returns is checked against that bound again."""
        access = self._mod.Access.COMPLETE if complete_access else self._mod.Access.PARTIAL

        def read(n: int) -> bytes:
            return bytes(self._bus.read_sdo(self._slave, index, subindex, access, n, self.sdo_timeout_s))

        first = UNKNOWN_SIZE_FIRST if size is None else max(1, size)
        try:
            try:
                data = read(first)
            except Exception as exc:  # noqa: BLE001 - ErrorCoE, RuntimeError: KickCAT's only exception types
                if not _too_small(exc):
                    raise
                if size is not None:
                    raise SdoTooLarge(index, subindex, self.position, size) from None
                data = read(UNKNOWN_SIZE_MAX)
        except SdoTooLarge:
            raise
        except Exception as exc:  # noqa: BLE001
            if _too_small(exc):
                raise SdoTooLarge(index, subindex, self.position, UNKNOWN_SIZE_MAX, known=False) from None
            error = self._error(exc, index, subindex)
            if type(error) is TargetError:  # KickCAT 2.5 says "Error while reading SDO" of a reply that announces
                # more than its buffer, as of a malformed one: the bound is named
                raise TargetError(f"{error.message} (KickCAT read at most {first} octets)") from None
            raise error from None
        return check_upload(data, size, index, subindex, self.position)

    def sdo_download(self, index: int, subindex: int, data: bytes, complete_access: bool = False,
                     expect_reply: bool = True) -> None:
        from kickcat.mailbox.request import MessageStatus  # type: ignore[import-not-found, import-untyped, unused-ignore]

        try:
            msg = self._slave.mailbox.write_sdo(index, subindex, complete_access, bytes(data), self.sdo_timeout_s)
            for _ in range(POLLS):
                if msg.status() != MessageStatus.RUNNING:
                    break
                self._bus.process_mailboxes()
        except Exception as exc:  # noqa: BLE001
            raise self._error(exc, index, subindex) from None
        status = int(msg.status())
        if status == int(MessageStatus.RUNNING) or status == int(getattr(MessageStatus, "TIMEDOUT", -1)):
            if expect_reply:
                raise SdoTimeout(index, subindex, self.position)
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
