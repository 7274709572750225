"""ecmc (EPICS motion control, PSI/ESS) startup scripts: ``Cfg.EcAddSdo`` lines and what ecmccfg writes.

Writing: one ``ecmcConfigOrDie "Cfg.EcAddSdo(<slave>,<index>,<sub>,<value>,<size>)"`` per command of 1, 2
or 4 bytes (ecmc's SDO value is a 32-bit integer); longer data and complete-access writes use
``Cfg.EcAddSdoBuffer`` / ``Cfg.EcAddSdoComplete`` with the data as hex bytes. The slave is its bus position,
or the ``${ECMC_EC_SLAVE_NUM}`` macro when the position of a single slave is unknown (as ecmccfg hardware
scripts use it; several slaves of unknown position get their list index).
PDO information becomes ``Cfg.EcAddEntryComplete`` lines.

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
from ecattool.od.numbers import parse_int
from ecattool.startup.config import SlaveConfig
from ecattool.startup.formats._common import decode_text, encode_sized, one_line, parse_hex, unsigned_type
from ecattool.startup.model import StartupCommand, StartupList

NAME = "ecmc"
EXTENSIONS = (".cmd", ".script")
DESCRIPTION = "ecmc/EPICS startup script (Cfg.EcAddSdo lines; reads EcWriteSdo and ecmccfg macros too)"

SLAVE_MACRO = "${ECMC_EC_SLAVE_NUM}"
_CALL = re.compile(r"Cfg\.(Ec\w+)\s*\((.*)\)")
_ENVSET = re.compile(r'^\s*epicsEnvSet\s*\(\s*"?([A-Za-z_]\w*)"?\s*,?\s*"([^"]*)"\s*\)')
_MACRO = re.compile(r"\$[({]([A-Za-z_]\w*)(?:=([^)}]*))?[)}]")
_SDO_WRITES = {"EcAddSdo", "EcWriteSdo"}
_BUFFER_WRITES = {"EcAddSdoBuffer", "EcAddSdoComplete", "EcWriteSdoComplete"}
_REPORTED = {"EcReadSdo", "EcVerifySdo", "EcAddSdoAsync"}


def _slave_ref(c: SlaveConfig, i: int, many: bool) -> str:
    """The bus position; for one slave of unknown position the ecmccfg macro, for several their list index."""
    if c.position is not None:
        return str(c.position)
    return str(i) if many else SLAVE_MACRO


def _command_line(slave: str, cmd: StartupCommand) -> str:
    """The ecmc call; ``ecmcConfig`` instead of ``ecmcConfigOrDie`` for writes the drive answers by resetting."""
    line = _call(slave, cmd)
    return line if cmd.expect_reply else line.replace("ecmcConfigOrDie ", "ecmcConfig ", 1)


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
        if c.identity is not None:
            v, p = "${ECMC_EC_VENDOR_ID}", "${ECMC_EC_PRODUCT_ID}"
            for direction, sm, pdos in (("1", 2, c.rx_pdos), ("2", 3, c.tx_pdos)):
                for pdo in pdos:
                    for k, e in enumerate(pdo.entries):
                        name = re.sub(r"\W+", "_", e.name).strip("_")[:40] or f"entry_{pdo.index:04x}_{k}"
                        out.append(f'ecmcConfigOrDie "Cfg.EcAddEntryComplete({slave},{v},{p},{direction},{sm},'
                                   f'0x{pdo.index:04x},0x{e.index:04x},0x{e.subindex:x},{e.bit_len},{name})"')
        if c.dc_assign_activate:
            # ecmc's Cfg.EcSlaveConfigDC(slave, assign_activate, sync0_cycle, sync0_shift, sync1_cycle, sync1_shift)
            out.append(f'ecmcConfigOrDie "Cfg.EcSlaveConfigDC({slave},0x{c.dc_assign_activate:X},'
                       f'{c.dc_cycle_ns or 0},{c.dc_shift_ns or 0},0,0)"')
        for s in c.soe_commands:
            out.append(f"#- SoE IDN {s.idn} drive {s.drive_no} ({s.transition}) {s.data.hex()}: "
                       "not representable in ecmc")
    return "\n".join(out) + "\n"


# --- reading -----------------------------------------------------------------------------------------

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

    def expand(self, text: str) -> str:
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
                expect_reply=not self.tolerant, source=loc))
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
                data, comment=self.pending_comment, complete_access=complete, source=loc))
        elif func == "EcAddEntryComplete":
            self.entry(args, loc)
        elif func == "EcSlaveConfigDC":
            if len(args) != 6:
                raise InputError("Cfg.EcSlaveConfigDC takes (slave,assign_activate,sync0_cycle,sync0_shift,"
                                 f"sync1_cycle,sync1_shift); got {len(args)} arguments", loc)
            cfg = self.slave(args[0], loc)
            cfg.dc_assign_activate = self.number(args[1], loc, "assign_activate")
            cfg.dc_cycle_ns = self.number(args[2], loc, "SYNC0 cycle")
            cfg.dc_shift_ns = self.number(args[3], loc, "SYNC0 shift")
        elif func in _REPORTED:
            reader = self.slave(args[0], loc) if args else None
            if reader is not None:
                reader.note("startup.ecmc.read", f"Cfg.{func} reads or verifies; not a startup write", loc,
                            Severity.INFO)
        self.pending_comment = ""

    def entry(self, args: list[str], loc: Location) -> None:
        if len(args) < 10:
            raise InputError("Cfg.EcAddEntryComplete takes "
                             "(slave,vendor,product,dir,sm,pdo,index,sub,bits,[signed,]name)", loc)
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
        pdo.entries.append(PdoEntry(self.number(args[6], loc, "entry index"), self.number(args[7], loc, "entry sub"),
                                    self.number(args[8], loc, "bit length"), name=args[-1], location=loc))

    def line(self, raw: str, n: int) -> None:
        loc = Location(self.source, n)
        s = raw.strip()
        if not s:
            return
        if s.startswith("#"):
            self.comment(s)
            return
        m = _ENVSET.match(s)
        if m:
            self.env[m.group(1)] = self.expand(m.group(2))
            return
        m = _CALL.search(s)
        if m:
            self.tolerant = not s.startswith("ecmcConfigOrDie")
            self.call(m.group(1), _split_args(self.expand(m.group(2))), loc)
            return
        if "SCRIPTEXEC" in s or s.startswith("<"):
            target = self.slaves.get(SLAVE_MACRO)
            msg = f"included script not followed: {self.expand(s)}"
            if target is not None:
                target.note("startup.ecmc.include", msg, loc, Severity.INFO)
            else:
                self.env.setdefault("__includes__", "")
                self.env["__includes__"] += f"{n}:{msg}\n"

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
            for entry in self.env.get("__includes__", "").splitlines():
                n, _, msg = entry.partition(":")
                cfg.note("startup.ecmc.include", msg, Location(self.source, int(n)), Severity.INFO)
            if not cfg.name:
                cfg.name = self.env.get("ECMC_EC_HWTYPE") or Path(self.source).stem
            cfg.startup.name = cfg.name
        return list(self.slaves.values())


def load(data: bytes, source: str) -> list[SlaveConfig]:
    if not detect(data):  # forced with --from-format ecmc on another file: say so, not an empty slave
        raise InputError("not an ecmc script: no Cfg.Ec… command and no epicsEnvSet", Location(source, 1))
    reader = _Reader(source)
    for n, raw in enumerate(decode_text(data, source).splitlines(), 1):
        reader.line(raw, n)
    return reader.result()


def detect(data: bytes) -> bool:
    return b"Cfg.Ec" in data[:1 << 20] or b"epicsEnvSet" in data[:1 << 16]
