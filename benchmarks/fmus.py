"""Speed of the pythonfmu FMUs: microseconds per doStep of each FMU, and the wall time of the
whole C1-C4 co-simulation (4 x 30 s at a 1 ms step, both FMUs), on one core.

    python benchmarks/fmus.py [--fmu-dir build] [--steps 5000] [--repeats 5] [--no-c1-c4]

Each doStep figure is the median over repeats of a loop that sets the inputs, steps and reads the
outputs, as the master does; the bare doStep (no get/set) is printed too. The baseline measured in
the same run is one call of the core model's CasADi Function from Python (what WheelTerrain's
doStep must do at least once). Goal (issue): C1-C4 under 10 s on one core.
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import sys
import time
from pathlib import Path

from fmpy import extract

from wheelterrain import contact, cosim, presets

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from fmu_support import Instance


def per_call(fn, n: int, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn(n)
        times.append((time.perf_counter() - t) / n)
    return statistics.median(times) * 1e6


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fmu-dir", default="build")
    ap.add_argument("--steps", type=int, default=5000)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--no-c1-c4", action="store_true")
    args = ap.parse_args()
    fmu_dir = Path(args.fmu_dir)
    names = ("WheelTerrain", "SingleWheelRig")
    for n in names:
        if not (fmu_dir / f"{n}.fmu").is_file():
            sys.exit(f"{fmu_dir / n}.fmu not found: run `wheelterrain build --out {fmu_dir}`")
    unzip = {n: extract(str(fmu_dir / f"{n}.fmu")) for n in names}
    ps = presets.load("paper-table2")
    try:
        t = Instance(fmu_dir / "WheelTerrain.fmu", unzip["WheelTerrain"], "t").start(
            {"sinkage": 0.035, "wheel_speed": 0.6, "carriage_speed": 0.024})
        r = Instance(fmu_dir / "SingleWheelRig.fmu", unzip["SingleWheelRig"], "r").start(
            {"rig.slip_paper": 0.25})
        t_in = [t.vr[k] for k in ("sinkage", "sinkage_rate", "wheel_speed", "carriage_speed")]
        t_out = [t.vr[k] for k in ("normal_force", "drawbar_pull", "torque")]
        r_in = [r.vr[k] for k in ("normal_force", "drawbar_pull", "torque")]
        r_out = [r.vr[k] for k in ("sinkage", "sinkage_rate", "wheel_speed", "carriage_speed")]
        clock = [0.0]

        def terrain_loop(n):
            for _ in range(n):
                t.fmu.setReal(t_in, [0.035, 0.0, 0.6, 0.024])
                t.fmu.getReal(t_out)
                t.fmu.doStep(clock[0], 1e-3)
                clock[0] += 1e-3

        def rig_loop(n):
            for _ in range(n):
                r.fmu.setReal(r_in, [62.0, -30.0, 0.6])
                r.fmu.getReal(r_out)
                r.fmu.doStep(clock[0], 1e-3)
                clock[0] += 1e-3

        def bare(inst):
            def loop(n):
                for _ in range(n):
                    inst.fmu.doStep(clock[0], 1e-3)
                    clock[0] += 1e-3
            return loop

        fn = contact.build().contact
        p = ps.vector()

        def core(n):
            for _ in range(n):
                fn(0.035, 0.0, 0.2, 0.1, p)

        n, k = args.steps, args.repeats
        print(f"pythonfmu FMUs, one core, median of {k} x {n} steps")
        print(f"  WheelTerrain   set+get+doStep : {per_call(terrain_loop, n, k):8.1f} us")
        print(f"  WheelTerrain   doStep alone   : {per_call(bare(t), n, k):8.1f} us")
        print(f"  SingleWheelRig set+get+doStep : {per_call(rig_loop, n, k):8.1f} us")
        print(f"  SingleWheelRig doStep alone   : {per_call(bare(r), n, k):8.1f} us")
        print(f"  baseline: core contact Function call from Python: {per_call(core, n, k):.1f} us")
        t.close()
        r.close()
        if not args.no_c1_c4:
            start = time.perf_counter()
            results = cosim.reproduce(fmu_dir, ps)
            wall = time.perf_counter() - start
            print(f"  C1-C4 (4 x 30 s at 1 ms, both FMUs): {wall:.1f} s wall "
                  f"(goal < 10 s); per case " +
                  ", ".join(f"{r.case} {r.wall_time:.1f} s" for r in results))
    finally:
        for d in unzip.values():
            shutil.rmtree(d, ignore_errors=True)


if __name__ == "__main__":
    main()
