"""The rover as FMUs: RoverChassis.fmu, four WheelTerrain.fmu and two Terrain.fmu (one per
track: the soil map and the rut profile each wheel's soil and rut come from), our master and
Rover.ssp.

Coupling per communication step h (fixed), Gauss-Seidel on the algebraic terrains, as the
single-wheel master couples the rig (:mod:`wheelterrain.cosim.master`):

1. each ``<wheel>.position`` of the chassis at t is set as its track's query point (the leading
   wheel q1, the one behind q2); the track's ``q*.rut_met`` and ``q*.rut_pressure_met``
   (and with a soil map its
   ``q*.ground.*``, the wheels then taking their soil from them: soil_from_inputs) at t are
   set as the wheel's inputs, with the chassis' per-wheel outputs at t (``<wheel>.sinkage``,
   ``.sinkage_rate``, ``.wheel_speed``, ``.carriage_speed``);
2. each WheelTerrain's forces at t (normal_force, drawbar_pull, torque) are set as the
   chassis' ``<wheel>.*`` inputs, with the scenario's slope and towing force at t, and its
   ``rut_left`` and ``rut_pressure_left`` as its track's ``q*.rut_left`` and
   ``q*.rut_pressure_left``;
3. all FMUs step t -> t + h (each track records the ruts left at t).

The in-process rover (:mod:`wheelterrain.cosim.rover`) couples the same Functions the same
way, so the two agree to rounding (tests/test_rover_fmus.py).

Rover.ssp (``Rover_<scenario>`` system; components ``chassis``, one per wheel, named as the
wheels, and one per track, ``<track>_track``) holds the FMUs, their connections and one
parameter set named after the scenario: the terrain parameters on each wheel, the map's soils,
patch and rut profile on each track, and the chassis' parameters, its input profile (the slope
and towing ramps of the scenario) included, so any engine runs the scenario whole. Engines
that pass every output one step late (libcosim, ecos) see the soil under a wheel two steps
late (chassis -> track -> wheel): at the rover's speed, 0.1 mm of travel.
"""

from __future__ import annotations

import contextlib
import math
import tempfile
import time
import zipfile
from collections.abc import Callable, Mapping
from pathlib import Path
from xml.etree import ElementTree as ET

import numpy as np

from wheelterrain.cosim import rover as rover_system
from wheelterrain.cosim import rover_scenarios, ssp
from wheelterrain.cosim.rover import (
    CHASSIS_RECORD,
    RECORD,
    STEP,
    RoverResult,
    Soil,
    from_records,
)
from wheelterrain.errors import CosimulationError, UsageError
from wheelterrain.files import replacing
from wheelterrain.fmu import functions
from wheelterrain.fmu.instance import Instance
from wheelterrain.fmu.variables import GROUND, QUERY_POINTS
from wheelterrain.model import rover
from wheelterrain.model.ground import RUT_LEFT, RUT_MET
from wheelterrain.parameters import GROUND_TABLE, ROVER_TABLE, TABLE, ParameterSet

CHASSIS = "chassis"
TO_TERRAIN = ("sinkage", "sinkage_rate", "wheel_speed", "carriage_speed")
TO_CHASSIS = rover.WHEEL_FORCES


def track_component(track: str) -> str:
    """The Terrain.fmu instance of a track (rover.TRACKS)."""
    return f"{track}_track"


COMPONENTS = (CHASSIS, *rover.WHEELS, *(track_component(t) for t in rover.TRACKS))


def query_of(wheel: str) -> tuple[str, str]:
    """(track component, query point) that answers for ``wheel``."""
    track = rover.TRACK_OF[wheel]
    return track_component(track), QUERY_POINTS[rover.TRACKS[track].index(wheel)]


def connections(with_map: bool = False) -> list[tuple[str, str, str, str]]:
    """(from component, output, to component, input) of Rover.ssp and of our master: every
    wheel's rut from its track's record; ``with_map``: also its soil from its track's map."""
    out = []
    for w in rover.WHEELS:
        track, q = query_of(w)
        out += [(CHASSIS, f"{w}.{n}", w, n) for n in TO_TERRAIN]
        out += [(w, n, CHASSIS, f"{w}.{n}") for n in TO_CHASSIS]
        out += [(CHASSIS, f"{w}.position", track, f"{q}.position")]
        out += [(w, n, track, f"{q}.{n}") for n in RUT_LEFT]
        out += [(track, f"{q}.{n}", w, n) for n in RUT_MET]
        if with_map:
            out += [(track, f"{q}.{n}", w, n) for n in GROUND]
    return out


PHASE_ROW = next(p for p in TABLE if p.name == "ripple.phase")


def terrain_values(ps: ParameterSet, with_map: bool = False,
                   phase: float = 0.0) -> dict:
    """A wheel's WheelTerrain values: ``ps``'s, its ripple.phase advanced by the wheel's own
    grouser ``phase``, wrapped by whole turns only where the sum leaves the row's range (so
    that within it the FMU adds what the in-process rover adds, to the bit)."""
    total = ps["ripple.phase"] + phase
    if not PHASE_ROW.min <= total <= PHASE_ROW.max:
        total = math.remainder(total, 2 * math.pi)
    return {**{p.name: ps[p.name] for p in TABLE}, "quasi_static": False,
            "soil_from_inputs": with_map, "ripple.phase": total}


def chassis_values(values: Mapping[str, float]) -> dict:
    return {**rover.defaults(), **values}


class RoverFMUs:
    """The five instances, started, and the coupling of the module doc."""

    def __init__(self, fmu_dir: Path, soil: Soil, values: Mapping[str, float],
                 stop: float | None = None) -> None:
        from fmpy import extract

        fmu_dir = Path(fmu_dir)
        self.with_map = bool(soil.patch)
        paths = {name: fmu_dir / f"{name}.fmu" for name in fmu_names()}
        missing = [str(p) for p in paths.values() if not p.is_file()]
        if missing:
            raise FileNotFoundError(f"{', '.join(missing)} not found: build the FMUs first "
                                    "(`wheelterrain build --flavor all`)")
        self._unzip = [extract(str(paths[name])) for name in paths if name != "RoverChassis"]
        self.instances: dict[str, Instance] = {}
        tracks = [track_component(t) for t in rover.TRACKS]
        try:
            # log=True: the FMUs' messages are kept, not printed (standard output may be a
            # JSON document), and a refusal's reason ends up in the result
            self.instances[CHASSIS] = Instance(paths["RoverChassis"], name=CHASSIS, log=True)
            for w in rover.WHEELS:
                self.instances[w] = Instance(paths["WheelTerrain"], self._unzip[0], name=w,
                                             log=True)
            for t in tracks:
                self.instances[t] = Instance(paths["Terrain"], self._unzip[1], name=t,
                                             log=True)
            self.instances[CHASSIS].start(chassis_values(values), stop)
            rover_p = chassis_values(values)
            for w in rover.WHEELS:
                self.instances[w].start(terrain_values(
                    soil.base, self.with_map, rover.grouser_phase(rover_p, w)), stop)
            for t in tracks:
                self.instances[t].start(soil.map_values(), stop)
        except BaseException:
            self.close()
            raise
        ch = self.instances[CHASSIS]
        # per wheel TO_TERRAIN, then every wheel's position (one call); each a lane (a
        # get or a put with its references and buffer made once: Instance.lane)
        self._ch_out = ch.lane(ch.refs([*(f"{w}.{n}" for w in rover.WHEELS for n in TO_TERRAIN),
                                        *(f"{w}.position" for w in rover.WHEELS)]))[0]
        self._ch_in = ch.lane(ch.refs(f"{w}.{n}" for w in rover.WHEELS for n in TO_CHASSIS))[1]
        self._ch_record = ch.lane(ch.refs([*(f"{w}.{n}" for w in rover.WHEELS for n in
                                             ("motor_torque", "wheel_speed")),
                                           *CHASSIS_RECORD]))[0]
        # per wheel, one call: the rut met (and the map's soil), then TO_TERRAIN
        self._ter_in = {w: self.instances[w].lane(self.instances[w].refs(
            [*RUT_MET, *(GROUND if self.with_map else []), *TO_TERRAIN]))[1]
            for w in rover.WHEELS}
        # per track, both query points at once: positions in; the rut met (and the map's
        # soil) out; the rut left in
        self._tracks = {}
        for track in rover.TRACKS:
            g = self.instances[track_component(track)]
            outs = [f"{q}.{n}" for q in QUERY_POINTS
                    for n in (*RUT_MET, *(GROUND if self.with_map else ()))]
            self._tracks[track] = (g.lane(g.refs(f"{q}.position" for q in QUERY_POINTS))[1],
                                   g.lane(g.refs(outs))[0],
                                   g.lane(g.refs(f"{q}.{n}" for q in QUERY_POINTS
                                                 for n in RUT_LEFT))[1])
        self._ter_out = {w: self.instances[w].lane(self.instances[w].refs(
            (*TO_CHASSIS, "slip", "contact_sinkage", *RUT_LEFT)))[0] for w in rover.WHEELS}
        self._steps = [inst.fmu.doStep for inst in self.instances.values()]

    def exchange(self) -> list[float]:
        """One exchange at the current time; returns the record row: per wheel RECORD, then
        CHASSIS_RECORD."""
        x = self._ch_out()
        forces, per, met = [], {}, {}
        n = len(TO_TERRAIN)
        position = dict(zip(rover.WHEELS, x[n * len(rover.WHEELS):], strict=True))
        for track, pair in rover.TRACKS.items():  # the ruts met (and the map's soil), at t
            put_where, get_met, _ = self._tracks[track]
            put_where([position[w] for w in pair])
            values = get_met()
            size = len(values) // len(pair)
            met.update({w: values[j * size:(j + 1) * size] for j, w in enumerate(pair)})
        for k, w in enumerate(rover.WHEELS):
            self._ter_in[w]([*met[w], *x[k * n:(k + 1) * n]])
            y = self._ter_out[w]()
            forces += y[:len(TO_CHASSIS)]
            per[w] = y
        for track, pair in rover.TRACKS.items():  # the ruts left, recorded at the step
            self._tracks[track][2]([v for w in pair for v in per[w][-len(RUT_LEFT):]])
        self._ch_in(forces)
        rec = self._ch_record()
        row = []
        for k, w in enumerate(rover.WHEELS):
            normal, pull, torque, slip, sinkage, rut, pressure = per[w]
            motor, omega = rec[2 * k], rec[2 * k + 1]
            values = {"slip": slip, "sinkage": sinkage, "normal_force": normal,
                      "drawbar_pull": pull, "torque": torque, "motor_torque": motor,
                      "wheel_speed": omega, "rut_left": rut, "rut_pressure_left": pressure}
            row += [values[r] for r in RECORD]
        return row + rec[2 * len(rover.WHEELS):]

    def step(self, t: float, h: float) -> None:
        for step in self._steps:
            step(t, h)

    def errors(self) -> list[str]:
        """What the FMUs logged as discard, error or fatal, by instance."""
        return [f"{name}: {m}" for name, inst in self.instances.items() for m in inst.errors()]

    def close(self) -> None:
        import shutil

        for inst in self.instances.values():
            with contextlib.suppress(Exception):  # the others still close
                inst.close()
        self.instances = {}
        for folder in self._unzip:
            shutil.rmtree(folder, ignore_errors=True)


def simulate(fmu_dir: Path, soil: Soil, values: Mapping[str, float], stop: float,
             step: float = STEP, stop_when: Callable[[dict], bool] | None = None,
             progress: Callable[[float], None] | None = None) -> RoverResult:
    """The rover's FMUs through fmpy, coupled by our master (module doc); the interface of
    :func:`wheelterrain.cosim.rover.simulate` (``progress(t)``: every simulated second)."""
    n = round(stop / step)
    rows = []
    system = RoverFMUs(fmu_dir, soil, values, stop)
    every = max(1, round(1.0 / step))
    left = None
    t0 = time.perf_counter()
    try:
        for k in range(n):
            t = k * step
            row = system.exchange()
            rows.append(row)
            if stop_when is not None and stop_when(rover_system.last_values(row)):
                break
            if progress is not None and (k + 1) % every == 0:
                progress((k + 1) * step)
            try:
                system.step(t, step)
            except Exception as err:  # an FMU refused the step: the run ends, with the reason
                logged = system.errors()
                left = (f"at t = {t + step:.3f} s an FMU refused the step: "
                        + (logged[-1] if logged else str(err)))
                break
    finally:
        wall = time.perf_counter() - t0
        system.close()
    return from_records(np.array(rows).T, step, wall, "wheelterrain master (fmpy)", left)


# what an SSP engine records, per wheel (component, variable) for each of RECORD
_SSP_RECORD = {"slip": "slip", "sinkage": "contact_sinkage", "normal_force": "normal_force",
               "drawbar_pull": "drawbar_pull", "torque": "torque", "rut_left": "rut_left",
               "rut_pressure_left": "rut_pressure_left"}
_CHASSIS_OF_WHEEL = {"motor_torque": "motor_torque", "wheel_speed": "wheel_speed"}


def _ssp_variables() -> list[tuple[str, str]]:
    """(component, variable) in the order of a record row."""
    out = []
    for w in rover.WHEELS:
        for r in RECORD:
            out.append((w, _SSP_RECORD[r]) if r in _SSP_RECORD
                       else (CHASSIS, f"{w}.{_CHASSIS_OF_WHEEL[r]}"))
    return out + [(CHASSIS, n) for n in CHASSIS_RECORD]


def simulate_ssp(engine: str, fmu_dir: Path, scenario: str, soil: Soil,
                 values: Mapping[str, float], stop: float, step: float = STEP,
                 stop_when=None, progress: Callable[[float], None] | None = None
                 ) -> RoverResult:
    """The scenario's Rover.ssp in ``engine`` (one of SSP_ENGINES; fmpy-ssp: fmpy's own SSP
    runner), to ``stop`` or to where a wheel leaves the model's domain. ``stop_when`` is not an
    SSP's: the engine runs on, and its record is cut at the first step ``stop_when`` holds, as
    our masters stop there (a descent's slide). ``progress(t)``: every simulated second where
    the engine steps in chunks (libcosim, ecos), else at the end. Refused before the run where
    the engine cannot run the scenario (:func:`refusal`)."""
    reason = refusal(engine, scenario, soil)
    if reason is not None:
        raise UsageError(reason)
    # the record, then each axle's speed (the chassis' <wheel>.carriage_speed): the slips
    names = _ssp_variables() + [(CHASSIS, f"{w}.carriage_speed") for w in rover.WHEELS]
    dotted = tuple(f"{c}.{v}" for c, v in names)  # "component.variable", as engines name them
    with tempfile.TemporaryDirectory(prefix="wheelterrain_rover_") as tmp:
        path = write_ssp(Path(tmp) / "Rover.ssp", fmu_dir, scenario, soil, values, stop, step)
        t0 = time.perf_counter()
        with ssp.engine_output_to_stderr():  # their log lines: not on standard output
            if engine == "libcosim":
                out = ssp.simulate_with_libcosim(path, stop, step, dotted, progress)
                wall = time.perf_counter() - t0
                data = np.array([out[n] for n in dotted])
            elif engine == "fmpy-ssp":
                from fmpy.fmi1 import FMICallException

                try:
                    out = ssp.simulate_with_fmpy(path, stop, step)
                except FMICallException as err:
                    raise CosimulationError(
                        f"fmpy's SSP runner ended with {err}: it stops at the first step an "
                        "FMU refuses (a wheel leaving the contact model's domain, as at a "
                        "stall) and returns nothing of the run; ecos, libcosim and our master "
                        "run on to there and keep the records") from None
                wall = time.perf_counter() - t0
                steps = round(stop / step)
                data = np.array([out[n][:steps] for n in dotted])
            elif engine == "omsimulator":
                executable = ssp.omsimulator()
                if executable is None:
                    raise CosimulationError(ssp.engine_missing(engine))
                try:
                    out = ssp.simulate_with_omsimulator(path, stop, step, dotted, executable)
                except RuntimeError as err:
                    raise CosimulationError(str(err)) from None
                wall = time.perf_counter() - t0
                steps = round(stop / step)  # its rows: t = 0, step, ..., as our records
                data = np.array([out[n][:steps] for n in dotted])
            elif engine == "ecos":
                csv_path = Path(tmp) / "ecos.csv"
                ids = tuple(f"{c}::{v}" for c, v in names)

                def inside(get) -> bool:  # ecos goes on past a refusal: end where ours end
                    now = np.array([[get(i)] for i in ids])
                    return rover_system.outside(_chassis_slips(now, values)) is None

                ssp.simulate_with_ecos(path, scenario, stop, step, csv_path, ids, inside,
                                       progress=progress)
                wall = time.perf_counter() - t0
                data = ssp.read_csv_columns(csv_path, ids)
            else:
                raise ValueError(f"unknown engine {engine!r}")
    data = _chassis_slips(data, values)
    stopped = False
    if stop_when is not None:
        for k in range(data.shape[1]):
            if stop_when(rover_system.last_values(data[:, k])):
                data, stopped = data[:, :k + 1], True
                break
    # the records end where the model's domain ends, as in our masters (those engines go on
    # past a refused step, with the refusing FMU's outputs frozen: not results)
    problem = rover_system.outside(data)
    left = None
    if problem is not None:
        k, why = problem
        data, left = data[:, :k], f"at t = {k * step:.3f} s {why}"
    elif not stopped and data.shape[1] < round(stop / step):  # it stopped at a refused step
        left = (f"at t = {data.shape[1] * step:.3f} s an FMU refused the step ({engine} "
                "stops there)")
    return from_records(data, step, wall, engine, left)


def refusal(engine: str, scenario: str, soil: Soil) -> str | None:
    """Why ``engine`` cannot run ``scenario`` on ``soil`` (said before the run), or None."""
    if engine != "fmpy-ssp":
        return None
    if soil.patch:
        return ("fmpy's SSP runner cannot run a soil map (soft-patch): it sets every connected "
                "input to 0 before the first step, and 0 is outside the declared ranges of the "
                "wheels' ground.* inputs (soil.k_phi >= 10, ...); ecos, libcosim, OMSimulator "
                "and our master (--engine fmus) run it")
    if scenario in rover_scenarios.LIMIT_SCENARIOS:
        # refused before the run: fmpy's runner would simulate it whole (minutes) first
        return (f"fmpy's SSP runner cannot run {scenario}: the scenario ends where a wheel "
                "leaves the contact model's domain (the rover's stall or slide), and fmpy.ssp "
                "stops with an exception at the first step an FMU refuses, returning nothing "
                "of the run; ecos, libcosim, OMSimulator and our master (--engine fmus) keep "
                "the record")
    return None


def runner(engine: str, fmu_dir: Path, scenario: str) -> Callable | None:
    """What :func:`rover_scenarios.run_scenario` takes as its ``engine`` for ``engine``:
    "in-process" None (its own), "fmus" our master on the FMUs in ``fmu_dir``, an SSP engine
    the scenario's Rover.ssp in it."""
    if engine == "in-process":
        return None
    if engine == "fmus":
        return lambda soil, values, stop, step, stop_when, progress=None: simulate(
            fmu_dir, soil, values, stop, step, stop_when, progress)
    return lambda soil, values, stop, step, stop_when, progress=None: simulate_ssp(
        engine, fmu_dir, scenario, soil, values, stop, step, stop_when=stop_when,
        progress=progress)


def _chassis_slips(data: np.ndarray, values: Mapping[str, float]) -> np.ndarray:
    """The record rows of ``data`` (the rows that follow them are the four axles' speeds) with
    each wheel's slip from the chassis' own speeds, the wheel's against its axle's (a terrain
    that refused a step keeps its last outputs, its slip among them, in an engine that goes on
    past a refusal)."""
    n_axles = len(rover.WHEELS)
    data, axles = data[:-n_axles], data[-n_axles:]
    radius = chassis_values(values)["rover.slip_radius"]
    wheels, _ = rover_system.named_record(data)
    for k, w in enumerate(rover.WHEELS):
        unified, _ = functions.slips(wheels[w]["wheel_speed"], axles[k], radius)
        data[k * len(RECORD) + RECORD.index("slip")] = np.asarray(unified).ravel()
    return data


# --- Rover.ssp --------------------------------------------------------------------------------

def system_name(scenario: str) -> str:
    return "Rover_" + scenario.replace("-", "_")


def fmu_names() -> tuple[str, ...]:
    """The FMUs a Rover.ssp holds (the tracks' Terrain.fmu in every scenario: the ruts)."""
    return ("RoverChassis", "WheelTerrain", "Terrain")


def system_description(scenario: str, soil: Soil, values: Mapping[str, float],
                       stop: float, step: float = STEP) -> bytes:
    q = ssp.qname
    for prefix, uri in ssp.NS.items():
        ET.register_namespace(prefix, uri)
    root = ET.Element(q("ssd", "SystemStructureDescription"), version="1.0",
                      name=system_name(scenario))
    system = ET.SubElement(root, q("ssd", "System"), name=system_name(scenario),
                           description=f"The Rashid rover on four wheels, scenario {scenario} "
                           "(its slope and towing ramps: the chassis' input profile)")
    elements = ET.SubElement(system, q("ssd", "Elements"))
    chassis = {p.name: ssp.binding(p, chassis_values(values)[p.name]) for p in ROVER_TABLE}
    ins = [f"{w}.{n}" for w in rover.WHEELS for n in TO_CHASSIS]
    with_map = bool(soil.patch)
    outs = [f"{w}.{n}" for w in rover.WHEELS for n in (*TO_TERRAIN, "position")]
    # what the record reads (unconnected outputs; an engine records its connectors)
    recorded = {c: [v for comp, v in _ssp_variables() if comp == c] for c in COMPONENTS}
    outs += [v for v in recorded[CHASSIS] if v not in outs]
    ssp.component(elements, CHASSIS, "resources/RoverChassis.fmu", ins, outs, chassis,
                   scenario)
    wheel = {p.name: ssp.binding(p, soil.base[p.name]) for p in TABLE}
    if with_map:
        wheel["soil_from_inputs"] = ("Boolean", "true")
    ground_rows = {p.name: p for p in (*TABLE, *GROUND_TABLE)}
    terrain_map = {name: ssp.binding(ground_rows[name], value)
                   for name, value in soil.map_values().items()}
    rover_p = chassis_values(values)
    for w in rover.WHEELS:
        own = dict(wheel)  # the wheel's grouser phase: added to its ripple.phase
        own["ripple.phase"] = ssp.binding(PHASE_ROW, terrain_values(
            soil.base, with_map, rover.grouser_phase(rover_p, w))["ripple.phase"])
        ssp.component(elements, w, "resources/WheelTerrain.fmu",
                       (*TO_TERRAIN, *RUT_MET, *(GROUND if with_map else ())),
                       (*TO_CHASSIS, *(v for v in recorded[w] if v not in TO_CHASSIS)), own,
                       scenario)
    for track in rover.TRACKS:
        ins = [f"{q}.{n}" for q in QUERY_POINTS for n in ("position", *RUT_LEFT)]
        outs = [f"{q}.{n}" for q in QUERY_POINTS
                for n in (*RUT_MET, *(GROUND if with_map else ()))]
        ssp.component(elements, track_component(track), "resources/Terrain.fmu", ins, outs,
                       terrain_map, scenario)
    conns = ET.SubElement(system, q("ssd", "Connections"))
    for a, av, b, bv in connections(with_map):
        ET.SubElement(conns, q("ssd", "Connection"), startElement=a, startConnector=av,
                      endElement=b, endConnector=bv)
    ssp.master_annotation(system, step)
    ssp.default_experiment(root, stop, step)
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def write_ssp(path: Path, fmu_dir: Path, scenario: str, soil: Soil,
              values: Mapping[str, float], stop: float, step: float = STEP) -> Path:
    """Rover.ssp for ``scenario`` (module doc), written atomically."""
    with replacing(Path(path)) as partial, zipfile.ZipFile(partial, "w",
                                                            zipfile.ZIP_DEFLATED) as z:
        z.writestr("SystemStructure.ssd", system_description(scenario, soil, values, stop,
                                                             step))
        for name in fmu_names():
            z.write(Path(fmu_dir) / f"{name}.fmu", f"resources/{name}.fmu")
    return path
