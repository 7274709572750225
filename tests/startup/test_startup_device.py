"""From a real ESI through PDO programming to every startup format: SlaveConfig.from_device."""

from __future__ import annotations

import pytest

from ecattool.errors import EncodeError

from ecattool.startup.model import is_pdo_programming

from ecattool import esi, pdo
from ecattool.errors import SelectionError
from ecattool.esi.model import Direction
from ecattool.startup import FORMATS, SlaveConfig, export, import_bytes
from tests.conftest import corpus_path
from tests.startup.test_startup_export import FakeMaster, FakeSlave, _gcc

RX = "0x1600=0x6040:00/16,0x607A:00/32,0x6060:00/8"
TX = "0x1A00=0x6041:00/16,0x6064:00/32,0x6061:00/8"


@pytest.fixture(scope="module")
def everest():
    return esi.load_device(corpus_path("esi", "ingenia_eve-xcr-e_esi.xml"))


def _config(device, complete_access: bool, cycle_ns: int | None = None) -> SlaveConfig:
    mapping = pdo.Mapping.from_text(rx=RX, tx=TX, device=device)
    startup = pdo.program(device, mapping, complete_access=complete_access)
    return SlaveConfig.from_device(device, startup, mapping=mapping, position=1, dc_opmode="DCSync",
                                   dc_cycle_ns=cycle_ns)


def test_from_device_takes_identity_pdos_sync_managers_and_dc(everest):
    cfg = _config(everest, False)
    assert cfg.identity == everest.identity and cfg.name == "EVE-XCR-E" and cfg.position == 1
    assert [p.index for p in cfg.rx_pdos] == [0x1600] and [p.index for p in cfg.tx_pdos] == [0x1A00]
    assert [(e.index, e.bit_len) for e in cfg.rx_pdos[0].entries] == [(0x6040, 16), (0x607A, 32), (0x6060, 8)]
    assert cfg.dc_assign_activate == 0x0300
    assert cfg.startup.vendor_id == everest.vendor_id
    assert len(cfg.commands) == 16


def test_default_assignment_without_mapping(everest):
    cfg = SlaveConfig.from_device(everest)
    assert cfg.rx_pdos == [p for p in everest.rx_pdos if p.sm is not None]
    assert all(p.direction is Direction.TX for p in cfg.tx_pdos)


def test_unknown_dc_opmode_names_the_choices(everest):
    with pytest.raises(SelectionError, match="DCSync"):
        SlaveConfig.from_device(everest, dc_opmode="nope")


@pytest.mark.parametrize("complete_access", [False, True])
def test_programmed_mapping_exports_to_every_format(everest, complete_access, tmp_path):
    cfg = _config(everest, complete_access)
    with pytest.raises(EncodeError, match="no SYNC0"):  # the ESI's DCSync gives no cycle; ENI never writes 0
        export(cfg, "eni")
    for name, fmt in FORMATS.items():
        if not fmt.can_export:
            continue
        text = export(cfg, name, lossy=True) if name != "eni" else \
            export(_config(everest, complete_access, 1_000_000), name)  # lossy: TwinCAT and CSV have no DC
        if fmt.can_import:
            back = [c for s in import_bytes(text.encode(), f"x.{name}", name) for c in s.commands]
            # ros2 carries the mapping in rpdo/tpdo (the driver programs it), not as sdo writes
            sent = [c for c in cfg.commands if not (name == "ros2" and is_pdo_programming(c.index))]
            assert [(c.index, c.subindex, c.data, c.complete_access) for c in back] == \
                [(c.index, c.subindex, c.data, c.complete_access) for c in sent], name
    # the ESI's DCSync OpMode gives no SYNC0 cycle: the C file compiles once the application defines it
    assert _gcc(export(cfg, "igh"), tmp_path, "SYNC0_CYCLE_NS=1000000U").returncode == 0
    namespace: dict = {}
    exec(compile(export(cfg, "pysoem"), "m.py", "exec"), namespace)
    slaves = [FakeSlave(0, 0), FakeSlave(everest.vendor_id, everest.product_code)]
    namespace["install"](FakeMaster(slaves))
    slaves[1].config_func(1)
    assert [w[:2] for w in slaves[1].writes] == [(c.index, c.subindex) for c in cfg.commands]
