"""``wheelterrain rover`` as one call: the registry of ways to run the rover (an engine and a
controller), the FMU folder, the scenario, and the files written as one set.

Every way to run a scenario is an entry of :data:`RUNNERS`, keyed by (engine, controller): the
in-process engine with the speed loops or with the slip NMPC per wheel, our FMU master, and
each SSP engine. An entry says what it needs (the FMUs) and, before any work, why it cannot run
a request (:meth:`Runner.refusal`): a pair that is not in the registry, a scenario the engine
cannot run, a step the controller does not take. Refusals are :class:`UsageError`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from wheelterrain import files
from wheelterrain.cosim import (
    ROVER_CONTROLLERS,
    ROVER_ENGINES,
    SSP_ENGINES,
    master,
    rover_fmus,
    rover_scenarios,
    ssp,
)
from wheelterrain.cosim import rover as rover_engine
from wheelterrain.errors import FMUError, UsageError
from wheelterrain.parameters import GRAVITY, ParameterSet

Progress = Callable[[str, float, float], None]


@dataclass(frozen=True)
class Request:
    """What ``wheelterrain rover`` was asked for."""

    scenario: str
    terrain: ParameterSet
    gravity: str = "earth"
    chassis: Mapping[str, float] = field(default_factory=dict)
    step: float | None = None
    engine: str = "in-process"
    controller: str = "speed"
    band: bool = False
    """Also the limit over its unmeasured values' bands (rover_scenarios.limit_band)."""


@dataclass(frozen=True)
class Runner:
    """One way to run the rover: ``engine`` with ``controller``."""

    engine: str
    controller: str
    description: str
    needs_fmus: bool
    start: Callable[[Path, str, dict], Callable | None]
    """(FMU folder, scenario, figures to add to) -> the ``engine`` of
    :func:`wheelterrain.cosim.rover_scenarios.run_scenario` (None: in process)."""
    refuses: Callable[[Request], str | None] = lambda request: None

    def refusal(self, request: Request) -> str | None:
        """Why this runner cannot run ``request`` (said before any work), or None."""
        if self.engine in SSP_ENGINES and (missing := ssp.engine_missing(self.engine)):
            return f"--engine {self.engine}: {missing}"
        return self.refuses(request)


def _speed_loops(engine: str) -> Runner:
    """The speed loops on ``engine``: in process, our master on the FMUs, or an SSP engine."""
    text = {"in-process": "the chassis and contact Functions stepped together, compiled",
            "fmus": "RoverChassis.fmu, four WheelTerrain.fmu and two Terrain.fmu through fmpy, "
                    "our master"}.get(engine, f"Rover-<scenario>.ssp in {engine}")

    def refuses(request: Request) -> str | None:
        soil = rover_scenarios.scenario_soil(request.scenario, request.terrain)
        reason = rover_fmus.refusal(engine, request.scenario, soil)
        return f"--engine {engine} --scenario {request.scenario}: {reason}" if reason else None

    return Runner(engine, "speed", text, engine != "in-process",
                  lambda folder, scenario, figures: rover_fmus.runner(engine, folder, scenario),
                  refuses)


def _mpc_refuses(request: Request) -> str | None:
    if request.scenario not in rover_scenarios.TRACKED_SCENARIOS:
        return (f"--controller mpc runs {' and '.join(rover_scenarios.TRACKED_SCENARIOS)} (each "
                f"wheel's prediction is a quarter rover on level ground), not "
                f"{request.scenario}")
    if request.step is not None and not math.isclose(request.step, rover_engine.STEP):
        return f"--controller mpc runs at the rover's step of {rover_engine.STEP:g} s"
    return None


def _mpc_start(folder: Path, scenario: str, figures: dict) -> Callable:
    """The in-process rover with the slip NMPC per wheel commanding its speed; its solver's
    figures are added to ``figures``."""
    from wheelterrain.control import rover_mpc

    def engine(soil, values, stop, step, stop_when, progress=None):
        run = rover_mpc.run(soil, values, stop, progress=progress)
        figures.update(
            controller_solver=run.settings.solver, speed_weight=run.settings.speed_weight,
            solve_time_median_s=float(np.median(run.solve_times)),
            solve_time_p90_s=float(np.percentile(run.solve_times, 90)),
            failed_solves=run.failures, solves=int(run.solve_times.size))
        return run.result

    return engine


RUNNERS: dict[tuple[str, str], Runner] = {
    **{(e, "speed"): _speed_loops(e) for e in ROVER_ENGINES},
    ("in-process", "mpc"): Runner("in-process", "mpc", "the slip NMPC per wheel (real-time "
                                  "iteration) commanding its speed, in process", False,
                                  _mpc_start, _mpc_refuses),
}
assert {e for e, _ in RUNNERS} == set(ROVER_ENGINES)
assert {c for _, c in RUNNERS} == set(ROVER_CONTROLLERS)


def runner_for(engine: str, controller: str) -> Runner:
    """The registry's entry for (``engine``, ``controller``); UsageError if there is none."""
    try:
        return RUNNERS[(engine, controller)]
    except KeyError:
        engines = [e for e, c in RUNNERS if c == controller]
        raise UsageError(f"--controller {controller} runs with --engine "
                         f"{' or '.join(engines)}, not {engine}") from None


def default_fmu_folder(build: Path = Path("build")) -> Path:
    """Where the rover's FMUs are by default: BUILD/native where all of them are built there,
    else BUILD where they are, else BUILD/native (said missing when needed)."""
    needed = rover_fmus.fmu_names()
    return next((d for d in (build / "native", build)
                 if all((d / f"{n}.fmu").is_file() for n in needed)), build / "native")


@dataclass
class RoverRun:
    """What :func:`run` did: the figures (``--json``), the run, the files written."""

    figures: dict
    result: rover_engine.RoverResult
    written: list[Path]
    ssp: Path | None
    fmu_folder: Path
    fmus_built: bool


def check(request: Request, fmu_dir: Path | None = None) -> tuple[Runner, Path, bool]:
    """Everything refusable before any work: the runner, the FMU folder and whether the FMUs
    are built there. UsageError with what would work."""
    if request.scenario not in rover_scenarios.scenarios():
        raise UsageError(f"unknown scenario {request.scenario!r}; valid: "
                         f"{', '.join(rover_scenarios.scenarios())}")
    if request.gravity not in GRAVITY:
        raise UsageError(f"unknown gravity {request.gravity!r}; valid: {', '.join(GRAVITY)}")
    if "rover.gravity" in request.chassis:  # it would be replaced by the gravity's value
        known = ", ".join(f"{k} {v:g}" for k, v in GRAVITY.items())
        raise UsageError(f"--set rover.gravity={request.chassis['rover.gravity']:g}: the gravity "
                         f"is --gravity's ({known} m/s2): each scenario's ramps, forces and "
                         "predictions are set for it")
    if request.band:
        wrong = [what for what, bad in (
            (f"--scenario {request.scenario}",
             request.scenario not in rover_scenarios.BAND_EVENTS),
            (f"--engine {request.engine}", request.engine != "in-process"),
            (f"--controller {request.controller}", request.controller != "speed"),
            ("--step", request.step is not None)) if bad]
        if wrong:
            raise UsageError(
                f"--band runs {' and '.join(rover_scenarios.BAND_EVENTS)} in process with the "
                "speed loops at the scenario's own step (six runs of it); not with "
                f"{', '.join(wrong)}")
    runner = runner_for(request.engine, request.controller)
    reason = runner.refusal(request)
    if reason is not None:
        raise UsageError(reason)
    folder = Path(fmu_dir) if fmu_dir is not None else default_fmu_folder()
    needed = rover_fmus.fmu_names()
    try:
        master.fmu_paths(folder, needed)  # each an FMU of its model, before an engine loads it
        built = True
    except (FileNotFoundError, FMUError) as err:
        built = False
        if runner.needs_fmus:
            raise UsageError(f"--engine {request.engine} needs "
                             f"{', '.join(f'{n}.fmu' for n in needed)} in {folder} ({err}): "
                             "build them (`wheelterrain build --flavor all`) or give --fmu-dir"
                             ) from None
    return runner, folder, built


def run(request: Request, out: Path, fmu_dir: Path | None = None, preset: str = "",
        progress: Progress | None = None) -> RoverRun:
    """Run ``request`` and write OUT/<scenario>-<gravity>[-mpc].png and .csv, and, where the
    FMUs are built, OUT/Rover-<scenario>.ssp, as one set (all, or none if interrupted)."""
    from wheelterrain import plots

    runner, folder, built = check(request, fmu_dir)
    control_figures: dict = {}
    engine = runner.start(folder, request.scenario, control_figures)
    outcome = rover_scenarios.run_scenario(request.scenario, request.terrain, request.gravity,
                                           dict(request.chassis), step=request.step,
                                           engine=engine, progress=progress)
    figures = {**outcome["figures"], "preset": preset, "controller": request.controller,
               **control_figures}
    if request.band:
        figures["limit_band"] = rover_scenarios.limit_band(
            request.scenario, request.terrain, request.gravity, dict(request.chassis),
            progress=progress)
    result = outcome["result"]
    out = Path(out)
    stem = f"{request.scenario}-{request.gravity}" + (
        "-mpc" if request.controller == "mpc" else "")
    series = {"time": result.time, **{f"{w}.{k}": v for w, d in result.wheels.items()
                                      for k, v in d.items()},
              **result.chassis, **result.inputs}
    names = [f"{stem}.png", f"{stem}.csv"]
    with files.one_set(out) as staging:  # all files, or none if interrupted
        plots.rover(result, figures, staging / names[0])
        master.write_series(staging / names[1], series,
                            every=max(len(result.time) // 5000, 1),
                            units=rover_engine.record_units())
        if built:
            names.append(f"Rover-{request.scenario}.ssp")
            soil = rover_scenarios.scenario_soil(request.scenario, request.terrain)
            rover_fmus.write_ssp(staging / names[-1], folder, request.scenario, soil,
                                 outcome["values"], outcome["stop"], outcome["step"])
    ssp_path = out / f"Rover-{request.scenario}.ssp" if built else None
    figures["ssp"] = str(ssp_path) if ssp_path else None
    return RoverRun(figures, result, [out / n for n in names], ssp_path, folder, built)
