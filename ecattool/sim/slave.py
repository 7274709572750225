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

import struct
from dataclasses import dataclass
from pathlib import Path

from ecattool import esi as esi_pkg
from ecattool.abort import AlStatus
from ecattool.errors import EcatToolError, InputError, StateChangeError, TargetError
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

#: the longest 60C2h a served drive paces its own cycles by: a longer interpolation period (Ingenia's ESI gives 1 s
#: as its default) is no processor's cycle, and a drive paced by it would apply a controlword once a second; such a
#: drive runs one cycle per process data event, as in process
MAX_OWN_CYCLE_NS = 100_000_000


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
        sms = sii_sync_managers(sii)
        self.esc = Esc(sii, app=self, clock=clock, ram_bytes=ram_for(sms))
        #: what each sync manager is for, as the SII says (a device's SMs come from its SII, any number of them)
        self.roles = sm_roles(sms, mailbox=self.esc.eeprom.words(0x19, 1)[0] not in (0, 0xFFFF))
        #: per SM: the SII gives it one buffer (mailbox mode) though it carries process data
        self._one_buffer = [False] * self.esc.sm_count
        for n, (_, _, control, _, kind) in enumerate(sms or ()):
            if n < self.esc.sm_count and kind in (3, 4) and control & 0x3 == SM_MODE_MAILBOX:
                self._one_buffer[n] = True
        #: the ESC follows the AL control itself (SII word 0 bit 8, device emulation): no application checks a
        #: state change; the drive model behind it only supplies the process data
        self.emulation = bool(self.esc.mem[R.ESC_CONFIG] & R.DEVICE_EMULATION)
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

    def unservable(self) -> str | None:
        """Why this slave cannot be served as its SII describes it (one sentence), or None. What the ESC model
        cannot be: more sync managers or FMMUs than it has, an SM outside its process memory (other than the
        output SM of a digital-I/O ESC over 0x0F00), a mailbox protocol without mailbox sync managers."""
        esc = self.esc
        sms = sii_sync_managers(bytes(esc.eeprom.data))
        if sms is not None:
            real = [(n, sm) for n, sm in enumerate(sms) if not sm[3] & 0x04]
            if real and real[-1][0] >= esc.sm_count:
                return f"its SII lists {len(sms)} sync managers, the simulated ESC has {esc.sm_count}"
            for n, (start, length, control, _, kind) in real:
                size = max(length, 1)
                if start + size > len(esc.mem) or (start < R.PROCESS_RAM
                                                   and not esc.digital_output_sm(start, size, control)):
                    where = "the digital outputs of an ESC whose PDI is not digital I/O" \
                        if start < R.PROCESS_RAM and esc.mem[R.PDI_CONTROL] != R.PDI_DIGITAL_IO and \
                        R.DIGITAL_OUTPUT <= start < R.DIGITAL_OUTPUT + R.DIGITAL_OUTPUT_SIZE else \
                        "no process memory of the simulated ESC"
                    what = SM_KINDS.get(kind, f"type {kind}")
                    return f"SM{n} ({what}) at 0x{start:04X}, {length} bytes, is in {where}"
        protocols = esc.eeprom.words(0x1C, 1)[0]
        if protocols and not self.roles.has_mailbox:
            return f"its SII names mailbox protocols (0x{protocols:04X}) but no mailbox sync managers"
        return None

    def state(self) -> EcState:
        """The state the AL status shows: the drive's, or with device emulation the one the master requested."""
        if self.emulation:
            return _BY_CODE.get(self.esc.al_state, EcState.INIT)
        return self.drive.state()

    # ------------------------------------------------------------------------------------------
    # ESM
    # ------------------------------------------------------------------------------------------
    def _sync_state(self, error: bool = False, code: int = 0) -> None:
        state = self.state()
        if not self.emulation:
            self.esc.set_al_status(state.code, error=error, code=code)
        mailbox_on = state in (EcState.PREOP, EcState.SAFEOP, EcState.OP, EcState.BOOT)
        pd_on = state in (EcState.SAFEOP, EcState.OP) and self.drive.state() in (EcState.SAFEOP, EcState.OP)
        self._no_outputs = pd_on and self.drive.process_image_sizes()[0] == 0
        if not pd_on:
            self._outputs = None  # below SAFE-OP the process image may change: a SYNC0 cycle waits for new outputs
            self._ran_on = None  # and the drive's own cycles start again with the first event in SAFE-OP
            self._cycle_at = None
        if self.emulation:
            return  # no application behind the PDI: nothing deactivates a sync manager
        mailboxes = self.roles.mailboxes
        for n in range(self.esc.sm_count):
            if n in mailboxes:
                self.esc.pdi_deactivate(n, not mailbox_on)
            else:
                self.esc.pdi_deactivate(n, not pd_on)

    def al_control(self, esc: Esc, control: int) -> None:
        if self.emulation:
            self._emulate(esc, control)
            return
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
        if requested in (EcState.PREOP, EcState.BOOT) and current is EcState.INIT and self.roles.has_mailbox:
            assert self.roles.mbx_out is not None and self.roles.mbx_in is not None
            self.mailbox.resize(esc.sm(self.roles.mbx_out).length, esc.sm(self.roles.mbx_in).length)
        elif requested is EcState.INIT:  # from PRE-OP, SAFE-OP, OP or BOOT
            self.mailbox.reset()  # the mailbox stops: transfers a master left unfinished are dropped
        self._sync_state()
        if requested in (EcState.SAFEOP, EcState.OP):
            self._exchange(None)

    def _emulate(self, esc: Esc, control: int) -> None:
        """Device emulation: the ESC copies the requested state into the AL status, checking nothing (ESC
        configuration 0x0141 bit 0); the drive model follows as far as it can, for the process data."""
        esc.set_al_status(control & 0x0F, error=False, code=0)
        requested = _BY_CODE.get(control & 0x0F)
        if requested is not None and requested is not self.drive.state():
            order = [EcState.INIT, EcState.PREOP, EcState.SAFEOP, EcState.OP]
            try:
                if requested in order and self.drive.state() in order:
                    current = order.index(self.drive.state())
                    target = order.index(requested)
                    steps = order[current + 1:target + 1] if target > current else [requested]
                    for step in steps:
                        self.drive.request_state(step)
                else:
                    self.drive.request_state(requested)
            except StateChangeError:
                pass  # the ESC shows the requested state whatever the model behind it makes of it
        self._sync_state()
        if requested in (EcState.SAFEOP, EcState.OP):
            self._exchange(None)

    def _refuse(self, requested: str, code: int, why: str) -> None:
        self.refusals.append(Refusal(requested, code, why))
        self._sync_state(error=True, code=code)

    def _check_config(self, current: EcState, requested: EcState) -> None:
        roles = self.roles
        if current is EcState.INIT and requested in (EcState.PREOP, EcState.BOOT):
            code = AlStatus.INVALID_MAILBOX_BOOT if requested is EcState.BOOT else AlStatus.INVALID_MAILBOX
            if roles.mbx_out is None or roles.mbx_in is None:
                if requested is EcState.BOOT:
                    raise ConfigRefused(code, "the device has no mailbox to boot through")
                return  # no mailbox: nothing to check at INIT -> PRE-OP
            out, inp = self.esc.sm(roles.mbx_out), self.esc.sm(roles.mbx_in)
            for n, sm, direction in ((roles.mbx_out, out, SM_DIR_WRITE), (roles.mbx_in, inp, SM_DIR_READ)):
                if not sm.enabled or sm.control & 0x3 != SM_MODE_MAILBOX or (sm.control >> 2) & 3 != direction:
                    raise ConfigRefused(code, f"SM{n} is not an enabled mailbox of the right direction")
                if sm.length < 8 or sm.start < R.PROCESS_RAM or sm.end > len(self.esc.mem):
                    raise ConfigRefused(code, f"SM{n} at 0x{sm.start:04X} length {sm.length} is not usable")
            if out.start < inp.end and inp.start < out.end:
                raise ConfigRefused(code, "the mailbox sync managers overlap")

    def _check_process_data(self) -> None:
        """PRE-OP -> SAFE-OP: the process data SMs (SM2/SM3 of a drive with a mailbox; those the SII names
        otherwise) and their FMMUs against the process image the drive's PDO assignment gives (the drive has
        accepted the assignment itself)."""
        out_size, in_size = self.drive.process_image_sizes()
        fmmus = self.esc.fmmus()
        for sms, size, direction, code, what in (
                (self.roles.outputs, out_size, SM_DIR_WRITE, AlStatus.INVALID_OUTPUT_CONFIG, "output"),
                (self.roles.inputs, in_size, SM_DIR_READ, AlStatus.INVALID_INPUT_CONFIG, "input")):
            if size == 0:
                for n in sms:
                    sm = self.esc.sm(n)
                    if sm.enabled and sm.length:
                        raise ConfigRefused(code, f"SM{n} is enabled with {sm.length} bytes, the drive has no "
                                                  f"{what}s")
                continue
            used = [n for n in sms if self.esc.sm(n).enabled and self.esc.sm(n).length]
            if not used:
                first = f"SM{sms[0]}" if sms else f"an {what} SM"
                raise ConfigRefused(code, f"{first} is not enabled ({size} {what} bytes assigned)")
            total = 0
            for n in used:
                sm = self.esc.sm(n)
                # buffered (3 buffers), or one buffer (mailbox mode) where the SII gives that: older terminals
                # such as the EM7004 have their process data SMs in mailbox mode (ControlByte 0x26/0x22)
                modes = (SM_MODE_BUFFERED, SM_MODE_MAILBOX) if self._one_buffer[n] else (SM_MODE_BUFFERED,)
                if sm.control & 0x3 not in modes or (sm.control >> 2) & 3 != direction:
                    raise ConfigRefused(code, f"SM{n} control 0x{sm.control:02X} is not a buffered {what} SM")
                if not sm.active:
                    raise ConfigRefused(code, f"SM{n} at 0x{sm.start:04X} is outside the process RAM")
                mapped = [f for f in fmmus if (f.write if direction == SM_DIR_WRITE else f.read)
                          and f.physical < sm.end and f.physical + f.length > sm.start]
                if not mapped:
                    raise ConfigRefused(code, f"no {'write' if direction == SM_DIR_WRITE else 'read'} FMMU "
                                              f"maps SM{n}")
                total += sm.length
            if total != size:
                where = f"SM{used[0]} length" if len(used) == 1 else \
                    "SM" + "+".join(str(n) for n in used) + " lengths"
                raise ConfigRefused(code, f"{where} {total} differs from the {size} {what} bytes of the PDO "
                                          "assignment")

    # ------------------------------------------------------------------------------------------
    # mailbox
    # ------------------------------------------------------------------------------------------
    def mailbox_written(self, esc: Esc, sm: int, data: bytes) -> None:
        esc.pdi_mailbox_take(sm)
        if sm in self.roles.outputs:  # process data through one buffer: the outputs, taken at once
            self.buffer_written(esc, sm, data)
            return
        if sm != self.roles.mbx_out:
            return  # a mailbox SM the device does not have: nothing behind it reads the request
        delay = self.drive.faults.mailbox_delay_ms(self.drive.state())
        if delay:
            self._reply_due = esc.frame_ns + delay * 1_000_000
        self.mailbox.handle(data)
        self._push_mailbox()

    def mailbox_read(self, esc: Esc, sm: int) -> None:
        if sm in self.roles.inputs:  # process data through one buffer: read out, as a buffered SM's last byte
            self.buffer_read(esc, sm)
            return
        self._push_mailbox()

    def mailbox_repeat(self, esc: Esc, sm: int) -> None:
        last = self.mailbox.repeat()
        if last is not None:
            esc.pdi_mailbox_put(sm, last, force=True)
        esc.pdi_repeat_ack(sm)

    def _push_mailbox(self) -> None:
        esc = self.esc
        mbx_in = self.roles.mbx_in
        if mbx_in is None or esc.sm_full(mbx_in) or esc.sm_deactivated(mbx_in) or not esc.sm(mbx_in).active:
            return
        if self._reply_due is not None:
            if esc.frame_ns < self._reply_due:
                return
            self._reply_due = None
        reply = self.mailbox.pending()
        if reply is not None:
            esc.pdi_mailbox_put(mbx_in, reply)

    # ------------------------------------------------------------------------------------------
    # process data
    # ------------------------------------------------------------------------------------------
    def buffer_written(self, esc: Esc, sm: int, data: bytes) -> None:
        outputs = self.roles.outputs
        if sm in outputs:
            if len(outputs) > 1:  # the image is the output SMs' buffers in SM order
                data = b"".join(bytes(esc.mem[s.start:s.end]) for s in (esc.sm(n) for n in outputs) if s.active)
            self._outputs = data
            self._pd_event = True

    def buffer_read(self, esc: Esc, sm: int) -> None:
        if self._no_outputs and sm in self.roles.inputs:
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
        period = self.drive.cycle_ns()
        if at is None or period > MAX_OWN_CYCLE_NS:
            self._cycle_at = now
            return 1  # the first event; or a 60C2h no processor cycles at: each event is the drive's cycle
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
        size = drive.process_image_sizes()[0]
        if outputs is None or state is not _OP:
            outputs = bytes(size)
        elif len(outputs) != size:  # SMs the master sized otherwise (device emulation checks nothing)
            outputs = outputs[:size] + bytes(max(0, size - len(outputs)))
        try:
            inputs = drive.exchange(outputs)
        except TargetError:
            self._sync_state()  # e.g. power lost during an EEPROM write: the drive is back in INIT
            return
        for n in self.roles.inputs:  # the input image of the drive's layout, over the input SMs in SM order
            if not inputs:
                break  # empty for a drive without inputs
            sm = self.esc.sm(n)
            if sm.active:
                if sm.mailbox:  # one buffer: the master reads it once it is full
                    self.esc.pdi_mailbox_put(n, inputs[:sm.length], force=True)
                else:
                    self.esc.pdi_write(sm.start, inputs[:sm.length])
                inputs = inputs[sm.length:]

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
        if self.emulation:
            return  # no application: the ESC stays in its state (a digital I/O ESC would release its outputs)
        if self.drive.state() is EcState.OP:
            self.drive.lose_communication()
            self._sync_state(error=True, code=AlStatus.SM_WATCHDOG)

    def frame_done(self, esc: Esc) -> None:
        if not self.emulation and _CODES[self.drive.state()] != esc.al_state:
            self._sync_state()  # the drive changed state by itself (power loss, communication lost)
        self._push_mailbox()


@dataclass(frozen=True, slots=True)
class SmRoles:
    """What each sync manager of a slave is for, from the SII's SyncM category (ETG.2010: type 1 mailbox out,
    2 mailbox in, 3 outputs, 4 inputs; virtual SMs, enable bit 2, are no SMs of the ESC). The process data of
    a slave with a mailbox is the first output and the first input SM (1C12h/1C13h assign to SM2/SM3); a slave
    without one has its fixed image over every output and every input SM, in SM order."""

    mbx_out: int | None
    mbx_in: int | None
    outputs: tuple[int, ...]
    inputs: tuple[int, ...]

    @property
    def has_mailbox(self) -> bool:
        return self.mbx_out is not None and self.mbx_in is not None

    @property
    def mailboxes(self) -> tuple[int, ...]:
        return tuple(n for n in (self.mbx_out, self.mbx_in) if n is not None)


#: the process RAM of an ET1100, and the most an ESC's 16-bit address space leaves above the registers
DEFAULT_RAM, MAX_RAM = 8192, 0x10000 - R.PROCESS_RAM

#: the SII's SM types (ETG.2010 SyncM category), for messages
SM_KINDS = {0: "unused", 1: "mailbox out", 2: "mailbox in", 3: "outputs", 4: "inputs"}

#: a slave whose SII has no SyncM category: the usual SM0/SM1 mailbox, SM2/SM3 process data
DEFAULT_ROLES = SmRoles(MBX_OUT, MBX_IN, (PD_OUT,), (PD_IN,))


def sii_sync_managers(sii: bytes) -> list[tuple[int, int, int, int, int]] | None:
    """(start, length, control, enable, type) of each SM of the SII's SyncM category, None without one."""
    from ecattool.sii.image import parse
    from ecattool.sii.model import SyncMCategory

    try:
        image = parse(sii)
    except (EcatToolError, ValueError, struct.error):  # an image the SII tools refuse: the usual roles
        return None
    for cat in image.categories:
        if isinstance(cat, SyncMCategory):
            return [(sm.start, sm.length, sm.control, sm.enable, sm.type) for sm in cat.sync_managers]
    return None


def ram_for(sms: list[tuple[int, int, int, int, int]] | None) -> int:
    """The process RAM (bytes) of the ESC a slave with the SII sync managers ``sms`` has: 8 KiB (an ET1100),
    or as much as its SMs reach, in whole KiB (an FPGA ESC such as an EL6695's has up to 60 KiB)."""
    end = max((start + length for start, length, _, enable, _ in sms or () if not enable & 0x04), default=0)
    need = -(-(end - R.PROCESS_RAM) // 1024) * 1024
    return max(DEFAULT_RAM, min(need, MAX_RAM))


def served_sii(device: Device) -> bytes:
    """The SII image ``ecattool sii build`` makes of ``device``; where the image does not fit the EEPROM size the
    ESI declares (a vendor's ByteSize too small for its own PDO categories), the served EEPROM is as large as
    the image needs (the next power of two)."""
    from ecattool.sii.builder import assemble, build

    try:
        return build(device).to_bytes()
    except InputError:
        used = len(assemble(device).to_bytes())
        size = 2048
        while size < used:
            size *= 2
        return build(device, size=size).to_bytes()


def sm_roles(sms: list[tuple[int, int, int, int, int]] | None, *, mailbox: bool = True) -> SmRoles:
    """The :class:`SmRoles` of the SII sync managers ``sms`` (:func:`sii_sync_managers`). Without a SyncM
    category: the usual four where the SII has a standard mailbox (``mailbox``: word 0x19, its size), none
    where it has not (a coupler)."""
    if sms is None:
        return DEFAULT_ROLES if mailbox else SmRoles(None, None, (), ())
    real = [(n, t) for n, (_, _, _, enable, t) in enumerate(sms) if not enable & 0x04]
    mbx_out = next((n for n, t in real if t == 1), None)
    mbx_in = next((n for n, t in real if t == 2), None)
    outputs = tuple(n for n, t in real if t == 3)
    inputs = tuple(n for n, t in real if t == 4)
    if mbx_out is not None and mbx_in is not None:
        outputs, inputs = outputs[:1], inputs[:1]
    return SmRoles(mbx_out, mbx_in, outputs, inputs)


def drive_for_device(device: Device) -> Drive:
    """The simulated drive of ``device`` as it runs (:meth:`Drive.from_device`: a built-in profile device as it
    is, an ESI device with its default modules plugged in and the communication objects its ESI leaves out)."""
    return Drive.from_device(device)


def sii_image(drive: Drive, esi: str | Path | None = None, selector: str | None = None) -> bytes:
    """The SII ``ecattool sii build`` makes for ``drive``: from its ESI file when given, else from the
    drive's device model (built-in profiles)."""
    from ecattool.sii.builder import build

    if esi is not None:
        return build(esi_pkg.load_device(esi, selector)).to_bytes()
    return build(drive.device).to_bytes()
