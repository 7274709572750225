"""A project drive's ``plant:`` as the simulator's :class:`~ecattool.sim.drive.plant.PlantParams`: the family's
default plant with the project's values, the load reflected to the motor through the scaling's mechanics."""

from __future__ import annotations

import math
from typing import Literal

from ecattool.project.slave import Slave
from ecattool.sim.drive.plant import PlantParams, plant_for, reflected_inertia


def _mechanics(slave: Slave) -> tuple[float, float]:
    """(gear ratio motor:load, metres per load revolution of a linear transmission; 0 for a rotary one) from the
    drive's ``scaling:`` (1, 0 where there is none)."""
    data = slave.drive.scaling
    if not isinstance(data, dict):
        return 1.0, 0.0
    from ecattool.scaling.model import gear_from, transmission_from

    gear = gear_from(data.get("gear")) if data.get("gear") is not None else None
    ratio = float(gear.ratio) if gear is not None else 1.0
    trans = transmission_from(data.get("transmission")) if data.get("transmission") is not None else None
    travel = float(trans.travel) if trans is not None and trans.output == "length" else 0.0
    return ratio, travel


def plant_params(slave: Slave) -> PlantParams | Literal["ideal"] | None:
    """The plant the project sets for ``slave`` (None: none set, the family's default stands)."""
    cfg = slave.drive.plant
    if cfg is None or cfg == "ideal":
        return cfg
    base = plant_for(slave.family)
    changes: dict[str, float] = {}
    names = {"motor_inertia": "motor_inertia", "viscous_friction": "viscous", "coulomb_friction": "coulomb",
             "rated_torque": "rated_torque", "peak_torque": "peak_torque", "position_bandwidth": "position_bandwidth",
             "damping": "damping", "velocity_feedforward": "velocity_feedforward", "velocity_tau": "velocity_tau"}
    for field, name in names.items():
        value = getattr(cfg, field)
        if value is not None:
            changes[name] = value
    if cfg.max_speed is not None:
        changes["max_speed"] = cfg.max_speed * 2 * math.pi / 60
    if cfg.load_inertia is not None or cfg.load_mass is not None:
        ratio, travel = _mechanics(slave)
        changes["load_inertia"] = reflected_inertia(gear_ratio=ratio, load_inertia=cfg.load_inertia or 0.0,
                                                    load_mass=cfg.load_mass or 0.0, travel_per_load_rev_m=travel)
    return base.with_(**changes)
