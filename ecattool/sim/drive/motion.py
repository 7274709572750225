"""CiA-402 on the drive: controlword and mode reactions, the motion model stepped per process-data cycle,
and the actual values it reports (statusword, positions, velocity, error code). Halt and homing per family
are :mod:`.halt_homing`."""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING

from ecattool import abort as A
from ecattool.od.model import EcState
from ecattool.sim.cia402 import CSP, CSV, HALT, HOMING, PP, PV, Homing, Profile, State
from ecattool.sim.drive import csp_options as csp
from ecattool.sim.drive import halt_homing as hh
from ecattool.sim.drive import polarity
from ecattool.sim.drive.core import sdo_abort
from ecattool.sim.drive.plant_step import cycle as plant_cycle
from ecattool.sim.drive.supervision import limit_stop, report_actual, supervise
from ecattool.sim.drive.mode_parts import MOVED, PARTS, ModeParts
from ecattool.sim.drive.torque_mode import TORQUE_MODES
from ecattool.sim.units import floor_ratio

if TYPE_CHECKING:
    from ecattool.sim.drive.app import DriveApp

_ZERO = Fraction(0)
#: 607Dh's sub-indices 1 and 2 at the whole INTEGER32 range (no software limit)
_OPEN_LOW, _OPEN_HIGH = (-(2**31)).to_bytes(4, "little", signed=True), (2**31 - 1).to_bytes(4, "little", signed=True)
_ENABLED = State.OPERATION_ENABLED
_LIMIT_LOW, _LIMIT_HIGH = (0x607D, 1), (0x607D, 2)
#: the option code a slow-down before leaving OPERATION ENABLED followed, by the state it ended in (event reasons)
_DISABLE_WHY = {State.READY: "605Bh = 1 (shutdown)", State.SWITCHED_ON: "605Ch = 1 (disable operation)",
                State.SWITCH_ON_DISABLED: "605Ch = 1 (disable voltage)"}
#: the states with the power stage on
_POWERED = frozenset({State.OPERATION_ENABLED, State.QUICK_STOP, State.FAULT_REACTION})
#: every object :meth:`Motion._make_profile` reads
_PROFILE_OBJECTS = ((0x6081, 0), (0x6083, 0), (0x6084, 0), (0x6086, 0), (0x2023, 0), (0x201A, 0), (0x2021, 0),
                    (0x2011, 0))
#: the actual values every cycle refreshes, in the order :meth:`Motion._refresh_inputs` gives them
_ACTUAL_VALUES = ((0x6041, 0), (0x6063, 0), (0x6064, 0), (0x6062, 0), (0x606C, 0), (0x603F, 0), (0x60F4, 0))


class Motion:
    """The CiA-402 part: device control (controlword, mode), the motion stepped per process-data cycle through
    the profile generators, the mode parts and the plant, and the actual values it reports. It reads the drive's
    shared state (``cia``, ``modes``, ``plant``, ``units``, the object store), which a reset renews."""

    __slots__ = ("drive", "modes", "_profile_cache", "_soft_cache", "_home_cache")

    def __init__(self, drive: DriveApp) -> None:
        self.drive = drive
        #: the demand side of vl, PP set-points, PV windows, torque and interpolated position (:mod:`.mode_parts`);
        #: renewed with the application (:meth:`reset`)
        self.modes = ModeParts()
        self._profile_cache: tuple[tuple[object, ...], Profile] | None = None
        #: the store's version and whether 607Dh limits at it (:attr:`_soft_limits`)
        self._soft_cache: tuple[int, bool] = (0, False)
        #: the store's version and 607Ch at it (:meth:`_home_offset`)
        self._home_cache: tuple[int, int] = (0, 0)

    def reset(self) -> None:
        """The application restarts: the mode parts start afresh."""
        self.modes = ModeParts()

    def modes_snapshot(self) -> tuple[object, ...]:
        """The mode parts' state, compared by value (the quiet-cycle skip of the process data part)."""
        return self.modes.snapshot()

    def _cia_moves(self, moves: list[tuple[State, State]], why: str) -> None:
        drive = self.drive
        for old, new in moves:
            drive._log("cia402", previous=old.value, state=new.value, reason=why)
            if new is State.OPERATION_ENABLED and drive.behaviour.mode_display_on_enable:
                drive._put(0x6061, 0, drive._read_int(0x6060, 0) or 0)

    def _on_controlword(self, sub: int, value: int | None) -> None:
        drive = self.drive
        cw = value or 0
        prev = drive.cia.controlword
        option = hh.quick_stop_option(drive)
        if drive.cia.state is not State.QUICK_STOP:  # a running quick stop keeps its ramp
            drive.cia.quick_stop_ramp = hh.quick_stop_ramp(drive, option)
        moves = drive.cia.controlword_written(cw, ecat_op=drive.esm is EcState.OP, quick_stop_option=option,
                                             disable_ramp=self._disable_ramp)
        self._cia_moves(moves, f"controlword 0x{cw:04X}")
        if moves and moves[0][0] is State.FAULT:
            drive.fault_reset()
        if drive.cia.state is State.OPERATION_ENABLED and self.mode() == PP:
            if self.modes.pp.on_controlword(drive, cw, prev):  # the set-point handshake (:mod:`.pp_setpoints`)
                self._report_blocked_motion()
        hh.on_controlword(drive, cw, prev)
        self._refresh_inputs()

    def _disable_ramp(self, to: State) -> Fraction | None:
        """:func:`.halt_homing.disable_ramp`: the slow-down before Shutdown / Disable Operation (605Bh/605Ch)."""
        return hh.disable_ramp(self.drive, to)

    def _report_blocked_motion(self) -> None:
        """A set-point the drive takes but cannot move to: a profile velocity or acceleration of 0, or a position
        factor pair (608Fh, 6091h, 6092h, 6093h) with one part 0 (0:0 reads as unset, 1:1). The drive names the
        object instead of standing still silently: emergency 6320h (parameter error) whose manufacturer bytes
        carry the index (little-endian) and sub-index, and a ``motion_blocked`` event."""
        drive = self.drive
        blocked = [(i, 0) for i in (0x6081, 0x6083) if (i, 0) in drive.objects.entries and not drive._read_int(i, 0)]
        for index in (0x608F, 0x6091, 0x6092, 0x6093):
            a, b = drive._read_int(index, 1), drive._read_int(index, 2)
            if a is not None and b is not None and (a == 0) != (b == 0):
                blocked.append((index, 1 if a == 0 else 2))
        for index, sub in blocked[:1]:
            entry = drive.objects.entries.get((index, sub))
            drive._log("motion_blocked", index=index, subindex=sub, name=entry.name if entry is not None else "")
            drive.emcy(0x6320, index.to_bytes(2, "little") + bytes([sub]))

    def _on_mode(self, sub: int, value: int | None) -> None:
        drive = self.drive
        if value == PV:
            self.modes.pv.armed = False  # Technosoft §10.1 Remark 2: 60FFh must be written again
        self.modes.mode_changed()
        if drive.behaviour.dc_mode_in_op_drops_to_safeop and drive.esm is EcState.OP and not drive.dc_active() \
                and value in drive.rules.dc_required_modes:
            drive.state_machine.fall_to_safeop(A.AlStatus.DC_INVALID_SYNC, f"mode {value} needs distributed clocks")
        if not drive.behaviour.mode_display_on_enable or drive.cia.state is State.OPERATION_ENABLED:
            drive._put(0x6061, 0, value or 0)
        hh.on_mode(drive)
        self._refresh_inputs()

    def _on_target_velocity(self, sub: int, value: int | None) -> None:
        self.modes.pv.armed = True

    def _check_mode(self, sub: int, data: bytes, value: int | None) -> bool:
        drive = self.drive
        mode = value or 0
        if drive.behaviour.mode_locked_when_enabled and drive.cia.state in (State.OPERATION_ENABLED, State.QUICK_STOP) \
                and mode != self.mode():
            raise sdo_abort(0x6060, sub, A.DATA_CANNOT_BE_STORED_STATE)
        supported = drive.rules.supported_modes
        if supported and mode not in supported and mode != 0:
            if drive.behaviour.unsupported_mode_emcy is not None:
                drive.emcy(drive.behaviour.unsupported_mode_emcy)
            else:
                raise sdo_abort(0x6060, sub, A.INVALID_VALUE)
        return True

    def _check_homing_method(self, sub: int, data: bytes, value: int | None) -> bool:
        hh.check_method(self.drive, sub, value or 0)
        return True

    def mode(self) -> int:
        # every dictionary entry has a stored value, so 6061h reads as an int whenever the drive has it
        drive = self.drive
        index = 0x6061 if (0x6061, 0) in drive.objects.entries else 0x6060
        return drive._read_int(index, 0) or 0

    def step(self, cycles: int = 1) -> None:
        """Advance the motion model by ``cycles`` process-data cycles (see the drive's :meth:`cycle_time`)."""
        drive = self.drive
        dt = drive.cycle_time()
        u = drive.units
        cia = drive.cia
        mode: int | None = None
        for _ in range(cycles):
            mode = self.mode()
            drive._demand_before = (cia.pos_n, cia.pos_d)
            # an enabled axis without halt follows the target of its mode; CSP and CSV in integers (the same
            # rationals as the Fraction conversions, numerator and denominator apart), the others through
            # Cia402.step, which converts only the targets the mode moves by
            if cia.state is _ENABLED and not cia.controlword & HALT and cia.disable_to is None:
                if (drive.limit_active or self._soft_limits) and limit_stop(drive, mode, dt):
                    self._after_step(dt, mode)
                    continue
                if mode == CSP:
                    pn, pd, _, _, sn, sd = u.ratios()
                    if drive.behaviour.csp_options and csp.applies(drive):  # Technosoft bit 6 relative, 2086h
                        goal = csp.target(drive, dt)
                        cia.follow_position(goal.numerator, goal.denominator, dt, sd, sn)
                        self._after_step(dt, mode)
                        continue
                    # internal velocity units per increment/s: the inverse of increments/s per unit (sn > 0)
                    sign = polarity.target_signs(drive, mode)[0]
                    cia.follow_position((sign * (drive._read_int(0x607A, 0) or 0) - self._home_offset()) * pn, pd, dt,
                                        sd, sn)
                    self._after_step(dt, mode)
                    continue
                if mode == CSV:
                    if csp.csv_limited(drive):  # Technosoft 2086h = 1: acceleration at most 6083h
                        csp.csv_step(drive, dt)
                        self._after_step(dt, mode)
                        continue
                    _, _, vn, vd, sn, sd = u.ratios()
                    sign = polarity.target_signs(drive, mode)[1]
                    cia.follow_velocity(sign * (drive._read_int(0x60FF, 0) or 0) * vn, vd, dt, sn, sd)
                    self._after_step(dt, mode)
                    continue
                if mode in MOVED:  # vl, profile torque, interpolated position, CST: their own parts
                    self.modes.step(drive, mode, dt)
                    self.modes.after(drive, mode, dt)
                    plant = drive.plant
                    self._after_step(dt, mode, self.modes.torque.newton_metres(plant.params.rated_torque)
                                     if plant is not None and mode in TORQUE_MODES else None)
                    continue
                moving = True
            else:
                moving = False
            homing_before = cia.homing
            cia.step(
                mode, dt,
                target_position=_ZERO,
                target_velocity=u.velocity_to_internal(polarity.target_signs(drive, mode)[1]
                                                       * (drive._read_int(0x60FF, 0) or 0))
                if moving and mode == PV and self.modes.pv.target_live(drive) else _ZERO,
                profile_velocity=_ZERO, acceleration=_ZERO,
                inc_per_s=u.increments_per_second, vel_from_inc_per_s=u.velocity_from_increments_per_second,
                inc_per_s2=u.increments_per_second2, halt_deceleration=hh.halt_decel_for_step(drive, mode),
                profile=(self._profile(mode) if mode == PV else self.modes.pp.profile(drive, self._profile(mode)))
                if moving and mode in (PP, PV) else None,
            )
            if homing_before is not cia.homing:
                hh.after_step(drive, homing_before)
            if mode == PP and cia.target is None and self.modes.pp.after_step(drive, dt):
                self._report_blocked_motion()  # the set-point that waited for the move is taken
            if mode in PARTS:
                self.modes.after(drive, mode, dt)
            self._after_step(dt, mode)
        self._refresh_inputs(mode)  # the step changes no mode (6061h)

    @property
    def _soft_limits(self) -> bool:
        """607Dh narrower than the whole INTEGER32 range (compared again only when the store's version changed:
        every cycle asks)."""
        drive = self.drive
        store = drive.objects.store
        version = store.version  # a write to 607Dh changes it (core.SETTING_OBJECTS)
        cached = self._soft_cache
        if cached[0] == version:
            return cached[1]
        get = store.get
        narrow = get(_LIMIT_LOW, _OPEN_LOW) != _OPEN_LOW or get(_LIMIT_HIGH, _OPEN_HIGH) != _OPEN_HIGH
        self._soft_cache = (version, narrow)
        return narrow

    def _after_step(self, dt: Fraction, mode: int | None = None, torque: float | None = None) -> None:
        """What follows every cycle's motion: the plant's step (``torque``: the torque mode's demand in N·m, which
        the plant's motor makes instead of following a position or velocity), the following error's supervision,
        and the transitions the drive made by itself (the end of a quick stop or of a fault reaction)."""
        drive = self.drive
        cia = drive.cia
        plant = drive.plant
        if plant is not None:
            if mode is None:
                mode = self.mode()
            plant_cycle(drive, plant, mode, dt, *drive._demand_before, torque)
            supervise(drive, mode)
        elif cia.following_error:
            self._supervise_following_error(dt)
        if cia.automatic:
            done, cia.automatic = cia.automatic, []
            first = done[0][0]
            self._cia_moves(done, "fault reaction completed" if first is State.FAULT_REACTION
                            else f"quick stop completed, 605Ah = {cia.quick_stop_option}" if first is State.QUICK_STOP
                            else f"slow down completed, {_DISABLE_WHY.get(done[0][1], '')}")

    def _supervise_following_error(self, dt: Fraction) -> None:
        """A following error beyond the window 6065h (user position units) for longer than 6066h ms sets
        statusword bit 13 and faults the drive with 8611h (HDT §4.06.5: "If this period is surpassed the bit 13
        of the statusword is set to 1 and the Drive switch to the Fault state"; CiA-402 for the others). A drive
        without both objects, or 6065h = FFFFFFFFh (CiA-402: supervision off), does not supervise."""
        drive = self.drive
        cia = drive.cia
        window, timeout = drive._read_int(0x6065, 0), drive._read_int(0x6066, 0)
        if window is None or timeout is None or window == 0xFFFFFFFF or cia.state is not _ENABLED:
            return
        if abs(drive.units.position_to_user(cia.following_error)) <= window:
            cia.following_error_s = _ZERO
            return
        cia.following_error_s += dt
        if cia.following_error_s * 1000 > timeout:
            cia.following_error_bit = True
            drive._log("following_error", window=window, timeout_ms=timeout,
                      error=drive.units.position_to_user_int(cia.following_error))
            drive.inject_fault(0x8611)

    def _profile(self, mode: int) -> Profile:
        """:meth:`_make_profile`, made again only when something it reads has changed: the mode, the objects of
        :data:`_PROFILE_OBJECTS` (compared by their stored bytes), the factor objects and the dictionary (the
        store's version). A profile is never changed once made, so the same one serves every cycle between (a
        PP or PV cycle converted six values in ``Fraction``s to make it)."""
        drive = self.drive
        store = drive.objects.store
        get = store.get
        key = (mode, store.version, *[get(k) for k in _PROFILE_OBJECTS])
        cached = self._profile_cache
        if cached is not None and cached[0] == key:
            return cached[1]
        profile = self._make_profile(mode)
        self._profile_cache = (key, profile)
        return profile

    def _make_profile(self, mode: int) -> Profile:
        """What a profile move runs by, in increments (the family's reading of its manual):

        * profile velocity 6081h (PP), profile acceleration 6083h;
        * deceleration: 6084h where the drive has it (HDT §4.07, Control Techniques, generic), else 6083h
          (Technosoft: "Profile Acceleration (6083h)" is the only ramp of §7.2 and §8);
        * a jerk-limited ramp where 6086h = 3: Technosoft §7.2.5 jerk time 2023h (ms, "the time needed to reach
          the maximum acceleration starting from zero"); HDT §4.07.9/4.07.10: 2021h rounding time (ms) when
          201Ah bit 2 = 1, else profile jerk 2011h (acceleration units per second, through 6097h)."""
        drive = self.drive
        u = drive.units
        read = drive._read_int

        def acc(index: int) -> Fraction:
            return abs(u.increments_per_second2(u.acceleration_to_internal(read(index, 0) or 0)))

        velocity = abs(u.increments_per_second(u.velocity_to_internal(read(0x6081, 0) or 0))) if mode == PP else _ZERO
        up = acc(0x6083)
        down = acc(0x6084) if (0x6084, 0) in drive.objects.entries else up
        jerk_time = _ZERO
        jerk: Fraction | None = None
        if mode == PP and (read(0x6086, 0) or 0) == 3:
            if drive.behaviour.scurve_jerk == "2023h":
                jerk_time = Fraction(read(0x2023, 0) or 0, 1000)
            elif drive.behaviour.scurve_jerk == "2011h/2021h":
                if (read(0x201A, 0) or 0) & 0x4:
                    jerk_time = Fraction(read(0x2021, 0) or 0, 1000)
                else:
                    # a jerk limit, not a jerk time: up / jerk would grow the move with the acceleration
                    jerk = acc(0x2011) or None
        # HDT §4.07.8 profile type -1, "linear ramp with torque limit": the trapezoid of 0, whose generator stops
        # while an obstacle blocks the axis (the model has no torque: :meth:`set_obstacle` is the obstacle)
        # or any profile type with 201Ah bit 1 "Torque limit enabled" (HDT §4.06.10: "the position profile is
        # adapted to the measured position; when the Drive torque is no longer at its limit, then the execution of
        # the position profile is resumed")
        torque_limited = mode == PP and drive.behaviour.torque_limited_profile and (
            read(0x6086, 0) == -1 or bool((read(0x201A, 0) or 0) & 0x2))
        return Profile(velocity, up, down, jerk_time, torque_limited, jerk)

    def _refresh_inputs(self, mode: int | None = None) -> None:
        """Actual values from the state: 6041h, 6063h/6064h, 606Ch, 603Fh (``mode``: 6061h, where the caller
        has just read it)."""
        drive = self.drive
        if mode is None:
            mode = self.mode()
        cia = drive.cia
        sw = cia.statusword(mode=mode) | (0x0800 if drive.limit_active else 0)
        if mode in PARTS:
            sw |= self.modes.status_bits(drive, mode)
        behaviour = drive.behaviour
        if behaviour.homing_busy_bits and mode == HOMING and cia.homing is Homing.IN_PROGRESS:
            sw |= 0x0100 | (0x0080 if drive.homing_warning else 0)  # §4.2.2 bit 8 homing executing, 7 warning
        if behaviour.axis_on_bit15 and cia.state in _POWERED:
            sw |= 0x8000  # Technosoft Table 4.2.3: "Axis on. Power stage is enabled"
        if behaviour.motion_error_register is not None:
            drive._put(behaviour.motion_error_register, 0, drive.motion_errors())
        if drive.plant is not None:
            report_actual(drive, sw, mode)
            return
        vn, vd = drive.units.ratios()[2:4]
        # 6063h, 6064h, 606Ch: floor(position), floor(position / factor) (+ the home offset), floor(velocity /
        # factor), in integers
        user_position = self._user_position()
        error = drive.units.position_to_user_int(cia.following_error) if cia.following_error else 0
        velocity = floor_ratio(cia.vel_n, cia.vel_d, vn, vd)
        if behaviour.polarity:
            ps, vs = polarity.actual_signs(drive, mode)
            user_position, error, velocity = ps * user_position, ps * error, vs * velocity
        drive._put_all(_ACTUAL_VALUES, (sw, cia.pos_n // cia.pos_d, user_position, user_position + error, velocity,
                                       cia.fault_code, error))

    def _home_offset(self) -> int:
        """607Ch where the family adds it to the measured position at all times (HDT), else 0 (decoded again only
        when the store's version changed: every cycle asks, twice)."""
        drive = self.drive
        if not drive.behaviour.home_offset_continuous:
            return 0
        version = drive.objects.store.version  # a write to 607Ch changes it (core.SETTING_OBJECTS)
        cached = self._home_cache
        if cached[0] == version:
            return cached[1]
        value = drive._read_int(0x607C, 0) or 0
        self._home_cache = (version, value)
        return value

    def _user_position(self) -> int:
        """6064h: the position in user units (HDT: sensor position + home offset 607Ch, §4.06.6)."""
        drive = self.drive
        pn, pd = drive.units.ratios()[:2]
        return floor_ratio(drive.cia.pos_n, drive.cia.pos_d, pn, pd) + self._home_offset()

    @property
    def internal_position(self) -> int:
        """Position in the drive's internal units (increments), truncated as the drive stores it."""
        drive = self.drive
        return drive.cia.pos_n // drive.cia.pos_d

    @property
    def internal_velocity(self) -> int:
        """Velocity in internal units (Technosoft: 16.16 increments per slow-loop sample)."""
        drive = self.drive
        return drive.cia.vel_n // drive.cia.vel_d

    @property
    def cia402_state(self) -> State:
        drive = self.drive
        return drive.cia.state

    def install_handlers(self) -> None:
        drive = self.drive
        drive._after_write[0x6040] = self._on_controlword
        drive._after_write[0x6060] = self._on_mode
        drive._after_write[0x60FF] = self._on_target_velocity
        drive._handlers_down[0x6060] = self._check_mode
        drive._handlers_down[0x6098] = self._check_homing_method
