"""Every rover scenario in every engine: do they agree?

    wheelterrain build --flavor all
    python validation/rover_engines.py [--gravity earth moon] [--scenario level slope ...]
                                       [--engines in-process fmus ecos libcosim ...]
                                       [--fmu-dir build/native] [--step 0.001] [--json FILE]

Each scenario of `wheelterrain rover` runs in process (the reference), through our master on the
FMUs (`fmus`), and as Rover-S.ssp in ecos, libcosim, OMSimulator (where built: $OMSIMULATOR or
on the PATH) and fmpy's SSP runner. Per engine it prints the largest relative difference from
the reference of the contract's per-wheel means (slip, sinkage, normal force; the pull, which
averages near 0 on level ground, on the wheel's normal force) over the window both runs cover:
from the scenario's settling time to where the shorter run ends (a stall ends a run, and the
one-step-late engines stall a little earlier or later); and the scenario's event (stall slope,
stall towing force, slide slope) beside the reference's. An engine that refuses a scenario is
listed with its reason.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from wheelterrain import presets
from wheelterrain.cosim import SSP_ENGINES, rover_fmus, rover_scenarios, ssp
from wheelterrain.errors import CosimulationError, UsageError
from wheelterrain.parameters import GRAVITY

ENGINES = ("in-process", "fmus", *SSP_ENGINES)
EVENTS = {"slope": ("stall_slope_deg", "deg"), "pull-test": ("stall_towing_force", "N"),
          "descent": ("slide_slope_deg", "deg")}


def compare(scenario: str, gravity: str, engines: tuple[str, ...], fmu_dir: Path,
            step: float | None = None) -> dict:
    terrain = presets.load(presets.DEFAULT_PRESET)
    runs = {}
    for engine in engines:
        print(f"  {scenario:10} {gravity:5} {engine:10} ...", end="", flush=True,
              file=sys.stderr)
        try:
            run = rover_scenarios.run_scenario(scenario, terrain, gravity, step=step,
                                            engine=rover_fmus.runner(engine, fmu_dir, scenario))
        except (CosimulationError, UsageError) as err:  # refused before or during the run
            runs[engine] = {"refused": str(err)}
            print(" refused", file=sys.stderr)
            continue
        runs[engine] = run
        f = run["figures"]
        print(f" {f['simulated_time_s']:.1f} s simulated in {f['wall_time_s']:.1f} s",
              file=sys.stderr)
    ref = runs["in-process"]
    settle = rover_scenarios.scenarios(gravity)[scenario].settle
    rows = {}
    event = EVENTS.get(scenario)
    for engine, run in runs.items():
        if "refused" in run:
            rows[engine] = {"refused": run["refused"]}
            continue
        d = rover_scenarios.difference(ref["result"], run["result"], settle)
        row = {"window_s": list(d["window"]), "worst_relative_difference": d["worst"],
               "worst_mean": d["where"], "step_s": run["figures"]["step_s"],
               "simulated_time_s": run["figures"]["simulated_time_s"],
               "left_domain": run["figures"]["left_domain"]}
        if event:
            row[event[0]] = run["figures"].get(event[0])
        rows[engine] = row
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--gravity", nargs="+", default=["earth", "moon"],
                    choices=list(GRAVITY))
    ap.add_argument("--scenario", nargs="+", default=list(rover_scenarios.scenarios()),
                    choices=list(rover_scenarios.scenarios()))
    ap.add_argument("--engines", nargs="+", default=list(ENGINES), choices=ENGINES)
    ap.add_argument("--fmu-dir", default=Path("build/native"), type=Path)
    ap.add_argument("--step", type=float, default=None,
                    help="communication step [s] of every engine (default: each scenario's, "
                    "1 ms, 0.25 ms for the Moon's stall runs; halve it to see the "
                    "one-step-late engines converge)")
    ap.add_argument("--json", type=Path, help="also write the table as JSON here")
    args = ap.parse_args()
    if "in-process" not in args.engines:
        args.engines.insert(0, "in-process")
    engines = []
    for e in args.engines:
        missing = ssp.engine_missing(e) if e in SSP_ENGINES else None
        if missing:
            print(f"{e}: left out: {missing}", file=sys.stderr)
            continue
        engines.append(e)
    if any(e != "in-process" for e in engines) and not (
            args.fmu_dir / "RoverChassis.fmu").is_file():
        sys.exit(f"no RoverChassis.fmu in {args.fmu_dir}: run `wheelterrain build --flavor all`")
    table = {}
    for gravity in args.gravity:
        for scenario in args.scenario:
            table[f"{scenario}/{gravity}"] = compare(scenario, gravity, tuple(engines),
                                                     args.fmu_dir, args.step)
    print(f"{'scenario':18} {'engine':11} {'step [ms]':>9} {'window [s]':>16} "
          f"{'worst rel. diff':>16}  {'(mean)':28} event")
    for name, rows in table.items():
        event = EVENTS.get(name.split("/")[0])
        for engine, row in rows.items():
            if "refused" in row:
                print(f"{name:18} {engine:11} refused: {row['refused'][:90]}")
                continue
            w = row["window_s"]
            ev = ""
            if event:
                v = row[event[0]]
                ev = f"{event[0]} = {v:.3f} {event[1]}" if v is not None and math.isfinite(v) \
                    else f"{event[0]}: none"
            print(f"{name:18} {engine:11} {row['step_s'] * 1e3:9g} {w[0]:7.1f}-{w[1]:7.1f}  "
                  f"{row['worst_relative_difference']:16.2e}  {row['worst_mean']:28} {ev}")
    if args.json:
        args.json.write_text(json.dumps(table, indent=1) + "\n")
        print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
