"""Operating points at which the Modelica library's functions are checked against their CasADi
Functions (tests/test_modelica.py through rumoca, tests/test_modelica_external.py through the
C): every preset, every contact form, braking, z = 0, tiny and deep sinkage, the soil's memory
pressing and lifted; chassis states, inputs and parameters; map positions."""

from __future__ import annotations

import numpy as np

from wheelterrain import presets
from wheelterrain.model import contact
from wheelterrain.modelica import reference


def points() -> list[tuple[str, list[float]]]:
    """(preset, memory-contact inputs without p) covering every form, braking, z = 0, tiny and
    deep sinkage, pressing (plastic <= z) and lifted (plastic > z)."""
    out = []
    for name in presets.available():
        for z in (0.0, 1e-7, 0.006, 0.04):
            for slip in (-0.6, 0.3, 0.8):
                plastic = z + 4e-4 if slip > 0 else 0.0
                out.append((name, [z, 0.01, slip, 0.3, plastic, 0.02, 2.0e4]))
    return out


SEED = [0.3, -0.7, 0.11, 0.5, 0.2, -0.05, 40.0]


def rover_points() -> list[dict]:
    """Chassis states, inputs and parameters covering the speed loop, a commanded speed, a
    torque command at the motor's limit, the slope ramp before and after its switch and its
    bound; map positions before, on and after a patch."""
    from wheelterrain.model import ground, rover

    rng = np.random.default_rng(3)
    base = rover.defaults()
    variants = [{}, {"rover.drive": 1, "rover.ramp_time": 10.0, "rover.slope_rate": 0.01,
                     "rover.slope_rate_after": -0.0175, "rover.slope_bound": 0.2},
                {"rover.drive": 2, "rover.motor_torque_limit": 0.05, "rover.towing_rate": 2.0},
                {"rover.gravity": 1.62}]
    soils = {**ground.defaults(), "patch.start": 0.5, "patch.end": 0.8}
    for soil, patch in zip(ground.SOIL_NAMES, ground.PATCH_NAMES, strict=True):
        soils[patch] = soils[soil] * 0.7
    points = []
    for k, variant in enumerate(variants):
        values = {**base, **variant}
        state = np.array(reference.rover_start())
        state += 0.01 * rng.standard_normal(state.size)
        state[rover.STATES.index("elapsed")] = (5.0, 30.0, 40.0, 0.0)[k]
        points.append({
            "x": state, "u": 5.0 * rng.standard_normal(len(rover.INPUTS)),
            "r": np.array([values[n] for n in rover.ROVER_NAMES]),
            "position": (0.1, 0.5, 0.79, 0.8)[k],
            "g": np.array([soils[n] for n in ground.NAMES])})
    return points


def vector_seed(name: str, size: int) -> np.ndarray:
    return np.linspace(-0.9, 1.1, size) if size > 1 else np.array([0.37])


COLUMN = {name: k for k, name in enumerate(contact.EXPORT_INPUTS[True][:-1])}
COLUMN.update(wheel_speed=2, slip_paper=2)  # the slips' inputs: taken from columns of X
COLUMN.update(slip_angle=3)  # the wheel angle's column: 0.3 rad, a slip angle of 17 deg
COLUMN.update(turn_slip=3)  # and 0.3 rad/m of turn slip: the turn kernels, both forms
COLUMN.update(mean_pressure=6)  # 20 kPa: lifted by 0.4 mm, a share of the contact left
