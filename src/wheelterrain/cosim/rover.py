"""The rover's engine: four wheel-terrain contacts on the chassis of
:mod:`wheelterrain.model.rover`, stepped in process.

Two ways to run the same equations:

- in process (:func:`simulate`): one CasADi Function steps the whole system (the chassis'
  ``rover_step`` and the four contacts of :func:`wheelterrain.model.functions.build`, coupled as
  the co-simulation master couples the FMUs: the chassis' wheel states at t give the forces at
  t, held over the step), mapped over a block of steps and compiled to C where a compiler is
  available: the fastest master;
- as FMUs (RoverChassis.fmu and four WheelTerrain.fmu in Rover.ssp): see
  :mod:`wheelterrain.cosim.rover_fmus`.

Soil along the path: each wheel's soil is the terrain map's (:mod:`wheelterrain.model.ground`,
Terrain.fmu's equations) at the wheel's position, evaluated at every step inside the stepped
system, as the FMUs evaluate it (:class:`Soil` holds the map's values); the ruts the wheels
leave are kept between blocks of steps as Terrain.fmu keeps them (:mod:`.ruts`).

Beside it: the rover's limits predicted from its steady motion (:mod:`.rover_limits`), the
scenarios and their figures (:mod:`.rover_scenarios`), the FMU engines (:mod:`.rover_fmus`).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from functools import lru_cache

import casadi as ca
import numpy as np

from wheelterrain import compiled
from wheelterrain.cosim import ruts
from wheelterrain.errors import WheelTerrainError
from wheelterrain.fmu import functions
from wheelterrain.model import contact, ground, rover
from wheelterrain.model import functions as model_functions
from wheelterrain.parameters import NAMES, ParameterSet

STEP = 1e-3  # s: communication step. Engines that pass the forces one step late (Jacobi:
# libcosim, ecos) need it: at 2 ms the delayed soil damper makes the bounce grow there.
BLOCK = 100  # steps per call of the mapped system step
RECORD = ("slip", "sinkage", "normal_force", "drawbar_pull", "torque", "motor_torque",
          "wheel_speed", "rut_left", "rut_pressure_left")
"""Per-wheel quantities recorded at every step."""
CHASSIS_RECORD = ("position", "speed", "heave", "pitch", "effective_slope",
                  "effective_towing_force")
N_X = len(rover.STATES) + 2 * len(rover.WHEELS)
"""The in-process state: the chassis states, then the four wheel angles, then the four wheels'
plastic sinkages (WheelTerrain's states in the FMUs)."""


def coupled_forces(xs: list, p: dict, pt: ca.MX, angles, plastics=None) -> tuple[dict, list]:
    """The chassis' inputs (by rover.INPUTS name, commands 0, slope and towing force left to
    the caller) from the four contacts at the chassis state ``xs``, as our master couples the
    FMUs: each wheel's sinkage, rate and slip from the chassis, its terrain parameters the
    column of ``pt``, its angle from ``angles``, its plastic sinkage from ``plastics`` (None:
    the contact without the wheel's own memory, the grouser-period mean of a steady motion).
    The slip is evaluated inside the contact model's domain (a state outside it ends a run:
    :func:`simulate`). Also returns per wheel (slip, sinkage, contact outputs by
    name; the slip the model's, :mod:`wheelterrain.model.slip`)."""
    fns = model_functions.build()
    s = dict(zip(rover.STATES, xs, strict=True))
    u, wheels = {}, []
    for k, w in enumerate(rover.WHEELS):
        z, rate = rover.wheel_kinematics(xs, p, w)
        speed = rover.axle_speed(xs, p, w)
        unified, _ = functions.slips(s[f"{w}.wheel_speed"], speed, p["rover.slip_radius"])
        slip = ca.fmin(ca.fmax(unified, -1), 1)
        if plastics is None:
            out = dict(zip(contact.CONTACT_OUTPUTS,
                           fns.contact(z, rate, slip, angles[k], pt[:, k]), strict=True))
        else:
            out = dict(zip((*contact.CONTACT_OUTPUTS, *contact.MEMORY_OUTPUTS),
                           fns.contact_memory(z, rate, slip, angles[k], plastics[k], speed,
                                              pt[:, k]), strict=True))
        out["axle_speed"] = speed
        u.update({f"{w}.{n}": out[n] for n in rover.WHEEL_FORCES})
        u.update({f"{w}.{n}": 0.0 for n in rover.WHEEL_COMMANDS})
        wheels.append((unified, z, out))
    return u, wheels


def _wheel_soils(xs: list, p: dict, pw: ca.MX, pg: ca.MX, met: ca.MX) -> ca.MX:
    """The four wheels' terrain parameter vectors side by side (len(NAMES) x 4): the wheels'
    parameters ``pw`` with the soil the map (values ``pg``, ground.NAMES order) has at each
    wheel's position, as each WheelTerrain with soil_from_inputs takes it from its Terrain, and
    the rut it meets from the record (``met``: per wheel the number of the first of ruts.NEAR cells,
    their ruts and their pressures), as its inputs rut_met and rut_pressure_met."""
    g = {name: pg[k] for k, name in enumerate(ground.NAMES)}
    columns = []
    for j, w in enumerate(rover.WHEELS):
        where = rover.wheel_position(p, xs[0], w)
        soil = dict(zip(ground.SOIL_NAMES, ground.soil_at(where, g), strict=True))
        rut = ground.met_in_table(where, g, met[j * ruts.TABLE:(j + 1) * ruts.TABLE])
        column = ca.vertcat(*(soil.get(name, pw[k]) for k, name in enumerate(NAMES)))
        column = functions.with_grouser_phase(column, rover.grouser_phase(p, w))
        columns.append(functions.with_rut_met(column, rut))
    return ca.horzcat(*columns)


N_CMD = len(rover.WHEELS) * len(rover.WHEEL_COMMANDS)
"""The wheels' commands (rover.WHEEL_COMMANDS per wheel, wheel-major): used with rover.drive 1
(speed) or 2 (torque)."""


def _system_step() -> ca.Function:
    """``system(x, pw, pg, pr, slope, tow, cmd, h) -> (x_next, rec)``: one communication step
    of the whole rover. ``x``: rover.STATES then four wheel angles; ``pw``: the wheels' terrain
    parameters (their soil replaced by the map's); ``pg``: the terrain map's values
    (ground.NAMES); ``pr``: rover parameters; ``cmd``: the wheels' commands (N_CMD); ``rec``:
    RECORD per wheel (wheel-major), then CHASSIS_RECORD, at the start of the step (the forces
    held over it)."""
    x = ca.MX.sym("x", N_X)
    cmd = ca.MX.sym("cmd", N_CMD)
    pw, pg = ca.MX.sym("pw", len(NAMES)), ca.MX.sym("pg", len(ground.NAMES))
    pr = ca.MX.sym("pr", len(rover.ROVER_NAMES))
    slope, tow, h = ca.MX.sym("slope"), ca.MX.sym("tow"), ca.MX.sym("h")
    met = ca.MX.sym("met", ruts.N_MET)
    xs = [x[k] for k in range(len(rover.STATES))]
    n_s, n_w = len(rover.STATES), len(rover.WHEELS)
    angles = [x[n_s + k] for k in range(n_w)]
    plastics = [x[n_s + n_w + k] for k in range(n_w)]
    p = rover.named([pr[k] for k in range(len(rover.ROVER_NAMES))])
    s = dict(zip(rover.STATES, xs, strict=True))
    soils = _wheel_soils(xs, p, pw, pg, met)
    u, wheels = coupled_forces(xs, p, soils, angles, plastics)
    u.update(slope=slope, towing_force=tow)
    u.update({f"{w}.{n}": cmd[k] for k, (w, n) in enumerate(
        (w, n) for w in rover.WHEELS for n in rover.WHEEL_COMMANDS)})
    rec = [(unified, z, out["normal_force"], out["drawbar_pull"], out["torque"],
            rover.motor_torque(xs, u, p, w), s[f"{w}.wheel_speed"], out["rut_left"],
            out["rut_pressure_left"])
           for w, (unified, z, out) in zip(rover.WHEELS, wheels, strict=True)]
    nxt, _ = rover.step(tuple(xs), u, p, h)
    new_angles = [angles[k] + h * s[f"{w}.wheel_speed"] for k, w in enumerate(rover.WHEELS)]
    fns = model_functions.build()
    new_plastics = [fns.plastic_step(z, plastics[k], out["axle_speed"], out["mean_pressure"],
                                     out["sinkage_exponent"], soils[:, k], h)
                    for k, (_, z, out) in enumerate(wheels)]
    s["effective_slope"], s["effective_towing_force"] = rover.effective_inputs(xs, u, p)
    record = [v for wheel in rec for v in wheel] + [s[n] for n in CHASSIS_RECORD]
    return ca.Function("rover_system", [x, pw, pg, pr, slope, tow, cmd, h, met],
                       [ca.vertcat(*nxt, *new_angles, *new_plastics), ca.vertcat(*record)],
                       ["x", "pw", "pg", "pr", "slope", "tow", "cmd", "h", "met"],
                       ["x_next", "rec"])


N_REC = len(RECORD) * len(rover.WHEELS) + len(CHASSIS_RECORD)


@lru_cache(maxsize=2)
def block_function(block: int = BLOCK) -> ca.Function:
    """``block`` system steps in one call (the inputs held): x -> x after the block, and the
    record of every step (N_REC x block)."""
    one = _system_step()
    acc = one.mapaccum("rover_block", block)
    x0 = ca.MX.sym("x", N_X)
    pw, pg = ca.MX.sym("pw", len(NAMES)), ca.MX.sym("pg", len(ground.NAMES))
    pr = ca.MX.sym("pr", len(rover.ROVER_NAMES))
    slope, tow, h = ca.MX.sym("slope"), ca.MX.sym("tow"), ca.MX.sym("h")
    cmd = ca.MX.sym("cmd", N_CMD)
    met = ca.MX.sym("met", ruts.N_MET)
    xs, recs = acc(x0, pw, pg, pr, slope, tow, cmd, h, met)
    return ca.Function(f"rover_block{block}", [x0, pw, pg, pr, slope, tow, cmd, h, met],
                       [xs[:, -1], recs],
                       ["x", "pw", "pg", "pr", "slope", "tow", "cmd", "h", "met"],
                       ["x_end", "rec"])


@lru_cache(maxsize=2)
def _evaluator(block: int) -> tuple[Callable, str]:
    """The block Function compiled to C (cached between runs), else CasADi's VM; and which."""
    fn = block_function(block)
    try:
        library = compiled.cached_library(fn, "rover", optimisation="-O1")
        c = compiled.CompiledFunction(library, fn)
        return c.arrays, "compiled C"
    except compiled.CompileError:
        return compiled.vm_arrays(fn), "CasADi VM"


@dataclass
class Soil:
    """The wheels' terrain parameters ``base`` and the terrain map along the path: ``base``'s
    soil everywhere, ``patch`` (soil values overriding base's) on [start, end) m."""

    base: ParameterSet
    patch: Mapping[str, float] | None = None
    start: float = 0.0
    end: float = 0.0

    def __post_init__(self) -> None:
        self.patched = self.base.with_values(dict(self.patch or {}))  # checks the values

    def map_values(self) -> dict[str, float]:
        """Terrain.fmu's parameters (ground.NAMES) for this map (the rut profile's
        terrain.cell and terrain.lookahead at their defaults)."""
        start, end = (self.start, self.end) if self.patch else (0.0, 0.0)
        return ground.map_values(self.base, self.patched, start, end)


@dataclass
class RoverResult:
    time: np.ndarray
    wheels: dict[str, dict[str, np.ndarray]]
    chassis: dict[str, np.ndarray]
    wall_time: float
    engine: str
    inputs: dict[str, np.ndarray] = field(default_factory=dict)
    left_domain: str | None = None
    """Why the run ended before its stop time where it left the model's domain (a wheel's
    slip beyond [-1, 1], a non-finite value): the records end at the last step inside it."""



def simulate(soil: Soil, rover_values: Mapping[str, float], stop: float, step: float = STEP,
             block: int = BLOCK, stop_when: Callable[[dict], bool] | None = None,
             slope: float = 0.0, towing: float = 0.0,
             control: Callable[[float, list], list] | None = None,
             x0: list[float] | None = None, ruts0: dict | None = None,
             progress: Callable[[float], None] | None = None) -> RoverResult:
    """Run the rover in process from rest on the surface for ``stop`` s, its inputs ``slope``
    [rad] and ``towing`` [N] constant (a scenario's ramps are the chassis' input profile, rows
    ``rover.ramp_time`` ... ``rover.towing_rate`` of ``rover_values``); ``stop_when(last)``
    (the last step's record by name) ends the run early. ``control(t, x)`` (x: rover.STATES
    then the wheel angles) gives the wheels' commands (N_CMD) held over the next ``block``
    steps (default: none, 0). ``x0``: the state to start from (N_X: rover.STATES, the wheel
    angles, the wheels' plastic sinkages) instead of rest on the surface; ``ruts0``: the
    tracks' rut profiles to start from (by track; default: no rut). ``progress(t)`` is told the
    simulated time reached after every block of steps."""
    p = {**rover.defaults(), **rover_values}
    evaluate, engine = _evaluator(block)
    pr = [p[n] for n in rover.ROVER_NAMES]
    pw = soil.base.vector()
    g = soil.map_values()
    pg = [g[n] for n in ground.NAMES]
    ruts.check_profile(p, g)
    profiles = {track: list(ruts0[track]) if ruts0 else ground.no_ruts()
              for track in rover.TRACKS}  # Terrain.fmu's record, per track
    x = list(rover.initial_state(p)) + [0.0] * (2 * len(rover.WHEELS))  # angles, plastics
    if x0 is not None:
        x = [float(v) for v in x0]
    blocks = max(1, round(stop / (step * block)))
    records = []
    left = None
    t0 = time.perf_counter()
    for b in range(blocks):
        t = b * block * step
        cmd = [0.0] * N_CMD if control is None else control(t, x)
        at = {w: rover.wheel_position(p, x[0], w) for w in rover.WHEELS}
        met = ruts.met_table(profiles, at, g)
        x, rec = evaluate(x, pw, pg, pr, slope, towing, cmd, step, met)
        rec = np.asarray(rec, dtype=float).reshape(N_REC, block, order="F")
        problem = outside(rec)
        if problem is not None:
            k, why = problem
            records.append(rec[:, :k])
            left = f"at t = {t + k * step:.3f} s {why}"
            break
        records.append(rec)
        if stop_when is not None and stop_when(last_values(rec[:, -1])):
            break  # the run ends here: no later step meets the ruts of this block
        wheels, chassis = named_record(rec)
        try:
            ruts.remember(profiles, chassis["position"],
                          {w: wheels[w]["rut_left"] for w in rover.WHEELS},
                          {w: wheels[w]["rut_pressure_left"] for w in rover.WHEELS}, met, p, g)
        except WheelTerrainError as err:  # the run ends here, with the reason
            left = f"at t = {t + block * step:.3f} s {err}"
            break
        if progress is not None:
            progress((b + 1) * block * step)
    wall = time.perf_counter() - t0
    return from_records(np.concatenate(records, axis=1), step, wall, f"in-process ({engine})",
                        left)


def named_record(rec) -> tuple[dict, dict]:
    """(per wheel {RECORD name: row}, {CHASSIS_RECORD name: row}) of record rows ``rec`` (RECORD
    per wheel, wheel-major, then CHASSIS_RECORD): a whole record or one column of it."""
    wheels = {w: {name: rec[k * len(RECORD) + j] for j, name in enumerate(RECORD)}
              for k, w in enumerate(rover.WHEELS)}
    base = len(RECORD) * len(rover.WHEELS)
    return wheels, {name: rec[base + j] for j, name in enumerate(CHASSIS_RECORD)}


def last_values(column) -> dict:
    """One step's record column by name (``front_left.slip``, ..., ``speed``): what a
    ``stop_when`` is given."""
    wheels, chassis = named_record(column)
    return {**{f"{w}.{n}": v for w, d in wheels.items() for n, v in d.items()}, **chassis}


def from_records(allrec: np.ndarray, step: float, wall: float, engine: str,
                 left: str | None = None) -> RoverResult:
    """A RoverResult from the record rows (RECORD per wheel, then CHASSIS_RECORD) by step."""
    n = allrec.shape[1]
    wheels, chassis = named_record(allrec)
    inputs = {"slope": chassis.pop("effective_slope"),
              "towing_force": chassis.pop("effective_towing_force")}
    return RoverResult(np.arange(n) * step, wheels, chassis, wall, engine, inputs, left)


def outside(rec: np.ndarray) -> tuple[int, str] | None:
    """(first step, why) where a block's record leaves the model's domain, else None."""
    slips = rec[[k * len(RECORD) + RECORD.index("slip") for k in range(len(rover.WHEELS))]]
    bad = ~np.isfinite(rec).all(axis=0) | (np.abs(slips) > 1).any(axis=0)
    if not bad.any():
        return None
    k = int(np.argmax(bad))
    worst = slips[:, k]
    if np.all(np.isfinite(worst)) and np.any(np.abs(worst) > 1):
        w = rover.WHEELS[int(np.argmax(np.abs(worst)))]
        return k, (f"{w}'s slip reached {worst.flat[np.argmax(np.abs(worst))]:.3f}, outside "
                   "the contact model's domain [-1, 1] (from a locked wheel to spinning): "
                   + ("the wheel turns backward while the rover moves forward"
                      if worst.min() < -1 else "the rover moves backward"))
    return k, "a value became non-finite"



def record_units() -> dict[str, str]:
    """Units of the series a rover run writes (CSV headers)."""
    per_wheel = {"slip": "1", "sinkage": "m", "normal_force": "N", "drawbar_pull": "N",
                 "torque": "N.m", "motor_torque": "N.m", "wheel_speed": "rad/s",
                 "rut_left": "m", "rut_pressure_left": "Pa"}
    units = {"time": "s", "position": "m", "speed": "m/s", "heave": "m", "pitch": "rad",
             "slope": "rad", "towing_force": "N"}
    units.update({f"{w}.{k}": u for w in rover.WHEELS for k, u in per_wheel.items()})
    return units
