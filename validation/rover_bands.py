"""The rover's limits over the unmeasured values they depend on: their band.

    python validation/rover_bands.py [--gravity earth moon] [--scenario slope descent]
                                     [--json FILE]

Each limit scenario of `wheelterrain rover` (in process, default wheel and soil) runs at the
default values and once per end of each unmeasured value's band, one at a time
(`wheelterrain.cosim.rover_scenarios.limit_band`, its BAND_VARIANTS: soil.unloading_stiffness
over its plausible range, the grouser phases aligned, soil.damping at half and twice the
paper's, model.rut_shear at 0). Per run: the simulated limit (stall or slide slope), its cause,
the prediction and its limit, and on the descent the steepest slope four locked wheels hold
(`locked_limit_deg`). The band is the smallest and largest limit over the runs; a run that
reaches its end without a stall or slide is counted apart.
"""

from __future__ import annotations

import argparse
import json
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from wheelterrain import presets
from wheelterrain.cosim import rover_scenarios


def band(job: tuple[str, str]) -> dict:
    scenario, gravity = job
    return rover_scenarios.limit_band(scenario, presets.load(presets.DEFAULT_PRESET), gravity)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--gravity", nargs="+", default=["earth", "moon"],
                        choices=["earth", "moon"])
    parser.add_argument("--scenario", nargs="+", default=list(rover_scenarios.BAND_EVENTS),
                        choices=list(rover_scenarios.BAND_EVENTS))
    parser.add_argument("--json", type=Path, help="write the rows to this file")
    args = parser.parse_args(argv)
    jobs = [(s, g) for g in args.gravity for s in args.scenario]
    rows = []
    with ProcessPoolExecutor(max_workers=2) as pool:
        for k, result in enumerate(pool.map(band, jobs), 1):
            print(f"[{k}/{len(jobs)}] {result['gravity']} {result['scenario']}:", flush=True)
            for row in result["runs"]:
                rows.append({"scenario": result["scenario"], "gravity": result["gravity"],
                             **row})
                print(f"    {row['variant']:15} limit {_deg(row['limit_deg'])} "
                      f"({row['cause']}), predicted {_deg(row['predicted_deg'])} "
                      f"({row['predicted_limit']})"
                      + (f", locked wheels hold to {_deg(row['locked_limit_deg'])}"
                         if result["scenario"] == "descent" else ""), flush=True)
            span = ("none" if result["low"] is None
                    else f"{result['low']:.2f} .. {result['high']:.2f} deg")
            extra = (f" ({result['without_limit']} without a limit)"
                     if result["without_limit"] else "")
            causes = sorted({r["cause"] or "none" for r in result["runs"]})
            print(f"  band {span}{extra}; causes {', '.join(causes)}", flush=True)
    if args.json:
        tmp = args.json.with_suffix(args.json.suffix + ".part")
        tmp.write_text(json.dumps(rows, indent=1) + "\n", encoding="utf-8")
        tmp.replace(args.json)
    return 0


def _deg(value) -> str:
    return "none" if value is None else f"{abs(value):.2f} deg"


if __name__ == "__main__":
    sys.exit(main())
