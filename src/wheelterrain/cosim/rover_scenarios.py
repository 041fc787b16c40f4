"""The rover's scenarios (level, slope, soft-patch, descent, pull-test): each one's input
profile, communication step and stop, and the figures ``wheelterrain rover --json`` reports
from a run of it in any engine (:func:`run_scenario`): means per wheel, the limit met and its
cause beside the prediction (:mod:`.rover_limits`), the slip against the slope, the pull test's
curve, how closely a run holds the steady level motion; and how far two engines' runs of one
scenario differ (:func:`difference`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from wheelterrain.cosim import ruts
from wheelterrain.cosim.rover import STEP, RoverResult, Soil, simulate
from wheelterrain.cosim.rover_limits import (
    SLIDE_SLIP,
    STALL_SLIP,
    growth_rate,
    has_memory,
    holds,
    limit_slope,
    locked_limit,
    run_cause,
    steady_slip,
)
from wheelterrain.errors import WheelTerrainError
from wheelterrain.model import ground, rover
from wheelterrain.model.slip import ground_speed
from wheelterrain.parameters import GRAVITY, NO_RIPPLE, ParameterSet

FINE_STEP = 2.5e-4
"""s: the step of the Moon's stall runs (slope, pull-test, descent). Each ends where the
steady motion loses its stability (the bounce's damping, or the traction); a force handed
over one step late (a delayed soil spring acts as a negative damper) brings that end earlier
by an amount first order in the step. On the Moon, where the grouser ripple is near the
1.5 Hz bounce, the one-step-late engines' mean slip differs from the in-process one by
1.2-2.5e-3 at 1 ms, 0.6-1.1e-3 at 0.5 ms and 1.9-5.9e-4 at this step, halving with the step
(validation/rover_engines.py [--step], README); on Earth 1 ms is enough (at most 8.2e-4)."""

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
                 step: float | None = None, engine: Callable | None = None,
                 progress: Callable[[str, float, float], None] | None = None) -> dict:
    """One scenario: the contract's figures (``wheelterrain rover --json``) and the series.
    ``terrain``: the wheels' terrain parameters (the soft patch scales its soil). ``step``:
    the communication step (default: the scenario's own, ``Scenario.step``: 1 ms, or
    :data:`FINE_STEP` for the Moon's stall runs). ``engine``:
    ``engine(soil, values, stop, step=, stop_when=, progress=) -> RoverResult`` runs it
    (default: :func:`simulate`, in process). ``progress(stage, done, total)``: the limit's
    prediction (trials of its bisection) and the run (simulated seconds of its stop)."""
    if name not in scenarios():
        raise ValueError(f"unknown scenario {name!r}; valid: {', '.join(scenarios())}")
    if gravity not in GRAVITY:
        raise ValueError(f"unknown gravity {gravity!r}; valid: {', '.join(GRAVITY)}")
    values = {**(rover_values or {}), "rover.gravity": GRAVITY[gravity]}
    p = {**rover.defaults(), **values}
    soil = scenario_soil(name, terrain)
    ruts.check_profile(p, soil.map_values())  # every engine's Terrain, not only in process
    quiet = terrain_of(terrain.with_values(NO_RIPPLE))
    pred = None
    if name in ("slope", "descent"):
        trials = ((lambda k, n: progress("predicting the limit", k, n))
                  if progress is not None else None)
        pred = limit_slope(quiet, p, 1 if name == "slope" else -1, trials=trials)
    knee = max(math.degrees(pred["slope"]) - KNEE_MARGIN, 0.0) if name == "slope" else 15.0
    sc = scenarios(gravity, knee, p["rover.mass"] * p["rover.gravity"])[name]
    step = sc.step if step is None else step
    stalled = None
    if name in STALL_SCENARIOS:
        def stalled(last: dict) -> bool:
            return last["front_left.slip"] >= STALL_SLIP
    elif name == "descent":
        def stalled(last: dict) -> bool:
            return min(last[f"{w}.slip"] for w in rover.WHEELS) <= SLIDE_SLIP
    run = engine or (lambda *a, **k: simulate(*a, **k))
    simulated = ((lambda t: progress(f"simulating {name}", t, sc.stop))
                 if progress is not None else None)
    res = run(soil, {**values, **sc.profile}, sc.stop, step=step, stop_when=stalled,
              progress=simulated)
    keep = res.time >= sc.settle
    out = {"scenario": name, "gravity": gravity, "engine": res.engine,
           "left_domain": res.left_domain,
           "simulated_time_s": float(res.time[-1] + step), "wall_time_s": res.wall_time,
           "real_time_factor": float((res.time[-1] + step) / max(res.wall_time, 1e-12)),
           "averaged_from_s": sc.settle, "step_s": step,
           "soil_memory": int(terrain["model.soil_memory"]),
           "rut_shear": terrain["model.rut_shear"],
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
            out["predicted_stability_mode"] = pred["mode"]
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
        out["predicted_stability_mode"] = pred["mode"]
        locked = locked_limit(quiet, p)  # the soil's own braking limit, whatever the drive
        out["locked_limit_deg"] = None if locked is None else math.degrees(locked)
        # the first step a wheel's slip passes SLIDE_SLIP (a run checks its stop condition
        # once a block, in process, and may record some steps past it), else the run's end
        # where it left the domain
        lowest = np.min([v["slip"] for v in res.wheels.values()], axis=0)
        hit = np.flatnonzero(lowest <= SLIDE_SLIP)
        ended = bool(hit.size) or res.left_domain
        k = int(hit[0]) if hit.size else len(res.time) - 1
        out["slide_slope_deg"] = math.degrees(res.inputs["slope"][k]) if ended else None
        out["stall_cause"] = (run_cause(res, quiet, p, float(res.inputs["slope"][k]))
                              if ended else None)
        out["slip_vs_slope"] = slip_vs_slope(res)
    return {"figures": out, "result": res, "values": {**values, **sc.profile},
            "stop": sc.stop, "step": step}


TRACKED_SCENARIOS = ("level", "soft-patch")
"""Scenarios on level ground, where the rover has a steady motion to hold (:func:`tracking`)."""
LIMIT_SCENARIOS = ("slope", "descent", "pull-test")
"""Scenarios that run until the rover reaches a limit (a stall or a slide): each ends at a step
a wheel's contact model refuses (it leaves the model's domain)."""
TRACKING_FROM = 2.0  # s: the rover has sunk in and settled (a controller may take over here)


BAND_VARIANTS = {
    "K_u 4e6": ({"soil.unloading_stiffness": 4e6}, {}),
    "K_u 4e8": ({"soil.unloading_stiffness": 4e8}, {}),
    "phases aligned": ({}, {f"rover.grouser_phase.{w}": 0.0 for w in rover.WHEELS}),
    "C_f 400": ({"soil.damping": 400.0}, {}),
    "C_f 1600": ({"soil.damping": 1600.0}, {}),
    "rut_shear 0": ({"model.rut_shear": 0.0}, {}),
}
"""The unmeasured values a rover limit depends on, one at a time at each end of its band, as
(terrain values, rover values): soil.unloading_stiffness K_u over its plausible range (4e6-4e8
Pa/m: Chrono's SCM demos use 4e7-4e8, a decade softer for loose sand; not measured for this
soil), the four grouser phases aligned against the default spread, soil.damping C_f at half and
twice the paper's 800 N.s/m (one value without a source in the paper; the factor 2 is an
assumption), and model.rut_shear at 0 against the default 1 (SCM's node keeps all of the shear
displacement; 0, the rear wheels shearing afresh in the front wheels' ruts, is the other end of
an unmeasured share)."""
BAND_EVENTS = {"slope": "stall_slope_deg", "descent": "slide_slope_deg"}


def limit_band(name: str, terrain: ParameterSet, gravity: str = "earth",
               rover_values: Mapping[str, float] | None = None,
               progress: Callable[[str, float, float], None] | None = None) -> dict:
    """Scenario ``name`` (slope or descent), in process, at ``terrain`` and at each of
    BAND_VARIANTS: ``runs`` (per variant, default first: ``variant``, ``limit_deg``, the
    scenario's ``cause``, ``predicted_deg``, ``predicted_limit``, ``locked_limit_deg`` on the
    descent) and ``low`` / ``high``, the smallest and largest |limit| [deg] over the runs that
    reached one (None where none did; ``without_limit`` counts those that did not)."""
    if name not in BAND_EVENTS:
        raise ValueError(f"limit_band runs {', '.join(BAND_EVENTS)}, not {name!r}")
    variants = {"default": ({}, {}), **BAND_VARIANTS}
    runs = []
    for k, (variant, (soil_values, chassis_values)) in enumerate(variants.items()):
        if progress is not None:
            progress(f"the band's runs ({variant})", k, len(variants))
        f = run_scenario(name, terrain.with_values(soil_values), gravity,
                         {**(rover_values or {}), **chassis_values})["figures"]
        runs.append({"variant": variant, "limit_deg": f[BAND_EVENTS[name]],
                     "cause": f["stall_cause"],
                     "predicted_deg": f.get("predicted_stall_slope_deg",
                                            f.get("predicted_descent_limit_deg")),
                     "predicted_limit": f.get("predicted_stall_limit",
                                              f.get("predicted_descent_limit")),
                     "locked_limit_deg": f.get("locked_limit_deg")})
    reached = [abs(r["limit_deg"]) for r in runs if r["limit_deg"] is not None]
    return {"scenario": name, "gravity": gravity, "runs": runs,
            "low": min(reached) if reached else None, "high": max(reached) if reached else None,
            "without_limit": len(runs) - len(reached)}


def steady_level_motion(soil: Soil, p: Mapping[str, float]) -> tuple[float, float]:
    """(slip, speed [m/s]) of the rover's steady motion on level ground on ``soil``'s base
    soil, ripple-free (the self-propelled slip of the speed loops)."""
    quiet = terrain_of(soil.base.with_values(NO_RIPPLE))
    slip = steady_slip(quiet, p, 0.0)
    if slip is None:
        raise WheelTerrainError("the rover has no steady motion on level ground with this "
                                "soil")
    return slip, ground_speed(slip, p["rover.rim_speed"])


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
    :func:`rover.steady_balance`. On a soil with memory the stability is :func:`holds`'s, and
    each rear wheel runs in the rut its front wheel left where the rear wheel meets it (a
    wheelbase less terrain.lookahead of travel before), at the slip the rover had then: the
    rut keeps the pressure it was made with (soil.rut_pressure), so a rear wheel whose slip
    has risen since meets a rut made at a lower one."""
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
    position = np.convolve(res.chassis["position"][:end + 1], kernel, "valid")
    back = p["rover.wheelbase"] - ground.defaults()["terrain.lookahead"]
    memory = has_memory(terrain)
    curve, predicted = [], []
    for target in np.linspace(0.02, top * 0.98, points):
        if not (slip >= target).any():
            break
        k = int(np.argmax(slip >= target))
        curve.append([float(slip[k]), float(tow[k])])
        made = None
        if memory:  # the slip at which the front wheels made the ruts the rear ones meet
            then = int(np.searchsorted(position, position[k] - back))
            made = rover.steady_balance(terrain, p, 0.0, float(slip[min(then, k)]))
            made = {w: made["wheels"][a] for w, a in rover.LEADING.items()}
        b = rover.steady_balance(terrain, p, 0.0, float(slip[k]), ruts=made)
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
