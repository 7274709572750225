"""Slave configurations attached to a master inside a master program that imports ecattool instead of generating
code (``Machine.install(master)`` gives them from a project).

pysoem (:func:`install_pysoem`), after ``master.config_init()`` and before ``master.config_map()``: checks each
slave's identity against its configuration (vendor and product code, and the revision with ``exact_revision``)
and attaches a ``config_func`` that writes the slave's startup SDOs when SOEM maps the slave (in PRE-OP), as the
module ``startup export --format pysoem`` writes does. KickCAT (:func:`install_kickcat`), after ``bus.init()`` and
before ``bus.create_mapping()``: KickCAT's binding has no per-slave hook, so the same identity check (through
1018h) and the writes happen at once, through each slave's mailbox. :func:`install` tells the two apart by the
master's type.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from types import ModuleType
from typing import Literal, Protocol, cast

from ecattool.errors import TargetError
from ecattool.esi.model import Identity
from ecattool.startup.config import SlaveConfig

#: the masters :func:`install` attaches to
MasterKind = Literal["pysoem", "kickcat"]


class PysoemSlave(Protocol):
    """What :func:`install_pysoem` uses of a ``pysoem`` slave: its SII identity, the hook SOEM calls with the
    0-based position when it maps the slave, and the SDO write."""

    man: int
    id: int
    rev: int
    config_func: Callable[[int], None] | None

    def sdo_write(self, index: int, subindex: int, data: bytes, ca: bool = False) -> None: ...


class PysoemMaster(Protocol):
    """What :func:`install_pysoem` uses of a ``pysoem.Master`` after ``config_init()``."""

    manual_state_change: int

    @property
    def slaves(self) -> Sequence[PysoemSlave]: ...


class KickcatBus(Protocol):
    """What :func:`install_kickcat` uses of a ``kickcat.Bus`` after ``init()`` (the slave access itself is
    :class:`ecattool.target.kickcat.KickcatSlave`'s)."""

    def slaves(self) -> Sequence[object]: ...


def check_identity(cfg: SlaveConfig, position: int, found: Identity, exact_revision: bool = False) -> None:
    """A TargetError when the slave at ``position`` is not the device ``cfg`` was made for."""
    want = cfg.identity
    if want is None:
        return
    if (found.vendor_id, found.product_code) != (want.vendor_id, want.product_code) or (
            exact_revision and want.revision and found.revision != want.revision):
        raise TargetError(f"slave {position} ({cfg.name or 'unnamed'}): found vendor 0x{found.vendor_id:08X} product "
                          f"0x{found.product_code:08X} revision 0x{found.revision:08X}, the project expects vendor "
                          f"0x{want.vendor_id:08X} product 0x{want.product_code:08X}"
                          + (f" revision 0x{want.revision:08X}" if exact_revision else ""))


def _placed(configs: Sequence[SlaveConfig], count: int) -> list[tuple[int, SlaveConfig]]:
    """(bus position, configuration) of each configuration (its position, else its place in the list)."""
    out = []
    for i, cfg in enumerate(configs):
        pos = cfg.position if cfg.position is not None else i
        if not 0 <= pos < count:
            raise TargetError(f"the project places {cfg.name or 'a drive'} at position {pos}; the bus has {count}")
        out.append((pos, cfg))
    return out


def install_pysoem(configs: Sequence[SlaveConfig], master: PysoemMaster, *, exact_revision: bool = False,
                   pysoem_module: ModuleType | None = None) -> list[int]:
    """Attach each configuration's startup list to its pysoem slave (identity checked first, every slave before
    any is touched; :func:`ecattool.target.pysoem.attach_startup`). Returns the positions configured. Sets
    ``manual_state_change`` so that ``config_map()`` leaves the state changes to the program."""
    from ecattool.target.pysoem import attach_startup

    placed = _placed(configs, len(master.slaves))
    attach_startup(master, [(pos, cfg.commands) for pos, cfg in placed],
                   lambda i, found: check_identity(placed[i][1], placed[i][0], found, exact_revision), pysoem_module)
    return [p for p, _ in placed]


def install_kickcat(configs: Sequence[SlaveConfig], bus: KickcatBus, *, exact_revision: bool = False,
                    kickcat_module: ModuleType | None = None) -> list[int]:
    """Write each configuration's startup list to its KickCAT slave now (identity through 1018h checked first for
    every slave). Call between ``bus.init()`` and ``bus.create_mapping()``."""
    from ecattool.target.kickcat import KickcatSlave, import_kickcat

    kc = kickcat_module or import_kickcat()
    slaves = bus.slaves()
    live = [(KickcatSlave(bus, slaves[pos], pos, kc), cfg) for pos, cfg in _placed(configs, len(slaves))]
    for s, cfg in live:
        check_identity(cfg, s.position, s.identity(), exact_revision)
    for s, cfg in live:
        for cmd in cfg.commands:
            s.sdo_download(cmd.index, cmd.subindex, cmd.data, cmd.complete_access, cmd.expect_reply)
    return [s.position for s, _ in live]


def master_kind(master: object) -> MasterKind:
    """``pysoem`` for a ``pysoem.Master`` (a ``slaves`` list and ``config_map``), ``kickcat`` for a
    ``kickcat.Bus`` (``slaves()`` a method and ``create_mapping``); a TargetError for anything else."""
    if hasattr(master, "create_mapping") and callable(getattr(master, "slaves", None)):
        return "kickcat"
    if hasattr(master, "config_map") and not callable(getattr(master, "slaves", None)):
        return "pysoem"
    raise TargetError(f"cannot install a startup list on a {type(master).__name__}: give a pysoem.Master (after "
                      "config_init) or a kickcat.Bus (after init), or kind='pysoem'/'kickcat'")


def install(configs: Sequence[SlaveConfig], master: PysoemMaster | KickcatBus, *, kind: MasterKind | None = None,
            exact_revision: bool = False, module: ModuleType | None = None) -> list[int]:
    """:func:`install_pysoem` or :func:`install_kickcat`, by ``kind`` or else by the master's type
    (:func:`master_kind`); ``module`` is the pysoem or kickcat module to use (tests pass a fake)."""
    chosen = kind or master_kind(master)
    # the kind (the caller's, else the master's type) says which of the two the master is
    if chosen == "kickcat":
        return install_kickcat(configs, cast(KickcatBus, master), exact_revision=exact_revision, kickcat_module=module)
    return install_pysoem(configs, cast(PysoemMaster, master), exact_revision=exact_revision, pysoem_module=module)
