"""A pysoem Python module: one ``config_func`` per slave that writes the startup SDOs.

pysoem calls ``slave.config_func(slave_pos)`` from ``master.config_map()`` while the slave is in PRE-OP,
i.e. in the PS transition, so every command is written there; commands of other transitions are kept and
marked with a comment. Usage::

    import pysoem, startup_pysoem
    master = pysoem.Master(); master.open("eth0"); master.config_init()
    startup_pysoem.install(master)
    master.config_map()

Export only.
"""

from __future__ import annotations

from ecattool.startup.config import SlaveConfig
from ecattool.startup.formats._common import one_line, unique_identifiers

NAME = "pysoem"
EXTENSIONS = (".py",)
DESCRIPTION = "pysoem Python module with one config_func per slave (sdo_write calls)"


def export(configs: list[SlaveConfig]) -> str:
    idents = unique_identifiers(configs)
    out = ['"""pysoem startup configuration written by ecattool.', "",
           "Call install(master) after master.config_init() and before master.config_map().", '"""', "",
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
    return "\n".join(out) + "\n"
