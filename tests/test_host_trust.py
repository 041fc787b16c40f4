"""The pythonfmu flavour as a host meets it: what an independent FMI integration test found
(issue: "The pythonfmu flavour a host can trust"), each a test that failed before.

- no non-finite output served as fmi2OK, and the warning reaches a host whose logging is off;
- any number of instances per process, in any order with the other FMUs, after their unzip
  folders are gone (each reads its own resources);
- FMU states owned by the guard: a truncated, overwritten, foreign or freed state is fmi2Error
  and the instance goes on;
- a host's misuse of doStep is fmi2Error; fmi2Terminated only where the FMU cannot go on;
- an unzip folder named with a literal %20 is refused with a message, not a crash; so is a
  resource location that is not the FMU's resources folder;
- after fmi2Fatal every call but fmi2FreeInstance is refused, not a crash.
The C host's exit without fmi2FreeInstance is in tests/test_c_host.py.
"""

from __future__ import annotations

import ctypes
import math
import os
import random
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from fmpy import extract
from fmpy.fmi1 import FMICallException

from wheelterrain.fmu import variables
from wheelterrain.fmu.instance import Instance

MODELS = ("WheelTerrain", "SingleWheelRig", "RoverChassis", "Terrain")
WARNING, DISCARD, ERROR = 1, 2, 3


@pytest.fixture(scope="module")
def unzipped(fmu_dir):
    folders = {name: extract(str(fmu_dir / f"{name}.fmu")) for name in MODELS}
    yield folders
    for folder in folders.values():
        shutil.rmtree(folder, ignore_errors=True)


def instance(fmu_dir, unzipped, name, label="x", logging_on=True) -> Instance:
    """An instance whose log is kept; with ``logging_on=False`` the host turns logging off,
    so only what FMI's status rules send whatever the flag reaches the log."""
    inst = Instance(fmu_dir / f"{name}.fmu", unzipped[name], label, log=True)
    if not logging_on:
        inst.fmu.setDebugLogging(False, [])
    return inst


def raw_get(inst: Instance, names) -> tuple[int, list[float]]:
    """(status, values) of fmi2GetReal as the host receives them (fmpy raises only above
    fmi2Warning, so a warning would pass unseen through getReal)."""
    refs = inst.refs(names)
    vr = (ctypes.c_uint * len(refs))(*refs)
    out = (ctypes.c_double * len(refs))()
    status = inst.fmu.fmi2GetReal(inst.fmu.component, vr, len(refs), out)
    return status, list(out)


def outputs(name: str) -> list[str]:
    return [v.name for v in variables.VARIABLES[name]() if v.causality == "output"]


# --- no NaN with fmi2OK --------------------------------------------------------------------

def test_outputs_with_no_valid_operating_point_yet_are_a_warning_that_says_so(fmu_dir,
                                                                              unzipped):
    """carriage_speed = -100 m/s (backward, the wheel turning forward) set in initialisation
    mode: the model
    refuses the point and has never had a valid one. Before: NaN with fmi2OK, in
    initialisation mode, after it and after the refused step, and with logging off the host
    learnt nothing."""
    t = instance(fmu_dir, unzipped, "WheelTerrain", logging_on=False)
    try:
        t.fmu.setupExperiment(startTime=0.0)
        t.fmu.enterInitializationMode()
        t.set({"carriage_speed": -100.0})
        names = ["normal_force", "drawbar_pull", "torque", "contact_sinkage"]
        seen = []
        for stage in ("initialisation", "after initialisation", "after the refused step"):
            if stage == "after initialisation":
                t.fmu.exitInitializationMode()
                t.running = True
            if stage == "after the refused step":
                with pytest.raises(FMICallException) as refused:
                    t.fmu.doStep(0.0, 1e-3)
                assert refused.value.status == DISCARD
            status, values = raw_get(t, names)
            assert all(math.isnan(x) for x in values), (stage, values)
            assert status == WARNING, stage
            seen.append(stage)
        warnings = [m for s, m in t.log if s == WARNING and "no valid operating point yet" in m]
        assert len(warnings) == len(seen), t.log
        assert "outside the model's domain" in warnings[-1]  # the reason, logging off
    finally:
        t.close()


@pytest.mark.slow
def test_no_non_finite_output_is_served_as_ok_at_random_points_inside_the_ranges(fmu_dir,
                                                                                 unzipped):
    """Random inputs inside the declared ranges (each FMU's Real inputs; WheelTerrain's
    contact inputs and soil switch): every output read is finite, or the read is a warning.
    The report saw NaN with fmi2OK in 170 of 553 such samples."""
    rng = random.Random(20261126)
    checked = 0
    for name in MODELS:
        rows = [v for v in variables.VARIABLES[name]()
                if v.causality == "input" and v.type == "Real" and v.min is not None]
        names = outputs(name)
        for k in range(12):
            values = {v.name: rng.uniform(v.min, v.max) if rng.random() < 0.5 else v.start
                      for v in rows}
            with instance(fmu_dir, unzipped, name, f"r{k}", logging_on=False) as inst:
                inst.fmu.setupExperiment(startTime=0.0)
                inst.fmu.enterInitializationMode()
                inst.set(values)
                for step in range(3):
                    status, got = raw_get(inst, names)
                    finite = all(math.isfinite(x) for x in got)
                    assert finite or status == WARNING, (name, values, step)
                    checked += 1
                    if step == 0:
                        inst.fmu.exitInitializationMode()
                        inst.running = True
                    else:
                        try:
                            inst.fmu.doStep((step - 1) * 1e-3, 1e-3)
                        except FMICallException:
                            break
    assert checked > 4 * 12


# --- several instances in one process --------------------------------------------------------

SIMULATE_EACH_TWICE = """
import sys
import fmpy
folder = sys.argv[1]
for round_ in range(2):
    for name in ("SingleWheelRig", "WheelTerrain", "RoverChassis", "Terrain"):
        r = fmpy.simulate_fmu(f"{folder}/{name}.fmu", stop_time=0.02)
        if name == "WheelTerrain":
            print(round_, r["normal_force"][-1])
"""


def test_each_fmu_runs_again_in_the_same_process_after_its_unzip_folder_is_gone(fmu_dir):
    """fmpy.simulate_fmu extracts to a temporary folder and removes it after the run. The
    second instance then failed ("Failed to instantiate model": the bundled package read its
    presets from the first, deleted folder). In a fresh process: the host has not imported
    wheelterrain, so the FMU's own bundled copy is the one imported, as in any host."""
    run = subprocess.run([sys.executable, "-c", SIMULATE_EACH_TWICE, str(fmu_dir)],
                         capture_output=True, text=True, timeout=300, check=False)
    assert run.returncode == 0, run.stderr[-3000:]
    forces = [float(line.split()[1]) for line in run.stdout.splitlines()]
    assert len(forces) == 2
    assert forces[0] == forces[1] > 10.0  # the soil carries the wheel both times


# --- FMU states -------------------------------------------------------------------------------

def _stepped(fmu_dir, unzipped, name, label):
    inst = instance(fmu_dir, unzipped, name, label).start({})
    inst.fmu.doStep(0.0, 1e-3)
    return inst


@pytest.mark.parametrize("name", MODELS)
@pytest.mark.parametrize("damage", ["truncated", "overwritten", "extended by one byte"])
def test_a_damaged_serialized_state_is_an_error_and_the_instance_goes_on(fmu_dir, unzipped,
                                                                         name, damage):
    """A serialized state with a valid header and a truncated or overwritten body was
    fmi2Fatal and the next call crashed the host (SIGSEGV), in all four FMUs."""
    inst = _stepped(fmu_dir, unzipped, name, "s")
    try:
        state = inst.fmu.getFMUstate()
        blob = bytearray(inst.fmu.serializeFMUstate(state))
        inst.fmu.freeFMUstate(state)
        if damage == "truncated":
            bad = blob[: len(blob) - 7]
        elif damage == "overwritten":
            bad = blob[:]
            bad[len(blob) - 9: len(blob) - 1] = b"\x00" * 8
        else:
            bad = blob + b"\x00"
        if damage == "extended by one byte":  # a longer buffer is allowed; the state is whole
            inst.fmu.setFMUstate(inst.fmu.deSerializeFMUstate(bytes(bad)))
        else:
            with pytest.raises(FMICallException) as info:
                inst.fmu.deSerializeFMUstate(bytes(bad))
            assert info.value.status == ERROR
            reason = "truncated" if damage == "truncated" else "checksum"
            assert any(reason in m for m in inst.errors()), inst.log
        inst.fmu.setFMUstate(inst.fmu.deSerializeFMUstate(bytes(blob)))  # its own still works
        inst.fmu.doStep(1e-3, 1e-3)
        assert all(math.isfinite(x) for x in inst.get(outputs(name)[:3]))
    finally:
        inst.close()


def test_another_models_or_a_freed_state_pointer_is_an_error(fmu_dir, unzipped):
    """SingleWheelRig's state pointer given to RoverChassis was accepted with fmi2OK (or was
    fmi2Fatal, then SIGSEGV). The guard owns its states: a pointer it did not make, or has
    freed, is refused without being read."""
    rig = _stepped(fmu_dir, unzipped, "SingleWheelRig", "rig")
    rover = _stepped(fmu_dir, unzipped, "RoverChassis", "rover")
    try:
        foreign = rig.fmu.getFMUstate()
        with pytest.raises(FMICallException) as info:
            rover.fmu.setFMUstate(foreign)
        assert info.value.status == ERROR
        assert any("not made by RoverChassis" in m for m in rover.errors()), rover.log
        own = rover.fmu.getFMUstate()
        stale = ctypes.c_void_p(own.value)
        rover.fmu.freeFMUstate(own)
        with pytest.raises(FMICallException):
            rover.fmu.setFMUstate(stale)
        rig.fmu.freeFMUstate(foreign)
        rover.fmu.doStep(1e-3, 1e-3)
    finally:
        rig.close()
        rover.close()


# --- doStep: the host's mistakes, and what Terminated means ----------------------------------

@pytest.mark.parametrize(("t", "h", "needle"), [
    (0.0, 0.0, "must be finite and > 0"),
    (0.0, -1e-3, "must be finite and > 0"),
    (0.0, math.nan, "must be finite and > 0"),
    (0.5, 1e-3, "steps must continue from the last step's end"),
])
def test_a_step_the_host_asks_for_wrongly_is_an_error(fmu_dir, unzipped, t, h, needle):
    """h = 0, h < 0 or NaN was fmi2Discard (the model's refusal, not the host's error); a step
    from another communication point was fmi2OK."""
    inst = instance(fmu_dir, unzipped, "WheelTerrain").start({})
    try:
        with pytest.raises(FMICallException) as info:
            inst.fmu.doStep(t, h)
        assert info.value.status == ERROR
        assert any(needle in m for m in inst.errors()), inst.log
        inst.fmu.doStep(0.0, 1e-3)  # the right step still goes
    finally:
        inst.close()


def test_a_refused_step_the_next_inputs_recover_from_does_not_terminate(fmu_dir, unzipped):
    """An input-driven refusal (the carriage moving backward under a wheel turning forward:
    outside the slip domain) set
    fmi2Terminated = true although the next step, with inputs back in the domain,
    succeeds (native: false)."""
    inst = instance(fmu_dir, unzipped, "WheelTerrain").start({})
    try:
        inst.set({"carriage_speed": -100.0})
        with pytest.raises(FMICallException) as info:
            inst.fmu.doStep(0.0, 1e-3)
        assert info.value.status == DISCARD
        terminated = ctypes.c_int(-1)
        inst.fmu.fmi2GetBooleanStatus(inst.fmu.component, 3, ctypes.byref(terminated))
        assert terminated.value == 0  # fmi2Terminated is status kind 3
        inst.set({"carriage_speed": 0.03})
        inst.fmu.doStep(0.0, 1e-3)
        assert math.isfinite(inst.value("normal_force"))
    finally:
        inst.close()


# --- a literal %20 in the unzip folder's name ---------------------------------------------

OPEN_UNDER = """
import sys
from fmpy import extract
from wheelterrain.fmu.instance import Instance
folder = extract(sys.argv[1], unzipdir=sys.argv[2])
try:
    Instance(sys.argv[1], folder, "x", log=False)
except Exception as err:
    print("refused:", err)
"""


def test_an_unzip_folder_named_with_a_literal_percent_20_is_refused_with_a_message(fmu_dir,
                                                                                   tmp_path):
    """pythonfmu reads %20 in the resource path as a space: the slave is not found and the
    host crashed (SIGSEGV) in fmi2Instantiate. In a fresh process, so a crash fails here."""
    run = subprocess.run([sys.executable, "-c", OPEN_UNDER, str(fmu_dir / "WheelTerrain.fmu"),
                          str(tmp_path / "wheel%20run")],
                         capture_output=True, text=True, timeout=120, check=False)
    assert run.returncode == 0, (run.returncode, run.stderr[-2000:])
    assert "refused:" in run.stdout
    assert "which pythonfmu 0.7 reads as a space" in run.stdout + run.stderr



# --- a resource location that is not the FMU's resources folder -------------------------

RESOURCE_LOCATIONS = """
import ctypes, sys
from pathlib import Path
from fmpy import extract, read_model_description
from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                       fmi2CallbackFunctions, fmi2CallbackLoggerTYPE, fmi2CoSimulation, calloc,
                       free)
fmu, scratch = sys.argv[1], Path(sys.argv[2])
md = read_model_description(fmu)
said = []
callbacks = fmi2CallbackFunctions()
callbacks.logger = fmi2CallbackLoggerTYPE(lambda env, name, status, cat, msg:
                                          said.append(msg.decode()))
callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
for kind, folder in [("missing", "plain"), ("root", "plain"), ("raw", "a%20b"), ("raw", "a#b")]:
    # each in a folder of its own: a library is never rewritten while it is loaded
    root = Path(extract(fmu, unzipdir=str(scratch / kind / folder)))
    uri = {"missing": (root / "nothere").as_uri(), "root": root.as_uri(),
           "raw": "file://" + str(root / "resources")}[kind]  # raw: not percent-encoded
    slave = FMU2Slave(guid=md.guid, unzipDirectory=str(root), instanceName="x",
                      modelIdentifier=md.coSimulation.modelIdentifier)
    said.clear()
    c = slave.fmi2Instantiate(b"x", fmi2CoSimulation, md.guid.encode(), uri.encode(),
                              ctypes.byref(callbacks), 0, 0)
    print(kind, folder, "instantiated" if c else "refused", said[-1] if said else "")
    if c:
        slave.fmi2FreeInstance(c)
"""


@pytest.mark.parametrize("name", MODELS)
def test_a_resource_location_that_is_not_the_resources_folder_is_refused_with_a_reason(
        fmu_dir, tmp_path, name):
    """pythonfmu crashed the host (SIGSEGV, 16 of 16) in fmi2Instantiate on a resource folder
    that does not exist, on the unzip root given instead of resources/, and on a URI written
    raw (not percent-encoded) whose folder name decodes to another (a%20b). The guard refuses
    each with a logged reason and NULL; a raw URI that names the folder (a#b) runs. In a fresh
    process, so that a crash fails here."""
    run = subprocess.run([sys.executable, "-c", RESOURCE_LOCATIONS, str(fmu_dir / f"{name}.fmu"),
                          str(tmp_path)], capture_output=True, text=True, timeout=300,
                         check=False)
    assert run.returncode == 0, (run.returncode, run.stderr[-2000:])
    lines = dict(((kind, folder), rest) for kind, folder, rest in
                 (line.split(" ", 2) for line in run.stdout.splitlines()))
    assert lines[("missing", "plain")].startswith("refused")
    assert "nothere does not exist" in lines[("missing", "plain")]
    assert lines[("root", "plain")].startswith("refused")
    assert "it is not this FMU's resources folder" in lines[("root", "plain")]
    assert lines[("raw", "a%20b")].startswith("refused")
    assert "raw/a b/resources does not exist" in lines[("raw", "a%20b")]
    assert lines[("raw", "a#b")].startswith("instantiated")


# --- fmi2Fatal: a Python exception escaped the slave --------------------------------------

AFTER_FATAL = """
import ctypes, sys
from fmpy.fmi1 import FMICallException
from wheelterrain.fmu.instance import Instance
inst = Instance(sys.argv[1], sys.argv[2], "x", log=True).start({})
try:
    inst.fmu.doStep(0.0, 1e-3)
except FMICallException as err:
    print("first", err.status)
for name, call in [("step", lambda: inst.fmu.doStep(0.0, 1e-3)),
                   ("get", lambda: inst.get(["normal_force"])),
                   ("state", lambda: inst.fmu.getFMUstate()),
                   ("set", lambda: inst.set({"carriage_speed": 0.03}))]:
    try:
        call()
        print(name, 0)
    except FMICallException as err:
        print(name, err.status)
terminated = ctypes.c_int(-1)
print("terminated", inst.fmu.fmi2GetBooleanStatus(inst.fmu.component, 3,
                                                   ctypes.byref(terminated)), terminated.value)
print("said", sum("an earlier call ended in fmi2Fatal" in m and "injected fault" in m
                  for _, m in inst.log))
inst.fmu.freeInstance()
print("freed", 1)
"""


def test_after_a_fatal_step_every_call_is_refused_and_the_host_survives(fmu_dir, unzipped,
                                                                       tmp_path):
    """A Python exception in the slave's doStep is fmi2Fatal; pythonfmu's next call then
    crashed the host (SIGSEGV). The guard refuses every call after fmi2Fatal but
    fmi2FreeInstance, with the reason, and answers fmi2Terminated = true. The fault is put in
    a copy of the FMU's own slave; in a fresh process, so a crash fails here."""
    folder = tmp_path / "faulty"
    shutil.copytree(unzipped["WheelTerrain"], folder)
    slaves = list((folder / "resources").glob("wheelterrain_slave*.py"))
    assert len(slaves) == 1
    text = slaves[0].read_text()
    step = "return self.core.do_step(current_time, step_size)"
    assert step in text
    slaves[0].write_text(text.replace(step, 'raise RuntimeError("injected fault")'))
    run = subprocess.run([sys.executable, "-c", AFTER_FATAL, str(fmu_dir / "WheelTerrain.fmu"),
                          str(folder)], capture_output=True, text=True, timeout=120,
                         check=False)
    assert run.returncode == 0, (run.returncode, run.stderr[-2000:])
    lines = dict(line.split(" ", 1) for line in run.stdout.splitlines())
    assert lines["first"] == "4", run.stdout  # fmi2Fatal
    assert lines["step"] == lines["get"] == lines["state"] == lines["set"] == str(ERROR)
    assert lines["terminated"] == "0 1"  # fmi2OK, true
    assert int(lines["said"]) == 4
    assert lines["freed"] == "1"


ENGINES_AFTER_FMPY = """
import importlib.util, sys
# only the FMUs' bundled copies of wheelterrain, as in a host that has not installed it
sys.meta_path[:] = [f for f in sys.meta_path if "editable" not in getattr(f, "__module__", "")
                    and "editable" not in type(f).__module__]
assert importlib.util.find_spec("wheelterrain") is None
import numpy as np
import fmpy
from ecospy import EcosSimulation
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimObserver import CosimObserver
fmus, path, tmp = sys.argv[1], sys.argv[2], sys.argv[3]
fmpy.simulate_fmu(f"{fmus}/WheelTerrain.fmu", stop_time=0.02)  # its unzip folder is removed
for k in range(2):
    sim = EcosSimulation(step_size=1e-3, ssp_path=path)
    sim.add_csv_writer(f"{tmp}/e{k}.csv", identifiers=["terrain::normal_force"],
                       decimation_factor=1)
    assert sim.init(0.0, "C3")
    sim.step(200)
    sim.terminate()
    sim.free()
    print("ecos", np.loadtxt(f"{tmp}/e{k}.csv", delimiter=",", skiprows=1)[-1, -1])
execution = CosimExecution.from_ssp_file(path)
observer = CosimObserver.create_last_value()
execution.add_observer(observer)
for _ in range(200):
    assert execution.step()
index = execution.slave_index_from_instance_name("terrain")
ref = {v.name.decode(): v.reference for v in execution.slave_variables(index)}["normal_force"]
print("libcosim", observer.last_real_values(index, [ref])[0])
"""


def test_ecos_and_libcosim_run_the_fmus_in_a_process_that_ran_them_before(fmu_dir, tmp_path):
    """After one fmpy run in the same process (its unzip folder then removed), ecos reported
    a successful initialisation and ran with zero soil forces, twice, and libcosim crashed
    (SIGSEGV): the bundled package read its data from the removed folder. In a fresh process
    without the project installed, the FMUs' own copies only."""
    from wheelterrain import presets
    from wheelterrain.cosim import ssp

    pytest.importorskip("ecospy")
    pytest.importorskip("libcosimpy")
    if ssp.libpython() is None:
        pytest.skip("needs a shared libpython to preload (this Python is static)")
    path = ssp.write(tmp_path / "C3.ssp", fmu_dir, "C3", presets.load(presets.DEFAULT_PRESET),
                     0.5, 62.0, 0.03, 0.2, 1e-3)
    env = ssp.c_host_environment()
    # not the resources folders of FMUs this test run instantiated in process (pythonfmu puts
    # them on sys.path): the child must find no wheelterrain but in the FMUs it loads
    env["PYTHONPATH"] = os.pathsep.join(
        p for p in env["PYTHONPATH"].split(os.pathsep) if not (Path(p) / "wheelterrain").exists())
    run = subprocess.run([sys.executable, "-c", ENGINES_AFTER_FMPY, str(fmu_dir), str(path),
                          str(tmp_path)], env=env, capture_output=True, text=True, timeout=600,
                         check=False)
    assert run.returncode == 0, (run.returncode, run.stderr[-2000:])
    forces = [float(line.split()[1]) for line in run.stdout.splitlines()
              if line.startswith(("ecos ", "libcosim "))]
    assert len(forces) == 3
    assert min(forces) > 50.0  # the soil carries the 62 N wheel in every run
