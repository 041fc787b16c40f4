"""Solve time of the slip-control NMPC per step, horizon 30 x 20 ms, full contact model, in the
closed loop of the nominal scenario (in-process plant, so only the controller is timed), for
each solver set-up, VM and compiled prediction model, measured in the same run:

    python benchmarks/mpc.py [--repeats 3] [--horizon 30] [--scenario nominal]
    python benchmarks/mpc.py --quick --json     # one repeat, one JSON object on stdout

``--json`` prints ``rows``: [{``setup`` (``ipopt-vm``, ``sqpmethod-vm``, ``ipopt-compiled``,
``sqpmethod-compiled``, ``sqpmethod-rti-compiled``, ``rti-vm``, ``rti-compiled``), ``median_s``,
``p90_s``, ``slip_rms_error``, ``iterations``, ``ratio_to_ipopt_vm``}]; the report goes to stderr.
``sqpmethod-rti`` is the real-time iteration: one SQP iteration per sample from the shifted
warm start (Settings.max_iterations = 1); ``rti`` the same step as our own iteration
(``Settings(solver="rti")``: the states condensed out, a dense QP in the commands for DAQP,
one CasADi Function per sample), ``rti-vm`` with the prediction model on the CasADi VM.

Each figure is the median over repeats of the per-run median (and 90th percentile) of the wall
time of the solver call. The baseline for the ratios is ipopt on the CasADi VM. Goals
(issue 5): median <= 2 ms compiled, <= 10 ms uncompiled. The first compiled run generates and
compiles the prediction model (15-80 s depending on the host, cached; reported apart).
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time

from wheelterrain import compiled as native
from wheelterrain import presets
from wheelterrain.control import closed_loop, mpc

# (name, solver, compiled prediction model, SQP iterations per sample)
SETUPS = (("ipopt-vm", "ipopt", False, 20), ("sqpmethod-vm", "sqpmethod", False, 20),
          ("ipopt-compiled", "ipopt", True, 20), ("sqpmethod-compiled", "sqpmethod", True, 20),
          ("sqpmethod-rti-compiled", "sqpmethod", True, 1), ("rti-vm", "rti", False, 1),
          ("rti-compiled", "rti", True, 1))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--horizon", type=int, default=30)
    parser.add_argument("--scenario", default="nominal", choices=sorted(closed_loop.SCENARIOS))
    parser.add_argument("--quick", action="store_true", help="one repeat per set-up")
    parser.add_argument("--json", action="store_true",
                        help="print one JSON object of figures (the report goes to stderr)")
    args = parser.parse_args()
    if args.quick:
        args.repeats = 1
    report = sys.stderr if args.json else sys.stdout
    ps = presets.load(presets.DEFAULT_PRESET)
    scenario = closed_loop.SCENARIOS[args.scenario]
    rows = []
    if native.compiler() is not None:
        started = time.perf_counter()
        mpc.compiled_interval()
        print(f"compiled prediction model ready in {time.perf_counter() - started:.1f} s "
              f"(generated and compiled once per model version, then cached)", file=report)
    for setup, solver, compiled, iterations in SETUPS:
        if compiled and native.compiler() is None:
            print(f"{setup}: skipped (no C compiler)", file=report)
            continue
        settings = mpc.Settings(solver=solver, compiled=compiled, horizon=args.horizon,
                                objective=scenario.objective, max_iterations=iterations)
        medians, p90s, rms, iters = [], [], [], []
        for _ in range(args.repeats):
            result = closed_loop.run(scenario, ps, "casadi", settings)
            figures = result.figures(scenario)
            medians.append(figures["solve_time_median_s"])
            p90s.append(figures["solve_time_p90_s"])
            iters.append(figures["iterations_median"])
            rms.append(figures.get("slip_rms_error", float("nan")))
        rows.append((setup, compiled, statistics.median(medians), statistics.median(p90s),
                     statistics.median(iters), statistics.median(rms)))
        print(f"{setup:24} median "
              f"{1e3 * rows[-1][2]:7.2f} ms  p90 {1e3 * rows[-1][3]:7.2f} ms  "
              f"iterations {rows[-1][4]:.0f}  slip RMS {rows[-1][5]:.2e}", flush=True,
              file=report)
    baseline = rows[0][2]
    print(f"\nhorizon {args.horizon} x {mpc.Settings().interval:g} s, scenario {args.scenario}, "
          f"{args.repeats} repeats; ratio = ipopt VM median / set-up median", file=report)
    for setup, compiled, median, p90, _, _ in rows:
        goal = 2e-3 if compiled else 10e-3
        print(f"  {setup:24} median {1e3 * median:6.2f} ms"
              f" (goal {1e3 * goal:g} ms: {'met' if median <= goal else 'NOT met'}), p90 "
              f"{1e3 * p90:6.2f} ms, {baseline / median:4.1f}x", file=report)
    if args.json:
        print(json.dumps({"scenario": args.scenario, "horizon": args.horizon,
                          "repeats": args.repeats, "rows": [
                              {"setup": setup, "median_s": median, "p90_s": p90,
                               "slip_rms_error": rms, "iterations": iterations,
                               "ratio_to_ipopt_vm": baseline / median}
                              for setup, _, median, p90, iterations, rms in rows]},
                         indent=2))


if __name__ == "__main__":
    main()
