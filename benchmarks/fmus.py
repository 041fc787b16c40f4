"""Speed of the FMUs, both flavours measured in the same run: microseconds per doStep of each
FMU, and the wall time of the whole C1-C4 co-simulation (4 x 30 s at a 1 ms step, both FMUs) on
one core, with the fmpy master (Python) for both flavours and with ecos (C++) for the native one.

    wheelterrain build --flavor all
    python benchmarks/fmus.py [--fmu-dir build] [--steps 5000] [--repeats 5] [--no-c1-c4]

The native FMUs are expected in FMU_DIR/native (skipped if absent).

Each doStep figure is the median over repeats of a loop that sets the inputs, steps and reads the
outputs, as the master does; the bare doStep (no get/set) is printed too. The baseline measured in
the same run is one call of the core model's CasADi Function from Python (what WheelTerrain's
doStep must do at least once). Goals: C1-C4 under 10 s on one core (pythonfmu); natively
<= 1 us per WheelTerrain doStep and C1-C4 at least 20x faster than the pythonfmu flavour.
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

from fmpy import extract

from wheelterrain import presets
from wheelterrain.cosim import master as cosim
from wheelterrain.fmu.instance import Instance
from wheelterrain.model import contact


def per_call(fn, n: int, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn(n)
        times.append((time.perf_counter() - t) / n)
    return statistics.median(times) * 1e6


def step_figures(fmu_dir: Path, label: str, n: int, k: int) -> None:
    names = ("WheelTerrain", "SingleWheelRig")
    unzip = {m: extract(str(fmu_dir / f"{m}.fmu")) for m in names}
    try:
        t = Instance(fmu_dir / "WheelTerrain.fmu", unzip["WheelTerrain"], "t").start(
            {"sinkage": 0.035, "wheel_speed": 0.6, "carriage_speed": 0.024})
        r = Instance(fmu_dir / "SingleWheelRig.fmu", unzip["SingleWheelRig"], "r").start(
            {"rig.slip_paper": 0.25})
        t_in = [t.vr[x] for x in ("sinkage", "sinkage_rate", "wheel_speed", "carriage_speed")]
        t_out = [t.vr[x] for x in ("normal_force", "drawbar_pull", "torque")]
        r_in = [r.vr[x] for x in ("normal_force", "drawbar_pull", "torque")]
        r_out = [r.vr[x] for x in ("sinkage", "sinkage_rate", "wheel_speed", "carriage_speed")]
        clock = [0.0]

        def loop(inst, ins, outs, values):
            def run(count):
                for _ in range(count):
                    inst.fmu.setReal(ins, values)
                    inst.fmu.getReal(outs)
                    inst.fmu.doStep(clock[0], 1e-3)
                    clock[0] += 1e-3
            return run

        def bare(inst):
            def run(count):
                for _ in range(count):
                    inst.fmu.doStep(clock[0], 1e-3)
                    clock[0] += 1e-3
            return run

        terrain = loop(t, t_in, t_out, [0.035, 0.0, 0.6, 0.024])
        rig_loop = loop(r, r_in, r_out, [62.0, -30.0, 0.6])
        print(f"{label}: one core, median of {k} x {n} steps, through fmpy (ctypes)")
        print(f"  WheelTerrain   set+get+doStep : {per_call(terrain, n, k):8.2f} us")
        print(f"  WheelTerrain   doStep alone   : {per_call(bare(t), n, k):8.2f} us "
              "(includes the force evaluation at the new wheel angle)")
        print(f"  SingleWheelRig set+get+doStep : {per_call(rig_loop, n, k):8.2f} us")
        print(f"  SingleWheelRig doStep alone   : {per_call(bare(r), n, k):8.2f} us")
        t.close()
        r.close()
    finally:
        for d in unzip.values():
            shutil.rmtree(d, ignore_errors=True)


def c1_c4_ecos(fmu_dir: Path, ps) -> float:
    from wheelterrain.cosim import ssp

    paper = cosim.table3()
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        for row in paper["cases"]:
            path = ssp.write(Path(tmp) / f"{row['case']}.ssp", fmu_dir, row["case"], ps,
                             row["slip_paper"], paper["load_N"], paper["wheel_speed_m_per_s"],
                             cosim.STOP_TIME, cosim.STEP)
            ssp.simulate_with_ecos(path, row["case"], cosim.STOP_TIME, cosim.STEP,
                                   Path(tmp) / f"{row['case']}.csv",
                                   ("rig::sensor.drawbar_pull",))
    return time.perf_counter() - start


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fmu-dir", default="build")
    ap.add_argument("--steps", type=int, default=5000)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--no-c1-c4", action="store_true")
    args = ap.parse_args()
    dirs = {"pythonfmu": Path(args.fmu_dir), "native": Path(args.fmu_dir) / "native"}
    dirs = {k: d for k, d in dirs.items() if (d / "WheelTerrain.fmu").is_file()
            and (d / "SingleWheelRig.fmu").is_file()}
    if not dirs:
        sys.exit(f"no FMUs in {args.fmu_dir}: run `wheelterrain build --flavor all "
                 f"--out {args.fmu_dir}`")
    ps = presets.load("paper-table2-arc")
    fn, p = contact.build().contact, ps.vector()

    def core(count):
        for _ in range(count):
            fn(0.035, 0.0, 0.2, 0.1, p)

    for label, d in dirs.items():
        step_figures(d, label, args.steps, args.repeats)
    print(f"baseline: core contact Function call from Python: "
          f"{per_call(core, args.steps, args.repeats):.1f} us")
    if args.no_c1_c4:
        return
    walls = {}
    for label, d in dirs.items():
        start = time.perf_counter()
        cosim.reproduce(d, ps)
        walls[label] = time.perf_counter() - start
        print(f"C1-C4 (4 x 30 s at 1 ms, both FMUs), fmpy master, {label}: "
              f"{walls[label]:.2f} s wall")
    if "native" in dirs:
        try:
            walls["native+ecos"] = c1_c4_ecos(dirs["native"], ps)
            print(f"C1-C4, ecos master (C++), native: {walls['native+ecos']:.2f} s wall")
        except ImportError:
            print("C1-C4 with ecos: ecospy not installed")
    if "pythonfmu" in walls:
        for label in ("native", "native+ecos"):
            if label in walls:
                print(f"  speed-up {label} vs pythonfmu (fmpy master): "
                      f"{walls['pythonfmu'] / walls[label]:.1f}x (goal >= 20x)")


if __name__ == "__main__":
    main()
