"""The rover's limits over the unmeasured parameters they depend on: their band.

    python validation/rover_bands.py [--gravity earth moon] [--scenario slope descent]
                                     [--json FILE]

Each limit scenario of `wheelterrain rover` (in process, default wheel and soil) runs at the
default values and once per end of each unmeasured parameter's band, one parameter at a time:

- soil.unloading_stiffness K_u: the row's plausible range (4e6-4e8 Pa/m: Chrono's SCM demos
  use 4e7-4e8, a decade softer for loose sand; no measurement of this soil's K_u);
- the grouser phases: the four wheels aligned (every rover.grouser_phase.* 0) against the
  default spread;
- soil.damping C_f: half and twice the paper's 800 N.s/m (the paper gives one value and no
  source for it; the factor 2 is an assumption).

Per run: the simulated limit (stall or slide slope), its cause, the prediction and its limit,
and on the descent the steepest slope four locked wheels hold (`locked_limit_deg`). The band of
a limit is the smallest and largest value over the runs; a run that reaches its end without a
stall or slide counts as "none".
"""

from __future__ import annotations

import argparse
import json
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from wheelterrain import presets
from wheelterrain.cosim import rover_scenarios
from wheelterrain.model import rover

EVENTS = {"slope": "stall_slope_deg", "descent": "slide_slope_deg"}
ALIGNED = {f"rover.grouser_phase.{w}": 0.0 for w in rover.WHEELS}
VARIANTS = {
    "default": ({}, {}),
    "K_u 4e6": ({"soil.unloading_stiffness": 4e6}, {}),
    "K_u 4e8": ({"soil.unloading_stiffness": 4e8}, {}),
    "phases aligned": ({}, ALIGNED),
    "C_f 400": ({"soil.damping": 400.0}, {}),
    "C_f 1600": ({"soil.damping": 1600.0}, {}),
}


def run(job: tuple[str, str, str]) -> dict:
    scenario, gravity, variant = job
    terrain_values, rover_values = VARIANTS[variant]
    terrain = presets.load(presets.DEFAULT_PRESET).with_values(terrain_values)
    f = rover_scenarios.run_scenario(scenario, terrain, gravity, rover_values)["figures"]
    return {"scenario": scenario, "gravity": gravity, "variant": variant,
            "limit_deg": f[EVENTS[scenario]], "cause": f["stall_cause"],
            "predicted_deg": f.get("predicted_stall_slope_deg",
                                   f.get("predicted_descent_limit_deg")),
            "predicted_limit": f.get("predicted_stall_limit", f.get("predicted_descent_limit")),
            "locked_limit_deg": f.get("locked_limit_deg")}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--gravity", nargs="+", default=["earth", "moon"],
                        choices=["earth", "moon"])
    parser.add_argument("--scenario", nargs="+", default=list(EVENTS), choices=list(EVENTS))
    parser.add_argument("--json", type=Path, help="write the rows to this file")
    args = parser.parse_args(argv)
    jobs = [(s, g, v) for g in args.gravity for s in args.scenario for v in VARIANTS]
    rows = []
    with ProcessPoolExecutor(max_workers=2) as pool:
        for k, row in enumerate(pool.map(run, jobs), 1):
            rows.append(row)
            print(f"[{k}/{len(jobs)}] {row['gravity']:5} {row['scenario']:7} "
                  f"{row['variant']:15} limit {_deg(row['limit_deg'])} ({row['cause']}), "
                  f"predicted {_deg(row['predicted_deg'])} ({row['predicted_limit']})"
                  + (f", locked wheels hold to {_deg(row['locked_limit_deg'])}"
                     if row["scenario"] == "descent" else ""), flush=True)
    print("\nband (smallest .. largest simulated limit over the variants):")
    for g in args.gravity:
        for s in args.scenario:
            mine = [r for r in rows if r["gravity"] == g and r["scenario"] == s]
            values = [abs(r["limit_deg"]) for r in mine if r["limit_deg"] is not None]
            none = len(mine) - len(values)
            causes = sorted({r["cause"] or "none" for r in mine})
            span = f"{min(values):.2f} .. {max(values):.2f} deg" if values else "none"
            print(f"  {g:5} {s:7} {span}" + (f" ({none} without a limit)" if none else "")
                  + f"; causes {', '.join(causes)}")
    if args.json:
        tmp = args.json.with_suffix(args.json.suffix + ".part")
        tmp.write_text(json.dumps(rows, indent=1) + "\n", encoding="utf-8")
        tmp.replace(args.json)
    return 0


def _deg(value) -> str:
    return "none" if value is None else f"{abs(value):.2f} deg"


if __name__ == "__main__":
    sys.exit(main())
