"""A real EtherCAT master through pysoem (optional extra: ``pip install ecattool[pysoem]``).

Implements the same :class:`~ecattool.target.base.SlaveTarget` interface as the simulator, translating
pysoem's exceptions into ecattool's (SdoAbort with the abort code, StateChangeError with the AL status).
The pysoem module is injectable so the adapter is tested with a fake in the test suite.

What pysoem (1.1, over SOEM) requires, and how the adapter meets it:

- ``Master.config_init()`` requests PRE-OP for every slave (automatic state change); afterwards the adapter
  switches ``manual_state_change`` on so that ``config_map()`` does not also push every slave on the bus to
  SAFE-OP (a drive that failed its PRE-OP steps stays in PRE-OP, a drive in OP is not knocked down).
- ``config_map()`` reads every slave's PDO assignment over CoE and lays out the IO map; it runs once, at the
  first SAFE-OP request, after the caller has written the PDO mappings (commission writes all drives'
  PRE-OP startup lists before any SAFE-OP). ``slave.output`` is a plain ``memcpy`` into that map, so the
  adapter checks the length before writing it.
- ``config_dc()`` (propagation delays, system time offsets) runs once before the first ``dc_sync``.
- A slave whose AL status shows the error indication ignores state requests until the master
  acknowledges it: the request carries ``STATE_ACK`` then.
- On the way to OP the adapter keeps process data flowing while it waits (SOEM's examples do the same): a
  drive takes SAFE-OP -> OP only once it receives outputs.
- Process data cycles are paced to the bus cycle (the SYNC0 cycle, else 1 ms): a drive in CSP takes one
  set-point per cycle, and frames sent as fast as Python can would skip set-points.
- Emergency messages are collected through ``add_emergency_callback``; without a callback pysoem raises
  ``Emergency`` from the SDO call that happened to pop it and the SDO's own result is lost.
- Once the IO map exists the process data never stops for long: a drive in OP leaves OP (AL status code
  0x001B) when its sync manager watchdog (100 ms by default) sees no outputs. A keeper thread sends a cycle
  with the last outputs whenever the caller has not cycled for a tenth of the shortest process data watchdog
  on the bus (10 ms by default; never less than two bus cycles), while it waits for an SDO, a state change or
  its own work, as SOEM's examples keep a process data thread. Not every bus cycle: SOEM waits for a frame by
  polling its socket without sleeping, and a keeper at 1 kHz beside an SDO that waits for its answer keeps two
  cores busy, so that on a small machine the frames themselves come back too late (an SDO then fails with no
  reply). SDO and process data calls release the GIL (pysoem ``always_release_gil``); SOEM serialises its
  frames itself. The keeper stops with
  :meth:`PysoemTarget.close`, or by itself once the caller has not used the target for ``KEEPER_IDLE_S``.
- A drive that leaves OP by itself (its watchdog, a fault) is noticed: every ``STATE_POLL_S`` of process data
  the adapter reads the AL status and raises a TargetError naming the state and the AL status code.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from types import ModuleType
from typing import Any, TypeVar

from ecattool.abort import al_status_text
from ecattool.errors import SdoAbort, SdoTimeout, SdoTooLarge, StateChangeError, TargetError
from ecattool.esi.model import Identity
from ecattool.od.model import EcState
from ecattool.target.base import UNKNOWN_SIZE_FIRST, UNKNOWN_SIZE_MAX, SlaveTarget, check_upload
from ecattool.target.timeouts import REPEATS, BusLimits, window_text

#: how long a state change may take, in microseconds (SOEM's own EC_TIMEOUTSTATE is 2 s)
STATE_TIMEOUT_US = 2_000_000
#: how long an empty bus is asked again before it counts as empty (a link just brought up drops the first frames)
LINK_WAIT_S = 2.0
#: how long one process data cycle may take to come back, in microseconds (pysoem's default)
PROCESSDATA_TIMEOUT_US = 2000
#: the process data cycle when no DC cycle is configured, in nanoseconds
DEFAULT_CYCLE_NS = 1_000_000
#: how long one state check waits before the GIL is given back (the keeper thread may cycle) or, on the way to OP,
#: the next process data cycle goes out, in microseconds
OP_POLL_US = 10_000
#: the keeper thread sends a cycle when the caller has not for this many bus cycles, or for WATCHDOG_SHARE of the
#: shortest process data watchdog on the bus if that is longer (see PysoemTarget.keep_interval_s)
KEEP_CYCLING_AFTER = 2
#: the share of a process data watchdog the keeper lets pass without a cycle
WATCHDOG_SHARE = 0.1
#: the process data watchdog of an ESC that has not been told otherwise (0x0400 = 2498, 0x0420 = 1000), in seconds
DEFAULT_WATCHDOG_S = 0.1
#: the keeper thread stops by itself when the target has not been used for this long, in seconds (a drive still in
#: OP then leaves OP through its own watchdog: the safe end)
KEEPER_IDLE_S = 5.0
#: how often process data exchanges read the AL status to notice a drive that left OP by itself, in seconds
STATE_POLL_S = 0.1
#: how long SOEM waits for one SDO answer, in microseconds (its own default is 0.7 s); an upload that got none is
#: asked once more (PysoemSlave.sdo_upload)
SDO_TIMEOUT_US = 2_000_000
_STATE_NAMES = {EcState.INIT: "INIT_STATE", EcState.PREOP: "PREOP_STATE", EcState.BOOT: "BOOT_STATE",
                EcState.SAFEOP: "SAFEOP_STATE", EcState.OP: "OP_STATE"}
#: PacketError.error_code of SOEM: "data container too small for type"
_PACKET_TOO_SMALL = 3
_T = TypeVar("_T")


class _Larger(Exception):
    """The slave announced more than SOEM's default buffer holds, where the object's size is not known."""


def _import_pysoem() -> ModuleType:
    try:
        # pysoem ships no stubs; without the extra it is not installed at all
        import pysoem  # type: ignore[import-not-found, import-untyped, unused-ignore]
    except ImportError:
        raise TargetError("the pysoem target needs the optional extra: pip install 'ecattool[pysoem]'") from None
    module: ModuleType = pysoem
    return module


def open_advice(ifname: str, euid: int | None = None, interfaces: str = "/sys/class/net") -> str:
    """Why a master cannot open ``ifname`` where it can be told (appended to the error): an interface this machine
    does not have, or a user without the right to open a raw socket on it (root or CAP_NET_RAW)."""
    import os

    if os.path.isdir(interfaces) and not os.path.exists(os.path.join(interfaces, ifname)):
        return f" (this machine has no network interface {ifname!r}: 'ip link' lists them)"
    uid = os.geteuid() if euid is None else euid
    if uid != 0:
        return (" (a master sends raw Ethernet frames: run as root, or give the Python interpreter CAP_NET_RAW, "
                "e.g. sudo setcap cap_net_raw+ep \"$(readlink -f \"$(command -v python3)\")\")")
    return ""


def dc_sync_args(assign_activate: int, sync0_cycle_ns: int, sync0_shift_ns: int = 0) -> tuple[Any, ...]:
    """The arguments of pysoem's ``slave.dc_sync`` for an ESI AssignActivate word.

    pysoem writes 0x0980 = 0 and 0x0981 = 0x03 (cyclic unit + SYNC0) or 0x07 (+ SYNC1, when
    ``sync1_cycle_time`` is given); the low byte of AssignActivate (latch unit assignment) is not written.
    Any other activation cannot be expressed through pysoem."""
    act = (assign_activate >> 8) & 0xFF
    if act == 0:
        return (False, 0)
    if act == 0x03:
        return (True, sync0_cycle_ns, sync0_shift_ns)
    if act == 0x07:
        return (True, sync0_cycle_ns, sync0_shift_ns, 0)  # SYNC1 fires with SYNC0
    raise TargetError(f"AssignActivate 0x{assign_activate:04X}: pysoem can only activate SYNC0 (0x0300) or "
                      "SYNC0 + SYNC1 (0x0700), or switch DC off (0x0000)")


class PysoemSlave:
    """One slave of a pysoem master, as an ecattool SlaveTarget."""

    def __init__(self, master: "PysoemTarget", position: int, slave: Any) -> None:
        self._master = master
        self._slave = slave
        self.position = position
        #: emergency messages the slave sent (pysoem ``Emergency`` objects), oldest first
        self.emergencies: list[Any] = []
        slave.add_emergency_callback(self.emergencies.append)
        #: the state last requested (a slave asked for OP is watched for leaving it by itself)
        self.requested: EcState | None = None
        #: uploads asked again because a try got no answer
        self.repeats = 0
        self._state_read_at = master.clock()

    @property
    def _mod(self) -> ModuleType:
        return self._master.pysoem

    @property
    def raw(self) -> Any:
        """The pysoem slave itself (SII EEPROM, SDO Information, AL status: ``ecattool.online`` reads them)."""
        return self._slave

    def identity(self) -> Identity:
        return Identity(int(self._slave.man), int(self._slave.id), int(self._slave.rev))

    def _name(self) -> str:
        """The slave's name as SOEM read it from the SII ('' where it has none)."""
        try:
            name = self._slave.name
        except Exception:  # noqa: BLE001 - a name is a courtesy in an error
            return ""
        text = name.decode("latin-1", "replace") if isinstance(name, (bytes, bytearray)) else str(name or "")
        return text.strip("\0 ")

    def _where(self, index: int, subindex: int) -> str:
        return f"slave {self.position}, 0x{index:04X}:{subindex:02X}"

    def _sdo(self, fn: Callable[[], _T], index: int, subindex: int) -> _T:
        """Run one pysoem SDO call, its exceptions translated into ecattool's."""
        mod = self._mod
        self._master.touch()
        try:
            return fn()
        except mod.SdoError as exc:
            raise SdoAbort(index, subindex, int(exc.abort_code)) from None
        except mod.WkcError:  # the mailbox answer did not come (the working counter stayed 0)
            raise SdoTimeout(index, subindex, self.position, self._name(),
                             f"no reply in {window_text(self._master.limits)}") from None
        except mod.MailboxError as exc:
            where = self._where(index, subindex)
            raise TargetError(f"{where}: mailbox error {exc.error_code}: {exc.desc}") from None
        except mod.PacketError as exc:
            raise TargetError(f"{self._where(index, subindex)}: mailbox packet error {exc.error_code}") from None
        except mod.Emergency as exc:  # only when no callback is registered; kept as a TargetError anyway
            raise TargetError(f"{self._where(index, subindex)}: emergency {exc}") from None

    def sdo_upload(self, index: int, subindex: int, complete_access: bool = False, size: int | None = None) -> bytes:
        """The object's value, read into a buffer of exactly ``size`` octets (its type's): SOEM refuses an
        announced size larger than its buffer ("data container too small", PacketError 3), which is an
        :class:`SdoTooLarge` here. Without ``size``: SOEM's default buffer (UNKNOWN_SIZE_FIRST), then once
        UNKNOWN_SIZE_MAX. SOEM copies the segments of a segmented upload without checking its buffer's end (docs/
        at-the-machine.md, "When the master crashes"): that is why the master runs in a child process."""
        mod = self._mod

        def read(n: int) -> bytes:
            try:
                return bytes(self._slave.sdo_read(index, subindex, n, ca=complete_access))
            except SystemError:
                # SOEM read an announced size of 2^31 octets or more as negative and passed it on as the reply's
                # length; pysoem cannot make bytes of it (with a larger buffer SOEM copies that much: a crash)
                raise SdoTooLarge(index, subindex, self.position, n, known=size is not None) from None
            except mod.PacketError as exc:
                if exc.error_code != _PACKET_TOO_SMALL:
                    raise
                if size is None and n < UNKNOWN_SIZE_MAX:
                    raise _Larger() from None
                raise SdoTooLarge(index, subindex, self.position, n, known=size is not None) from None

        def read_bounded() -> bytes:
            if size is not None:
                return check_upload(read(max(1, size)), size, index, subindex, self.position)
            try:
                return read(UNKNOWN_SIZE_FIRST)
            except _Larger:
                return check_upload(read(UNKNOWN_SIZE_MAX), None, index, subindex, self.position)

        def read_again() -> bytes:
            # an upload changes nothing on the slave: one that got no answer, or a stale mailbox error (the answer
            # to an earlier request, e.g. a refused SDO Information request), is asked again, REPEATS times at the
            # most, after SOEM's error list is emptied and not before the slave's mailbox window (its request and
            # response timeouts) has passed since the last try: a request whose frames did not come back fails at
            # once, and a slave that is away for a moment gets its whole window each time. SOEM gives each request
            # the next mailbox counter (1..7, ETG.1000.6 5.6: the slave takes a request with the counter of the
            # previous one as a repeated write), and itself toggles SM1's repeat request when a reply was lost on
            # its way (ecx_mbxreceive): docs/at-the-machine.md, "Mailbox repeats"
            window = self._master.limits.mailbox_s
            for attempt in range(REPEATS + 1):
                started = self._master.clock()
                try:
                    return read_bounded()
                except (mod.WkcError, mod.MailboxError):
                    if attempt == REPEATS:
                        raise
                    self._master.drain_errors()
                    self.repeats += 1
                    rest = started + window - self._master.clock()
                    if rest > 0:
                        self._master.sleep(rest)
            raise AssertionError("unreachable")  # pragma: no cover

        try:
            return self._sdo(read_again, index, subindex)
        except SdoTimeout:
            raise SdoTimeout(index, subindex, self.position, self._name(),
                             f"no reply in {REPEATS + 1} tries of {window_text(self._master.limits)}") from None

    def sdo_download(self, index: int, subindex: int, data: bytes, complete_access: bool = False,
                     expect_reply: bool = True) -> None:
        try:
            self._sdo(lambda: self._slave.sdo_write(index, subindex, bytes(data), ca=complete_access),
                      index, subindex)
        except SdoTimeout:
            if expect_reply:
                raise
            # e.g. Technosoft 2080h: the drive resets instead of answering

    def _al_status(self) -> int:
        """The AL status register (state and error indication) as the master last read it."""
        self._master.master.read_state()
        return int(self._slave.state)

    def _decode(self, raw: int) -> EcState:
        for state, name in _STATE_NAMES.items():
            if raw & 0x0F == getattr(self._mod, name):
                return state
        raise TargetError(f"slave {self.position} does not answer (AL status 0x{raw:04X})")

    def state(self) -> EcState:
        return self._decode(self._al_status())

    def request_state(self, state: EcState) -> None:
        mod = self._mod
        raw = self._al_status()
        current = self._decode(raw)
        if state in (EcState.SAFEOP, EcState.OP) and not self._master.mapped:
            self._master.map()
        code = int(getattr(mod, _STATE_NAMES[state]))
        ack = int(mod.STATE_ACK) if raw & int(mod.STATE_ERROR) else 0  # never on a slave without an error
        self._master.touch()
        self.requested = state
        self._slave.state = code | ack
        self._slave.write_state()
        if int(reached := self._wait_for(code)) & 0x0F != code:
            if not reached:  # SOEM reads state 0 when the AL status read itself got no answer
                raise TargetError(f"slave {self.position}: no answer while requesting {state.value} (the frames "
                                  "did not come back)")
            raise StateChangeError(state.value, current.value, int(self._slave.al_status or 0))

    def _wait_for(self, code: int) -> int:
        """Wait for the requested state. On the way to OP the process data keeps flowing: a drive takes
        SAFE-OP -> OP only once it has received outputs, and its sync manager watchdog is running."""
        reached = 0
        if code != int(self._mod.OP_STATE):
            # short checks: pysoem's state_check holds the GIL, the keeper thread cycles between two of them
            for _ in range(math.ceil(STATE_TIMEOUT_US / OP_POLL_US)):
                reached = int(self._slave.state_check(code, OP_POLL_US))
                if reached & 0x0F == code:
                    break
            return reached
        # as many paced cycles as STATE_TIMEOUT_US holds (>= 2 s); each state check may add up to OP_POLL_US, so
        # a drive that never reaches OP is given up after 2 s + cycles x OP_POLL_US at the most (~22 s at 1 ms)
        for _ in range(math.ceil(STATE_TIMEOUT_US / 1e6 / self._master.cycle_s)):
            self._master.cycle()
            reached = int(self._slave.state_check(code, OP_POLL_US))
            if reached & 0x0F == code:
                break
        return reached

    def configure_dc(self, assign_activate: int, sync0_cycle_ns: int = 0, sync0_shift_ns: int = 0) -> None:
        if sync0_cycle_ns <= 0:  # the ESC reads a SYNC0 cycle of 0 as one single pulse: SYNC0 runs at the bus cycle
            sync0_cycle_ns = round(self._master.cycle_s * 1e9)
        args = dc_sync_args(assign_activate, sync0_cycle_ns, sync0_shift_ns)
        if args[0]:
            self._master.configure_dc()
            self._master.cycle_s = sync0_cycle_ns / 1e9
        self._slave.dc_sync(*args)

    def exchange(self, outputs: bytes) -> bytes:
        size = len(self._slave.output)
        if len(outputs) != size:
            raise TargetError(f"slave {self.position}: {len(outputs)} output bytes for a {size}-byte output image "
                              "(the PDO mapping the master read differs from the project's)")
        with self._master.lock:  # the keeper thread never sends a half-written image
            self._slave.output = bytes(outputs)
            wkc = self._master.cycle()
        if wkc <= 0:
            raise TargetError(f"slave {self.position}: no process data came back (working counter {wkc})")
        # ETG.1000.4: every slave adds 2 for its outputs (in OP) and 1 for its inputs. With every slave in OP
        # (as the master last read them) anything but the full count is a slave missing its part of the frame;
        # a counter above the full count is never right (a frame spoilt on the way, or an unknown slave).
        expected = full_working_counter(self._master.master)
        op = int(self._mod.OP_STATE)
        all_op = all(int(s.state) & 0x0F == op for s in self._master.master.slaves)
        if wkc > expected or (all_op and wkc != expected):
            self._check_still_op(now=True)  # the likeliest cause: the slave left OP
            raise TargetError(f"slave {self.position}: process data working counter {wkc}, expected {expected}")
        self._check_still_op()
        return bytes(self._slave.input)

    def _check_still_op(self, now: bool = False) -> None:
        """Every STATE_POLL_S (or ``now``): a slave asked for OP must still be there. In SAFE-OP a drive may still
        take its outputs (the working counter stays full): only its AL status tells that it left OP by itself."""
        t = self._master.clock()
        if self.requested is not EcState.OP or (not now and t - self._state_read_at < STATE_POLL_S):
            return
        self._state_read_at = t
        raw = self._al_status()
        if raw & 0x0F != int(self._mod.OP_STATE):
            code = int(self._slave.al_status or 0)
            raise TargetError(f"slave {self.position} left OP by itself: it is in {self._decode(raw).value} with AL "
                              f"status code 0x{code:04X} ({al_status_text(code)})")


class PysoemTarget:
    """A pysoem master on a network interface, e.g. ``PysoemTarget("eth0")``."""

    def __init__(self, ifname: str, pysoem_module: ModuleType | None = None,
                 clock: Callable[[], float] = time.monotonic, sleep: Callable[[float], None] = time.sleep,
                 keep_cycling: bool = True, keeper_idle_s: float = KEEPER_IDLE_S,
                 limits: BusLimits | None = None) -> None:
        self.pysoem = pysoem_module or _import_pysoem()
        #: how long to wait for the slaves (their ESI timeouts where known: ecattool.target.timeouts)
        self.limits = limits or BusLimits()
        #: the bus cycle in seconds: the SYNC0 cycle once DC is configured, else 1 ms
        self.cycle_s = DEFAULT_CYCLE_NS / 1e9
        self.clock = clock
        self._sleep = sleep
        self._next_cycle = clock()
        #: held while the IO map is written or sent (the caller's cycles and the keeper's)
        self.lock = threading.RLock()
        self.keep_cycling = keep_cycling
        self.keeper_idle_s = keeper_idle_s
        #: cycles the keeper thread sent while the caller did something else
        self.kept_cycles = 0
        self._used = clock()
        self._stop = threading.Event()
        self._keeper: threading.Thread | None = None
        self._watchdog_s = DEFAULT_WATCHDOG_S
        self.master = self.pysoem.Master()
        # SDO and process data calls wait in SOEM without the GIL: the keeper thread runs meanwhile
        self.master.always_release_gil = True
        # SOEM waits 0.7 s for a mailbox answer (EC_TIMEOUTRXM); the slave's own request + response timeouts (its
        # ESI's, else 0.1 + 2 s) are what it may take, and on a loaded machine the frames carrying the answer too.
        # A longer wait costs nothing when the answer comes
        for name in ("sdo_read_timeout", "sdo_write_timeout"):
            if hasattr(self.master, name):
                setattr(self.master, name, max(SDO_TIMEOUT_US, round(self.limits.mailbox_s * 1e6)))
        try:
            self.master.open(ifname)
        except Exception as exc:  # noqa: BLE001 - ConnectionError, or an OS error on some platforms
            raise TargetError(f"cannot open EtherCAT interface {ifname!r}: {exc}{open_advice(ifname)}") from None
        count = self.master.config_init()
        # a link that was just brought up (a NIC negotiating, a fresh veth pair) drops the first frames: ask again
        # for up to LINK_WAIT_S before saying the bus is empty
        deadline = time.monotonic() + LINK_WAIT_S
        while count <= 0 and time.monotonic() < deadline:
            time.sleep(0.2)
            count = self.master.config_init()
        if count <= 0:
            self.master.close()
            raise TargetError(f"no EtherCAT slaves found on {ifname!r} (asked for {LINK_WAIT_S:g} s)")
        # config_init has requested PRE-OP (without waiting for it); from here on ecattool requests every state
        self.master.state_check(int(self.pysoem.PREOP_STATE), round(self.limits.preop_s * 1e6))
        self.master.manual_state_change = 1
        self._slaves = [PysoemSlave(self, i, s) for i, s in enumerate(self.master.slaves)]
        self.mapped = False
        self.dc_configured = False

    def sleep(self, seconds: float) -> None:
        """Wait (the injectable sleep: a test's virtual clock)."""
        self._sleep(seconds)

    def drain_errors(self) -> None:
        """Empty SOEM's error list: an error left there (e.g. by a refused SDO Information request, one per
        mailbox answer) is raised by pysoem from the next call on that master, whatever that call's own result."""
        collect = getattr(self.master, "_collect_mailbox_errors", None)
        if collect is None:
            return
        try:
            collect()
        except Exception:  # noqa: BLE001 - the errors are the stale ones being dropped
            pass

    def map(self) -> None:
        """Lay out the IO map from the PDO mappings the slaves report (pysoem ``config_map``)."""
        try:
            self.master.config_map()
        except self.pysoem.ConfigMapError as exc:
            first = exc.error_list[0] if exc.error_list else None
            detail = str(first)
            if isinstance(first, self.pysoem.SdoError):
                detail = f"slave {first.slave_pos - 1}, 0x{first.index:04X}:{first.subindex:02X}: {first.desc}"
            elif isinstance(first, self.pysoem.MailboxError):
                detail = f"slave {first.slave_pos - 1}: mailbox error {first.error_code}: {first.desc}"
            raise TargetError(f"reading the PDO mappings failed ({len(exc.error_list)} errors, "
                              f"first: {detail})") from None
        self.mapped = True
        self._watchdog_s = self._shortest_watchdog_s()
        if self.keep_cycling and self._keeper is None:
            self._keeper = threading.Thread(target=self._keep, name="ecattool-pysoem-keeper", daemon=True)
            self._keeper.start()

    def _shortest_watchdog_s(self) -> float:
        """The shortest process data watchdog the slaves run (0 = switched off does not count); the ESC default
        where none says."""
        times = []
        for slave in self.master.slaves:
            try:
                ms = float(slave.get_watchdog("processdata"))
            except self.pysoem.WkcError:  # the registers did not answer: the default stands
                continue
            if ms > 0:
                times.append(ms / 1000)
        return min(times, default=DEFAULT_WATCHDOG_S)

    @property
    def keep_interval_s(self) -> float:
        """How long the keeper thread lets the process data rest while the caller does something else."""
        return max(KEEP_CYCLING_AFTER * self.cycle_s, WATCHDOG_SHARE * self._watchdog_s)

    def touch(self) -> None:
        """The caller uses the target (the keeper's idle time starts again)."""
        self._used = self.clock()

    def _keep(self) -> None:
        """The keeper thread: a cycle with the last outputs whenever none has gone out for ``keep_interval_s``.
        Ends with close(), or once the caller has been idle for keeper_idle_s."""
        while not self._stop.wait(self.cycle_s):
            now = self.clock()
            if now - self._used > self.keeper_idle_s:
                return
            caller_late = now >= self._next_cycle - self.cycle_s + self.keep_interval_s
            if not caller_late or not self.lock.acquire(blocking=False):
                continue
            try:
                self._send_receive(now)
                self.kept_cycles += 1
            except Exception:  # noqa: BLE001 - a closed interface: the caller's next call reports it
                return
            finally:
                self.lock.release()

    def configure_dc(self) -> None:
        """Locate the DC slaves and measure propagation delays (pysoem ``config_dc``), once."""
        if not self.dc_configured:
            if not self.master.config_dc():
                raise TargetError("no slave with distributed clocks found on the bus")
            self.dc_configured = True

    def cycle(self) -> int:
        """One process data cycle of the bus, paced: it starts one bus cycle after the previous one (a drive
        in CSP/CSV takes one set-point per SYNC0 cycle, faster frames would skip set-points). Returns the
        working counter."""
        with self.lock:
            self.touch()
            now = self.clock()
            if now < self._next_cycle:
                self._sleep(self._next_cycle - now)
                now = self._next_cycle
            return self._send_receive(now)

    def _send_receive(self, now: float) -> int:
        """One frame of process data (the lock held) at ``now``; the next cycle is due one bus cycle later."""
        self._next_cycle = now + self.cycle_s
        self.master.send_processdata()
        return int(self.master.receive_processdata(PROCESSDATA_TIMEOUT_US))

    def slaves(self) -> list[SlaveTarget]:
        return list(self._slaves)

    def close(self) -> None:
        self._stop.set()
        if self._keeper is not None:
            self._keeper.join(timeout=1.0)
        with self.lock:
            self.master.close()


#: the most process data bytes SOEM puts into one LRW (EC_MAXLRWDATA less the first frame's DC datagram)
_ONE_FRAME = 1486 - 20


def full_working_counter(master: Any) -> int:
    """The working counter of a bus whose every slave takes part: 2 per slave with outputs, 1 per slave with
    inputs (ETG.1000.4, LRW). SOEM's own ``expected_wkc`` (SOEM 1.4, as pysoem 1.1.13 bundles it) counts no input
    for a slave whose inputs are bits (an EL1002's two, an EK1300's): its ESC still adds 1, and the master saw
    "working counter 41, expected 39" on a bus in OP. Where the image spans several frames SOEM's count stands
    (a slave split across frames counts once per frame)."""
    slaves = list(master.slaves)
    if sum(len(s.output) + len(s.input) for s in slaves) > _ONE_FRAME:
        return int(master.expected_wkc)
    return sum(2 for s in slaves if len(s.output)) + sum(1 for s in slaves if len(s.input))

