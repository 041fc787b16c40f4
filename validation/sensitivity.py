"""Sensitivity ranking of the soil parameters at C1-C4 (local elasticities from the exact
Jacobian, and one-at-a-time swings over the plausible ranges through WheelTerrain.fmu).

    wheelterrain build && python3 validation/sensitivity.py [--preset P] [--fmu F] [--png FILE]
"""

from __future__ import annotations

import argparse
from pathlib import Path

from wheelterrain import presets
from wheelterrain.cosim import master as cosim
from wheelterrain.fit import sensitivity


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--preset", default=presets.DEFAULT_PRESET)
    ap.add_argument("--fmu", default="build/WheelTerrain.fmu", type=Path)
    ap.add_argument("--png", default=Path("validation/output/sensitivity.png"), type=Path)
    args = ap.parse_args()
    ps = presets.load(args.preset)
    cases = cosim.table3()["cases"]
    print(f"preset {args.preset}; elasticity (dy/dp)(p/y) and swing over the plausible range")
    table = {}
    for case in cases:
        el = sensitivity.elasticities(ps, case["slip_paper"])
        sw = sensitivity.swings(args.fmu, ps, case["slip_paper"])
        table[case["case"]] = (el, sw)
        print(f"\n{case['case']} (s = {case['slip_paper']}):")
        print(f"  {'parameter':20} {'elast. DP':>10} {'elast. z':>9} {'swing DP [N]':>13} "
              f"{'swing z [mm]':>13}")
        for n in sensitivity.ranking(el, "drawbar_pull"):
            print(f"  {n:20} {el[n]['drawbar_pull']:10.3f} {el[n]['sinkage']:9.3f} "
                  f"{sw[n]['drawbar_pull']:13.2f} {1e3 * sw[n]['sinkage']:13.2f}"
                  + (f"  ({sw[n]['infeasible']} infeasible)" if sw[n]['infeasible'] else ""))
    el, sw = table["C2"]
    from wheelterrain import plots
    plots.sensitivity_bars(el, sw, args.png, f"Sensitivity at C2, preset {args.preset}")
    print(f"\nwrote {args.png}")


if __name__ == "__main__":
    main()
