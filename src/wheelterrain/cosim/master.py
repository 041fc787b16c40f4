"""The co-simulation master: SingleWheelRig.fmu + WheelTerrain.fmu under fmpy, the C1-C4 runs.

Coupling, per communication step h (fixed), Gauss-Seidel on the algebraic terrain:
1. the rig's state outputs at t (sinkage, sinkage rate, wheel speed, carriage speed) are set as
   WheelTerrain's inputs;
2. WheelTerrain's forces at t (direct feedthrough: evaluated from those inputs and the wheel
   angle at t) are set as the rig's inputs;
3. both FMUs step t -> t + h (the rig integrates its motion with the forces held, the terrain
   advances the wheel angle).

Averages: the start-up transient (the wheel settling into the soil from the surface) is waited
out for SETTLE_TIME; the mean is then taken over the largest whole number of grouser periods
2*pi/(n_g*omega_ref) that ends at the stop time, so the ripple averages out exactly in the
steady state.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

import numpy as np

from wheelterrain import data
from wheelterrain.errors import CosimulationError, FMUError
from wheelterrain.files import write_atomic
from wheelterrain.fmu.instance import Instance, read_description
from wheelterrain.fmu.variables import COUPLED_FORCES, COUPLED_STATES, RIG_IO, TERRAIN_IO
from wheelterrain.model import rig
from wheelterrain.model.slip import reference_radius
from wheelterrain.parameters import TABLE, ParameterSet

STOP_TIME = 30.0  # s, per case (the paper's runs are ~30 s)
STEP = 1e-3  # s, communication step
SETTLE_TIME = 10.0  # s: transient waited out before averaging (it settles in ~2 s)
RECORD = ("sinkage", "normal_force", "drawbar_pull", "torque", "slip", "slip_paper",
          "wheel_speed", "carriage_speed", "motor_torque", "wheel_angle")


@dataclass
class CaseResult:
    case: str
    slip_paper: float
    means: dict[str, float]
    window: tuple[float, float]
    series: dict[str, np.ndarray] = field(repr=False)
    wall_time: float = 0.0
    master: str = ""  # how the pair was run, in words (plots and reports name it)


def rig_parameters(ps: ParameterSet, slip_paper: float, load: float,
                   rim_speed: float) -> dict[str, float]:
    values = rig.defaults()
    values.update({"rig.load": load, "rig.mass": load / rig.STANDARD_GRAVITY,
                   "rig.rim_speed": rim_speed, "rig.slip_paper": slip_paper,
                   "rig.slip_radius": reference_radius(ps)})
    for name, value in values.items():
        rig.check(name, value)
    return values


def averaging_window(ps: ParameterSet, rim_speed: float, stop: float,
                     settle: float = SETTLE_TIME) -> tuple[float, float]:
    """[start, stop]: the most whole grouser periods that fit after ``settle``."""
    omega = rim_speed / reference_radius(ps)
    count = ps["grouser.count"]
    if count <= 0 or omega <= 0:
        return settle, stop
    period = 2 * math.pi / (count * omega)
    periods = math.floor((stop - settle) / period)
    return (stop - periods * period, stop) if periods >= 1 else (settle, stop)


def start_pair(paths: dict[str, Path], unzipped: dict[str, str], ps: ParameterSet,
               rig_values: dict[str, float], stop: float | None = None,
               interface: str = "cs") -> tuple:
    """(terrain, rig) instances, initialised: the table parameters ``ps`` on WheelTerrain in
    dynamic mode, ``rig_values`` on SingleWheelRig; co-simulation or model exchange."""
    terrain = Instance(paths["WheelTerrain"], unzipped["WheelTerrain"], "terrain",
                       interface=interface)
    try:
        rig_fmu = Instance(paths["SingleWheelRig"], unzipped["SingleWheelRig"], "rig",
                           interface=interface)
    except BaseException:
        terrain.close()
        raise
    try:
        terrain.start({**{p.name: ps[p.name] for p in TABLE}, "quasi_static": False}, stop)
        rig_fmu.start(rig_values, stop)
    except BaseException:
        terrain.close()
        rig_fmu.close()
        raise
    return terrain, rig_fmu




class Coupling:
    """The FMU pair's coupling scheme, written once: Gauss-Seidel, rig first.

    :meth:`exchange` reads the rig's wheel states (COUPLED_STATES), hands them to the terrain,
    reads the terrain's forces (COUPLED_FORCES) and hands them, with any ``commands``, to the rig;
    :meth:`step` then advances the rig and the terrain over the same interval. ``rig_extra`` and
    ``terrain_extra`` name further outputs read with the states and with the forces (what a
    caller records), ``commands`` further rig inputs set with the forces. Used by the C1-C4
    master (:func:`run_case`) and the MPC's FMU plant (``closed_loop.FMUPlant``).
    """

    def __init__(self, terrain: Instance, rig_fmu: Instance, rig_extra: tuple = (),
                 terrain_extra: tuple = (), commands: tuple = ()) -> None:
        self.terrain, self.rig = terrain, rig_fmu
        self._rig_out = rig_fmu.refs((*COUPLED_STATES, *rig_extra))
        self._ter_in = terrain.refs(COUPLED_STATES)
        self._ter_out = terrain.refs((*COUPLED_FORCES, *terrain_extra))
        self._rig_in = rig_fmu.refs((*COUPLED_FORCES, *commands))
        self._states, self._forces = len(COUPLED_STATES), len(COUPLED_FORCES)
        self.read = (*COUPLED_STATES, *rig_extra, *COUPLED_FORCES, *terrain_extra)
        """What one :meth:`exchange` reads, by name, in the order of its two lists joined."""

    def positions(self, names) -> list[int]:
        """Where each of ``names`` sits in the two lists of :meth:`exchange` joined (x + y)."""
        missing = [n for n in names if n not in self.read]
        if missing:
            raise ValueError(f"the exchange does not read {', '.join(missing)}")
        return [self.read.index(n) for n in names]

    def exchange(self, commands: tuple = ()) -> tuple[list[float], list[float]]:
        """One exchange; returns (rig outputs: COUPLED_STATES + rig_extra, terrain outputs: forces +
        terrain_extra)."""
        x = self.rig.fmu.getReal(self._rig_out)
        self.terrain.fmu.setReal(self._ter_in, x[:self._states])
        y = self.terrain.fmu.getReal(self._ter_out)
        self.rig.fmu.setReal(self._rig_in, [*y[:self._forces], *commands])
        return x, y

    def step(self, t: float, h: float) -> None:
        self.rig.fmu.doStep(t, h)
        self.terrain.fmu.doStep(t, h)


def _extra(names, io, coupled) -> tuple[str, ...]:
    """Those of ``names`` that are outputs in ``io`` and not already read as ``coupled``."""
    outputs = {v.name for v in io if v.causality == "output"}
    return tuple(n for n in names if n in outputs and n not in coupled)


def _cosimulate(pair: Coupling, where: list[int], n: int, step: float) -> np.ndarray:
    """Co-simulation: exchange, record, then both FMUs step (rows: t, then RECORD)."""
    exchange, advance = pair.exchange, pair.step
    data = np.empty((n + 1, len(where) + 1))
    for k in range(n + 1):
        t = k * step
        x, y = exchange()
        xy = x + y
        data[k, 0] = t
        data[k, 1:] = [xy[j] for j in where]
        if k < n:
            advance(t, step)
    return data


def _integrate(pair: Coupling, where: list[int], n: int, step: float) -> np.ndarray:
    """Model exchange: the master integrates the states of both FMUs together with the
    classical fourth-order Runge-Kutta method at the communication step, exchanging the wheel
    states and the forces at every stage (rows as :func:`_cosimulate`)."""
    from ctypes import POINTER, c_double

    terrain, rig_fmu = pair.terrain.fmu, pair.rig.fmu
    nt = pair.terrain.md.numberOfContinuousStates
    nr = pair.rig.md.numberOfContinuousStates
    state, rate = np.zeros(nt + nr), np.zeros(nt + nr)

    def pointer(a: np.ndarray, offset: int):
        return a[offset:].ctypes.data_as(POINTER(c_double))

    terrain.getContinuousStates(pointer(state, 0), nt)
    rig_fmu.getContinuousStates(pointer(state, nt), nr)

    def rates(t: float, x: np.ndarray) -> tuple[np.ndarray, list[float]]:
        state[:] = x
        for fmu, offset, size in ((terrain, 0, nt), (rig_fmu, nt, nr)):
            fmu.setTime(t)
            fmu.setContinuousStates(pointer(state, offset), size)
        xs, ys = pair.exchange()
        terrain.getDerivatives(pointer(rate, 0), nt)
        rig_fmu.getDerivatives(pointer(rate, nt), nr)
        return rate.copy(), xs + ys

    data = np.empty((n + 1, len(where) + 1))
    x = state.copy()
    for k in range(n + 1):
        t = k * step
        k1, xy = rates(t, x)
        data[k, 0] = t
        data[k, 1:] = [xy[j] for j in where]
        if k < n:
            k2 = rates(t + step / 2, x + step / 2 * k1)[0]
            k3 = rates(t + step / 2, x + step / 2 * k2)[0]
            k4 = rates(t + step, x + step * k3)[0]
            x = x + step / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return data


WARNING = 1  # fmi2Warning: the highest status fmpy's wrappers accept


def _direct_calls(pair: Coupling):
    """(component, fmi2GetReal, fmi2SetReal, fmi2DoStep) of the rig and of the terrain: new
    ctypes function objects on the libraries fmpy loaded, without argument types (ctypes then
    passes the ctypes objects it is given as they are, the cheapest call it makes; fmpy's own
    function objects are left as they are). None when the pair is not two FMI 2 slaves (an
    FMI 3 pair goes through the adapter's fmpy calls)."""
    from ctypes import PyDLL, c_void_p

    from fmpy.fmi2 import FMU2Slave

    fmus = (pair.rig.fmu, pair.terrain.fmu)
    if not all(isinstance(f, FMU2Slave) for f in fmus):
        return None
    calls = []
    for fmu in fmus:
        # the library fmpy loaded, seen as a PyDLL: its calls keep the GIL instead of
        # releasing and taking it back around each ~1 us call (a mutex pair per call, ~5 % of
        # the loop); an FMU's logger callback into Python still works, its thread holds the GIL
        dll = PyDLL(fmu.dll._name, handle=fmu.dll._handle)
        component = fmu.component
        handle = c_void_p(component.value if isinstance(component, c_void_p) else component)
        calls.append((handle, *(dll._FuncPtr((name, dll)) for name in
                                ("fmi2GetReal", "fmi2SetReal", "fmi2DoStep"))))
    return calls


@lru_cache(maxsize=1)
def _coupling_loop():
    """The master's loop compiled from coupling.c (``couple``, ctypes), or None where this
    machine cannot compile it (no C compiler, or it failed: the Python loop then runs, with
    the same numbers)."""
    from ctypes import CDLL, c_double, c_long, c_size_t, c_void_p

    from wheelterrain.compiled import CompileError, cached_source

    try:
        library = CDLL(str(cached_source(Path(__file__).with_name("coupling.c"))))
    except (CompileError, OSError):
        return None
    couple = library.couple
    couple.restype = c_long
    couple.argtypes = ([c_void_p] * 8 + [c_void_p, c_size_t] * 4
                       + [c_void_p, c_size_t, c_void_p, c_size_t, c_long, c_double, c_long])
    return couple


COUPLING_CALLS = 6
"""Calls per step of the direct loops (coupling.c's order: rig get, terrain set, terrain get,
rig set, rig step, terrain step): the compiled loop's stopping point is 6*k + call."""


def _cosimulate_direct(pair: Coupling, where: list[int], n: int, step: float) -> np.ndarray:
    """:func:`_cosimulate`'s loop, the same calls in the same order, made straight into the
    FMUs' FMI 2 functions, the FMUs reading and writing the rows of the record in place:
    fmpy's wrappers build their argument arrays and check every status in Python, ~20 us per
    coupled step, more than the native FMUs' own time. The loop runs in C (coupling.c,
    compiled once per machine: ~1.5 us a step on the native pair) or, where that cannot be
    compiled, in Python through ctypes (~3 us). A call that does not return fmi2OK is made
    again through fmpy's wrapper, which raises as in :func:`_cosimulate` (a refused call
    changes nothing; fmi2Warning passes, as there)."""
    from ctypes import addressof, c_double, c_int, c_size_t, c_uint, c_void_p, cast

    calls = _direct_calls(pair)
    if calls is None or len(pair._rig_in) != len(COUPLED_FORCES):  # no commands here
        return _cosimulate(pair, where, n, step)
    (rig_c, rig_get, rig_set, rig_step), (ter_c, ter_get, ter_set, ter_step) = calls
    rig_out, ter_in, ter_out, rig_in = (
        (c_uint * len(r))(*r) for r in (pair._rig_out, pair._ter_in, pair._ter_out, pair._rig_in))
    n_x, n_y = c_size_t(len(rig_out)), c_size_t(len(ter_out))
    n_states, n_forces = c_size_t(len(ter_in)), c_size_t(len(rig_in))
    xs, ys = np.empty((n + 1, len(rig_out))), np.empty((n + 1, len(ter_out)))
    rig, ter = pair.rig.fmu, pair.terrain.fmu
    # each call of step k through fmpy's wrapper, in coupling.c's order: made again where the
    # direct one did not return fmi2OK (fmpy raises with the FMU's reason)
    redo = (lambda k: xs.__setitem__(k, rig.getReal(pair._rig_out)),
            lambda k: ter.setReal(pair._ter_in, list(xs[k, :len(ter_in)])),
            lambda k: ys.__setitem__(k, ter.getReal(pair._ter_out)),
            lambda k: rig.setReal(pair._rig_in, list(ys[k, :len(rig_in)])),
            lambda k: rig.doStep(k * step, step),
            lambda k: ter.doStep(k * step, step))
    couple = _coupling_loop()
    if couple is not None:
        pointers = [rig_c, *(cast(f, c_void_p) for f in (rig_get, rig_set, rig_step)),
                    ter_c, *(cast(f, c_void_p) for f in (ter_get, ter_set, ter_step))]
        resume = 0
        while True:
            stopped = couple(*pointers, addressof(rig_out), n_x, addressof(ter_in), n_states,
                             addressof(ter_out), n_y, addressof(rig_in), n_forces,
                             xs.ctypes.data, xs.strides[0] // xs.itemsize, ys.ctypes.data,
                             ys.strides[0] // ys.itemsize, n, step, resume)
            if stopped < 0:
                break
            k, call = divmod(stopped, COUPLING_CALLS)
            redo[call](k)  # raises with the FMU's reason; if it goes through, carry on
            resume = stopped + 1
        return _record(xs, ys, where, n, step)
    x0, y0 = xs.ctypes.data, ys.ctypes.data
    dx, dy = xs.strides[0], ys.strides[0]
    h, no_set_prior = c_double(step), c_int(1)
    # one ctypes object each for the row pointers and the time, their values set in place:
    # making new ones was ~10 % of the loop
    x, y, t = c_void_p(), c_void_p(), c_double()
    for k in range(n + 1):
        x.value, y.value = x0 + k * dx, y0 + k * dy
        if rig_get(rig_c, rig_out, n_x, x) > WARNING:
            redo[0](k)
        if ter_set(ter_c, ter_in, n_states, x) > WARNING:
            redo[1](k)
        if ter_get(ter_c, ter_out, n_y, y) > WARNING:
            redo[2](k)
        if rig_set(rig_c, rig_in, n_forces, y) > WARNING:
            redo[3](k)
        if k < n:
            t.value = k * step
            if rig_step(rig_c, t, h, no_set_prior) > WARNING:
                redo[4](k)
            if ter_step(ter_c, t, h, no_set_prior) > WARNING:
                redo[5](k)
    return _record(xs, ys, where, n, step)


def _record(xs: np.ndarray, ys: np.ndarray, where: list[int], n: int, step: float
            ) -> np.ndarray:
    """The rows of :func:`_cosimulate` from the direct loops' rig outputs ``xs`` and terrain
    outputs ``ys``."""
    data = np.empty((n + 1, len(where) + 1))
    data[:, 0] = np.arange(n + 1) * step
    data[:, 1:] = np.hstack([xs, ys])[:, where]
    return data


INTERFACES = {"cs": _cosimulate, "me": _integrate}
"""How the pair runs: FMI co-simulation (each FMU steps itself) or model exchange (the master
integrates the FMUs' states)."""
MASTER_NAMES = {
    "direct": "wheelterrain master, co-simulation (FMI called straight from its loop)",
    "cs": "wheelterrain master, co-simulation (fmpy's FMI wrappers)",
    "me": "wheelterrain master, model exchange (RK4)",
}
"""The master's loop in words (CaseResult.master): the direct ctypes loop or an INTERFACES one."""


def run_case(fmu_dir: Path, ps: ParameterSet, slip_paper: float, load: float, rim_speed: float,
             case: str = "", stop: float = STOP_TIME, step: float = STEP,
             unzipped: dict[str, str] | None = None, settle: float = SETTLE_TIME,
             interface: str = "cs", direct: bool = True) -> CaseResult:
    """Run one rig case through ``interface`` (:data:`INTERFACES`); returns means over the
    averaging window and the series. ``direct``: co-simulation calls the FMI 2 functions
    straight from the master's loop (:func:`_cosimulate_direct`, the same numbers); False
    keeps fmpy's wrappers in the loop (the reference the benchmarks compare against)."""
    from fmpy import extract
    from fmpy.fmi1 import FMICallException

    paths = fmu_paths(fmu_dir)
    own = unzipped is None
    unzipped = unzipped or {name: extract(str(p)) for name, p in paths.items()}
    started = time.perf_counter()
    terrain, rig_fmu = start_pair(paths, unzipped, ps,
                                  rig_parameters(ps, slip_paper, load, rim_speed), stop,
                                  interface)
    try:
        pair = Coupling(terrain, rig_fmu,
                        rig_extra=_extra(RECORD, RIG_IO, COUPLED_STATES),
                        terrain_extra=_extra(RECORD, TERRAIN_IO, COUPLED_FORCES))
        loop = _cosimulate_direct if interface == "cs" and direct else INTERFACES[interface]
        try:
            data = loop(pair, pair.positions(RECORD), round(stop / step), step)
        except FMICallException as err:  # the FMU has logged why
            raise CosimulationError(f"case {case or slip_paper}: {err} The FMU logged the "
                                    "reason above.") from None
    finally:
        terrain.close()
        rig_fmu.close()
        if own:
            for d in unzipped.values():
                shutil.rmtree(d, ignore_errors=True)
    wall = time.perf_counter() - started
    series = {"time": data[:, 0], **{name: data[:, j + 1] for j, name in enumerate(RECORD)}}
    start, end = averaging_window(ps, rim_speed, stop, settle)
    # samples at t in [start, end): a whole number of periods of a sampled signal
    mask = (series["time"] >= start - 0.5 * step) & (series["time"] < end - 0.5 * step)
    means = {name: float(np.mean(series[name][mask])) for name in RECORD}
    master = MASTER_NAMES["direct" if interface == "cs" and direct else interface]
    return CaseResult(case, slip_paper, means, (start, end), series, wall,
                      f"{master}, {flavour_of(terrain.md)} FMUs, step {step:g} s")


def flavour_of(md) -> str:
    """'pythonfmu' or 'native': which build wrote the FMU of model description ``md``."""
    return "pythonfmu" if (md.generationTool or "").startswith("PythonFMU") else "native"


def fmu_paths(fmu_dir: Path, names: tuple[str, ...] = ("WheelTerrain", "SingleWheelRig")
              ) -> dict[str, Path]:
    """The FMUs ``names`` in ``fmu_dir``, each checked before any engine loads it: a missing
    one is FileNotFoundError saying how to build it; a file that is not an FMU, or is another
    model's, is FMUError naming it (an engine given such a file crashed: ecos with SIGSEGV)."""
    paths = {name: Path(fmu_dir) / f"{name}.fmu" for name in names}
    for name, path in paths.items():
        if not path.is_file():
            raise FileNotFoundError(f"{path} not found: run `wheelterrain build --out {fmu_dir}`")
        md = read_description(path)
        model = (md.coSimulation or md.modelExchange).modelIdentifier
        if model != name:
            raise FMUError(f"{path} is the FMU of {model}, not {name}: `wheelterrain build` "
                           f"writes {name}.fmu")
    return paths


def table3() -> dict:
    return json.loads(data.path("paper_table3.json").read_text(encoding="utf-8"))


def choose_fmus(fmu_dir: Path | None, interface: str = "cs",
                build: Path = Path("build")) -> tuple[Path, str]:
    """The folder of the FMU pair to run and what it is, in words. ``fmu_dir`` None: the
    fastest built flavour, BUILD/native (generated C, no Python at run time) when both its FMUs
    exist and are no older than BUILD's pythonfmu pair, else BUILD (model exchange: native
    only). FileNotFoundError, saying how to build them, when there is none."""
    if fmu_dir is None:
        native, python = Path(build) / "native", Path(build)

        def built(folder: Path) -> float | None:
            paths = [folder / f"{n}.fmu" for n in ("WheelTerrain", "SingleWheelRig")]
            return min(p.stat().st_mtime for p in paths) if all(
                p.is_file() for p in paths) else None

        t_native, t_python = built(native), built(python)
        usable = t_native is not None and (t_python is None or t_native >= t_python - 1.0)
        fmu_dir = native if usable or interface == "me" else python
    paths = fmu_paths(fmu_dir)
    md = read_description(paths["WheelTerrain"])
    flavour = ("pythonfmu flavour (Python inside the FMUs; `wheelterrain build --flavor all` "
               "adds the faster native ones)" if flavour_of(md) == "pythonfmu"
               else "native flavour (generated C, no Python at run time)")
    how = ("FMI calls straight from the master's loop" if interface == "cs"
           and md.fmiVersion == "2.0" else "FMI calls through fmpy")
    return Path(fmu_dir), f"{flavour}, FMI {md.fmiVersion}, {how}"


def default_workers() -> int:
    """Worker processes for C1-C4: one per case, at most one per core this process may use."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        cores = os.cpu_count() or 1
    return max(1, min(len(table3()["cases"]), cores))


def reproduce(fmu_dir: Path, ps: ParameterSet, step: float = STEP, stop: float = STOP_TIME,
              progress: Callable[[str], None] | None = None,
              interface: str = "cs", workers: int = 1, direct: bool = True
              ) -> list[CaseResult]:
    """C1-C4 through ``interface`` (one extraction of each FMU reused for all cases), in
    ``workers`` processes (1: in this one). The cases are independent runs, so the results do
    not depend on ``workers`` (nor on ``direct``, see :func:`run_case`). ``progress(case)`` is
    called as each case finishes."""
    from fmpy import extract

    paper = table3()
    unzipped = {name: extract(str(p)) for name, p in fmu_paths(fmu_dir).items()}
    args = [(fmu_dir, ps, row["slip_paper"], paper["load_N"], paper["wheel_speed_m_per_s"],
             row["case"], stop, step, unzipped, SETTLE_TIME, interface, direct)
            for row in paper["cases"]]
    try:
        if workers <= 1:
            results = []
            for a in args:
                results.append(run_case(*a))
                if progress:
                    progress(a[5])  # this case is done
            return results
        return _in_processes(args, workers, progress)
    finally:
        for d in unzipped.values():
            shutil.rmtree(d, ignore_errors=True)


def _in_processes(args: list[tuple], workers: int,
                  progress: Callable[[str], None] | None) -> list[CaseResult]:
    """run_case(*a) for each of ``args`` in a pool of forked processes (forked: a spawned
    interpreter would spend longer importing than a case takes), in the order of ``args``."""
    import importlib
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, as_completed

    for module in ("fmpy.fmi2", "fmpy.fmi3"):  # imported once here, not in every worker
        importlib.import_module(module)

    methods = multiprocessing.get_all_start_methods()
    context = multiprocessing.get_context("fork" if "fork" in methods else None)
    with ProcessPoolExecutor(max_workers=min(workers, len(args)), mp_context=context) as pool:
        futures = {pool.submit(run_case, *a): k for k, a in enumerate(args)}
        results: list[CaseResult | None] = [None] * len(args)
        for future in as_completed(futures):
            k = futures[future]
            results[k] = future.result()
            if progress:
                progress(args[k][5])
    return results  # type: ignore[return-value]


def comparison(results: list[CaseResult]) -> list[dict]:
    """Rows of the Table III comparison: simulated means, experiment, paper's simulation."""
    paper = {row["case"]: row for row in table3()["cases"]}
    rows = []
    for r in results:
        p = paper[r.case]
        row = {"case": r.case, "slip_paper": r.slip_paper}
        for key in ("drawbar_pull", "normal_force", "sinkage"):
            row[key] = r.means[key]
            row[f"{key}_experiment"] = p["experiment"][key]
            row[f"{key}_paper_simulation"] = p["paper_simulation"][key]
            row[f"{key}_error"] = r.means[key] - p["experiment"][key]
        rows.append(row)
    return rows


def mean_absolute_errors(rows: list[dict]) -> dict[str, float]:
    out = {}
    for key in ("drawbar_pull", "normal_force", "sinkage"):
        out[key] = float(np.mean([abs(r[f"{key}_error"]) for r in rows]))
        out[f"{key}_paper_simulation"] = float(np.mean(
            [abs(r[f"{key}_paper_simulation"] - r[f"{key}_experiment"]) for r in rows]))
        out[f"{key}_vs_paper_simulation"] = float(np.mean(
            [abs(r[key] - r[f"{key}_paper_simulation"]) for r in rows]))
    return out


def format_table(rows: list[dict], mae: dict[str, float]) -> str:
    head = (f"{'case':4} {'s':>5} | {'DP sim':>7} {'DP exp':>7} {'DP pap':>7} {'err':>7} | "
            f"{'Fz sim':>7} {'Fz exp':>7} {'Fz pap':>7} {'err':>6} | "
            f"{'z sim':>6} {'z exp':>6} {'z pap':>6} {'err':>6}")
    units = f"{'':4} {'':>5} | {'[N]':>31} | {'[N]':>30} | {'[mm]':>27}"
    lines = [head, units, "-" * len(head)]
    for r in rows:
        lines.append(
            f"{r['case']:4} {r['slip_paper']:5.2f} | {r['drawbar_pull']:7.2f} "
            f"{r['drawbar_pull_experiment']:7.2f} {r['drawbar_pull_paper_simulation']:7.2f} "
            f"{r['drawbar_pull_error']:+7.2f} | {r['normal_force']:7.2f} "
            f"{r['normal_force_experiment']:7.2f} {r['normal_force_paper_simulation']:7.2f} "
            f"{r['normal_force_error']:+6.2f} | {1e3 * r['sinkage']:6.2f} "
            f"{1e3 * r['sinkage_experiment']:6.2f} {1e3 * r['sinkage_paper_simulation']:6.2f} "
            f"{1e3 * r['sinkage_error']:+6.2f}")
    lines.append("-" * len(head))
    lines.append(
        f"mean absolute error vs experiment: drawbar pull {mae['drawbar_pull']:.2f} N "
        f"(paper's simulation {mae['drawbar_pull_paper_simulation']:.2f} N), normal force "
        f"{mae['normal_force']:.2f} N ({mae['normal_force_paper_simulation']:.2f} N), sinkage "
        f"{1e3 * mae['sinkage']:.2f} mm ({1e3 * mae['sinkage_paper_simulation']:.2f} mm)")
    lines.append(
        f"mean absolute difference from the paper's simulation: drawbar pull "
        f"{mae['drawbar_pull_vs_paper_simulation']:.2f} N, normal force "
        f"{mae['normal_force_vs_paper_simulation']:.2f} N, sinkage "
        f"{1e3 * mae['sinkage_vs_paper_simulation']:.2f} mm")
    return "\n".join(lines)


def write_csv(path: Path, result: CaseResult, every: int = 10) -> None:
    write_series(path, {name: result.series[name] for name in ("time", *RECORD)}, every)


def csv_header(names, units: dict[str, str] | None = None) -> str:
    """A CSV header whose columns carry their units, ``drawbar_pull [N]`` (a column without a
    unit, e.g. a status, stays bare). ``units`` defaults to the FMU variables' units; a column
    with no declared unit is refused rather than written unlabelled."""
    if units is None:
        from wheelterrain.fmu.variables import units as variable_units

        units = variable_units()
    missing = [n for n in names if n not in units]
    if missing:
        raise ValueError(f"no unit declared for column(s) {', '.join(missing)}")
    return ",".join(f"{n} [{units[n]}]" if units[n] else n for n in names)


def write_series(path: Path, series: dict[str, np.ndarray], every: int = 1,
                 units: dict[str, str] | None = None) -> None:
    """Equal-length columns ``series`` as CSV, every ``every``-th row, written atomically; the
    header carries the units (:func:`csv_header`)."""
    names = list(series)
    data = np.column_stack([series[n] for n in names])[::every]
    lines = [csv_header(names, units)] + [",".join(f"{x:.10g}" for x in row) for row in data]
    write_atomic(path, "\n".join(lines) + "\n")
