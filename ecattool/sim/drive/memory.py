"""The drive's memory: the Technosoft EEPROM objects (2064h-2069h, 2091h) and the drive reset 2080h, power loss
and power cycle, the EEPROM as words, and FoE setup/firmware downloads."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ecattool import abort as A
from ecattool.errors import TargetError
from ecattool.od.model import EcState
from ecattool.sim import eeprom as ee
from ecattool.sim.drive.core import DriveCore, sdo_abort


class FoeError(TargetError):
    """An FoE write was refused; ``code`` is the FoE error code (ETG.1000.6, 0x8000…)."""

    def __init__(self, name: str, code: int, reason: str) -> None:
        self.name = name
        self.code = code
        super().__init__(f"FoE write of {name!r} refused with error 0x{code:04X}: {reason}")


class Memory(DriveCore):
    """EEPROM objects, reset, power, FoE."""

    def _install_memory_handlers(self) -> None:
        if not self.behaviour.eeprom_objects:
            return
        m = self.memory

        def memory_op(index: int, op: Callable[[int], Any]) -> Callable[[int, bytes, int | None], bool]:
            def handler(sub: int, data: bytes, value: int | None) -> bool:
                try:
                    op(value or 0)
                except ee.EepromLocked:
                    raise sdo_abort(index, sub, A.DATA_CANNOT_BE_STORED) from None
                except ee.PowerLost:
                    raise
                self._sync_memory_objects()
                self._log("eeprom", object=f"0x{index:04X}", value=value)
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

        self._handlers_down[0x2064] = memory_op(0x2064, set_config)
        self._handlers_down[0x2065] = memory_op(0x2065, self._eeprom_guarded(m.write_2065))
        self._handlers_down[0x2067] = memory_op(0x2067, self._eeprom_guarded(m.write_2067))
        self._handlers_down[0x2069] = memory_op(0x2069, checksum)
        self._handlers_down[0x2091] = memory_op(0x2091, set_lock)
        self._handlers_down[0x2080] = self._reset_object

        def read_2066(sub: int) -> bytes:
            v = m.read_2066()
            self._sync_memory_objects()
            return v.to_bytes(4, "little")

        self._handlers_up[0x2066] = read_2066

    def _eeprom_guarded(self, op: Callable[[int], None]) -> Callable[[int], None]:
        def run(value: int) -> None:
            if self.faults.eeprom_power_loss_after is not None:
                self.memory.power_loss_after = self.faults.eeprom_power_loss_after
                self.faults.eeprom_power_loss_after = None
            op(value)
        return run

    def _sync_memory_objects(self) -> None:
        m = self.memory
        self._put(0x2064, 0, m.config)
        self._put(0x206A, 0, m.checksum)
        self._put(0x2091, 0, int(m.locked))
        if (0x2002, 0) in self._entries:
            der = self._read_int(0x2002, 0) or 0
            self._put(0x2002, 0, (der | 0x8000) if m.locked else (der & 0x7FFF))

    def _reset_object(self, sub: int, data: bytes, value: int | None) -> bool | None:
        if not value:
            return True
        self.reset()
        return None

    def reset(self) -> None:
        """2080h: reset the drive (not the EtherCAT interface). RAM objects return to their defaults; the
        EEPROM keeps what was written, so the setup after the reset is what the EEPROM holds."""
        self._log("reset", reason="drive reset")
        locked = self.memory.locked
        layout = self.layout
        self._reset_application()
        self.memory.locked = locked
        self._sync_memory_objects()
        self.layout = layout

    def _power_loss(self) -> None:
        self._log("power_loss", esm=self.esm.value)
        self.memory.power_loss_after = None
        self._power_on()

    def power_cycle(self) -> None:
        """Switch the drive off and on: ESM back to INIT, RAM lost, EEPROM kept."""
        self._power_loss()

    def eeprom_words(self, start: int, count: int) -> list[int]:
        return [self.memory.read_word(ee.EEPROM, start + i) for i in range(count)]

    def foe_accepts(self, name: str, password: int) -> bool:
        """Whether an FoE write of ``name`` with ``password`` may start now (what the drive checks on the write
        request, before any data): True for a firmware file in BOOT, False for a setup file; FoeError (with the
        FoE error code) when it is refused."""
        if self.device.mailbox is None or "FoE" not in self.device.mailbox.protocols:
            raise FoeError(name, ee.FOE_NOT_DEFINED, "the device has no FoE mailbox")
        if self.esm is EcState.INIT:
            raise FoeError(name, ee.FOE_ACCESS_DENIED, "no mailbox in INIT")
        # §17.4.5: setup data in BOOT only from F515I on (210Ch exists from F515F)
        setup_in_boot = self.rules.foe_setup_in_boot and (self._read_int(0x210C, 0) or 0) == 1
        if self.esm is EcState.BOOT and not setup_in_boot:
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
        if self.memory.locked:
            raise FoeError(name, ee.FOE_ACCESS_DENIED, "the EEPROM is locked (2091h)")
        return False

    def foe_write(self, name: str, data: bytes, password: int = 0) -> None:
        """An FoE download. Setup files (FOESW_…, password 0) are accepted in PRE-OP/SAFE-OP/OP, and in
        BOOT only when 210Ch = 1; firmware files (FOEFW_…) only in BOOT with the firmware password."""
        self._log("foe", name=name, bytes=len(data), password=password, esm=self.esm.value)
        if self.foe_accepts(name, password):
            self._log("foe", name=name, result="firmware accepted")
            return
        try:
            blocks = ee.parse_foe_setup(data)
        except ValueError as exc:
            raise FoeError(name, ee.FOE_ILLEGAL, str(exc)) from None
        for start, words in blocks:
            for i, w in enumerate(words):
                self.memory.eeprom[(start + i) & 0xFFFF] = w
        self._log("foe", name=name, result="setup written", blocks=[(b[0], len(b[1])) for b in blocks])
