"""Halt (controlword bit 8), quick stop (605Ah), fault reaction (605Eh) and homing mode (6) of the simulated drive,
per family.

The state of both lives in :class:`~ecattool.sim.cia402.Cia402`; this module decides what the option codes
and homing methods mean, reading the drive's dictionary the way the manuals describe it:

* Halt option code 605Dh. HDT §4.03.7: 0 = disable the drive -> SWITCH ON DISABLED, 1 = slow-down ramp
  (604Eh / 6050h), 2 = quick-stop ramp (604Eh / 6051h), both staying in OPERATION ENABLED. Technosoft §4.4.10:
  1 = slow-down ramp (6083h), 2 = quick-stop ramp (6085h), stay in OPERATION ENABLED; 0 and 3.. reserved.
  Control Techniques lists 605Dh without a table; generic drives follow CiA-402 (1 slow-down ramp = 6084h,
  2 quick-stop ramp = 6085h, 3/4 current/voltage limit). The end state comes from the family rules
  (``option_code_end_states``), the same data the rest of ecattool reads.
* Homing 6098h: 35 (and the generic 37) = the current position is home; HDT 0 = the home is the position
  zeroed at power-on. The simulated axis has no limit switch, home switch or index pulse connected: a method
  that needs one searches at its homing speed for :attr:`Drive.homing_search_s` and then reports a homing
  error (docs/decisions.md, "Simulator: halt and homing").
* Methods 1, 2, 17 and 18 use the limit switches, which a test can operate with
  :meth:`Drive.set_limit_switches`: the search stops at the switch, leaves it at the zero search speed and
  homes where it becomes inactive (17/18) or goes on looking for an index pulse (1/2, none connected).
* After homing the position actual value 6064h equals the home offset 607Ch (Technosoft §6.1 and §6.3.3,
  HDT §4.06.6 ``measured = sensor + home offset`` with the sensor reset to 0); HDT applies 607Ch to 6064h
  at all times.
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING

from ecattool.errors import SdoAbort
from ecattool import abort as A
from ecattool.sim.cia402 import CSP, CSV, HALT, HOMING, PP, PV, Homing, State
from ecattool.sim.drive.velocity_mode import counts_per_rev

if TYPE_CHECKING:
    from ecattool.sim.drive.behaviour import Behaviour
    from ecattool.sim.drive.app import FamilyData
    from ecattool.sim.drive.app import DriveApp

HOMING_START = 0x0010  # controlword bit 4 in homing mode
#: the modes a halt ramps down with a deceleration (the others stop within the cycle)
_HALT_RAMP_MODES = frozenset({PV, PP, HOMING, CSP, CSV})

#: methods whose home is the current position, per family (HDT 0 = zeroed at power-on is separate)
CURRENT_POSITION = {"hdt": frozenset({35}), "technosoft-ipos": frozenset({35}),
                    "controltechniques": frozenset({35}), "generic": frozenset({35, 37})}
_RESERVED = frozenset({15, 16, 31, 32})
#: methods that search for a switch, a mechanical limit or an index pulse, per family
SEARCH = {
    "hdt": frozenset(set(range(1, 35)) - _RESERVED),  # §4.08.3: 1..34 except 15, 16, 31, 32
    "technosoft-ipos": frozenset((set(range(-4, 35)) - _RESERVED) - {0}),  # §6.3.4: -4..-1, 1..14, 17..30, 33, 34
    "controltechniques": frozenset(set(range(1, 35)) - _RESERVED),  # Table 7.59
}


def reserved_method(behaviour: Behaviour, method: int) -> bool:
    """A 6098h value the drive refuses when it is written (HDT §4.08.3 "0..35 except 15, 16, 31, 32",
    Control Techniques Table 7.59 "15, 16, 31, 32 reserved": ``Behaviour.homing_reserved_refused``). Values
    outside 0..35 are refused by the entry's range (0609 0031h / 0609 0032h); Technosoft stores any INTEGER8 and
    answers at the start."""
    return behaviour.homing_reserved_refused and method in _RESERVED


def homing_kind(family: FamilyData, method: int) -> str:
    """What a homing start does with ``method``: "current" (home here), "power_on" (HDT 0: the power-on
    zero is home), "none" (0: no homing is executed), "search" (needs a switch or index pulse) or
    "unavailable" (Technosoft EMCY FF03h; generic: a reserved method). The method tables are data per family
    (:data:`CURRENT_POSITION`, :data:`SEARCH`), chosen once with the family (:class:`~.family.Family`)."""
    if method in family.homing_current:
        return "current"
    if method == 0:
        return "power_on" if family.behaviour.homing_zero_is_power_on else "none"
    methods = family.homing_search
    if methods is None:  # generic CiA-402: 1..34 standard, negative = manufacturer specific
        return "unavailable" if method in _RESERVED or method == 36 or method > 37 else "search"
    return "search" if method in methods else "unavailable"


#: limit-switch methods and whether they look for the negative (True) or positive switch (CiA-402; HDT
#: §4.08.3.b/c: 1 = CCW limit, 2 = CW limit)
LIMIT_SWITCH_METHODS = {1: True, 17: True, 2: False, 18: False}


def search_direction(method: int) -> tuple[int, int]:
    """(direction, 6099h sub-index) of the first search move (CiA-402 method figures; HDT §4.08.3:
    CW = positive). Index-pulse methods 33/34 search at the zero search speed, the others at the switch
    search speed; a positive home switch that is not active (none is connected) is searched in the
    positive direction, a negative one in the negative direction."""
    if method in (33, 34):
        return (-1 if method == 33 else 1), 2
    base = method - 16 if 17 <= method <= 30 else method
    negative = base in (1, 5, 6, 11, 12, 13, 14, -1, -3)
    return (-1 if negative else 1), 1


# --- halt ---------------------------------------------------------------------------------------------
def halt_option(drive: DriveApp) -> int:
    """605Dh, or the CiA-402 default 1 where the drive has no such object."""
    value = drive._read_int(0x605D, 0) if (0x605D, 0) in drive.objects.entries else None
    return 1 if value is None else value


def halt_deceleration(drive: DriveApp, option: int | None = None) -> Fraction | None:
    """The ramp a halt uses in profile velocity, in increments per second² (None: stop within the cycle);
    ``option`` 1 slow-down ramp, 2 quick-stop ramp (default: 605Dh)."""
    option = halt_option(drive) if option is None else option
    read = drive._read_int
    ramps = drive.behaviour.halt_ramps
    if ramps == "604Eh":
        # §4.03.7-4.03.9: deceleration = 604Eh (6042h units, x 604Ch -> rpm) / 6050h or 6051h (ms)
        time_ms = read(0x6051 if option == 2 else 0x6050, 0)
        num, den = read(0x604C, 1) or 1, read(0x604C, 2) or 1
        rpm = Fraction(read(0x604E, 0) or 0) * Fraction(num, den)
        return rpm * 65536 / 60 / Fraction(time_ms, 1000) if time_ms else None
    if ramps == "6083h":
        index = 0x6085 if option == 2 else 0x6083  # §4.4.10: slow-down ramp 6083h, quick-stop ramp 6085h
    elif option in (3, 4):
        return None  # current / voltage limit: the model has no torque, the axis stops within the cycle
    else:
        index = 0x6085 if option == 2 else (0x6084 if (0x6084, 0) in drive.objects.entries else 0x6083)
    u = drive.units
    return abs(u.increments_per_second2(u.acceleration_to_internal(read(index, 0) or 0)))


# --- controlword and mode reactions -------------------------------------------------------------------
def on_controlword(drive: DriveApp, cw: int, prev: int) -> None:
    """Halt and homing reactions to a controlword, after the state machine has moved."""
    cia = drive.cia
    if (cw ^ prev) & HALT:
        drive._log("halt", active=bool(cw & HALT), option=halt_option(drive), mode=drive.mode(),
                   state=cia.state.value)
    if cia.halted:
        option = halt_option(drive)
        if drive.option_end_state(0x605D, option, "OPERATION_ENABLED") == "SWITCH_ON_DISABLED":
            drive._cia_moves(cia.disable(), f"halt, 605Dh = {option}")
            return
    if drive.mode() != HOMING:
        return
    rising, falling = cw & ~prev, prev & ~cw
    if rising & HOMING_START and not cw & HALT:
        start_homing(drive)
    elif cia.homing is Homing.IN_PROGRESS and falling & HOMING_START and drive.behaviour.homing_stop_on_bit4_clear:
        cia.interrupt_homing()
        drive._log("homing", event="interrupted", reason="controlword bit 4 cleared")


def on_mode(drive: DriveApp) -> None:
    if drive.cia.homing is Homing.IN_PROGRESS and drive.mode() != HOMING:
        drive.cia.interrupt_homing()
        drive._log("homing", event="interrupted", reason=f"mode changed to {drive.mode()}")


def start_homing(drive: DriveApp) -> None:
    cia = drive.cia
    method = drive._read_int(0x6098, 0) if (0x6098, 0) in drive.objects.entries else 0
    method = method or 0
    kind = homing_kind(drive.family_part, method)
    enabled = cia.state is State.OPERATION_ENABLED
    outside = kind == "current" and drive.behaviour.homing_current_outside_enabled and \
        cia.state in (State.READY, State.SWITCHED_ON)
    if not (enabled or outside):
        return
    if cia.homing is Homing.IN_PROGRESS and drive.behaviour.homing_busy_warning:
        drive.homing_warning = True  # Technosoft §4.2.2 bit 7: homing called while another runs; ignored
        drive._log("homing", event="ignored", method=method, reason="a homing is already running")
        return
    drive.homing_warning = False
    drive._log("homing", event="start", method=method, procedure=kind, state=cia.state.value)
    # the search speeds up with the homing acceleration 609Ah (CiA-402; every family's manual lists it)
    if (0x609A, 0) in drive.objects.entries:
        u = drive.units
        cia.homing_acceleration = abs(u.increments_per_second2(
            u.acceleration_to_internal(drive._read_int(0x609A, 0) or 0))) or None
    if kind == "none":
        cia.homing = Homing.NOT_STARTED  # "no homing operation will be executed" (Technosoft §6.3.4)
        return
    if kind == "unavailable":
        cia.homing_failed()
        drive._log("homing", event="error", method=method, reason="method not available")
        if drive.behaviour.homing_unavailable_emcy is not None:
            drive.emcy(drive.behaviour.homing_unavailable_emcy)
        return
    if kind == "power_on":
        cia.home_found(None)  # HDT 0: the position zeroed at power-on is home; nothing moves
    elif kind == "current":
        cia.home_found(home_position(drive))
    else:
        direction, sub = search_direction(method)
        if _on_its_switch(drive, method):  # already on the limit switch: move off it first
            cia.start_homing(-direction * _speed(drive, 2), drive.homing_search_s, "leave")
        else:
            cia.start_homing(direction * _speed(drive, sub), drive.homing_search_s)
        return
    drive._log("homing", event="attained", method=method, position=drive._user_position())


def _speed(drive: DriveApp, sub: int) -> Fraction:
    """Homing speed 6099h:``sub`` (1 switch search, 2 zero search) in internal velocity units."""
    return abs(drive.units.velocity_to_internal(drive._read_int(0x6099, sub) or 0))


def _on_its_switch(drive: DriveApp, method: int) -> bool:
    negative = LIMIT_SWITCH_METHODS.get(method)
    if negative is None:
        return False
    return drive.limit_switches[0 if negative else 1]


def on_limit_switches(drive: DriveApp) -> None:
    """The limit-switch inputs changed: a limit-switch homing search finds the switch, leaves it at the zero
    search speed, and homes where it becomes inactive (17/18) or then looks for an index pulse (1/2)."""
    cia = drive.cia
    method = drive._read_int(0x6098, 0) if (0x6098, 0) in drive.objects.entries else None
    if cia.homing is not Homing.IN_PROGRESS or drive.mode() != HOMING or method not in LIMIT_SWITCH_METHODS:
        return
    on_switch = _on_its_switch(drive, method)
    direction, _ = search_direction(method)
    if cia.homing_phase == "switch" and on_switch:
        cia.start_homing(-direction * _speed(drive, 2), drive.homing_search_s, "leave")
        drive._log("homing", event="limit switch found", method=method, position=drive._user_position())
    elif cia.homing_phase == "leave" and not on_switch:
        if method in (17, 18):
            cia.home_found(home_position(drive))
            drive._log("homing", event="attained", method=method, position=drive._user_position())
        else:
            cia.start_homing(-direction * _speed(drive, 2), drive.homing_search_s, "index")
            drive._log("homing", event="limit switch left", method=method, position=drive._user_position())


def home_position(drive: DriveApp) -> Fraction | None:
    """The internal position the home gets: HDT resets the sensor to 0 (6064h = 0 + 607Ch); the others set
    6064h to 607Ch, except Technosoft with 210Bh bit 12 = 1 (position kept, §6.3.3)."""
    if drive.behaviour.home_offset_continuous:
        return Fraction(0)
    if drive.behaviour.home_keeps_position_bit and (drive._read_int(0x210B, 0) or 0) & 0x1000:
        return None
    offset = drive._read_int(0x607C, 0) if (0x607C, 0) in drive.objects.entries else 0
    return drive.units.position_to_internal(offset or 0)


def after_step(drive: DriveApp, before: Homing) -> None:
    """Log and signal a homing search that ended in this step (no switch or index pulse was found)."""
    if before is Homing.IN_PROGRESS and drive.cia.homing is Homing.ERROR:
        drive._log("homing", event="error", method=drive._read_int(0x6098, 0),
                   reason="no switch or index pulse found (none is connected)")
        code = drive.behaviour.homing_error_emcy
        if code is not None:
            drive.emcy(code, drive.behaviour.homing_error_emcy_data)


def check_method(drive: DriveApp, sub: int, value: int) -> None:
    if reserved_method(drive.behaviour, value):
        raise SdoAbort(0x6098, sub, A.INVALID_VALUE)


def halt_decel_for_step(drive: DriveApp, mode: int) -> Fraction | None:
    """The ramp a halt uses in the mode (increments/s²): profile velocity the option code's (see
    :func:`halt_deceleration`); profile position the slow-down ramp of the mode (HDT §4.07: 6084h; Technosoft
    §4.4.10: 6083h, or 6085h for option 2); a homing search the homing acceleration 609Ah; CSP and CSV the option
    code's ramp as in profile velocity (the target is ignored, statusword bit 12 = 0, while the axis slows down:
    Technosoft §14.1.2 "Target velocity ignored. When 6040h.8 Halt is set to 1"); other modes: None."""
    if not drive.cia.controlword & HALT or mode not in _HALT_RAMP_MODES:
        return None
    if mode == PV or mode == CSP or mode == CSV:
        return halt_deceleration(drive)
    if mode == HOMING:
        return drive.cia.homing_acceleration
    if drive.behaviour.pp_halt_uses_6084:
        u = drive.units
        return abs(u.increments_per_second2(u.acceleration_to_internal(drive._read_int(0x6084, 0) or 0))) or None
    return halt_deceleration(drive)


def quick_stop_option(drive: DriveApp) -> int:
    """The quick stop option code 605Ah a quick stop follows: 0-8 as stored (CiA-402 meanings; a family whose
    manual leaves 3, 4, 7 or 8 out refuses them by its value list — HDT, Control Techniques Table 7.9 — or
    stores them as reserved — Technosoft §4.4.7 — and then they act as CiA-402 defines them); a drive without
    605Ah, and any other (manufacturer-specific or reserved) value, acts as the default 2."""
    value = drive._read_int(0x605A, 0) if (0x605A, 0) in drive.objects.entries else None
    return value if value is not None and 0 <= value <= 8 else 2


def quick_stop_ramp(drive: DriveApp, option: int) -> Fraction | None:
    """The ramp of QUICK STOP ACTIVE for quick stop option code ``option`` (605Ah), increments/s²; None where the
    drive function is disabled at once (0). 1 and 5 the slow-down ramp, 2 and 6 the quick-stop ramp, each as the
    family's manual names them (:func:`halt_deceleration`: Technosoft §4.4.7 6083h / 6085h, HDT §4.03.6 604Eh
    over 6050h / 6051h, Control Techniques 7.3.2 "the deceleration value of the used mode of operations" = 6084h
    / 6085h); 3, 4, 7, 8 (current / voltage limit) the quick-stop ramp: the model has no torque
    (docs/decisions.md, "Simulator: quick stop and fault reaction")."""
    if option == 0:
        return None
    if drive.behaviour.vl_quick_stop_ramps and drive.mode() in (2, 4):
        # Control Techniques 7.5.7/7.5.8, 7.6: vl and profile torque stop along the vl ramps, 6049h (slow down)
        # and 604Ah ("the slope of the deceleration ramp for quick stop")
        return vl_ramp(drive, 0x6049 if option in (1, 5) else 0x604A)
    return halt_deceleration(drive, 1 if option in (1, 5) else 2)


def vl_ramp(drive: DriveApp, index: int) -> Fraction | None:
    """A vl ramp record (delta speed in 6042h units, delta time in s) in increments/s²; None: delta time 0 or no
    known increments per revolution (the axis stops within the cycle)."""
    speed, time = drive._read_int(index, 1), drive._read_int(index, 2)
    cpr = counts_per_rev(drive)
    if not time or cpr is None:
        return None
    num, den = drive._read_int(0x604C, 1), drive._read_int(0x604C, 2)
    dimension = Fraction(num, den) if num and den else Fraction(1)
    return Fraction(speed or 0, time) * dimension * cpr / 60


def fault_reaction_ramp(drive: DriveApp, code: int) -> Fraction | None:
    """The ramp a fault with error code ``code`` stops the axis with before FAULT (605Eh), increments/s²; None:
    FAULT at once. Only the faults the family's manual gives a reaction (``Behaviour.fault_reaction_codes``:
    Technosoft §4.4.11's non-fatal errors, HDT §4.03.10's alarm table; Control Techniques 7.3.5 "ignored if the
    drive is tripped", and each of its simulated faults is a trip). 0 disables the drive (motor free); 1 the
    slow-down ramp, 2 the quick-stop ramp; 3 (HDT: stop within the fault torque limit 201Dh; CiA-402 3/4
    current / voltage limit) the quick-stop ramp as a stand-in; Technosoft's −1 "no action" and other values:
    FAULT at once."""
    codes = drive.behaviour.fault_reaction_codes
    if (0x605E, 0) not in drive.objects.entries or (codes is not None and code not in codes):
        return None
    option = drive._read_int(0x605E, 0)
    if option not in (1, 2, 3, 4):
        return None
    return halt_deceleration(drive, 1 if option == 1 else 2) or None


#: the option code object each transition out of OPERATION ENABLED reads (CiA-402 transitions 8 Shutdown -> 605Bh,
#: 5 Disable Operation -> 605Ch; 9 Disable Voltage -> 605Ch only where ``Behaviour.disable_voltage_uses_605c``)
_DISABLE_OPTION = {State.READY: 0x605B, State.SWITCHED_ON: 0x605C, State.SWITCH_ON_DISABLED: 0x605C}


def disable_option(drive: DriveApp, to: State) -> int | None:
    """The option code (605Bh / 605Ch) a transition from OPERATION ENABLED to ``to`` follows; None: the drive has
    no such object (HDT) or the transition reads none (Disable Voltage, CiA-402 transition 9, disables at once).
    The value is the stored one: its power-on default is the family's profile data (Technosoft §4.4.8/§4.4.9:
    605Bh 0, 605Ch 1), and the entry's range is the family's (Control Techniques Tables 7.10/7.12: 0 to 1)."""
    if to is State.SWITCH_ON_DISABLED and not drive.behaviour.disable_voltage_uses_605c:
        return None
    index = _DISABLE_OPTION.get(to)
    if index is None or (index, 0) not in drive.objects.entries:
        return None
    return drive._read_int(index, 0)


def disable_ramp(drive: DriveApp, to: State) -> Fraction | None:
    """The ramp (increments/s²) the axis slows down with before the transition from OPERATION ENABLED to ``to``;
    None: the drive function is disabled at once (option code 0, the manufacturer-specific and reserved codes, a
    drive without the object). Option code 1 "slow down with slow down ramp; disable the drive function"
    (Technosoft §4.4.8/§4.4.9, Control Techniques Tables 7.11/7.13): the slow-down ramp as the quick stop's code 1
    takes it (:func:`quick_stop_ramp`: Technosoft 6083h, Control Techniques "the deceleration value of the used
    mode of operations", CiA-402 6084h)."""
    if disable_option(drive, to) != 1:
        return None
    return quick_stop_ramp(drive, 1) or None
