"""Speed of the rover (RoverChassis + four wheel-terrain contacts): simulated seconds per wall
second, every master measured in the same run on the level scenario.

    wheelterrain build --flavor all
    python benchmarks/rover.py [--fmu-dir build] [--seconds 20] [--repeats 5]
    python benchmarks/rover.py --quick --json      # shorter runs, one JSON object

Masters: in process (the chassis and contact Functions stepped together, compiled C, blocks of
steps per call); our master through fmpy on the native FMUs (FMU_DIR/native) and on the
pythonfmu ones (FMU_DIR); libcosim, ecos, OMSimulator (its command-line tool: start-up and
its CSV of every variable included) and fmpy's own SSP runner on Rover.ssp with the native FMUs
(where installed).
Each figure is the median over repeats of one run's real-time factor (simulated time over wall
time, start-up excluded: each engine's own loop is timed). The baseline measured in the same
run is one call of the core contact Function from Python per simulated step, four wheels: what
a Python loop over the CasADi model could at best do; the ratios say how far each master is
from it.

``--json`` prints ``rover_rtf_fastest`` (the fastest master), ``rover_how`` (which),
``rover_rtf_fmpy`` (our master through fmpy's FMU classes, native FMUs),
``rover_rtf_fmpy_ssp`` (fmpy's own SSP runner, fmpy.ssp, on Rover.ssp with the native FMUs),
and every master's figure. Goals (issue 30): >= 100x real time fastest, >= 10x through fmpy.
Chrono's published SCM benchmark runs a four-wheel vehicle at 2-3x real time.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

from wheelterrain import presets
from wheelterrain.cosim import SSP_ENGINES, rover_fmus, ssp
from wheelterrain.cosim import rover as rover_system
from wheelterrain.model import functions as model_functions


def baseline_rtf(seconds: float, step: float) -> float:
    """Real-time factor of four Python calls of the contact Function per step."""
    fns = model_functions.build()
    p = presets.load(presets.DEFAULT_PRESET).vector()
    n = max(int(seconds / step / 20), 50)  # a sample of the steps
    t = time.perf_counter()
    for _ in range(n):
        for _ in range(4):
            fns.contact(0.007, 0.0, 0.05, 0.3, p)
    return n * step / (time.perf_counter() - t)


def measure(run, repeats: int) -> float:
    rtf = []
    for _ in range(repeats):
        res = run()
        rtf.append((res.time[-1] + (res.time[1] - res.time[0])) / res.wall_time)
    return statistics.median(rtf)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fmu-dir", default="build", type=Path)
    ap.add_argument("--seconds", type=float, default=20.0, help="simulated seconds a run")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--quick", action="store_true", help="5 s runs, 3 repeats")
    ap.add_argument("--json", action="store_true", help="one JSON object on stdout")
    args = ap.parse_args()
    if args.quick:
        args.seconds, args.repeats = 5.0, 3
    terrain = presets.load(presets.DEFAULT_PRESET)
    soil = rover_system.Soil(terrain)
    step = rover_system.STEP
    rover_system.simulate(soil, {}, 0.5)  # compile (or load) the in-process code once
    figures = {"baseline_rtf_python_calls": baseline_rtf(args.seconds, step)}
    masters = {"in-process (compiled C)": lambda: rover_system.simulate(soil, {}, args.seconds)}
    native = args.fmu_dir / "native"
    if (native / "RoverChassis.fmu").is_file():
        masters["wheelterrain master (fmpy), native FMUs"] = lambda: rover_fmus.simulate(
            native, soil, {}, args.seconds)
        for engine in SSP_ENGINES:
            if ssp.engine_missing(engine) is None:
                masters[f"{engine}, native FMUs"] = (
                    lambda engine=engine: rover_fmus.simulate_ssp(
                        engine, native, "level", soil, {}, args.seconds))
    if (args.fmu_dir / "RoverChassis.fmu").is_file():
        masters["wheelterrain master (fmpy), pythonfmu FMUs"] = lambda: rover_fmus.simulate(
            args.fmu_dir, soil, {}, min(args.seconds, 2.0))
    for name, run in masters.items():
        figures[f"rtf {name}"] = measure(run, args.repeats)
        print(f"{name:45} {figures[f'rtf {name}']:9.1f}x real time "
              f"({figures[f'rtf {name}'] / figures['baseline_rtf_python_calls']:.1f}x the "
              "Python-call baseline)", file=sys.stderr)
    rtfs = {k[4:]: v for k, v in figures.items() if k.startswith("rtf ")}
    fastest = max(rtfs, key=rtfs.get)
    figures.update(rover_rtf_fastest=rtfs[fastest], rover_how=fastest,
                   rover_rtf_fmpy=rtfs.get("wheelterrain master (fmpy), native FMUs"),
                   rover_rtf_fmpy_ssp=rtfs.get("fmpy-ssp, native FMUs"))
    print(f"baseline (4 Python calls of the contact Function a step): "
          f"{figures['baseline_rtf_python_calls']:.1f}x real time", file=sys.stderr)
    if args.json:
        print(json.dumps(figures, indent=2))


if __name__ == "__main__":
    main()
