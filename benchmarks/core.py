"""Core-model speed: force evaluations and quasi-static solves, interpreted and compiled.

    python benchmarks/core.py [--points 100000] [--repeats 5] [--no-compile] [--quick] [--json]

Prints the median of repeats for:
- one contact-force evaluation called from Python (casadi Function call);
- per point through Function.map over N points (CasADi's virtual machine);
- the same mapped Functions generated as C, compiled with the machine's C compiler (-O3) and
  loaded with casadi.external;
- the force evaluation and the solve as lane-parallel C (wheelterrain.model.lanes: the same SX
  kernels, eight points per vector instruction, glibc's vector math), compiled on first use
  (about 100 s for both) and cached;
- quasi-static sinkage solves per second, both ways;
- the baseline measured in the same run: the independent scipy-quad Wong-Reece reference of the
  tests (tests/classical_reference.py), per force evaluation and per solve.
One core: CasADi's serial map; no threads. The mapped figures are the model's time: the
inputs are converted to CasADi matrices once, and that conversion is reported on its own.
``--json`` prints force_eval_s, solve_s (per point, the fastest compiled path; which one in
force_eval_how and solve_how; the solve cold, at unrelated random points), solve_sweep_s (a
load x slip sweep through model.steady_map, warm-started from neighbouring points),
force_eval_reference_s, solve_reference_s (the scipy reference solves cold), their ratios, the
CasADi-C and VM figures and input_conversion_s; lateral_eval_s, lateral_eval_reference_s and
lateral_eval_speedup: the side force and aligning moment of a wheel at a slip angle (5-30 deg),
against the scipy quadrature of Ishigami et al.'s integrals in the same reference.
"""

from __future__ import annotations

import argparse
import json
import math
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import casadi as ca
import numpy as np

from wheelterrain import model, presets
from wheelterrain.model import functions as model_functions
from wheelterrain.model import lanes, solve

ROOT = Path(__file__).resolve().parents[1]


def median_time(fn, repeats: int) -> float:
    fn()  # warm-up
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def compile_external(fn: ca.Function, workdir: Path) -> ca.Function:
    """Generate C for ``fn``, compile it into a shared library and load it back."""
    compiler = shutil.which("cc") or shutil.which("gcc")
    if compiler is None:
        raise RuntimeError("no C compiler (cc/gcc) on PATH")
    c_file = workdir / f"{fn.name()}.c"
    fn.generate(str(c_file.name), {"with_header": False})
    Path(c_file.name).replace(c_file)
    so = workdir / f"{fn.name()}.so"
    subprocess.run([compiler, "-O3", "-march=native", "-fPIC", "-shared", str(c_file), "-o",
                    str(so), "-lm"], check=True)
    return ca.external(fn.name(), str(so))


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=100_000)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--no-compile", action="store_true")
    parser.add_argument("--quick", action="store_true",
                        help="20 000 points, 3 repeats (about a minute on two cores)")
    parser.add_argument("--json", action="store_true",
                        help="print one JSON object (per-point seconds) on stdout; the text "
                        "goes to stderr")
    args = parser.parse_args(argv)
    if args.quick:
        args.points, args.repeats = 20_000, 3
    n = args.points
    out = sys.stderr if args.json else sys.stdout

    def say(text: str) -> None:
        print(text, file=out)

    fns = model_functions.build()
    p = presets.load("paper-table2-arc").vector()
    rng = np.random.default_rng(0)
    z = rng.uniform(0.005, 0.045, n)
    slip = rng.uniform(0.0, 0.5, n)
    load = rng.uniform(20.0, 60.0, n)
    P = np.tile(p[:, None], (1, n))
    zeros = np.zeros(n)
    # the inputs as CasADi matrices, converted once: the model's time is measured without the
    # numpy -> DM conversion, which is reported on its own
    conversion = median_time(lambda: [ca.DM(x) for x in (z, zeros, slip, zeros, P)],
                             args.repeats) / n
    contact_in = [ca.DM(x) for x in (z, zeros, slip, zeros, P)]
    beta = np.radians(rng.uniform(5.0, 30.0, n))  # the side force, at slip angles
    no_turn = np.zeros(n)  # the side force of a wheel that does not yaw (turn slip 0)
    lateral_in = [ca.DM(x) for x in (z, slip, beta, no_turn, P)]
    solve_in = [ca.DM(x) for x in (load, slip, P)]
    figures = {"points": n, "repeats": args.repeats, "input_conversion_s": conversion}

    say(f"core benchmark: {n} points, median of {args.repeats}, one core, "
        f"{fns.nodes} nodes per panel, at most {solve.NEWTON_ITERATIONS} Newton steps (the "
        "solve stops once converged)")
    single = median_time(lambda: [fns.contact(0.03, 0.0, 0.2, 0.0, p) for _ in range(200)],
                         args.repeats) / 200
    say(f"  force eval, one call from Python      : {single * 1e6:9.2f} us")
    say(f"  numpy -> DM input conversion           : {conversion * 1e6:9.3f} us/pt "
        "(not in the figures below)")

    contact_map = fns.contact.map(n)
    lateral_map = fns.lateral.map(n)
    t_lateral_vm = median_time(lambda: lateral_map(*lateral_in), args.repeats) / n
    figures["lateral_eval_vm_s"] = t_lateral_vm
    say(f"  side force, Function.map (CasADi VM)   : {t_lateral_vm * 1e6:9.3f} us/pt")
    solve_map = fns.sinkage_solve.map(n)
    t_map = median_time(lambda: contact_map(*contact_in), args.repeats) / n
    # the VM's solve is the slow one (~1.5 ms/pt): --quick measures it on 2000 points
    m = min(n, 2000) if args.quick else n
    solve_vm = fns.sinkage_solve.map(m)
    vm_in = [ca.DM(x) for x in (load[:m], slip[:m], P[:, :m])]
    t_solve = median_time(lambda: solve_vm(*vm_in), max(1, args.repeats // 2)) / m
    figures.update(force_eval_vm_s=t_map, solve_vm_s=t_solve)
    say(f"  force eval, Function.map (CasADi VM)   : {t_map * 1e6:9.3f} us/pt "
        f"= {1 / t_map:10.3g} /s")
    say(f"  sinkage solve, Function.map (VM)       : {t_solve * 1e6:9.3f} us/pt "
        f"= {1 / t_solve:10.3g} /s")

    if not args.no_compile:
        with tempfile.TemporaryDirectory() as tmp:
            work = Path(tmp)
            t0 = time.perf_counter()
            c_contact = compile_external(contact_map, work)
            c_solve = compile_external(solve_map, work)
            build = time.perf_counter() - t0
            tc_map = median_time(lambda: c_contact(*contact_in), args.repeats) / n
            tc_solve = median_time(lambda: c_solve(*solve_in), args.repeats) / n
            check = np.max(np.abs(np.array(c_contact(*contact_in)[1])
                                  - np.array(contact_map(*contact_in)[1])))
        say(f"  (generated C compiled in {build:.1f} s; max |DP(C) - DP(VM)| = {check:.1e} N)")
        say(f"  force eval, mapped + compiled C        : {tc_map * 1e6:9.3f} us/pt "
            f"= {1 / tc_map:10.3g} /s")
        t0 = time.perf_counter()
        lane = lanes.compiled_contact()
        lane_build = time.perf_counter() - t0
        tl_map = median_time(lambda: lane(z, zeros, slip, zeros, P), args.repeats) / n
        lane_check = np.max(np.abs(lane(z, zeros, slip, zeros, P)[1]
                                   - np.array(contact_map(*contact_in)[1]).ravel()))
        how = (f"lane-parallel C, {lanes.LANES} points per call"
               + (", glibc vector math" if lane.vector_math else ", scalar math"))
        t0 = time.perf_counter()
        lane_solve = lanes.compiled_solve()
        lane_build += time.perf_counter() - t0
        cold = (np.nan, np.nan, np.nan)  # no guess, no scan ends given
        tl_solve = median_time(lambda: lane_solve(load, slip, *cold, P), args.repeats) / n
        solve_check = np.max(np.abs(lane_solve(load, slip, *cold, P)[0]
                                    - np.array(c_solve(*solve_in)[0]).ravel()))
        # a sweep: model.steady_map over loads x slips, warm-started along the loads from
        # the neighbouring solutions (the whole API path: validation, retries, NaN marking)
        ps = presets.load("paper-table2-arc")
        loads, slips = np.linspace(20.0, 60.0, 100), np.linspace(0.0, 0.5, max(1, n // 100))
        t_sweep = median_time(lambda: model.steady_map(ps, loads, slips),
                              args.repeats) / (loads.size * slips.size)
        # the unit of a solve's cost: one Fz_static value at the same points (two per point:
        # the scan's ends, lanes.compiled_scan_ends)
        ends = lanes.compiled_scan_ends()
        t_value = median_time(lambda: ends(slip, P), args.repeats) / (2 * n)
        scan = solve.scan_angles().size
        figures.update(scan_value_eval_s=t_value, solve_in_values=tl_solve / t_value)
        figures.update(force_eval_s=tl_map, force_eval_how=how, force_eval_casadi_c_s=tc_map,
                       solve_s=tl_solve, solve_how=how + ", cold (pruned scan)",
                       solve_casadi_c_s=tc_solve, solve_sweep_s=t_sweep,
                       solve_sweep_how=f"model.steady_map, {loads.size} loads x {slips.size} "
                       "slips, warm-started along the loads")
        say(f"  force eval, lane-parallel C            : {tl_map * 1e6:9.3f} us/pt "
            f"= {1 / tl_map:10.3g} /s   (goal >= 1e6 /s)")
        say(f"  ({how}; max |DP - DP(VM)| = {lane_check:.1e} N)")
        say(f"  sinkage solve, mapped + compiled C     : {tc_solve * 1e6:9.3f} us/pt "
            f"= {1 / tc_solve:10.3g} /s")
        say(f"  sinkage solve, lane-parallel C         : {tl_solve * 1e6:9.3f} us/pt "
            f"= {1 / tl_solve:10.3g} /s   (goal >= 1e5 /s; max |z - z(CasADi C)| = "
            f"{solve_check:.1e} m; both libraries ready in {lane_build:.1f} s)")
        say(f"  steady states, sweep (model.steady_map): {t_sweep * 1e6:8.3f} us/pt "
            f"= {1 / t_sweep:10.3g} /s   ({figures['solve_sweep_how']})")
        say(f"  one Fz_static value, lane-parallel C   : {t_value * 1e6:9.3f} us/pt; a cold "
            f"solve costs {tl_solve / t_value:.1f} of them (the full {scan}-point scan alone "
            f"was {scan})")
        with tempfile.TemporaryDirectory() as tmp:
            c_lateral = compile_external(lateral_map, Path(tmp))
            tc_lateral = median_time(lambda: c_lateral(*lateral_in), args.repeats) / n
        lane_lateral = lanes.compiled_lateral()
        tl_lateral = median_time(lambda: lane_lateral(z, slip, beta, no_turn, P),
                                 args.repeats) / n
        lateral_check = np.max(np.abs(lane_lateral(z, slip, beta, no_turn, P)
                                      - np.array(lateral_map(*lateral_in)).reshape(-1, n)))
        figures.update(lateral_eval_s=tl_lateral, lateral_eval_how="lane-parallel C",
                       lateral_eval_casadi_c_s=tc_lateral)
        say(f"  side force, mapped + compiled C        : {tc_lateral * 1e6:9.3f} us/pt "
            f"= {1 / tc_lateral:10.3g} /s   (slip angles 5-30 deg)")
        say(f"  side force, lane-parallel C            : {tl_lateral * 1e6:9.3f} us/pt "
            f"= {1 / tl_lateral:10.3g} /s   (max |F_y - F_y(VM)| = {lateral_check:.1e} N)")
    else:  # the figures of record are the compiled ones; without a compiler, the VM's
        figures.update(force_eval_s=t_map, solve_s=t_solve, lateral_eval_s=t_lateral_vm,
                       lateral_eval_how="Function.map (CasADi VM)")
    figures["compiled"] = not args.no_compile

    sys.path.insert(0, str(ROOT / "tests"))  # the reference lives with the tests it serves
    from classical_reference import Classical

    ref = Classical(R=0.05, b=0.075, c=0.0, phi=np.radians(23), kc=0.63, kphi=80, n=1.1,
                    gamma=15620, K=0.036)
    t_ref = median_time(lambda: ref.forces(0.03, 0.2), args.repeats)
    t_ref_solve = median_time(lambda: ref.sinkage(62.0, 0.2), args.repeats)
    t_ref_lateral = median_time(lambda: ref.lateral(0.03, 0.2, math.radians(15.0), K_y=0.036),
                                args.repeats)
    figures.update(lateral_eval_reference_s=t_ref_lateral,
                   lateral_eval_speedup=t_ref_lateral / figures["lateral_eval_s"])
    say(f"  baseline: scipy-quad reference, side   : {t_ref_lateral * 1e6:9.1f} us "
        f"({figures['lateral_eval_how']} {figures['lateral_eval_speedup']:7.0f}x faster)")
    figures.update(force_eval_reference_s=t_ref, solve_reference_s=t_ref_solve,
                   force_eval_speedup=t_ref / figures["force_eval_s"],
                   solve_speedup=t_ref_solve / figures["solve_s"])
    if "solve_sweep_s" in figures:
        figures["solve_sweep_speedup"] = t_ref_solve / figures["solve_sweep_s"]
    say(f"  baseline: scipy-quad reference, force  : {t_ref * 1e6:9.1f} us "
        f"(mapped VM {t_ref / t_map:6.0f}x faster"
        + ("" if args.no_compile else f", CasADi C {t_ref / tc_map:7.0f}x, lanes "
                                      f"{t_ref / tl_map:7.0f}x") + ")")
    say(f"  baseline: scipy reference, solve       : {t_ref_solve * 1e6:9.1f} us "
        f"(mapped VM {t_ref_solve / t_solve:6.0f}x faster"
        + ("" if args.no_compile else f", CasADi C {t_ref_solve / tc_solve:7.0f}x, lanes "
                                      f"{t_ref_solve / tl_solve:7.0f}x, sweep "
                                      f"{t_ref_solve / t_sweep:7.0f}x") + ")")
    if args.json:
        print(json.dumps(figures, indent=2))


if __name__ == "__main__":
    main()
