"""What the outside world does to a drive, for tests and scripts: faults (and the family's alarms and trips),
lost communication, limit-switch inputs."""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING

from ecattool.od.model import EcState
from ecattool.sim.cia402 import State
from ecattool.sim.drive import halt_homing as hh
from ecattool.sim.drive.behaviour import CT_TRIP_CODES

if TYPE_CHECKING:
    from ecattool.sim.drive.app import DriveApp


class Injection:
    """The faults part: faults, communication loss and inputs, with the reactions the family's rules give them,
    and the error registers they latch."""

    __slots__ = ("drive", "_motion_errors", "_alarms")

    def __init__(self, drive: DriveApp) -> None:
        self.drive = drive
        #: Motion Error Register bits latched by errors until a Fault Reset (the limit-switch bits are live)
        self._motion_errors = 0
        #: the alarms present (HDT: the bitmap of the EMCY's bytes 3..6), until a Fault Reset
        self._alarms = 0

    def motion_error(self, bit: int) -> None:
        """An error sets bit ``bit`` of the family's Motion Error Register (Technosoft 2000h)."""
        drive = self.drive
        if drive.behaviour.motion_error_register is not None:
            self._motion_errors |= 1 << bit

    def motion_errors(self) -> int:
        """The Motion Error Register: the latched bits, and the limit switches (Technosoft Table 4.4.2: bit 7
        negative, bit 6 positive limit switch active, "Reset when ... inactive")."""
        drive = self.drive
        negative, positive = drive.limit_switches
        return self._motion_errors | (0x80 if negative else 0) | (0x40 if positive else 0)

    def fault_reset(self) -> None:
        """A Fault Reset has taken the drive out of FAULT: the error register 1001h is cleared, the "error reset"
        EMCY 0000h sent, the Motion Error Register's latched bits cleared but "invalid setup data" (bit 2)."""
        drive = self.drive
        self._alarms = 0
        if not drive.behaviour.error_reset_emcy:
            return
        drive._put(0x1001, 0, 0)
        self._motion_errors &= 1 << 2
        drive.emcy(0x0000)

    def inject_fault(self, code: int, data: bytes = b"") -> None:
        """A drive fault: FAULT REACTION ACTIVE -> FAULT, 603Fh = code, EMCY with the code (and, where the family
        sends one and ``data`` is not given, the bitmap of the alarms present: HDT §2.04.1)."""
        drive = self.drive
        for error, bit in drive.behaviour.motion_error_bits:
            if error == code:
                self.motion_error(bit)
        if not data:
            for error, bit in drive.behaviour.alarm_bits:
                if error == code:
                    data = self._alarm(bit)
        drive._cia_moves(drive.cia.fault(code, hh.fault_reaction_ramp(drive, code)), f"fault 0x{code:04X}")
        drive.emcy(code, data)
        drive._refresh_inputs()

    def lose_communication(self) -> None:
        """Fault injection: the process data stops (cable pulled, SM watchdog). The ESM drops from OP to
        SAFE-OP (AL status 0x001B) and the drive reacts with its abort connection option code 6007h:
        0 no action, 1 fault (EMCY 0x8100), 2 disable voltage, 3 quick stop, unless the family's
        rules say otherwise (HDT 3: quick-stop ramp and stay enabled); Control Techniques always ends in
        SWITCH ON DISABLED (7.3.1)."""
        drive = self.drive
        drive.state_machine.watchdog()
        option = drive._read_int(0x6007, 0)
        option = 1 if option is None else option
        end = self.option_end_state(0x6007, option,
                                    {0: "NO_ACTION", 1: "FAULT", 2: "SWITCH_ON_DISABLED"}.get(option, "QUICK_STOP"))
        if drive.behaviour.communication_lost_state is not None:
            end = drive.behaviour.communication_lost_state
        drive._log("cia402", reason=f"communication lost, 6007h = {option}", reaction=end)
        if end == "FAULT":
            self.inject_fault(0x8100)
        elif end == "SWITCH_ON_DISABLED":
            drive._cia_moves(drive.cia.communication_lost(), "communication lost")
        elif end == "QUICK_STOP" and drive.cia.state is State.OPERATION_ENABLED:
            option = hh.quick_stop_option(drive)
            drive.cia.quick_stop_ramp = hh.quick_stop_ramp(drive, option)
            drive._cia_moves(drive.cia.controlword_written(drive.cia.controlword & ~0x04 | 0x02, ecat_op=False,
                                                        quick_stop_option=option),
                            "communication lost: quick stop")
        elif end == "OPERATION_ENABLED":
            drive.cia.velocity = Fraction(0)
            drive.cia.target = None
            drive.cia.interrupt_homing()
        self._finish_reaction()
        drive._refresh_inputs()

    def _finish_reaction(self) -> None:
        """Out of OP no process-data cycle steps the model, yet the drive ramps down by itself: a quick stop or
        fault reaction the lost communication started runs to its end at once (the axis's cycles, counted by
        the drive's own clock)."""
        drive = self.drive
        for _ in range(10**6):  # bounded: the slowest documented ramp (HDT 6050h 60 s at 250 us) is 240000
            if drive.esm is EcState.OP or drive.cia.state not in (State.QUICK_STOP, State.FAULT_REACTION) \
                    or not drive.cia.velocity:
                return
            drive.step()

    def set_motor_supply(self, present: bool) -> None:
        """The motor supply (+Vmot) is switched on or off. Technosoft (§4.2.2 Remark 2): statusword bit 4
        follows it in every state; its loss in SWITCHED ON or OPERATION ENABLED is an undervoltage fault
        (3220h), in a lower state no fault. Other families: bit 4 (voltage enabled) clears, no reaction."""
        drive = self.drive
        drive.cia.voltage = present
        drive._log("inputs", motor_supply=present)
        code = drive.behaviour.supply_undervoltage_fault
        if not present and code is not None and drive.cia.state in (State.SWITCHED_ON, State.OPERATION_ENABLED):
            self.inject_fault(code)
            return
        drive._refresh_inputs()

    def option_end_state(self, index: int, option: int, default: str) -> str:
        """The end state the family rules give an option code (``option_code_end_states``), else ``default``."""
        drive = self.drive
        for i, v, end in drive.rules.option_code_end_states:
            if i == index and v == option:
                return str(end)
        return default

    def set_limit_switches(self, *, negative: bool = False, positive: bool = False) -> None:
        """The limit-switch inputs change: 60FDh bits per the family (HDT swaps them: bit 0 = CW =
        positive); Technosoft sends EMCY 0x5442/0x5443 when one becomes active and 0x0000 when it clears
        (§3.1.3), and statusword bit 11 (internal limit active) follows."""
        drive = self.drive
        neg_bit, pos_bit = drive.rules.limit_switch_bits
        old = drive._read_int(0x60FD, 0) or 0
        new = old & ~((1 << neg_bit) | (1 << pos_bit))
        new |= (negative << neg_bit) | (positive << pos_bit)
        drive._put(0x60FD, 0, new)
        was_neg, was_pos = bool(old >> neg_bit & 1), bool(old >> pos_bit & 1)
        drive.limit_active = negative or positive
        drive.limit_switches = (negative, positive)
        drive._log("inputs", digital_inputs=new)
        codes = drive.behaviour.limit_switch_emcy
        if codes is not None:
            for was, now, code in ((was_neg, negative, codes[0]), (was_pos, positive, codes[1])):
                if now and not was:
                    drive.emcy(code)
                elif was and not now:
                    drive.emcy(0x0000)
        hh.on_limit_switches(drive)
        drive._refresh_inputs()

    def set_load_torque(self, torque: float) -> None:
        """An external torque on the motor shaft, N·m (a load, gravity on a vertical axis); the plant's axis
        works against it (the ideal plant ignores it)."""
        drive = self.drive
        if drive.plant is not None:
            drive.plant.load_torque = float(torque)
        drive._log("inputs", load_torque=float(torque))

    def set_obstacle(self, position: int | None) -> None:
        """An obstacle at ``position`` (user units, as 6064h reads; None: taken away) that the axis cannot pass,
        on the side of it the axis is on now. On a plant it blocks the load in every mode: the demand (profile, the
        master's CSP set-points, the interpolator) runs on, the following error 60F4h grows through the plant, and
        past 6065h for 6066h ms the drive faults (8611h); with HDT's profile type -1 (torque-limited ramp, §4.07.8)
        the profile stops at it and resumes once the obstacle is gone. On the ideal plant a profile position move
        runs into it the same way (the demand is held, the error is the demand's)."""
        drive = self.drive
        internal = None if position is None else drive.units.position_to_internal(position - drive._home_offset())
        cia = drive.cia
        plant = drive.plant
        cia.obstacle_on_plant = plant is not None
        cia.set_obstacle(internal)
        if plant is not None and internal is not None:
            # the side of the obstacle the load is on: the actual position's, not the demand's
            cia.obstacle_side = 1 if internal > cia.position + Fraction(round(plant.error * 65536), 65536) else -1
        drive._log("inputs", obstacle=position)
        drive._refresh_inputs()

    def _alarm(self, bit: int) -> bytes:
        """Alarm ``bit`` is present: the EMCY's manufacturer bytes 3..7, the bitmap of every alarm present (HDT
        §2.04.1: "4 of these 5 Bytes are used to report all the current alarms of the Drive")."""
        self._alarms |= 1 << bit
        return self._alarms.to_bytes(4, "little") + b"\x00"

    def inject_hdt_alarm(self, alarm: int, code: int) -> None:
        """HDT: alarm FA_n with EMCY ``code``; EMCY bytes 3..6 carry the alarm bitmap (bit n-1 and the alarms
        already present)."""
        self.inject_fault(code, self._alarm(alarm - 1))

    def inject_trip(self, trip: int) -> None:
        """Control Techniques: drive trip number -> 603Fh per Table 9.17 (unlisted trips 0x1000)."""
        self.inject_fault(CT_TRIP_CODES.get(trip, 0x1000))
