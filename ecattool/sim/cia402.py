"""The CiA-402 drive state machine and a simple motion model (PP, PV, CSP, CSV).

The state machine follows the transition table of CiA-402 as the three manuals print it (Technosoft
Table 4.1.1, HDT §4.03.1, Control Techniques Table 7.2); the family differences are parameters of
:class:`Cia402`:
* Control Techniques: in PRE-OP/SAFE-OP, Shutdown must not leave SWITCH ON DISABLED (7.3.1); modes of
  operation cannot change in OPERATION ENABLED or QUICK STOP ACTIVE.
* quick stop option code 605Ah: 0 disables the drive function at once (SWITCH ON DISABLED); 1..4 ramp down in
  QUICK STOP ACTIVE and then make transition 12 to SWITCH ON DISABLED by themselves ("automatic transition when
  the quick stop function is completed", CT Table 7.7); 5..8 ramp down and stay in QUICK STOP ACTIVE (and allow
  transition 16 back to OPERATION ENABLED).
* fault reaction (605Eh, the drive passes the ramp in): a fault while the axis moves holds FAULT REACTION ACTIVE
  while it ramps down, then FAULT (transition 14); without a ramp (0: disable drive, motor free) FAULT at once.

Halt (controlword bit 8) and homing (mode 6) keep their state here; what the option codes and homing methods
mean per family is decided by the drive application (``ecattool.sim.drive``), which reads the dictionary.

Profile position runs the trapezoid (or S-curve) of :mod:`ecattool.sim.ramp` planned when a set-point is taken;
profile velocity ramps up with the profile acceleration and down with the profile deceleration; a homing search
speeds up with the homing acceleration; a halt ramps PP, PV and a homing search down with the deceleration the
drive passes in, and QUICK STOP ACTIVE (option codes 5-8, where the state lasts) with the quick-stop ramp
(increments per second²; None or 0 stops within the cycle). CSP and CSV follow the master's set-points.
"""

from __future__ import annotations

from collections.abc import Callable
from enum import Enum
from fractions import Fraction

from ecattool.od.cia402 import CMD_ENABLE_OPERATION, CMD_QUICK_STOP, CMD_SHUTDOWN, CMD_SWITCH_ON, CW_ENABLE_VOLTAGE
from ecattool.od.cia402 import HALT as HALT  # the definitions, read by the drive application from here too
from ecattool.od.cia402 import STATUS_BITS
from ecattool.od.cia402 import State as State
from ecattool.od.cia402 import decode_statusword as decode_statusword
from ecattool.sim.ramp import ProfileMove
from ecattool.sim.units import reduced

#: a unit conversion of the drive (internal velocity/acceleration units <-> increments per second)
_Convert = Callable[[Fraction], Fraction]


class Profile:
    """The profile a mode moves by, as the drive reads it from its dictionary: profile velocity (6081h) in
    increments/s, acceleration (6083h) and deceleration (6084h, or the family's choice) in increments/s², and
    the jerk time in s of a jerk-limited ramp (0: trapezoidal), or the jerk in increments/s³ that limits it
    (None: the jerk time rules)."""

    __slots__ = ("velocity", "acceleration", "deceleration", "jerk_time", "torque_limited", "jerk")

    def __init__(self, velocity: Fraction, acceleration: Fraction, deceleration: Fraction,
                 jerk_time: Fraction = Fraction(0), torque_limited: bool = False,
                 jerk: Fraction | None = None) -> None:
        self.jerk = jerk
        self.velocity = abs(velocity)
        self.acceleration = abs(acceleration)
        self.deceleration = abs(deceleration)
        self.jerk_time = jerk_time
        #: the profile generator stops while the axis is blocked and adapts to the measured position (HDT
        #: §4.07.8 profile type -1, "linear ramp with torque limit")
        self.torque_limited = torque_limited


PP, PV, HOMING, CSP, CSV = 1, 3, 6, 8, 9
#: looked up once (the statusword is made every cycle)
_NOT_READY, _DISABLED, _ENABLED = State.NOT_READY, State.SWITCH_ON_DISABLED, State.OPERATION_ENABLED
_FAULT_REACTION, _FAULT = State.FAULT_REACTION, State.FAULT


class Homing(str, Enum):
    """The homing procedure as statusword bits 13/12/10 report it (Technosoft Table 6.3.3, CT Table 7.54)."""

    NOT_STARTED = "not started or interrupted"  # 0 0 1
    IN_PROGRESS = "in progress"  # 0 0 0 (0 0 1 while halted at standstill)
    ATTAINED = "attained"  # 0 1 1
    ERROR = "error"  # 1 0 0 moving / 1 0 1 at standstill


class Cia402:
    """State, controlword handling and the motion model of one axis (internal units as exact rationals).

    The position and the velocity are carried as integers, numerator and denominator in lowest terms
    (``pos_n``/``pos_d``, ``vel_n``/``vel_d``): the cyclic modes (CSP, CSV: :meth:`follow_position`,
    :meth:`follow_velocity`) and the actual values compute on them without a ``Fraction`` per operation.
    :attr:`position` and :attr:`velocity` are the same values as ``Fraction`` for everything else (made when
    first read after a change, and kept out of ``vars()``, which holds the state only)."""

    # the Fractions made from the integer pairs, cached; slots, so that vars() (the state the process data cycle
    # compares to skip a quiet cycle) holds only the pairs they are made from
    __slots__ = ("__dict__", "_position", "_velocity")

    def __init__(self, *, enable_needs_op: bool = False, supply_bit_always: bool = False) -> None:
        self.enable_needs_op = enable_needs_op
        #: statusword bit 4 shows the motor supply in every state, and SWITCHED ON / OPERATION ENABLED need
        #: it (Technosoft §4.2.2 "Motor supply voltage is present", Remark 2)
        self.supply_bit_always = supply_bit_always
        self.state = State.SWITCH_ON_DISABLED
        self.controlword = 0
        self.fault_code = 0
        self.pos_n, self.pos_d = 0, 1  # internal units
        self._position: Fraction | None = None
        self.vel_n, self.vel_d = 0, 1  # internal velocity units
        self._velocity: Fraction | None = None
        self.acceleration = Fraction(0)
        self.target: Fraction | None = None
        #: the profile move running towards ``target`` (planned on the first step after the set-point)
        self.move: ProfileMove | None = None
        #: the ramp of QUICK STOP ACTIVE (option codes 1-8), increments/s² (None: within the cycle)
        self.quick_stop_ramp: Fraction | None = None
        #: the quick stop option code the running quick stop follows (1-4 leave QUICK STOP ACTIVE at standstill)
        self.quick_stop_option = 2
        #: the ramp of FAULT REACTION ACTIVE (605Eh), increments/s² (None: FAULT at once)
        self.fault_ramp: Fraction | None = None
        #: a Shutdown / Disable Operation (/ Technosoft: Disable Voltage) whose option code 605Bh / 605Ch is 1 "slow
        #: down with slow down ramp; disable the drive function": the state it ends in once :meth:`step` has ramped
        #: the axis to standstill with :attr:`disable_ramp` (increments/s²); the drive stays OPERATION ENABLED until
        #: then. None: no such ramp runs
        self.disable_to: State | None = None
        self.disable_ramp: Fraction | None = None
        #: transitions the drive made by itself during :meth:`step` (12, 14), for the drive to report
        self.automatic: list[tuple[State, State]] = []
        #: the homing acceleration 609Ah in increments/s² (None: the search starts at full speed)
        self.homing_acceleration: Fraction | None = None
        self.target_reached = True
        self.setpoint_ack = False
        #: position demand minus actual position, increments (non-zero only while an obstacle blocks the axis)
        self.following_error = Fraction(0)
        #: an obstacle the axis cannot pass (internal position), and the side of it the axis is on
        self.obstacle: Fraction | None = None
        self.obstacle_side = 0
        #: the obstacle blocks the plant's load, not the demand (the drive is on a plant): the profile runs on and
        #: the plant's axis lags behind it; only a torque-limited profile (HDT -1) stops at it
        self.obstacle_on_plant = False
        #: the profile's position demand where it differs from the actual position (the axis is blocked)
        self.demand: Fraction | None = None
        #: statusword bit 13 in profile position: the following error is outside its window too long
        self.following_error_bit = False
        #: how long the following error has been outside its window, s
        self.following_error_s = Fraction(0)
        self.voltage = True
        self.homing = Homing.NOT_STARTED
        #: internal velocity of the homing search (set by the drive when it starts a search)
        self.homing_velocity = Fraction(0)
        #: seconds of search left before the drive gives up (no switch or index pulse is connected)
        self.homing_search_left = Fraction(0)
        #: what a search is looking for: "switch", "leave" (moving off a limit switch) or "index"
        self.homing_phase = ""

    @property
    def position(self) -> Fraction:
        """The position in internal units (increments)."""
        f = self._position
        if f is None:
            f = self._position = Fraction(self.pos_n, self.pos_d)
        return f

    @position.setter
    def position(self, value: Fraction) -> None:
        self.pos_n, self.pos_d = value.numerator, value.denominator
        self._position = value

    @property
    def velocity(self) -> Fraction:
        """The velocity in internal velocity units."""
        f = self._velocity
        if f is None:
            f = self._velocity = Fraction(self.vel_n, self.vel_d)
        return f

    @velocity.setter
    def velocity(self, value: Fraction) -> None:
        self.vel_n, self.vel_d = value.numerator, value.denominator
        self._velocity = value

    def follow_position(self, num: int, den: int, dt: Fraction, per_inc_n: int, per_inc_d: int) -> None:
        """One cycle of CSP in integers: the axis is at the target ``num / den`` (internal units, ``den`` > 0),
        its velocity what took it there in ``dt`` s, ``(target - position) / dt`` increments/s times
        ``per_inc_n / per_inc_d`` (internal velocity units per increment/s, ``per_inc_d`` > 0)."""
        pn, pd = self.pos_n, self.pos_d
        dn = dt.numerator
        if dn:
            self.vel_n, self.vel_d = reduced((num * pd - pn * den) * dt.denominator * per_inc_n,
                                             den * pd * dn * per_inc_d)
        else:
            self.vel_n, self.vel_d = 0, 1
        self._velocity = None
        self.pos_n, self.pos_d = reduced(num, den)
        self._position = None
        self.target_reached = True

    def follow_velocity(self, num: int, den: int, dt: Fraction, inc_n: int, inc_d: int) -> None:
        """One cycle of CSV in integers: the velocity is the target ``num / den`` (internal velocity units,
        ``den`` > 0) and the axis moves by it for ``dt`` s (``inc_n / inc_d``: increments/s per internal velocity
        unit, ``inc_d`` > 0)."""
        self.vel_n, self.vel_d = reduced(num, den)
        self._velocity = None
        pn, pd = self.pos_n, self.pos_d
        step_d = den * inc_d * dt.denominator
        self.pos_n, self.pos_d = reduced(pn * step_d + num * inc_n * dt.numerator * pd, pd * step_d)
        self._position = None

    @property
    def halted(self) -> bool:
        """Controlword bit 8 in OPERATION ENABLED: the axis is stopped (or stopping) by a halt."""
        return self.state is State.OPERATION_ENABLED and bool(self.controlword & HALT)

    def _stop(self) -> None:
        """The power stage leaves OPERATION ENABLED (or faults): motion and any homing search end."""
        self.disable_to = None
        self.velocity = Fraction(0)
        self.target = None
        self.move = None
        self.demand = None
        self.following_error = Fraction(0)
        self.following_error_s = Fraction(0)
        if self.homing is Homing.IN_PROGRESS:
            self.homing = Homing.NOT_STARTED

    def start_homing(self, velocity: Fraction, search_s: Fraction, phase: str = "switch") -> None:
        """Start (or move on to the next phase of) a homing search at ``velocity`` (internal units)."""
        self.homing = Homing.IN_PROGRESS
        self.homing_velocity = velocity
        self.homing_search_left = search_s
        self.homing_phase = phase
        self.target = None
        self.move = None

    def interrupt_homing(self) -> None:
        if self.homing is Homing.IN_PROGRESS:
            self.homing = Homing.NOT_STARTED
            self.velocity = Fraction(0)

    def home_found(self, position: Fraction | None) -> None:
        """Homing attained: the axis stands still; ``position`` is the new internal position (None: kept)."""
        self.homing = Homing.ATTAINED
        self.velocity = Fraction(0)
        self.target = None
        self.move = None
        if position is not None:
            self.position = position

    def homing_failed(self) -> None:
        self.homing = Homing.ERROR
        self.velocity = Fraction(0)

    def disable(self) -> list[tuple[State, State]]:
        """OPERATION ENABLED -> SWITCH ON DISABLED without a controlword command (HDT halt option 0)."""
        if self.state is not State.OPERATION_ENABLED:
            return []
        self.state = State.SWITCH_ON_DISABLED
        self._stop()
        return [(State.OPERATION_ENABLED, State.SWITCH_ON_DISABLED)]

    # --- state machine ----------------------------------------------------------------------------
    def controlword_written(self, cw: int, *, ecat_op: bool, quick_stop_option: int,
                            disable_ramp: Callable[[State], Fraction | None] | None = None
                            ) -> list[tuple[State, State]]:
        """Apply a controlword; returns the transitions made (from, to). ``disable_ramp(state)``: the ramp
        (increments/s²) a transition out of OPERATION ENABLED to ``state`` (READY: Shutdown, 605Bh; SWITCHED ON:
        Disable Operation, 605Ch; SWITCH ON DISABLED: Disable Voltage where the family's manual applies 605Ch) runs
        before the state changes, None: at once. Asked only while the axis moves."""
        prev = self.controlword
        self.controlword = cw
        moves: list[tuple[State, State]] = []

        def go(new: State) -> None:
            moves.append((self.state, new))
            self.state = new

        s = self.state
        fault_reset = bool(cw & 0x80) and not prev & 0x80
        if s is State.FAULT:
            if fault_reset:
                self.fault_code = 0
                self.following_error_bit = False
                go(State.SWITCH_ON_DISABLED)
            return moves
        if s is State.FAULT_REACTION or cw & 0x80:
            return moves
        shutdown = cw & CMD_SHUTDOWN[0] == CMD_SHUTDOWN[1]
        switch_on = cw & CMD_SWITCH_ON[0] == CMD_SWITCH_ON[1]
        enable = cw & CMD_ENABLE_OPERATION[0] == CMD_ENABLE_OPERATION[1]
        disable_voltage = not cw & CW_ENABLE_VOLTAGE
        quick_stop = cw & CMD_QUICK_STOP[0] == CMD_QUICK_STOP[1]
        if self.supply_bit_always and not self.voltage:
            # Remark 2: "cannot transition to states Switched On and Operation enabled without this bit"
            switch_on = enable = False
        if s is State.SWITCH_ON_DISABLED:
            if shutdown and (ecat_op or not self.enable_needs_op):
                go(State.READY)
        elif s is State.READY:
            if disable_voltage or quick_stop:
                go(State.SWITCH_ON_DISABLED)
            elif switch_on:
                go(State.SWITCHED_ON)
            elif enable:
                go(State.SWITCHED_ON)
                go(State.OPERATION_ENABLED)
        elif s is State.SWITCHED_ON:
            if disable_voltage or quick_stop:
                go(State.SWITCH_ON_DISABLED)
            elif shutdown:
                go(State.READY)
            elif enable:
                go(State.OPERATION_ENABLED)
        elif s is State.OPERATION_ENABLED:
            leave = (State.SWITCH_ON_DISABLED if disable_voltage else None if quick_stop else State.READY if shutdown
                     else State.SWITCHED_ON if switch_on else None)
            ramp = disable_ramp(leave) if leave is not None and disable_ramp is not None and self.vel_n else None
            if leave is not None and ramp:
                # 605Bh/605Ch = 1: slow down with the slow down ramp, then disable (the state changes in step)
                if self.disable_to is None:
                    self.disable_ramp = ramp
                    self.target = None
                    self.move = None
                    if self.homing is Homing.IN_PROGRESS:
                        self.homing = Homing.NOT_STARTED
                self.disable_to = leave
                return moves
            if not quick_stop and leave is None:
                self.disable_to = None  # Enable Operation again: the running slow-down ends, the axis follows
            if disable_voltage:
                go(State.SWITCH_ON_DISABLED)
            elif quick_stop:
                self.disable_to = None
                go(State.QUICK_STOP)
                self.target = None
                self.move = None
                if self.homing is Homing.IN_PROGRESS:
                    self.homing = Homing.NOT_STARTED
                self.quick_stop_option = quick_stop_option
                if quick_stop_option not in (5, 6, 7, 8) and not (self.quick_stop_ramp and self.velocity):
                    go(State.SWITCH_ON_DISABLED)  # 0 (disable drive function), or already at standstill
            elif shutdown:
                go(State.READY)
            elif switch_on:
                go(State.SWITCHED_ON)
        elif s is State.QUICK_STOP:
            if disable_voltage:
                go(State.SWITCH_ON_DISABLED)
            elif enable and quick_stop_option in (5, 6, 7, 8):
                go(State.OPERATION_ENABLED)
        if self.state is State.QUICK_STOP and self.quick_stop_ramp:
            return moves  # the axis ramps down in QUICK STOP ACTIVE (step)
        if self.state is not State.OPERATION_ENABLED:
            self._stop()
        return moves

    def fault(self, code: int, ramp: Fraction | None = None) -> list[tuple[State, State]]:
        """A fault: FAULT REACTION ACTIVE, then FAULT — at once, or (``ramp`` increments/s², the fault reaction
        605Eh, while the power stage is on and the axis moves) once :meth:`step` has ramped it to standstill."""
        moves: list[tuple[State, State]] = []
        self.fault_code = code
        if self.state is State.FAULT_REACTION:
            return moves  # the running reaction goes on
        if self.state is not State.FAULT:
            moves.append((self.state, State.FAULT_REACTION))
            powered = self.state in (State.OPERATION_ENABLED, State.QUICK_STOP)
            self.disable_to = None
            if ramp and powered and self.velocity:
                self.state = State.FAULT_REACTION
                self.fault_ramp = ramp
                self.target = None
                self.move = None
                if self.homing is Homing.IN_PROGRESS:
                    self.homing = Homing.NOT_STARTED
                return moves
            moves.append((State.FAULT_REACTION, State.FAULT))
            self.state = State.FAULT
        self._stop()
        return moves

    def communication_lost(self) -> list[tuple[State, State]]:
        """Leaving OP with the power stage on: the drive falls back to SWITCH ON DISABLED (a running fault
        reaction ends in FAULT at once)."""
        if self.state is State.FAULT_REACTION:
            self.state = State.FAULT
            self.fault_ramp = None
            self._stop()
            return [(State.FAULT_REACTION, State.FAULT)]
        if self.state in (State.READY, State.SWITCHED_ON, State.OPERATION_ENABLED, State.QUICK_STOP):
            old = self.state
            self.state = State.SWITCH_ON_DISABLED
            self._stop()
            return [(old, self.state)]
        return []

    def statusword(self, *, mode: int) -> int:
        state = self.state
        sw = STATUS_BITS[state] | 0x0200  # bit 9 remote
        if self.voltage and (self.supply_bit_always or (state is not _NOT_READY and state is not _DISABLED)):
            sw |= 0x0010
        if state is _FAULT_REACTION or state is _FAULT:
            sw |= 0x0008
        reached = self.target_reached
        if mode == HOMING:
            # bits 13/12/10 (Technosoft Table 6.3.3, Control Techniques Table 7.54 with bit 13 per CiA-402)
            reached = self.homing is not Homing.IN_PROGRESS and (self.homing is not Homing.ERROR or self.vel_n == 0)
            if self.homing is Homing.ATTAINED:
                sw |= 0x1000
            elif self.homing is Homing.ERROR:
                sw |= 0x2000
        halted = state is _ENABLED and self.controlword & HALT  # :attr:`halted`
        if halted:
            reached = self.vel_n == 0  # halt: 0 = decelerating, 1 = axis at standstill (HDT §4.07.2)
        if reached:
            sw |= 0x0400
        if mode == PP:
            if self.setpoint_ack:
                sw |= 0x1000
            if self.following_error_bit:
                sw |= 0x2000
        elif (mode == CSP or mode == CSV) and state is _ENABLED and not halted:
            sw |= 0x1000  # the drive follows the command value (0 = target ignored, e.g. while halted)
        return sw

    # --- motion -------------------------------------------------------------------------------------
    def new_setpoint(self, target: Fraction, *, relative: bool) -> None:
        self.target = self.position + target if relative else target
        self.move = None  # planned again from where the axis is, at the speed it has
        self.target_reached = False
        self.setpoint_ack = True

    def step(self, mode: int, dt: Fraction, *, target_position: Fraction, target_velocity: Fraction,
             profile_velocity: Fraction, acceleration: Fraction, inc_per_s: _Convert,
             vel_from_inc_per_s: _Convert, inc_per_s2: _Convert,
             halt_deceleration: Fraction | None = None, profile: Profile | None = None) -> None:
        """Advance the motion by ``dt`` seconds. Velocity/acceleration are internal units; the callables
        convert them to increments per second (per second²) and back. ``profile`` is what PP and PV move by
        (increments; without it PP runs at ``profile_velocity`` with ``acceleration`` both ways);
        ``halt_deceleration`` (increments/s²) is the ramp a halt uses; None or 0 stops within the cycle."""
        if self.state is State.QUICK_STOP or self.state is State.FAULT_REACTION:
            self._reaction_step(dt, inc_per_s, vel_from_inc_per_s)
            return
        if self.state is not State.OPERATION_ENABLED:
            self.velocity = Fraction(0)
            return
        if self.disable_to is not None:
            self._disable_step(dt, inc_per_s, vel_from_inc_per_s)
            return
        if self.controlword & HALT:
            self._halt_step(mode, dt, halt_deceleration, inc_per_s, vel_from_inc_per_s)
            return
        if profile is None and (mode == PV or mode == PP):  # only these modes move by a profile
            acc = abs(inc_per_s2(acceleration))
            profile = Profile(inc_per_s(profile_velocity), acc, acc)
        if mode == HOMING:
            if self.homing is not Homing.IN_PROGRESS:
                self.velocity = Fraction(0)
                return
            if self.homing_acceleration:
                self._ramp_to(self.homing_velocity, self.homing_acceleration, self.homing_acceleration, dt,
                              inc_per_s, vel_from_inc_per_s)
            else:
                self.velocity = self.homing_velocity
            self.position += inc_per_s(self.velocity) * dt
            self.homing_search_left -= dt
            if self.homing_search_left <= 0:
                self.homing_failed()
        elif mode == CSP:
            per_inc = Fraction(vel_from_inc_per_s(Fraction(1)))
            self.follow_position(target_position.numerator, target_position.denominator, dt, per_inc.numerator,
                                 per_inc.denominator)
        elif mode == CSV:
            inc = Fraction(inc_per_s(Fraction(1)))
            self.follow_velocity(target_velocity.numerator, target_velocity.denominator, dt, inc.numerator,
                                 inc.denominator)
        elif mode == PV:
            assert profile is not None
            if profile.acceleration == 0:
                self.velocity = target_velocity  # no ramp configured: the set-point at once
            else:
                self._ramp_to(target_velocity, profile.acceleration, profile.deceleration or profile.acceleration,
                              dt, inc_per_s, vel_from_inc_per_s)
            self.position += inc_per_s(self.velocity) * dt
            self.target_reached = self.velocity == target_velocity
        elif mode == PP:
            assert profile is not None
            self._profile_position_step(dt, profile, inc_per_s, vel_from_inc_per_s)

    def _profile_position_step(self, dt: Fraction, profile: Profile, inc_per_s: _Convert,
                               vel_from_inc_per_s: _Convert) -> None:
        """One cycle of the profile move towards the set-point (planned on its first cycle). A profile velocity
        of 0 does not move. A profile acceleration of 0 is a drive whose ramp is not known here (Technosoft's
        comes from its setup, §7.3's examples write only 6081h): it moves at the profile velocity from the first
        cycle and stops on the target (the drive reports 6083h = 0 with EMCY 6320h)."""
        if self.target is None:
            self.velocity = Fraction(0)
            return
        if profile.velocity == 0:
            return
        if profile.acceleration == 0:
            self.move = None
            remaining = self.target - self.position
            stepped = profile.velocity * dt
            if abs(remaining) <= stepped:
                self.position = self.target
                self.velocity = Fraction(0)
                self.target = None
                self.target_reached = True
            else:
                sign = 1 if remaining > 0 else -1
                self.position += sign * stepped
                self.velocity = vel_from_inc_per_s(sign * profile.velocity)
            return
        if self.move is None or self.move.target != self.target:
            self.move = ProfileMove(self.position, inc_per_s(self.velocity), self.target, profile.velocity,
                                    profile.acceleration, profile.deceleration or profile.acceleration,
                                    profile.jerk_time, dt, profile.jerk)
        position, velocity, done = self.move.step(dt)
        if self.blocked_at(position) and (profile.torque_limited or not self.obstacle_on_plant):
            self._blocked_step(position, done, profile.torque_limited)
            return
        self.demand = None
        self.following_error = Fraction(0)
        self.position = position
        self.velocity = vel_from_inc_per_s(velocity)
        if done:
            self.velocity = Fraction(0)
            self.target = None
            self.move = None
            self.target_reached = True

    def _at_standstill(self, ramp: Fraction | None, dt: Fraction, inc_per_s: _Convert, vel_from_inc_per_s: _Convert) -> bool:
        """One cycle down ``ramp`` (none: stop at once); True once the axis stands."""
        if ramp and self.velocity:
            self._slow_down(dt, ramp, inc_per_s, vel_from_inc_per_s)
        else:
            self.velocity = Fraction(0)
        return not self.velocity

    def _reaction_step(self, dt: Fraction, inc_per_s: _Convert, vel_from_inc_per_s: _Convert) -> None:
        """One cycle of a quick stop or a fault reaction: ramp down, and at standstill make the automatic
        transition — 12 (QUICK STOP ACTIVE -> SWITCH ON DISABLED, option codes 1-4) or 14 (FAULT REACTION ACTIVE
        -> FAULT)."""
        ramp = self.quick_stop_ramp if self.state is State.QUICK_STOP else self.fault_ramp
        if not self._at_standstill(ramp, dt, inc_per_s, vel_from_inc_per_s):
            return
        if self.state is State.FAULT_REACTION:
            self.automatic.append((State.FAULT_REACTION, State.FAULT))
            self.state = State.FAULT
            self.fault_ramp = None
            self._stop()
        elif self.quick_stop_option not in (5, 6, 7, 8):
            self.automatic.append((State.QUICK_STOP, State.SWITCH_ON_DISABLED))
            self.state = State.SWITCH_ON_DISABLED
            self._stop()

    def _disable_step(self, dt: Fraction, inc_per_s: _Convert, vel_from_inc_per_s: _Convert) -> None:
        """One cycle of a Shutdown / Disable Operation with option code 1: ramp down in OPERATION ENABLED, and at
        standstill make the transition (8, 5; Technosoft 9) the controlword asked for."""
        if not self._at_standstill(self.disable_ramp, dt, inc_per_s, vel_from_inc_per_s):
            return
        to = self.disable_to
        assert to is not None
        self.automatic.append((State.OPERATION_ENABLED, to))
        self.state = to
        self._stop()

    # --- an obstacle in the way ---------------------------------------------------------------------------
    def set_obstacle(self, position: Fraction | None) -> None:
        """Put an obstacle at ``position`` (internal units; None: take it away). It blocks the axis on the side
        it is on now. Taken away, a plain profile's axis is pulled to the demand it kept (the model has no
        position-loop dynamics: within the cycle); a torque-limited one plans on from where it stands."""
        self.obstacle = position
        self.obstacle_side = 0 if position is None else (1 if position > self.position else -1)
        if position is None and self.demand is not None:
            self.position = self.demand
            self.demand = None
            self.following_error = Fraction(0)
            if self.target is None:
                self.target_reached = True

    def blocked_at(self, position: Fraction) -> bool:
        """Whether ``position`` lies beyond the obstacle, seen from the axis's side of it."""
        return self.obstacle is not None and (position - self.obstacle) * self.obstacle_side > 0

    def _blocked_step(self, demand: Fraction, done: bool, torque_limited: bool) -> None:
        """The profile wants ``demand`` but the obstacle holds the axis. Torque-limited (HDT 6086h = -1): "the
        algorithm generating the position profile stops" and "adapts to the measured position" — the move is
        dropped and planned again from standstill at the obstacle next cycle, the set-point kept, no following
        error. Otherwise the profile runs on: the demand leaves the axis behind (following error)."""
        assert self.obstacle is not None
        self.position = self.obstacle
        self.velocity = Fraction(0)
        self.target_reached = False
        if torque_limited:
            self.move = None
            self.demand = None
            self.following_error = Fraction(0)
            return
        self.demand = demand
        self.following_error = demand - self.obstacle
        if done:  # the generator has finished at the set-point; the axis never got there
            self.move = None
            self.target = None

    def _halt_step(self, mode: int, dt: Fraction, deceleration: Fraction | None, inc_per_s: _Convert,
                   vel_from_inc_per_s: _Convert) -> None:
        """Halt: the pending set-point (PP target, homing search) is kept for when bit 8 clears; the axis ramps
        down with ``deceleration`` (a 0 or missing ramp stops within the cycle); CSP/CSV ignore their targets."""
        self.move = None  # a PP move resumes with a new plan from standstill
        if not deceleration or deceleration <= 0:
            self.velocity = Fraction(0)
            return
        self._slow_down(dt, deceleration, inc_per_s, vel_from_inc_per_s)

    def _slow_down(self, dt: Fraction, deceleration: Fraction, inc_per_s: _Convert,
                   vel_from_inc_per_s: _Convert) -> None:
        """One cycle of a ramp to standstill at ``deceleration`` increments/s²."""
        now = inc_per_s(self.velocity)
        if abs(now) <= deceleration * dt:
            self.velocity = Fraction(0)
            return
        now -= deceleration * dt if now > 0 else -deceleration * dt
        self.velocity = vel_from_inc_per_s(now)
        self.position += now * dt

    def _ramp_to(self, target: Fraction, acceleration: Fraction, deceleration: Fraction, dt: Fraction,
                 inc_per_s: _Convert, vel_from_inc_per_s: _Convert) -> None:
        """Velocity towards ``target`` (internal units): ``acceleration`` while the speed grows, ``deceleration``
        while it falls (increments/s²)."""
        now = inc_per_s(self.velocity)
        goal = inc_per_s(target)
        rate = acceleration if abs(goal) > abs(now) and goal * now >= 0 else deceleration
        max_change = rate * dt
        if abs(goal - now) <= max_change:
            self.velocity = target
        else:
            self.velocity = vel_from_inc_per_s(now + (max_change if goal > now else -max_change))
