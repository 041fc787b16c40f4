"""Traction control on the rover: the slip NMPC of :mod:`wheelterrain.control.mpc` per wheel,
against the in-process rover (:func:`wheelterrain.cosim.rover.simulate`).

Why a speed term
    On the single-wheel rig the carriage speed is imposed, so the wheel's slip is its
    controller's to choose. On a rover the four wheels share one chassis speed, and the slip of
    steady motion is set by the force balance (the self-propelled slip on level ground). A
    controller that tracks slip alone moves the speed instead: on level ground any speed is an
    equilibrium at that slip, and a soft patch (more resistance at the same slip) slows the
    rover with nothing to bring it back. So each wheel's controller weighs both: the slip
    error and the relative speed error, each against the rover's steady motion on the nominal
    soil (:func:`wheelterrain.cosim.rover.steady_level_motion`). ``speed_weight`` sets the
    trade: 0 is slip alone.

Prediction (per wheel)
    The single-wheel model of the MPC (the FMUs' Functions: terrain_dynamic and the rig's
    equations) as a quarter rover: the wheel's static axle load on a free carriage carrying a
    quarter of the rover's mass (the wheel's share of the weight over gravity), level ground,
    no towing force, the rover's wheel inertia and speed loop. The soil each controller
    predicts with is the terrain map's at its wheel's position when it solves (the map is
    known; no estimator here). The plant is the whole rover: load transfer, the other wheels'
    pulls on the shared chassis and the map ahead are what the quarter model leaves out, and
    the feedback at every interval is what corrects them.

Loop
    The rover settles for :data:`SETTLE` s on its speed loops (rover.drive 1 with the common
    reference as the command: the contact's entry angle has an infinite derivative at zero
    sinkage, where no NLP starts), then every ``interval`` each wheel's controller solves from
    that wheel's state and its speed command is held over the interval.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from wheelterrain import compiled
from wheelterrain.control import mpc
from wheelterrain.cosim import rover as rover_system
from wheelterrain.cosim import rover_scenarios
from wheelterrain.model import ground, rig, rover
from wheelterrain.parameters import INDEX

SETTLE = rover_scenarios.TRACKING_FROM  # s on the speed loops before the controllers take over
SPEED_WEIGHT = 1.0
"""Default weight of the relative speed error against the slip error (mpc.Settings). Measured
on soft-patch (Earth): 0.01 lets the speed stray 3.8 % RMS, 0.1 0.5 %, 1 0.08 %, 10 and 100
0.04 %, the wheels' slip RMS 0.022 throughout; below 0.01 the plan leaves the soil."""
SCENARIOS = rover_scenarios.TRACKED_SCENARIOS
"""The scenarios the controllers run: level ground (each prediction is a level quarter rover)."""


def wheel_rig(p: Mapping[str, float], wheel: str) -> dict[str, float]:
    """The rig parameters of ``wheel``'s quarter-rover prediction (module doc)."""
    load = rover.static_axle_loads(p)[wheel]
    values = {
        "rig.load": load, "rig.mass": load / p["rover.gravity"],
        "rig.rim_speed": p["rover.rim_speed"], "rig.slip_paper": 0.0,
        "rig.slip_radius": p["rover.slip_radius"],
        "rig.wheel_inertia": p["rover.wheel_inertia"],
        "rig.speed_bandwidth": p["rover.speed_bandwidth"], "rig.drive": rig.DRIVE_SPEED,
        "rig.carriage": rig.CARRIAGE_FREE, "rig.towing_force": 0.0, "rig.slope": 0.0}
    for name, value in values.items():
        rig.check(name, value)
    return values


@dataclass
class RoverControl:
    """What :func:`run` returns besides the rover's record."""

    result: rover_system.RoverResult
    slip_reference: float
    speed_reference: float
    solve_times: np.ndarray  # s, every wheel's every solve
    failures: int  # solves that did not succeed (the shifted plan was applied)
    settings: mpc.Settings


def default_settings(p: Mapping[str, float]) -> mpc.Settings:
    """The real-time iteration (compiled where a C compiler is), 30 x 20 ms, the rover's motor
    torque limit, and the speed term."""
    return mpc.Settings(solver="rti", compiled=compiled.compiler() is not None,
                        torque_limit=p["rover.motor_torque_limit"], speed_weight=SPEED_WEIGHT)


def run(soil: rover_system.Soil, rover_values: Mapping[str, float], stop: float,
        settings: mpc.Settings | None = None,
        progress: Callable[[float], None] | None = None) -> RoverControl:
    """The rover for ``stop`` s with an NMPC per wheel commanding its speed (module doc);
    ``progress(t)``: the simulated time after every block of steps."""
    p = {**rover.defaults(), **rover_values, "rover.drive": rover.DRIVE_SPEED}
    settings = (settings or default_settings(p)).check()
    block = round(settings.interval / rover_system.STEP)
    if block < 1 or not math.isclose(block * rover_system.STEP, settings.interval,
                                     rel_tol=1e-9):
        raise mpc.MPCError(f"interval = {settings.interval!r} s is out of range; valid: a whole "
                           f"number of the rover's steps of {rover_system.STEP:g} s")
    slip_ref, speed_ref = rover_scenarios.steady_level_motion(soil, p)
    controllers = {w: mpc.Controller(settings, wheel_rig(p, w)) for w in rover.WHEELS}
    common = p["rover.rim_speed"] / p["rover.slip_radius"]
    commands = dict.fromkeys(rover.WHEELS, common)
    base = soil.base.vector()
    map_values = soil.map_values()
    solve_times: list[float] = []
    failures = 0
    n_states = len(rover.STATES)

    def control(t: float, x: list) -> list:
        nonlocal failures
        if t >= SETTLE - 1e-9:
            s = dict(zip(rover.STATES, x[:n_states], strict=True))
            for k, w in enumerate(rover.WHEELS):
                z, rate = rover.wheel_kinematics(x[:n_states], p, w)
                state = [z, rate, s[f"{w}.wheel_speed"], s[f"{w}.speed_error_integral"],
                         rover.axle_speed(x[:n_states], p, w), mpc.wrap_angle(x[n_states + k]),
                         x[n_states + len(rover.WHEELS) + k]]  # its plastic sinkage
                pt = base.copy()
                pt[INDEX["ripple.phase"]] += rover.grouser_phase(p, w)  # this wheel's
                where = rover.wheel_position(p, s["position"], w)
                for name, value in zip(ground.SOIL_NAMES, ground.soil_at(where, map_values),
                                       strict=True):
                    pt[INDEX[name]] = value
                step = controllers[w].solve(state, pt, slip_ref, commands[w], speed_ref)
                solve_times.append(step.solve_time)
                failures += not step.success
                commands[w] = step.command
        return [v for w in rover.WHEELS for v in (commands[w], 0.0)]

    started = time.perf_counter()
    res = rover_system.simulate(soil, p, stop, block=block, control=control, progress=progress)
    res.wall_time = time.perf_counter() - started
    res.engine = f"{res.engine}, NMPC per wheel ({settings.solver})"
    return RoverControl(res, slip_ref, speed_ref, np.array(solve_times), failures, settings)
