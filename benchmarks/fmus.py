"""Speed of the FMUs, both flavours measured in the same run: microseconds per doStep of each
FMU, and the wall time of the whole C1-C4 co-simulation (4 x 30 s at a 1 ms step, both FMUs) on
one core, with the fmpy master (Python) for both flavours and with ecos (C++) for the native one.

    wheelterrain build --flavor all
    python benchmarks/fmus.py [--fmu-dir build] [--steps 5000] [--repeats 5] [--no-c1-c4]
    python benchmarks/fmus.py --quick --json      # fewer steps and repeats, one JSON object

``--json`` prints (seconds): ``<flavour>_start_up_wheel_s`` and ``<flavour>_start_up_rover_s``
(a fresh process's wait from its imports to the first WheelTerrain instance, or the rover's
seven instances, ready), ``native_step_c_host_s`` (a WheelTerrain set + doStep + get of
the native binary from a C host compiled here, no Python in the loop), ``pythonfmu_step_fmpy_s``
(the same through fmpy on the pythonfmu flavour), ``c1_c4_pythonfmu_fmpy_s`` (C1-C4, fmpy
master, pythonfmu), ``c1_c4_fastest_s`` and ``c1_c4_fastest_how`` (the fastest path measured in
the same run), and their ratios; the human-readable report goes to stderr.

The native FMUs are expected in FMU_DIR/native (skipped if absent).

Each doStep figure is the median over repeats of a loop that sets the inputs, steps and reads the
outputs, as the master does; the bare doStep (no get/set) is printed too. The C1-C4 runs
through fmpy (seconds each) are timed once; the direct ones (under half a second) are the median
of the repeats. The baseline measured in
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
from wheelterrain.model import functions as model_functions
from wheelterrain.parameters import TABLE


def per_call(fn, n: int, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn(n)
        times.append((time.perf_counter() - t) / n)
    return statistics.median(times) * 1e6


def step_figures(fmu_dir: Path, label: str, n: int, k: int) -> dict[str, float]:
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
        clock = {t: 0.0, r: 0.0}  # each instance's time: a step starts where its last ended

        def loop(inst, ins, outs, values):
            def run(count):
                for _ in range(count):
                    inst.fmu.setReal(ins, values)
                    inst.fmu.getReal(outs)
                    inst.fmu.doStep(clock[inst], 1e-3)
                    clock[inst] += 1e-3
            return run

        def bare(inst):
            def run(count):
                for _ in range(count):
                    inst.fmu.doStep(clock[inst], 1e-3)
                    clock[inst] += 1e-3
            return run

        terrain = loop(t, t_in, t_out, [0.035, 0.0, 0.6, 0.024])
        rig_loop = loop(r, r_in, r_out, [62.0, -30.0, 0.6])
        terrain_us = per_call(terrain, n, k)
        print(f"{label}: one core, median of {k} x {n} steps, through fmpy (ctypes)")
        print(f"  WheelTerrain   set+get+doStep : {terrain_us:8.2f} us")
        print(f"  WheelTerrain   doStep alone   : {per_call(bare(t), n, k):8.2f} us "
              "(includes the force evaluation at the new wheel angle)")
        print(f"  SingleWheelRig set+get+doStep : {per_call(rig_loop, n, k):8.2f} us")
        print(f"  SingleWheelRig doStep alone   : {per_call(bare(r), n, k):8.2f} us")
        t.close()
        r.close()
        return {"terrain_step_s": terrain_us * 1e-6}
    finally:
        for d in unzip.values():
            shutil.rmtree(d, ignore_errors=True)


ARC_PRESET = "paper-table2-arc"  # the C1-C4 runs and the second C-host step figure use it

HOST = Path(__file__).resolve().parents[1] / "tests" / "fmi_host.c"
"""The FMI host the platform tests use; with "time" it reports the wall time per step."""


def native_step_c_host(fmu_dir: Path, steps: int, repeats: int,
                       ps=None, quasi_static: str | None = None) -> float | None:
    """Seconds per WheelTerrain set + doStep + get of the native binary from a C host (median
    of ``repeats``), or None without a C compiler. ``ps``: the table parameters to set (None:
    the FMU's start values, the default preset's). Dynamic mode (constant inputs), or with
    ``quasi_static`` "warm" or "cold" the quasi-static mode with that warm_start (the load
    ramps from 20 N at 1 N/s, 1 mN a 1 ms step: a smoothly varying load, as in a system
    simulation)."""
    import subprocess

    from fmpy import read_model_description

    from wheelterrain import compiled as native
    from wheelterrain.fmu import build_native

    cc = native.compiler()
    if cc is None or not HOST.is_file():
        return None
    fmu = fmu_dir / "WheelTerrain.fmu"
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    ramp = ",".join(f"{vr[n]}={x}+0" for n, x in (("sinkage", 0.035), ("sinkage_rate", 0.0),
                                                  ("wheel_speed", 0.6),
                                                  ("carriage_speed", 0.024)))
    get = ",".join(str(vr[n]) for n in ("normal_force", "drawbar_pull", "torque"))
    kinds = {v.name: v.type for v in md.modelVariables}
    given = [] if ps is None else [
        f"{vr[p.name]}={ps[p.name]!r}" if kinds[p.name] == "Real"
        else f"i{vr[p.name]}={round(ps[p.name])}" for p in TABLE]
    if quasi_static is not None:
        given += [f"b{vr['quasi_static']}=1",
                  f"b{vr['warm_start']}={int(quasi_static == 'warm')}"]
        ramp = ",".join(f"{vr[n]}={x}" for n, x in (("load", "20+1"), ("wheel_speed", "0.6+0"),
                                                     ("carriage_speed", "0.024+0")))
        get += f",{vr['contact_sinkage']}"
    given = ",".join(given) or "-"
    with tempfile.TemporaryDirectory() as tmp:
        unzip = extract(str(fmu), unzipdir=str(Path(tmp) / "fmu"))
        exe = Path(tmp) / "host"
        subprocess.run([cc, "-O2", "-I", str(build_native.fmi_headers()), str(HOST), "-o",
                        str(exe), "-ldl"], check=True)
        library = Path(unzip) / "binaries" / "linux64" / "WheelTerrain.so"
        times = []
        for _ in range(repeats):
            run = subprocess.run([str(exe), str(library), md.guid, str(steps), "1e-3", given,
                                  ramp, get, "2", "time"],
                                 capture_output=True, text=True, check=True)
            times.append(float(run.stdout.split()[0]))
    return statistics.median(times)


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
                                   (f"{ssp.RIG_COMPONENT}::sensor.drawbar_pull",))
    return time.perf_counter() - start


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fmu-dir", default="build")
    ap.add_argument("--steps", type=int, default=5000)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--no-c1-c4", action="store_true")
    ap.add_argument("--quick", action="store_true",
                    help="1000 steps x 3 repeats for the per-step figures")
    ap.add_argument("--json", action="store_true",
                    help="print one JSON object of figures (the report goes to stderr)")
    args = ap.parse_args()
    if args.quick:
        args.steps, args.repeats = min(args.steps, 1000), min(args.repeats, 3)
    if args.json:  # the report goes to stderr, stdout carries the JSON alone
        import builtins
        import functools

        builtins.print = functools.partial(builtins.print, file=sys.stderr)
    dirs = {"pythonfmu": Path(args.fmu_dir), "native": Path(args.fmu_dir) / "native"}
    dirs = {k: d for k, d in dirs.items() if (d / "WheelTerrain.fmu").is_file()
            and (d / "SingleWheelRig.fmu").is_file()}
    if not dirs:
        sys.exit(f"no FMUs in {args.fmu_dir}: run `wheelterrain build --flavor all "
                 f"--out {args.fmu_dir}`")
    # the elastic soil: on the soil with memory paper-table2-arc's 49 mm at C4 digs in to full
    # burial and the case ends (the same work per step either way)
    ps = presets.load(ARC_PRESET).with_values({"model.soil_memory": 0})
    fn, p = model_functions.build().contact, ps.vector()

    def core(count):
        for _ in range(count):
            fn(0.035, 0.0, 0.2, 0.1, p)

    figures: dict = {}
    steps = {label: step_figures(d, label, args.steps, args.repeats) for label, d in dirs.items()}
    if "pythonfmu" in steps:
        figures["pythonfmu_step_fmpy_s"] = steps["pythonfmu"]["terrain_step_s"]
    if "native" in steps:
        figures["native_step_fmpy_s"] = steps["native"]["terrain_step_s"]
        c_host = native_step_c_host(dirs["native"], 20 * args.steps, args.repeats)
        if c_host is not None:
            figures["native_step_c_host_s"] = c_host
            arc = native_step_c_host(dirs["native"], 20 * args.steps, args.repeats, ps)
            figures["native_step_c_host_arc_s"] = arc
            print(f"native: WheelTerrain set+doStep+get from a C host: {c_host * 1e6:.2f} us "
                  f"(FMU defaults, {presets.DEFAULT_PRESET}: patch form); {arc * 1e6:.2f} us "
                  f"with {ARC_PRESET}'s parameters (arc form)")
            # quasi-static mode, the load ramping: every solve cold, then warm-started from
            # the previous step's sinkage (the FMU's default)
            for label, params in ((presets.DEFAULT_PRESET, None), (ARC_PRESET, ps)):
                quasi = {how: native_step_c_host(dirs["native"], 5 * args.steps, args.repeats,
                                                 params, how) for how in ("cold", "warm")}
                key = "" if params is None else "_arc"
                figures[f"native_quasi_static_cold_c_host{key}_s"] = quasi["cold"]
                figures[f"native_quasi_static_warm_c_host{key}_s"] = quasi["warm"]
                print(f"native, quasi-static mode, load ramping, {label}: "
                      f"{quasi['cold'] * 1e6:.2f} us a step solved cold, "
                      f"{quasi['warm'] * 1e6:.2f} us warm-started ("
                      f"{quasi['cold'] / quasi['warm']:.1f}x)")
    print(f"baseline: core contact Function call from Python: "
          f"{per_call(core, args.steps, args.repeats):.1f} us")
    for label, d in dirs.items():  # a host's wait before the first step
        if all((d / f"{m}.fmu").is_file() for m in ("RoverChassis", "Terrain")):
            for what in ("wheel", "rover"):
                figures[f"{label}_start_up_{what}_s"] = start_up(d, what, args.repeats)
            print(f"{label}: start-up in a fresh process (median of {args.repeats}): first "
                  f"WheelTerrain instance {figures[f'{label}_start_up_wheel_s']:.2f} s, the "
                  f"rover's seven instances {figures[f'{label}_start_up_rover_s']:.2f} s")
    if args.no_c1_c4:
        _emit(args, figures)
        return
    walls = {}
    for label, d in dirs.items():  # fmpy's wrappers in the loop, one process: the baseline
        start = time.perf_counter()
        cosim.reproduce(d, ps, direct=False)
        walls[label] = time.perf_counter() - start
        print(f"C1-C4 (4 x 30 s at 1 ms, both FMUs), fmpy master, {label}: "
              f"{walls[label]:.2f} s wall")
    workers = cosim.default_workers()
    if "native" in dirs:  # what `wheelterrain reproduce` runs by default
        for label, count in (("native+direct", 1), ("native+direct+processes", workers)):
            runs = []
            for _ in range(args.repeats):  # under half a second each: the median of repeats
                start = time.perf_counter()
                cosim.reproduce(dirs["native"], ps, workers=count)
                runs.append(time.perf_counter() - start)
            walls[label] = statistics.median(runs)
            print(f"C1-C4, native, our master's compiled loop, {count} process(es): "
                  f"{walls[label]:.2f} s wall (median of {len(runs)})")
    if "native" in dirs:
        try:
            walls["native+ecos"] = c1_c4_ecos(dirs["native"], ps)
            print(f"C1-C4, ecos master (C++), native: {walls['native+ecos']:.2f} s wall")
        except ImportError:
            print("C1-C4 with ecos: ecospy not installed")
    if "pythonfmu" in walls:
        for label in ("native", "native+ecos", "native+direct", "native+direct+processes"):
            if label in walls:
                print(f"  speed-up {label} vs pythonfmu (fmpy master): "
                      f"{walls['pythonfmu'] / walls[label]:.1f}x (goal >= 20x)")
        figures["c1_c4_pythonfmu_fmpy_s"] = walls["pythonfmu"]
    how = {"pythonfmu": "pythonfmu FMUs, fmpy master", "native": "native FMUs, fmpy master",
           "native+ecos": "native FMUs, ecos master (C++; Jacobi coupling, so its means are "
           "O(step) from ours)",
           "native+direct": "native FMUs, our master's compiled loop calling FMI",
           "native+direct+processes": "native FMUs, our master's compiled loop calling FMI, "
           f"the four cases in {workers} processes (wheelterrain reproduce)"}
    fastest = min(walls, key=walls.get)
    figures["c1_c4_fastest_s"], figures["c1_c4_fastest_how"] = walls[fastest], how[fastest]
    _emit(args, figures)


START_UP = """
import sys, time
started = time.perf_counter()
from pathlib import Path
from wheelterrain import presets
from wheelterrain.cosim import rover as engine, rover_fmus
from wheelterrain.fmu.instance import Instance
imported = time.perf_counter()
folder = Path(sys.argv[1])
if sys.argv[2] == "wheel":
    inst = Instance(folder / "WheelTerrain.fmu", name="t").start({})
    ready = time.perf_counter()
    inst.fmu.doStep(0.0, 1e-3)
    inst.close()
else:
    rover = rover_fmus.RoverFMUs(folder, engine.Soil(presets.load(presets.DEFAULT_PRESET)), {}, 1.0)
    ready = time.perf_counter()
    rover.exchange()
    rover.step(0.0, 1e-3)
    rover.close()
print(ready - imported, time.perf_counter() - started)
"""


def start_up(fmu_dir: Path, what: str, repeats: int) -> float:
    """Seconds from the imports done to the instances ready (``what``: "wheel", the first
    WheelTerrain instance; "rover", the rover's seven instances), each in a fresh process, the
    median of ``repeats``."""
    import subprocess

    runs = []
    for _ in range(repeats):
        out = subprocess.run([sys.executable, "-c", START_UP, str(fmu_dir), what],
                             capture_output=True, text=True, check=True)
        runs.append(float(out.stdout.split()[0]))
    return statistics.median(runs)


def _emit(args, figures: dict) -> None:
    """The ratios of the figures measured in this run, then the JSON object if asked for."""
    import json

    if "pythonfmu_step_fmpy_s" in figures and "native_step_c_host_s" in figures:
        figures["step_ratio_pythonfmu_fmpy_over_native_c_host"] = (
            figures["pythonfmu_step_fmpy_s"] / figures["native_step_c_host_s"])
    if "c1_c4_pythonfmu_fmpy_s" in figures:
        figures["c1_c4_ratio_pythonfmu_over_fastest"] = (
            figures["c1_c4_pythonfmu_fmpy_s"] / figures["c1_c4_fastest_s"])
    if args.json:
        sys.stdout.write(json.dumps(figures, indent=2) + "\n")


if __name__ == "__main__":
    main()
