"""An SSP 1.0 file per C1-C4 case: the two FMUs, their connections and every parameter value,
so the same system runs in any SSP master (fmpy.ssp here; ecos for the native flavour).

Layout of ``<case>.ssp`` (a zip): SystemStructure.ssd and resources/{WheelTerrain,
SingleWheelRig}.fmu. Parameters are inline ssv:ParameterSets in each component's
ParameterBindings, all named after the case (ecos applies a named set at init:
``EcosSimulation.init(0, "C2")``; fmpy.ssp is given them by :func:`simulate_with_fmpy`).
``quasi_static`` is left at its default (false): the SSP runs the dynamic co-simulation.
"""

from __future__ import annotations

import os
import zipfile
from pathlib import Path
from xml.etree import ElementTree as ET

import numpy as np

from wheelterrain.cosim.master import rig_parameters
from wheelterrain.fmu import variables
from wheelterrain.model import rig
from wheelterrain.parameters import TABLE, ParameterSet

NS = {"ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
      "ssc": "http://ssp-standard.org/SSP1/SystemStructureCommon",
      "ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues"}
COUPLED_STATES, FORCES = variables.COUPLED_STATES, variables.COUPLED_FORCES  # the connections
RIG_OUTPUTS = variables.RIG_OUTPUTS  # every output of each FMU is a connector
TERRAIN_OUTPUTS = tuple(v.name for v in variables.TERRAIN_IO if v.causality == "output")


def _q(prefix: str, tag: str) -> str:
    return f"{{{NS[prefix]}}}{tag}"


def _component(elements, name: str, source: str, inputs, outputs, params: dict,
               set_name: str) -> None:
    comp = ET.SubElement(elements, _q("ssd", "Component"), name=name,
                         type="application/x-fmu-sharedlibrary", source=source)
    connectors = ET.SubElement(comp, _q("ssd", "Connectors"))
    for kind, names in (("input", inputs), ("output", outputs)):
        for n in names:
            c = ET.SubElement(connectors, _q("ssd", "Connector"), name=n, kind=kind)
            ET.SubElement(c, _q("ssc", "Real"))
    bindings = ET.SubElement(comp, _q("ssd", "ParameterBindings"))
    binding = ET.SubElement(bindings, _q("ssd", "ParameterBinding"))
    values = ET.SubElement(binding, _q("ssd", "ParameterValues"))
    pset = ET.SubElement(values, _q("ssv", "ParameterSet"), version="1.0", name=set_name)
    plist = ET.SubElement(pset, _q("ssv", "Parameters"))
    for key, (kind, value) in params.items():
        p = ET.SubElement(plist, _q("ssv", "Parameter"), name=key)
        ET.SubElement(p, _q("ssv", kind), value=repr(value) if kind == "Real" else str(value))


# The components' names in the SSP: identifiers valid in every engine (letters, digits and
# underscores), and none equal to the first part of a parameter's structured name (a component
# "rig" with parameters "rig.load" is read by OMSimulator's importer as component "rig",
# variable "load").
RIG_COMPONENT, TERRAIN_COMPONENT = "test_rig", "terrain"


def system_name(case: str) -> str:
    """The system's name for ``case``: an identifier (OMSimulator aborts on
    'SingleWheelRig-C2')."""
    return f"SingleWheelRig_{case}"


def system_description(case: str, ps: ParameterSet, slip_paper: float, load: float,
                       rim_speed: float, stop: float, step: float) -> bytes:
    for prefix, uri in NS.items():
        ET.register_namespace(prefix, uri)
    root = ET.Element(_q("ssd", "SystemStructureDescription"), version="1.0",
                      name=system_name(case))
    system = ET.SubElement(root, _q("ssd", "System"), name=case,
                           description=f"Rashid wheel on the single-wheel rig, case {case}: "
                           f"slip s = {slip_paper:g} (paper's definition), load {load:g} N")
    elements = ET.SubElement(system, _q("ssd", "Elements"))
    terrain_params = {p.name: _binding(p, ps[p.name]) for p in TABLE}
    rig_values = rig_parameters(ps, slip_paper, load, rim_speed)
    rig_params = {p.name: _binding(p, rig_values[p.name]) for p in rig.RIG_TABLE}
    _component(elements, RIG_COMPONENT, "resources/SingleWheelRig.fmu", FORCES, RIG_OUTPUTS,
               rig_params, case)
    _component(elements, TERRAIN_COMPONENT, "resources/WheelTerrain.fmu", COUPLED_STATES,
               TERRAIN_OUTPUTS, terrain_params, case)
    connections = ET.SubElement(system, _q("ssd", "Connections"))
    for n in COUPLED_STATES:
        ET.SubElement(connections, _q("ssd", "Connection"), startElement=RIG_COMPONENT,
                      startConnector=n, endElement=TERRAIN_COMPONENT, endConnector=n)
    for n in FORCES:
        ET.SubElement(connections, _q("ssd", "Connection"), startElement=TERRAIN_COMPONENT,
                      startConnector=n, endElement=RIG_COMPONENT, endConnector=n)
    ET.SubElement(root, _q("ssd", "DefaultExperiment"), startTime="0.0", stopTime=repr(stop))
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def _binding(p, value) -> tuple[str, int | float]:
    """(SSV type, value) of a parameter binding: switches and counts are Integer."""
    if p.kind in ("integer", "enum"):
        return "Integer", round(value)
    return "Real", float(value)


def write(path: Path, fmu_dir: Path, case: str, ps: ParameterSet, slip_paper: float,
          load: float, rim_speed: float, stop: float, step: float) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(f".{path.name}.part")
    with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("SystemStructure.ssd",
                   system_description(case, ps, slip_paper, load, rim_speed, stop, step))
        for name in ("SingleWheelRig", "WheelTerrain"):
            z.write(Path(fmu_dir) / f"{name}.fmu", f"resources/{name}.fmu")
    os.replace(partial, path)
    return path


def simulate_with_fmpy(path: Path, stop: float, step: float):
    """Run an SSP written by :func:`write` with fmpy.ssp. fmpy reads the inline parameter
    bindings but does not apply them itself; they are passed on as its parameter_set."""
    from fmpy.ssp.simulation import simulate_ssp
    from fmpy.ssp.ssd import Parameter, ParameterSet, read_ssd

    ssd = read_ssd(str(path))
    merged = ParameterSet(name="bindings")
    for comp in ssd.system.elements:
        for binding in comp.parameterBindings:
            for pset in binding.parameterValues:
                for p in pset.parameters:
                    merged.parameters.append(Parameter(name=f"{comp.name}.{p.name}",
                                                       type=p.type, value=p.value))
    return simulate_ssp(str(path), stop_time=stop, step_size=step, parameter_set=merged)


def simulate_with_ecos(path: Path, case: str, stop: float, step: float, csv: Path,
                       variables: tuple[str, ...]) -> None:
    """Run an SSP written by :func:`write` in ecos (ecospy), applying the case's parameter set,
    and write ``variables`` ("component::name") at every step to ``csv``."""
    from ecospy import EcosSimulation

    sim = EcosSimulation(step_size=step, ssp_path=str(path))
    try:
        sim.add_csv_writer(str(csv), identifiers=list(variables), decimation_factor=1)
        if not sim.init(0.0, case):
            raise RuntimeError(f"ecos could not initialise {path} with parameter set {case}")
        sim.step_until(stop)
        sim.terminate()
    finally:
        sim.free()


def simulate_with_libcosim(path: Path, stop: float, step: float,
                           variables: tuple[str, ...]) -> dict[str, np.ndarray]:
    """Run an SSP written by :func:`write` in libcosim (PyPI libcosimpy, the Open Simulation
    Platform's engine; fixed step, its SSP reader applies the file's parameter set) and return
    ``time`` and ``variables`` ("component.name", Real) at every step."""
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    log_output_level(CosimLogLevel.ERROR)  # its info and debug lines would flood the output
    nanoseconds = round(step * 1e9)  # libcosim's time unit
    execution = CosimExecution.from_ssp_file(str(path), step_size=nanoseconds)
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    wanted = []
    for name in variables:
        component, variable = name.split(".", 1)
        index = execution.slave_index_from_instance_name(component)
        refs = {v.name.decode(): v.reference for v in execution.slave_variables(index)}
        wanted.append((index, refs[variable]))
    steps = round(stop / step)
    out = np.empty((steps, len(variables)))
    for k in range(steps):
        execution.step()
        for j, (index, ref) in enumerate(wanted):
            out[k, j] = observer.last_real_values(index, [ref])[0]
    return {"time": step * np.arange(1, steps + 1),
            **{name: out[:, j] for j, name in enumerate(variables)}}
