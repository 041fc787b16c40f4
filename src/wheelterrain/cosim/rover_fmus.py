"""The rover as FMUs: RoverChassis.fmu and four WheelTerrain.fmu, our master and Rover.ssp.

Coupling per communication step h (fixed), Gauss-Seidel on the algebraic terrains, as the
single-wheel master couples the rig (:mod:`wheelterrain.cosim.master`):

1. the chassis' per-wheel outputs at t (``<wheel>.sinkage``, ``.sinkage_rate``,
   ``.wheel_speed``, ``.carriage_speed``) are set as each wheel's WheelTerrain inputs;
2. each WheelTerrain's forces at t (normal_force, drawbar_pull, torque) are set as the
   chassis' ``<wheel>.*`` inputs, with the scenario's slope and towing force at t;
3. all five FMUs step t -> t + h.

The in-process rover (:mod:`wheelterrain.cosim.rover`) couples the same Functions the same
way, so the two agree to rounding (tests/test_rover_fmus.py).

Rover.ssp (``Rover_<scenario>`` system; components ``chassis`` and one per wheel, named as the
wheels) holds the five FMUs, the 24 connections and one parameter set named after the
scenario: the terrain parameters on each wheel, the chassis' parameters, and the start values
of the chassis' inputs ``slope`` and ``towing_force`` (an SSP carries no time-varying input:
engines other than ours run a scenario's inputs as constants, its initial ones).
"""

from __future__ import annotations

import contextlib
import os
import tempfile
import time
import zipfile
from collections.abc import Callable, Mapping
from pathlib import Path
from xml.etree import ElementTree as ET

import numpy as np

from wheelterrain.cosim import ssp
from wheelterrain.cosim.rover import CHASSIS_RECORD, RECORD, STEP, RoverResult, Soil
from wheelterrain.errors import CosimulationError
from wheelterrain.fmu.instance import Instance
from wheelterrain.model import rover
from wheelterrain.parameters import ROVER_TABLE, TABLE, ParameterSet

CHASSIS = "chassis"
COMPONENTS = (CHASSIS, *rover.WHEELS)
TO_TERRAIN = ("sinkage", "sinkage_rate", "wheel_speed", "carriage_speed")
TO_CHASSIS = rover.WHEEL_FORCES


def connections() -> list[tuple[str, str, str, str]]:
    """(from component, output, to component, input) of Rover.ssp and of our master."""
    out = []
    for w in rover.WHEELS:
        out += [(CHASSIS, f"{w}.{n}", w, n) for n in TO_TERRAIN]
        out += [(w, n, CHASSIS, f"{w}.{n}") for n in TO_CHASSIS]
    return out


def terrain_values(ps: ParameterSet) -> dict:
    return {**{p.name: ps[p.name] for p in TABLE}, "quasi_static": False}


def chassis_values(values: Mapping[str, float]) -> dict:
    return {**rover.defaults(), **values}


class RoverFMUs:
    """The five instances, started, and the coupling of the module doc."""

    def __init__(self, fmu_dir: Path, terrain: ParameterSet, values: Mapping[str, float],
                 slope: float = 0.0, towing: float = 0.0, stop: float | None = None) -> None:
        from fmpy import extract

        fmu_dir = Path(fmu_dir)
        paths = {"RoverChassis": fmu_dir / "RoverChassis.fmu",
                 "WheelTerrain": fmu_dir / "WheelTerrain.fmu"}
        missing = [str(p) for p in paths.values() if not p.is_file()]
        if missing:
            raise FileNotFoundError(f"{', '.join(missing)} not found: build the FMUs first "
                                    "(`wheelterrain build --flavor all`)")
        self._unzip = extract(str(paths["WheelTerrain"]))
        self.instances: dict[str, Instance] = {}
        try:
            self.instances[CHASSIS] = Instance(paths["RoverChassis"], name=CHASSIS)
            for w in rover.WHEELS:
                self.instances[w] = Instance(paths["WheelTerrain"], self._unzip, name=w)
            self.instances[CHASSIS].start({**chassis_values(values), "slope": slope,
                                           "towing_force": towing}, stop)
            for w in rover.WHEELS:
                self.instances[w].start(terrain_values(terrain), stop)
        except BaseException:
            self.close()
            raise
        ch = self.instances[CHASSIS]
        self._ch_out = ch.refs(f"{w}.{n}" for w in rover.WHEELS for n in TO_TERRAIN)
        self._ch_in = ch.refs(f"{w}.{n}" for w in rover.WHEELS for n in TO_CHASSIS)
        self._ch_inputs = ch.refs(("slope", "towing_force"))
        self._ch_record = ch.refs([*(f"{w}.{n}" for w in rover.WHEELS for n in
                                     ("motor_torque", "wheel_speed")),
                                   "position", "speed", "heave", "pitch"])
        self._ter_in = {w: self.instances[w].refs(TO_TERRAIN) for w in rover.WHEELS}
        self._ter_out = {w: self.instances[w].refs((*TO_CHASSIS, "slip", "contact_sinkage"))
                         for w in rover.WHEELS}

    def exchange(self, slope: float, towing: float) -> list[float]:
        """One exchange at the current time; returns the record row: per wheel RECORD, then
        position, speed, heave, pitch."""
        ch = self.instances[CHASSIS].fmu
        x = ch.getReal(self._ch_out)
        forces, per = [], {}
        n = len(TO_TERRAIN)
        for k, w in enumerate(rover.WHEELS):
            t = self.instances[w].fmu
            t.setReal(self._ter_in[w], x[k * n:(k + 1) * n])
            y = t.getReal(self._ter_out[w])
            forces += y[:len(TO_CHASSIS)]
            per[w] = y
        ch.setReal(self._ch_in, forces)
        ch.setReal(self._ch_inputs, [slope, towing])
        rec = ch.getReal(self._ch_record)
        row = []
        for k, w in enumerate(rover.WHEELS):
            normal, pull, torque, slip, sinkage = per[w]
            motor, omega = rec[2 * k], rec[2 * k + 1]
            values = {"slip": slip, "sinkage": sinkage, "normal_force": normal,
                      "drawbar_pull": pull, "torque": torque, "motor_torque": motor,
                      "wheel_speed": omega}
            row += [values[r] for r in RECORD]
        return row + rec[2 * len(rover.WHEELS):]

    def step(self, t: float, h: float) -> None:
        for inst in self.instances.values():
            inst.fmu.doStep(t, h)

    def close(self) -> None:
        import shutil

        for inst in self.instances.values():
            with contextlib.suppress(Exception):  # the others still close
                inst.close()
        self.instances = {}
        shutil.rmtree(self._unzip, ignore_errors=True)


def simulate(fmu_dir: Path, soil: Soil, values: Mapping[str, float], stop: float,
             slope: Callable[[float], float] = lambda t: 0.0,
             towing: Callable[[float], float] = lambda t: 0.0,
             step: float = STEP, stop_when: Callable[[dict], bool] | None = None
             ) -> RoverResult:
    """The rover's five FMUs through fmpy, coupled by our master (module doc); the interface
    of :func:`wheelterrain.cosim.rover.simulate`. A soil that changes along the path needs
    WheelTerrain parameters that change during the run, which the FMUs do not take: refused."""
    if soil.patch:
        raise CosimulationError("a soil that changes along the path is not in the FMUs' "
                                "parameter contract (WheelTerrain's soil values are fixed "
                                "parameters): run this scenario in process")
    n = round(stop / step)
    rows = []
    inputs = {"slope": [], "towing_force": []}
    system = RoverFMUs(fmu_dir, soil.base, values, slope(0.0), towing(0.0), stop)
    left = None
    t0 = time.perf_counter()
    try:
        for k in range(n):
            t = k * step
            a, f = slope(t), towing(t)
            row = system.exchange(a, f)
            rows.append(row)
            inputs["slope"].append(a)
            inputs["towing_force"].append(f)
            if stop_when is not None and stop_when(_named_row(row)):
                break
            try:
                system.step(t, step)
            except Exception as err:
                left = f"at t = {t + step:.3f} s an FMU refused the step ({err})"
                break
    finally:
        wall = time.perf_counter() - t0
        system.close()
    return _result(np.array(rows).T, step, wall, "wheelterrain master (fmpy)", inputs, left)


def _named_row(row: list[float]) -> dict:
    out = {f"{w}.{r}": row[k * len(RECORD) + j] for k, w in enumerate(rover.WHEELS)
           for j, r in enumerate(RECORD)}
    base = len(RECORD) * len(rover.WHEELS)
    out.update({n: row[base + j] for j, n in enumerate(CHASSIS_RECORD)})
    return out


def _result(data: np.ndarray, step: float, wall: float, engine: str, inputs: dict,
            left: str | None) -> RoverResult:
    wheels = {w: {r: data[k * len(RECORD) + j] for j, r in enumerate(RECORD)}
              for k, w in enumerate(rover.WHEELS)}
    base = len(RECORD) * len(rover.WHEELS)
    chassis = {name: data[base + j] for j, name in enumerate(CHASSIS_RECORD)}
    return RoverResult(np.arange(data.shape[1]) * step, wheels, chassis, wall, engine,
                       {k: np.array(v) for k, v in inputs.items()}, left)


# what an SSP engine records, per wheel (component, variable) for each of RECORD
_SSP_RECORD = {"slip": "slip", "sinkage": "contact_sinkage", "normal_force": "normal_force",
               "drawbar_pull": "drawbar_pull", "torque": "torque"}
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
                 values: Mapping[str, float], stop: float,
                 slope: Callable[[float], float], towing: Callable[[float], float],
                 step: float = STEP, stop_when=None) -> RoverResult:
    """The scenario's Rover.ssp in ``engine`` ("ecos" or "libcosim"), which run an SSP's
    inputs as constants: scenarios whose inputs change are refused with the reason."""
    if soil.patch or slope(stop) != slope(0.0) or towing(stop) != towing(0.0):
        raise CosimulationError(
            f"{engine} runs Rover.ssp, whose inputs (slope, towing force, soil) are constants; "
            f"scenario {scenario!r} changes them during the run: run it with our masters "
            "(--engine in-process or fmus)")
    names = _ssp_variables()
    with tempfile.TemporaryDirectory(prefix="wheelterrain_rover_") as tmp:
        path = write_ssp(Path(tmp) / "Rover.ssp", fmu_dir, scenario, soil.base, values,
                         slope(0.0), towing(0.0), stop)
        t0 = time.perf_counter()
        if engine == "libcosim":
            out = ssp.simulate_with_libcosim(path, stop, step,
                                             tuple(f"{c}.{v}" for c, v in names))
            wall = time.perf_counter() - t0
            data = np.array([out[f"{c}.{v}"] for c, v in names])
        elif engine == "ecos":
            csv_path = Path(tmp) / "ecos.csv"
            ids = tuple(f"{c}::{v}" for c, v in names)
            ssp.simulate_with_ecos(path, scenario, stop, step, csv_path, ids)
            wall = time.perf_counter() - t0
            data = _read_ecos(csv_path, ids)
        else:
            raise ValueError(f"unknown engine {engine!r}")
    n = data.shape[1]
    inputs = {"slope": [slope(0.0)] * n, "towing_force": [towing(0.0)] * n}
    return _result(data, step, wall, engine, inputs, None)


def _read_ecos(path: Path, ids: tuple[str, ...]) -> np.ndarray:
    import csv

    with path.open(newline="") as f:
        rows = list(csv.reader(f))
    header = [h.strip().split("[")[0] for h in rows[0]]
    table = np.array(rows[1:], dtype=float)
    return np.array([table[:, header.index(i)] for i in ids])


# --- Rover.ssp --------------------------------------------------------------------------------

def system_name(scenario: str) -> str:
    return "Rover_" + scenario.replace("-", "_")


def system_description(scenario: str, terrain: ParameterSet, values: Mapping[str, float],
                       slope: float, towing: float, stop: float) -> bytes:
    q = ssp._q
    for prefix, uri in ssp.NS.items():
        ET.register_namespace(prefix, uri)
    root = ET.Element(q("ssd", "SystemStructureDescription"), version="1.0",
                      name=system_name(scenario))
    system = ET.SubElement(root, q("ssd", "System"), name=system_name(scenario),
                           description=f"The Rashid rover on four wheels, scenario {scenario}: "
                           f"slope {slope:g} rad, towing force {towing:g} N")
    elements = ET.SubElement(system, q("ssd", "Elements"))
    chassis = {p.name: ssp._binding(p, chassis_values(values)[p.name]) for p in ROVER_TABLE}
    chassis.update({"slope": ("Real", float(slope)), "towing_force": ("Real", float(towing))})
    ins = [f"{w}.{n}" for w in rover.WHEELS for n in TO_CHASSIS]
    outs = [f"{w}.{n}" for w in rover.WHEELS for n in TO_TERRAIN]
    ssp._component(elements, CHASSIS, "resources/RoverChassis.fmu", ins, outs, chassis,
                   scenario)
    soil = {p.name: ssp._binding(p, terrain[p.name]) for p in TABLE}
    for w in rover.WHEELS:
        ssp._component(elements, w, "resources/WheelTerrain.fmu", TO_TERRAIN, TO_CHASSIS,
                       soil, scenario)
    conns = ET.SubElement(system, q("ssd", "Connections"))
    for a, av, b, bv in connections():
        ET.SubElement(conns, q("ssd", "Connection"), startElement=a, startConnector=av,
                      endElement=b, endConnector=bv)
    ET.SubElement(root, q("ssd", "DefaultExperiment"), startTime="0.0", stopTime=repr(stop))
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def write_ssp(path: Path, fmu_dir: Path, scenario: str, terrain: ParameterSet,
              values: Mapping[str, float], slope: float, towing: float, stop: float) -> Path:
    """Rover.ssp for ``scenario`` (module doc), written atomically."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.NamedTemporaryFile(dir=path.parent, prefix=f".{path.name}.",
                                     delete=False) as tmp:
        partial = Path(tmp.name)
    try:
        with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as z:
            z.writestr("SystemStructure.ssd", system_description(
                scenario, terrain, values, slope, towing, stop))
            for name in ("RoverChassis", "WheelTerrain"):
                z.write(Path(fmu_dir) / f"{name}.fmu", f"resources/{name}.fmu")
        os.replace(partial, path)
    finally:
        partial.unlink(missing_ok=True)
    return path
