"""A virtual EtherCAT slave: one drive of the simulator behind an ESC model and a mailbox.

:class:`VirtualSlave` is the slave application behind the ESC's PDI. It turns what a master writes into calls
of the drive's public API, so the in-process :class:`~ecattool.sim.Drive` and the wire serve the same drive:

- AL control -> ``drive.request_state``; a refusal sets the error indication and the drive's AL status code,
  which stays until the master acknowledges it (AL control bit 4);
- the sync managers the master configured are checked against the state it asks for: the mailbox SMs at
  INIT -> PRE-OP (0x0016; 0x0015 for BOOT), the process data SMs and FMMUs at PRE-OP -> SAFE-OP against the
  drive's PDO assignment (0x001D outputs, 0x001E inputs); SMs not valid in a state are deactivated;
- SM0 -> mailbox server -> SM1 (with the repeat request), SM2 outputs -> ``drive.exchange`` -> SM3 inputs,
  after the frame has passed (:meth:`after_frame`): the master reads the inputs of this cycle in its next frame;
- DC activation (0x0981, SYNC0 cycle 0x09A0, start time 0x0990) -> ``drive.configure_dc``;
- the process data watchdog expiring in OP -> ``drive.lose_communication`` (the family's reaction, 6007h):
  SAFE-OP with the error indication and AL status code 0x001B until the master acknowledges it.

The SII image is the one ``ecattool sii build`` makes: from the drive's ESI, or from the built-in profile's
device model (the three manual families have no public ESI).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ecattool.abort import AlStatus
from ecattool.errors import StateChangeError, TargetError
from ecattool.esi.model import Device
from ecattool.od.model import EcState
from ecattool.sim.drive import Drive
from ecattool.sim.esc import Clock, Esc, EscApplication
from ecattool.sim.esc import registers as R
from ecattool.sim.esc.core import SM_DIR_READ, SM_DIR_WRITE, SM_MODE_BUFFERED, SM_MODE_MAILBOX
from ecattool.sim.mailbox import MailboxServer


_BY_CODE = {s.code: s for s in EcState}
#: looked up once (every frame asks, for every slave)
_CODES = {s: s.code for s in EcState}
_OP, _SAFEOP = EcState.OP, EcState.SAFEOP
MBX_OUT, MBX_IN, PD_OUT, PD_IN = 0, 1, 2, 3


class ConfigRefused(Exception):
    def __init__(self, code: int, why: str) -> None:
        super().__init__(why)
        self.code = code


#: the most cycles a drive on its own clock runs after one frame to make up for the time since its last cycle
#: (100 ms at 1 kHz, the default process data watchdog): a longer silence is not made up, which bounds what one
#: frame can cost the server
MAX_CATCH_UP = 100


@dataclass(frozen=True, slots=True)
class Refusal:
    """The last state change the slave refused: AL status code and why (for logs and tests)."""

    requested: str
    code: int
    reason: str


class VirtualSlave(EscApplication):
    """``drive`` behind an ESC serving ``sii`` (bytes of an SII image)."""

    def __init__(self, drive: Drive, sii: bytes, *, clock: Clock | None = None) -> None:
        self.drive = drive
        #: the drive runs on its own clock (``sim serve`` sets it): as many cycles as its cycle time (60C2h), or
        #: the SYNC0 pulses, fit into the host time since its last cycle; else one cycle per event (in process: the
        #: caller's frames are the drive's time, which keeps traces exact). See :meth:`after_frame`.
        self.own_clock = False
        #: own clock without SYNC0: host time (ns) of the drive's last cycle boundary (None: not run yet)
        self._cycle_at: int | None = None
        #: own clock: the outputs of the drive's last cycle (None: none yet)
        self._ran_on: bytes | None = None
        self.esc = Esc(sii, app=self, clock=clock)
        mbx = self._mailbox_defaults()
        self.mailbox = MailboxServer(drive, mbx[0], mbx[1])
        self.refusals: list[Refusal] = []
        #: host time (ns) before which the mailbox answer waits (a slow mailbox, ``Faults.slow_mailbox``)
        self._reply_due: int | None = None
        #: the outputs of the last complete SM2 write (b"" for a drive without outputs, whose SM3 read counts)
        self._outputs: bytes | None = None
        #: a process data event fired since the drive last ran (SM2 written, SM3 read without outputs)
        self._pd_event = False
        #: the last SYNC0 pulse (its number since the start time) the drive ran for, while DC is on
        self._sync0_seen = -1
        #: SAFE-OP or OP without outputs: each complete read of SM3 is the drive's event (kept by _sync_state,
        #: which every state change passes, instead of asking the drive on every read of SM3)
        self._no_outputs = False
        self._sync_state()

    # ------------------------------------------------------------------------------------------
    @classmethod
    def from_drive(cls, drive: Drive, *, esi: str | Path | None = None, selector: str | None = None,
                   clock: Clock | None = None) -> "VirtualSlave":
        """The slave of ``drive``; its SII is built from ``esi`` (the file the drive came from) when given,
        else from the drive's device model (a built-in profile)."""
        return cls(drive, sii_image(drive, esi, selector), clock=clock)

    def _mailbox_defaults(self) -> tuple[int, int]:
        words = self.esc.eeprom.words(0x18, 4)  # standard receive / send mailbox offset and size
        return (words[1] or 128, words[3] or 128)

    # ------------------------------------------------------------------------------------------
    # ESM
    # ------------------------------------------------------------------------------------------
    def _sync_state(self, error: bool = False, code: int = 0) -> None:
        state = self.drive.state()
        self.esc.set_al_status(state.code, error=error, code=code)
        mailbox_on = state in (EcState.PREOP, EcState.SAFEOP, EcState.OP, EcState.BOOT)
        pd_on = state in (EcState.SAFEOP, EcState.OP)
        self._no_outputs = pd_on and self.drive.process_image_sizes()[0] == 0
        if not pd_on:
            self._outputs = None  # below SAFE-OP the process image may change: a SYNC0 cycle waits for new outputs
            self._ran_on = None  # and the drive's own cycles start again with the first event in SAFE-OP
            self._cycle_at = None
        for n in range(self.esc.sm_count):
            sm = self.esc.sm(n)
            if n in (MBX_OUT, MBX_IN) or (sm.mailbox and n < 2):
                self.esc.pdi_deactivate(n, not mailbox_on)
            else:
                self.esc.pdi_deactivate(n, not pd_on)

    def al_control(self, esc: Esc, control: int) -> None:
        status = esc.u16(R.AL_STATUS)
        ack = bool(control & R.AL_ERROR)
        if status & R.AL_ERROR and not ack:
            return  # an error indication ignores requests until the master acknowledges it
        requested = _BY_CODE.get(control & 0x0F)
        current = self.drive.state()
        if requested is None:
            self._refuse(f"0x{control & 0x0F:X}", AlStatus.UNKNOWN_STATE, "unknown requested state")
            return
        if requested is current:
            self._sync_state()  # acknowledged (or nothing to do)
            return
        try:
            self._check_config(current, requested)
            self.drive.request_state(requested)
            if current is EcState.PREOP and requested is EcState.SAFEOP:
                try:
                    self._check_process_data()
                except ConfigRefused:
                    self.drive.request_state(EcState.PREOP)
                    raise
        except ConfigRefused as exc:
            self._refuse(requested.value, exc.code, str(exc))
            return
        except StateChangeError as exc:
            self._refuse(requested.value, exc.al_status, str(exc))
            return
        if requested in (EcState.PREOP, EcState.BOOT) and current is EcState.INIT:
            self.mailbox.resize(esc.sm(MBX_OUT).length, esc.sm(MBX_IN).length)
        elif requested is EcState.INIT:  # from PRE-OP, SAFE-OP, OP or BOOT
            self.mailbox.reset()  # the mailbox stops: transfers a master left unfinished are dropped
        self._sync_state()
        if requested in (EcState.SAFEOP, EcState.OP):
            self._exchange(None)

    def _refuse(self, requested: str, code: int, why: str) -> None:
        self.refusals.append(Refusal(requested, code, why))
        self._sync_state(error=True, code=code)

    def _check_config(self, current: EcState, requested: EcState) -> None:
        if current is EcState.INIT and requested in (EcState.PREOP, EcState.BOOT):
            code = AlStatus.INVALID_MAILBOX_BOOT if requested is EcState.BOOT else AlStatus.INVALID_MAILBOX
            out, inp = self.esc.sm(MBX_OUT), self.esc.sm(MBX_IN)
            for n, sm, direction in ((MBX_OUT, out, SM_DIR_WRITE), (MBX_IN, inp, SM_DIR_READ)):
                if not sm.enabled or sm.control & 0x3 != SM_MODE_MAILBOX or (sm.control >> 2) & 3 != direction:
                    raise ConfigRefused(code, f"SM{n} is not an enabled mailbox of the right direction")
                if sm.length < 8 or sm.start < R.PROCESS_RAM or sm.end > len(self.esc.mem):
                    raise ConfigRefused(code, f"SM{n} at 0x{sm.start:04X} length {sm.length} is not usable")
            if out.start < inp.end and inp.start < out.end:
                raise ConfigRefused(code, "the mailbox sync managers overlap")

    def _check_process_data(self) -> None:
        """PRE-OP -> SAFE-OP: SM2/SM3 and their FMMUs against the process image the drive's PDO assignment
        gives (the drive has accepted the assignment itself)."""
        out_size, in_size = self.drive.process_image_sizes()
        fmmus = self.esc.fmmus()
        for n, size, direction, code, what in ((PD_OUT, out_size, SM_DIR_WRITE, AlStatus.INVALID_OUTPUT_CONFIG, "output"),
                                               (PD_IN, in_size, SM_DIR_READ, AlStatus.INVALID_INPUT_CONFIG, "input")):
            sm = self.esc.sm(n)
            if size == 0:
                if sm.enabled and sm.length:
                    raise ConfigRefused(code, f"SM{n} is enabled with {sm.length} bytes, the drive has no {what}s")
                continue
            if not sm.enabled:
                raise ConfigRefused(code, f"SM{n} is not enabled ({size} {what} bytes assigned)")
            if sm.control & 0x3 != SM_MODE_BUFFERED or (sm.control >> 2) & 3 != direction:
                raise ConfigRefused(code, f"SM{n} control 0x{sm.control:02X} is not a buffered {what} SM")
            if sm.length != size:
                raise ConfigRefused(code, f"SM{n} length {sm.length} differs from the {size} {what} bytes "
                                          "of the PDO assignment")
            if sm.start < R.PROCESS_RAM or sm.end > len(self.esc.mem):
                raise ConfigRefused(code, f"SM{n} at 0x{sm.start:04X} is outside the process RAM")
            mapped = [f for f in fmmus if (f.write if direction == SM_DIR_WRITE else f.read)
                      and f.physical < sm.end and f.physical + f.length > sm.start]
            if not mapped:
                raise ConfigRefused(code, f"no {'write' if direction == SM_DIR_WRITE else 'read'} FMMU maps SM{n}")

    # ------------------------------------------------------------------------------------------
    # mailbox
    # ------------------------------------------------------------------------------------------
    def mailbox_written(self, esc: Esc, sm: int, data: bytes) -> None:
        esc.pdi_mailbox_take(sm)
        delay = self.drive.faults.mailbox_delay_ms(self.drive.state())
        if delay:
            self._reply_due = esc.frame_ns + delay * 1_000_000
        self.mailbox.handle(data)
        self._push_mailbox()

    def mailbox_read(self, esc: Esc, sm: int) -> None:
        self._push_mailbox()

    def mailbox_repeat(self, esc: Esc, sm: int) -> None:
        last = self.mailbox.repeat()
        if last is not None:
            esc.pdi_mailbox_put(sm, last, force=True)
        esc.pdi_repeat_ack(sm)

    def _push_mailbox(self) -> None:
        esc = self.esc
        if esc.sm_full(MBX_IN) or esc.sm_deactivated(MBX_IN) or not esc.sm(MBX_IN).active:
            return
        if self._reply_due is not None:
            if esc.frame_ns < self._reply_due:
                return
            self._reply_due = None
        reply = self.mailbox.pending()
        if reply is not None:
            esc.pdi_mailbox_put(MBX_IN, reply)

    # ------------------------------------------------------------------------------------------
    # process data
    # ------------------------------------------------------------------------------------------
    def buffer_written(self, esc: Esc, sm: int, data: bytes) -> None:
        if sm == PD_OUT:
            self._outputs = data
            self._pd_event = True

    def buffer_read(self, esc: Esc, sm: int) -> None:
        if sm == PD_IN and self._no_outputs:
            self._outputs = b""
            self._pd_event = True

    def after_frame(self, esc: Esc) -> None:
        """The drive's cycle, after the frame: when SM2 was written (SM3 read, for a drive without outputs) or,
        with SYNC0 on, when a SYNC0 pulse has come since its last cycle (then on the last outputs it got).

        Paced by the frames (the default, in process): one cycle per frame however much time passed. On its own
        clock (``own_clock``, what ``sim serve`` gives each drive), as a drive's processor runs on its timer or on
        SYNC0 whatever the master does: the cycles that ended since the drive's last cycle run (at most
        :data:`MAX_CATCH_UP`; a longer silence is not made up), those before the frame came on the outputs the
        drive had then and the last on the frame's, and an event that comes before the drive's next cycle waits
        for it. A master that is late or sends frames back to back then neither slows the drive's motion down nor
        speeds it up."""
        fired = self._pd_event
        self._pd_event = False
        pulses = -1  # with a SYNC0 train: how many pulses came since the drive's last cycle (-1: none runs)
        if self._outputs is not None and esc.mem[R.DC_ACTIVATION] & 0x03 == 0x03:
            pulse = self._sync0_pulse(esc)
            if pulse is not None:
                seen = self._sync0_seen
                # before the first pulse it sees, the drive's first cycle is the first pulse after an event
                pulses = pulse - seen if seen >= 0 else int(fired and pulse >= 0)
                if pulse > seen:
                    fired = fired or seen >= 0
                    self._sync0_seen = pulse
        if not fired:
            return
        if not self.own_clock:
            self._exchange(self._outputs)
            return
        cycles = pulses if pulses >= 0 else self._timer_cycles(esc.clock.host_ns())
        if cycles <= 0:
            self._pd_event = True  # before the drive's next cycle: the event waits for it
            return
        # the cycles that ended before this frame came ran on the outputs the drive had then; this frame's
        # outputs are for its last cycle only (a set-point counts from when it arrived, not from the silence)
        before = self._ran_on if self._ran_on is not None else self._outputs
        for _ in range(min(cycles, MAX_CATCH_UP) - 1):
            self._exchange(before)
        self._exchange(self._outputs)
        self._ran_on = self._outputs

    def _timer_cycles(self, now: int) -> int:
        """Own clock without SYNC0: how many of the drive's cycles (60C2h) ended since its last one; the first
        event runs one cycle at once."""
        at = self._cycle_at
        if at is None:
            self._cycle_at = now
            return 1
        period = self.drive.cycle_ns()
        cycles = (now - at) // period
        # a silence longer than MAX_CATCH_UP cycles is not made up: the cycles restart from now
        self._cycle_at = now if cycles > MAX_CATCH_UP else at + cycles * period
        return cycles

    def _sync0_pulse(self, esc: Esc) -> int | None:
        """The number of the last SYNC0 pulse before now (-1 before the first; None without a SYNC0 train)."""
        act, cycle, start = esc.dc_sync0()
        if not act & 0x01 or not act & 0x02 or not cycle:
            return None
        now = (esc.local_time(esc.clock.host_ns()) + esc.u64(R.DC_SYSTEM_OFFSET)) & 0xFFFFFFFFFFFFFFFF
        return (now - start) // cycle if now >= start else -1

    def _exchange(self, outputs: bytes | None) -> None:
        """One process data cycle: outputs to the drive (None: the first inputs at SAFE-OP), inputs to SM3."""
        drive = self.drive
        state = drive.state()
        if state is not _OP and state is not _SAFEOP:
            return
        if outputs is None or state is not _OP:
            outputs = bytes(drive.process_image_sizes()[0])
        try:
            inputs = drive.exchange(outputs)
        except TargetError:
            self._sync_state()  # e.g. power lost during an EEPROM write: the drive is back in INIT
            return
        sm = self.esc.sm(PD_IN)
        if inputs and sm.active:  # the input image of the drive's layout: empty for a drive without inputs
            self.esc.pdi_write(sm.start, inputs[:sm.length])

    # ------------------------------------------------------------------------------------------
    # distributed clocks, frames
    # ------------------------------------------------------------------------------------------
    def dc_activation(self, esc: Esc, activation: int) -> None:
        self._sync0_seen = -1
        self._cycle_at = None
        act, cycle, start = esc.dc_sync0()
        if act & 0x01 and act & 0x06:
            shift = start % cycle if cycle else 0
            self.drive.configure_dc(act << 8, cycle, shift)
        else:
            self.drive.configure_dc(0, 0, 0)

    def pd_watchdog_expired(self, esc: Esc) -> None:
        if self.drive.state() is EcState.OP:
            self.drive.lose_communication()
            self._sync_state(error=True, code=AlStatus.SM_WATCHDOG)

    def frame_done(self, esc: Esc) -> None:
        if _CODES[self.drive.state()] != esc.al_state:
            self._sync_state()  # the drive changed state by itself (power loss, communication lost)
        self._push_mailbox()


def drive_for_device(device: Device) -> Drive:
    """The simulated drive of ``device`` as it runs (:meth:`Drive.from_device`: a built-in profile device as it
    is, an ESI device with its default modules plugged in and the communication objects its ESI leaves out)."""
    return Drive.from_device(device)


def sii_image(drive: Drive, esi: str | Path | None = None, selector: str | None = None) -> bytes:
    """The SII ``ecattool sii build`` makes for ``drive``: from its ESI file when given, else from the
    drive's device model (built-in profiles)."""
    from ecattool.sii.builder import build

    if esi is not None:
        from ecattool import esi as esi_pkg

        return build(esi_pkg.load_device(esi, selector)).to_bytes()
    return build(drive.device).to_bytes()
