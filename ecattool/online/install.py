"""A project's startup list inside a master program that imports ecattool instead of generating code.

``install_pysoem(project, master)``, after ``master.config_init()`` and before ``master.config_map()``: checks each
slave's identity against the project (vendor and product code, and the revision where the project asks for an
exact one) and attaches a ``config_func`` that writes the slave's startup SDOs when SOEM maps the slave (in
PRE-OP), as the module ``startup export --format pysoem`` writes does. ``install_kickcat(project, bus)``, after
``bus.init()`` and before ``bus.create_mapping()``: KickCAT has no per-slave hook, so the same identity check
(through 1018h) and the writes happen at once, through each slave's mailbox.

``project`` is a project file (linted; errors refuse it) or the list of ``SlaveConfig`` it gives.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from types import ModuleType
from typing import Any

from ecattool.errors import TargetError
from ecattool.esi.model import Identity
from ecattool.startup.config import SlaveConfig


def _configs(project: str | Path | Sequence[SlaveConfig]) -> list[SlaveConfig]:
    if isinstance(project, (str, Path)):
        from ecattool.project.export import slave_configs

        return slave_configs(project)
    return list(project)


def check_identity(cfg: SlaveConfig, position: int, found: Identity, exact_revision: bool = False) -> None:
    want = cfg.identity
    if want is None:
        return
    if (found.vendor_id, found.product_code) != (want.vendor_id, want.product_code) or (
            exact_revision and want.revision and found.revision != want.revision):
        raise TargetError(f"slave {position} ({cfg.name or 'unnamed'}): found vendor 0x{found.vendor_id:08X} product "
                          f"0x{found.product_code:08X} revision 0x{found.revision:08X}, the project expects vendor "
                          f"0x{want.vendor_id:08X} product 0x{want.product_code:08X}"
                          + (f" revision 0x{want.revision:08X}" if exact_revision else ""))


def _writer(cfg: SlaveConfig, wkc_error: type[BaseException]) -> Callable[[Any], None]:
    def write(slave: Any) -> None:
        for cmd in cfg.commands:
            try:
                slave.sdo_write(cmd.index, cmd.subindex, bytes(cmd.data), cmd.complete_access)
            except wkc_error:
                if cmd.expect_reply:
                    raise  # only a write the drive answers by resetting may go without a reply
    return write


def install_pysoem(project: str | Path | Sequence[SlaveConfig], master: Any, *, exact_revision: bool = False,
                   pysoem_module: ModuleType | None = None) -> list[int]:
    """Attach the startup list of each project drive to its pysoem slave (identity checked first, every slave
    before any is touched). Returns the positions configured. Sets ``manual_state_change`` so that
    ``config_map()`` leaves the state changes to the program."""
    if pysoem_module is None:
        from ecattool.target.pysoem import _import_pysoem

        pysoem_module = _import_pysoem()
    wkc_error = pysoem_module.WkcError
    configs = _configs(project)
    slaves = master.slaves
    placed = []
    for i, cfg in enumerate(configs):
        pos = cfg.position if cfg.position is not None else i
        if not 0 <= pos < len(slaves):
            raise TargetError(f"the project places {cfg.name or 'a drive'} at position {pos}; the bus has {len(slaves)}")
        s = slaves[pos]
        check_identity(cfg, pos, Identity(int(s.man), int(s.id), int(s.rev)), exact_revision)
        placed.append((pos, cfg))
    for pos, cfg in placed:
        write = _writer(cfg, wkc_error)
        slaves[pos].config_func = lambda p, _w=write: _w(master.slaves[p])
    master.manual_state_change = 1
    return [p for p, _ in placed]


def install_kickcat(project: str | Path | Sequence[SlaveConfig], bus: Any, *, exact_revision: bool = False,
                    kickcat_module: ModuleType | None = None) -> list[int]:
    """Write each project drive's startup list to its KickCAT slave now (identity through 1018h checked first for
    every slave). Call between ``bus.init()`` and ``bus.create_mapping()``."""
    from ecattool.online.kickcat_bus import KickcatLiveSlave, _import

    kc = kickcat_module or _import()
    configs = _configs(project)
    slaves = bus.slaves()
    live = []
    for i, cfg in enumerate(configs):
        pos = cfg.position if cfg.position is not None else i
        if not 0 <= pos < len(slaves):
            raise TargetError(f"the project places {cfg.name or 'a drive'} at position {pos}; the bus has {len(slaves)}")
        s = KickcatLiveSlave(bus, slaves[pos], pos, kc)
        check_identity(cfg, pos, s.identity(), exact_revision)
        live.append((s, cfg))
    for s, cfg in live:
        for cmd in cfg.commands:
            s.sdo_download(cmd.index, cmd.subindex, cmd.data, cmd.complete_access, cmd.expect_reply)
    return [s.position for s, _ in live]
