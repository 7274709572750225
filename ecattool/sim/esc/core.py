"""The EtherCAT slave controller: the register file and process RAM a master reads and writes with datagrams.

:class:`Esc` answers the *ECAT* side (``ecat_read`` / ``ecat_write`` / ``logical``: what the datagram engine
calls) and offers the *PDI* side to the slave application (``pdi_*`` methods; the application is told what the
master did through :class:`EscApplication`). Sync managers, FMMUs, the SII EEPROM interface and the distributed
clock are modelled as the ET1100 data sheet describes them; see docs/virtual-bus.md for what is left out.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

from ecattool.sim.esc import registers as R
from ecattool.sim.esc.dc import Clock, next_pulse, sync1_train
from ecattool.sim.esc.eeprom import SiiEeprom
from ecattool.sim.esc.mapping import Derived, Piece, Segment, pieces, segments

_WRITABLE = R.writable_mask()
_WD_DIV, _WD_PD = R.WD_DIVIDER, R.WD_TIME_PD
#: the loop settings: DL control bits 8..15, two per port
_LOOP = R.DL_CONTROL + 1
_DC_OFFSET, _DC_DELAY = R.DC_SYSTEM_OFFSET, R.DC_SYSTEM_DELAY

#: SM control register: operation mode (bits 0..1) and direction (bits 2..3)
SM_MODE_BUFFERED, SM_MODE_MAILBOX = 0x0, 0x2
SM_DIR_READ, SM_DIR_WRITE = 0x0, 0x1  # ECAT reads (inputs, SM1/SM3) / ECAT writes (outputs, SM0/SM2)
SM_WATCHDOG_TRIGGER = 0x40


class EscApplication:
    """What the slave application behind the PDI is told. The default does what an ESC in device emulation
    does without a microcontroller: the AL status follows the AL control."""

    def al_control(self, esc: "Esc", control: int) -> None:
        esc.set_al_status(control & 0x0F, error=False, code=0)

    def mailbox_written(self, esc: "Esc", sm: int, data: bytes) -> None:
        """The master completed a write of mailbox SM ``sm`` (its whole buffer is ``data``)."""

    def mailbox_read(self, esc: "Esc", sm: int) -> None:
        """The master read mailbox SM ``sm`` to its last byte: the buffer is empty again."""

    def mailbox_repeat(self, esc: "Esc", sm: int) -> None:
        """The master toggled the repeat request of SM ``sm``."""

    def buffer_written(self, esc: "Esc", sm: int, data: bytes) -> None:
        """The master completed a write of buffered (3-buffer) SM ``sm``."""

    def buffer_read(self, esc: "Esc", sm: int) -> None:
        """The master read buffered SM ``sm`` to its last byte."""

    def dc_activation(self, esc: "Esc", activation: int) -> None:
        """The master wrote the DC activation register 0x0981."""

    def pd_watchdog_expired(self, esc: "Esc") -> None:
        """The process data watchdog expired: no write of a watchdog-triggering SM for longer than its time.
        An ESC without an application (digital I/O) would release its outputs; a slave application in OP
        goes to SAFE-OP with AL status code 0x001B (ETG.1000.6, as the slave stack code does)."""

    def frame_done(self, esc: "Esc") -> None:
        """A frame has passed this slave (still inside the frame: only ESC memory may change here)."""

    def after_frame(self, esc: "Esc") -> None:
        """The frame has left the slave: the application's processor runs what its events asked for since its
        last run (an SM2 write, a SYNC0 pulse), as a slave's microcontroller does on its PDI interrupt after the
        ESC has answered the frame. What it writes into the ESC is read by the master's next frame."""


@dataclass(slots=True)
class _Sm:
    start: int
    length: int
    control: int
    #: the enable bit (register +6 bit 0) as the master wrote it
    enabled: bool
    #: whether the ESC serves the area: enabled, with a length, inside the process memory the ESC has (an SM over
    #: the register area 0x0000-0x0FFF or past the memory end is not activated, and never shadows a register)
    active: bool = False

    @property
    def end(self) -> int:
        return self.start + self.length

    @property
    def mailbox(self) -> bool:
        return self.control & 0x3 == SM_MODE_MAILBOX

    @property
    def ecat_writes(self) -> bool:
        return (self.control >> 2) & 0x3 == SM_DIR_WRITE


@dataclass(slots=True)
class _Fmmu:
    logical: int
    length: int
    start_bit: int
    stop_bit: int
    physical: int
    physical_bit: int
    read: bool
    write: bool

    def bit_range(self) -> tuple[int, int]:
        """The logical bits [first, end) the FMMU maps."""
        return self.logical * 8 + self.start_bit, (self.logical + self.length - 1) * 8 + self.stop_bit + 1


#: what a logical access may map: the datagram's data (a bytearray, or a view of the frame being answered)
Buffer = bytearray | memoryview

#: one FMMU share of a planned logical access: the :data:`~ecattool.sim.esc.mapping.Piece` fields, then the SM
#: whose area it is in (-1: plain process RAM), whether the master may write that SM, the SM's first byte where
#: the share reaches its last byte (its buffer completes; else -1), and whether such a write triggers the process
#: data watchdog
PlanOp = tuple[bool, bool, int, int, int, int, bool, int, int, int, int, bool, int, bool]
_PLAN_LIMIT = 64


@dataclass(frozen=True, slots=True)
class _Plan:
    """A logical access whose every FMMU share lies inside one buffered sync manager or one run of plain process
    RAM; ``copy``: a read share comes before a write share over the same datagram bytes. ``general``: the
    access is not such a one (:meth:`Esc.logical_general` serves it)."""

    ops: tuple[PlanOp, ...]
    copy: bool
    general: bool


_GENERAL = _Plan((), False, True)


def _hits(addr: int, end: int, *areas: tuple[int, int]) -> tuple[bool, ...]:
    """For each (first, size) of ``areas``: whether [addr, end) covers a byte of it."""
    return tuple(addr < first + size and end > first for first, size in areas)


def _put_bits(source: Buffer | bytes, source_shift: int, target: Buffer | bytes, target_shift: int,
              mask: int) -> bytes:
    """``target`` (little-endian bytes) with the ``mask`` bits of ``source`` from bit ``source_shift`` on put at
    bit ``target_shift``, the other bits as they were: an FMMU share that is not on whole bytes."""
    bits = (int.from_bytes(source, "little") >> source_shift) & mask
    current = int.from_bytes(target, "little")
    return ((current & ~(mask << target_shift)) | (bits << target_shift)).to_bytes(len(target), "little")


@lru_cache(maxsize=1024)
def _read_hits(addr: int, end: int) -> tuple[bool, bool, bool, bool, bool, bool, bool, bool]:
    """Which registers whose value is computed when read a read of [addr, end) covers: DL status, the SMs, the
    system time, the event request, the DC activation status to the next SYNC1 pulse, the watchdog status;
    then the EEPROM control/status (a busy EEPROM advances), and the AL status (its event is cleared). Once per
    (addr, end): a master reads the same few places every cycle."""
    dl, sm, time, events, dc, wd, eeprom, al = _hits(
        addr, end, (R.DL_STATUS, 2), (R.SM, R.SM_SIZE * 16), (R.DC_SYSTEM_TIME, 8), (R.ECAT_EVENT_REQUEST, 4),
        (R.DC_ACTIVATION_STATUS, R.DC_SYNC1_CYCLE - R.DC_ACTIVATION_STATUS), (R.WD_STATUS_PD, 2),
        (R.EEPROM_CONTROL, 2), (R.AL_STATUS, 1))
    return dl, sm, time, events, dc, wd, eeprom, al


@lru_cache(maxsize=1024)
def _write_hits(addr: int, end: int) -> tuple[bool, bool, bool, bool, bool, bool, bool, bool, bool, bool]:
    """Which registers with an effect a write of [addr, end) covers: the SMs, the FMMUs, the error counters, the
    watchdog divider and times, the watchdog counters, the EEPROM control, the receive time latch, the system
    time, the DC activation, the AL control. Once per (addr, end)."""
    sms, fmmus, rx, wd, wd_counter, eeprom, receive, time, activation, al = _hits(
        addr, end, (R.SM, R.SM_SIZE * 16), (R.FMMU, R.FMMU_SIZE * 16), (R.RX_ERROR_COUNTER, 0x14),
        (R.WD_DIVIDER, R.WD_TIME_PD + 2 - R.WD_DIVIDER), (R.WD_COUNTER_PD, 2), (R.EEPROM_CONTROL, 2),
        (R.DC_RECEIVE_TIME, 4), (R.DC_SYSTEM_TIME, 8), (R.DC_ACTIVATION, 1), (R.AL_CONTROL, 2))
    return sms, fmmus, rx, wd, wd_counter, eeprom, receive, time, activation, al


@lru_cache(maxsize=1024)
def _writable_runs(addr: int, end: int) -> tuple[tuple[int, int], ...]:
    """The runs [lo, hi) of [addr, end) the master may write: every byte of the process RAM, the registers of
    :data:`_WRITABLE`."""
    runs: list[tuple[int, int]] = []
    for a in range(addr, end):
        if a >= R.PROCESS_RAM or _WRITABLE[a]:
            if runs and runs[-1][1] == a:
                runs[-1] = (runs[-1][0], a + 1)
            else:
                runs.append((a, a + 1))
    return tuple(runs)


@lru_cache(maxsize=None)
def _dl_status(loop: int, *links: bool) -> int:
    """DL status 0x0110 from the loop settings (DL control bits 8..15) and the link of each port; a pure
    function of at most 256 x 16 arguments, so it is computed once per combination (the bus asks every frame)."""
    v = 0x0001 | 0x0002  # PDI operational (EEPROM loaded), PDI watchdog reloaded
    for port, linked in enumerate(links):
        setting = (loop >> (2 * port)) & 0x3
        # loop setting: 0 auto, 1 auto close (closed without a link), 2 always open, 3 always closed
        closed = setting == 3 or (setting in (0, 1) and not linked)
        v |= (0x10 << port) if linked else 0
        v |= (1 << (8 + 2 * port)) if closed else 0
        v |= (1 << (9 + 2 * port)) if linked and not closed else 0
    return v


class Esc:
    """One EtherCAT slave controller. ``eeprom``: the SII image; ``clock``: the local clock (ns)."""

    def __init__(self, eeprom: bytes, *, app: EscApplication | None = None, ram_bytes: int = 8192,
                 sms: int = 8, fmmus: int = 8, read_8: bool = True, clock: Clock | None = None,
                 esc_type: int = 0x11, revision: int = 0x00, build: int = 0x0003) -> None:
        self.app = app or EscApplication()
        self.mem = bytearray(R.PROCESS_RAM + ram_bytes)
        self.sm_count, self.fmmu_count = min(sms, 16), min(fmmus, 16)
        self.eeprom = SiiEeprom(eeprom, read_8=read_8)
        self.clock = clock or Clock()
        #: physical link per port (set by the bus: port 0 to the master side, port 1 to the next slave)
        self.link = [True, False, False, False]
        self._sm_full = [False] * 16
        self._sm_pdi_off = [False] * 16
        self._sms: list[_Sm] | None = None
        self._fmmus: list[_Fmmu] | None = None
        #: per (address, length): its pieces at SM boundaries / its FMMU geometry, until the SMs / FMMUs change
        self._segment_cache: dict[tuple[int, int], tuple[Segment, ...]] = {}
        #: the active mailbox SMs the master reads (their "full" is an event request), with the SM list
        self._read_mailboxes: tuple[int, ...] = ()
        self._piece_memo: Derived[tuple[int, int], tuple[Piece, ...]] = Derived()
        #: per (logical address, length): its :class:`_Plan`, until the SMs / FMMUs change
        self._plans: dict[tuple[int, int], _Plan] = {}
        self._al_event = False
        self.frame_ns = 0
        #: host time (ns) of the last process data watchdog trigger while the watchdog runs, else None
        self._wd_pd_since: int | None = None
        #: the start time of cyclic operation the cyclic unit took when it was activated
        self._dc_start: int | None = None
        m = self.mem
        m[R.TYPE], m[R.REVISION] = esc_type, revision
        m[R.BUILD:R.BUILD + 2] = build.to_bytes(2, "little")
        m[R.FMMUS_SUPPORTED], m[R.SMS_SUPPORTED] = self.fmmu_count, self.sm_count
        m[R.RAM_SIZE] = ram_bytes // 1024
        m[R.PORT_DESCRIPTOR] = 0x0F  # ports 0 and 1 MII, 2 and 3 not implemented
        # features: FMMU bit operation, DC, 64-bit DC, enhanced link detection; LRW and xRW supported
        self._put16(R.FEATURES, 0x000C | 0x0040 | 0x0100)
        # PDI control 0x0140 and ESC configuration 0x0141 are loaded from SII word 0 (_load_eeprom_config); an
        # image that leaves the word 0 gets an SPI PDI, and device emulation where there is no application
        self._default_pdi = 0x0005 if app else 0x0105
        self._put16(R.PDI_CONTROL, self._default_pdi)
        self._put16(R.WD_DIVIDER, 0x09C2)  # 100 us
        self._put16(R.WD_TIME_PDI, 1000)
        self._put16(R.WD_TIME_PD, 1000)
        self._put16(R.DC_SPEED_START, 0x1000)
        self._put16(R.DC_FILTER_DEPTH, 0x0C04)
        self._put16(R.ECAT_EVENT_MASK, 0x0000)
        self._sync_eeprom_status()
        self.set_al_status(1, error=False, code=0)
        self._al_event = False
        self._load_eeprom_config()

    # ------------------------------------------------------------------------------------------
    # small helpers
    # ------------------------------------------------------------------------------------------
    def _put16(self, addr: int, v: int) -> None:
        self.mem[addr:addr + 2] = (v & 0xFFFF).to_bytes(2, "little")

    def u16(self, addr: int) -> int:
        return int.from_bytes(self.mem[addr:addr + 2], "little")

    def u32(self, addr: int) -> int:
        return int.from_bytes(self.mem[addr:addr + 4], "little")

    def u64(self, addr: int) -> int:
        return int.from_bytes(self.mem[addr:addr + 8], "little")

    @property
    def station_address(self) -> int:
        return self.u16(R.STATION_ADDRESS)

    @property
    def alias(self) -> int:
        return self.u16(R.STATION_ALIAS)

    def addressed_fixed(self, adp: int) -> bool:
        """Node addressing: the station address, or the alias when DL control bit 24 enables it."""
        if adp == self.station_address:
            return True
        return bool(self.mem[R.DL_CONTROL + 3] & 0x01) and self.alias != 0 and adp == self.alias

    # ------------------------------------------------------------------------------------------
    # sync managers and FMMUs (parsed from their registers, cached until they are written)
    # ------------------------------------------------------------------------------------------
    def sms(self) -> list[_Sm]:
        if self._sms is None:
            out = []
            size = len(self.mem)
            for n in range(self.sm_count):
                a = R.SM + R.SM_SIZE * n
                start, length, enabled = self.u16(a), self.u16(a + 2), bool(self.mem[a + 6] & 1)
                control = self.mem[a + 4]
                active = enabled and length > 0 and (start >= R.PROCESS_RAM and start + length <= size
                                                     or self.digital_output_sm(start, length, control))
                out.append(_Sm(start, length, control, enabled, active))
            self._sms = out
            self._read_mailboxes = tuple(n for n, sm in enumerate(out)
                                         if sm.active and sm.mailbox and not sm.ecat_writes)
        return self._sms

    def sm(self, n: int) -> _Sm:
        return self.sms()[n]

    @property
    def digital_io(self) -> bool:
        """PDI control 0x0140 = 04h: the ESC's PDI is digital I/O (an EL1xxx/EL2xxx terminal, no processor)."""
        return self.mem[R.PDI_CONTROL] == R.PDI_DIGITAL_IO

    def digital_output_sm(self, start: int, length: int, control: int) -> bool:
        """An SM over the digital output registers 0x0F00-0x0F03, which an ESC with digital I/O serves as its
        output buffer (ET1100 data sheet: "digital output data" 0x0F00:0x0F03, written by a buffered SM of ECAT
        write direction): the only register area an SM may cover, and only on such an ESC."""
        return (self.digital_io and control & 0x3 == SM_MODE_BUFFERED and (control >> 2) & 0x3 == SM_DIR_WRITE
                and R.DIGITAL_OUTPUT <= start and start + length <= R.DIGITAL_OUTPUT + R.DIGITAL_OUTPUT_SIZE)

    def fmmus(self) -> list[_Fmmu]:
        if self._fmmus is None:
            out = []
            for n in range(self.fmmu_count):
                a = R.FMMU + R.FMMU_SIZE * n
                if not self.mem[a + 12] & 1 or not self.u16(a + 4):
                    continue
                t = self.mem[a + 11]
                f = _Fmmu(self.u32(a), self.u16(a + 4), self.mem[a + 6] & 7, self.mem[a + 7] & 7,
                          self.u16(a + 8), self.mem[a + 10] & 7, bool(t & 1), bool(t & 2))
                first, end = f.bit_range()
                if f.physical * 8 + f.physical_bit + max(0, end - first) > len(self.mem) * 8:
                    continue  # its physical bytes run past the memory the ESC has: the FMMU serves nothing
                out.append(f)
            self._fmmus = out
        return self._fmmus

    def _sm_status(self, n: int) -> int:
        sm = self.sm(n)
        if sm.mailbox:
            return (0x08 if self._sm_full[n] else 0) | (0x01 if self._sm_full[n] and not sm.ecat_writes else 0)
        return 0x30 if not self._sm_full[n] else 0x00  # buffered: 11 = no buffer written yet, 00 = buffer 0

    def _sync_sm_registers(self) -> None:
        for n in range(self.sm_count):
            self._sync_sm(n)

    def _sync_sm(self, n: int) -> None:
        """Status (offset 5) and PDI control (offset 7) of SM ``n`` from the SM's state."""
        a = R.SM + R.SM_SIZE * n
        self.mem[a + 5] = self._sm_status(n)
        self.mem[a + 7] = (self.mem[a + 7] & 0xFE) | (1 if self._sm_pdi_off[n] else 0)

    def _sm_reset(self, n: int) -> None:
        self._sm_full[n] = False

    # ------------------------------------------------------------------------------------------
    # the ECAT side (datagram engine)
    # ------------------------------------------------------------------------------------------
    def begin_frame(self, arrive_ns: int, back_ns: int | None) -> None:
        """A frame arrives at port 0 at host time ``arrive_ns`` (ns) and, where it comes back through port 1 from
        the slaves after this one, passes port 1 at ``back_ns`` (None: it turns back here)."""
        self._arrival = (arrive_ns, back_ns)
        self.frame_ns = arrive_ns
        since = self._wd_pd_since
        if since is not None:
            m = self.mem  # watchdog_pd_ns() from the register bytes (every frame asks while the watchdog runs)
            timeout = ((m[_WD_DIV] | m[_WD_DIV + 1] << 8) + 2) * 40 * (m[_WD_PD] | m[_WD_PD + 1] << 8)
            if timeout and arrive_ns - since > timeout:
                self.watchdog_check(arrive_ns)

    def end_frame(self) -> None:
        self.app.frame_done(self)

    def _segments(self, addr: int, n: int) -> tuple[Segment, ...]:
        """Split [addr, addr+n) into pieces outside (None) and inside an enabled sync manager's area (kept per
        (addr, n) until the SM registers are written)."""
        cache = self._segment_cache
        found = cache.get((addr, n))
        if found is None:
            if len(cache) >= _PLAN_LIMIT:
                cache.clear()
            found = cache[addr, n] = segments(self.sms(), addr, n)
        return found

    def ecat_read(self, addr: int, n: int) -> tuple[bytes, bool]:
        """The master reads ``n`` bytes at ``addr``; False when the ESC refuses (no working counter)."""
        sms = self.sms()  # the list the segments come from (only an ECAT write of the SM registers renews it)
        segs = self._segments(addr, n)
        if len(segs) == 1 and segs[0][2] is None:
            return self._read_plain(addr, n), True  # registers or RAM outside every SM: the common case
        out = bytearray()
        ok = True
        for lo, hi, smn in segs:
            if smn is None:
                out += self._read_plain(lo, hi - lo)
                continue
            sm = sms[smn]
            if self._sm_pdi_off[smn]:
                ok = False
                out += bytes(hi - lo)
                continue
            if sm.mailbox and not sm.ecat_writes:
                if not self._sm_full[smn]:
                    ok = False
                    out += bytes(hi - lo)
                    continue
            out += self.mem[lo:hi]
            if hi == sm.end and not sm.ecat_writes:
                if sm.mailbox:
                    self._sm_full[smn] = False
                    self._sync_sm(smn)
                    self.app.mailbox_read(self, smn)
                else:
                    self.app.buffer_read(self, smn)
        return bytes(out), ok

    def _read_plain(self, addr: int, n: int) -> bytes:
        end = addr + n
        mem = self.mem
        if addr < R.PROCESS_RAM:
            dl, sm, time, events, dc, wd, eeprom, al = _read_hits(addr, end)
            if dl or sm or time or events or dc or wd:
                self._refresh(dl, sm, time, events, dc, wd)
        else:
            eeprom = al = False
        if addr >= len(mem):
            return bytes(n)
        data = bytes(mem[addr:end])
        if eeprom:
            self.eeprom_poll()  # a busy EEPROM finishes after the status has been read busy
        if al:
            self._al_event = False
            self._sync_events()
        return data + bytes(n - len(data)) if len(data) < n else data

    def _refresh(self, dl: bool, sm: bool, time: bool, events: bool, dc: bool, wd: bool) -> None:
        """Registers whose value is computed when they are read (which a read covers: :func:`_read_hits`)."""
        if dl:
            self._put16(R.DL_STATUS, self._dl_status())
        if sm:
            self._sync_sm_registers()
        if time:
            self.mem[R.DC_SYSTEM_TIME:R.DC_SYSTEM_TIME + 8] = self.system_time().to_bytes(8, "little")
        if events:
            self._sync_events()
        if dc:
            self._sync_dc_status()
        if wd:
            running = self._wd_pd_since is not None or not self.watchdog_pd_ns()
            self._put16(R.WD_STATUS_PD, 1 if running else 0)

    def ecat_write(self, addr: int, data: bytes) -> bool:
        """The master writes ``data`` at ``addr``; False when the ESC refuses (no working counter)."""
        sms = self.sms()  # as in ecat_read; the loop below renews nothing (registers are handled after it)
        segs = self._segments(addr, len(data))
        if len(segs) == 1 and segs[0][2] is None:  # registers or RAM outside every SM: the common case
            self._write_plain(addr, data)
            if addr < R.PROCESS_RAM:
                self._after_register_write(addr, addr + len(data), data)
            return True
        ok = True
        touched_registers = False
        done: list[tuple[int, bool]] = []
        for lo, hi, smn in segs:
            chunk = data[lo - addr:hi - addr]
            if smn is None:
                self._write_plain(lo, chunk)
                touched_registers = touched_registers or lo < R.PROCESS_RAM
                continue
            sm = sms[smn]
            if self._sm_pdi_off[smn] or not sm.ecat_writes or (sm.mailbox and self._sm_full[smn]):
                ok = False
                continue
            self.mem[lo:hi] = chunk
            if hi == sm.end:
                done.append((smn, sm.mailbox))
        if touched_registers:
            self._after_register_write(addr, addr + len(data), data)
        for smn, mailbox in done:
            sm = self.sm(smn)
            buffer = bytes(self.mem[sm.start:sm.end])
            if mailbox:
                self._sm_full[smn] = True
                self._sync_sm(smn)
                self.app.mailbox_written(self, smn, buffer)
            else:
                self._sm_full[smn] = True
                if sm.control & SM_WATCHDOG_TRIGGER:
                    self._wd_pd_since = self.frame_ns
                self.app.buffer_written(self, smn, buffer)
        return ok

    def _write_plain(self, addr: int, data: bytes) -> None:
        mem = self.mem
        for lo, hi in _writable_runs(addr, min(addr + len(data), len(mem))):
            mem[lo:hi] = data[lo - addr:hi - addr]

    def _after_register_write(self, addr: int, end: int, data: bytes) -> None:
        """What a write of the registers [addr, end) sets off (which of them it covers: :func:`_write_hits`)."""
        sms, fmmus, rx, wd, wd_counter, eeprom, receive, time, activation, al = _write_hits(addr, end)
        if sms:
            old_sms = list(self.sms())
            self._sms = None
            self._plans.clear()
            self._segment_cache.clear()
            for n, old in enumerate(old_sms):
                new = self.sm(n)
                if (old.enabled, old.start, old.length, old.control) != (new.enabled, new.start, new.length,
                                                                          new.control):
                    self._sm_reset(n)
                a = R.SM + R.SM_SIZE * n + 6
                if addr <= a < end:
                    request = bool(self.mem[a] & 0x02)
                    if request != bool(self.mem[a + 1] & 0x02):
                        self.app.mailbox_repeat(self, n)
        if fmmus:
            self._fmmus = None
            self._plans.clear()
        if rx:
            # writing an error counter clears it
            for a in range(max(addr, R.RX_ERROR_COUNTER), min(end, R.RX_ERROR_COUNTER + 0x14)):
                self.mem[a] = 0
        if wd and self._wd_pd_since is not None:
            self._wd_pd_since = self.frame_ns  # a new watchdog time counts from its write
        if wd_counter:
            # writing either watchdog counter clears both
            self.mem[R.WD_COUNTER_PD] = self.mem[R.WD_COUNTER_PDI] = 0
        if eeprom:
            self._eeprom_command()
        if receive:
            self._latch_receive_times()
        if time:
            self._compare_system_time(addr, data)
        if activation:
            # the cyclic unit takes the start time when it is switched on (0x0990 is writable only while it is off)
            self._dc_start = self.u64(R.DC_START_TIME) if self.mem[R.DC_ACTIVATION] & 0x01 else None
            self.app.dc_activation(self, self.mem[R.DC_ACTIVATION])
        if al:
            self.app.al_control(self, self.u16(R.AL_CONTROL))

    # ------------------------------------------------------------------------------------------
    # logical addressing (LRD / LWR / LRW) through the FMMUs, bit granular
    # ------------------------------------------------------------------------------------------
    def logical(self, address: int, data: Buffer, read: bool, write: bool) -> tuple[bool, bool]:
        """Map the datagram bytes at logical ``address``: FMMUs of read type copy physical bits into
        ``data`` (when ``read``), those of write type copy ``data`` bits into the ESC (when ``write``).
        Returns (read happened, write happened) for the working counter.

        The common access (each FMMU's share inside one buffered sync manager or in plain process RAM) runs a
        :class:`_Plan` made once per (address, length) until an SM or FMMU register is written: a few slice
        copies and the sync manager's bookkeeping, no segment search. Every other access (registers, mailbox
        areas, shares across SM boundaries or past the memory) takes :meth:`logical_general`, which the plan
        equals wherever it applies (tests/sim/test_esc_logical_plan.py)."""
        key = (address, len(data))
        plan = self._plans.get(key)
        if plan is None:
            if len(self._plans) >= _PLAN_LIMIT:
                self._plans.clear()
            plan = self._plans[key] = self._plan(address, len(data))
        if plan.general:
            return self.logical_general(address, data, read, write)
        mem = self.mem
        pdi_off = self._sm_pdi_off
        incoming = bytes(data) if write and read and plan.copy else data
        did_read = did_write = False
        for f_read, f_write, p0, p1, d0, d1, whole, mask, pshift, dshift, smn, ecat_writes, first, wd in plan.ops:
            if write and f_write and (smn < 0 or (ecat_writes and not pdi_off[smn])):
                if whole:
                    mem[p0:p1] = incoming[d0:d1]
                else:
                    mem[p0:p1] = _put_bits(incoming[d0:d1], dshift, mem[p0:p1], pshift, mask)
                did_write = True
                if first >= 0:  # the write reached the SM's last byte: the buffer is complete
                    self._sm_full[smn] = True
                    if wd:
                        self._wd_pd_since = self.frame_ns
                    self.app.buffer_written(self, smn, bytes(mem[first:p1]))
            if read and f_read and (smn < 0 or not pdi_off[smn]):
                if whole:
                    data[d0:d1] = mem[p0:p1]
                else:
                    data[d0:d1] = _put_bits(mem[p0:p1], pshift, data[d0:d1], dshift, mask)
                did_read = True
                if first >= 0 and not ecat_writes:
                    self.app.buffer_read(self, smn)
        return did_read, did_write

    def _plan(self, address: int, n: int) -> "_Plan":
        """The plan of a logical access of ``n`` bytes at ``address``; :data:`_GENERAL` where it needs the
        general way: a share that is not inside one buffered SM's area or one run of plain process RAM."""
        fmmus = self.fmmus()
        sms = self.sms()
        ops: list[PlanOp] = []
        for f_read, f_write, p0, p1, d0, d1, whole, mask, pshift, dshift in pieces(fmmus, address, n):
            segs = self._segments(p0, p1 - p0)
            if len(segs) != 1:
                return _GENERAL
            smn = segs[0][2]
            if smn is None:
                if p0 < R.PROCESS_RAM or p1 > len(self.mem):
                    return _GENERAL
                ops.append((f_read, f_write, p0, p1, d0, d1, whole, mask, pshift, dshift, -1, True, -1, False))
                continue
            sm = sms[smn]
            if sm.mailbox:
                return _GENERAL
            ops.append((f_read, f_write, p0, p1, d0, d1, whole, mask, pshift, dshift, smn, sm.ecat_writes,
                        sm.start if p1 == sm.end else -1, bool(sm.control & SM_WATCHDOG_TRIGGER)))
        # a write FMMU takes the datagram's bytes as they came, whatever a read FMMU before it put there
        copy = any(a[0] and b[1] and a[4] < b[5] and b[4] < a[5] for i, a in enumerate(ops) for b in ops[i + 1:])
        return _Plan(tuple(ops), copy, False)

    def logical_general(self, address: int, data: Buffer, read: bool, write: bool) -> tuple[bool, bool]:
        """:meth:`logical` through the ECAT read and write of each FMMU's share (any access)."""
        fmmus = self.fmmus()
        n = len(data)
        incoming = bytes(data)  # what a write FMMU takes, whatever a read FMMU put into ``data`` before it
        did_read = did_write = False
        for f_read, f_write, p0, p1, d0, d1, whole, mask, pshift, dshift in \
                self._piece_memo.get(fmmus, (address, n), lambda: pieces(fmmus, address, n)):
            if write and f_write:
                if whole:
                    chunk = incoming[d0:d1]
                else:
                    chunk = _put_bits(incoming[d0:d1], dshift, self.mem[p0:p1], pshift, mask)
                if self.ecat_write(p0, chunk):
                    did_write = True
            if read and f_read:
                raw, ok = self.ecat_read(p0, p1 - p0)
                if ok:
                    if whole:
                        data[d0:d1] = raw
                    else:
                        data[d0:d1] = _put_bits(raw, pshift, data[d0:d1], dshift, mask)
                    did_read = True
        return did_read, did_write

    # ------------------------------------------------------------------------------------------
    # the process data watchdog 0x0400-0x0443
    # ------------------------------------------------------------------------------------------
    def watchdog_pd_ns(self) -> int:
        """The process data watchdog time in ns, 0 when disabled: (divider 0x0400 + 2) x 40 ns x 0x0420."""
        return (self.u16(R.WD_DIVIDER) + 2) * 40 * self.u16(R.WD_TIME_PD)

    def watchdog_check(self, now_ns: int) -> None:
        """Expire the process data watchdog when its time has passed since the last trigger (a complete write
        of a buffered SM whose control has bit 6 set): status 0x0440 reads 0, counter 0x0442 counts (saturates),
        and the application is told. The check runs when a frame arrives, so the master sees the expiry in the
        first frame after the watchdog time, as it would from a real ESC; a stopped watchdog waits for the
        next trigger."""
        since = self._wd_pd_since
        timeout = self.watchdog_pd_ns()
        if since is None or not timeout or now_ns - since <= timeout:
            return
        self._wd_pd_since = None
        self.mem[R.WD_COUNTER_PD] = min(0xFF, self.mem[R.WD_COUNTER_PD] + 1)
        self.app.pd_watchdog_expired(self)

    # ------------------------------------------------------------------------------------------
    # AL, DL, events
    # ------------------------------------------------------------------------------------------
    def set_al_status(self, state: int, *, error: bool, code: int) -> None:
        """PDI: the application reports its state, the error indication and the AL status code."""
        value = (state & 0x0F) | (R.AL_ERROR if error else 0)
        if value != self.u16(R.AL_STATUS):
            self._al_event = True
        self._put16(R.AL_STATUS, value)
        self._put16(R.AL_STATUS_CODE, code)

    @property
    def al_state(self) -> int:
        return self.mem[R.AL_STATUS] & 0x0F

    def _dl_status(self) -> int:
        link = self.link
        return _dl_status(self.mem[R.DL_CONTROL + 1], link[0], link[1], link[2], link[3])

    def port_open(self, port: int) -> bool:
        """Whether frames leave through ``port`` (the loop is open and a link is there): DL status bit 9 + 2 x
        ``port`` (:func:`_dl_status`), which with a link is set unless the loop setting is 3, always closed."""
        return self.link[port] and (self.mem[_LOOP] >> (2 * port)) & 0x3 != 3

    def _sync_events(self) -> None:
        req = 0x08 if self._al_event else 0
        full = self._sm_full
        self.sms()  # brings _read_mailboxes up to date
        for n in self._read_mailboxes:
            if full[n]:
                req |= 0x10 << n
        self.mem[R.ECAT_EVENT_REQUEST] = req & 0xFF
        self.mem[R.ECAT_EVENT_REQUEST + 1] = (req >> 8) & 0xFF

    def irq(self) -> int:
        """The bits this slave ORs into a datagram's IRQ field: event requests under the event mask."""
        if not self.mem[R.ECAT_EVENT_MASK] and not self.mem[R.ECAT_EVENT_MASK + 1]:
            return 0
        self._sync_events()
        return self.u16(R.ECAT_EVENT_REQUEST) & self.u16(R.ECAT_EVENT_MASK)

    def count_rx_error(self, port: int = 0) -> None:
        """A frame with a bad FCS arrived on ``port``: the invalid frame counter counts it (saturates)."""
        a = R.RX_ERROR_COUNTER + 2 * port
        self.mem[a] = min(0xFF, self.mem[a] + 1)

    def count_lost_link(self, port: int) -> None:
        a = R.LOST_LINK + port
        self.mem[a] = min(0xFF, self.mem[a] + 1)

    # ------------------------------------------------------------------------------------------
    # the PDI side (the slave application)
    # ------------------------------------------------------------------------------------------
    def sm_full(self, sm: int) -> bool:
        """Mailbox SM ``sm`` holds a frame not yet read (by the master for SM1, by the application for SM0)."""
        return self._sm_full[sm]

    def sm_deactivated(self, sm: int) -> bool:
        return self._sm_pdi_off[sm]

    def pdi_deactivate(self, sm: int, off: bool) -> None:
        """PDI control bit 0 of ``sm``: a deactivated SM refuses the master's accesses to its area."""
        if self._sm_pdi_off[sm] != off:
            self._sm_pdi_off[sm] = off
            self._sm_reset(sm)
            self._sync_sm_registers()

    def pdi_mailbox_put(self, sm: int, data: bytes, *, force: bool = False) -> bool:
        """Write one mailbox frame into read mailbox ``sm``; False when it is still full (unless ``force``:
        a repeat overwrites it)."""
        s = self.sm(sm)
        if not s.active or self._sm_pdi_off[sm] or (self._sm_full[sm] and not force):
            return False
        self.mem[s.start:s.start + min(len(data), s.length)] = data[:s.length]
        self._sm_full[sm] = True
        self._sync_sm(sm)
        return True

    def pdi_mailbox_take(self, sm: int) -> None:
        """The application has read write mailbox ``sm``: it is empty for the master again."""
        self._sm_full[sm] = False
        self._sync_sm(sm)

    def pdi_repeat_ack(self, sm: int) -> None:
        """Set the repeat acknowledge (PDI control bit 1) equal to the master's repeat request."""
        a = R.SM + R.SM_SIZE * sm
        self.mem[a + 7] = (self.mem[a + 7] & ~0x02 & 0xFF) | (self.mem[a + 6] & 0x02)

    def pdi_write(self, addr: int, data: bytes) -> None:
        """The application writes process RAM (the input buffer of a buffered SM); bytes past the memory end
        are not there to write (the memory never grows)."""
        data = data[:max(0, len(self.mem) - addr)]
        self.mem[addr:addr + len(data)] = data

    def pdi_read(self, addr: int, n: int) -> bytes:
        return bytes(self.mem[addr:addr + n])

    # ------------------------------------------------------------------------------------------
    # SII EEPROM interface 0x0500-0x050F
    # ------------------------------------------------------------------------------------------
    def _eeprom_command(self) -> None:
        control = self.u16(R.EEPROM_CONTROL)
        cmd = control & R.EE_CMD_MASK
        address = self.u32(R.EEPROM_ADDRESS)
        data = self.u16(R.EEPROM_DATA)
        result = self.eeprom.command(cmd, bool(control & R.EE_WRITE_ENABLE), address, data)
        if result.data is not None:
            self.mem[R.EEPROM_DATA:R.EEPROM_DATA + len(result.data)] = result.data
        if cmd == R.EE_CMD_RELOAD and not result.error:
            self._load_eeprom_config()
        self._sync_eeprom_status(cmd if result.busy else 0)

    def _sync_eeprom_status(self, running: int = 0) -> None:
        status = self.eeprom.status_bits() | running
        self._put16(R.EEPROM_CONTROL, status)

    def eeprom_poll(self) -> None:
        """Reads of the status register advance a busy EEPROM (called by the engine before a read)."""
        if self.eeprom.busy:
            self.eeprom.tick()
            self._sync_eeprom_status(self.u16(R.EEPROM_CONTROL) & R.EE_CMD_MASK if self.eeprom.busy else 0)

    def _load_eeprom_config(self) -> None:
        """Words 0..7 (the ESC configuration area): PDI control and the station alias."""
        words = self.eeprom.words(0, 8)
        self._put16(R.PDI_CONTROL, words[0] or self._default_pdi)
        self._sms = None  # whether an SM over the digital outputs is active depends on the PDI
        self._plans.clear()
        self._segment_cache.clear()
        self._put16(R.STATION_ALIAS, words[4])
        self._sync_eeprom_status()

    # ------------------------------------------------------------------------------------------
    # distributed clocks 0x0900-0x09FF
    # ------------------------------------------------------------------------------------------
    def local_time(self, host_ns: int | None = None) -> int:
        return self.clock.local_ns(self.frame_ns if host_ns is None else host_ns)

    def system_time(self) -> int:
        return (self.local_time() + self.u64(R.DC_SYSTEM_OFFSET)) & 0xFFFFFFFFFFFFFFFF

    def _latch_receive_times(self) -> None:
        for port, t in enumerate(self._arrival):
            if t is not None:
                local = self.local_time(t)
                self.mem[R.DC_RECEIVE_TIME + 4 * port:R.DC_RECEIVE_TIME + 4 * port + 4] = \
                    (local & 0xFFFFFFFF).to_bytes(4, "little")
        self.mem[R.DC_RECEIVE_TIME_PU:R.DC_RECEIVE_TIME_PU + 8] = self.local_time().to_bytes(8, "little")

    def _compare_system_time(self, addr: int, data: bytes) -> None:
        """A write of the system time is compared with the local copy (drift control input); the register
        keeps the local system time."""
        mem = self.mem
        # the frame's system time (system_time()): the same for the bytes written and the comparison
        local = (self.clock.local_ns(self.frame_ns) + int.from_bytes(mem[_DC_OFFSET:_DC_OFFSET + 8], "little")) \
            & 0xFFFFFFFFFFFFFFFF
        if addr == R.DC_SYSTEM_TIME and len(data) >= 8:
            received = int.from_bytes(data[:8], "little")  # all of it (as SOEM's ARMW/FRMW write it)
        else:
            written = bytearray(local.to_bytes(8, "little"))
            for a in range(max(addr, R.DC_SYSTEM_TIME), min(addr + len(data), R.DC_SYSTEM_TIME + 8)):
                written[a - R.DC_SYSTEM_TIME] = data[a - addr]
            received = int.from_bytes(written, "little")
        diff = (received - local + int.from_bytes(mem[_DC_DELAY:_DC_DELAY + 4], "little")) & 0xFFFFFFFF
        # 0x092C: bits 0..30 the difference's magnitude, bit 31 set when the local copy is ahead
        signed = diff - (1 << 32) if diff & 0x80000000 else diff
        mem[R.DC_SYSTEM_DIFFERENCE:R.DC_SYSTEM_DIFFERENCE + 4] = (
            (min(abs(signed), 0x7FFFFFFF)) | (0x80000000 if signed < 0 else 0)).to_bytes(4, "little")
        mem[R.DC_SYSTEM_TIME:R.DC_SYSTEM_TIME + 8] = local.to_bytes(8, "little")

    def _sync_dc_status(self) -> None:
        """0x0984 activation status (bit 0/1: the first SYNC0/SYNC1 pulse is still pending), 0x098E/0x098F SYNC0/1
        status (a pulse has come), and while the cyclic unit runs 0x0990 = the next SYNC0 pulse and 0x0998 = the
        next SYNC1 pulse (:func:`~ecattool.sim.esc.dc.sync1_train`)."""
        act, cycle, start = self.dc_sync0()
        sync0 = bool(act & 0x01) and bool(act & 0x02)
        sync1 = sync0 and bool(act & 0x04)
        now = self.system_time()
        first1, period1 = sync1_train(start, cycle, self.u32(R.DC_SYNC1_CYCLE))
        self.mem[R.DC_ACTIVATION_STATUS] = (0x01 if sync0 and now < start else 0) | (0x02 if sync1 and now < first1
                                                                                      else 0)
        self.mem[R.DC_SYNC0_STATUS] = 0x01 if sync0 and now >= start else 0
        self.mem[R.DC_SYNC1_STATUS] = 0x01 if sync1 and now >= first1 else 0
        if sync0:
            self.mem[R.DC_START_TIME:R.DC_START_TIME + 8] = next_pulse(now, start, cycle).to_bytes(8, "little")
        if sync1:
            self.mem[R.DC_NEXT_SYNC1:R.DC_NEXT_SYNC1 + 8] = next_pulse(now, first1, period1).to_bytes(8, "little")

    def dc_sync0(self) -> tuple[int, int, int]:
        """(activation 0x0981, SYNC0 cycle ns, start time) as the master wrote them: the start time is the one the
        cyclic unit took when it was activated (while it runs, 0x0990 reads the next SYNC0 pulse)."""
        act = self.mem[R.DC_ACTIVATION]
        start = self._dc_start if act & 0x01 and self._dc_start is not None else self.u64(R.DC_START_TIME)
        return act, self.u32(R.DC_SYNC0_CYCLE), start

