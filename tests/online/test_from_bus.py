"""``project new --from-bus`` on a commissioned bus (issue 35 item 2): the project it writes lints clean and
commissions that bus. DC from the slave's registers and mode, the model the SII names among those sharing a
product code, the revision kept as found with its policy, paths as the user gave them. In process against the
simulator; the raw register read against the ESCs of the served simulator's bus engine (no network)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from ecattool.commission.runner import commission
from ecattool.online import Library, sim_bus
from ecattool.online.from_bus import project_from_bus
from ecattool.project.machine import load_machine
from ecattool.target.sim import SimTarget
from tests.conftest import ROOT

CT = "samples/controltechniques/project.yaml"
GENERIC = ROOT / "samples" / "generic_esi"
INOVANCE = "inovance_SV660_EOE_1Axis_V9.12.xml"


def _commissioned(project: str | Path) -> tuple[SimTarget, object]:
    result = load_machine(project)
    target = SimTarget.from_devices([rd.device for rd in sorted(result.slaves, key=lambda r: r.position)])
    assert commission(project, target).ok
    return target, sim_bus(target.slaves())


def _again(target: SimTarget) -> SimTarget:
    """The same drives, powered up again (a fresh simulator of their devices)."""
    return SimTarget.from_devices([s.drive.device for s in sim_bus(target.slaves()).slaves])


def test_a_digitax_st_in_csp_on_dc_is_written_as_such_lints_clean_and_commissions(tmp_path: Path) -> None:
    """The issue's case: a Digitax ST running CSP on DC came back as ``unidrive-sp`` (the SM-EtherCAT hosts share
    product code 0x00000201 and the first won) without ``dc:`` (PRJ041; with --allow-errors commission stopped at
    AL 0x0030)."""
    target, bus = _commissioned(CT)
    out = tmp_path / "machine.yaml"
    text = project_from_bus(bus, None, out)  # type: ignore[arg-type]
    out.write_text(text, encoding="utf-8")
    assert "product: digitax-st" in text, text
    assert 'dc: {opmode: "DC", cycle_ns: 1000000}  # as found: AssignActivate 0x0300' in text, text
    assert '{object: "6060:00", value: 8,' in text, text
    assert 'revision: "01.02.00"' in text and "identity: {revision: exact}" in text
    result = load_machine(out)
    assert not result.findings, [str(f) for f in result.findings]  # no PRJ041, and no PRJ044: 60C2h as found
    (rd,) = result.slaves
    assert rd.device.extra["product"] == "digitax-st" and rd.dc is not None and rd.dc.assign_activate == 0x0300
    report = commission(out, _again(target))
    assert report.ok, report.to_json()


def test_the_revision_found_is_kept_where_it_is_not_the_family_default(tmp_path: Path) -> None:
    """A Digitax ST with SM-EtherCAT firmware 01.00.00: without the revision the project would name the family's
    default (01.02.00) and commission's identity check (exact) refuses the drive."""
    src = tmp_path / "old.yaml"
    src.write_text(Path(CT).read_text(encoding="utf-8").replace(
        "      product: digitax-st\n", "      product: digitax-st\n      revision: \"01.00.00\"\n"), encoding="utf-8")
    target, bus = _commissioned(src)
    out = tmp_path / "machine.yaml"
    out.write_text(project_from_bus(bus, None, out), encoding="utf-8")  # type: ignore[arg-type]
    assert 'revision: "01.00.00"' in out.read_text(encoding="utf-8")
    assert commission(out, _again(target)).ok


def _library_link(tmp_path: Path) -> Path:
    """A library folder ``lib`` beside the project whose ESI is a symlink to a vendor folder elsewhere."""
    vendor = tmp_path / "vendor" / "inovance"
    vendor.mkdir(parents=True)
    (vendor / INOVANCE).write_bytes((GENERIC / INOVANCE).read_bytes())
    lib = tmp_path / "machine" / "lib"
    lib.mkdir(parents=True)
    os.symlink(vendor / INOVANCE, lib / INOVANCE)
    return lib


def test_an_esi_reached_through_a_symlink_is_written_as_the_path_given(tmp_path: Path) -> None:
    from ecattool.online.targets import open_bus

    lib = _library_link(tmp_path)
    out = tmp_path / "machine" / "m.yaml"
    with open_bus(f"sim:{GENERIC / INOVANCE}") as bus:
        text = project_from_bus(bus, Library(lib), out)
    assert f'esi: "lib/{INOVANCE}"' in text, text
    assert 'select: "0x000C010D:0x00010000"\n      policy: exact\n    identity: {revision: exact}' in text, text
    out.write_text(text, encoding="utf-8")
    moved = tmp_path / "elsewhere"
    (tmp_path / "machine").rename(moved)  # the project and its library, taken to another machine
    (moved / "lib" / INOVANCE).unlink()
    (moved / "lib" / INOVANCE).write_bytes((GENERIC / INOVANCE).read_bytes())
    assert not [f for f in load_machine(moved / "m.yaml").findings if f.severity.name == "ERROR"]


def test_a_library_without_the_revision_found_writes_the_policy_that_resolves_it(tmp_path: Path) -> None:
    """The slave reports a newer revision than the library's ESI: the selector keeps the revision found, the
    policy picks the library's newest not newer, and the identity check accepts at least that revision."""
    from ecattool.sim.slave import drive_for_device
    from ecattool.esi import load

    device = load(GENERIC / INOVANCE).devices[0]
    drive = drive_for_device(device)
    bus = sim_bus([drive])
    newer = device.identity.revision + 0x10000
    slave = bus.slaves[0]
    sii = bytearray(slave.sii)
    sii[0x18:0x1C] = newer.to_bytes(4, "little")  # the header's revision word (ETG.2010 word 0x0C)
    slave.sii = bytes(sii)  # (the checksum covers words 0-6 only)
    out = tmp_path / "m.yaml"
    text = project_from_bus(bus, Library(GENERIC), out)
    assert f'select: "0x000C010D:0x{newer:08X}"\n      policy: newest-not-newer' in text, text
    assert "identity: {revision: at-least}" in text
    out.write_text(text, encoding="utf-8")
    assert not [f for f in load_machine(out).findings if f.severity.name == "ERROR"]


def test_the_dc_registers_are_read_from_the_escs_before_the_bus_is_reset() -> None:
    """The raw read of the AL states (issue 35 item 4) reads the activation word 0x0980-0x0981 and the SYNC0/SYNC1
    cycles 0x09A0/0x09A4 of every slave too, frame by frame through the served simulator's bus engine: what SOEM's
    config_init clears (0x0981 := 0) is read first."""
    from ecattool.online.bus_state import read_found
    from ecattool.sim.bus.engine import Bus
    from ecattool.sim.esc import registers as R
    from ecattool.sim.slave import VirtualSlave, drive_for_device
    from ecattool.project.machine import load_machine as lp

    devices = [rd.device for rd in lp(CT).slaves] * 2
    slaves = [VirtualSlave(drive_for_device(d), __import__("ecattool.sii.builder", fromlist=["build"]).build(d)
                           .to_bytes()) for d in devices]
    engine = Bus([s.esc for s in slaves])
    esc = slaves[1].esc
    esc.mem[R.DC_SYNC0_CYCLE:R.DC_SYNC0_CYCLE + 4] = (1_000_000).to_bytes(4, "little")
    esc.mem[R.DC_SYNC1_CYCLE:R.DC_SYNC1_CYCLE + 4] = (500_000).to_bytes(4, "little")
    esc.mem[R.DC_ACTIVATION] = 0x03
    found = read_found(lambda frame, index: engine.process(frame))
    assert found is not None and [f.position for f in found] == [0, 1]
    assert (found[0].assign_activate, found[0].sync0_cycle_ns) == (0, 0)
    assert (found[1].assign_activate, found[1].sync0_cycle_ns, found[1].sync1_cycle_ns) == (0x0300, 1_000_000, 500_000)


def test_without_the_registers_the_project_says_so_and_takes_the_esi_dc_mode(tmp_path: Path) -> None:
    """A bus whose DC registers were not read (no ``found``, no simulated drive's own): a comment names what was
    not read, and a drive found in csp gets the ESI's DC OpMode."""
    target, bus = _commissioned(CT)
    for s in bus.slaves:
        s.dc_activation = None  # type: ignore[assignment]  (as a remote master's slave: nothing to ask)
    out = tmp_path / "m.yaml"
    text = project_from_bus(bus, None, out)  # type: ignore[arg-type]
    assert "# DC not read: sim gave no ESC register read" in text, text
    assert 'the ESI\'s DC OpMode DC is assumed, set your cycle\n    dc: {opmode: "DC", cycle_ns: 1000000}\n' in text
    out.write_text(text, encoding="utf-8")
    assert "PRJ041" not in {f.rule for f in load_machine(out).findings}


def test_bus_scan_names_the_model_the_sii_names() -> None:
    """``bus scan`` matches as ``project new --from-bus`` writes: the Digitax ST is not shown as a Unidrive SP."""
    from ecattool.online import scan

    _, bus = _commissioned(CT)
    (found,) = scan(bus, None)  # type: ignore[arg-type]
    assert found.match is not None and found.match.product == "digitax-st", found.match


def test_late_answers_to_frames_sent_again_are_taken_off_before_the_master_opens(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """A frame answered late is sent again; its late answer must not reach the master's socket opened next (KickCAT
    reads it as an answer to its own frame): the raw read takes it off before it closes its socket."""
    import socket

    from ecattool.online import bus_state
    from ecattool.sim.bus.engine import Bus
    from ecattool.sim.slave import VirtualSlave, drive_for_device
    from ecattool.sii.builder import build

    (rd,) = load_machine(CT).slaves
    engine = Bus([VirtualSlave(drive_for_device(rd.device), build(rd.device).to_bytes()).esc])

    class LateWire:
        """The last frame's answer comes only after it was sent again (then twice)."""

        def __init__(self) -> None:
            self.queue: list[bytes] = []
            self.sent = 0
            self.closed = False

        def send(self, frame: bytes) -> None:
            self.sent += 1
            answer = engine.process(frame)
            assert answer is not None
            if self.sent == 3:  # the last read (the DC registers)
                self.held = answer
                return
            if self.sent == 4:
                self.queue.append(self.held)  # the late answer to the first
            self.queue.append(answer)

        def settimeout(self, _: float) -> None:
            pass

        def recvfrom(self, _: int) -> tuple[bytes, tuple[str, int, int]]:
            if not self.queue:
                raise socket.timeout
            return self.queue.pop(0), ("veth", 0x88A4, socket.PACKET_HOST)

        def close(self) -> None:
            self.closed = True

    wire = LateWire()
    monkeypatch.setattr("ecattool.sim.bus.raw.open_raw", lambda ifname: wire)
    found = bus_state.read_states("veth")
    assert found is not None and found[0].assign_activate == 0 and wire.sent == 4
    assert wire.queue == []  # nothing left for the master's socket
    bus_state.settle(10)  # the socket is closed aside (bus_state._close_aside) until the master's fork
    assert wire.closed


def test_a_slave_running_sync1_gets_its_sync1_cycle_in_the_project(tmp_path: Path) -> None:
    """AssignActivate bit 10 (SYNC1 active) set in 0x0980: the SYNC1 cycle found in 0x09A4 is written as
    ``dc: sync1_cycle_ns`` (it was a comment only: the project format had no SYNC1, issue 35 item 2), reads back
    into the slave's DC and its exports, and the project lints clean. Without bit 10 no SYNC1 is written."""
    from ecattool.online.bus_state import Found
    from ecattool.project.machine import slave_config

    target, bus = _commissioned(CT)
    bus.found = [Found(0, 0x02, 0, 0x0700, 1_000_000, 250_000)]  # type: ignore[attr-defined]
    out = tmp_path / "machine.yaml"
    text = project_from_bus(bus, None, out)  # type: ignore[arg-type]
    assert "dc: {assign_activate: 0x0700, cycle_ns: 1000000, sync1_cycle_ns: 250000}" in text, text
    out.write_text(text, encoding="utf-8")
    result = load_machine(out)
    assert not result.findings, [str(f) for f in result.findings]
    (rd,) = result.slaves
    assert rd.dc is not None and (rd.dc.assign_activate, rd.dc.sync1_cycle_ns) == (0x0700, 250_000)
    assert slave_config(rd).dc_sync1_cycle_ns == 250_000
    bus.found = [bus.found[0].replace(assign_activate=0x0300)]  # type: ignore[attr-defined]
    assert "sync1_cycle_ns" not in project_from_bus(bus, None, out)  # type: ignore[arg-type]


def _as_through_kickcat(bus: object) -> None:
    """The slaves of ``bus`` as KickCAT's binding gives them: no SII access (the adapter's Unsupported)."""
    from ecattool.target.base import Unsupported

    def no_sii() -> bytes:
        raise Unsupported("kickcat: the Python binding gives no SII EEPROM access (use pysoem:IF)")

    for s in bus.slaves:  # type: ignore[attr-defined]
        s.sii_read = no_sii


def test_through_kickcat_the_sii_read_before_the_master_opens_names_the_model(tmp_path: Path) -> None:
    """Through KickCAT (no SII in its binding) the model by SII name fell back to the first model of the product
    code: the Digitax ST was written as ``unidrive-sp`` (issue 35, closing note). The SII is now read through each
    ESC's EEPROM interface (0x0502-0x050F) with raw frames before the master opens, as the DC registers are; here
    frame by frame through the served simulator's bus engine."""
    from ecattool.online.bus_state import read_found, with_sii
    from ecattool.sii.builder import build
    from ecattool.sim.bus.engine import Bus
    from ecattool.sim.esc import registers as R
    from ecattool.sim.slave import VirtualSlave, drive_for_device

    target, bus = _commissioned(CT)
    _as_through_kickcat(bus)
    out = tmp_path / "machine.yaml"
    assert "product: unidrive-sp" in project_from_bus(bus, None, out)  # type: ignore[arg-type]  (no SII: the first)
    devices = [s.drive.device for s in bus.slaves]  # type: ignore[attr-defined]
    images = [build(d).to_bytes() for d in devices]
    escs = [VirtualSlave(drive_for_device(d), image).esc for d, image in zip(devices, images)]
    escs[0].mem[R.DC_SYNC0_CYCLE:R.DC_SYNC0_CYCLE + 4] = (1_000_000).to_bytes(4, "little")
    escs[0].mem[R.DC_ACTIVATION] = 0x03  # the drive runs csp on DC, as commissioned
    engine = Bus(escs)
    found = with_sii(lambda frame, index: engine.process(frame), read_found(lambda f, i: engine.process(f)) or [])
    assert [images[0][:len(f.sii or b"")] == f.sii and len(f.sii or b"") > 128 for f in found] == [True]
    _, bus = _commissioned(CT)
    _as_through_kickcat(bus)
    bus.found = found  # type: ignore[attr-defined]
    text = project_from_bus(bus, None, out)  # type: ignore[arg-type]
    assert "product: digitax-st" in text, text
    out.write_text(text, encoding="utf-8")
    assert not load_machine(out).findings


def test_a_slave_without_an_identity_through_the_master_is_named_from_the_sii_read_before(tmp_path: Path) -> None:
    """KickCAT reads the identity from 1018h: a slave it cannot ask (no mailbox) has the identity of its SII."""
    from ecattool.errors import SdoTimeout
    from ecattool.online.bus_state import Found

    _, bus = _commissioned(CT)
    _as_through_kickcat(bus)
    image = __import__("ecattool.sii.builder", fromlist=["build"]).build(bus.slaves[0].drive.device).to_bytes()  # type: ignore[attr-defined]

    def no_identity() -> object:
        raise SdoTimeout(0x1018, 1, 0)

    bus.slaves[0].identity = no_identity  # type: ignore[attr-defined]
    bus.found = [Found(0, 0x02, sii=image)]  # type: ignore[attr-defined]
    text = project_from_bus(bus, None, tmp_path / "m.yaml")  # type: ignore[arg-type]
    assert "product: digitax-st" in text, text
