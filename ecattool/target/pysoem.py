"""A real EtherCAT master through pysoem (optional extra: ``pip install ecattool[pysoem]``).

Implements the same :class:`~ecattool.target.base.SlaveTarget` interface as the simulator, translating
pysoem's exceptions into ecattool's (SdoAbort with the abort code, StateChangeError with the AL status).
The pysoem module is injectable so the adapter is tested with a fake in the test suite.
"""

from __future__ import annotations

from types import ModuleType
from typing import Any, Protocol, cast

from ecattool.errors import SdoAbort, SdoTimeout, StateChangeError, TargetError
from ecattool.esi.model import Identity
from ecattool.od.model import EcState
from ecattool.target.base import SlaveTarget

_STATE_CODES = {EcState.INIT: 1, EcState.PREOP: 2, EcState.BOOT: 3, EcState.SAFEOP: 4, EcState.OP: 8}
_CODE_STATES = {v: k for k, v in _STATE_CODES.items()}
#: how long a state change may take, in microseconds
STATE_TIMEOUT_US = 2_000_000


class _SdoError(Protocol):
    """What ecattool reads from pysoem's ``SdoError``."""

    abort_code: int


def _import_pysoem() -> ModuleType:
    try:
        import pysoem  # type: ignore[import-not-found]
    except ImportError:
        raise TargetError("the pysoem target needs the optional extra: pip install 'ecattool[pysoem]'") from None
    module: ModuleType = pysoem
    return module


class PysoemSlave:
    """One slave of a pysoem master, as an ecattool SlaveTarget."""

    def __init__(self, master: "PysoemTarget", position: int, slave: Any) -> None:
        self._master = master
        self._slave = slave
        self.position = position

    def identity(self) -> Identity:
        return Identity(int(self._slave.man), int(self._slave.id), int(self._slave.rev))

    def _translate(self, exc: Exception, index: int, subindex: int) -> Exception:
        mod = self._master.pysoem
        if isinstance(exc, getattr(mod, "SdoError", ())):
            return SdoAbort(index, subindex, int(cast(_SdoError, exc).abort_code))
        if isinstance(exc, (getattr(mod, "WkcError", ()), getattr(mod, "MailboxError", ()), getattr(mod, "PacketError", ()))):
            return SdoTimeout(index, subindex)
        return exc

    def sdo_upload(self, index: int, subindex: int, complete_access: bool = False) -> bytes:
        try:
            return bytes(self._slave.sdo_read(index, subindex, ca=complete_access))
        except Exception as exc:  # noqa: BLE001 - translated below
            raise self._translate(exc, index, subindex) from None

    def sdo_download(self, index: int, subindex: int, data: bytes, complete_access: bool = False,
                     expect_reply: bool = True) -> None:
        try:
            self._slave.sdo_write(index, subindex, bytes(data), ca=complete_access)
        except Exception as exc:  # noqa: BLE001
            err = self._translate(exc, index, subindex)
            if not expect_reply and isinstance(err, SdoTimeout):
                return  # e.g. Technosoft 2080h: the drive resets instead of answering
            raise err from None

    def state(self) -> EcState:
        self._master.master.read_state()
        return _CODE_STATES.get(int(self._slave.state) & 0x0F, EcState.INIT)

    def request_state(self, state: EcState) -> None:
        current = self.state()
        if state in (EcState.SAFEOP, EcState.OP) and not self._master.mapped:
            self._master.map()
        self._slave.state = _STATE_CODES[state]
        self._slave.write_state()
        reached = self._slave.state_check(_STATE_CODES[state], STATE_TIMEOUT_US)
        if int(reached) & 0x0F != _STATE_CODES[state]:
            al = int(getattr(self._slave, "al_status", 0) or 0)
            raise StateChangeError(state.value, current.value, al)

    def configure_dc(self, assign_activate: int, sync0_cycle_ns: int = 0) -> None:
        self._slave.dc_sync(bool(assign_activate), sync0_cycle_ns)

    def exchange(self, outputs: bytes) -> bytes:
        self._slave.output = bytes(outputs)
        self._master.master.send_processdata()
        self._master.master.receive_processdata(2000)
        return bytes(self._slave.input)


class PysoemTarget:
    """A pysoem master on a network interface, e.g. ``PysoemTarget("eth0")``."""

    def __init__(self, ifname: str, pysoem_module: ModuleType | None = None) -> None:
        self.pysoem = pysoem_module or _import_pysoem()
        self.master = self.pysoem.Master()
        try:
            self.master.open(ifname)
        except Exception as exc:  # noqa: BLE001
            raise TargetError(f"cannot open EtherCAT interface {ifname!r}: {exc}") from None
        count = self.master.config_init()
        if count <= 0:
            self.master.close()
            raise TargetError(f"no EtherCAT slaves found on {ifname!r}")
        self._slaves = [PysoemSlave(self, i, s) for i, s in enumerate(self.master.slaves)]
        self.mapped = False

    def map(self) -> None:
        self.master.config_map()
        self.mapped = True

    def slaves(self) -> list[SlaveTarget]:
        return list(self._slaves)

    def close(self) -> None:
        self.master.close()
