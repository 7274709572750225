"""The plant in the drive's cycle: what the drive's demand does to its :class:`~ecattool.sim.drive.plant.Plant`
each cycle (the position or the velocity loop while the power stage is on, else the motor coasts). Apart from the
plant's physics so that the plant knows nothing of the drive."""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING

from ecattool.sim.cia402 import State
from ecattool.sim.drive.plant import Plant
from ecattool.sim.drive.velocity_mode import counts_per_rev as _counts_per_rev

if TYPE_CHECKING:
    from ecattool.sim.cia402 import Cia402
    from ecattool.sim.drive.app import DriveApp

_ENABLED, _QUICK_STOP, _FAULT_REACTION = State.OPERATION_ENABLED, State.QUICK_STOP, State.FAULT_REACTION
#: modes whose loop is the velocity loop (vl 2, PV 3, CSV 9); the others close the position loop
VELOCITY_MODES = frozenset({2, 3, 9})
#: interpolated position (CiA-402 mode 7)
_IP = 7


def counts_per_rev(drive: "DriveApp") -> float:
    """Increments per motor revolution for the plant: 608Fh where the drive has it, else the family's fixed
    resolution (:func:`ecattool.sim.drive.velocity_mode.counts_per_rev`), else 65536 (HDT's, §4.06)."""
    cpr = _counts_per_rev(drive)
    return float(cpr) if cpr else 65536.0


#: 6080h max motor speed, 607Fh max profile velocity
_MAX_MOTOR_SPEED, _MAX_PROFILE_VELOCITY = (0x6080, 0), (0x607F, 0)


def speed_limit(drive: "DriveApp", plant: Plant, mode: int) -> float:
    """The speed the plant's motor cannot pass, increments/s: the motor's own (:attr:`Plant.max_speed`), and what
    the drive is told in 6080h max motor speed and 607Fh max profile velocity, where it has them and they are not 0
    (Technosoft §15.2.3: "The speed limitation is activated when setting a value different from zero"). The unit
    is the entry's (the family's profile data: Control Techniques 7.3.17 rpm, Technosoft user velocity units);
    an entry without one: 6080h rpm (CiA-402, "taken from the motor data sheet"), 607Fh the profile velocity's
    user units. 6080h counts only in the modes the family's manual names (``Behaviour.max_motor_speed_modes``)."""
    limit = plant.max_speed
    modes = drive.behaviour.max_motor_speed_modes
    entries = drive.objects.entries
    units = drive.units
    for key in (_MAX_MOTOR_SPEED, _MAX_PROFILE_VELOCITY):
        entry = entries.get(key)
        if entry is None or (key is _MAX_MOTOR_SPEED and modes is not None and mode not in modes):
            continue
        raw = drive._read_int(*key)
        if not raw:
            continue
        unit = entry.unit.strip().lower() or ("rpm" if key is _MAX_MOTOR_SPEED else "")
        if unit == "rpm":
            value = abs(raw) * plant.counts_per_rev / 60
        else:
            fast = units.increments_per_second(units.velocity_to_internal(raw))
            value = abs(fast.numerator / fast.denominator)
        limit = min(limit, value)
    return limit


def cycle(drive: "DriveApp", plant: Plant, mode: int, dt: Fraction, pn0: int, pd0: int,
          torque: float | None = None) -> None:
    """Step ``plant`` one cycle ``dt`` after the drive's demand moved from ``pn0 / pd0`` to where its CiA-402 model
    is now (increments): the position loop or the velocity loop while the power stage is on (OPERATION ENABLED, a
    quick stop or fault reaction ramping); a torque mode's ``torque`` (N·m) made by the motor; else the motor
    coasts. Where no loop holds the axis on the demand, the demand follows the actual position."""
    cia = drive.cia
    version = drive.objects.store.version
    if plant.version != version:  # 608Fh or the cycle 60C2h may have changed
        plant.version = version
        plant.set_geometry(counts_per_rev(drive), dt.numerator / dt.denominator)
    if plant.limits_key != version or plant.limits_mode != mode:  # 6080h/607Fh or the factors written (a write
        plant.limits_key = version  # to them changes the version: core.SETTING_OBJECTS), or another mode
        plant.limits_mode = mode
        plant.speed_limit = speed_limit(drive, plant, mode)
    pn, pd = cia.pos_n, cia.pos_d
    if pd == pd0:
        moved = (pn - pn0) / pd if pn != pn0 else 0.0
    else:
        moved = (pn * pd0 - pn0 * pd) / (pd * pd0)
    state = cia.state
    if torque is not None and state is _ENABLED:
        plant.apply_torque(torque, moved)
        if cia.obstacle is not None:
            _block(cia, plant)
        _demand_follows(drive, plant)
        # the model's velocity is the axis's: a halt or quick stop ramps down from there
        cia.velocity = drive.units.velocity_from_increments_per_second(Fraction(round(plant.velocity * 65536),
                                                                                65536))
        return
    if state is _ENABLED or state is _QUICK_STOP or state is _FAULT_REACTION:
        if mode in VELOCITY_MODES and state is _ENABLED:
            sn, sd = drive.units.ratios()[4:6]
            plant.follow_velocity(cia.vel_n * sn / (cia.vel_d * sd), moved)
        else:
            # the one period Control Techniques inserts is the interpolator's in mode 7 (Behaviour.ip_delay_periods):
            # the loop takes that demand at once, not one period later again
            plant.follow_position(moved, not (mode == _IP and drive.behaviour.ip_delay_periods))
        if cia.obstacle is not None:
            _block(cia, plant)
        return
    plant.apply_torque(0.0, moved)
    if cia.obstacle is not None:
        _block(cia, plant)
    _demand_follows(drive, plant)


def _block(cia: "Cia402", plant: Plant) -> None:
    """The obstacle (``cia.obstacle``, on the side ``cia.obstacle_side`` of the load) holds the load: an axis the
    step took beyond it stands at it (the demand runs on; the following error is the plant's)."""
    obstacle = cia.obstacle
    assert obstacle is not None
    side = cia.obstacle_side
    demand = cia.pos_n / cia.pos_d
    at = obstacle.numerator / obstacle.denominator
    if (demand + plant.error - at) * side < 0:  # side: where the obstacle lies, seen from the load
        return
    plant.error = at - demand
    if plant.velocity * side > 0:
        plant.velocity = 0.0


def _demand_follows(drive: "DriveApp", plant: Plant) -> None:
    """No loop holds the axis on the demand: the demand follows the axis (in 1/65536 increments; the rest stays an
    error below that)."""
    error = plant.error
    if error:
        step = Fraction(round(error * 65536), 65536)
        if step:
            cia = drive.cia
            cia.position = cia.position + step
            plant.take_error(float(step))
