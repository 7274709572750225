"""Slaves without a mailbox on the served bus (issue 34, items 5 and 8), frame by frame through the in-process loop:
a device's sync managers come from its SII, whatever their number and use; an ESC without an application (device
emulation, SII word 0 bit 8) follows the AL control itself; an ESC whose PDI is digital I/O (PDI control 04h)
serves its output SM over the digital output registers 0x0F00-0x0F03, and no other ESC lets an SM cover a
register; ``sim serve`` refuses in one line a slave it cannot serve.

Real files: the Beckhoff ESIs of ../shared/corpus/esi (SOURCES.md: DiamondLightSource/ethercat)."""

from __future__ import annotations

import struct

import pytest

from ecattool import esi
from ecattool.errors import InputError
from ecattool.od.model import EcState
from ecattool.sim import Drive
from ecattool.sim.bus import Cmd, Datagram
from ecattool.sim.bus.serve import device_source, virtual_slaves
from ecattool.sim.esc import registers as R
from ecattool.sim.slave import VirtualSlave, drive_for_device, served_sii
from tests.conftest import CORPUS, need_corpus
from tests.conftest import run as run_main
from tests.wire.test_wire_slave import MiniMaster, _fmmu, _sm

need_corpus()
ESI = CORPUS / "esi"


def _slave(file: str, select: str) -> VirtualSlave:
    device = esi.load_device(ESI / file, select, "newest")
    return VirtualSlave(drive_for_device(device), served_sii(device))


def _states(m: MiniMaster, *codes: int) -> list[tuple[int, int]]:
    return [m.al(code) for code in codes]


def test_the_roles_of_the_sync_managers_come_from_the_sii() -> None:
    """EJ2809: two output SMs over 0x0F00 and 0x0F01 (ESI: ``<Sm StartAddress="#x0f00" ControlByte="#x44"``),
    EL1008: one input SM at 0x1000 as SM0, EK1100: none; a drive keeps SM0/SM1 mailbox, SM2/SM3 process data."""
    ej2809 = _slave("beckhoff_EJ2xxx.xml", "EJ2809")
    assert (ej2809.roles.mbx_out, ej2809.roles.mbx_in, ej2809.roles.outputs, ej2809.roles.inputs) == \
        (None, None, (0, 1), ())
    el1008 = _slave("beckhoff_EL1xxx.xml", "EL1008")
    assert (el1008.roles.has_mailbox, el1008.roles.outputs, el1008.roles.inputs) == (False, (), (0,))
    ek1100 = _slave("beckhoff_EK11xx.xml", "EK1100")
    assert (ek1100.roles.has_mailbox, ek1100.roles.outputs, ek1100.roles.inputs) == (False, (), ())
    hdt = VirtualSlave.from_drive(Drive.from_profile("hdt"))
    assert (hdt.roles.mbx_out, hdt.roles.mbx_in, hdt.roles.outputs, hdt.roles.inputs) == (0, 1, (2,), (3,))
    # device emulation from SII word 0 (the ESI's ConfigData 04 01: PDI digital I/O, ESC configuration bit 0)
    assert ej2809.emulation and el1008.emulation and ek1100.emulation and not hdt.emulation
    assert ej2809.esc.digital_io and not hdt.esc.digital_io


def test_a_coupler_follows_the_al_control_through_every_state() -> None:
    """EK1100 (ConfigData 0001: device emulation): no mailbox to check, no application to refuse; the AL status
    is what the master asked for, with status code 0, as an ESC without a processor shows it."""
    m = MiniMaster(_slave("beckhoff_EK11xx.xml", "EK1100"))
    assert _states(m, 2, 4, 8, 4, 2, 1) == [(2, 0), (4, 0), (8, 0), (4, 0), (2, 0), (1, 0)]
    assert m.slave.refusals == []


def test_digital_outputs_are_served_over_0x0f00_with_the_working_counter() -> None:
    """EJ2008: SOEM's configuration of its SII (SM0 at 0x0F00, 1 byte, control 0x44; FMMU0 writes it): INIT to OP
    without a mailbox, the LWR reaches the digital output register and the drive's 7000h..7070h objects."""
    m = MiniMaster(_slave("beckhoff_EJ2xxx.xml", "EJ2008"))
    assert m.al(2) == (0x02, 0)  # was AL 0x0016 (invalid mailbox configuration): the slave has none
    assert m.wr(R.SM, _sm(0x0F00, 1, 0x44)) == 1 and m.wr(R.FMMU, _fmmu(0x0, 1, 0x0F00, 2)) == 1
    assert m.slave.esc.sm(0).active
    assert _states(m, 4, 8) == [(0x04, 0), (0x08, 0)]
    lwr = m.loop.one(Datagram.logical(Cmd.LWR, 0, bytes([0b1000_0101])))
    assert lwr.wkc == 1
    assert m.rd(R.DIGITAL_OUTPUT, 1) == (bytes([0b1000_0101]), 1)
    drive = m.slave.drive
    assert [drive.value(0x7000 + 0x10 * k, 1) for k in range(8)] == [1, 0, 1, 0, 0, 0, 0, 1]


def test_two_output_sms_make_one_image() -> None:
    """EJ2809: 16 outputs over SM0 (0x0F00) and SM1 (0x0F01), one FMMU over both: one image for the drive."""
    m = MiniMaster(_slave("beckhoff_EJ2xxx.xml", "EJ2809"))
    m.wr(R.SM, _sm(0x0F00, 1, 0x44) + _sm(0x0F01, 1, 0x44))
    m.wr(R.FMMU, _fmmu(0x0, 2, 0x0F00, 2))
    assert _states(m, 2, 4, 8) == [(2, 0), (4, 0), (8, 0)]
    assert m.loop.one(Datagram.logical(Cmd.LWR, 0, bytes([0x01, 0x80]))).wkc == 1
    drive = m.slave.drive
    assert drive.value(0x7000, 1) == 1 and drive.value(0x70F0, 1) == 1 and drive.value(0x7080, 1) == 0


def test_digital_inputs_are_read_from_their_sm() -> None:
    """EL1008: SM0 at 0x1000, 1 byte, control 0x00 (inputs); the LRD is answered with the working counter 1."""
    m = MiniMaster(_slave("beckhoff_EL1xxx.xml", "EL1008"))
    m.wr(R.SM, _sm(0x1000, 1, 0x00))
    m.wr(R.FMMU, _fmmu(0x0, 1, 0x1000, 1))
    assert _states(m, 2, 4, 8) == [(2, 0), (4, 0), (8, 0)]
    lrd = m.loop.one(Datagram.logical(Cmd.LRD, 0, 1))
    assert lrd.wkc == 1 and m.slave.drive.state() is EcState.OP


def test_an_sm_over_the_digital_outputs_of_an_esc_without_digital_io_is_not_activated() -> None:
    """The register area stays closed to every SM of an ESC whose PDI is not digital I/O (HDT: SPI), also at
    0x0F00: the bytes are the register's, the SM does not serve them (tests/wire/test_wire_esc_bounds.py for more)."""
    m = MiniMaster(VirtualSlave.from_drive(Drive.from_profile("hdt")))
    assert m.wr(R.SM + 2 * R.SM_SIZE, _sm(0x0F00, 1, 0x44)) == 1
    assert m.slave.esc.sm(2).enabled and not m.slave.esc.sm(2).active
    # and on a digital-I/O ESC only the four output registers: an SM over 0x0F00..0x0F07 is not activated
    ej = MiniMaster(_slave("beckhoff_EJ2xxx.xml", "EJ2008"))
    ej.wr(R.SM, _sm(0x0F00, 8, 0x44) + _sm(0x0E00, 1, 0x44) + _sm(0x0F00, 1, 0x00))
    assert [ej.slave.esc.sm(n).active for n in range(3)] == [False, False, False]


def test_a_slave_with_a_mailbox_still_needs_its_mailbox_sms() -> None:
    """EJ3004 (analog inputs, CoE): INIT -> PRE-OP without mailbox SMs stays refused with 0x0016."""
    m = MiniMaster(_slave("beckhoff_EJ3xxx.xml", "EJ3004"))
    assert not m.slave.emulation and m.slave.roles.has_mailbox
    assert m.al(2) == (0x11, 0x0016)


def test_sim_serve_refuses_a_slave_it_cannot_serve_in_one_line(capsys: pytest.CaptureFixture[str]) -> None:
    """Elmo's ESI (corpus) gives its SII a SyncM category (Eeprom/Category 41) whose SM0 is at 0x0000, 32792
    bytes: SOEM programs SM0 from it and no master could use the slave. ``sim serve`` says so before it
    starts, naming the slave, and exits 1 (it used to print "serving 1 slave")."""
    elmo = str(ESI / "elmo_Elmo_ECAT_00010420_V11.xml")
    with pytest.raises(InputError, match="cannot serve slave 0 .*SM0 .* at 0x0000"):
        virtual_slaves([device_source(elmo, selector="0")])
    code, out, err = run_main(capsys, "sim", "serve", "hdt", elmo, "--device", "0", "--iface", "nonexistent0")
    lines = err.strip().splitlines()
    assert code == 1 and len(lines) == 1 and out == "", (out, err)
    assert "cannot serve slave 1 (Elmo Drive" in lines[0] and "product 0x" in lines[0]


def test_a_drive_whose_60c2_is_no_processor_cycle_takes_each_frames_outputs_on_its_own_clock() -> None:
    """Found by the wire sweep (tests/wire/test_wire_whole_bus.py): Ingenia's ESI gives 60C2h = 1 x 10^0 s; served on
    its own clock the drive took a controlword once a second and commission's enable gave up after 200 cycles.
    A 60C2h over 100 ms paces nothing: each process data event is one cycle."""
    from tests.wire.test_wire_slave import FakeTime

    device = esi.load_device(ESI / "ingenia_eve-xcr-e_esi.xml", "0x29C:0x2C31001:0x50014")
    slave = VirtualSlave(drive_for_device(device), served_sii(device))
    assert slave.drive.cycle_ns() == 1_000_000_000
    time = FakeTime()
    m = MiniMaster(slave, clock=time)
    slave.own_clock = True
    m.mailbox_config()
    m.wr(R.SM + 16, _sm(0x1800, 11, 0x64) + _sm(0x1C00, 11, 0x20))
    m.wr(R.FMMU, _fmmu(0, 11, 0x1800, 2) + _fmmu(11, 11, 0x1C00, 1))
    assert _states(m, 2, 4, 8) == [(2, 0), (4, 0), (8, 0)]
    for cw in (6, 7, 15):
        time.ms(1)
        assert m.loop.one(Datagram.logical(Cmd.LRW, 0, struct.pack("<HiiB", cw, 0, 0, 1) + bytes(11))).wkc == 3
        time.ms(1)
        m.loop.one(Datagram.logical(Cmd.LRD, 0x100, 1))  # a frame after it: the drive has run its cycle
        assert slave.drive.value(0x6040) == cw


def _live_mixed() -> tuple[object, list[list[tuple[int, int]]]]:
    """A live simulator bus of an EK1100, an EL1008 (no mailbox) and an HDT drive; per slave, the SDOs sent to it."""
    from ecattool.online import sim_bus

    devices = [esi.load_device(ESI / "beckhoff_EK11xx.xml", "EK1100", "newest"),
               esi.load_device(ESI / "beckhoff_EL1xxx.xml", "EL1008", "newest")]
    drives = [drive_for_device(d) for d in devices] + [Drive.from_profile("hdt")]
    bus = sim_bus(drives)
    sent: list[list[tuple[int, int]]] = [[] for _ in drives]
    for slave, log in zip(bus.slaves, sent):
        upload = slave.sdo_upload

        def spy(index: int, sub: int, complete_access: bool = False, size: int | None = None, _up=upload,
                _log=log) -> bytes:
            _log.append((index, sub))
            return bytes(_up(index, sub, complete_access, size=size))

        slave.sdo_upload = spy
    return bus, sent


def test_scan_and_from_bus_never_send_an_sdo_to_a_slave_without_a_mailbox(tmp_path) -> None:
    """Issue 35 item 1: the coupler and the digital terminal are read from their SII only (``bus scan`` used to
    try 1018h on each, ``project new --from-bus`` stopped at ``SDO timeout on 0x1C12:00``)."""
    from ecattool.online import Library, scan
    from ecattool.online.from_bus import project_from_bus

    bus, sent = _live_mixed()
    scanned = scan(bus, Library(ESI))
    assert [s.coe_identity is None for s in scanned] == [True, True, False]
    assert sent[0] == [] and sent[1] == [] and (0x1018, 1) in sent[2]
    text = project_from_bus(bus, Library(ESI), tmp_path / "m.yaml")
    assert sent[0] == [] and sent[1] == []
    assert '- name: "io1"' in text and '- name: "io2"' in text and '- name: "axis3"' in text
    assert text.count("no CoE mailbox") == 2 and "0x1C12" not in text.split('"axis3"')[0]


def test_from_bus_names_a_slave_that_does_not_answer_and_writes_the_others(tmp_path) -> None:
    from ecattool.errors import SdoTimeout
    from ecattool.online import Library
    from ecattool.online.from_bus import project_from_bus

    bus, _ = _live_mixed()

    def silent(*a: object, **k: object) -> bytes:
        raise SdoTimeout(0x1C12, 0)

    bus.slaves[2].sdo_upload = silent
    problems: list[str] = []
    text = project_from_bus(bus, Library(ESI), tmp_path / "m.yaml", problems=problems)
    assert text.count("  - name: ") == 2 and len(problems) == 1
    assert problems[0].startswith("not written: slave 2 (") and "vendor 0x00000289" in problems[0], problems
    assert "# not written: slave 2" in text


def test_the_full_working_counter_counts_a_slave_with_bit_inputs() -> None:
    """SOEM 1.4 (pysoem 1.1.13) gives expected_wkc 0 for a lone EL1002 (2 bit inputs) although its ESC adds 1
    for the read; on the wire sample of the corpus sweep commission saw "working counter 41, expected 39"."""
    from types import SimpleNamespace

    from ecattool.target.pysoem import full_working_counter

    def slave(o: int, i: int) -> SimpleNamespace:
        return SimpleNamespace(output=bytes(o), input=bytes(i))

    bus = SimpleNamespace(slaves=[slave(0, 0), slave(0, 1), slave(1, 0), slave(28, 20)], expected_wkc=5)
    assert full_working_counter(bus) == 1 + 2 + 3
    big = SimpleNamespace(slaves=[slave(1000, 1000)], expected_wkc=7)  # two frames: SOEM's count stands
    assert full_working_counter(big) == 7


def test_a_1c00h_without_defaults_reads_the_sync_manager_types() -> None:
    """Copley XE2 and EM7004 list 1C00h without DefaultData: every SM read type 0, and KickCAT's create_mapping
    (which finds the process data SMs through 1C00h) mapped nothing, so SAFE-OP was refused with 0x001D."""
    for file, select in (("copley_XE2_4.60.xml", "0xAB:0x10B0:0x10004"),
                         ("beckhoff_EM7xxx.xml", "0x2:0x1B5C3452:0x270B0000")):
        drive = drive_for_device(esi.load_device(ESI / file, select))
        drive.request_state(EcState.PREOP)
        assert [drive.sdo_upload(0x1C00, sub)[0] for sub in range(5)] == [4, 1, 2, 3, 4], file
