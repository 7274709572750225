"""The drive's memory: the Technosoft EEPROM objects (2064h-2069h, 2091h) and the drive reset 2080h, power loss
and power cycle, the EEPROM as words, and FoE setup/firmware downloads."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from ecattool import abort as A
from ecattool.errors import TargetError
from ecattool.od.model import EcState
from ecattool.sim import eeprom as ee
from ecattool.sim.drive.core import sdo_abort

if TYPE_CHECKING:
    from ecattool.sim.drive.app import DriveApp


class FoeError(TargetError):
    """An FoE write was refused; ``code`` is the FoE error code (ETG.1000.6, 0x8000…)."""

    def __init__(self, name: str, code: int, reason: str) -> None:
        self.name = name
        self.code = code
        super().__init__(f"FoE write of {name!r} refused with error 0x{code:04X}: {reason}")


class Memory:
    """The memory part: EEPROM objects, reset, power, FoE. The EEPROM itself (:class:`ecattool.sim.eeprom.Memory`,
    the drive's ``memory``) outlives a reset; a power-on restarts the application through the drive."""

    __slots__ = ("drive",)

    def __init__(self, drive: DriveApp) -> None:
        self.drive = drive

    def install_handlers(self) -> None:
        drive = self.drive
        if not drive.behaviour.eeprom_objects:
            return
        m = drive.memory

        def memory_op(index: int, op: Callable[[int], Any]) -> Callable[[int, bytes, int | None], bool]:
            def handler(sub: int, data: bytes, value: int | None) -> bool:
                try:
                    op(value or 0)
                except ee.EepromLocked:
                    raise sdo_abort(index, sub, A.DATA_CANNOT_BE_STORED) from None
                except ee.PowerLost:
                    raise
                self.sync_objects()
                drive._log("eeprom", object=f"0x{index:04X}", value=value)
                return index not in (0x2065, 0x2067)
            return handler

        def set_config(v: int) -> None:
            m.config = v

        def set_lock(v: int) -> None:
            m.locked = bool(v & 1)

        def checksum(v: int) -> None:
            if (v >> 16) < (v & 0xFFFF):
                raise sdo_abort(0x2069, 0, A.INVALID_VALUE)
            m.compute_checksum(v)

        drive._handlers_down[0x2064] = memory_op(0x2064, set_config)
        drive._handlers_down[0x2065] = memory_op(0x2065, self._eeprom_guarded(m.write_2065))
        drive._handlers_down[0x2067] = memory_op(0x2067, self._eeprom_guarded(m.write_2067))
        drive._handlers_down[0x2069] = memory_op(0x2069, checksum)
        drive._handlers_down[0x2091] = memory_op(0x2091, set_lock)
        drive._handlers_down[0x2080] = self._reset_object

        def read_2066(sub: int) -> bytes:
            v = m.read_2066()
            self.sync_objects()
            return v.to_bytes(4, "little")

        drive._handlers_up[0x2066] = read_2066

    def _eeprom_guarded(self, op: Callable[[int], None]) -> Callable[[int], None]:
        drive = self.drive
        def run(value: int) -> None:
            if drive.faults.eeprom_power_loss_after is not None:
                drive.memory.power_loss_after = drive.faults.eeprom_power_loss_after
                drive.faults.eeprom_power_loss_after = None
            op(value)
        return run

    def sync_objects(self) -> None:
        drive = self.drive
        m = drive.memory
        drive._put(0x2064, 0, m.config)
        drive._put(0x206A, 0, m.checksum)
        drive._put(0x2091, 0, int(m.locked))
        if (0x2002, 0) in drive.objects.entries:
            der = drive._read_int(0x2002, 0) or 0
            drive._put(0x2002, 0, (der | 0x8000) if m.locked else (der & 0x7FFF))

    def _reset_object(self, sub: int, data: bytes, value: int | None) -> bool | None:
        if not value:
            return True
        self.reset()
        return None

    def reset(self) -> None:
        """2080h: reset the drive (not the EtherCAT interface). RAM objects return to their defaults; the
        EEPROM keeps what was written, so the setup after the reset is what the EEPROM holds."""
        drive = self.drive
        drive._log("reset", reason="drive reset")
        locked = drive.memory.locked
        layout = drive.layout
        drive._reset_application()
        drive.memory.locked = locked
        self.sync_objects()
        drive.layout = layout

    def power_loss(self) -> None:
        drive = self.drive
        drive._log("power_loss", esm=drive.esm.value)
        drive.memory.power_loss_after = None
        drive._power_on()

    def power_cycle(self) -> None:
        """Switch the drive off and on: ESM back to INIT, RAM lost, EEPROM kept."""
        self.power_loss()

    def eeprom_words(self, start: int, count: int) -> list[int]:
        drive = self.drive
        return [drive.memory.read_word(ee.EEPROM, start + i) for i in range(count)]

    def foe_accepts(self, name: str, password: int) -> bool:
        """Whether an FoE write of ``name`` with ``password`` may start now (what the drive checks on the write
        request, before any data): True for a firmware file in BOOT, False for a setup file; FoeError (with the
        FoE error code) when it is refused."""
        drive = self.drive
        if drive.device.mailbox is None or "FoE" not in drive.device.mailbox.protocols:
            raise FoeError(name, ee.FOE_NOT_DEFINED, "the device has no FoE mailbox")
        if drive.esm is EcState.INIT:
            raise FoeError(name, ee.FOE_ACCESS_DENIED, "no mailbox in INIT")
        # §17.4.5: setup data in BOOT only from F515I on (210Ch exists from F515F)
        setup_in_boot = drive.rules.foe_setup_in_boot and (drive._read_int(0x210C, 0) or 0) == 1
        if drive.esm is EcState.BOOT and not setup_in_boot:
            if not ee.is_firmware_name(name):
                raise FoeError(name, ee.FOE_ILLEGAL, "in BOOT the drive expects a FOEFW_ firmware file (210Ch = 0)")
            if password not in ee.FIRMWARE_PASSWORDS:
                raise FoeError(name, ee.FOE_NO_RIGHTS, f"wrong firmware password 0x{password:08X}")
            return True
        if ee.is_firmware_name(name):
            raise FoeError(name, ee.FOE_BOOTSTRAP_ONLY, "firmware files are accepted only in BOOT")
        why = ee.check_setup_name(name)
        if why:
            raise FoeError(name, ee.FOE_ILLEGAL, why)
        if password != 0:
            raise FoeError(name, ee.FOE_NO_RIGHTS, "setup files need password 0")
        if drive.memory.locked:
            raise FoeError(name, ee.FOE_ACCESS_DENIED, "the EEPROM is locked (2091h)")
        return False

    def foe_write(self, name: str, data: bytes, password: int = 0) -> None:
        """An FoE download. Setup files (FOESW_…, password 0) are accepted in PRE-OP/SAFE-OP/OP, and in
        BOOT only when 210Ch = 1; firmware files (FOEFW_…) only in BOOT with the firmware password."""
        drive = self.drive
        drive._log("foe", name=name, bytes=len(data), password=password, esm=drive.esm.value)
        if self.foe_accepts(name, password):
            drive._log("foe", name=name, result="firmware accepted")
            return
        try:
            blocks = ee.parse_foe_setup(data)
        except ValueError as exc:
            raise FoeError(name, ee.FOE_ILLEGAL, str(exc)) from None
        for start, words in blocks:
            for i, w in enumerate(words):
                drive.memory.eeprom[(start + i) & 0xFFFF] = w
        drive._log("foe", name=name, result="setup written", blocks=[(b[0], len(b[1])) for b in blocks])
