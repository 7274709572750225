"""A pysoem Python module: one ``config_func`` per slave that writes the startup SDOs.

pysoem calls ``slave.config_func(slave_pos)`` from ``master.config_map()`` while the slave is in PRE-OP,
i.e. in the PS transition, so every command is written there; commands of other transitions are kept and
marked with a comment. A PDO mapping the source gives only as PDO tables (ros2 ``rpdo``/``tpdo``, lcec
``syncManager``, ecmc entries, ENI ``ProcessData``) is programmed by the config function as IgH does it from
its tables: the assignment and mapping objects are read, and written only where they differ.
``install(master)`` sets ``manual_state_change`` so that ``config_map()`` does not request SAFE-OP before the
distributed clocks run; ``to_safe_op(master)`` starts them (``config_dc()`` once, then ``dc_sync`` per slave,
SOEM's order; the ``DC`` table holds the ``dc_sync`` arguments the ESI ``AssignActivate`` stands for) and then
requests SAFE-OP. Usage::

    import pysoem, startup_pysoem
    master = pysoem.Master(); master.open("eth0"); master.config_init()
    startup_pysoem.install(master)
    master.config_map()
    startup_pysoem.to_safe_op(master)

Export only.
"""

from __future__ import annotations

from ecattool.errors import TargetError
from ecattool.esi.model import Pdo
from ecattool.startup.config import SlaveConfig
from ecattool.startup.formats._common import dc_losses, one_line, soe_losses, sync_plan, unique_identifiers
from ecattool.startup.model import StartupCommand, is_pdo_programming
from ecattool.target.pysoem import dc_sync_args

NAME = "pysoem"
EXTENSIONS = (".py",)
DESCRIPTION = "pysoem Python module with one config_func per slave (sdo_write calls)"


def export(configs: list[SlaveConfig]) -> str:
    idents = unique_identifiers(configs)
    out = ['"""pysoem startup configuration written by ecattool.', "",
           "Call install(master) after master.config_init() and before master.config_map(), and",
           "to_safe_op(master) after master.config_map(): it starts the distributed clocks, then requests SAFE-OP.",
           '"""', "", "from __future__ import annotations", ""]
    if any(not cmd.expect_reply for c in configs for cmd in c.commands):
        out += ["import pysoem", ""]  # its WkcError: the write that gets no reply
    if any(cmd.one_shot for c in configs for cmd in c.commands):
        out[1:1] = ["", "Call once(master) first, after master.config_init(): the one-shot writes (EEPROM programming,",
                    "a reset), in order; config_map() re-runs the startup writes at every configuration."]
    tables = {id(c): _pdo_tables(c) for c in configs}
    if any(tables.values()):
        out += ["", *_PROGRAM_PDOS]
    out.append("")
    installs = []
    onces: list[tuple[int, str]] = []
    for i, (ident, c) in enumerate(zip(idents, configs)):
        pos = c.position if c.position is not None else i
        vendor = f"0x{c.identity.vendor_id:08X}" if c.identity else "None"
        product = f"0x{c.identity.product_code:08X}" if c.identity else "None"
        once = [cmd for cmd in c.commands if cmd.one_shot]
        startup = [cmd for cmd in c.commands if not cmd.one_shot]
        if once:
            out.append(f"def once_{ident}(slave) -> None:")
            out.append(f'    """{one_line(c.label).replace(chr(34), chr(39))}: {len(once)} one-shot write(s), in order."""')
            out += _write_lines(once)
            out += ["", ""]
            onces.append((pos, ident))
        out.append(f"def config_{ident}(slave) -> None:")
        out.append(f'    """{one_line(c.label).replace(chr(34), chr(39))}: {len(startup)} startup SDO write(s)."""')
        pdo_tables = tables[id(c)]
        if pdo_tables:
            out.append("    # the source gives the PDO mapping as tables only: program it (where the slave differs)")
            out.append(f"    program_pdos(slave, {pdo_tables!r})")
        elif not startup:
            out.append("    return None")
        if once:
            out.append(f"    # {len(once)} one-shot write(s) are in once_{ident}(), called once by once(master)")
        out += _write_lines(startup)
        for s in c.soe_commands:
            out.append(f"    # SoE IDN {s.idn} drive {s.drive_no} ({s.transition}) {s.data.hex()}: not sent by pysoem")
        out.append("")
        out.append("")
        installs.append((pos, ident, vendor, product))
    if onces:
        out.append("def once(master) -> None:")
        out.append('    """The one-shot writes of every slave, once, in PRE-OP (after config_init(), before install()).')
        out.append('    Never part of config_func: config_map() runs that at every configuration."""')
        for pos, ident in onces:
            out.append(f"    once_{ident}(master.slaves[{pos}])")
        out += ["", ""]
    out.append("#: (position, config function, vendor id, product code)")
    out.append("SLAVES = [")
    for pos, ident, vendor, product in installs:
        out.append(f"    ({pos}, config_{ident}, {vendor}, {product}),")
    out.append("]")
    out.append("")
    out.append("")
    out.append("def install(master) -> None:")
    out.append('    """Attach each config function to its slave, checking the identity where known."""')
    out.append("    for position, func, vendor_id, product_code in SLAVES:")
    out.append("        slave = master.slaves[position]")
    out.append("        if vendor_id is not None and (slave.man, slave.id) != (vendor_id, product_code):")
    out.append("            raise RuntimeError(")
    out.append('                f"slave {position}: found 0x{slave.man:08X}/0x{slave.id:08X}, "')
    out.append('                f"expected 0x{vendor_id:08X}/0x{product_code:08X}"')
    out.append("            )")
    out.append("        slave.config_func = lambda pos, _func=func: _func(master.slaves[pos])")
    out.append("    # config_map() must not request SAFE-OP: to_safe_op() does, once the distributed clocks run")
    out.append("    master.manual_state_change = 1")
    out += ["", ""] + _dc_lines(configs) + ["", ""] + _SAFE_OP
    return "\n".join(out) + "\n"


def _write_lines(commands: list[StartupCommand]) -> list[str]:
    """``slave.sdo_write`` per command, in order; a reset (no reply) inside ``try/except pysoem.WkcError``."""
    out = []
    for cmd in commands:
        note = one_line(cmd.comment)
        if cmd.transition != "PS" and not cmd.one_shot:
            note = f"{note} [transition {cmd.transition}; pysoem writes it in PRE-OP]".strip()
        ca = ", True" if cmd.complete_access else ""
        call = f"slave.sdo_write(0x{cmd.index:04X}, 0x{cmd.subindex:02X}, bytes.fromhex({cmd.data.hex()!r}){ca})"
        if cmd.expect_reply:
            out.append(f"    {call}" + (f"  # {note}" if note else ""))
        else:
            out.append("    try:")
            out.append(f"        {call}" + (f"  # {note}" if note else ""))
            out.append("    except pysoem.WkcError:  # the drive answers this write by resetting, not with a reply")
            out.append("        pass")
    return out


def _pdo_tables(c: SlaveConfig) -> list[tuple[int, list[tuple[int, list[int]]]]]:
    """``[(assignment object, [(PDO, [mapping entry words])])]`` for a slave whose startup list does not program
    its PDO tables itself; empty where it does (or there are no tables)."""
    if not _table_pdos(c):
        return []
    return [(0x1C10 + plan.number, [(p.index, [(e.index << 16) | (e.subindex << 8) | e.bit_len for e in p.entries])
                                    for p in plan.pdos])
            for plan in sync_plan(c) if not plan.mailbox and 2 <= plan.number <= 15]


def _table_pdos(c: SlaveConfig) -> list[Pdo]:
    """The PDOs the config function programs from the tables: none where the startup list programs them itself
    (or there are no tables), and none of a slave whose tables are not CoE mapping objects (SoE IDNs)."""
    if not c.has_pdo_info or any(is_pdo_programming(cmd.index) for cmd in c.commands):
        return []
    pdos = [*c.rx_pdos, *c.tx_pdos]
    return [] if any(not is_pdo_programming(p.index) for p in pdos) else pdos


_PROGRAM_PDOS = [
    "def _entries(slave, index):",
    '    """The mapping words (or PDO indices) the slave holds in ``index`` (sub-index 0 = count)."""',
    "    count = slave.sdo_read(index, 0)[0]",
    "    width = 2 if index < 0x1600 else 4",
    '    return [int.from_bytes(slave.sdo_read(index, k)[:width], "little") for k in range(1, count + 1)]',
    "",
    "",
    "def program_pdos(slave, tables) -> None:",
    '    """Assign and map the PDOs of ``tables`` as IgH does from its PDO tables: only what differs is written',
    "    (a fixed PDO that already holds the mapping is left alone; one that differs aborts with its SdoError).",
    '    """',
    "    for assign, pdos in tables:",
    "        wanted = [index for index, _ in pdos]",
    "        differs = [(index, words) for index, words in pdos if _entries(slave, index) != words]",
    "        if _entries(slave, assign) == wanted and not differs:",
    "            continue",
    "        slave.sdo_write(assign, 0, bytes(1))",
    "        for index, words in differs:",
    "            slave.sdo_write(index, 0, bytes(1))",
    "            for k, word in enumerate(words, 1):",
    '                slave.sdo_write(index, k, word.to_bytes(4, "little"))',
    "            slave.sdo_write(index, 0, bytes([len(words)]))",
    "        for k, index in enumerate(wanted, 1):",
    '            slave.sdo_write(assign, k, index.to_bytes(2, "little"))',
    "        slave.sdo_write(assign, 0, bytes([len(wanted)]))",
    "",
]

_SAFE_OP = [
    "#: pysoem.SAFEOP_STATE (SOEM's EC_STATE_SAFE_OP)",
    "SAFEOP_STATE = 4",
    "",
    "",
    "def to_safe_op(master, sync0_cycle_ns=None, timeout_us=2_000_000) -> None:",
    '    """After master.config_map(): start the distributed clocks (configure_dc), then request SAFE-OP and wait.',
    "",
    "    install() set manual_state_change, so config_map() did not request SAFE-OP before SYNC0 ran (a drive",
    "    that needs SYNC0 refuses SAFE-OP without it).",
    '    """',
    "    configure_dc(master, sync0_cycle_ns)",
    "    for slave in master.slaves:",
    "        slave.state = SAFEOP_STATE",
    "        slave.write_state()",
    "    for position, slave in enumerate(master.slaves):",
    "        if slave.state_check(SAFEOP_STATE, timeout_us) != SAFEOP_STATE:",
    '            raise RuntimeError(f"slave {position} did not reach SAFE-OP (AL status code 0x{slave.al_status:04X})")',
]


def _dc_lines(configs: list[SlaveConfig]) -> list[str]:
    """The DC table and ``configure_dc``: pysoem's ``dc_sync`` arguments per slave that activates DC."""
    out = ["#: (position, dc_sync arguments or None where pysoem cannot set the AssignActivate, comment) per slave",
           "#: that uses distributed clocks; a SYNC0 cycle of None is the bus cycle given to configure_dc()",
           "DC = ["]
    for i, c in enumerate(configs):
        if not c.dc_assign_activate:
            continue
        pos = c.position if c.position is not None else i
        what = f"{one_line(c.label)}: AssignActivate 0x{c.dc_assign_activate:04X}"
        try:
            args = dc_sync_args(c.dc_assign_activate, c.dc_cycle_ns or 0, c.dc_shift_ns or 0)
            if len(args) == 4:  # SYNC0 + SYNC1: the SYNC1 cycle of the source (0: SYNC1 fires with SYNC0)
                args = (*args[:3], c.dc_sync1_cycle_ns or 0)
        except TargetError:
            out.append(f"    ({pos}, None, {what!r}),")
            continue
        if c.dc_cycle_ns is None and args[0]:  # the source gives no SYNC0 cycle (a ros2 file): configure_dc() must
            args = (args[0], None, *args[2:])
        out.append(f"    ({pos}, {args!r}, {what!r}),")
    out += ["]", "", "",
            "def configure_dc(master, sync0_cycle_ns=None) -> None:",
            '    """Start SYNC0 on every DC slave: after master.config_map(), before SAFE-OP.',
            "",
            "    sync0_cycle_ns is the bus cycle for slaves whose configuration gives no SYNC0 cycle.",
            '    """',
            "    if not DC:",
            "        return None",
            "    for position, args, what in DC:",
            "        if args is None:",
            '            raise RuntimeError(f"slave {position} ({what}): pysoem can only activate SYNC0 (0x0300) or "',
            '                               "SYNC0 + SYNC1 (0x0700)")',
            "        if args[0] and args[1] is None and sync0_cycle_ns is None:",
            '            raise RuntimeError(f"slave {position} ({what}): give the SYNC0 cycle: '
            'configure_dc(master, sync0_cycle_ns=...)")',
            "    if not master.config_dc():",
            '        raise RuntimeError("config_dc() found no slave with distributed clocks")',
            "    for position, args, what in DC:",
            "        if args[0] and args[1] is None:",
            "            args = (args[0], sync0_cycle_ns, *args[2:])",
            "        master.slaves[position].dc_sync(*args)"]
    return out


def losses(c: SlaveConfig) -> list[str]:
    """What the pysoem module cannot carry: SoE commands, a SYNC1 shift, an AssignActivate other than SYNC0 or
    SYNC0+SYNC1, and PDO tables of SoE IDNs (pysoem would write them into the CoE objects 1C12h/1C13h)."""
    out = soe_losses(c, "pysoem") + dc_losses(c, "pysoem", sync1_shift=False)
    if c.dc_assign_activate:
        try:
            dc_sync_args(c.dc_assign_activate, 0)
        except TargetError as exc:
            out.append(str(exc.message))
    programmed = any(is_pdo_programming(cmd.index) for cmd in c.commands)
    idns = [] if programmed else [p for p in (*c.rx_pdos, *c.tx_pdos) if not is_pdo_programming(p.index)]
    if idns:
        out.append(f"PDOs {', '.join(f'0x{p.index:04X}' for p in idns)} are not CoE mapping objects (1600h-17FFh, "
                   "1A00h-1BFFh) but SoE IDNs (AT/MDT telegrams), mapped by SoE commands: not written into "
                   f"1C12h/1C13h ({idns[0].location or c.source})")
    return out
