"""A fake pysoem module (the 1.1 API) whose slaves are simulated drives.

Faithful to pysoem/SOEM where ecattool depends on it (checked against the real module by
tests/target/test_pysoem_surface.py when pysoem is installed): names, signatures, exception types and attributes,
state constants, the AL status with its error indication, the IO map that ``config_map`` builds from the PDO
assignment the slaves report over CoE, the working counter of a process data cycle.

Stricter than the real library where the real one would fail silently on a customer's bus; those cases
raise :class:`FakeMisuse` so that a test fails:
- ``slave.output = data`` of another length than the slave's output image (pysoem ``memcpy``'s it);
- ``dc_sync`` before ``Master.config_dc()`` (SYNC0 would start without propagation delays and offsets);
- ``config_map`` while a slave is in SAFE-OP or OP (SOEM would reprogram its sync managers under it).
Like a real drive, a slave asked for OP enters it only when a process data frame reaches it.
"""

from __future__ import annotations

import types
from typing import Any

from ecattool.errors import SdoAbort, SdoTimeout, StateChangeError
from ecattool.od.model import EcState

NONE_STATE, INIT_STATE, PREOP_STATE, BOOT_STATE, SAFEOP_STATE, OP_STATE = 0, 1, 2, 3, 4, 8
STATE_ACK = 0x10
STATE_ERROR = 0x10
CODES = {EcState.INIT: INIT_STATE, EcState.PREOP: PREOP_STATE, EcState.BOOT: BOOT_STATE,
         EcState.SAFEOP: SAFEOP_STATE, EcState.OP: OP_STATE}
STATES = {v: k for k, v in CODES.items()}
#: SOEM's sdo_read buffer when no size is given
STATIC_SDO_READ_BUFFER_SIZE = 256


class FakeMisuse(AssertionError):
    """A use of pysoem that the real library would not reject but that breaks a real bus."""


class SdoError(Exception):
    def __init__(self, slave_pos, index, subindex, abort_code, desc):
        self.slave_pos = slave_pos
        self.index = index
        self.subindex = subindex
        self.abort_code = abort_code
        self.desc = desc


class Emergency(Exception):
    def __init__(self, slave_pos, error_code, error_reg, b1, w1, w2):
        self.slave_pos = slave_pos
        self.error_code = error_code
        self.error_reg = error_reg
        self.b1 = b1
        self.w1 = w1
        self.w2 = w2

    def __str__(self):
        return f"Slave {self.slave_pos}:  {self.error_code:04x}, {self.error_reg:02x}"


class MailboxError(Exception):
    def __init__(self, slave_pos, error_code, desc):
        self.slave_pos = slave_pos
        self.error_code = error_code
        self.desc = desc


class PacketError(Exception):
    def __init__(self, slave_pos, error_code):
        self.slave_pos = slave_pos
        self.error_code = error_code

    @property
    def desc(self):
        return {1: "Unexpected frame returned", 3: "Data container too small for type"}[self.error_code]


class ConfigMapError(Exception):
    def __init__(self, error_list):
        self.error_list = error_list


class WkcError(Exception):
    def __init__(self, message=None, wkc=None):
        self.message = message
        self.wkc = wkc


class NetworkInterfaceNotOpenError(Exception):
    pass


class EepromError(Exception):
    def __init__(self, message):
        self.message = message


class SdoInfoError(Exception):
    def __init__(self, message):
        self.message = message


class CoeObjectEntry:
    """An entry of SOEM's OE list (``pysoem.CdefCoeObjectEntry``)."""

    def __init__(self, name, data_type, bit_length, obj_access):
        self.name, self.data_type, self.bit_length, self.obj_access = (name.encode("latin-1", "replace"), data_type, bit_length,
                                                                      obj_access)


class CoeObject:
    """An object of SOEM's OD list (what ``slave.od`` returns), as the virtual bus shows it to the real pysoem
    (tests/wire/test_wire_mailbox.py): names as bytes; a VAR has its data type and no entries; an ARRAY/RECORD lists
    every sub-index up to the highest."""

    def __init__(self, index, object_code, name, data_type=0, entries=()):
        self.index, self.object_code, self.name = index, object_code, name.encode("latin-1", "replace")
        self.data_type = data_type
        self.entries = list(entries)


def _object_access(e):
    bits = 0
    for i, s in enumerate((EcState.PREOP, EcState.SAFEOP, EcState.OP)):
        bits |= (1 << i) if s in e.access.read else 0
        bits |= (8 << i) if s in e.access.write else 0
    return bits | (0x40 if e.rx_mappable else 0) | (0x80 if e.tx_mappable else 0)


def soem_od(dictionary):
    """The OD list SOEM reads over the SDO Information service, from a drive's dictionary."""
    codes = {"VAR": 7, "ARRAY": 8, "RECORD": 9}
    out = []
    for obj in dictionary:
        code = codes.get(obj.object_code.name, 7)
        if code == 7:
            e = obj.entry(0)
            out.append(CoeObject(obj.index, 7, obj.name, e.datatype.code if e and e.datatype else 0))
            continue
        entries = []
        for sub in range(obj.max_subindex + 1):
            e = obj.entry(sub)
            entries.append(CoeObjectEntry("", 0, 0, 0) if e is None else
                           CoeObjectEntry(e.name, e.datatype.code if e.datatype else 0, e.bit_size, _object_access(e)))
        out.append(CoeObject(obj.index, code, obj.name, entries=entries))
    return out


class CdefSlave:
    """``pysoem.CdefSlave`` backed by a simulated drive (``ecattool.sim.Drive``)."""

    def __init__(self, master, pos, drive):
        self._master = master
        self._pos = pos  # 1-based, as in SOEM
        self.drive = drive
        ident = drive.identity()
        self._man, self._id, self._rev = ident.vendor_id, ident.product_code, ident.revision
        self._error = False
        self._al_code = 0
        self._state = CODES[drive.state()]
        self._obytes = self._ibytes = 0
        self._out = b""
        self._in = b""
        self._emcy_callbacks = []
        self._pending_op = None
        self.pending_emergencies = []  # (error_code, error_reg) the next mailbox transfer pops
        self.dc = None  # what dc_sync wrote: (activation 0x0981, sync0 cycle, shift, sync1 cycle)
        self.config_func = None  # pysoem: called by config_map() with the 0-based position (SOEM's PO2SOconfig)
        from ecattool.sii.builder import build

        self.sii = bytearray(build(drive.device).to_bytes())  # the EEPROM words (what sim serve gives the ESC)
        self.sii_writes = []  # (word address, 2 bytes) in the order they were written
        self.watchdog_ms = {"pdi": 100.0, "processdata": 100.0}  # the ESC defaults (0x0400 = 2498, 0x410/0x420)

    # -- identity and images (read-only properties, as in pysoem) --
    man = property(lambda self: self._man)
    id = property(lambda self: self._id)
    rev = property(lambda self: self._rev)
    name = property(lambda self: "fake")
    al_status = property(lambda self: self._al_code)
    input = property(lambda self: self._in)

    @property
    def output(self):
        return self._out

    @output.setter
    def output(self, value):
        if not isinstance(value, bytes):
            raise TypeError(f"expected bytes, got {type(value).__name__}")
        if len(value) != self._obytes:
            raise FakeMisuse(f"slave {self._pos}: {len(value)} output bytes into a {self._obytes}-byte image")
        self._out = value

    @property
    def state(self):
        return self._state

    @state.setter
    def state(self, value):
        self._state = value

    # -- mailbox --
    def _mailbox(self, fn, index, subindex, *args):
        self._master.check_context_is_initialized()
        if not 0 <= subindex <= 255:
            raise OverflowError("value too large to convert to uint8_t")
        try:
            result = fn(index, subindex, *args)
        except SdoAbort as exc:
            raise SdoError(self._pos, index, subindex, exc.code, str(exc)) from None
        except SdoTimeout:
            raise WkcError(wkc=0) from None
        finally:
            while self.pending_emergencies:
                code, reg = self.pending_emergencies.pop(0)
                emcy = Emergency(self._pos, code, reg, 0, 0, 0)
                if not self._emcy_callbacks:
                    raise emcy  # the SDO's own result is lost
                for cb in self._emcy_callbacks:
                    cb(emcy)
        return result

    def sdo_read(self, index, subindex, size=0, ca=False, *, release_gil=None):
        data = self._mailbox(self.drive.sdo_upload, index, subindex, bool(ca))
        if len(data) > (size or STATIC_SDO_READ_BUFFER_SIZE):
            raise PacketError(self._pos, 3)
        return bytes(data)

    def sdo_write(self, index, subindex, data, ca=False, *, release_gil=None):
        if not isinstance(data, bytes):
            raise TypeError(f"Argument 'data' has incorrect type (expected bytes, got {type(data).__name__})")
        self._mailbox(self.drive.sdo_download, index, subindex, data, bool(ca))

    # -- SII EEPROM and SDO Information --
    def eeprom_read(self, word_address, timeout=20000):
        self._master.check_context_is_initialized()
        if not 0 <= 2 * word_address < len(self.sii):
            raise EepromError(f"EEPROM read at word {word_address} failed")
        return bytes(self.sii[2 * word_address:2 * word_address + 4]).ljust(4, b"\xff")

    def eeprom_write(self, word_address, data, timeout=20000):
        self._master.check_context_is_initialized()
        if len(data) != 2:
            raise AttributeError("data size must be 2")
        if not 0 <= 2 * word_address < len(self.sii):
            raise EepromError(f"EEPROM write at word {word_address} failed")
        self.sii[2 * word_address:2 * word_address + 2] = data
        self.sii_writes.append((word_address, bytes(data)))

    @property
    def od(self):
        self._master.check_context_is_initialized()
        return soem_od(self.drive.device.dictionary)

    def get_watchdog(self, wd_type):
        return self.watchdog_ms[wd_type]

    def set_watchdog(self, wd_type, wd_time_ms):
        self.watchdog_ms[wd_type] = float(wd_time_ms)

    def add_emergency_callback(self, callback):
        self._master.check_context_is_initialized()
        self._emcy_callbacks.append(callback)

    # -- AL state machine --
    def _observe(self):
        self._state = CODES[self.drive.state()] | (STATE_ERROR if self._error else 0)

    def _request(self, value):
        """What the slave does with a write to AL control."""
        code, ack = value & 0x0F, value & STATE_ACK
        if self._error and not ack:
            return  # the error indication must be acknowledged before the slave takes a new request
        if ack:
            self._error = False
            self._al_code = 0
        if code not in STATES:
            self._error, self._al_code = True, 0x0012
            return
        try:
            self.drive.request_state(STATES[code])
        except StateChangeError as exc:
            self._error, self._al_code = True, exc.al_status

    def write_state(self):
        self._master.check_context_is_initialized()
        value = self._state
        if value & 0x0F == OP_STATE and self.drive.state() is EcState.SAFEOP and (value & STATE_ACK or not self._error):
            self._pending_op = value  # the slave waits for valid outputs before it enters OP
        else:
            self._request(value)
        return 1

    def state_check(self, expected_state, timeout=2000):
        self._master.check_context_is_initialized()
        self._observe()
        return self._state & 0x0F  # SOEM returns the state without the error indication

    # -- distributed clocks --
    def dc_sync(self, act, sync0_cycle_time, sync0_shift_time=0, sync1_cycle_time=None):
        self._master.check_context_is_initialized()
        if act and not self._master.dc_configured:
            raise FakeMisuse("dc_sync before Master.config_dc()")
        activation = 0 if not act else (0x07 if sync1_cycle_time is not None else 0x03)
        self.dc = (activation, sync0_cycle_time, sync0_shift_time, sync1_cycle_time)
        self.drive.configure_dc(activation << 8, sync0_cycle_time)

    # -- used by the fake master --
    def _read_mapping_bits(self, assign):
        """What SOEM's ecx_readPDOmap does: the PDO assignment object, then each PDO's entries, over CoE."""
        bits = 0
        count = self.sdo_read(assign, 0)[0]
        for i in range(1, count + 1):
            pdo = int.from_bytes(self.sdo_read(assign, i), "little")
            for j in range(1, self.sdo_read(pdo, 0)[0] + 1):
                bits += int.from_bytes(self.sdo_read(pdo, j), "little") & 0xFF
        return bits


class VirtualClock:
    """A clock for PysoemTarget(clock=, sleep=) that advances only when the adapter sleeps: the pacing of
    process data is checked without real waiting (and without timed assertions)."""

    def __init__(self):
        self.t = 0.0

    def now(self):
        return self.t

    def sleep(self, seconds):
        assert seconds > 0
        self.t += seconds


def make_module(drives, interfaces=("eth0", "eth-test")):
    """A pysoem-like module whose bus (on any of ``interfaces``) holds ``drives`` in order."""

    class Master:
        def __init__(self):
            self.slaves = None
            self.context_initialized = False
            self.manual_state_change = 0
            self.dc_configured = False
            self.map_calls = 0
            self.opened = None
            self._wkc = -1
            self.clock = None  # a VirtualClock the test shares with the adapter, to record when frames go out
            self.sent_at = []
            self.sdo_read_timeout = self.sdo_write_timeout = 700000  # SOEM's EC_TIMEOUTRXM, in microseconds
            self.state_checks = []  # (expected state, timeout in microseconds) of every bus-wide state check

        def check_context_is_initialized(self):
            if not self.context_initialized:
                raise NetworkInterfaceNotOpenError("SOEM Network interface is not initialized or has been closed")

        def open(self, ifname, ifname_red=None):
            if ifname not in interfaces:
                raise ConnectionError(f"could not open interface {ifname}")
            self.context_initialized = True
            self.opened = ifname

        def config_init(self, usetable=False, *, release_gil=None):
            self.check_context_is_initialized()
            self.slaves = []
            if not drives:
                return -1
            for i, d in enumerate(drives):
                s = CdefSlave(self, i + 1, d)
                s._request(INIT_STATE | STATE_ACK)  # SOEM resets every slave to INIT first
                if self.manual_state_change == 0:
                    s._request(PREOP_STATE | STATE_ACK)
                s._observe()
                self.slaves.append(s)
            return len(self.slaves)

        def config_map(self):
            self.check_context_is_initialized()
            self.map_calls += 1
            errors = []
            for s in self.slaves:
                s._observe()
                if s._state & 0x0F in (SAFEOP_STATE, OP_STATE):
                    raise FakeMisuse(f"config_map reprograms slave {s._pos}, which runs in AL state 0x{s._state:02X}")
                if s._state & 0x0F != PREOP_STATE:
                    continue  # SOEM waits for PRE-OP, then finds no CoE mapping (the SII fallback is not modelled)
                if s.config_func is not None:  # SOEM calls PO2SOconfig before it reads the PDO mapping
                    s.config_func(s._pos - 1)
                try:
                    obits, ibits = s._read_mapping_bits(0x1C12), s._read_mapping_bits(0x1C13)
                except (SdoError, MailboxError) as exc:
                    errors.append(exc)
                    continue
                s._obytes, s._ibytes = (obits + 7) // 8, (ibits + 7) // 8
                s._out, s._in = bytes(s._obytes), bytes(s._ibytes)
                if self.manual_state_change == 0:
                    s._request(SAFEOP_STATE)
            if errors:
                raise ConfigMapError(errors)
            return sum(s._obytes + s._ibytes for s in self.slaves)

        def config_dc(self):
            self.check_context_is_initialized()
            self.dc_configured = True
            return True

        def read_state(self):
            self.check_context_is_initialized()
            for s in self.slaves:
                s._observe()
            return min(s._state & 0x0F for s in self.slaves)

        def state_check(self, expected_state, timeout=50000):
            """All slaves (a broadcast read: the AL status bits of every slave ORed)."""
            self.check_context_is_initialized()
            self.state_checks.append((expected_state, timeout))
            found = 0
            for s in self.slaves:
                s._observe()
                found |= s._state
            return found & 0x0F

        @property
        def expected_wkc(self):
            return sum(2 * bool(s._obytes) + bool(s._ibytes) for s in self.slaves)

        def send_processdata(self, *, release_gil=None):
            self.check_context_is_initialized()
            self.sent_at.append(self.clock.now() if self.clock else None)
            wkc = 0
            for s in self.slaves:
                if s._pending_op is not None and (s._obytes or s._ibytes):
                    s._request(s._pending_op)  # the outputs of this frame let the slave complete SAFE-OP -> OP
                    s._pending_op = None
                state = s.drive.state()
                if state in (EcState.SAFEOP, EcState.OP) and (s._obytes or s._ibytes):
                    s._in = s.drive.exchange(s._out)
                    wkc += bool(s._ibytes) + (2 * bool(s._obytes) if state is EcState.OP else 0)
            self._wkc = wkc
            return 1

        def receive_processdata(self, timeout=2000, *, release_gil=None):
            self.check_context_is_initialized()
            wkc, self._wkc = self._wkc, -1
            return wkc

        def close(self):
            self.context_initialized = False

    return types.SimpleNamespace(
        Master=Master, CdefMaster=Master, CdefSlave=CdefSlave, SdoError=SdoError, Emergency=Emergency,
        MailboxError=MailboxError, PacketError=PacketError, ConfigMapError=ConfigMapError, WkcError=WkcError,
        NetworkInterfaceNotOpenError=NetworkInterfaceNotOpenError, EepromError=EepromError,
        SdoInfoError=SdoInfoError, NONE_STATE=NONE_STATE, INIT_STATE=INIT_STATE,
        PREOP_STATE=PREOP_STATE, BOOT_STATE=BOOT_STATE, SAFEOP_STATE=SAFEOP_STATE, OP_STATE=OP_STATE,
        STATE_ACK=STATE_ACK, STATE_ERROR=STATE_ERROR)


def public_surface() -> dict[str, Any]:
    """The names the fake pretends, for the comparison with the real module."""
    return vars(make_module([]))
