"""An I/O slave gets its own small application (issue 33 item 1): a slave without the CiA-402 objects 6040h/6041h
(a terminal, a coupler) is a :class:`Drive` holding the I/O application, not the motion, plant, supervision and
fault parts; its process data is its object store as mapped."""

from __future__ import annotations

import pytest

from ecattool import esi
from ecattool.errors import TargetError
from ecattool.esi.model import Direction
from ecattool.od.model import EcState
from ecattool.sim import Drive
from ecattool.sim.cia402 import Cia402
from ecattool.sim.drive.injection import Injection
from ecattool.sim.drive.io_app import IoApplication
from ecattool.sim.drive.mode_parts import ModeParts
from ecattool.sim.drive.motion import Motion
from ecattool.sim.drive.plant import Plant
from ecattool.sim.drive.supervision_state import Supervision
from ecattool.sim.slave import drive_for_device
from ecattool.sim.units import Units
from tests.conftest import CORPUS, need_corpus

need_corpus()
ESI = CORPUS / "esi"
#: the CiA-402 application's parts and state: none of them belongs on an I/O slave
AXIS_TYPES = (Motion, Injection, Cia402, ModeParts, Plant, Supervision, Units)
#: mailbox-less terminals, a coupler and a CoE terminal, from the corpus
IO_SLAVES = [("beckhoff_EL1xxx.xml", "EL1008"), ("beckhoff_EJ2xxx.xml", "EJ2008"), ("beckhoff_EK11xx.xml", "EK1100"),
             ("beckhoff_EJ3xxx.xml", "EJ3004")]


def _slave(file: str, select: str, state: EcState | None = EcState.OP) -> Drive:
    drive = drive_for_device(esi.load_device(ESI / file, select, "newest"))
    if state is not None:
        for s in (EcState.PREOP, EcState.SAFEOP, EcState.OP):
            drive.request_state(s)
            if s is state:
                break
    return drive


def _axis_parts(drive: Drive) -> list[str]:
    """The drive's attributes that are a part or the state of the CiA-402 application."""
    return [name for name, value in vars(drive).items() if isinstance(value, AXIS_TYPES)]


@pytest.mark.parametrize("file,select", IO_SLAVES, ids=[s for _, s in IO_SLAVES])
def test_an_io_slave_holds_the_io_application_and_no_cia402_part(file: str, select: str) -> None:
    drive = _slave(file, select)
    assert not drive.has_cia402
    assert isinstance(drive.io, IoApplication)
    assert _axis_parts(drive) == []
    assert not hasattr(drive, "motion") and not hasattr(drive, "cia") and drive.plant is None
    # a cycle in OP steps nothing and reports no CiA-402 value
    out, _ = drive.process_image_sizes()
    drive.exchange(bytes(out))
    assert _axis_parts(drive) == [] and drive.state() is EcState.OP


def test_a_drive_still_holds_the_cia402_parts_and_no_io_application() -> None:
    drive = Drive.from_profile("hdt")
    assert drive.has_cia402 and drive.io is None
    assert {type(v) for v in vars(drive).values()} >= {Motion, Injection, Cia402, Supervision}


def test_the_inputs_a_test_sets_go_out_through_the_process_data() -> None:
    """EL1008: eight 1-bit inputs 6000h:01 … 6070h:01 in one byte, bit k = channel k+1."""
    drive = _slave("beckhoff_EL1xxx.xml", "EL1008")
    assert drive.exchange(b"") == b"\x00"
    drive.set_inputs({(0x6000, 1): 1, (0x6020, 1): 1, (0x6070, 1): True})
    assert drive.exchange(b"") == bytes([0b1000_0101])
    assert drive.process_values(Direction.TX)[(0x6070, 1)] == 1
    drive.set_inputs({(0x6000, 1): 0})
    assert drive.exchange(b"") == bytes([0b1000_0100])
    assert drive.events[-1].kind == "inputs"


def test_a_signed_analog_input_goes_out_as_its_twos_complement_and_reads_back_by_sdo() -> None:
    """EJ3004 (CoE): 6000h:11h is the channel's INT value at bits 16..31 of its 4-byte input block."""
    drive = _slave("beckhoff_EJ3xxx.xml", "EJ3004")
    drive.set_inputs({(0x6000, 0x11): -1234, (0x6030, 0x11): 32767})
    image = drive.exchange(b"")
    assert image[2:4] == (-1234).to_bytes(2, "little", signed=True)
    assert image[14:16] == (32767).to_bytes(2, "little")
    assert drive.sdo_upload(0x6000, 0x11) == (-1234).to_bytes(2, "little", signed=True)


def test_the_outputs_the_master_writes_are_held_in_the_mapped_objects() -> None:
    drive = _slave("beckhoff_EJ2xxx.xml", "EJ2008")
    assert drive.exchange(bytes([0b1000_0101])) == b""
    values = drive.process_values(Direction.RX)
    assert [values[(0x7000 + 0x10 * k, 1)] for k in range(8)] == [1, 0, 1, 0, 0, 0, 0, 1]
    assert drive.io is not None and drive.io.outputs() == values
    drive.request_state(EcState.SAFEOP)  # SAFE-OP: outputs ignored, the last ones held
    drive.exchange(bytes([0xFF]))
    assert drive.process_values(Direction.RX) == values


def test_set_inputs_is_all_or_nothing_with_a_one_line_error() -> None:
    drive = _slave("beckhoff_EL1xxx.xml", "EL1008")
    with pytest.raises(TargetError) as bad:
        drive.set_inputs({(0x6000, 1): 1, (0x6010, 1): 2})
    assert str(bad.value) == "0x6010:01 is 1 bit(s): 2 is not in 0..1"
    with pytest.raises(TargetError) as unknown:
        drive.set_inputs({(0x6000, 1): 1, (0x7000, 1): 1})
    assert "0x7000:01 is no input of EL1008" in str(unknown.value) and "\n" not in str(unknown.value)
    assert drive.exchange(b"") == b"\x00"  # nothing was set
    ej = _slave("beckhoff_EJ3xxx.xml", "EJ3004")
    with pytest.raises(TargetError, match=r"0x6000:11 is 16 bit\(s\): 40000 is not in -32768\.\.32767"):
        ej.set_inputs({(0x6000, 0x11): 40000})


def test_set_inputs_on_a_drive_says_its_inputs_are_its_actual_values() -> None:
    with pytest.raises(TargetError, match="is a CiA-402 drive: its inputs are its actual values"):
        Drive.from_profile("hdt").set_inputs({(0x60FD, 0): 1})


@pytest.mark.parametrize("call", [
    lambda d: d.set_limit_switches(positive=True), lambda d: d.set_plant("ideal"), lambda d: d.set_obstacle(10),
    lambda d: d.set_load_torque(1.0), lambda d: d.inject_fault(0x8611), lambda d: d.fault_reset(),
    lambda d: d.mode(), lambda d: d.cia402_state, lambda d: d.internal_position, lambda d: d.modes,
    lambda d: d.set_motor_supply(False), lambda d: d.set_encoder_resolution(4096), lambda d: d.inject_trip(1),
], ids=["limit_switches", "plant", "obstacle", "load_torque", "fault", "fault_reset", "mode", "cia402_state",
        "position", "modes", "motor_supply", "encoder", "trip"])
def test_an_axis_call_on_an_io_slave_is_a_one_line_error(call) -> None:  # type: ignore[no-untyped-def]
    drive = _slave("beckhoff_EL1xxx.xml", "EL1008")
    with pytest.raises(TargetError) as exc:
        call(drive)
    message = str(exc.value)
    assert message.startswith("EL1008 is an I/O slave (no CiA-402 objects 6040h/6041h): ") and "\n" not in message


def test_time_passing_and_a_lost_communication_are_what_they_are_for_any_slave() -> None:
    drive = _slave("beckhoff_EL1xxx.xml", "EL1008")
    drive.set_inputs({(0x6010, 1): 1})
    drive.step(100)  # nothing to advance
    assert drive.exchange(b"") == b"\x02"
    assert drive.cycle_ns() == 1_000_000
    drive.lose_communication()
    assert drive.state() is EcState.SAFEOP
    assert drive.events[-1].kind == "state" and drive.events[-1].data["al_status"] == 0x001B


def test_a_repeated_cycle_answers_from_the_store_as_it_is_now() -> None:
    """The I/O cycle skips the latch and the packing when the outputs and the store are those of the cycle before;
    a write between two cycles on the same outputs is seen: an output object written behind the master's back is
    latched again, an input set is sent."""
    drive = _slave("beckhoff_EJ2xxx.xml", "EJ2008")
    drive.exchange(bytes([0b0000_0001]))
    drive.exchange(bytes([0b0000_0001]))
    drive.objects.store[(0x7000, 1)] = b"\x00"
    drive.exchange(bytes([0b0000_0001]))
    assert drive.value(0x7000, 1) == 1
    el = _slave("beckhoff_EL1xxx.xml", "EL1008")
    assert [el.exchange(b"") for _ in range(2)] == [b"\x00", b"\x00"]
    el.set_inputs({(0x6030, 1): 1})
    assert el.exchange(b"") == b"\x08"
    el.power_cycle()
    for s in (EcState.PREOP, EcState.SAFEOP, EcState.OP):
        el.request_state(s)
    assert el.exchange(b"") == b"\x00"  # a new store: the inputs at their defaults


def test_a_sim_run_script_sets_an_io_slaves_inputs_by_address(tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    """``sim run`` on an EL1008: ``inputs:`` takes input objects by address and the next exchange carries them; an
    axis input on the terminal is the script's one-line error with its line, exit 1."""
    import json

    from tests.conftest import run

    script = tmp_path / "io.yaml"
    script.write_text("- state: PREOP\n- state: SAFEOP\n- state: OP\n- inputs: {'6000:01': 1, '6070:01': 1}\n"
                      "- exchange: ''\n")
    code, out, err = run(capsys, "sim", "run", str(ESI / "beckhoff_EL1xxx.xml"), str(script), "--device", "EL1008", "--policy", "newest",
                         "--json")
    assert code == 0, out + err
    assert json.loads(out)["steps"][-1]["data"] == "81"
    bad = tmp_path / "bad.yaml"
    bad.write_text("- state: PREOP\n- inputs: {limit_positive: true}\n")
    code, out, err = run(capsys, "sim", "run", str(ESI / "beckhoff_EL1xxx.xml"), str(bad), "--device", "EL1008",
                         "--policy", "newest")
    assert code == 1
    message = (out + err).strip()
    assert "bad.yaml:2" in message and "EL1008 is an I/O slave (no CiA-402 objects 6040h/6041h): limit switches " \
        "needs a drive" in message and "Traceback" not in message and len(message.splitlines()) == 1, message
