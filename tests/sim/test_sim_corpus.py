"""Every CoE drive ESI in the corpus loads into a simulated drive and reaches OP with its default PDOs."""

from __future__ import annotations

import pytest

from ecattool.esi.model import Direction
from ecattool.od.model import EcState
from ecattool.sim import Drive
from tests.conftest import corpus_path

FILES = [
    "elmo_Elmo_ECAT_00010420_V11.xml",
    "inovance_SV660_EOE_1Axis_V9.12.xml",
    "ingenia_eve-xcr-e_esi.xml",
    "copley_XE2_4.60.xml",
    "synapticon_Somanet_CiA402-single.xml",
    "beckhoff_AX2xxx.xml",
    "etg_ETG2001_ModulesSlots_CiA402.xml",
]
#: (file, device index) for every CoE device of every drive ESI (Elmo has four revisions/products)
DRIVES = [(f, None) for f in FILES if not f.startswith("elmo")] + [(FILES[0], str(i)) for i in range(4)]


def _up(drive: Drive) -> Drive:
    for s in (EcState.PREOP, EcState.SAFEOP, EcState.OP):
        drive.request_state(s)
    assert drive.state() is EcState.OP
    return drive


def _image_bits_by_sdo(drive: Drive, assign: int) -> int:
    """The process image size read back the way a master does: 1C1xh, then each mapping object."""
    def u(index: int, sub: int) -> int:
        return int.from_bytes(drive.sdo_upload(index, sub), "little")

    total = 0
    for s in range(1, u(assign, 0) + 1):
        pdo = u(assign, s)
        if pdo:
            total += sum(u(pdo, e) & 0xFF for e in range(1, u(pdo, 0) + 1))
    return total


@pytest.mark.parametrize("name,selector", DRIVES, ids=[d[0].split("_")[0] + (d[1] or "") for d in DRIVES])
def test_corpus_drive_reaches_op_with_default_pdos(name, selector):
    d = Drive.from_esi(corpus_path("esi", name), selector)
    d.request_state(EcState.PREOP)
    rx_bits, tx_bits = _image_bits_by_sdo(d, 0x1C12), _image_bits_by_sdo(d, 0x1C13)
    _up(d)
    out_size, in_size = d.process_image_sizes()
    assert (out_size, in_size) == (rx_bits // 8, tx_bits // 8)
    if d.has_cia402:
        assert out_size >= 2 and in_size >= 2  # at least controlword / statusword
    inputs = d.exchange(bytes(out_size))
    assert len(inputs) == in_size


@pytest.mark.parametrize("name", ["elmo_Elmo_ECAT_00010420_V11.xml", "synapticon_Somanet_CiA402-single.xml",
                                  "inovance_SV660_EOE_1Axis_V9.12.xml"])
def test_corpus_drive_enables_through_pdos(name):
    """With controlword and statusword in the default PDOs, the CiA-402 machine reaches OPERATION ENABLED."""
    d = _up(Drive.from_esi(corpus_path("esi", name), "2" if name.startswith("elmo") else None))
    rx = d.layout[Direction.RX].entries
    cw = next(off for idx, _s, off, _b in rx if idx == 0x6040)
    size = d.process_image_sizes()[0]
    for value in (0x06, 0x07, 0x0F):
        image = bytearray(size)
        image[cw // 8:cw // 8 + 2] = value.to_bytes(2, "little")
        d.exchange(bytes(image))
    assert d.cia402_state.value == "OPERATION_ENABLED"


def test_copley_assigns_a_pdo_over_sdo_and_reaches_op():
    d = Drive.from_esi(corpus_path("esi", "copley_XE2_4.60.xml"))
    d.request_state(EcState.PREOP)
    rx = d.device.rx_pdos[1]
    d.sdo_download(0x1C12, 0, b"\x00")
    d.sdo_download(0x1C12, 1, rx.index.to_bytes(2, "little"))
    d.sdo_download(0x1C12, 0, b"\x01")
    d.request_state(EcState.SAFEOP)
    d.request_state(EcState.OP)
    assert d.process_image_sizes()[0] == (rx.bit_size + 7) // 8


def test_sim_target_from_raw_esi_devices():
    """SimTarget.from_devices completes raw ESI devices (modules, 1C12h/1C13h) like Drive.from_esi."""
    from ecattool import esi
    from ecattool.target import SimTarget

    devices = [esi.load_device(corpus_path("esi", "etg_ETG2001_ModulesSlots_CiA402.xml")),
               esi.load_device(corpus_path("esi", "synapticon_Somanet_CiA402-single.xml"))]
    t = SimTarget.from_devices(devices)
    for slave in t.slaves():
        for s in (EcState.PREOP, EcState.SAFEOP, EcState.OP):
            slave.request_state(s)
        assert slave.sdo_upload(0x1C12, 0) != b"\x00"
