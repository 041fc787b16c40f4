"""Reference results of the Modelica library's examples, computed by the Python model, in MSL's
regression layout (``Resources/Reference/WheelTerrain/Examples/[FMUTwin/]<Example>/<Example>.csv``
and ``comparisonSignals.txt`` beside it, :func:`location`; the columns and signals in the
library's names, :mod:`.names`): what a Modelica tool's run of each
example should give at the example's own experiment annotation (:func:`tolerance`).

- SteadyC2 and SlipRamp: the project's steady state (:func:`wheelterrain.model.api.steady_state`)
  at the examples' loads and slips.
- RigC1 ... RigC4: the paper's rig in continuous time (:func:`wheelterrain.model.rig.rates`, the
  rig's model-exchange equations) on the contact with the soil's memory (``contact_memory``),
  integrated by CasADi's CVODES at tolerances far below the comparison's (1e-12 relative): the
  same equations the Modelica rig states with MSL components.
"""

from __future__ import annotations

import csv
import io
import math
import os
import re
from collections.abc import Sequence
from pathlib import Path

import casadi as ca
import numpy as np

from wheelterrain import presets
from wheelterrain.fmu import functions as fmu_functions
from wheelterrain.model import api, ground, rig, rover
from wheelterrain.model.slip import unified_from_paper
from wheelterrain.modelica import names

STEADY_LOAD = 62.0
"""N: the rig's load in the paper's C1-C4 (Table III), the steady examples' load."""
RAMP = (-0.5, 1.3)
"""SlipRamp's slip (the model's: skid braking, traction driving): RAMP[0] + RAMP[1]*time,
time in [0, 1] s."""
RAMP_TIMES = tuple(round(0.05 * k, 2) for k in range(21))
RIG_CASES = {"C1": 0.0, "C2": 0.25, "C3": 0.5, "C4": 0.75}
"""The paper's rig cases and their slips s (Abubakar et al., Table III)."""
RIG_STOP, RIG_INTERVAL = 4.0, 0.01
RIG_SINKAGE_START = 0.01
RIG_COLUMNS = ("time", *fmu_functions.RIG_LOOP_STATES, *rig.FORCE_INPUTS)
RIG_COMPARED = ("time", "sinkage", "sinkage_rate", "wheel_speed", "wheel_angle",
                "plastic_sinkage", "normal_force", "drawbar_pull", "torque")
"""The rig examples' compared signals: every column of the rig's reference but the speed loop's
integral (the Python rig's integral of the speed error; MSL's PI keeps it divided by T)."""

QUASI_STATIC_TOLERANCE = 1e-8
ROVER_TOLERANCE = 1e-13
RIG_TOLERANCE = 1e-12
"""The examples' experiment tolerances (relative; absolute 1e-2 of it, ABSOLUTE_SHARE): the
tolerance at which rumoca's run of each example reproduces its reference within 1e-8 of each
compared signal's largest value (tests/test_modelica.py runs every example at its own
annotation). The contact's switches (the soil's memory yielding or unloading, the ripple's
clip) are not events, so a tool's error where its steps cross them falls with its tolerance
(rumoca, worst compared signal: RigC2's first second 6.0e-8 at 1e-8, 9.3e-11 at 1e-12;
RoverSlope 3.8e-8 at 1e-8, 1.3e-10 at 1e-13; the rover descent's pulls 2.7e-8 at 1e-12). The
quasi-static examples have no state, only the sinkage's implicit equation."""
ABSOLUTE_SHARE = 1e-2


def steady_rows(slips: Sequence[float], times: Sequence[float] | None = None) -> list[dict]:
    """The steady state of the default preset at STEADY_LOAD and each of the model's slips."""
    params = presets.load()
    rows = []
    for k, slip in enumerate(slips):
        s = api.steady_state(params, STEADY_LOAD, float(slip), "unified")
        row = {"time": times[k]} if times is not None else {}
        row.update(slip=float(slip), sinkage=s["sinkage"], drawbar_pull=s["drawbar_pull"],
                   torque=s["torque"])
        rows.append(row)
    return rows


def ramp_slips() -> list[float]:
    return [RAMP[0] + RAMP[1] * t for t in RAMP_TIMES]


def rig_trajectory(slip_paper: float, stop: float = RIG_STOP,
                   interval: float = RIG_INTERVAL) -> np.ndarray:
    """The rig at the paper's slip ``slip_paper`` from rest in the soil at RIG_SINKAGE_START
    (wheel at its reference speed, no memory yet): one row per output time, RIG_COLUMNS."""
    rp = {**rig.defaults(), "rig.slip_paper": slip_paper}
    loop = fmu_functions.rig_on_contact(ca.DM(presets.load().vector()), rp, RIG_SINKAGE_START)
    forces = [loop["values"][k] for k in rig.FORCE_INPUTS]
    return _integrate(loop["state"], loop["rate"], loop["start"],
                      ca.vertcat(loop["state"], *forces), stop, interval)


def _integrate(state: ca.SX, rate: ca.SX, start: Sequence[float], columns: ca.SX,
               stop: float, interval: float) -> np.ndarray:
    """d(state)/dt = rate from ``start``, integrated by CVODES at 1e-12 relative: one row per
    output time (every ``interval`` s up to ``stop``), the time, then ``columns`` there."""
    times = np.round(np.arange(0, stop + interval / 2, interval), 10)
    integrator = ca.integrator("reference", "cvodes", {"x": state, "ode": rate}, 0.0,
                               times[1:].tolist(),
                               {"abstol": 1e-14, "reltol": 1e-12, "max_num_steps": 10**7})
    states = np.column_stack([start, np.array(integrator(x0=list(start))["xf"])]).T
    evaluate = ca.Function("columns", [state], [columns])
    rows = np.array([np.array(evaluate(s), dtype=float).ravel() for s in states])
    return np.column_stack([times, rows])


ROVER_STOP, ROVER_INTERVAL = 10.0, 0.01
ROVER_HEAVE_START = 1e-3
"""m: the chassis starts this deep in the soil (all four wheels in contact; at exactly zero
sinkage on fresh soil the contact's derivative is infinite)."""
ROVER_COLUMNS = ("time", "speed", "position", "heave", "pitch",
                 *(f"{w}.{q}" for q in ("sinkage", "drawbar_pull", "normal_force",
                                        "wheel_speed") for w in rover.WHEELS))


def rover_start() -> list[float]:
    """Examples.FMUTwin.Rover's start (rover.STATES order): rover.initial_state at the table's
    defaults, the chassis ROVER_HEAVE_START in the soil."""
    return list(rover.initial_state(rover.defaults(), heave=ROVER_HEAVE_START))


ROVER_PROFILES = {
    "Rover": {},
    "RoverSlope": {"rover.ramp_time": 3.0, "rover.slope_rate_after": math.radians(2.0),
                   "rover.slope_bound": math.radians(10.0)},
    "RoverDescent": {"rover.ramp_time": 3.0, "rover.slope_rate_after": math.radians(-2.0),
                     "rover.slope_bound": math.radians(5.0)},
    "RoverPullTest": {"rover.towing_rate": 1.0},
}
"""The rover examples and their input profiles (rover.* rows changed from the defaults): level
ground; after 3 s on level ground, the slope rising at 2 deg/s to a 10 deg climb, or falling to
a 5 deg descent the speed loops brake on (both inside the limits ``wheelterrain rover`` finds:
a stall at 27 deg, a slide at 8.9 deg); on level ground, a force holding the rover back rising
at 1 N/s (the pull test's profile, faster: the CLI's rises at 0.05 % of the weight per second
until the rover stalls, an hour). Starting on the slope instead, the rover would slide while
it sinks into the soil from its start."""
PLANAR_ROVERS = {"PlanarRover": "Rover", "PlanarRoverSlope": "RoverSlope"}
"""The rover examples from standard parts (PlanarWheels on a body) and the RoverChassis example
whose rover each is: the same trajectory, so the same reference."""
ROVER_MAPS = {"RoverSoftPatch": ground.soft_patch(presets.load())}
"""The rover examples on a terrain map (MapWheels): the soft-patch scenario's map over the
default preset's soil."""
ROVER_RUNS = {"RoverSoftPatch": (40.0, 0.05)}
"""(stop, interval) [s] of the rover examples that differ from ROVER_STOP, ROVER_INTERVAL: the
soft patch lies under the front axle from 9.4 s to 19.0 s, under the rear from 22.1 s to
31.7 s."""
ROVER_DESCRIPTIONS = {
    "RoverSlope": "after 3 s on level ground the slope rises at 2 deg/s to a 10 deg climb",
    "RoverDescent": "after 3 s on level ground the slope falls at 2 deg/s to a 5 deg descent, "
                    "the speed loops braking",
    "RoverPullTest": "on level ground, a force holding it back rising at 1 N/s",
}


def rover_parameters(example: str = "Rover") -> dict[str, float]:
    """The rover's parameters of ``example`` (ROVER_PROFILES; the map examples: defaults)."""
    return {**rover.defaults(), **ROVER_PROFILES.get(example, {})}


def rover_run(example: str) -> tuple[float, float]:
    """(stop, interval) [s] of the rover example ``example``."""
    return ROVER_RUNS.get(example, (ROVER_STOP, ROVER_INTERVAL))


def rover_trajectory(stop: float = ROVER_STOP, interval: float = ROVER_INTERVAL,
                     example: str = "Rover") -> np.ndarray:
    """The rover of ``example`` (Examples.FMUTwin.Rover, RoverSlope, RoverDescent): the RoverChassis
    FMU's model-exchange rates on four contacts with the soil's memory (each wheel's angle and
    plastic sinkage states), the default preset's soil and the example's rover parameters,
    integrated by CVODES at 1e-12: one row per output time, ROVER_COLUMNS."""
    loop = fmu_functions.rover_on_contact(ca.DM(presets.load().vector()),
                                          rover_parameters(example), ROVER_MAPS.get(example),
                                          ROVER_HEAVE_START)
    report = {f"{w}.{q}": loop["wheels"][w][q] for w in rover.WHEELS
              for q in ("sinkage", "drawbar_pull", "normal_force", "wheel_speed")}
    report.update({k: loop["x"][k] for k in ("speed", "position", "heave", "pitch")})
    return _integrate(loop["state"], loop["rate"], loop["start"],
                      ca.vertcat(*(report[c] for c in ROVER_COLUMNS[1:])), stop, interval)


def _csv(columns: Sequence[str], rows) -> str:
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow([names.path(c) for c in columns])
    for row in rows:
        writer.writerow([repr(float(v)) for v in row])
    return buffer.getvalue()


QUASI_STATIC_EXAMPLES = ("SteadyC2", "SlipRamp")


def _kind(name: str) -> str:
    """'quasi-static', 'rig' (RigC1 ... RigC4, PlanarRig) or 'rover': what the example ``name``
    runs, which sets its tolerance and its compared signals."""
    if name in QUASI_STATIC_EXAMPLES:
        return "quasi-static"
    return "rig" if name.startswith("Rig") or name == "PlanarRig" else "rover"


def fmu_twins() -> tuple[str, ...]:
    """The examples of Examples.FMUTwin: the rover on the RoverChassis block, the FMUs' model
    exchange in Modelica (the rover from standard parts is in Examples itself)."""
    return (*ROVER_PROFILES, *ROVER_MAPS)


def class_path(name: str) -> str:
    """The example ``name``'s class below WheelTerrain: 'Examples.SteadyC2',
    'Examples.FMUTwin.Rover'."""
    return f"Examples.FMUTwin.{name}" if name in fmu_twins() else f"Examples.{name}"


def location(name: str) -> str:
    """The folder of the example ``name``'s reference files below Resources/Reference (MSL's
    regression layout: the example's class path)."""
    return "WheelTerrain/" + class_path(name).replace(".", "/")


def tolerance(name: str) -> float:
    """The relative tolerance of the example ``name``'s experiment annotation."""
    return {"quasi-static": QUASI_STATIC_TOLERANCE, "rig": RIG_TOLERANCE,
            "rover": ROVER_TOLERANCE}[_kind(name)]


def compared(name: str) -> tuple[str, ...]:
    """The signals of the example ``name`` its reference is compared on (comparisonSignals.txt):
    model variables, time first, each a column of its reference CSV."""
    return {"quasi-static": STEADY_COLUMNS, "rig": RIG_COMPARED,
            "rover": ROVER_COLUMNS}[_kind(name)]


def _folder(library_root: Path, name: str) -> Path:
    """The example ``name``'s reference folder in the library written to ``library_root``."""
    return Path(library_root) / "WheelTerrain" / "Resources" / "Reference" / location(name)


def read_signals(library_root: Path, name: str) -> tuple[str, ...]:
    """The example ``name``'s comparisonSignals.txt in the library written to
    ``library_root``."""
    path = _folder(library_root, name) / "comparisonSignals.txt"
    return tuple(path.read_text(encoding="utf-8").split())


def read(library_root: Path, name: str) -> dict[str, np.ndarray]:
    """The reference result ``name`` (an example's) of the library written to
    ``library_root`` (the folder holding WheelTerrain/): column -> values."""
    path = _folder(library_root, name) / f"{name}.csv"
    with path.open(encoding="utf-8") as handle:
        rows = list(csv.reader(handle))
    data = np.array(rows[1:], dtype=float)
    return {column: data[:, k] for k, column in enumerate(rows[0])}


def find_msl() -> Path | None:
    """A folder on MODELICAPATH holding the Modelica Standard Library 4.x (Modelica/,
    ModelicaServices/, Complex.mo), or None."""
    for entry in os.environ.get("MODELICAPATH", "").split(os.pathsep):
        package = Path(entry) / "Modelica" / "package.mo" if entry else None
        if package and package.is_file() and re.search(
                r'version\s*=\s*"4\.', package.read_text(encoding="utf-8",
                                                       errors="replace")[:4000]):
            return Path(entry)
    return None


def one_root(msl: Path, library_root: Path, folder: Path) -> Path:
    """``folder`` made one source root holding MSL (and PlanarMechanics, where it lies beside
    MSL) and the library side by side (links):
    rumoca 0.10 does not resolve a class of one root from a class of another."""
    folder.mkdir(parents=True, exist_ok=True)
    for name in ("Modelica", "ModelicaServices", "Complex.mo", "PlanarMechanics"):
        if name != "PlanarMechanics" or (Path(msl) / name).is_dir():
            (folder / name).symlink_to(Path(msl) / name)
    (folder / "WheelTerrain").symlink_to(Path(library_root) / "WheelTerrain")
    return folder


STEADY_COLUMNS = ("time", "slip", "sinkage", "drawbar_pull", "torque")
"""The quasi-static examples' reference columns, each a model variable (their compared signals)."""
STEADY_TIMES = (0.0, 1.0)
"""s: SteadyC2's output times (its experiment's start and stop): the steady state at both."""


def files() -> dict[str, str]:
    """<Example folder>/<Example>.csv and comparisonSignals.txt (below Resources/Reference) ->
    text, for every example."""
    tables = {}
    (c2,) = steady_rows([unified_from_paper(0.25)])  # the same steady state at every time
    tables["SteadyC2"] = _csv(STEADY_COLUMNS, [[t, *(c2[k] for k in STEADY_COLUMNS[1:])]
                                               for t in STEADY_TIMES])
    ramp = steady_rows(ramp_slips(), RAMP_TIMES)
    tables["SlipRamp"] = _csv(STEADY_COLUMNS, [[r[k] for k in STEADY_COLUMNS] for r in ramp])
    for case, s in RIG_CASES.items():
        tables[f"Rig{case}"] = _csv(RIG_COLUMNS, rig_trajectory(s))
    tables["PlanarRig"] = tables["RigC1"]  # its defaults: level, the paper's slip 0
    for example in (*ROVER_PROFILES, *ROVER_MAPS):
        stop, interval = rover_run(example)
        tables[example] = _csv(ROVER_COLUMNS, rover_trajectory(stop, interval, example))
    for example, same in PLANAR_ROVERS.items():
        tables[example] = tables[same]
    out = {}
    for name, text in tables.items():
        out[f"{location(name)}/{name}.csv"] = text
        out[f"{location(name)}/comparisonSignals.txt"] = "".join(
            f"{names.path(signal)}\n" for signal in compared(name))
    return out
