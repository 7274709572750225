"""A pysoem Python module: one ``config_func`` per slave that writes the startup SDOs.

pysoem calls ``slave.config_func(slave_pos)`` from ``master.config_map()`` while the slave is in PRE-OP,
i.e. in the PS transition, so every command is written there; commands of other transitions are kept and
marked with a comment. Distributed clocks go to ``configure_dc(master)``, to be called after ``config_map()``
(SOEM's order: ``config_dc()`` once, then ``dc_sync`` per slave, before SAFE-OP); the ``DC`` table holds the
``dc_sync`` arguments the ESI ``AssignActivate`` stands for. Usage::

    import pysoem, startup_pysoem
    master = pysoem.Master(); master.open("eth0"); master.config_init()
    startup_pysoem.install(master)
    master.config_map()
    startup_pysoem.configure_dc(master)

Export only.
"""

from __future__ import annotations

from ecattool.errors import TargetError
from ecattool.startup.config import SlaveConfig
from ecattool.startup.formats._common import one_line, unique_identifiers
from ecattool.target.pysoem import dc_sync_args

NAME = "pysoem"
EXTENSIONS = (".py",)
DESCRIPTION = "pysoem Python module with one config_func per slave (sdo_write calls)"


def export(configs: list[SlaveConfig]) -> str:
    idents = unique_identifiers(configs)
    out = ['"""pysoem startup configuration written by ecattool.', "",
           "Call install(master) after master.config_init() and before master.config_map(),",
           "and configure_dc(master) after master.config_map() and before requesting SAFE-OP.", '"""', "",
           "from __future__ import annotations", ""]
    if any(not cmd.expect_reply for c in configs for cmd in c.commands):
        out += ["import pysoem", ""]  # its WkcError: the write that gets no reply
    out.append("")
    installs = []
    for i, (ident, c) in enumerate(zip(idents, configs)):
        pos = c.position if c.position is not None else i
        vendor = f"0x{c.identity.vendor_id:08X}" if c.identity else "None"
        product = f"0x{c.identity.product_code:08X}" if c.identity else "None"
        out.append(f"def config_{ident}(slave) -> None:")
        out.append(f'    """{one_line(c.label).replace(chr(34), chr(39))}: {len(c.commands)} startup SDO write(s)."""')
        if not c.commands:
            out.append("    return None")
        for cmd in c.commands:
            note = one_line(cmd.comment)
            if cmd.transition != "PS":
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
        for s in c.soe_commands:
            out.append(f"    # SoE IDN {s.idn} drive {s.drive_no} ({s.transition}) {s.data.hex()}: not sent by pysoem")
        out.append("")
        out.append("")
        installs.append((pos, ident, vendor, product))
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
    out += ["", ""] + _dc_lines(configs)
    return "\n".join(out) + "\n"


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
