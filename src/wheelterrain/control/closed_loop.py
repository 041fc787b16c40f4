"""The NMPC in closed loop with a plant: the two FMUs through fmpy, or the same Functions in
process; scenarios, online soil estimation and the figures issue 5 asks for.

Plants
    :class:`FMUPlant` co-simulates SingleWheelRig.fmu (rig.drive = 1: the speed loop tracks the
    MPC's command) and WheelTerrain.fmu through fmpy with the master of
    :mod:`wheelterrain.cosim.master` (Gauss-Seidel, 1 ms). :class:`CasadiPlant` runs the very same
    Functions (``terrain_dynamic``, :func:`wheelterrain.model.rig.step`) in process with the same
    coupling. When the models agree the two trajectories agree to rounding; when they do not,
    the harness is wrong (a forgotten input update once hid that way).

Estimator
    :class:`SoilEstimator`, an extended Kalman filter on (soil.phi, soil.k_phi) as random walks.
    Its measurement model is the terrain Function itself: the normal force and drawbar pull the
    rig's force sensor reads, predicted at the measured sinkage, sinkage rate, speeds and wheel
    angle, with exact CasADi Jacobians with respect to the two parameters.
"""

from __future__ import annotations

import math
import shutil
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import casadi as ca
import numpy as np

from wheelterrain import model
from wheelterrain.control import mpc
from wheelterrain.cosim import master as cosim
from wheelterrain.fmu import functions as fmu_model
from wheelterrain.fmu import variables
from wheelterrain.model import rig
from wheelterrain.parameters import INDEX, NAMES, TABLE, ParameterSet

PLANT_STEP = cosim.STEP  # s, the co-simulation's communication step
RECORD = ("time", "slip", "slip_reference", "command", "wheel_speed", "motor_torque",
          "sinkage", "drawbar_pull", "normal_force", "soil_torque", "phi_estimate",
          "k_phi_estimate", "phi_true", "k_phi_true", "carriage_speed")
RECORD_UNITS = {"slip_reference": "1", "command": "rad/s", "soil_torque": "N.m",
                "phi_estimate": "rad", "k_phi_estimate": "1", "phi_true": "rad",
                "k_phi_true": "1"}
"""Units of the recorded columns that are not FMU variables (the rest: variables.units)."""


def record_units() -> dict[str, str]:
    """The unit of every RECORD column (the result CSV's header)."""
    return {**variables.units(), **RECORD_UNITS}
ESTIMATED = ("soil.phi", "soil.k_phi")
MEASURED = ("normal_force", "drawbar_pull")  # what the soil estimator's update compares


@dataclass(frozen=True)
class Scenario:
    """A closed-loop run: slip reference steps, the soil change, the scoring windows."""

    name: str
    description: str
    duration: float  # s
    reference: tuple[tuple[float, float], ...]  # (from time s, traction slip reference)
    slip_paper: float = 0.25  # the rig's carriage: V = rim_speed/(1 + slip_paper)
    soil_change_time: float | None = None  # s
    soil_change: tuple[tuple[str, float], ...] = ()  # (parameter, factor)
    estimate: bool = False
    score_after: float = 1.0  # s after each reference step or soil change: the transient
    objective: str = "track"
    carriage: int = rig.CARRIAGE_KINEMATIC
    towing_force: float | None = 0.0  # N; None: balanced, the steady drawbar pull at the
    # first reference (the vehicle neither speeds up nor slows down there)
    soil: tuple[tuple[str, float], ...] = ()  # table parameters set for this scenario
    settle: float = 1.0  # s before t = 0: the wheel sinks in at the first reference's speed

    def reference_at(self, t: float) -> float:
        value = self.reference[0][1]
        for start, slip in self.reference:
            if t >= start - 1e-12:
                value = slip
        return value

    def events(self) -> list[float]:
        """Times [s] that start a transient: reference steps and the soil change."""
        events = [start for start, _ in self.reference]
        if self.soil_change_time is not None:
            events.append(self.soil_change_time)
        return sorted(events)

    def scored(self, t: np.ndarray) -> np.ndarray:
        """Samples outside every transient window (a reference step, the soil change)."""
        mask = np.ones_like(t, dtype=bool)
        for event in self.events():
            mask &= ~((t >= event - 1e-12) & (t < event + self.score_after))
        return mask


SCENARIOS = {s.name: s for s in (
    Scenario("nominal", "slip reference 0.2 then 0.35 at 3 s on the calibrated soil",
             6.0, ((0.0, 0.2), (3.0, 0.35))),
    Scenario("terrain-change", "reference 0.2; at 2 s the soil under the wheel loses 15 % of "
             "its friction angle and gains 20 % of k_phi; an EKF re-estimates both online",
             8.0, ((0.0, 0.2),), soil_change_time=2.0,
             soil_change=(("soil.phi", 0.85), ("soil.k_phi", 1.2)), estimate=True,
             score_after=3.0),
    Scenario("free-carriage", "a rover wheel: the carriage is free and tows the drawbar pull "
             "the quasi-static model gives at slip 0.2; reference 0.2. Grouser ripple off (a "
             "rover's wheels are out of phase; one wheel's ripple, +-1 N on 6.3 kg, surges the "
             "3 cm/s carriage by more than its speed)", 6.0, ((0.0, 0.2),),
             carriage=rig.CARRIAGE_FREE, towing_force=None, soil=(("ripple.k_g", 0.0),)),
    Scenario("efficiency", "maximise drawbar pull per unit motor power (tractive efficiency) "
             "instead of tracking", 4.0, ((0.0, 0.2),), objective="efficiency"),
)}


def rig_parameters(ps: ParameterSet, scenario: Scenario, load: float = 62.0,
                   rim_speed: float = 0.03) -> dict[str, float]:
    """The rig of C1-C4 with the wheel speed commanded (rig.drive 1) and the scenario's
    carriage."""
    values = cosim.rig_parameters(ps, scenario.slip_paper, load, rim_speed)
    towing = scenario.towing_force
    if towing is None:
        towing = model.steady_state(ps, load=load, slip=scenario.reference_at(0.0))[
            "drawbar_pull"]
    values.update({"rig.drive": rig.DRIVE_SPEED, "rig.carriage": scenario.carriage,
                   "rig.towing_force": towing})
    for name, value in values.items():
        rig.check(name, value)
    return values


# ------------------------------------------------------------------------------------------------
# Plants


class CasadiPlant:
    """SingleWheelRig + WheelTerrain as their Functions in process, coupled as cosim couples the
    FMUs."""

    def __init__(self, ps: ParameterSet, p_rig: dict[str, float]) -> None:
        self.terrain, _, self.memory = fmu_model.terrain_functions()
        self.p = np.array([ps[name] for name in NAMES])
        self.p_rig = dict(p_rig)
        self.x = rig.initial_state(self.p_rig)
        self.angle = 0.0
        self.plastic = 0.0  # WheelTerrain's plastic sinkage
        self.motor_torque = 0.0

    def set_soil(self, values: dict[str, float]) -> None:
        for name, value in values.items():
            self.p[INDEX[name]] = value

    def set_rig(self, values: dict[str, float]) -> None:
        self.p_rig.update(values)

    def _inputs(self) -> list[float]:
        """WheelTerrain's inputs (TERRAIN_INPUTS) at the rig's state, as the FMU pair couples
        them (no rut met: the rig's strip is virgin soil)."""
        given = {**dict(zip(rig.RIG_STATES, self.x, strict=True)),
                 "load": self.p_rig["rig.load"], "rut_met": 0.0, "rut_pressure_met": 0.0,
                 "slip_angle": 0.0, "yaw_rate": 0.0}
        return [given[n] for n in fmu_model.TERRAIN_INPUTS]

    def _forces(self) -> np.ndarray:
        """The terrain's outputs (TERRAIN_OUTPUTS) at the rig's state, its inputs by name."""
        u = self._inputs()
        y, status, info, _ = self.terrain(u, self.angle, self.plastic, self.p)
        if int(status) != fmu_model.STATUS_OK:
            raise mpc.PlantError("the in-process plant refused the step: "
                                 + fmu_model.status_message(int(status), float(info), u))
        return np.array(y).ravel()

    def state(self) -> np.ndarray:
        return np.array([*self.x, self.angle, self.plastic])

    def advance(self, command: float, steps: int, record: Callable) -> None:
        for _ in range(steps):
            y = self._forces()
            given = {**dict(zip(fmu_model.TERRAIN_OUTPUTS, y, strict=True)),
                     "wheel_speed_command": command, "motor_torque_command": 0.0}
            forces = tuple(given[n] for n in variables.RIG_INPUTS)
            record(self.x, self.angle, y, self.motor_torque)
            # WheelTerrain advances its angle and plastic sinkage with the inputs it was given
            omega = self.x[rig.RIG_STATES.index("wheel_speed")]
            self.plastic = float(self.memory(self._inputs(), self.plastic, self.p, PLANT_STEP))
            self.x, self.motor_torque = rig.step(self.x, forces, self.p_rig, PLANT_STEP)
            self.angle += omega * PLANT_STEP

    def close(self) -> None:
        pass


class FMUPlant:
    """SingleWheelRig.fmu + WheelTerrain.fmu through fmpy (one extraction, two instances)."""

    def __init__(self, fmu_dir: Path, ps: ParameterSet, p_rig: dict[str, float]) -> None:
        from fmpy import extract

        paths = cosim.fmu_paths(fmu_dir)
        self.unzipped = {name: extract(str(p)) for name, p in paths.items()}
        self.terrain, self.rig = cosim.start_pair(paths, self.unzipped, ps, p_rig)
        rig_extra = ("speed_error_integral", "motor_torque")
        terrain_extra = (*(n for n in fmu_model.TERRAIN_OUTPUTS
                           if n not in variables.COUPLED_FORCES), "wheel_angle")
        self.pair = cosim.Coupling(self.terrain, self.rig, rig_extra=rig_extra,
                                   terrain_extra=terrain_extra,
                                   commands=("wheel_speed_command",))
        # what one exchange returns, by name (the Coupling's order)
        self._rig_names = (*variables.COUPLED_STATES, *rig_extra)
        self._terrain_names = (*variables.COUPLED_FORCES, *terrain_extra)
        self.t = 0.0

    def set_soil(self, values: dict[str, float]) -> None:
        self.terrain.set(values)

    def set_rig(self, values: dict[str, float]) -> None:
        self.rig.set(values)

    def state(self) -> np.ndarray:
        """mpc.MPC_STATES: the rig's states (rig.RIG_STATES), then the terrain's wheel angle and
        plastic sinkage."""
        return np.array([*self.rig.get(rig.RIG_STATES),
                         *self.terrain.get(("wheel_angle", "plastic_sinkage"))])

    def advance(self, command: float, steps: int, record: Callable) -> None:
        for _ in range(steps):
            r, y = self.pair.exchange((command,))
            rv = dict(zip(self._rig_names, r, strict=True))
            tv = dict(zip(self._terrain_names, y, strict=True))
            record(tuple(rv[n] for n in rig.RIG_STATES), tv["wheel_angle"],
                   [tv[n] for n in fmu_model.TERRAIN_OUTPUTS], rv["motor_torque"])
            try:
                self.pair.step(self.t, PLANT_STEP)
            except Exception as err:  # fmpy raises FMICallException on fmi2Discard/Error
                raise mpc.PlantError(f"the FMU plant refused the step at t = {self.t:g} s: "
                                   f"{err}") from err
            self.t += PLANT_STEP

    def close(self) -> None:
        for inst in (self.terrain, self.rig):
            inst.close()
        for d in self.unzipped.values():
            shutil.rmtree(d, ignore_errors=True)


# ------------------------------------------------------------------------------------------------
# Online soil estimation


ESTIMATOR_STATES = (*rig.RIG_STATES, "wheel_angle")
"""The wheel state the soil estimator's measurement model reads (it yields the soil at the
wheel's sinkage: the plastic sinkage is not part of it)."""


class SoilEstimator:
    """EKF on (soil.phi, soil.k_phi) as random walks, relative to their nominal values.

    Measurement: the normal force and drawbar pull of the terrain Function at the measured
    wheel state; Jacobians by CasADi. An estimate that would leave a parameter's valid range is
    projected back onto it and counted in ``projections`` (reported, never silent).
    """

    def __init__(self, p: np.ndarray, load: float, interval: float) -> None:
        terrain = fmu_model.terrain_functions()[0]
        theta = ca.MX.sym("theta", len(ESTIMATED))
        x = ca.MX.sym("x", len(ESTIMATOR_STATES))
        pt = ca.MX.sym("p", len(NAMES))
        nominal = np.array([p[INDEX[name]] for name in ESTIMATED])
        scaled = ca.vertcat(*(pt[INDEX[n]] if n not in ESTIMATED
                              else theta[ESTIMATED.index(n)] * nominal[ESTIMATED.index(n)]
                              for n in NAMES))
        xs = dict(zip(ESTIMATOR_STATES, ca.vertsplit(x), strict=True))
        # the soil's memory off the measurement model: the wheel yields at its sinkage
        out = dict(zip(fmu_model.TERRAIN_OUTPUTS, ca.vertsplit(
            terrain(mpc.terrain_inputs(xs, load), xs["wheel_angle"], xs["sinkage"], scaled)[0]),
            strict=True))
        y = ca.vertcat(*(out[n] for n in MEASURED))
        self.measure = ca.Function("soil_measurement", [theta, x, pt], [y, ca.jacobian(y, theta)])
        self.nominal, self.p = nominal, np.array(p, dtype=float)
        self.theta = np.ones(len(ESTIMATED))
        self.P = np.diag([0.1**2, 0.3**2])  # prior: +-10 % phi, +-30 % k_phi
        # random walk per update: the soil may change along the track
        self.Q = np.diag([0.002**2, 0.006**2]) * (interval / 0.02)
        self.R = np.diag([0.2**2, 0.2**2])  # N^2: force sensor resolution
        self.lower = np.array([TABLE[INDEX[n]].min for n in ESTIMATED]) / nominal
        self.upper = np.array([TABLE[INDEX[n]].max for n in ESTIMATED]) / nominal
        self.projections = 0

    def update(self, x: np.ndarray, measured: np.ndarray) -> np.ndarray:
        """One predict-update with the state ``x`` (ESTIMATOR_STATES) and the forces measured
        there; returns the table parameter vector with the estimates."""
        self.P = self.P + self.Q
        y, H = (np.array(v) for v in self.measure(self.theta, x, self.p))
        S = H @ self.P @ H.T + self.R
        K = self.P @ H.T @ np.linalg.inv(S)
        theta = self.theta + K @ (np.asarray(measured) - y.ravel())
        self.P = (np.eye(len(theta)) - K @ H) @ self.P
        clipped = np.clip(theta, self.lower, self.upper)
        self.projections += int(np.any(clipped != theta))
        self.theta = clipped
        return self.parameters()

    def parameters(self) -> np.ndarray:
        p = self.p.copy()
        for k, name in enumerate(ESTIMATED):
            p[INDEX[name]] = self.theta[k] * self.nominal[k]
        return p


# ------------------------------------------------------------------------------------------------
# The loop


@dataclass
class Result:
    scenario: str
    plant: str
    settings: mpc.Settings
    series: dict[str, np.ndarray] = field(repr=False)
    solve_times: np.ndarray = field(repr=False)
    iterations: np.ndarray = field(repr=False)
    failures: int = 0
    projections: int = 0
    wall_time: float = 0.0

    def figures(self, scenario: Scenario) -> dict:
        t = self.series["time"]
        mask = scenario.scored(t)
        error = self.series["slip"] - self.series["slip_reference"]
        out = {"scenario": self.scenario, "plant": self.plant,
               "solver": self.settings.solver, "compiled": self.settings.compiled,
               "memory": self.settings.memory,
               "horizon": self.settings.horizon, "interval_s": self.settings.interval,
               "solve_time_median_s": float(np.median(self.solve_times)),
               "solve_time_p90_s": float(np.percentile(self.solve_times, 90)),
               "solve_time_max_s": float(np.max(self.solve_times)),
               "iterations_median": float(np.median(self.iterations)),
               "failed_solves": self.failures, "mpc_steps": len(self.solve_times),
               "wall_time_s": self.wall_time}
        if scenario.objective == "track":
            out["slip_rms_error"] = float(np.sqrt(np.mean(error[mask] ** 2)))
            out["slip_max_error"] = float(np.max(np.abs(error[mask])))
            out["scored_from_s"] = [float(e) for e in scenario.events()]
            out["transient_s"] = scenario.score_after
        else:
            late = t >= t[-1] - 1.0
            power = self.series["motor_torque"] * self.series["wheel_speed"]
            speed = self.series["carriage_speed"]
            out["slip_final"] = float(np.mean(self.series["slip"][late]))
            out["tractive_efficiency_final"] = float(
                np.mean(self.series["drawbar_pull"][late] * speed[late]) / np.mean(power[late]))
        if scenario.estimate:
            out["estimator_projections"] = self.projections
            for key in ("phi", "k_phi"):
                est, true = self.series[f"{key}_estimate"][-1], self.series[f"{key}_true"][-1]
                out[f"{key}_estimate_final"] = float(est)
                out[f"{key}_true"] = float(true)
                out[f"{key}_relative_error_final"] = float(abs(est - true) / abs(true))
        return out


def run(scenario: Scenario, ps: ParameterSet, plant: str = "fmu",
        settings: mpc.Settings | None = None, fmu_dir: Path | None = None,
        progress: Callable[[float], None] | None = None) -> Result:
    """Run ``scenario`` with the NMPC against the ``plant`` ('fmu' or 'casadi')."""
    settings = settings or mpc.Settings()
    if scenario.soil:
        ps = ps.with_values(dict(scenario.soil))
    if scenario.objective != settings.objective:
        settings = mpc.Settings(**{**settings.__dict__, "objective": scenario.objective})
    steps = round(settings.interval / PLANT_STEP)
    if not math.isclose(steps * PLANT_STEP, settings.interval, rel_tol=1e-9) or steps < 1:
        raise mpc.MPCError(f"interval = {settings.interval!r} s is out of range; valid: a whole "
                           f"number of plant steps of {PLANT_STEP:g} s")
    # the carriage is held while the wheel sinks in (free, the sinking wheel's compaction
    # resistance would push it backwards) and released at t = 0
    p_rig = {**rig_parameters(ps, scenario), "rig.carriage": rig.CARRIAGE_KINEMATIC}
    if plant == "fmu":
        the_plant = FMUPlant(Path(fmu_dir), ps, p_rig)
    elif plant == "casadi":
        the_plant = CasadiPlant(ps, p_rig)
    else:
        raise mpc.MPCError(f"plant = {plant!r}; valid: fmu, casadi")
    started = time.perf_counter()
    try:
        return _loop(scenario, ps, plant, settings, steps, p_rig, the_plant, progress, started)
    finally:
        the_plant.close()


def _loop(scenario, ps, plant_name, settings, steps, p_rig, plant, progress, started) -> Result:
    controller = mpc.Controller(settings, {**p_rig, "rig.carriage": scenario.carriage})
    p_nominal = np.array([ps[name] for name in NAMES])
    p_true = p_nominal.copy()
    estimator = (SoilEstimator(p_nominal, p_rig["rig.load"], settings.interval)
                 if scenario.estimate else None)
    p_model = p_nominal.copy()
    n = round(scenario.duration / settings.interval)
    rows: list[tuple] = []
    last = {}
    settle_steps = round(scenario.settle / PLANT_STEP)

    def record(x, angle, y, motor_torque):
        """One plant sample: x the rig's states (rig.RIG_STATES), y the terrain's outputs
        (TERRAIN_OUTPUTS); the row holds RECORD, by name."""
        xs = dict(zip(rig.RIG_STATES, x, strict=True))
        ys = dict(zip(fmu_model.TERRAIN_OUTPUTS, y, strict=True))
        last.update(x=np.array([*x, angle]),
                    forces=np.array([ys[n] for n in MEASURED]))
        row = {"time": (len(rows) - settle_steps) * PLANT_STEP, "slip": ys["slip"],
               "slip_reference": state["reference"], "command": state["command"],
               "wheel_speed": xs["wheel_speed"], "motor_torque": motor_torque,
               "sinkage": xs["sinkage"], "drawbar_pull": ys["drawbar_pull"],
               "normal_force": ys["normal_force"], "soil_torque": ys["torque"],
               "phi_estimate": p_model[INDEX["soil.phi"]],
               "k_phi_estimate": p_model[INDEX["soil.k_phi"]],
               "phi_true": p_true[INDEX["soil.phi"]], "k_phi_true": p_true[INDEX["soil.k_phi"]],
               "carriage_speed": xs["carriage_speed"]}
        rows.append(tuple(row[name] for name in RECORD))

    # the wheel is set down on the soil and sinks in at the speed of the first reference (the
    # contact's entry angle has an infinite derivative at zero sinkage: no NLP starts there)
    _, speed = rig.references(p_rig)
    first = scenario.reference_at(0.0)
    state = {"command": speed / (p_rig["rig.slip_radius"] * (1 - first)), "reference": first}
    plant.advance(state["command"], settle_steps, record)
    if scenario.carriage != rig.CARRIAGE_KINEMATIC:
        plant.set_rig({"rig.carriage": scenario.carriage})
    solve_times, iterations, failures = [], [], 0
    for k in range(n):
        t = k * settings.interval
        if scenario.soil_change_time is not None and math.isclose(
                t, scenario.soil_change_time, abs_tol=0.5 * PLANT_STEP):
            change = {name: p_true[INDEX[name]] * factor for name, factor in scenario.soil_change}
            plant.set_soil(change)
            for name, value in change.items():
                p_true[INDEX[name]] = value
        if estimator is not None and "x" in last:
            p_model = estimator.update(last["x"], last["forces"])
        x = plant.state()
        x[5] = mpc.wrap_angle(x[5])
        # the reference as it stands now (no preview: a planner above sets it as it goes)
        step = controller.solve(x, p_model, scenario.reference_at(t), state["command"])
        solve_times.append(step.solve_time)
        iterations.append(step.iterations)
        failures += not step.success
        state["command"], state["reference"] = step.command, scenario.reference_at(t)
        plant.advance(step.command, steps, record)
        if progress:
            progress(settings.interval)
    data = np.array(rows[settle_steps:])
    series = {name: data[:, j] for j, name in enumerate(RECORD)}
    return Result(scenario.name, plant_name, settings, series, np.array(solve_times),
                  np.array(iterations), failures,
                  estimator.projections if estimator else 0, time.perf_counter() - started)
