"""ecmc (EPICS motion control, PSI/ESS) startup scripts: ``Cfg.EcAddSdo`` lines and what ecmccfg writes.

Writing: one ``ecmcConfigOrDie "Cfg.EcAddSdo(<slave>,<index>,<sub>,<value>,<size>)"`` per command of 1, 2
or 4 bytes (ecmc's SDO value is a 32-bit integer); longer data and complete-access writes use
``Cfg.EcAddSdoBuffer`` / ``Cfg.EcAddSdoComplete`` with the data as hex bytes. The slave is its bus position,
or the ``${ECMC_EC_SLAVE_NUM}`` macro when the position of a single slave is unknown (as ecmccfg hardware
scripts use it; several slaves of unknown position get their list index).
PDO information becomes ``Cfg.EcAddEntryComplete`` lines, DC ``Cfg.EcSlaveConfigDC`` (SYNC0 at the ecmc sample
rate, as ecmccfg writes it, where the cycle is not known).

Reading: ``EcAddSdo``, ``EcWriteSdo`` (both become PS commands: ecmc sends them in PRE-OP),
``EcAddSdoBuffer``/``EcAddSdoComplete``, ``EcAddEntryComplete`` (PDO information), and ``epicsEnvSet``
macros (``$(NAME)``/``${NAME}``, ``${NAME=default}``). An unresolved slave macro such as
``${ECMC_EC_SLAVE_NUM}`` names the slave; an unresolved macro in an index or value is an error with the line.
Reads and verifies (``EcReadSdo``, ``EcVerifySdo``) and included scripts are reported, not followed.
A write through ``ecmcConfig`` (not ``ecmcConfigOrDie``, so its failure is tolerated, as ecmccfg does for the
Technosoft 2080h reset that sends no reply) gets ``expect_reply=False``, and is written back that way.
A comment line right before a command becomes its comment.
"""

from __future__ import annotations

import re
from pathlib import Path

from ecattool.errors import EncodeError, InputError, Location
from ecattool.esi.model import Direction, Identity, Pdo, PdoEntry
from ecattool.findings import Severity
from ecattool.od import types as dt
from ecattool.od.numbers import parse_int
from ecattool.od.standard import standard_type
from ecattool.od.types import Kind, lookup
from ecattool.startup.config import SlaveConfig
from ecattool.startup.formats._common import (
    decode_text,
    encode_sized,
    one_line,
    parse_hex,
    pdo_sm,
    soe_losses,
    unsigned_type,
)
from ecattool.startup.model import StartupCommand, StartupList

NAME = "ecmc"
EXTENSIONS = (".cmd", ".script")
DESCRIPTION = "ecmc/EPICS startup script (Cfg.EcAddSdo lines; reads EcWriteSdo and ecmccfg macros too)"

SLAVE_MACRO = "${ECMC_EC_SLAVE_NUM}"
#: the longest macro value or expanded line (ecmccfg's longest are file paths of a few hundred characters)
MAX_MACRO_CHARS = 1 << 16
_CALL = re.compile(r"Cfg\.(Ec\w+)\s*\((.*)\)")
#: a command given to ecmcConfig without the ``Cfg.`` prefix (ecmccfg writes ``ecmcConfig "EcReadSdo(...)"``)
_BARE_CALL = re.compile(r'^ecmcConfig(?:OrDie)?\s+"\s*(Ec\w+)\s*\((.*)\)')
#: iocsh lines with no effect on the slave configuration
_NO_EFFECT = re.compile(r"^(epicsThreadSleep|ecmcFileExist|iocshLoad\s*\(\s*\$\{?ecmccfg_DIR)\b")
#: ecmc data type names (``EcAddSdoDT``, ``EcAddEntryDT``) -> CoE type
ECMC_TYPES = {"B1": "BOOL", "B2": "BIT2", "B3": "BIT3", "B4": "BIT4", "U8": "USINT", "S8": "SINT", "U16": "UINT",
              "S16": "INT", "U32": "UDINT", "S32": "DINT", "U64": "ULINT", "S64": "LINT", "F32": "REAL",
              "F64": "LREAL", "S8_TO_U8": "SINT", "S16_TO_U16": "INT", "S32_TO_U32": "DINT", "S64_TO_U64": "LINT"}
_ENVSET = re.compile(r'^\s*epicsEnvSet\s*\(\s*"?([A-Za-z_]\w*)"?\s*,?\s*"([^"]*)"\s*\)')
_MACRO = re.compile(r"\$[({]([A-Za-z_]\w*)(?:=([^)}]*))?[)}]")
_SDO_WRITES = {"EcAddSdo", "EcWriteSdo"}
#: header lines of ecmccfg scripts and of the scripts its .sw converter writes: about the file, not a command
_HEADER_FIELD = re.compile(r"^(date|author|file|input file[\w ]*|output file[\w ]*|description|brief|version)\s*:",
                           re.IGNORECASE)
_BUFFER_WRITES = {"EcAddSdoBuffer", "EcAddSdoComplete", "EcWriteSdoComplete"}
_REPORTED = {"EcReadSdo", "EcVerifySdo", "EcAddSdoAsync"}
#: understood and without a startup-list meaning (process-image access, master selection, diagnostics)
_NOT_STARTUP = {"EcSetMaster", "EcAddMemMap", "EcAddMemMapDT", "EcAddDataDT", "EcSetDiagnostics",
                "EcEnablePrintouts", "EcSetDomainFailedCyclesLimit", "EcSelectReferenceDC", "EcSetEntryUpdateInRealtime",
                "EcApplyConfig", "EcSetDelayECOkAtStartup", "EcSetSlaveNeedSDOSettings"}


def _slave_ref(c: SlaveConfig, i: int, many: bool) -> str:
    """The bus position; for one slave of unknown position the ecmccfg macro, for several their list index."""
    if c.position is not None:
        return str(c.position)
    return str(i) if many else SLAVE_MACRO


def _command_line(slave: str, cmd: StartupCommand) -> str:
    """The ecmc call. A startup write is added to the startup list (``EcAddSdo``, sent at every
    configuration); a one-shot write is written once when the script runs, as ecmccfg's EEPROM scripts do:
    ``ecmcConfigOrDie "Cfg.EcWriteSdo(...)"``, and a reset (no reply) through ``ecmcConfig``, whose failure
    does not stop the IOC. ecmc runs them in script order, so EEPROM writes come before the reset."""
    line = _call(slave, cmd)
    if not cmd.one_shot:
        return line
    if cmd.complete_access or len(cmd.data) not in (1, 2, 4):
        raise EncodeError(f"{cmd.address}: a one-shot write of {len(cmd.data)} bytes has no ecmc EcWriteSdo form",
                          cmd.source)
    line = line.replace("Cfg.EcAddSdo(", "Cfg.EcWriteSdo(", 1)
    return line.replace("ecmcConfigOrDie ", "ecmcConfig ", 1) if cmd.kind == "reset" else line


def _call(slave: str, cmd: StartupCommand) -> str:
    size = len(cmd.data)
    if cmd.complete_access:
        if cmd.subindex != 0:
            raise EncodeError(f"0x{cmd.index:04X}:{cmd.subindex:02X}: ecmc complete access starts at sub-index 0")
        return f'ecmcConfigOrDie "Cfg.EcAddSdoComplete({slave},0x{cmd.index:04X},{cmd.data.hex(" ").upper()},{size})"'
    if size in (1, 2, 4):
        args = f"0x{cmd.index:04X},0x{cmd.subindex:X},0x{cmd.int_value:X},{size}"
        return f'ecmcConfigOrDie "Cfg.EcAddSdo({slave},{args})"'
    args = f"0x{cmd.index:04X},0x{cmd.subindex:X},{cmd.data.hex(' ').upper()},{size}"
    return f'ecmcConfigOrDie "Cfg.EcAddSdoBuffer({slave},{args})"'


def export(configs: list[SlaveConfig]) -> str:
    out = ["#- ecmc startup SDOs written by ecattool"]
    for i, c in enumerate(configs):
        slave = _slave_ref(c, i, len(configs) > 1)
        out.append("")
        out.append(f"#- {one_line(c.label)}")
        if c.identity is not None:
            out.append(f'epicsEnvSet("ECMC_EC_VENDOR_ID"          "0x{c.identity.vendor_id:08x}")')
            out.append(f'epicsEnvSet("ECMC_EC_PRODUCT_ID"         "0x{c.identity.product_code:08x}")')
        for cmd in c.commands:
            notes = [one_line(cmd.comment)] if cmd.comment else []
            if cmd.transition != "PS":
                notes.append(f"transition {cmd.transition}: ecmc sends every SDO in PRE-OP")
            if notes:
                out.append(f"# {'; '.join(notes)}")
            out.append(_command_line(slave, cmd))
        if c.has_pdo_info:
            if c.identity is None:  # as in ecmccfg's shared scripts: the including hardware script sets them
                out.append("#- ECMC_EC_VENDOR_ID and ECMC_EC_PRODUCT_ID are not known here: the script that runs "
                           "this one must set them")
            out += _entry_lines(c, slave)
        if c.dc_assign_activate:
            if c.dc_cycle_ns:
                cycle = str(c.dc_cycle_ns)
            else:  # as ecmccfg hardware scripts do: SYNC0 at the ecmc sample rate
                cycle = "${ECMC_TEMP_PERIOD_NANO_SECS}"
                out.append('ecmcEpicsEnvSetCalc("ECMC_TEMP_PERIOD_NANO_SECS",1000/${ECMC_EC_SAMPLE_RATE=1000}*1E6)')
            out.append(f'ecmcConfigOrDie "Cfg.EcSlaveConfigDC({slave},0x{c.dc_assign_activate:x},{cycle},'
                       f'{c.dc_shift_ns or 0},{c.dc_sync1_cycle_ns or 0},{c.dc_sync1_shift_ns or 0})"')
        for s in c.soe_commands:
            out.append(f"#- SoE IDN {s.idn} drive {s.drive_no} ({s.transition}) {s.data.hex()}: "
                       "not representable in ecmc")
    return "\n".join(out) + "\n"


#: CoE float types -> ecmc's data type (``Cfg.EcAddEntryDT``)
_ECMC_REAL = {"REAL": "F32", "REAL32": "F32", "LREAL": "F64", "REAL64": "F64"}

#: the entry sizes ecmc maps (``ecmcEcEntry``: B1..B4 and whole 8/16/32/64-bit values); others map as 0 bits
ECMC_BITS = (64, 32, 16, 8, 4, 3, 2, 1)


def _pieces(bits: int) -> list[int]:
    """A gap of ``bits`` as gaps of sizes ecmc maps, largest first (a 5-bit gap: 4 + 1)."""
    out = []
    for size in ECMC_BITS:
        while bits >= size:
            out.append(size)
            bits -= size
    return out


def _entry_lines(c: SlaveConfig, slave: str) -> list[str]:
    """``Cfg.EcAddEntryComplete`` per PDO entry, with the sync manager of the source, names unique within the
    slave (ecmc stops the IOC on a duplicate) and gaps split into sizes ecmc maps; an entry of another size
    (ecmc would map it as 0 bits) is refused."""
    v, p = "${ECMC_EC_VENDOR_ID}", "${ECMC_EC_PRODUCT_ID}"
    out: list[str] = []
    used: set[str] = set()

    def unique(base: str) -> str:
        name, n = base, 1
        while name.lower() in used:
            n += 1
            name = f"{base}_{n}"
        used.add(name.lower())
        return name

    for direction, pdos in (("1", c.rx_pdos), ("2", c.tx_pdos)):
        for pdo in pdos:
            sm = pdo_sm(c, pdo)
            for k, e in enumerate(pdo.entries):
                base = re.sub(r"\W+", "_", e.name).strip("_")[:40] or f"entry_{pdo.index:04x}_{k}"
                if e.bit_len in ECMC_BITS:
                    sizes = [e.bit_len]
                elif e.index == 0:
                    sizes = _pieces(e.bit_len)
                else:
                    raise EncodeError(f"{c.label}: PDO 0x{pdo.index:04X} entry 0x{e.index:04X}:{e.subindex:02X} has "
                                      f"{e.bit_len} bits; ecmc maps entries of 1-4, 8, 16, 32 or 64 bits (it would "
                                      "map this one as 0 bits)", e.location or c.source)
                real = _ECMC_REAL.get((e.data_type or "").upper())
                if real is not None and sizes == [e.bit_len]:  # a float is typed, not read as an unsigned integer
                    out.append(f'ecmcConfigOrDie "Cfg.EcAddEntryDT({slave},{v},{p},{direction},{sm},0x{pdo.index:04x},'
                               f'0x{e.index:04x},0x{e.subindex:x},{real},{unique(base)})"')
                    continue
                signed = _signed(e.data_type)  # given where the type is known, as ecmccfg scripts do
                flag = "" if signed is None or len(sizes) > 1 else f"{int(signed)},"
                for bits in sizes:
                    out.append(f'ecmcConfigOrDie "Cfg.EcAddEntryComplete({slave},{v},{p},{direction},{sm},'
                               f'0x{pdo.index:04x},0x{e.index:04x},0x{e.subindex:x},{bits},{flag}{unique(base)})"')
    return out


# --- reading -----------------------------------------------------------------------------------------

#: (bits, signed) -> the integer type ecmc's signed flag means
_INT_TYPES = {(8, False): "USINT", (16, False): "UINT", (32, False): "UDINT", (64, False): "ULINT",
              (8, True): "SINT", (16, True): "INT", (32, True): "DINT", (64, True): "LINT"}


def _signed(type_name: str | None) -> bool | None:
    """Whether an entry of ``type_name`` is a signed integer (None: unknown or not an integer)."""
    t = lookup(type_name) if type_name else None
    if t is None or t.kind not in (Kind.SIGNED, Kind.UNSIGNED):
        return None
    return t.kind is Kind.SIGNED


def _split_args(text: str) -> list[str]:
    return [a.strip().strip('"') for a in text.split(",")]


class _Reader:
    def __init__(self, source: str) -> None:
        self.source = source
        self.env: dict[str, str] = {}
        self.slaves: dict[str, SlaveConfig] = {}
        self.pending_comment = ""
        self.pdos: dict[tuple[str, int], Pdo] = {}
        self.tolerant = False  # `ecmcConfig` (not OrDie): a failure is tolerated, e.g. a reset with no reply
        self.unused: list[tuple[str, str, Location, Severity]] = []  # notes for lines no slave owns yet
        self.location = Location(source)  # of the line being read

    def skip(self, rule: str, message: str, loc: Location, severity: Severity = Severity.WARNING,
             slave: str | None = None) -> None:
        """Report a line or command that is not used: on the slave it names, else on the script's slaves."""
        cfg = self.slaves.get(slave.strip()) if slave else None
        if cfg is not None:
            cfg.note(rule, message, loc, severity)
        else:
            self.unused.append((rule, message, loc, severity))

    def expand(self, text: str) -> str:
        """``text`` with the script's macros replaced (8 rounds at most, each result bounded)."""
        def repl(m: re.Match[str]) -> str:
            name, default = m.group(1), m.group(2)
            if name in self.env:
                return self.env[name]
            if default is not None:
                return default
            return m.group(0)

        for _ in range(8):
            new = _MACRO.sub(repl, text)
            if new == text:
                break
            if len(new) > MAX_MACRO_CHARS:
                raise InputError(f"macros expand to more than {MAX_MACRO_CHARS} characters", self.location)
            text = new
        return text

    def number(self, text: str, loc: Location, what: str) -> int:
        if _MACRO.search(text):
            raise InputError(f"{what} {text!r} uses a macro that the script does not define", loc)
        return parse_int(text, loc, what)

    def slave(self, ref: str, loc: Location) -> SlaveConfig:
        key = ref.strip()
        cfg = self.slaves.get(key)
        if cfg is None:
            pos = None if _MACRO.search(key) else self.number(key, loc, "slave position")
            cfg = SlaveConfig(startup=StartupList(), position=pos, source=loc)
            cfg.extra["ecmc_slave"] = key
            self.slaves[key] = cfg
        return cfg

    def comment(self, text: str) -> None:
        body = text.lstrip("#").strip()
        if text.startswith("#-") or not body:
            return
        if _HEADER_FIELD.match(body):  # the script's header (Date:, Author:, …) describes the file, not a write
            self.pending_comment = ""
            return
        if re.match(r"^<[A-Za-z]{2}>,", body) and body.count(",") >= 4:
            body = body.split(",", 4)[4].strip()  # a TwinCAT line quoted as comment: keep its comment field
        self.pending_comment = body

    def call(self, func: str, args: list[str], loc: Location) -> None:
        if func in _SDO_WRITES:
            if len(args) != 5:
                raise InputError(f"Cfg.{func} takes (slave,index,subindex,value,bytesize); "
                                 f"got {len(args)} arguments", loc)
            cfg = self.slave(args[0], loc)
            size = self.number(args[4], loc, "byte size")
            value = self.number(args[3], loc, "value")
            data = encode_sized(value, size, loc)
            cfg.startup.commands.append(StartupCommand(
                "PS", self.number(args[1], loc, "index"), self.number(args[2], loc, "subindex"), data,
                comment=self.pending_comment, type_name=unsigned_type(size), value=value,
                expect_reply=not (self.tolerant and func == "EcWriteSdo"), once=func == "EcWriteSdo", source=loc))
        elif func in _BUFFER_WRITES:
            complete = "Complete" in func
            if len(args) != (4 if complete else 5):
                raise InputError(f"Cfg.{func}: unexpected argument count {len(args)}", loc)
            cfg = self.slave(args[0], loc)
            data = parse_hex(args[-2], loc)
            if len(data) != self.number(args[-1], loc, "byte size"):
                raise InputError(f"Cfg.{func}: {len(data)} data bytes but byte size {args[-1]}", loc)
            cfg.startup.commands.append(StartupCommand(
                "PS", self.number(args[1], loc, "index"), 0 if complete else self.number(args[2], loc, "subindex"),
                data, comment=self.pending_comment, complete_access=complete, once=func.startswith("EcWrite"),
                source=loc))
        elif func == "EcAddEntryComplete":
            self.entry(args, loc)
        elif func == "EcSlaveConfigDC":
            self.dc(args, loc)
        elif func == "EcAddSdoDT":
            self.sdo_dt(args, loc)
        elif func == "EcAddEntryDT":
            self.entry(args, loc, typed=True)
        elif func == "EcSlaveVerify" and len(args) == 4:
            cfg = self.slave(args[1], loc)
            if cfg.identity is None and not _MACRO.search(args[2] + args[3]):
                cfg.identity = Identity(self.number(args[2], loc, "vendor id"), self.number(args[3], loc, "product code"))
        elif func in _REPORTED:
            self.skip("startup.ecmc.read", f"{func}({','.join(args)}) reads or verifies; not a startup write", loc,
                      Severity.INFO, args[0] if args else None)
        elif func in _NOT_STARTUP:
            self.skip("startup.ecmc.unused", f"{func}(...) is not part of a slave's startup configuration; not "
                      "converted", loc, Severity.INFO)
        else:
            self.skip("startup.ecmc.unused", f"{func}({','.join(args)}) is not understood; not converted", loc,
                      slave=args[0] if args else None)
        self.pending_comment = ""

    def sdo_dt(self, args: list[str], loc: Location) -> None:
        """``Cfg.EcAddSdoDT(slave,index,subindex,value,dataType)``: a startup SDO of an ecmc data type."""
        if len(args) != 5:
            raise InputError(f"Cfg.EcAddSdoDT takes (slave,index,subindex,value,dataType); got {len(args)} arguments",
                             loc)
        coe = ECMC_TYPES.get(args[4].strip().upper())
        if coe is None or coe.startswith("B"):
            raise InputError(f"Cfg.EcAddSdoDT: data type {args[4]!r} is not one of U8..U64, S8..S64, F32, F64", loc)
        if _MACRO.search(args[3]):
            raise InputError(f"value {args[3]!r} uses a macro that the script does not define", loc)
        t = dt.require(coe)
        text = args[3].strip()
        try:
            value: object = float(text) if t.kind is dt.Kind.REAL else parse_int(text, loc, "value")
        except ValueError:
            raise InputError(f"value {text!r} is not a number", loc) from None
        if t.kind is not dt.Kind.REAL and isinstance(value, float):
            value = int(value)
        try:
            data = t.encode(value)
        except EncodeError as exc:
            raise EncodeError(exc.message, loc) from None
        cfg = self.slave(args[0], loc)
        cfg.startup.commands.append(StartupCommand(
            "PS", self.number(args[1], loc, "index"), self.number(args[2], loc, "subindex"), data,
            comment=self.pending_comment, type_name=t.name, value=value, source=loc))

    def entry(self, args: list[str], loc: Location, typed: bool = False) -> None:
        """``Cfg.EcAddEntryComplete(slave,vendor,product,dir,sm,pdo,index,sub,bits,[signed,]name)``, its older
        ``...,bits,name,updateInRealtime)`` form, and ``Cfg.EcAddEntryDT(...,sub,dataType,name[,updateInRealtime])``."""
        func = "EcAddEntryDT" if typed else "EcAddEntryComplete"
        if len(args) < 10 or len(args) > 12:
            raise InputError(f"Cfg.{func} takes (slave,vendor,product,dir,sm,pdo,index,sub,"
                             f"{'dataType,name[,updateInRealtime]' if typed else 'bits,[signed,]name'}); "
                             f"got {len(args)} arguments", loc)
        cfg = self.slave(args[0], loc)
        vendor, product = args[1], args[2]
        if not _MACRO.search(vendor + product) and cfg.identity is None:
            cfg.identity = Identity(self.number(vendor, loc, "vendor id"), self.number(product, loc, "product code"))
        direction = Direction.RX if self.number(args[3], loc, "direction") == 1 else Direction.TX
        pdo_index = self.number(args[5], loc, "PDO index")
        pdo = self.pdos.get((args[0], pdo_index))
        if pdo is None:
            pdo = Pdo(direction, pdo_index, sm=self.number(args[4], loc, "sync manager"), location=loc)
            self.pdos[(args[0], pdo_index)] = pdo
            cfg.pdos(direction).append(pdo)
        index, sub = self.number(args[6], loc, "entry index"), self.number(args[7], loc, "entry sub")
        rest = args[9:]
        if typed:
            coe = ECMC_TYPES.get(args[8].strip().upper())
            if coe is None:
                raise InputError(f"Cfg.EcAddEntryDT: data type {args[8]!r} is not an ecmc type (B1..B4, U8..U64, "
                                 "S8..S64, F32, F64)", loc)
            data_type: str | None = coe
            bits = dt.require(coe).bits or 1
            name = rest[0]
        else:
            bits = self.number(args[8], loc, "bit length")
            if len(rest) >= 2 and _is_int(rest[0]) and not _is_int(rest[1]):  # ...,bits,signed,name[,rt]
                data_type = _INT_TYPES.get((bits, self.number(rest[0], loc, "signed flag") != 0))
                name = rest[1]
            else:  # ...,bits,name[,updateInRealtime]: a standard CiA-402 object has its standard type
                data_type = standard_type(index, sub, bits)
                name = rest[0]
        pdo.entries.append(PdoEntry(index, sub, bits, name=name, data_type=data_type or "", location=loc))

    def dc(self, args: list[str], loc: Location) -> None:
        """``Cfg.EcSlaveConfigDC(slave,assign_activate,sync0_cycle,sync0_shift,sync1_cycle,sync1_shift)``; a cycle
        or shift given by a macro the script leaves to ecmc (its sample rate) stays unknown."""
        if len(args) != 6:
            raise InputError("Cfg.EcSlaveConfigDC takes (slave,assign_activate,sync0_cycle,sync0_shift,"
                             f"sync1_cycle,sync1_shift); got {len(args)} arguments", loc)
        cfg = self.slave(args[0], loc)
        cfg.dc_assign_activate = self.number(args[1], loc, "DC assign activate")
        cycle, shift = (None if _MACRO.search(a) else self.number(a, loc, what)
                        for a, what in ((args[2], "SYNC0 cycle"), (args[3], "SYNC0 shift")))
        cfg.dc_cycle_ns, cfg.dc_shift_ns = cycle or None, shift
        sync1, shift1 = (None if _MACRO.search(a) else self.number(a, loc, what)
                         for a, what in ((args[4], "SYNC1 cycle"), (args[5], "SYNC1 shift")))
        cfg.dc_sync1_cycle_ns, cfg.dc_sync1_shift_ns = sync1 or None, shift1 or None

    def line(self, raw: str, n: int) -> None:
        loc = self.location = Location(self.source, n)
        s = raw.strip()
        if not s:
            return
        if s.startswith("#"):
            self.comment(s)
            return
        m = _ENVSET.match(s)
        if m:
            value = self.expand(m.group(2))
            if len(value) > MAX_MACRO_CHARS:  # macros doubling each other grow exponentially: a bounded budget
                raise InputError(f"macro {m.group(1)} expands to more than {MAX_MACRO_CHARS} characters", loc)
            self.env[m.group(1)] = value
            return
        m = _CALL.search(s) or _BARE_CALL.match(s)
        if m:
            self.tolerant = not s.startswith("ecmcConfigOrDie")
            self.call(m.group(1), _split_args(self.expand(m.group(2))), loc)
            return
        m = re.match(r"^epicsEnvUnset\s*\(\s*\"?(\w+)\"?\s*\)", s)
        if m:
            self.env.pop(m.group(1), None)
            return
        if _NO_EFFECT.match(s):
            return
        if "SCRIPTEXEC" in s or s.startswith("<"):
            self.skip("startup.ecmc.include", f"included script not followed: {self.expand(s)}", loc, Severity.INFO,
                      SLAVE_MACRO)
            return
        self.skip("startup.ecmc.unused", f"line not used: {s[:120]}", loc)

    def result(self) -> list[SlaveConfig]:
        vendor, product = self.env.get("ECMC_EC_VENDOR_ID"), self.env.get("ECMC_EC_PRODUCT_ID")
        if not self.slaves:
            self.slaves[SLAVE_MACRO] = SlaveConfig(startup=StartupList(), source=Location(self.source, 1),
                                                   extra={"ecmc_slave": SLAVE_MACRO})
        for cfg in self.slaves.values():
            if cfg.identity is None and vendor and product and not _MACRO.search(vendor + product):
                loc = Location(self.source)
                cfg.identity = Identity(parse_int(vendor, loc), parse_int(product, loc))
            if cfg.identity is not None:
                cfg.startup.vendor_id, cfg.startup.product_code = cfg.identity.vendor_id, cfg.identity.product_code
            if not cfg.name:
                cfg.name = self.env.get("ECMC_EC_HWTYPE") or Path(self.source).stem
            cfg.startup.name = cfg.name
        out = list(self.slaves.values())
        for rule, msg, loc, severity in self.unused:  # lines no slave owns: reported once, on the first slave
            out[0].note(rule, msg, loc, severity)
        out[0].notes.sort(key=lambda f: (f.location.line or 0) if f.location else 0)
        return out


def _is_int(text: str) -> bool:
    try:
        parse_int(text.strip())
    except (InputError, ValueError):
        return False
    return True


def load(data: bytes, source: str) -> list[SlaveConfig]:
    if not detect(data):  # forced with --from-format ecmc on another file: say so, not an empty slave
        raise InputError("not an ecmc script: no Cfg.Ec… command and no epicsEnvSet", Location(source, 1))
    reader = _Reader(source)
    for n, raw in enumerate(decode_text(data, source).splitlines(), 1):
        reader.line(raw, n)
    return reader.result()


#: lines only an ecmc (iocsh) script has: ecmccfg's script includes and ecmc's configuration calls
_ECMC_LINE = re.compile(rb"^\s*(\$\{SCRIPTEXEC\}|\$\(SCRIPTEXEC\)|iocshLoad\b|ecmcConfig(OrDie)?\s+\"|"
                        rb"ecmcEpicsEnvSetCalc\b|require\s+ecmccfg\b)", re.MULTILINE)


def detect(data: bytes) -> bool:
    """An ecmc script: ``Cfg.Ec…`` calls, macros, or (a script that only includes others) ecmccfg's include
    lines; never YAML, whose keys these lines are not."""
    return (b"Cfg.Ec" in data[:1 << 20] or b"epicsEnvSet" in data[:1 << 16]
            or _ECMC_LINE.search(data[:1 << 16]) is not None)


def losses(c: SlaveConfig) -> list[str]:
    """What an ecmc script cannot carry: SoE commands, the transition of a write (ecmc sends every SDO in
    PRE-OP) and a PDO without entries (ecmc declares PDOs through their entries)."""
    out = soe_losses(c, "ecmc")
    other = [cmd for cmd in c.commands if cmd.transition != "PS"]
    if other:
        out.append(f"the transition of {len(other)} write(s) ({other[0].transition} {other[0].address}…): ecmc sends "
                   "every SDO in PRE-OP (PS)")
    empty = [p for p in (*c.rx_pdos, *c.tx_pdos) if not p.entries]
    if empty:
        out.append(f"PDO(s) {', '.join(f'0x{p.index:04X}' for p in empty)} without entries: ecmc declares a PDO "
                   "through its entries")
    return out


def nothing_left(c: SlaveConfig) -> bool:
    """No command, PDO entry or DC setting: the script would hold comments only."""
    return not c.commands and not any(p.entries for p in (*c.rx_pdos, *c.tx_pdos)) and not c.dc_assign_activate
