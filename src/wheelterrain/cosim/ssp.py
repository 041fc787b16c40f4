"""An SSP 1.0 file per C1-C4 case: the two FMUs, their connections and every parameter value,
so the same system runs in any SSP master (fmpy.ssp here; ecos for the native flavour).

Layout of ``<case>.ssp`` (a zip): SystemStructure.ssd and resources/{WheelTerrain,
SingleWheelRig}.fmu. Parameters are inline ssv:ParameterSets in each component's
ParameterBindings, all named after the case (ecos applies a named set at init:
``EcosSimulation.init(0, "C2")``; fmpy.ssp is given them by :func:`simulate_with_fmpy`).
``quasi_static`` is left at its default (false): the SSP runs the dynamic co-simulation.
"""

from __future__ import annotations

import contextlib
import csv
import importlib.util
import os
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import zipfile
from collections.abc import Callable
from pathlib import Path
from xml.etree import ElementTree as ET

import numpy as np

from wheelterrain.cosim import SSP_ENGINES
from wheelterrain.cosim.master import rig_parameters
from wheelterrain.files import replacing
from wheelterrain.fmu import variables
from wheelterrain.model import rig
from wheelterrain.parameters import TABLE, ParameterSet

NS = {"ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
      "ssc": "http://ssp-standard.org/SSP1/SystemStructureCommon",
      "ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues",
      "oms": "https://raw.githubusercontent.com/OpenModelica/OMSimulator/master/schema/oms.xsd",
      "osp": "http://opensimulationplatform.com/SSP/OSPAnnotations"}
COUPLED_STATES, FORCES = variables.COUPLED_STATES, variables.COUPLED_FORCES  # the connections
RIG_OUTPUTS = variables.RIG_OUTPUTS  # every output of each FMU is a connector
TERRAIN_OUTPUTS = tuple(v.name for v in variables.TERRAIN_IO if v.causality == "output")


def qname(prefix: str, tag: str) -> str:
    return f"{{{NS[prefix]}}}{tag}"


def component(elements, name: str, source: str, inputs, outputs, params: dict,
               set_name: str) -> None:
    """An ssd:Component of ``elements``: the FMU at ``source`` with its connectors and one
    parameter set ``set_name`` binding ``params`` (name -> (SSV type, value), :func:`binding`)."""
    comp = ET.SubElement(elements, qname("ssd", "Component"), name=name,
                         type="application/x-fmu-sharedlibrary", source=source)
    connectors = ET.SubElement(comp, qname("ssd", "Connectors"))
    for kind, names in (("input", inputs), ("output", outputs)):
        for n in names:
            c = ET.SubElement(connectors, qname("ssd", "Connector"), name=n, kind=kind)
            ET.SubElement(c, qname("ssc", "Real"))
    bindings = ET.SubElement(comp, qname("ssd", "ParameterBindings"))
    bound = ET.SubElement(bindings, qname("ssd", "ParameterBinding"))
    values = ET.SubElement(bound, qname("ssd", "ParameterValues"))
    pset = ET.SubElement(values, qname("ssv", "ParameterSet"), version="1.0", name=set_name)
    plist = ET.SubElement(pset, qname("ssv", "Parameters"))
    for key, (kind, value) in params.items():
        p = ET.SubElement(plist, qname("ssv", "Parameter"), name=key)
        ET.SubElement(p, qname("ssv", kind), value=repr(value) if kind == "Real" else str(value))


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
    root = ET.Element(qname("ssd", "SystemStructureDescription"), version="1.0",
                      name=system_name(case))
    system = ET.SubElement(root, qname("ssd", "System"), name=case,
                           description=f"Rashid wheel on the single-wheel rig, case {case}: "
                           f"slip s = {slip_paper:g} (paper's definition), load {load:g} N")
    elements = ET.SubElement(system, qname("ssd", "Elements"))
    terrain_params = {p.name: binding(p, ps[p.name]) for p in TABLE}
    rig_values = rig_parameters(ps, slip_paper, load, rim_speed)
    rig_params = {p.name: binding(p, rig_values[p.name]) for p in rig.RIG_TABLE}
    component(elements, RIG_COMPONENT, "resources/SingleWheelRig.fmu", FORCES, RIG_OUTPUTS,
               rig_params, case)
    component(elements, TERRAIN_COMPONENT, "resources/WheelTerrain.fmu", COUPLED_STATES,
               TERRAIN_OUTPUTS, terrain_params, case)
    connections = ET.SubElement(system, qname("ssd", "Connections"))
    for n in COUPLED_STATES:
        ET.SubElement(connections, qname("ssd", "Connection"), startElement=RIG_COMPONENT,
                      startConnector=n, endElement=TERRAIN_COMPONENT, endConnector=n)
    for n in FORCES:
        ET.SubElement(connections, qname("ssd", "Connection"), startElement=TERRAIN_COMPONENT,
                      startConnector=n, endElement=RIG_COMPONENT, endConnector=n)
    master_annotation(system, step)
    default_experiment(root, stop, step)
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def master_annotation(system: ET.Element, step: float) -> None:
    """The system's co-simulation master as OMSimulator's vendor annotation: a fixed-step
    master at ``step``. OMSimulator takes a system's type only from this annotation and refuses
    to import a system without one ("internal error" at NewSystem); other engines skip an
    annotation of a type they do not know, as SSP asks of them."""
    annotations = ET.SubElement(system, qname("ssd", "Annotations"))
    annotation = ET.SubElement(annotations, qname("ssc", "Annotation"), type="org.openmodelica")
    oms = ET.SubElement(annotation, qname("oms", "Annotations"))
    info = ET.SubElement(oms, qname("oms", "SimulationInformation"))
    ET.SubElement(info, qname("oms", "FixedStepMaster"), description="oms-ma", stepSize=repr(step),
                  relativeTolerance="0.0001")


def default_experiment(root: ET.Element, stop: float, step: float) -> None:
    """SSP's DefaultExperiment (start 0, ``stop``), with the step where the engines read one:
    libcosim takes its fixed-step algorithm from the Open Simulation Platform's annotation
    there (without it, and without a step given in code, libcosimpy crashed: SIGSEGV);
    OMSimulator reads the stop time from DefaultExperiment and the step from the system's
    annotation (:func:`master_annotation`). ecos reads neither: its runner and command line
    are given both (:func:`simulate_with_ecos`; ``ecos simulate --stopTime --stepSize``)."""
    experiment = ET.SubElement(root, qname("ssd", "DefaultExperiment"), startTime="0.0",
                               stopTime=repr(stop))
    annotations = ET.SubElement(experiment, qname("ssd", "Annotations"))
    annotation = ET.SubElement(annotations, qname("ssc", "Annotation"),
                               type="com.opensimulationplatform")
    algorithm = ET.SubElement(annotation, qname("osp", "Algorithm"))
    ET.SubElement(algorithm, qname("osp", "FixedStepAlgorithm"), baseStepSize=repr(step))


def parameter_set_names(path: Path) -> list[str]:
    """The names of the parameter sets the components of the SSP at ``path`` bind, in the
    order met (one per C1-C4 or rover file: the case's or the scenario's)."""
    with zipfile.ZipFile(path) as z:
        root = ET.fromstring(z.read("SystemStructure.ssd"))
    names = [pset.get("name") for pset in root.iter(qname("ssv", "ParameterSet"))]
    return list(dict.fromkeys(n for n in names if n))


def binding(p, value) -> tuple[str, int | float]:
    """(SSV type, value) of a parameter binding: switches and counts are Integer."""
    if p.kind in ("integer", "enum"):
        return "Integer", round(value)
    return "Real", float(value)


def write(path: Path, fmu_dir: Path, case: str, ps: ParameterSet, slip_paper: float,
          load: float, rim_speed: float, stop: float, step: float) -> Path:
    path = Path(path)
    with replacing(path) as partial, zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("SystemStructure.ssd",
                   system_description(case, ps, slip_paper, load, rim_speed, stop, step))
        for name in ("SingleWheelRig", "WheelTerrain"):
            z.write(Path(fmu_dir) / f"{name}.fmu", f"resources/{name}.fmu")
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


@contextlib.contextmanager
def engine_output_to_stderr():
    """File descriptor 1 pointed at standard error for the duration: the C++ engines (ecos,
    libcosim) write their log lines to it, and standard output may be a JSON document."""
    sys.stdout.flush()
    saved = os.dup(1)
    try:
        os.dup2(2, 1)
        yield
    finally:
        sys.stdout.flush()
        os.dup2(saved, 1)
        os.close(saved)


def simulate_with_ecos(path: Path, case: str | None, stop: float, step: float, csv: Path,
                       variables: tuple[str, ...],
                       go_on: Callable[[Callable[[str], float]], bool] | None = None,
                       every: float = 1.0,
                       progress: Callable[[float], None] | None = None) -> None:
    """Run an SSP written by :func:`write` in ecos (ecospy), applying the case's parameter set,
    and write ``variables`` ("component::name") at every step to ``csv``. ``go_on``, where
    given, is asked every ``every`` s of simulated time, with a getter of any variable's present
    value, whether to go on: ecos itself goes on past a step an FMU refuses (its outputs
    frozen), to ``stop``, which on a long run that ended early is most of the time and a CSV of
    gigabytes.

    ecos applies an SSP's parameter bindings only when their set is named at initialisation
    (with no name it runs every FMU at its start values: C2-C4 ran as C1, silently). ``case``
    None takes the one set the file binds; a name the file does not bind is refused. On
    ecos's command line: ``ecos simulate --path C2.ssp --parameterSet C2 --stopTime ...
    --stepSize ...``."""
    names = parameter_set_names(path)
    if case is None and len(names) == 1:
        case = names[0]
    if case not in names:
        raise RuntimeError(f"{path} binds the parameter sets {names}, not {case!r}: ecos would "
                           "run its FMUs at their start values")
    with engine_output_to_stderr(), _ecos(path, step) as sim:
        sim.add_csv_writer(str(csv), identifiers=list(variables), decimation_factor=1)
        if not sim.init(0.0, case):
            raise RuntimeError(f"ecos could not initialise {path} with parameter set {case}")
        steps, chunk = round(stop / step), max(1, round(every / step))
        done = 0
        while done < steps:
            n = min(chunk, steps - done)
            sim.step(n)
            done += n
            if progress is not None:
                progress(done * step)
            if go_on is not None and not go_on(sim.get_real):
                break
        sim.terminate()


def _plain_root() -> str | None:
    """A temporary folder whose path has no white space, for ecos (it runs ``chmod`` on the
    binaries it unzips through a shell, the path unquoted: under a folder with a space it
    printed a line per part of the path, 35 a run); None (the usual one) where that has none
    or no other is writable."""
    usual = tempfile.gettempdir()
    if not any(c.isspace() for c in usual):
        return None
    for candidate in ("/tmp", "/var/tmp", "/dev/shm"):
        if os.path.isdir(candidate) and os.access(candidate, os.W_OK | os.X_OK):
            return candidate
    return None


@contextlib.contextmanager
def _ecos(path: Path, step: float):
    """An ecos simulation of the SSP at ``path``, freed after the block. ecos unzips the SSP and
    its FMUs into folders of its own (ecos_ssp_<uuid>, ~1 MB each) under the temporary
    directory and leaves them there: it is given one of ours, removed after."""
    from ecospy import EcosSimulation

    with tempfile.TemporaryDirectory(prefix="wheelterrain_ecos_", dir=_plain_root()) as scratch:
        saved = os.environ.get("TMPDIR")
        os.environ["TMPDIR"] = scratch  # read by ecos when it unzips, in the constructor
        try:
            sim = EcosSimulation(step_size=step, ssp_path=str(path))
        finally:
            if saved is None:
                os.environ.pop("TMPDIR", None)
            else:
                os.environ["TMPDIR"] = saved
        try:
            yield sim
        finally:
            sim.free()


def read_csv_columns(path: Path, names: tuple[str, ...]) -> np.ndarray:
    """The columns ``names`` (headers without their "[unit]") of an engine's CSV result, one row
    per name, read without holding the text in memory (a long run's CSV has millions of rows)."""
    with Path(path).open(newline="") as f:
        header = [h.strip().split("[")[0] for h in next(csv.reader(f))]
    missing = [n for n in names if n not in header]
    if missing:
        raise RuntimeError(f"{path} lacks the columns {', '.join(missing)}")
    table = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2,
                       usecols=[header.index(n) for n in names])
    return table.T


def simulate_with_libcosim(path: Path, stop: float, step: float, variables: tuple[str, ...],
                           progress: Callable[[float], None] | None = None
                           ) -> dict[str, np.ndarray]:
    """Run an SSP written by :func:`write` in libcosim (PyPI libcosimpy, the Open Simulation
    Platform's engine; fixed step, its SSP reader applies the file's parameter set) and return
    ``time`` and ``variables`` ("component.name", Real) at every step; ``progress(t)`` every
    simulated second."""
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    log_output_level(CosimLogLevel.ERROR)  # its info and debug lines would flood the output
    nanoseconds = round(step * 1e9)  # libcosim's time unit
    execution = CosimExecution.from_ssp_file(str(path), step_size=nanoseconds)
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    # the variables by component, read with one call per component and step
    wanted: dict[int, tuple[list[int], list[int]]] = {}
    references: dict[int, dict[str, int]] = {}
    for j, name in enumerate(variables):
        component, variable = name.split(".", 1)
        index = execution.slave_index_from_instance_name(component)
        if index not in wanted:
            wanted[index] = ([], [])
            references[index] = {v.name.decode(): v.reference
                                 for v in execution.slave_variables(index)}
        wanted[index][0].append(j)
        wanted[index][1].append(references[index][variable])
    steps = round(stop / step)
    every = max(1, round(1.0 / step))
    out = np.empty((steps, len(variables)))
    done = steps
    for k in range(steps):
        if not execution.step():
            # an FMU refused the step (fmi2Discard): libcosim has not advanced its time and
            # would step again from it, which the FMUs that did step refuse, at every later
            # step. The run ends here, as in our master.
            done = k
            break
        for index, (columns, refs) in wanted.items():
            out[k, columns] = observer.last_real_values(index, refs)
        if progress is not None and (k + 1) % every == 0:
            progress((k + 1) * step)
    return {"time": step * np.arange(1, done + 1),
            **{name: out[:done, j] for j, name in enumerate(variables)}}


def libpython() -> Path | None:
    """This Python's shared libpython, or None where it is built static."""
    lib = Path(sysconfig.get_config_var("LIBDIR") or "") / (
        sysconfig.get_config_var("LDLIBRARY") or "")
    return lib if lib.name.endswith(".so") and lib.is_file() else None


def c_host_environment() -> dict[str, str]:
    """The environment of a C host (not Python) that runs pythonfmu FMUs: this Python's libpython
    preloaded (pythonfmu's library does not link it: fmu_src/README.md) and this Python's
    path, where the embedded interpreter finds wheelterrain, casadi and numpy."""
    env = {**os.environ,
           "PYTHONPATH": os.pathsep.join(p for p in sys.path if p and Path(p).is_dir())}
    lib = libpython()
    if lib is not None:
        env["LD_PRELOAD"] = str(lib)
    return env


def omsimulator() -> str | None:
    """OMSimulator's command-line tool: $OMSIMULATOR, else OMSimulator on the PATH, else None
    (it has no binary on PyPI or in Debian; validation/build_omsimulator.sh builds it)."""
    return os.environ.get("OMSIMULATOR") or shutil.which("OMSimulator")


def engine_missing(engine: str) -> str | None:
    """Why ``engine`` (one of SSP_ENGINES) cannot run on this machine, or None."""
    module = SSP_ENGINES[engine]
    if module is None:
        return None if omsimulator() else (
            "OMSimulator is not installed: no binary on PyPI or in Debian; build it from its "
            "public sources (validation/build_omsimulator.sh) and put it on the PATH or in "
            "$OMSIMULATOR")
    if importlib.util.find_spec(module) is None:
        return f"{module} is not installed (pip install {module})"
    return None


def simulate_with_omsimulator(path: Path, stop: float, step: float,
                              variables: tuple[str, ...], executable: str = "OMSimulator",
                              timeout: float = 600.0) -> dict[str, np.ndarray]:
    """Run an SSP written by :func:`write` in OMSimulator (the OpenModelica co-simulation
    engine, its command-line tool ``executable``): the FMUs as co-simulation, its fixed-step
    master at ``step`` (the system's annotation, :func:`master_annotation`), the file's
    parameter sets applied by its importer. Returns ``time`` and ``variables``
    ("component.name") at every step (of the rows it writes twice at a time, the last).
    Raises RuntimeError with its log when it fails or writes no result."""
    steps = round(stop / step)
    with tempfile.TemporaryDirectory(prefix="wheelterrain_oms_") as tmp:
        result = Path(tmp) / "result.csv"
        try:
            run = subprocess.run(
                [executable, "--mode=cs", f"--stopTime={stop!r}", f"--stepSize={step!r}",
                 f"--intervals={steps}", f"--resultFile={result}", f"--tempDir={tmp}",
                 "--suppressPath=true", str(Path(path).resolve())],
                cwd=tmp, capture_output=True, text=True, env=c_host_environment(),
                timeout=timeout, check=False)
        except subprocess.TimeoutExpired:
            raise RuntimeError(
                f"OMSimulator did not finish {steps} steps of {path} in {timeout:g} s: its "
                "command-line tool runs every run to the stop time (a run that ended early "
                "goes on with the refusing FMU's outputs frozen) and writes every variable "
                "at every step; a larger step or a shorter stop fits") from None
        log = run.stdout + run.stderr
        # an FMU's refusal (a wheel leaving the model's domain) is logged as an error and
        # the run goes on, the refusing FMU's outputs frozen: the caller cuts the record there
        if run.returncode != 0 or not result.is_file():
            raise RuntimeError(f"OMSimulator failed (exit status {run.returncode}) on {path}:"
                               f"\n{log[-3000:]}")
        with result.open(newline="") as f:
            header = next(csv.reader(f))
        system = ".".join(next(h for h in header if h != "time").split(".")[:2])  # model.system
        try:
            data = read_csv_columns(result, ("time", *(f"{system}.{v}" for v in variables)))
        except RuntimeError as err:
            raise RuntimeError(f"OMSimulator's result of {path}: {err}") from None
    t = data[0]
    data = data[:, np.append(t[1:] != t[:-1], True)]  # the last row written at each time
    return {"time": data[0], **{v: data[1 + j] for j, v in enumerate(variables)}}
