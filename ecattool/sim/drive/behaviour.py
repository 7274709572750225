"""Where the families differ: the choices each family's drive makes where the manuals leave one open (see
docs/decisions.md, "Simulator"), as data the pieces of the drive read."""

from __future__ import annotations

from dataclasses import dataclass

from ecattool import abort as A


@dataclass(frozen=True, slots=True)
class Behaviour:
    """How a family reacts where the manuals leave a choice (see docs/decisions.md, "Simulator")."""

    #: mapping entry (16xx/1Axx sub n) written while the mapping's sub-index 0 is not 0
    mapping_busy: int = A.SUBINDEX_CANNOT_BE_WRITTEN_SI0_NONZERO
    #: assignment entry (1C12/1C13 sub n) written while sub-index 0 is not 0
    assign_busy: int = A.SUBINDEX_CANNOT_BE_WRITTEN_SI0_NONZERO
    #: any write to a mapping object whose PDO is assigned (None: allowed in PRE-OP; the Control Techniques
    #: quick start rewrites 1A05h while the default 1C13h assigns it, ambiguity A4b)
    mapping_assigned: int | None = A.DATA_CANNOT_BE_STORED_STATE
    #: CiA-402 Shutdown only leaves SWITCH ON DISABLED in OP (Control Techniques 7.3.1)
    enable_needs_op: bool = False
    #: 6060h cannot change in OPERATION ENABLED / QUICK STOP ACTIVE (Control Techniques 7.3.6)
    mode_locked_when_enabled: bool = False
    #: an unsupported mode is accepted and reported with this EMCY (Technosoft 0xFF04) instead of an abort
    unsupported_mode_emcy: int | None = None
    #: 6061h follows 6060h only once OPERATION ENABLED is reached (Technosoft §4.2.3)
    mode_display_on_enable: bool = False
    #: EMCY sent when an over-long PDO is found at PRE-OP -> SAFE-OP (Technosoft 0x8220)
    pdo_length_emcy: int | None = None
    #: controlword bit 4 1 -> 0 stops a homing search (HDT §4.08.1 "1->0 stop"; CT/CiA-402 "1 = start or
    #: continue"); Technosoft only reacts to the 0 -> 1 edge (§6.3.1)
    homing_stop_on_bit4_clear: bool = True
    #: homing on the current position (35) also outside OPERATION ENABLED (Control Techniques 7.7.1, CiA-402)
    homing_current_outside_enabled: bool = False
    #: EMCY when a homing search fails (HDT FF02h, alarm FA_14 = bit 13 of the alarm bitmap) and its data
    homing_error_emcy: int | None = None
    homing_error_emcy_data: bytes = b""
    #: EMCY when a homing start names a method the drive does not have (Technosoft FF03h)
    homing_unavailable_emcy: int | None = None
    #: 6064h = sensor position + 607Ch at all times (HDT §4.06.6), not only when homing ends
    home_offset_continuous: bool = False
    #: a homing start while a search runs is ignored with statusword bit 7 (warning) set (Technosoft §4.2.2)
    homing_busy_warning: bool = False
    #: statusword bit 4 = motor supply present in every state; SWITCHED ON / OPERATION ENABLED need it, and its
    #: loss there is an undervoltage fault with this code (Technosoft §4.2.2 Remark 2, EMCY 3220h); None: bit 4
    #: is the CiA-402 "voltage enabled" of the power stage
    supply_undervoltage_fault: int | None = None
    #: the error codes whose fault reaction follows 605Eh (a ramp before FAULT); None: every fault
    #: (CiA-402). Technosoft §4.4.11 "non-fatal errors": under-/over-voltage, drive and motor over-temperature,
    #: communication error (EMCY codes of Table 3.1.3); HDT §4.03.10's table: 3220h, 8611h; Control Techniques
    #: 7.3.5 "ignored if the drive is tripped" (every simulated fault is a trip): none
    fault_reaction_codes: frozenset[int] | None = None
    #: the largest following-error window in increments whatever 6065h says (HDT §4.06.5: 32,768 pulses)
    following_error_cap: int | None = None
    #: 6066h and 6068h count control-loop samples, not ms (Technosoft §7.2.11: "The value is given in control
    #: loop time which is by default 1ms")
    window_times_in_samples: bool = False
    #: 6065h = 0 with 6066h = 0 is a setup that has not set the supervision (Technosoft §7.2.10: "Default value
    #: -", "automatically set in Drive Setup by modifying the Position control error"): no supervision
    following_error_zero_unset: bool = False
    #: vl velocity mode reads controlword bits 4-6 (enable ramp, ramp unlock, enable reference: HDT §4.11.1,
    #: CiA-402); Control Techniques' controlword has no vl bits (Table 7.1), its ramp always runs
    vl_ramp_bits: bool = True
    #: interpolated position runs only while controlword bit 4 "enable ip mode" is 1 (HDT §4.09.1, CiA-402)
    ip_enable_bit: bool = True
    #: interpolation periods between a 60C1h record and the demand reaching it (Control Techniques 7.4.3: 1)
    ip_delay_periods: int = 0
    #: a 60FFh written before profile velocity is entered does not start a motion until it is written again
    #: (Technosoft §10.1 Remark 2)
    pv_needs_new_target: bool = False
    #: profile position with bit 5 = 0 takes a set-point given during a move only once that move has ended, and
    #: keeps set-point acknowledge until then (Technosoft §7.1.1, HDT §4.07.3; :mod:`.pp_setpoints`)
    pp_single_setpoint: bool = False
    #: ... acquiring 607Ah at the end of the move if bit 4 is still 1, and clearing bit 12 there (HDT §4.07.3);
    #: else the set-point of the rising edge, bit 12 cleared once bit 4 is 0 as well (Technosoft §7.1.1)
    pp_acquire_at_end: bool = False
    #: controlword bit 11 makes a relative set-point additive (Technosoft §7.1)
    pp_additive_bit11: bool = False
    #: 6086h = 3 (S-curve) with bit 5 = 1 is a command error (Technosoft §7.1.2 Remark)
    scurve_single_setpoint_only: bool = False
    #: statusword bit 15 "Axis on": the power stage is enabled (Technosoft Table 4.2.3)
    axis_on_bit15: bool = False
    #: statusword bit 8 "homing executing" and bit 7 "warning" in homing (Technosoft §4.2.2)
    homing_busy_bits: bool = False
    #: the Motion Error Register the drive keeps (Technosoft 2000h, Table 4.4.2), None: none
    motion_error_register: int | None = None
    #: EMCY code -> the bit of the Motion Error Register it sets (Technosoft Table 4.4.2 with the codes of
    #: Table 3.1.3); a Fault Reset clears them (2325: "the error is reset using a Fault Reset command")
    motion_error_bits: tuple[tuple[int, int], ...] = ()
    #: a Fault Reset out of FAULT clears 1001h and sends the "error reset" EMCY 0000h (Technosoft 1781 "00xx
    #: Error Reset or No Error", Control Techniques Table 9.17 "0x0000 Error reset / No error")
    error_reset_emcy: bool = True
    #: objects the drive keeps equal, both ways ((index, sub), (index, sub)): Control Techniques 7.3.17 "changing
    #: the value of this object [6080h] will also change Pr 1.06"
    linked_objects: tuple[tuple[tuple[int, int], tuple[int, int]], ...] = ()
    #: a positioning mode (``FamilyRules.dc_required_modes``) selected in OP without DC sends the module to
    #: SAFE-OP (Control Techniques 7.4 NOTE: "may result in the SM-EtherCAT module going into the
    #: SAFE-OPERATIONAL state (Pr MM.04 = 4)")
    dc_mode_in_op_drops_to_safeop: bool = False
    #: CSP reads controlword bit 6 (relative: 607Ah is added to the position, Technosoft §13.1.1) and 2086h = 1
    #: (the speed limited to 6081h, Technosoft §13.2)
    csp_options: bool = False
    #: 608Fh reports the drive's encoder resolution, not the table default (Control Techniques A24)
    encoder_resolution_reported: bool = False
    #: the module shows the ESM state in its slot menu (MM.04) and writes its drive parameters on SAFE-OP -> OP
    #: (Control Techniques 5.5, 7.3.1)
    module_menu: bool = False
    #: 6046h max <= min is refused with 0609 0030h (HDT §4.11.6)
    vl_min_max_checked: bool = False
    #: 604Bh/604Ch refuse 0, and 6046h sub 1/2 overwrite 6047h (Control Techniques 7.5.4, 7.5.9, 7.5.10)
    vl_factors_nonzero: bool = False
    #: the state lost communication ends in whatever 6007h says (Control Techniques 7.3.1: SWITCH ON DISABLED)
    communication_lost_state: str | None = None
    #: EMCY codes for the (negative, positive) limit switch becoming active, 0000h when it clears (Technosoft)
    limit_switch_emcy: tuple[int, int] | None = None
    #: the EEPROM objects, drive reset and FoE setup of Technosoft (:mod:`.memory`)
    eeprom_objects: bool = False
    #: the jerk of 6086h = 3: "2023h" (Technosoft jerk time, ms), "2011h/2021h" (HDT profile jerk or rounding
    #: time per 201Ah bit 2), "" none
    scurve_jerk: str = ""
    #: 6086h = -1 is HDT's "linear ramp with torque limit" (§4.07.8)
    torque_limited_profile: bool = False
    #: the halt and quick-stop ramps: "604Eh" (HDT: 604Eh over 6050h/6051h), "6083h" (Technosoft: slow-down
    #: 6083h, quick-stop 6085h), "" CiA-402 (6084h / 6085h)
    halt_ramps: str = ""
    #: a halt in profile position uses the profile deceleration 6084h (HDT §4.07)
    pp_halt_uses_6084: bool = False
    #: 210Bh bit 12 keeps the position when homing ends (Technosoft §6.3.3)
    home_keeps_position_bit: bool = False
    #: homing methods 15, 16, 31, 32 are refused when written (HDT §4.08.3, CT Table 7.59)
    homing_reserved_refused: bool = False
    #: homing method 0 homes on the position zeroed at power-on (HDT §4.08.3)
    homing_zero_is_power_on: bool = False
    #: how the manual converts user units (:func:`ecattool.sim.units.units_for`): "technosoft", "hdt", "cia402"
    units: str = "cia402"
    #: what 607Eh reverses (:mod:`.polarity`): "targets+actuals" (Technosoft §5.1.1, in PP/PV/CSP/CSV),
    #: "targets" (HDT §4.05.11), "" not read
    polarity: str = ""
    #: profile position keeps the ramps of a positioning until the motor stands, takes 6081h at once (HDT §4.07.3)
    pp_ramps_at_standstill: bool = False
    #: a quick stop in vl or profile torque ramps along 6049h (option 1/5) and 604Ah (2/6) (Control Techniques 7.6:
    #: "When using profile torque mode object 0x604A vl_velocity_quick_stop will be used in the event of a quick
    #: stop"; docs/decisions.md)
    vl_quick_stop_ramps: bool = False
    #: PP bit 10 waits for the position window 6067h held for 6068h (Technosoft §7.2.12)
    pp_position_window: bool = False
    #: EMCY code -> bit of the alarm bitmap the drive's EMCY bytes 3..6 carry, every alarm present set (HDT §2.04.1
    #: "every single bit of the bytes 3,4,5, and 6 identify an alarm", the FA_n table and the error code table of
    #: §2.08.2, matched by the alarms' names); () : the drive sends no bitmap
    alarm_bits: tuple[tuple[int, int], ...] = ()
    #: the modes in which 6080h "max motor speed" limits the motor (Technosoft §15.2.3: "when the mode of operation
    #: is CST or External Torque value"); None: every mode (Control Techniques 7.3.17 "used to protect the motor")
    max_motor_speed_modes: frozenset[int] | None = None
    #: Disable Voltage out of OPERATION ENABLED (transition 9) follows 605Ch as Disable Operation does (Technosoft
    #: Table 4.1.1 transition 9: "The drive will execute the instructions from Object 605Ch: Disable operation
    #: option code and finally transition into Switch on disabled state"); CiA-402: the power stage off at once
    disable_voltage_uses_605c: bool = False

    @property
    def supply_bit_always(self) -> bool:
        return self.supply_undervoltage_fault is not None


#: HDT: EMCY error code (§2.08.2, seeds/003 lines 383-420) -> alarm bit FA_(n+1) (§2.04.1, lines 103-131), where the
#: two tables name the same alarm (FF0Bh "Hall sensors error" and 8130h "Life Guard Error" match no one FA_n: left out)
HDT_ALARM_BITS: tuple[tuple[int, int], ...] = (
    (0x7600, 0),  # FA_01 error parameters storage / "Parameter memorization error"
    (0xFF01, 1),  # FA_02 error offset currents / "Current offset error"
    (0x2340, 2),  # FA_03 power overcurrent / "Power circuit overcurrent"
    (0x3210, 3),  # FA_04 over-voltage DC bus
    (0xFF08, 7),  # FA_08 secure disable
    (0x7120, 8),  # FA_09 over temperature motor
    (0x7110, 9),  # FA_10 braking resistor
    (0x3220, 11),  # FA_12 under voltage DC bus
    (0x8611, 12),  # FA_13 position error / "Following Error  Position error"
    (0xFF02, 13),  # FA_14 error home position
    (0xFF03, 14),  # FA_15 warning I2t inverter
    (0xFF04, 15),  # FA_16 warning I2t motor
    (0xFF05, 16),  # FA_17 warning over speed
    (0xFF09, 17),  # FA_18 secure disable error 1
    (0xFF07, 20),  # FA_21 fault memory / "Memory Fault"
    (0xFF0A, 21),  # FA_22 motor phases error
)

BEHAVIOURS: dict[str, Behaviour] = {
    "technosoft-ipos": Behaviour(
        mapping_busy=A.DATA_CANNOT_BE_STORED_STATE, assign_busy=A.DATA_CANNOT_BE_STORED_STATE,
        unsupported_mode_emcy=0xFF04, mode_display_on_enable=True, pdo_length_emcy=0x8220,
        homing_stop_on_bit4_clear=False, homing_unavailable_emcy=0xFF03, homing_busy_warning=True,
        supply_undervoltage_fault=0x3220, fault_reaction_codes=frozenset({0x3210, 0x3220, 0x4280, 0x4310, 0x8100}),
        pv_needs_new_target=True, pp_single_setpoint=True, pp_additive_bit11=True, scurve_single_setpoint_only=True,
        axis_on_bit15=True, homing_busy_bits=True, motion_error_register=0x2000,
        motion_error_bits=((0x8100, 0), (0x2340, 1), (0x6100, 2), (0x8611, 3), (0x7500, 4), (0x7300, 5),
                           (0x2310, 8), (0x8331, 9), (0x4280, 10), (0x4310, 11), (0x3210, 12), (0x3220, 13),
                           (0x9000, 14), (0x5441, 15)),
        csp_options=True, limit_switch_emcy=(0x5442, 0x5443), eeprom_objects=True, scurve_jerk="2023h",
        halt_ramps="6083h", home_keeps_position_bit=True, units="technosoft",
        polarity="targets+actuals", pp_position_window=True, disable_voltage_uses_605c=True,
        max_motor_speed_modes=frozenset({10}),
        window_times_in_samples=True, following_error_zero_unset=True,
    ),
    "hdt": Behaviour(alarm_bits=HDT_ALARM_BITS, following_error_cap=32768, homing_error_emcy=0xFF02, homing_error_emcy_data=(1 << 13).to_bytes(4, "little") + b"\x00",
                     home_offset_continuous=True, fault_reaction_codes=frozenset({0x3220, 0x8611}),
                     pp_single_setpoint=True, pp_acquire_at_end=True, vl_min_max_checked=True,
                     scurve_jerk="2011h/2021h", torque_limited_profile=True, halt_ramps="604Eh",
                     pp_halt_uses_6084=True, homing_reserved_refused=True, homing_zero_is_power_on=True,
                     units="hdt", polarity="targets", pp_ramps_at_standstill=True),
    "controltechniques": Behaviour(enable_needs_op=True, mode_locked_when_enabled=True, mapping_assigned=None,
                                   homing_current_outside_enabled=True, fault_reaction_codes=frozenset(),
                                   vl_ramp_bits=False, ip_enable_bit=False, ip_delay_periods=1,
                                   linked_objects=(((0x6080, 0), (0x2001, 6)),), dc_mode_in_op_drops_to_safeop=True,
                                   encoder_resolution_reported=True, module_menu=True, vl_factors_nonzero=True,
                                   communication_lost_state="SWITCH_ON_DISABLED", homing_reserved_refused=True,
                                   vl_quick_stop_ramps=True),
    # an ESI's 6065h = 6066h = 0 is a window nobody set (as Technosoft's "Default value -"): no supervision
    "generic": Behaviour(homing_current_outside_enabled=True, following_error_zero_unset=True),
}

def _trip_table() -> dict[int, int]:
    """Control Techniques trip number -> 603Fh error code, SM-EtherCAT Table 9.17 (CT 3124-3165). Where the
    OCR'd table names a trip twice the product decides, and the simulated drive is a Unidrive SP: 32 is "PH"
    (0x3130; "32 - t038" under 0x6200 is trip 38), 189 is "Enc1 (SP Only)" (0x7300; "O.cL (SK Only)" under
    0x2200): docs/decisions.md. Trips the table does not list are "Generic error" 0x1000."""
    rows: dict[int, tuple[int, ...]] = {
        0x0000: (0,), 0x2200: (109,), 0x2300: (3, 20, 104), 0x3000: (8,), 0x3130: (32, 107),
        0x3200: (1, 2, 5, 9, 108), 0x3210: (106,), 0x4200: (21, 22, 23, 27, 102, 105),
        0x5000: (*range(200, 216), 217, 218, 219, *range(220, 233)), 0x5530: (31, 36, 37),
        0x6200: (10, 38, *range(40, 100), 101, *range(112, 161), *range(168, 175), 216), 0x6320: (199,),
        0x7112: (4, 19, 103), 0x7200: (33,), 0x7300: (14, 15, 16, *range(161, 168), 176, 189, *range(190, 199)),
        0x7510: (30,), 0x7600: (175, *range(177, 189)), 0x9000: (6,),
    }
    table: dict[int, int] = {}
    for code, trips in rows.items():
        for trip in trips:
            table.setdefault(trip, code)
    return table


#: Control Techniques trip number -> 603Fh error code (SM-EtherCAT Table 9.17)
CT_TRIP_CODES = _trip_table()
