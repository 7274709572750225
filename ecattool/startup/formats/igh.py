"""IgH EtherCAT master (etherlab) C source: ``ecrt_slave_config_sdo*`` calls and the PDO tables.

Per slave: ``ec_pdo_entry_info_t``, ``ec_pdo_info_t`` and ``ec_sync_info_t`` tables from the assigned PDOs
(SM0/SM1 mailboxes, SM2 outputs, SM3 inputs), and a function ``int <name>_configure(ec_master_t *master)``
that creates the slave configuration, registers the PDOs, adds every startup SDO with
``ecrt_slave_config_sdo8/16/32`` by size (``ecrt_slave_config_sdo`` for other sizes,
``ecrt_slave_config_complete_sdo`` for complete access), SoE IDNs with ``ecrt_slave_config_idn``, and sets
DC. IgH sends all SDO configurations in PRE-OP before SAFE-OP; a command of another transition gets a
comment saying so. Export only.
"""

from __future__ import annotations

from ecattool.errors import EncodeError
from ecattool.startup.config import SlaveConfig, SoeCommand
from ecattool.startup.formats._common import require_identity, sync_plan, unique_identifiers
from ecattool.startup.model import StartupCommand, is_pdo_programming

NAME = "igh"
EXTENSIONS = (".c",)
DESCRIPTION = "IgH EtherCAT master C (ecrt_slave_config_sdo8/16/32, ec_pdo_entry_info_t/ec_pdo_info_t/ec_sync_info_t)"

_SIZED = {1: "ecrt_slave_config_sdo8", 2: "ecrt_slave_config_sdo16", 4: "ecrt_slave_config_sdo32"}


def _c_comment(text: str) -> str:
    t = " ".join(text.split()).replace("*/", "* /")
    return f" /* {t} */" if t else ""


def _c_bytes(data: bytes) -> str:
    return ", ".join(f"0x{b:02x}" for b in data)


def _sdo_call(ident: str, n: int, cmd: StartupCommand, body: list[str]) -> None:
    where = f"0x{cmd.index:04X}:{cmd.subindex:02X}"
    note = cmd.comment
    if cmd.transition != "PS":
        note = f"{note} (transition {cmd.transition}; IgH sends every SDO in PRE-OP)".strip()
    if cmd.complete_access:
        if cmd.subindex != 0:
            raise EncodeError(f"{where}: IgH complete-access SDO configuration always starts at sub-index 0")
        body.append(f"    static const uint8_t {ident}_sdo{n}[] = {{{_c_bytes(cmd.data)}}};")
        call = f"ecrt_slave_config_complete_sdo(sc, 0x{cmd.index:04x}, {ident}_sdo{n}, sizeof({ident}_sdo{n}))"
    elif len(cmd.data) in _SIZED:
        width = 2 * len(cmd.data)
        call = f"{_SIZED[len(cmd.data)]}(sc, 0x{cmd.index:04x}, 0x{cmd.subindex:02x}, 0x{cmd.int_value:0{width}x}U)"
    else:
        if not cmd.data:
            raise EncodeError(f"{where}: an SDO download needs at least one byte")
        body.append(f"    static const uint8_t {ident}_sdo{n}[] = {{{_c_bytes(cmd.data)}}};")
        call = (f"ecrt_slave_config_sdo(sc, 0x{cmd.index:04x}, 0x{cmd.subindex:02x}, {ident}_sdo{n}, "
                f"sizeof({ident}_sdo{n}))")
    body.append(f"    if ({call}) return -1;{_c_comment(note)}")


#: IgH applies IDN configurations when entering these states
_IDN_STATE = {"PS": "EC_AL_STATE_PREOP", "SO": "EC_AL_STATE_SAFEOP"}


def _idn_call(ident: str, n: int, s: SoeCommand, body: list[str]) -> None:
    state = _IDN_STATE.get(s.transition)
    if state is None or not s.data:
        body.append(f"    /* SoE IDN {s.idn} drive {s.drive_no} ({s.transition}) {s.data.hex()}: IgH configures IDNs "
                    f"only in PRE-OP/SAFE-OP; not written */")
        return
    body.append(f"    static const uint8_t {ident}_idn{n}[] = {{{_c_bytes(s.data)}}};")
    body.append(f"    if (ecrt_slave_config_idn(sc, {s.drive_no}, {s.idn}, {state}, {ident}_idn{n}, "
                f"sizeof({ident}_idn{n}))) return -1;{_c_comment(s.comment)}")


_WD = {True: "EC_WD_ENABLE", False: "EC_WD_DISABLE", None: "EC_WD_DEFAULT"}


def _tables(ident: str, c: SlaveConfig) -> list[str]:
    plans = sync_plan(c)
    pdos = [p for plan in plans for p in plan.pdos]
    out = [f"static ec_pdo_entry_info_t {ident}_pdo_entries[] = {{"]
    offsets: list[tuple[int, int, int, str]] = []
    k = 0
    for p in pdos:
        offsets.append((p.index, len(p.entries), k, p.name))
        for e in p.entries:
            out.append(f"    {{0x{e.index:04x}, 0x{e.subindex:02x}, {e.bit_len}}},{_c_comment(e.name)}")
            k += 1
    if k == 0:
        out.append("    {0x0000, 0x00, 0}, /* no entries */")
    out.append("};")
    out.append(f"static ec_pdo_info_t {ident}_pdos[] = {{")
    for index, count, start, name in offsets:
        out.append(f"    {{0x{index:04x}, {count}, {ident}_pdo_entries + {start}}},{_c_comment(name)}")
    if not offsets:
        out.append("    {0x0000, 0, NULL},")
    out.append("};")
    # sync manager numbers and watchdogs as the source gives them (EC_WD_DEFAULT: the slave's own setting)
    out.append(f"static ec_sync_info_t {ident}_syncs[] = {{")
    first = 0
    for plan in plans:
        d = "EC_DIR_OUTPUT" if plan.output else "EC_DIR_INPUT"
        table = f"{ident}_pdos + {first}" if plan.pdos else "NULL"
        wd = "EC_WD_DISABLE" if plan.mailbox else _WD[plan.watchdog]
        out.append(f"    {{{plan.number}, {d}, {len(plan.pdos)}, {table}, {wd}}},")
        first += len(plan.pdos)
    out.append("    {0xff}")
    out.append("};")
    return out


def _once(ident: str, pos: int, once: list[StartupCommand]) -> list[str]:
    """One-shot writes: not startup configuration (IgH re-sends that at every reconfiguration) but a function
    the application calls once, with ``ecrt_master_sdo_download``, in the order of the source (EEPROM writes,
    then the reset). The data arrays are not ``const``: IgH 1.5 headers before 2014 take ``uint8_t *``."""
    out = [f"/* One-shot writes of {ident}: call once, before ecrt_master_activate(), never at reconfiguration;",
           " * they run in this order. A reset has no SDO reply (the drive resets): its error return is expected.",
           " * Returns -1 at the first other write that fails. */",
           f"int {ident}_once(ec_master_t *master)", "{", "    uint32_t abort_code = 0;"]
    for n, cmd in enumerate(once):
        out.append(f"    static uint8_t {ident}_once{n}[] = {{{_c_bytes(cmd.data)}}};")
        call = (f"ecrt_master_sdo_download(master, {pos}, 0x{cmd.index:04x}, 0x{cmd.subindex:02x}, "
                f"{ident}_once{n}, sizeof({ident}_once{n}), &abort_code)")
        if cmd.kind == "reset":
            out.append(f"    (void){call};{_c_comment(cmd.comment)}")
        else:
            out.append(f"    if ({call}) return -1;{_c_comment(cmd.comment)}")
    out += ["    return 0;", "}", ""]
    return out


def export(configs: list[SlaveConfig]) -> str:
    out = ["/* IgH EtherCAT master slave configuration, written by ecattool. */", "#include <stddef.h>",
           "#include <stdint.h>", "#include <ecrt.h>", ""]
    for i, (ident, c) in enumerate(zip(unique_identifiers(configs), configs)):
        pos = c.position if c.position is not None else i
        ident_ = require_identity(c, "IgH's ecrt_master_slave_config() (vendor 0 matches no slave)")
        vendor, product = ident_.vendor_id, ident_.product_code
        out.append(f"/* {c.label}: position {pos}, vendor 0x{vendor:08x}, product 0x{product:08x} */")
        out.append(f"#define {ident.upper()}_POS 0, {pos}")
        out.append(f"#define {ident.upper()}_ID 0x{vendor:08x}, 0x{product:08x}")
        if c.has_pdo_info:
            out += _tables(ident, c)
        out.append("")
        once = [cmd for cmd in c.commands if cmd.one_shot]
        if once:
            out += _once(ident, pos, once)
        out.append(f"int {ident}_configure(ec_master_t *master)")
        out.append("{")
        out.append(f"    ec_slave_config_t *sc = ecrt_master_slave_config(master, {ident.upper()}_POS, "
                   f"{ident.upper()}_ID);")
        out.append("    if (!sc) return -1;")
        body: list[str] = []
        commands = [cmd for cmd in c.commands if not cmd.one_shot]
        if once:
            body.append(f"    /* {len(once)} one-shot write(s) are in {ident}_once(), not in the startup configuration */")
        if c.has_pdo_info:
            body.append(f"    if (ecrt_slave_config_pdos(sc, EC_END, {ident}_syncs)) return -1;")
            # IgH writes the assignment (1C12h/1C13h) and the mapping objects itself from the tables above;
            # the same writes as SDOs would program the mapping twice (and abort on fixed PDOs)
            pdo_writes = [cmd for cmd in commands if is_pdo_programming(cmd.index)]
            if pdo_writes:
                body.append(f"    /* {len(pdo_writes)} PDO assignment/mapping writes of the startup list are done by "
                            "ecrt_slave_config_pdos() */")
                commands = [cmd for cmd in commands if not is_pdo_programming(cmd.index)]
        for n, cmd in enumerate(commands):
            _sdo_call(ident, n, cmd, body)
        if c.dc_assign_activate:
            if c.dc_cycle_ns:
                cycle = f"{c.dc_cycle_ns}U"
            else:  # the source has no SYNC0 cycle (a ros2 file): the program must give its own, it cannot be 0
                cycle = "SYNC0_CYCLE_NS"
                if "#ifndef SYNC0_CYCLE_NS" not in out:
                    out[5:5] = ["/* SYNC0 cycle of the slaves whose configuration gives none: your task period */",
                                "#ifndef SYNC0_CYCLE_NS", '#error "define SYNC0_CYCLE_NS (the SYNC0 cycle in ns, the '
                                'application\'s task period): the source configuration has none"', "#endif", ""]
            body.append(f"    ecrt_slave_config_dc(sc, 0x{c.dc_assign_activate:04x}, {cycle}, "
                        f"{c.dc_shift_ns or 0}, {c.dc_sync1_cycle_ns or 0}U, {c.dc_sync1_shift_ns or 0});")
        for n, s in enumerate(c.soe_commands):
            _idn_call(ident, n, s, body)
        out += body
        out.append("    return 0;")
        out.append("}")
        out.append("")
    return "\n".join(out)
