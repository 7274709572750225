"""Every SDO upload is bounded by what the object can hold (issue 37 item 1, "bound what ecattool asks of a
master"): the caller that knows the object's type passes its size, each target asks its master for exactly that
(pysoem: ``sdo_read(..., size)``, SOEM's buffer; KickCAT: the read buffer; the simulator: the value's length) and
a reply larger than that is one :class:`SdoTooLarge` naming the slave and the object. Where the type is not known
the bound is documented: SOEM's default buffer, then one try of UNKNOWN_SIZE_MAX. In process, with the fake pysoem
(tests/target/fake_pysoem.py, which refuses a reply larger than its buffer as SOEM does: PacketError 3) and the simulator.
"""

from __future__ import annotations

from typing import Any

import pytest

from ecattool.errors import SdoTooLarge
from ecattool.online.dictionary import typed
from ecattool.online.targets import sim_bus
from ecattool.online.objects import read_value
from ecattool.online.scan import scan_slave
from ecattool.sim import Drive
from ecattool.target.base import UNKNOWN_SIZE_FIRST, UNKNOWN_SIZE_MAX
from ecattool.target.kickcat import KickcatSlave
from ecattool.target.pysoem import PysoemTarget
from tests.target.fake_pysoem import VirtualClock, make_module


def _pysoem(profile: str = "hdt") -> tuple[PysoemTarget, Drive, list[int]]:
    """A fake-pysoem master with one drive; the list collects the buffer size of every ``sdo_read``."""
    drive = Drive.from_profile(profile)
    clock = VirtualClock()
    target = PysoemTarget("eth0", pysoem_module=make_module([drive]), clock=clock.now, sleep=clock.sleep,
                          keep_cycling=False)
    fake = target.slaves()[0].raw  # type: ignore[attr-defined]
    sizes: list[int] = []
    real = fake.sdo_read

    def sdo_read(index: int, subindex: int, size: int = 0, ca: bool = False, **kw: Any) -> bytes:
        sizes.append(size)
        return bytes(real(index, subindex, size, ca, **kw))

    fake.sdo_read = sdo_read
    return target, drive, sizes


def _answer(drive: Drive, index: int, subindex: int, data: bytes) -> None:
    """The drive answers ``data`` to an upload of ``index:subindex`` (a hostile or broken slave)."""
    sdo = drive.sdo  # the drive's SDO access part answers the uploads
    real = sdo._upload
    sdo._upload = lambda i, s: data if (i, s) == (index, subindex) else real(i, s)  # type: ignore[method-assign]


def test_a_typed_read_asks_soem_for_exactly_the_type_size() -> None:
    target, drive, sizes = _pysoem()
    slave = target.slaves()[0]
    t = typed(slave)  # the built-in HDT family types the objects
    v = read_value(slave, t, 0x1018, 1)
    assert v.value == drive.identity().vendor_id
    read_value(slave, t, 0x6060, 0)
    # a UDINT: a 4-octet buffer; an SINT: 1 octet (before: pysoem's 256-byte default for every object)
    assert sizes == [4, 1]


def test_a_reply_larger_than_the_type_is_refused_naming_the_slave_and_the_object() -> None:
    target, drive, sizes = _pysoem()
    slave = target.slaves()[0]
    t = typed(slave)
    _answer(drive, 0x1018, 1, bytes(64))  # a "UDINT" of 64 octets
    with pytest.raises(SdoTooLarge) as ei:
        read_value(slave, t, 0x1018, 1)
    assert str(ei.value) == "slave 0: 0x1018:01: the slave announced more than the 4 the object can have (refused)"
    assert sizes == [4]  # asked once: a reply that does not fit is not asked for again with a larger buffer


def test_an_unknown_type_is_bounded_soem_default_then_one_larger_try() -> None:
    target, drive, sizes = _pysoem()
    s = target.slaves()[0]
    _answer(drive, 0x2100, 0, b"x" * 300)
    assert s.sdo_upload(0x2100, 0) == b"x" * 300
    assert sizes == [UNKNOWN_SIZE_FIRST, UNKNOWN_SIZE_MAX]
    sizes.clear()
    _answer(drive, 0x2101, 0, b"x" * (UNKNOWN_SIZE_MAX + 1))
    with pytest.raises(SdoTooLarge, match=r"^slave 0: 0x2101:00: .* than the 65536 octets read of an object whose "
                                          r"type is not known"):
        s.sdo_upload(0x2101, 0)
    assert sizes == [UNKNOWN_SIZE_FIRST, UNKNOWN_SIZE_MAX]  # never a third, larger buffer


def test_scan_reads_the_identity_object_as_udints() -> None:
    target, drive, sizes = _pysoem()
    slave = target.slaves()[0]
    scanned = scan_slave(slave)
    assert scanned.coe_identity is not None and scanned.coe_identity.vendor_id == drive.identity().vendor_id
    assert sizes == [4, 4, 4, 4]  # 1018h:01-04
    _answer(drive, 0x1018, 2, bytes(64))
    scanned = scan_slave(slave)
    assert scanned.coe_identity is None
    assert any("0x1018:02: the slave announced more than the 4" in u for u in scanned.unknown), scanned.unknown


def test_the_simulator_target_checks_the_length() -> None:
    bus = sim_bus([Drive.from_profile("hdt")])
    slave = bus.slaves[0]
    assert len(slave.sdo_upload(0x1018, 1, size=4)) == 4
    _answer(slave.drive, 0x1018, 1, bytes(64))
    with pytest.raises(SdoTooLarge, match=r"^slave 0: 0x1018:01: the reply has 64 octets, more than the 4 the object"):
        slave.sdo_upload(0x1018, 1, size=4)
    assert len(slave.sdo_upload(0x1018, 1)) == 64  # no bound asked: the simulator is no hostile slave


def test_kickcat_reads_into_a_buffer_of_the_type_size() -> None:
    asked: list[int] = []

    class Access:
        COMPLETE, PARTIAL = 1, 0

    class Module:
        pass

    Module.Access = Access  # type: ignore[attr-defined]

    class Bus:
        def read_sdo(self, slave: Any, index: int, subindex: int, access: int, size: int, timeout: float) -> bytes:
            asked.append(size)
            return bytes(64) if index == 0x2000 else (0x289).to_bytes(4, "little")

    s = KickcatSlave(Bus(), object(), 3, Module)  # type: ignore[arg-type]
    assert s.sdo_upload(0x1018, 1, size=4) == (0x289).to_bytes(4, "little")
    assert s.identity().vendor_id == 0x289
    assert asked == [4, 4, 4, 4]
    with pytest.raises(SdoTooLarge, match=r"^slave 3: 0x2000:00: the reply has 64 octets, more than the 4"):
        s.sdo_upload(0x2000, 0, size=4)  # a KickCAT that returned more than its buffer: refused all the same


def test_sdo_read_cli_names_the_slave_and_object_exit_1(monkeypatch: pytest.MonkeyPatch,
                                                        capsys: pytest.CaptureFixture[str]) -> None:
    from ecattool.online import targets
    from tests.conftest import run

    real = targets.open_bus

    def hostile(spec: str, *a: Any, **kw: Any) -> Any:
        bus = real(spec, *a, **kw)
        _answer(bus.slaves[0].drive, 0x1018, 1, bytes(64))
        return bus

    monkeypatch.setattr(targets, "open_bus", hostile)
    code, out, err = run(capsys, "sdo", "read", "0x1018:01", "--target", "sim:hdt")
    assert code == 1 and out == "", out
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "slave 0: 0x1018:01: the reply has 64 octets, more than the 4" in lines[0], err
