"""The rover: four wheel-terrain contacts on the chassis of :mod:`wheelterrain.model.rover`.

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
system, as the FMUs evaluate it (:class:`Soil` holds the map's values).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from functools import lru_cache

import casadi as ca
import numpy as np

from wheelterrain import compiled
from wheelterrain.errors import ParameterError, WheelTerrainError
from wheelterrain.fmu import functions
from wheelterrain.model import contact, ground, rover
from wheelterrain.model import functions as model_functions
from wheelterrain.parameters import GRAVITY, NAMES, ParameterSet

STEP = 1e-3  # s: communication step. Engines that pass the forces one step late (Jacobi:
# libcosim, ecos) need it: at 2 ms the delayed soil damper makes the bounce grow there.
FINE_STEP = 2.5e-4
"""s: the step of the Moon's stall runs (slope, pull-test, descent). Each ends where the
steady motion loses its stability (the bounce's damping, or the traction); a force handed
over one step late (a delayed soil spring acts as a negative damper) brings that end earlier
by an amount first order in the step. On the Moon, where the grouser ripple is near the
1.5 Hz bounce, the one-step-late engines' mean slip differs from the in-process one by
1.2-2.5e-3 at 1 ms, 0.6-1.1e-3 at 0.5 ms and 1.9-5.9e-4 at this step, halving with the step
(validation/rover_engines.py [--step], README); on Earth 1 ms is enough (at most 8.2e-4)."""
BLOCK = 100  # steps per call of the mapped system step
RECORD = ("slip", "sinkage", "normal_force", "drawbar_pull", "torque", "motor_torque",
          "wheel_speed", "rut_left")
"""Per-wheel quantities recorded at every step."""
CHASSIS_RECORD = ("position", "speed", "heave", "pitch", "effective_slope",
                  "effective_towing_force")
N_X = len(rover.STATES) + 2 * len(rover.WHEELS)
"""The in-process state: the chassis states, then the four wheel angles, then the four wheels'
plastic sinkages (WheelTerrain's states in the FMUs)."""


def _coupled_forces(xs: list, p: dict, pt: ca.MX, angles, plastics=None) -> tuple[dict, list]:
    """The chassis' inputs (by rover.INPUTS name, commands 0, slope and towing force left to
    the caller) from the four contacts at the chassis state ``xs``, as our master couples the
    FMUs: each wheel's sinkage, rate and slip from the chassis, its terrain parameters the
    column of ``pt``, its angle from ``angles``, its plastic sinkage from ``plastics`` (None:
    the contact without the wheel's own memory, the grouser-period mean of a steady motion).
    The slip is evaluated inside the contact model's domain (a state outside it ends a run:
    :func:`simulate`). Also returns per wheel (traction slip, sinkage, contact outputs by
    name)."""
    fns = model_functions.build()
    s = dict(zip(rover.STATES, xs, strict=True))
    u, wheels = {}, []
    for k, w in enumerate(rover.WHEELS):
        z, rate = rover.wheel_kinematics(xs, p, w)
        traction, _, _ = functions.slips(s[f"{w}.wheel_speed"], s["speed"],
                                         p["rover.slip_radius"])
        slip = ca.fmin(ca.fmax(traction, -1), 1)
        if plastics is None:
            out = dict(zip(contact.CONTACT_OUTPUTS,
                           fns.contact(z, rate, slip, angles[k], pt[:, k]), strict=True))
        else:
            out = dict(zip((*contact.CONTACT_OUTPUTS, *contact.MEMORY_OUTPUTS),
                           fns.contact_memory(z, rate, slip, angles[k], plastics[k], s["speed"],
                                              pt[:, k]), strict=True))
        u.update({f"{w}.{n}": out[n] for n in rover.WHEEL_FORCES})
        u.update({f"{w}.{n}": 0.0 for n in rover.WHEEL_COMMANDS})
        wheels.append((traction, z, out))
    return u, wheels


NEAR = 5
"""Cells of the rut record a wheel may meet within one block of steps, from the one before the
first of the two it meets between at the block's start (:func:`met_table`): the record is
replayed between blocks (:func:`replay`), exactly as Terrain.fmu keeps it step by step,
where a wheel moves less than two cells a block."""
N_MET = len(rover.WHEELS) * (NEAR + 1)


def _wheel_soils(xs: list, p: dict, pw: ca.MX, pg: ca.MX, met: ca.MX) -> ca.MX:
    """The four wheels' terrain parameter vectors side by side (len(NAMES) x 4): the wheels'
    parameters ``pw`` with the soil the map (values ``pg``, ground.NAMES order) has at each
    wheel's position, as each WheelTerrain with soil_from_inputs takes it from its Terrain, and
    the rut it meets from the record (``met``: per wheel the number of the first of NEAR cells
    and their ruts), as its input rut_met."""
    g = {name: pg[k] for k, name in enumerate(ground.NAMES)}
    columns = []
    for j, w in enumerate(rover.WHEELS):
        where = rover.wheel_position(p, xs[0], w)
        soil = dict(zip(ground.SOIL_NAMES, ground.soil_at(where, g), strict=True))
        number, share = ground.met_cells(where, g)
        first = met[j * (NEAR + 1)]
        near = far = 0
        for k in range(NEAR):
            near = near + ca.if_else(number == first + k, met[j * (NEAR + 1) + 1 + k], 0)
            far = far + ca.if_else(number + 1 == first + k, met[j * (NEAR + 1) + 1 + k], 0)
        rut = ground.between(near, far, share)
        column = ca.vertcat(*(soil.get(name, pw[k]) for k, name in enumerate(NAMES)))
        columns.append(functions.with_rut_met(column, rut))
    return ca.horzcat(*columns)


def met_table(records: dict, positions: dict[str, float], g: Mapping[str, float]) -> list:
    """The ``met`` input of a block (N_MET): per wheel, the number of the cell before the
    first of the two it meets between at the block's start (ground.met_cells), then the
    record's ruts of NEAR cells from there."""
    out = []
    for w in rover.WHEELS:
        first = ground.met_cells(positions[w], g)[0] - 1
        out += [float(first), *(ground.recorded(records[rover.TRACK_OF[w]], first + k)
                                for k in range(NEAR))]
    return out


def replay(records: dict, wheel_positions: dict, ruts: dict, g: Mapping[str, float]) -> None:
    """Terrain.fmu's record of each track after a block: every step, each wheel of the track
    (the leading one first) left its rut at its position. Steps in one cell leave their
    deepest rut once (ground.record_one); within a block the leading and the following
    wheel never write the same slot (the record is longer than the wheelbase)."""
    for track, pair in rover.TRACKS.items():
        x = records[track]
        for w in pair:
            numbers = ground.cell_number(wheel_positions[w], g)
            starts = np.concatenate(([0], np.flatnonzero(np.diff(numbers)) + 1))
            deepest = np.maximum.reduceat(ruts[w], starts)  # per run of steps in one cell
            for a, rut in zip(starts, deepest, strict=True):
                x = ground.record_one(x, float(wheel_positions[w][a]), float(rut), g)
        records[track] = x


def check_record(p: Mapping[str, float], g: Mapping[str, float]) -> None:
    """Refuse, with the parameters to change, a rover the rut record cannot serve: a wheel
    must meet the rut at least three cells ahead of where it leaves its own, and the record
    must be longer than a track (the wheelbase and the lookahead, two cells to spare)."""
    cell, ahead = g["terrain.cell"], g["terrain.lookahead"]
    if ahead < 3 * cell:
        raise ParameterError(
            "terrain.lookahead", ahead, f"m is less than three cells of terrain.cell = "
            f"{cell:g} m: a wheel would meet the rut it leaves itself; make it at least "
            f"{3 * cell:g} m")
    span = p["rover.wheelbase"] + ahead + 2 * cell
    if span >= ground.RUT_CELLS * cell:
        raise ParameterError(
            "terrain.cell", cell, f"m is too short: the rut record holds {ground.RUT_CELLS} "
            f"cells ({ground.RUT_CELLS * cell:g} m), less than the wheelbase and lookahead "
            f"({span:g} m); make terrain.cell (a Terrain FMU parameter) at least "
            f"{span / ground.RUT_CELLS:.3g} m, or rover.wheelbase shorter")


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
    met = ca.MX.sym("met", N_MET)
    xs = [x[k] for k in range(len(rover.STATES))]
    n_s, n_w = len(rover.STATES), len(rover.WHEELS)
    angles = [x[n_s + k] for k in range(n_w)]
    plastics = [x[n_s + n_w + k] for k in range(n_w)]
    p = rover.named([pr[k] for k in range(len(rover.ROVER_NAMES))])
    s = dict(zip(rover.STATES, xs, strict=True))
    soils = _wheel_soils(xs, p, pw, pg, met)
    u, wheels = _coupled_forces(xs, p, soils, angles, plastics)
    u.update(slope=slope, towing_force=tow)
    u.update({f"{w}.{n}": cmd[k] for k, (w, n) in enumerate(
        (w, n) for w in rover.WHEELS for n in rover.WHEEL_COMMANDS)})
    rec = [(traction, z, out["normal_force"], out["drawbar_pull"], out["torque"],
            rover.motor_torque(xs, u, p, w), s[f"{w}.wheel_speed"], out["rut_left"])
           for w, (traction, z, out) in zip(rover.WHEELS, wheels, strict=True)]
    nxt, _ = rover.step(tuple(xs), u, p, h)
    new_angles = [angles[k] + h * s[f"{w}.wheel_speed"] for k, w in enumerate(rover.WHEELS)]
    fns = model_functions.build()
    new_plastics = [fns.plastic_step(z, plastics[k], s["speed"], soils[:, k], h)
                    for k, (_, z, _) in enumerate(wheels)]
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
    met = ca.MX.sym("met", N_MET)
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
        """Terrain.fmu's parameters (ground.NAMES) for this map (the rut record's
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
             x0: list[float] | None = None, ruts0: dict | None = None) -> RoverResult:
    """Run the rover in process from rest on the surface for ``stop`` s, its inputs ``slope``
    [rad] and ``towing`` [N] constant (a scenario's ramps are the chassis' input profile, rows
    ``rover.ramp_time`` ... ``rover.towing_rate`` of ``rover_values``); ``stop_when(last)``
    (the last step's record by name) ends the run early. ``control(t, x)`` (x: rover.STATES
    then the wheel angles) gives the wheels' commands (N_CMD) held over the next ``block``
    steps (default: none, 0). ``x0``: the state to start from (N_X: rover.STATES, the wheel
    angles, the wheels' plastic sinkages) instead of rest on the surface; ``ruts0``: the
    tracks' rut records to start from (by track; default: no rut)."""
    p = {**rover.defaults(), **rover_values}
    evaluate, engine = _evaluator(block)
    pr = [p[n] for n in rover.ROVER_NAMES]
    pw = soil.base.vector()
    g = soil.map_values()
    pg = [g[n] for n in ground.NAMES]
    check_record(p, g)
    memory = {track: list(ruts0[track]) if ruts0 else ground.initial_record()
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
        met = met_table(memory, at, g)
        x, rec = evaluate(x, pw, pg, pr, slope, towing, cmd, step, met)
        rec = np.asarray(rec, dtype=float).reshape(N_REC, block, order="F")
        problem = _outside(rec)
        if problem is not None:
            k, why = problem
            records.append(rec[:, :k])
            left = f"at t = {t + k * step:.3f} s {why}"
            break
        records.append(rec)
        if stop_when is not None and stop_when(last_values(rec[:, -1])):
            break  # the run ends here: no later step meets the ruts of this block
        _remember(memory, rec, met, p, g)
    wall = time.perf_counter() - t0
    return from_records(np.concatenate(records, axis=1), step, wall, f"in-process ({engine})",
                        left)


def _remember(records: dict, rec: np.ndarray, met: list, p: Mapping[str, float],
              g: Mapping[str, float]) -> None:
    """After a block: the ruts its steps left, into the tracks' records (:func:`replay`);
    refused where a wheel met a cell outside the block's NEAR (it moved two cells or more)."""
    wheels, chassis = named_record(rec)
    positions = {w: rover.wheel_position(p, chassis["position"], w) for w in rover.WHEELS}
    for j, w in enumerate(rover.WHEELS):
        numbers = ground.met_cells(positions[w], g)[0]  # and the cell after each
        first = met[j * (NEAR + 1)]
        if np.any(numbers < first) or np.any(numbers + 1 > first + NEAR - 1):
            raise WheelTerrainError(
                f"{w} moved more than two cells of the rut record (terrain.cell = "
                f"{g['terrain.cell']:g} m) in one block of {rec.shape[1]} steps: make "
                "terrain.cell larger or the block shorter")
    replay(records, positions, {w: wheels[w]["rut_left"] for w in rover.WHEELS}, g)


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


def _outside(rec: np.ndarray) -> tuple[int, str] | None:
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
                   "the contact model's domain [-1, 1]" + (" (the wheels cannot brake the "
                                                          "rover: it slides)"
                                                          if worst.min() < -1 else ""))
    return k, "a value became non-finite"


# --- the steady-state prediction: traction limit and linear stability ------------------------

MOVING = tuple(n for n in rover.STATES if n not in ("position", "elapsed"))
"""The states of steady motion (the position and the clock only advance): what the
linearisation keeps (the input profile is off in a prediction)."""


@lru_cache(maxsize=1)
def _closed_loop() -> tuple[ca.Function, ca.Function]:
    """``rates(x, pt, pr, slope, tow) -> dx`` of the whole rover in continuous time (the
    contacts' forces at the state, ripple as the terrain parameters say) over MOVING, and its
    exact Jacobian ``jac(x, pt, pr, slope, tow)`` by MOVING."""
    x = ca.MX.sym("x", len(rover.STATES))
    pt = ca.MX.sym("pt", len(NAMES), len(rover.WHEELS))
    pr = ca.MX.sym("pr", len(rover.ROVER_NAMES))
    slope, tow = ca.MX.sym("slope"), ca.MX.sym("tow")
    xs = [x[k] for k in range(len(rover.STATES))]
    p = rover.named([pr[k] for k in range(len(rover.ROVER_NAMES))])
    u, _ = _coupled_forces(xs, p, pt, [0.0] * len(rover.WHEELS))  # grouser-period mean
    u.update(slope=slope, towing_force=tow)
    dx = ca.vertcat(*rover.rates(tuple(xs), u, p))
    keep = [rover.STATES.index(n) for n in MOVING]
    f = ca.Function("rover_rates_closed", [x, pt, pr, slope, tow], [dx[keep]])
    jac = ca.Function("rover_jac_closed", [x, pt, pr, slope, tow],
                      [ca.jacobian(dx[keep], x)[:, keep]])
    return f, jac


def steady_state_vector(balance: dict, p: Mapping[str, float]) -> np.ndarray:
    """The rover's state (STATES) in the steady motion of :func:`rover.steady_balance`."""
    omega = p["rover.rim_speed"] / p["rover.slip_radius"]
    _, ki = rover.gains(p)
    zf = balance["wheels"]["front_left"]["sinkage"]
    zr = balance["wheels"]["rear_left"]["sinkage"]
    lf, lr = rover.lever(p, "front_left"), rover.lever(p, "rear_left")
    sin_t = (zf - zr) / (lf - lr)
    s = dict.fromkeys(rover.STATES, 0.0)
    s.update(speed=(1 - balance["slip"]) * p["rover.rim_speed"], heave=zf - lf * sin_t,
             pitch=math.asin(sin_t))
    for w in rover.WHEELS:
        s[f"{w}.wheel_speed"] = omega
        s[f"{w}.speed_error_integral"] = balance["wheels"][w]["torque"] / ki
    return np.array([s[n] for n in rover.STATES])


def growth_rate(terrain: Mapping, p: Mapping[str, float], slope: float, slip: float,
                balance_tow: bool = False) -> dict:
    """The largest real part [1/s] of the eigenvalues of the rover's linearisation (exact
    Jacobian of the same Functions) about its steady motion at ``slip`` on ``slope``: > 0, the
    steady motion is unstable. The state is polished by Newton on the continuous rates.
    ``balance_tow``: the towing force is whatever holds the rover at that slip (the pull
    test), else 0 (``slip`` must then be the slope's steady slip)."""
    f, jac = _closed_loop()
    pr = [p[n] for n in rover.ROVER_NAMES]
    balance = rover.steady_balance(terrain, p, slope, slip)
    # each rear wheel in its front wheel's rut (the steady rover's soils)
    pt = np.column_stack([balance["terrain"][w].vector() for w in rover.WHEELS])
    tow = balance["surplus"] if balance_tow else 0.0
    x = steady_state_vector(balance, p)
    keep = [rover.STATES.index(n) for n in MOVING]
    for _ in range(20):
        r = np.array(f(x, pt, pr, slope, tow)).ravel()
        J = np.array(jac(x, pt, pr, slope, tow))
        step = np.linalg.solve(J, -r)
        x[keep] += step
        if np.max(np.abs(step)) < 1e-14 * max(1.0, np.max(np.abs(x))):
            break
    eig = np.linalg.eigvals(np.array(jac(x, pt, pr, slope, tow)))
    top = eig[np.argmax(eig.real)]
    return {"rate": float(top.real), "frequency_hz": float(abs(top.imag) / (2 * math.pi)),
            "state": x}


def steady_slip(terrain: Mapping, p: Mapping[str, float], slope: float) -> float | None:
    """The slip of steady motion on ``slope`` in [-0.999, STALL_SLIP], or None (none there:
    the wheels cannot hold the rover)."""
    from scipy.optimize import brentq

    def surplus(i: float) -> float:
        return rover.steady_balance(terrain, p, slope, i)["surplus"]

    lo, hi = -0.999, STALL_SLIP
    try:
        if surplus(lo) > 0 or surplus(hi) < 0:
            return None
        return brentq(surplus, lo, hi, xtol=1e-12)
    except WheelTerrainError:
        return None


def has_memory(terrain: Mapping) -> bool:
    """True where the wheels' soil remembers (``model.soil_memory`` = 1)."""
    return any(terrain[w]["model.soil_memory"] == 1 for w in rover.WHEELS)


PROBE_TIME = 12.0  # s: how long a perturbed steady motion is run (PROBE_KICK's test)
PROBE_KICK = 1e-4  # rad/s: the pitch rate the steady motion is started with


def holds(terrain: Mapping, p: Mapping[str, float], slope: float, slip: float,
          step: float = STEP, balance_tow: bool = False) -> bool:
    """Whether the rover's steady motion at ``slip`` on ``slope`` survives a small
    disturbance, by running it: from the steady state (:func:`steady_state_vector`, each wheel's
    plastic sinkage at its sinkage) with the pitch rate PROBE_KICK, in process for PROBE_TIME s
    at that slope; it holds when the normal forces' deviation from the steady motion over the
    last second is below its largest over the first second (it dies out) and the slip stays
    below STALL_SLIP. The test for a soil with memory, which has no one linearisation: lifted,
    a wheel unloads along the stiff elastic line; pressed, it yields along the soft
    pressure-sinkage law. ``balance_tow``: the towing force is whatever holds the rover at
    that slip (the pull test), else 0 (``slip`` must be the slope's steady slip)."""
    balance = rover.steady_balance(terrain, p, slope, slip)
    tow = balance["surplus"] if balance_tow else 0.0
    x = steady_state_vector(balance, p)
    x[rover.STATES.index("pitch_rate")] += PROBE_KICK
    plastics = [float(rover.wheel_kinematics(list(x), p, w)[0]) for w in rover.WHEELS]
    x0 = [*x, *([0.0] * len(rover.WHEELS)), *plastics]
    soil = Soil(terrain["front_left"])
    res = simulate(soil, dict(p), PROBE_TIME, step=step, slope=slope, towing=tow, x0=x0,
                   ruts0=steady_ruts(balance, p, x, soil.map_values()))
    if res.left_domain or res.time.size < round(PROBE_TIME / step) - 1:
        return False
    steady = np.array([balance["wheels"][w]["normal_force"] for w in rover.WHEELS])
    forces = np.array([res.wheels[w]["normal_force"] for w in rover.WHEELS])
    deviation = np.max(np.abs(forces - steady[:, None]), axis=0)
    second = round(1.0 / step)
    slips = np.array([res.wheels[w]["slip"] for w in rover.WHEELS])
    return bool(deviation[-second:].max() < deviation[:second].max()
                and slips.max() < STALL_SLIP)


def steady_ruts(balance: dict, p: Mapping[str, float], x, g: Mapping[str, float]) -> dict:
    """The tracks' rut records of a rover in steady motion (``balance``) at the state ``x``:
    the track behind each leading wheel holds its steady rut, back past the wheel behind."""
    records = {}
    position = x[rover.STATES.index("position")]
    for track, (front, rear) in rover.TRACKS.items():
        rut = balance["wheels"][front]["rut_left"]
        record = ground.initial_record()
        first = ground.cell_number(rover.wheel_position(p, position, rear), g) - 2
        last = ground.cell_number(rover.wheel_position(p, position, front), g)
        for number in range(first, last + 1):  # at each cell's middle: its own number
            record = ground.record_one(record, (number + 0.5) * g["terrain.cell"], rut, g)
        records[track] = record
    return records


def statically_stable(terrain: Mapping, p: Mapping[str, float], slope: float,
                      slip: float) -> bool:
    """The force balance's slope at a steady slip: more slip must give more net forward force
    (the rover then slows less and the slip falls back). Where sinkage grows with slip faster
    than the thrust (``soil.n1``, bulldozing), the surplus can fall with slip: the steady
    motion is then statically unstable and the slip runs away (``slip_sinkage``)."""
    h = 1e-4
    lo, hi = max(slip - h, -0.999), min(slip + h, 0.999)
    return (rover.steady_balance(terrain, p, slope, hi)["surplus"]
            > rover.steady_balance(terrain, p, slope, lo)["surplus"])


STALL_CAUSES = ("traction", "slip_sinkage", "stability", "motor_torque", "domain")
"""What can end a slope or descent run (``stall_cause``), in the order they are tested."""


def steady_cause(terrain: Mapping, p: Mapping[str, float], slope: float,
                 slip: float | None = None) -> str | None:
    """Which steady condition fails on ``slope``, or None: no steady slip in
    [-0.999, STALL_SLIP] (``traction``: the wheels cannot hold the rover; downhill, cannot
    brake it), the force balance falls with slip there (``slip_sinkage``), or the motors
    cannot give its torque (``motor_torque``, rover.motor_torque_limit). ``slip``: the
    slope's steady slip where the caller has it (:func:`steady_slip`)."""
    i = steady_slip(terrain, p, slope) if slip is None else slip
    if i is None:
        return "traction"
    if not statically_stable(terrain, p, slope, i):
        return "slip_sinkage"
    balance = rover.steady_balance(terrain, p, slope, i)
    if max(abs(balance["wheels"][w]["torque"]) for w in rover.WHEELS) \
            > p["rover.motor_torque_limit"]:
        return "motor_torque"
    return None


def run_cause(res: RoverResult, terrain: Mapping, p: Mapping[str, float],
              slope: float) -> str:
    """Which of STALL_CAUSES ended a run that stalled or slid at ``slope`` [rad]: ``domain``
    where it left the model's domain other than by its slip (a non-finite value, a refused
    step); else the first steady condition that fails there (:func:`steady_cause`, on the
    ripple-free soil ``terrain``); else ``stability``: a steady motion that the motors can
    drive exists and is statically stable, and the run did not hold it (a disturbance grew)."""
    if res.left_domain and "slip reached" not in res.left_domain:
        return "domain"
    return steady_cause(terrain, p, slope) or "stability"


def slip_vs_slope(res: RoverResult, settle: float = 1.0) -> list[dict]:
    """One row per whole degree of slope the run reached: the four wheels' mean slip and
    sinkage over ``settle`` s from where the slope first reached it (uphill or downhill)."""
    slope = np.degrees(np.abs(res.inputs["slope"]))
    step = float(res.time[1] - res.time[0]) if res.time.size > 1 else STEP
    window = max(round(settle / step), 1)
    slips = np.mean([v["slip"] for v in res.wheels.values()], axis=0)
    sinkages = np.mean([v["sinkage"] for v in res.wheels.values()], axis=0)
    rows = []
    for degree in range(int(np.floor(slope.max())) + 1 if slope.size else 0):
        k = int(np.argmax(slope >= degree))
        sign = 1.0 if res.inputs["slope"][min(k + 1, slope.size - 1)] >= 0 else -1.0
        rows.append({"slope_deg": sign * degree,
                     "mean_slip": float(np.mean(slips[k:k + window])),
                     "mean_sinkage": float(np.mean(sinkages[k:k + window]))})
    return rows


def limit_slope(terrain: Mapping, p: Mapping[str, float], direction: int = 1,
                tolerance: float = 1e-4) -> dict:
    """The steepest slope [rad] (uphill for ``direction`` 1, downhill for -1) on which the rover
    has a steady motion that it also holds: a steady slip exists in [-0.999, STALL_SLIP] (else
    ``traction``: the wheels cannot hold the rover, downhill their braking), more slip gives
    more net force there (else ``slip_sinkage``, :func:`statically_stable`), and a disturbance
    dies out (else ``stability``): on a soil without memory the linearisation about the steady
    motion has no eigenvalue with a positive real part; on a soil with memory, which has none,
    the perturbed motion is run (:func:`holds`). Bisection on the slope from level ground, every
    condition checked at every trial; ``limit`` says which one ended it (a tolerance of
    1e-3 rad where the motion is run)."""
    top = direction * math.radians(60)
    memory = has_memory(terrain)
    if memory:
        tolerance = max(tolerance, 1e-3)

    def verdict(slope: float) -> str | None:
        i = steady_slip(terrain, p, slope)
        if i is None:
            return "traction"
        cause = steady_cause(terrain, p, slope, i)
        if cause is not None:
            return cause
        if memory:
            return None if holds(terrain, p, slope, i) else "stability"
        return "stability" if growth_rate(terrain, p, slope, i)["rate"] > 0 else None

    level = verdict(0.0)  # each verdict once: on a soil with memory it runs the rover
    if level is not None:
        return {"slope": 0.0, "limit": level, "slip": None}
    why = verdict(top)
    if why is None:
        return {"slope": top, "limit": None, "slip": steady_slip(terrain, p, top)}
    lo, hi = 0.0, top
    while abs(hi - lo) > tolerance:
        mid = (lo + hi) / 2
        v = verdict(mid)
        if v is None:
            lo = mid
        else:
            hi, why = mid, v
    return {"slope": lo, "limit": why, "slip": steady_slip(terrain, p, lo)}


STALL_SLIP = 0.95
"""Slip at which the rover counts as stalled: it moves at 5 % of its wheels' rim speed."""


# --- scenarios ----------------------------------------------------------------------------------

SOFT = ground.SOFT_PATCH
"""The soft patch: k_phi' and phi scaled by these factors (a looser soil)."""
PATCH_START, PATCH_LENGTH = ground.SOFT_PATCH_START, ground.SOFT_PATCH_LENGTH


@dataclass(frozen=True)
class Scenario:
    name: str
    description: str
    stop: float
    profile: dict  # the chassis' input profile (rover.ramp_time ... rover.towing_rate)
    settle: float  # s: averaging starts here
    step: float = STEP  # s: the communication step of every engine (FINE_STEP's note)


SLOW_RAMP = 0.002  # deg/s: the slope's rate near the predicted limit
FAST_RAMP = 0.1  # deg/s: up to KNEE_MARGIN before it
KNEE_MARGIN = 2.0
"""deg: how far before the predicted limit the slope's ramp slows down. With 1 deg the Moon's
runs stalled (climb, 23.99 deg) or slid (descent approached this way, 6.72 deg) during the
fast ramp, before its knee (24.22, 6.82 deg; measured with the rut met as a staircase of
cells): 0.1 deg/s is not quasi-static there. With 2 deg both end in the slow ramp."""


def approach(knee_deg: float, direction: int = 1) -> dict:
    """The input profile that tilts the ground at FAST_RAMP to ``knee_deg`` (uphill for
    ``direction`` 1, downhill for -1), then at SLOW_RAMP: a limit approached quasi-statically
    (the slope scenario; tests/test_rover.py approaches the descent's limit so)."""
    deg = math.pi / 180
    return {"rover.slope_rate": direction * FAST_RAMP * deg,
            "rover.ramp_time": knee_deg / FAST_RAMP,
            "rover.slope_rate_after": direction * SLOW_RAMP * deg}


def approach_stop(knee_deg: float, beyond_deg: float = 6.0) -> float:
    """The time [s] at which :func:`approach` has gone ``beyond_deg`` past its knee."""
    return knee_deg / FAST_RAMP + beyond_deg / SLOW_RAMP


def scenarios(gravity: str = "earth", knee_deg: float = 15.0,
              weight: float = 10.0 * GRAVITY["earth"]) -> dict[str, Scenario]:
    """The scenarios; ``knee_deg``: where the slope scenario's ramp slows down (run_scenario
    puts it KNEE_MARGIN below the predicted stall slope, so that an instability's growth does
    not lag the slope). Each scenario's inputs are the chassis' input profile, so its Rover.ssp
    carries it whole."""
    deg = math.pi / 180
    stall_step = FINE_STEP if gravity == "moon" else STEP
    return {
        "level": Scenario("level", "steady traverse on level ground at the commanded rim speed",
                          40.0, {}, 20.0),
        "slope": Scenario("slope", f"the slope rises ({FAST_RAMP} deg/s to {knee_deg:.1f} deg, "
                          f"then {SLOW_RAMP} deg/s) until the rover stalls (slip {STALL_SLIP})",
                          approach_stop(knee_deg), approach(knee_deg), 0.0, stall_step),
        "soft-patch": Scenario("soft-patch", f"level; a looser soil (k_phi' x{SOFT['soil.k_phi']}, "
                               f"phi x{SOFT['soil.phi']}) from {PATCH_START} m to "
                               f"{PATCH_START + PATCH_LENGTH} m under the front, then the rear "
                               "axle", 40.0, {}, 0.0),
        "descent": Scenario("descent", "20 deg downhill (settled on level ground for 10 s, "
                            "then 1 deg/s), the speed loops braking", 60.0,
                            {"rover.ramp_time": 10.0, "rover.slope_rate_after": -deg,
                             "rover.slope_bound": 20 * deg}, 40.0, stall_step),
        "pull-test": Scenario("pull-test", "level, wheels at the commanded speed, a resisting "
                              "force rising slowly (0.05 % of the weight per second) until the "
                              "rover stalls: its pull-slip curve", 3600.0,
                              {"rover.towing_rate": 5e-4 * weight}, 0.0, stall_step),
    }


STALL_SCENARIOS = ("slope", "pull-test")


def terrain_of(preset_values: ParameterSet) -> dict[str, ParameterSet]:
    return {w: preset_values for w in rover.WHEELS}


def scenario_soil(name: str, terrain: ParameterSet) -> Soil:
    """The soil along the path of scenario ``name``: ``terrain``'s everywhere, but for the
    soft patch of ``soft-patch`` (a terrain map: Terrain.fmu in the FMU engines)."""
    if name != "soft-patch":
        return Soil(terrain)
    return Soil(terrain, ground.soft_values(terrain), PATCH_START, PATCH_START + PATCH_LENGTH)


def run_scenario(name: str, terrain: ParameterSet, gravity: str = "earth",
                 rover_values: Mapping[str, float] | None = None,
                 step: float | None = None, engine: Callable | None = None) -> dict:
    """One scenario: the contract's figures (``wheelterrain rover --json``) and the series.
    ``terrain``: the wheels' terrain parameters (the soft patch scales its soil). ``step``:
    the communication step (default: the scenario's own, ``Scenario.step``: 1 ms, or
    :data:`FINE_STEP` for the Moon's stall runs). ``engine``:
    ``engine(soil, values, stop, step, stop_when) -> RoverResult`` runs it
    (default: :func:`simulate`, in process)."""
    if name not in scenarios():
        raise ValueError(f"unknown scenario {name!r}; valid: {', '.join(scenarios())}")
    if gravity not in GRAVITY:
        raise ValueError(f"unknown gravity {gravity!r}; valid: {', '.join(GRAVITY)}")
    values = {**(rover_values or {}), "rover.gravity": GRAVITY[gravity]}
    p = {**rover.defaults(), **values}
    soil = scenario_soil(name, terrain)
    check_record(p, soil.map_values())  # every engine's Terrain, not only in process
    quiet = terrain_of(terrain.with_values(NO_RIPPLE))
    pred = None
    if name in ("slope", "descent"):
        pred = limit_slope(quiet, p, 1 if name == "slope" else -1)
    knee = max(math.degrees(pred["slope"]) - KNEE_MARGIN, 0.0) if name == "slope" else 15.0
    sc = scenarios(gravity, knee, p["rover.mass"] * p["rover.gravity"])[name]
    step = sc.step if step is None else step
    stalled = (lambda last: last["front_left.slip"] >= STALL_SLIP) \
        if name in STALL_SCENARIOS else None
    run = engine or (lambda *a, **k: simulate(*a, **k))
    res = run(soil, {**values, **sc.profile}, sc.stop, step=step, stop_when=stalled)
    keep = res.time >= sc.settle
    out = {"scenario": name, "gravity": gravity, "engine": res.engine,
           "left_domain": res.left_domain,
           "simulated_time_s": float(res.time[-1] + step), "wall_time_s": res.wall_time,
           "real_time_factor": float((res.time[-1] + step) / max(res.wall_time, 1e-12)),
           "averaged_from_s": sc.settle, "step_s": step,
           "soil_memory": int(terrain["model.soil_memory"]),
           "rut_shear": int(terrain["model.rut_shear"]),
           "wheels": [{"name": w, "mean_slip": _mean(v["slip"], keep),
                       "mean_sinkage": _mean(v["sinkage"], keep),
                       "mean_normal_force": _mean(v["normal_force"], keep),
                       "mean_drawbar_pull": _mean(v["drawbar_pull"], keep),
                       "mean_motor_power": _mean(v["motor_torque"] * v["wheel_speed"], keep),
                       "rut_depth": _mean(v["rut_left"], keep),
                       "peak_sinkage": _peak(v["sinkage"], res.time, sc.settle)}
                      for w, v in res.wheels.items()]}
    if name in STALL_SCENARIOS:
        slip = res.wheels["front_left"]["slip"]
        hit = np.flatnonzero(slip >= STALL_SLIP)
        if not hit.size and res.left_domain and slip.size:  # slip went past 1 in one step
            hit = np.array([slip.size - 1])
        k = int(hit[0]) if hit.size else len(slip) - 1
        if name == "slope":
            out["stall_slope_deg"] = math.degrees(res.inputs["slope"][k]) if hit.size else None
            out["predicted_stall_slope_deg"] = math.degrees(pred["slope"])
            out["predicted_stall_limit"] = pred["limit"]
            out["stall_cause"] = (run_cause(res, quiet, p, float(res.inputs["slope"][k]))
                                  if hit.size else None)
            out["slip_vs_slope"] = slip_vs_slope(res)
        else:
            out["stall_towing_force"] = float(res.inputs["towing_force"][k]) \
                if hit.size else None
            out.update(pull_curve(res, quiet, p, k))
    if name in TRACKED_SCENARIOS:
        out.update(tracking(res, soil, p))
    if name == "descent":
        out["predicted_descent_limit_deg"] = math.degrees(pred["slope"])
        out["predicted_descent_limit"] = pred["limit"]
        out["slide_slope_deg"] = (math.degrees(res.inputs["slope"][-1])
                                  if res.left_domain else None)
        out["stall_cause"] = (run_cause(res, quiet, p, float(res.inputs["slope"][-1]))
                              if res.left_domain else None)
        out["slip_vs_slope"] = slip_vs_slope(res)
    return {"figures": out, "result": res, "values": {**values, **sc.profile},
            "stop": sc.stop, "step": step}


NO_RIPPLE = {"ripple.k_g": 0.0, "ripple.k_0": 0.0}
TRACKED_SCENARIOS = ("level", "soft-patch")
"""Scenarios on level ground, where the rover has a steady motion to hold (:func:`tracking`)."""
LIMIT_SCENARIOS = ("slope", "descent", "pull-test")
"""Scenarios that run until the rover reaches a limit (a stall or a slide): each ends at a step
a wheel's contact model refuses (it leaves the model's domain)."""
TRACKING_FROM = 2.0  # s: the rover has sunk in and settled (a controller may take over here)


def steady_level_motion(soil: Soil, p: Mapping[str, float]) -> tuple[float, float]:
    """(slip, speed [m/s]) of the rover's steady motion on level ground on ``soil``'s base
    soil, ripple-free (the self-propelled slip of the speed loops)."""
    quiet = terrain_of(soil.base.with_values(NO_RIPPLE))
    slip = steady_slip(quiet, p, 0.0)
    if slip is None:
        raise WheelTerrainError("the rover has no steady motion on level ground with this "
                                "soil")
    return slip, (1.0 - slip) * p["rover.rim_speed"]


def tracking(res: RoverResult, soil: Soil, p: Mapping[str, float]) -> dict:
    """How far a run strays from the steady level motion from TRACKING_FROM on: the RMS of
    every wheel's slip error and of the relative speed error (a controller's score)."""
    slip, speed = steady_level_motion(soil, p)
    keep = res.time >= TRACKING_FROM
    errors = np.concatenate([v["slip"][keep] - slip for v in res.wheels.values()])
    relative = res.chassis["speed"][keep] / speed - 1.0
    return {"slip_reference": slip, "speed_reference": speed,
            "slip_rms": float(np.sqrt(np.mean(errors**2))) if errors.size else None,
            "speed_rms_relative": float(np.sqrt(np.mean(relative**2)))
            if relative.size else None,
            "tracking_from_s": TRACKING_FROM}


def _peak(values: np.ndarray, time: np.ndarray, settle: float) -> float | None:
    """The largest value from ``settle`` s on, or from TRACKING_FROM (after the rover has
    landed in the soil and its first sinking has settled) where the averaging starts earlier;
    None where the run ended before."""
    keep = time >= max(settle, TRACKING_FROM)
    return float(np.max(values[keep])) if keep.any() else None


def _mean(values: np.ndarray, keep: np.ndarray) -> float | None:
    """Mean over the averaging window; None where the run ended before it (left_domain says
    why)."""
    return float(np.mean(values[keep])) if keep.any() else None


def pull_curve(res: RoverResult, terrain: Mapping, p: Mapping[str, float], end: int,
               points: int = 12) -> dict:
    """The pull-test's curve: the towing force the rover holds against its slip (both averaged
    over one grouser period), sampled at ``points`` slips from 0.02 up to the slip where the
    steady motion loses its stability (:func:`growth_rate`, towing balanced) or 0.9, beside the
    sum of the four single-wheel steady pulls at those slips with the loads of
    :func:`rover.steady_balance`. On a soil with memory the stability is :func:`holds`'s."""
    from scipy.optimize import brentq

    top = 0.9
    if has_memory(terrain):  # no linearisation: the perturbed motion is run (:func:`holds`)
        def stable(i: float) -> bool:
            return holds(terrain, p, 0.0, i, balance_tow=True)

        if not stable(top):
            lo, hi = 0.02, top
            if not stable(lo):
                hi = lo
            while hi - lo > 1e-3:
                mid = (lo + hi) / 2
                lo, hi = (mid, hi) if stable(mid) else (lo, mid)
            top = lo
    else:
        def rate(i: float) -> float:
            return growth_rate(terrain, p, 0.0, i, balance_tow=True)["rate"]

        if rate(top) > 0:
            top = brentq(rate, 0.02, top, xtol=1e-5) if rate(0.02) < 0 else 0.02
    omega = p["rover.rim_speed"] / p["rover.slip_radius"]
    n_g = max(terrain["front_left"]["grouser.count"], 1)
    window = max(round(2 * math.pi / (n_g * omega) / (res.time[1] - res.time[0])), 1)
    kernel = np.ones(window) / window
    slip = np.convolve(res.wheels["front_left"]["slip"][:end + 1], kernel, "valid")
    tow = np.convolve(res.inputs["towing_force"][:end + 1], kernel, "valid")
    curve, predicted = [], []
    for target in np.linspace(0.02, top * 0.98, points):
        if not (slip >= target).any():
            break
        k = int(np.argmax(slip >= target))
        curve.append([float(slip[k]), float(tow[k])])
        b = rover.steady_balance(terrain, p, 0.0, float(slip[k]))
        predicted.append(float(sum(b["wheels"][w]["drawbar_pull"] for w in rover.WHEELS)))
    errors = [abs(c[1] - q) for c, q in zip(curve, predicted, strict=True)]
    return {"pull_curve": curve, "predicted_pull": predicted, "stable_up_to_slip": top,
            "pull_curve_max_error_n": max(errors) if errors else None}


COMPARED = ("slip", "sinkage", "normal_force", "drawbar_pull")
"""The per-wheel means two engines' runs of a scenario are compared on."""


def difference(ref: RoverResult, other: RoverResult, settle: float) -> dict:
    """How far ``other``'s run of a scenario is from ``ref``'s: the largest relative difference
    of the per-wheel means of COMPARED (the pull, which averages near 0 on level ground, on its
    wheel's normal force) over the window both runs cover, from the scenario's ``settle`` time
    (from TRACKING_FROM where a run ends before it: a descent that slides) to where the
    shorter run ends (a stall ends a run, and an engine may stall a little earlier or later).
    Returns ``worst``, ``where`` (wheel.quantity) and ``window`` [s]."""
    end = min(float(ref.time[-1]), float(other.time[-1]))
    start = settle if settle < end else TRACKING_FROM

    def means(res: RoverResult) -> dict[str, float]:
        keep = (res.time >= start) & (res.time <= end)
        return {f"{w}.{k}": float(np.mean(d[k][keep])) for w, d in res.wheels.items()
                for k in COMPARED}

    a, b = means(ref), means(other)
    worst, where = 0.0, ""
    for key, value in a.items():
        wheel = key.split(".")[0]
        scale = abs(a[f"{wheel}.normal_force"]) if "pull" in key else abs(value)
        d = abs(b[key] - value) / scale
        if d > worst:
            worst, where = d, key
    return {"worst": worst, "where": where, "window": (start, end)}


def record_units() -> dict[str, str]:
    """Units of the series a rover run writes (CSV headers)."""
    per_wheel = {"slip": "1", "sinkage": "m", "normal_force": "N", "drawbar_pull": "N",
                 "torque": "N.m", "motor_torque": "N.m", "wheel_speed": "rad/s",
                 "rut_left": "m"}
    units = {"time": "s", "position": "m", "speed": "m/s", "heave": "m", "pitch": "rad",
             "slope": "rad", "towing_force": "N"}
    units.update({f"{w}.{k}": u for w in rover.WHEELS for k, u in per_wheel.items()})
    return units
