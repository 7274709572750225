"""Never stop a running machine by surprise (issue 35 item 4), in process: the refusal of a bus with slaves in
SAFE-OP or OP, ``--reset-bus``, and what is put back when the command ends. The raw read itself runs on the wire
(tests/wire/test_wire_hostile_slave.py, "running bus")."""

from __future__ import annotations

import pytest

from ecattool.errors import TargetError
from ecattool.od.model import EcState
from ecattool.online import bus_state
from ecattool.online.bus_state import Found, guard, restore
from ecattool.target.base import Unsupported


class Slave:
    def __init__(self, position: int, refuse: bool = False, whole_bus_only: bool = False) -> None:
        self.position, self.refuse, self.whole_bus_only, self.asked = position, refuse, whole_bus_only, []

    def request_state(self, state: EcState) -> None:
        if self.whole_bus_only:
            raise Unsupported("kickcat: the Python binding requests a state for the whole bus, not for one slave")
        if self.refuse:
            raise TargetError("no answer")
        self.asked.append(state)


def test_a_running_bus_is_refused_naming_its_running_slaves(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(bus_state, "read_states", lambda ifname, sii=False: [Found(0, 0x02), Found(1, 0x08), Found(2, 0x14, 0x1B)])
    with pytest.raises(TargetError) as refused:
        guard("eth0", reset_bus=False)
    assert str(refused.value) == ("slave 1 (OP), slave 2 (SAFEOP, error) on 'eth0' are running: opening the bus "
                                  "resets every slave to INIT and would stop the machine; pass --reset-bus to do it "
                                  "anyway")
    assert [f.position for f in guard("eth0", reset_bus=True)] == [0, 1, 2]


def test_a_bus_in_init_or_preop_or_unknown_opens(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(bus_state, "read_states", lambda ifname, sii=False: [Found(0, 0x01), Found(1, 0x12, 0x1D)])
    assert len(guard("eth0", reset_bus=False)) == 2
    monkeypatch.setattr(bus_state, "read_states", lambda ifname, sii=False: None)  # no raw socket, nothing answered
    assert guard("eth0", reset_bus=False) == []


def test_each_slave_is_put_back_where_it_can_be_and_the_rest_is_named() -> None:
    slaves = [Slave(0), Slave(1), Slave(2), Slave(3, refuse=True), Slave(4, whole_bus_only=True)]
    notes = restore(slaves, [Found(0, 0x01), Found(1, 0x02), Found(2, 0x08), Found(3, 0x01), Found(4, 0x01)])
    assert slaves[0].asked == [EcState.INIT] and slaves[1].asked == [] and slaves[2].asked == []
    assert notes == ["slave 2 (OP) was left in PRE-OP: ecattool has no configuration to take it back to OP (give "
                     "the command a project)",
                     "slave 3 (INIT) could not be put back in INIT: no answer",
                     "slave 4 (INIT) was left in PRE-OP: kickcat: the Python binding requests a state for the whole "
                     "bus, not for one slave"]


def _powered_up(project: str) -> tuple[object, list[object]]:
    """The project's machine, and its drives simulated as a master leaves them after its bus init: in PRE-OP, the
    device's default PDO mapping, no DC (what a project's configuration has to be written again into)."""
    from ecattool.online import sim_bus
    from ecattool.project.machine import load_machine
    from ecattool.target.sim import SimTarget

    machine = load_machine(project)
    target = SimTarget.from_devices([rd.device for rd in sorted(machine.slaves, key=lambda r: r.position)])
    bus = sim_bus(target.slaves())
    for s in bus.slaves:
        s.request_state(EcState.PREOP)
    return machine, list(bus.slaves)


def test_slaves_found_running_are_put_back_as_the_project_configures_them() -> None:
    """Issue 35 item 4: "put each slave back in the state it was found in where it can (PRE-OP always; SAFE-OP/OP
    with a project that configures them)". The Control Techniques sample runs csp on DC with a mapping that is not
    the drive's default (6 output and 7 input octets, the default 4 and 4): found in OP, the drive is configured as
    commissioning does (its PRE-OP startup list, DC; without them SAFE-OP is refused, AL 0x0030) and ends in OP with
    the project's process image, its power stage disabled; the note says who must send process data now."""
    from functools import partial

    from ecattool.commission.runner import put_back

    machine, slaves = _powered_up("samples/controltechniques/project.yaml")
    (drive,) = slaves
    notes = restore(slaves, [Found(0, 0x08)], put_back=partial(put_back, machine.slaves))  # type: ignore[attr-defined]
    assert drive.state() is EcState.OP  # type: ignore[attr-defined]
    assert list(drive.drive.process_image_sizes()) == [6, 7]  # type: ignore[attr-defined]
    assert drive.dc_activation()[0] == 0x0300  # type: ignore[attr-defined]
    assert notes == ["slave 0 was put back in OP as the project configures it",
                     "slave 0 is in OP: the process data must now come from the machine's master (ecattool's stops "
                     "as the command ends; a drive's power stage is left disabled), else the sync manager watchdog "
                     "takes it to SAFE-OP (AL status code 0x001B)"]
    statusword = int.from_bytes(drive.sdo_upload(0x6041, 0, size=2), "little")  # type: ignore[attr-defined]
    assert statusword & 0x6F != 0x27  # CiA-402 "operation enabled" is never set by putting a drive back


def test_a_slave_found_in_safeop_goes_back_to_safeop_and_one_the_project_lacks_stays_in_preop() -> None:
    from functools import partial

    from ecattool.commission.runner import put_back

    machine, slaves = _powered_up("samples/controltechniques/project.yaml")
    notes = restore(slaves, [Found(0, 0x14, 0x1B)], put_back=partial(put_back, machine.slaves))
    assert slaves[0].state() is EcState.SAFEOP  # type: ignore[attr-defined]
    assert notes == ["slave 0 was put back in SAFEOP as the project configures it"]
    _, slaves = _powered_up("samples/controltechniques/project.yaml")
    notes = restore(slaves, [Found(0, 0x08)], put_back=partial(put_back, []))
    assert slaves[0].state() is EcState.PREOP  # type: ignore[attr-defined]
    assert notes == ["slave 0 (OP) was left in PRE-OP: the project configures no slave at position 0, ecattool "
                     "cannot take it back to OP"]


def test_a_slave_that_is_not_the_projects_device_is_not_configured() -> None:
    """The identity is checked as commissioning checks it before anything is written: the HDT sample's project on
    the Control Techniques drive leaves it in PRE-OP with the identity named."""
    from functools import partial

    from ecattool.commission.runner import put_back
    from ecattool.project.machine import load_machine

    _, slaves = _powered_up("samples/controltechniques/project.yaml")
    other = load_machine("samples/hdt/project.yaml")
    notes = restore(slaves, [Found(0, 0x08)], put_back=partial(put_back, other.slaves))
    assert slaves[0].state() is EcState.PREOP  # type: ignore[attr-defined]
    assert len(notes) == 1 and notes[0].startswith("slave 0 (OP) was left in PRE-OP: putting it back failed at "
                                                   "identity: wrong device"), notes


class _Gone:
    """A slave whose master went away: every request is a TargetError, outside any named step of the run too."""

    def __init__(self, position: int) -> None:
        self.position = position

    def __getattr__(self, name: str) -> object:
        def gone(*args: object, **kwargs: object) -> None:
            raise TargetError("the master is gone")

        return gone


def test_a_slave_that_fails_outside_a_named_step_is_named_and_the_rest_still_put_back() -> None:
    """As commissioning takes a failure (``_DriveRun._guarded``): an error a target raises outside a named step (the
    identity read from the EEPROM after 1018h failed) leaves that slave in PRE-OP with a note, and the slaves after
    it are still put back; it ended the put-back, and the INIT restores after it, with that error."""
    from ecattool.commission.runner import put_back

    machine, slaves = _powered_up("samples/controltechniques/project.yaml")
    gone = _Gone(0)  # the same project slave for both: each is put back as the drive at position 0
    notes = put_back(machine.slaves, [(gone, EcState.OP), (slaves[0], EcState.SAFEOP)])  # type: ignore[list-item]
    assert slaves[0].state() is EcState.SAFEOP  # type: ignore[attr-defined]
    assert notes == ["slave 0 (OP) was left in PRE-OP: putting it back failed at commission: the master is gone",
                     "slave 0 was put back in SAFEOP as the project configures it"]


#: every command that acts on slaves through a real master (they take every slave through INIT too), with the
#: arguments after its --target
ACTING = {
    "commission": ["commission", "samples/technosoft_ipos/project.yaml"],
    "sw verify": ["sw", "verify", "samples/technosoft_ipos/setup.sw"],
    "sw download": ["sw", "download", "samples/technosoft_ipos/setup.sw"],
    "sw upload": ["sw", "upload", "--like", "samples/technosoft_ipos/setup.sw", "-o", "-"],
    "scale explain": ["scale", "explain", "--profile", "hdt"],
}


@pytest.mark.parametrize("command", sorted(ACTING))
def test_a_command_that_acts_on_slaves_refuses_a_running_bus_until_told(
        monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], command: str) -> None:
    from ecattool.target import isolated
    from tests.conftest import ROOT, run

    monkeypatch.chdir(ROOT)
    monkeypatch.setattr(bus_state, "read_states", lambda ifname, sii=False: [Found(0, 0x02), Found(1, 0x08)])
    opened: list[str] = []
    limited: list[int] = []

    def master(ifname: str, limits: object = None) -> None:  # limits: the slaves' timeouts (target.timeouts)
        opened.append(ifname)
        limited.append(len(getattr(limits, "slaves", ())))
        raise TargetError(f"(the master would open {ifname} here)")

    monkeypatch.setattr(isolated, "pysoem_target", master)
    args = [*ACTING[command], "--target", "pysoem:ecat9"]
    code, _, err = run(capsys, *args)
    assert code == 1 and opened == [], err
    assert "slave 1 (OP) on 'ecat9' is running" in err and "--reset-bus" in err and len(err.splitlines()) == 1, err
    code, _, err = run(capsys, *args, "--reset-bus")
    assert opened == ["ecat9"] and "the master would open ecat9 here" in err, err
    # the real master's waits are bounded by the timeouts of the devices the command has (a project's, the
    # family's, the .sw's Technosoft drive), as a bare 'sim' holds those devices: one rule of the target spec
    assert limited == [1], limited


def test_an_sii_that_cannot_be_read_through_the_esc_is_left_unknown() -> None:
    """with_sii (KickCAT's from-bus): a slave whose EEPROM interface does not answer, or reports an error (status
    0x2000, no acknowledge), keeps no SII image; the others are read."""
    from ecattool.online.bus_state import with_sii
    from ecattool.sii.builder import build
    from ecattool.profiles import load
    from ecattool.sim.bus.engine import Bus
    from ecattool.sim.bus.frame import parse_frame
    from ecattool.sim.slave import VirtualSlave, drive_for_device

    device = load("hdt")
    image = build(device).to_bytes()
    engine = Bus([VirtualSlave(drive_for_device(device), image).esc for _ in range(3)])

    def exchange(frame: bytes, index: int) -> bytes | None:
        parsed = parse_frame(frame)
        assert parsed is not None
        adp = parsed.datagrams[0].address & 0xFFFF
        if adp == (-1 & 0xFFFF):
            return None  # slave 1 does not answer
        got = engine.process(frame)
        if adp == (-2 & 0xFFFF) and index == 0x55 and got is not None:  # slave 2: the EEPROM reports no acknowledge
            back = bytearray(got)
            at = 14 + 2 + 10  # the first datagram's data (the status): Ethernet, EtherCAT and datagram headers
            back[at:at + 2] = (0x2000).to_bytes(2, "little")
            assert parse_frame(bytes(back)).datagrams[0].data[:2] == b"\x00\x20"  # type: ignore[union-attr]
            return bytes(back)
        return got

    found = with_sii(exchange, [Found(0, 0x02), Found(1, 0x02), Found(2, 0x02)])
    assert found[0].sii is not None and image[:len(found[0].sii)] == found[0].sii
    assert found[1].sii is None and found[2].sii is None


def test_through_kickcat_a_running_slave_stays_in_preop_and_nothing_is_written(monkeypatch: pytest.MonkeyPatch) -> None:
    """KickCAT's binding requests a state for the whole bus only: a slave found in SAFE-OP/OP is left in PRE-OP
    with a note naming why, and the project's put-back (which would write its startup list) is not called."""
    from ecattool.online import targets

    called: list[object] = []
    monkeypatch.setattr(bus_state, "read_states", lambda ifname, sii=False: [Found(0, 0x08), Found(1, 0x02)])
    monkeypatch.setattr(targets, "isolated_bus", lambda spec, opener, limits=None: targets.LiveBus(
        spec, [Slave(0), Slave(1)], closer=lambda: None))  # type: ignore[list-item]
    monkeypatch.setattr("ecattool.target.kickcat.import_kickcat", lambda: None)
    bus = targets.open_bus("kickcat:eth0", reset_bus=True, put_back=lambda wanted: called.append(wanted) or [])
    bus.close()
    assert called == []
    assert bus.notes == ["slave 0 (OP) was left in PRE-OP: KickCAT's Python binding takes no single slave to a state, "
                         "ecattool cannot take it back to OP (pysoem:IF can)"]
