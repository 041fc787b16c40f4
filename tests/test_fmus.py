"""Gates on the built pythonfmu FMUs: validation, default experiment,
agreement with the core model, several instances, FMU state, reset, bad input."""

from __future__ import annotations

import csv
import math
import os
import shutil
import subprocess
import sys

import pytest
from fmpy import extract, simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from wheelterrain import model, presets
from wheelterrain.fmu.instance import Instance
from wheelterrain.model.slip import reference_radius
from wheelterrain.parameters import TABLE

NAMES = ("WheelTerrain", "SingleWheelRig")


@pytest.fixture(scope="session")
def fmus(fmu_dir):
    out = fmu_dir
    unzip = {name: extract(str(out / f"{name}.fmu")) for name in NAMES}
    yield {"dir": out, **{name: out / f"{name}.fmu" for name in NAMES}, "unzip": unzip}
    for d in unzip.values():
        shutil.rmtree(d, ignore_errors=True)


def terrain(fmus, name="terrain", **values):
    return Instance(fmus["WheelTerrain"], fmus["unzip"]["WheelTerrain"], name,
                    log=True).start(values)


def rig(fmus, name="rig", **values):
    return Instance(fmus["SingleWheelRig"], fmus["unzip"]["SingleWheelRig"], name,
                    log=True).start(values)


@pytest.mark.parametrize("name", NAMES)
def test_validate_reports_no_problems(fmus, name):
    assert validate_fmu(str(fmus[name])) == []


@pytest.mark.parametrize("name", NAMES)
def test_default_experiment_simulates(fmus, name):
    result = simulate_fmu(str(fmus[name]))
    assert result["time"][-1] == pytest.approx(1.0)
    for field in result.dtype.names:
        assert all(math.isfinite(v) for v in result[field])


def test_model_description_is_modelica_friendly(fmus):
    from fmpy import read_model_description

    md = read_model_description(str(fmus["WheelTerrain"]))
    by_name = {v.name: v for v in md.modelVariables}
    assert {p.name for p in TABLE} <= set(by_name)
    for v in md.modelVariables:
        assert v.description, v.name
        assert v.declaredType is not None, v.name
    phi = by_name["soil.phi"]
    assert phi.declaredType.name == "Modelica.Units.SI.Angle"
    assert phi.unit == "rad"
    assert phi.displayUnit == "deg"
    assert float(phi.max) == TABLE[[p.name for p in TABLE].index("soil.phi")].max
    assert by_name["drawbar_pull"].declaredType.name == "Modelica.Units.SI.Force"
    units = {u.name: u for u in md.unitDefinitions}
    assert units["N"].baseUnit.kg == 1
    assert units["N"].baseUnit.s == -2
    outputs = {u.variable.name: u for u in md.outputs}
    assert {d.name for d in outputs["drawbar_pull"].dependencies} >= {"sinkage", "wheel_speed"}
    assert outputs["wheel_angle"].dependencies == []
    assert md.defaultExperiment.stepSize == "0.001"
    # mode switches are Integers (libcosim and ecos set no Enumeration) over exactly the
    # table's choices, each named in the description
    for p in TABLE:
        if p.kind == "enum":
            v = by_name[p.name]
            assert v.type == "Integer", p.name
            assert (int(v.min), int(v.max)) == (min(p.choices), max(p.choices)), p.name
            for value in p.choices:
                assert f"{value} = " in v.description, (p.name, value)
    assert by_name["model.contact_form"].declaredType.name == "wheelterrain.model.contact_form"


@pytest.mark.parametrize("name", NAMES)
def test_guid_is_derived_from_the_content_and_the_fmu_names_its_version(fmus, name):
    """The GUID hashes the description without the GUID and the build time: recomputing it
    from the shipped description gives it back (a rebuild of the same model gets the same
    GUID), and any change to a variable gives another one. Version and author are set."""
    import copy
    import zipfile
    from xml.etree import ElementTree as ET

    from wheelterrain import __version__
    from wheelterrain.fmu.description import identify

    with zipfile.ZipFile(fmus[name]) as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
    assert root.get("version") == __version__
    assert root.get("author")
    assert "generationDateAndTime" not in root.attrib
    shipped = root.get("guid")
    again = copy.deepcopy(root)
    identify(again)
    assert again.get("guid") == shipped
    changed = copy.deepcopy(root)
    changed.find("ModelVariables")[0][0].set("start", "0.123")
    identify(changed)
    assert changed.get("guid") != shipped


@pytest.mark.parametrize(("slip", "phi"), [(0.0, 0.45), (0.2, 0.40), (0.43, 0.42)])
def test_quasi_static_fmpy_cli_matches_steady(fmus, tmp_path, slip, phi):
    ps = presets.load(presets.DEFAULT_PRESET).with_values({"soil.phi": phi})
    omega = 0.6
    speed = omega * ps["wheel.radius"] * (1 - slip)
    out = tmp_path / "qs.csv"
    subprocess.run([sys.executable, "-m", "fmpy", "simulate", str(fmus["WheelTerrain"]),
                    "--start-values", "quasi_static", "true", "soil.phi", repr(phi),
                    "wheel_speed", repr(omega), "carriage_speed", repr(speed), "load", "62",
                    "--output-variables", "contact_sinkage", "drawbar_pull", "slip",
                    "--output-file", str(out)], check=True)
    with out.open() as f:
        rows = list(csv.DictReader(f))
    fmu_slip = float(rows[-1]["slip"])
    want = model.steady_state(ps, 62.0, fmu_slip)
    assert fmu_slip == pytest.approx(slip, rel=1e-12, abs=1e-15)
    for row in rows:
        assert float(row["contact_sinkage"]) == pytest.approx(want["sinkage"], rel=1e-9)
        assert float(row["drawbar_pull"]) == pytest.approx(want["drawbar_pull"], rel=1e-9)


def test_dynamic_mode_matches_contact_forces(fmus):
    ps = presets.load(presets.DEFAULT_PRESET)
    t = terrain(fmus, sinkage=0.03, sinkage_rate=0.002, wheel_speed=0.6, carriage_speed=0.024)
    try:
        got = t.get(("normal_force", "drawbar_pull", "torque", "slip", "wheel_angle"))
        want = model.contact_forces(ps, 0.03, got[3], sinkage_rate=0.002, wheel_angle=got[4])
        for k, key in enumerate(("normal_force", "drawbar_pull", "torque")):
            assert got[k] == pytest.approx(want[key], rel=1e-12)
    finally:
        t.close()


@pytest.mark.parametrize("slip", [-0.3, -0.9, -1.0, 0.4])
def test_braking_and_driving_use_the_contact_models_slip(fmus, slip):
    """The FMU hands the contact model the slip of the true kinematics, the traction slip
    driving (V = (1 - i)*omega*R) and the skid braking (omega*R = (1 + s)*V), down to the
    locked wheel (omega = 0): its ``slip`` output is that slip."""
    ps = presets.load(presets.DEFAULT_PRESET)
    radius = ps["wheel.radius"]
    if slip >= 0:
        omega, speed = 0.6, 0.6 * radius * (1 - slip)
    else:
        speed = 0.03
        omega = speed * (1 + slip) / radius
    t = terrain(fmus, sinkage=0.02, wheel_speed=omega, carriage_speed=speed)
    try:
        got = t.get(("normal_force", "drawbar_pull", "torque", "slip", "wheel_angle"))
        assert got[3] == pytest.approx(slip, rel=1e-12)
        want = model.contact_forces(ps, 0.02, slip, wheel_angle=got[4],
                                    slip_definition="unified")
        for k, key in enumerate(("normal_force", "drawbar_pull", "torque")):
            assert got[k] == pytest.approx(want[key], rel=1e-12)
        t.fmu.doStep(0.0, 1e-3)  # a locked wheel is a step like any other
    finally:
        t.close()


@pytest.mark.parametrize(("omega", "speed", "slip"), [
    # the wheel turning backward under a carriage moving forward, the rim faster: the slip of
    # the mirror image (rolling backward), (0.03 + 0.01)/0.03
    (-0.6, 0.01, "1.33333"),
    (0.6, -0.02, "1.66667"),  # the carriage moving backward under a wheel turning forward
])
def test_speeds_outside_the_slip_domain_are_refused_with_the_reason(fmus, omega, speed, slip):
    t = terrain(fmus, sinkage=0.02, wheel_speed=omega, carriage_speed=speed)
    try:
        with pytest.raises(FMICallException):
            t.fmu.doStep(0.0, 1e-3)
        message = " ".join(t.errors())
        assert f"gives slip {slip}, outside the model's domain" in message, t.log
        assert "in [-1, 1], from a locked wheel (-1) to spinning in place (1)" in message
        assert "against its carriage's motion only within 1e-05 m/s of rest" in message
    finally:
        t.close()


@pytest.mark.parametrize(("rim", "speed", "slip"), [
    (-3e-6, 5e-6, -0.8),  # the wheel turning backward a little, its carriage still forward
    (4e-6, -1e-6, 0.5),  # the carriage a little backward, the wheel still forward
    (2e-6, 2e-6, 0.0),  # both creeping at the same speed
    (-6e-6, -2e-6, 0.4),  # backward, both below the floor: the mirror image's (6 - 2)/10
])
def test_a_wheel_and_its_carriage_pass_through_rest_with_the_regularised_slip(fmus, rim, speed,
                                                                              slip):
    """Within the slip's speed floor (1e-5 m/s) of rest the wheel and its carriage may turn
    against each other, as they do when a vehicle stops and reverses: the step is served, its
    slip (omega*R_ref - V)/1e-5 m/s in the frame of the faster motion, the forces finite."""
    radius = reference_radius(presets.load(presets.DEFAULT_PRESET))
    t = terrain(fmus, sinkage=0.02, wheel_speed=rim / radius, carriage_speed=speed)
    try:
        t.fmu.doStep(0.0, 1e-3)
        got = dict(zip(("slip", "normal_force", "drawbar_pull"),
                       t.get(("slip", "normal_force", "drawbar_pull")), strict=True))
        assert got["slip"] == pytest.approx(slip, abs=1e-9)
        assert all(math.isfinite(v) for v in got.values())
        assert got["normal_force"] > 0
    finally:
        t.close()


def test_several_instances_and_both_fmus_in_one_process(fmus):
    a = terrain(fmus, "a", sinkage=0.02, wheel_speed=0.6, carriage_speed=0.03)
    b = terrain(fmus, "b", **{"soil.phi": 0.5, "sinkage": 0.02, "wheel_speed": 0.6,
                              "carriage_speed": 0.02})
    r1 = rig(fmus, "r1")
    r2 = rig(fmus, "r2", **{"rig.load": 40.0, "rig.slip_paper": 0.5})
    try:
        fa, fb = a.value("drawbar_pull"), b.value("drawbar_pull")
        assert fa != fb  # independent parameters and inputs
        for k in range(20):
            for inst in (a, b, r1, r2):
                inst.fmu.doStep(k * 1e-3, 1e-3)
        assert a.value("wheel_angle") == pytest.approx(20 * 0.6e-3)
        single = terrain(fmus, "single", sinkage=0.02, wheel_speed=0.6, carriage_speed=0.03)
        for k in range(20):
            single.fmu.doStep(k * 1e-3, 1e-3)
        assert single.value("drawbar_pull") == a.value("drawbar_pull")
        single.close()
        assert r2.value("carriage_speed") == pytest.approx(0.03 / 1.5)
        assert r1.value("carriage_speed") == pytest.approx(0.03)
    finally:
        for inst in (a, b, r1, r2):
            inst.close()


@pytest.mark.parametrize("serialize", [False, True])
def test_fmu_state_round_trip_restores_internal_state(fmus, serialize):
    t = terrain(fmus, sinkage=0.03, wheel_speed=0.6, carriage_speed=0.024)
    r = rig(fmus, **{"rig.slip_paper": 0.25})
    try:
        def run(n, k0):
            trace = []
            for k in range(k0, k0 + n):
                x = r.get(("sinkage", "sinkage_rate", "wheel_speed", "carriage_speed"))
                t.set(dict(zip(("sinkage", "sinkage_rate", "wheel_speed", "carriage_speed"), x,
                               strict=True)))
                f = t.get(("normal_force", "drawbar_pull", "torque"))
                r.set(dict(zip(("normal_force", "drawbar_pull", "torque"), f, strict=True)))
                r.fmu.doStep(k * 1e-3, 1e-3)
                t.fmu.doStep(k * 1e-3, 1e-3)
                trace.append((*x, *f, t.value("wheel_angle")))
            return trace

        run(50, 0)
        states = [inst.fmu.getFMUstate() for inst in (t, r)]
        if serialize:
            blobs = [inst.fmu.serializeFMUstate(s) for inst, s in zip((t, r), states,
                                                                       strict=True)]
            for inst, s in zip((t, r), states, strict=True):
                inst.fmu.freeFMUstate(s)
            states = [inst.fmu.deSerializeFMUstate(b) for inst, b in zip((t, r), blobs,
                                                                          strict=True)]
        first = run(40, 50)
        for inst, s in zip((t, r), states, strict=True):
            inst.fmu.setFMUstate(s)
        again = run(40, 50)
        assert again == first  # bit-identical: wheel angle, rig states and inputs all restored
    finally:
        t.close()
        r.close()


def test_reset_restores_the_start(fmus):
    t = terrain(fmus, sinkage=0.03, wheel_speed=0.6, carriage_speed=0.024)
    try:
        before = t.get(("drawbar_pull", "wheel_angle"))
        for k in range(30):
            t.fmu.doStep(k * 1e-3, 1e-3)
        assert t.value("wheel_angle") != before[1]
        t.fmu.reset()
        t.start({"sinkage": 0.03, "wheel_speed": 0.6, "carriage_speed": 0.024})
        assert t.get(("drawbar_pull", "wheel_angle")) == before
    finally:
        t.close()


@pytest.mark.parametrize(("name", "value", "needle"), [
    ("soil.phi", float("nan"), "soil.phi"),
    ("wheel.width", -0.075, "wheel.width"),
    ("soil.phi", math.pi / 2, "soil.phi"),
])
def test_bad_parameter_is_refused_with_a_logged_reason(fmus, name, value, needle):
    t = terrain(fmus, sinkage=0.03)
    try:
        with pytest.raises(FMICallException) as info:  # fmi2Error from the guard library
            t.set({name: value})
        assert info.value.status == 3
        with pytest.raises(FMICallException) as info:
            t.fmu.doStep(0.0, 1e-3)
        assert info.value.status in (2, 3)  # fmi2Discard or fmi2Error, never fatal
        assert any(needle in m and "valid range" in m for m in t.errors()), t.log
        t.set({name: presets.load(presets.DEFAULT_PRESET)[name]})  # recovers once valid again
        t.fmu.doStep(0.0, 1e-3)
    finally:
        t.close()


def test_fmpy_simulate_with_a_bad_start_value_writes_no_plausible_numbers(fmus, tmp_path):
    """The start value is refused when set (fmi2Error from the guard library, as the native
    flavour), with the reason in fmpy's log; fmpy stops there and writes no results, so
    nothing plausible-looking reaches a results file."""
    out = tmp_path / "bad.csv"
    run = subprocess.run([sys.executable, "-m", "fmpy", "simulate", str(fmus["WheelTerrain"]),
                          "--debug-logging", "--start-values", "soil.phi", "5",
                          "--stop-time", "0.01", "--output-file", str(out)],
                         capture_output=True, text=True, check=False)
    assert "soil.phi = 5 is out of range" in run.stdout + run.stderr
    assert run.returncode != 0
    assert not out.exists()


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("valgrind") is None, reason="needs valgrind (.ci/run installs it)")
def test_no_invalid_memory_access_in_the_fmu_binary_up_to_process_exit(fmus, tmp_path):
    """pythonfmu 0.7.0's library released its interpreter state twice at exit (a use after
    free that sometimes corrupted the heap: the host aborted after a good run). The build
    removes that (build_pythonfmu.fix_exit_crash); memcheck sees every run, not just the
    unlucky ones: no invalid read, write or free inside the FMU's binaries, to the last exit
    handler."""
    import re

    log = tmp_path / "memcheck.log"
    run = subprocess.run(["valgrind", "--error-limit=no", "--num-callers=30",
                          f"--log-file={log}", sys.executable, "-m", "fmpy", "simulate",
                          str(fmus["WheelTerrain"]), "--start-values", "quasi_static", "true",
                          "load", "62", "--stop-time", "0.02",
                          "--output-file", str(tmp_path / "out.csv")],
                         capture_output=True, text=True, check=False,
                         env={**os.environ, "PYTHONMALLOC": "malloc"})
    assert run.returncode == 0, run.stderr[-2000:]
    text = log.read_text()
    assert "ERROR SUMMARY" in text  # memcheck ran to the end of the process
    blocks = re.split(r"\n==\d+== \n", text)
    bad = [b for b in blocks if re.search(r"== (Invalid (read|write|free)|Mismatched free)", b)
           and "binaries/linux64" in b]
    assert not bad, bad[0][:3000]


def test_impossible_operating_point_is_refused_with_the_capacity(fmus):
    t = terrain(fmus, quasi_static=True, load=5000.0)
    try:
        with pytest.raises(FMICallException) as info:
            t.fmu.doStep(0.0, 1e-3)
        assert info.value.status in (2, 3)
        assert any("exceeds what the wheel can carry" in m for m in t.errors()), t.log
    finally:
        t.close()


def test_bad_rig_parameter_is_refused(fmus):
    r = rig(fmus)
    try:
        with pytest.raises(FMICallException):  # fmi2Error from the guard library
            r.set({"rig.mass": -1.0})
        with pytest.raises(FMICallException):
            r.fmu.doStep(0.0, 1e-3)
        assert any("rig.mass" in m for m in r.errors())
    finally:
        r.close()


def test_wheelterrain_ships_and_uses_the_compiled_model(fmus):
    from wheelterrain import compiled as native

    if native.compiler() is None:
        pytest.skip("no C compiler: the FMU is built for the CasADi VM")
    t = Instance(fmus["WheelTerrain"], fmus["unzip"]["WheelTerrain"], "c", log=True).start()
    try:
        assert any("evaluated by compiled C" in m for _, m in t.log), t.log
    finally:
        t.close()


@pytest.mark.parametrize(("drive", "carriage"), [(1, 0), (2, 1)])
def test_rig_command_inputs_and_free_carriage_follow_rig_step(fmus, drive, carriage):
    """The controller's test bench: rig.drive / rig.carriage switch the FMU to the command inputs
    and the free carriage, step for step as wheelterrain.model.rig.step."""
    from wheelterrain.model import rig as rig_model

    values = {"rig.drive": drive, "rig.carriage": carriage, "rig.towing_force": 2.0}
    r = rig(fmus, f"modes{drive}{carriage}", **values)
    p = {**rig_model.defaults(), **values}
    x = rig_model.initial_state(p)
    for k in range(50):
        u = (55.0 + k, 3.0 - 0.1 * k, 0.4, 0.8 - 0.002 * k, 0.45)
        r.set(dict(zip(rig_model.INPUTS, u, strict=True)))
        r.fmu.doStep(k * 1e-3, 1e-3)
        x, torque = rig_model.step(x, u, p, 1e-3)
        got = r.get(("sinkage", "sinkage_rate", "wheel_speed", "speed_error_integral",
                    "carriage_speed", "motor_torque"))
        assert got == pytest.approx([*x, torque], rel=1e-12, abs=1e-15)
    r.close()


FREE_AFTER_INSTANTIATE = """
import sys
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
md = read_model_description(sys.argv[1])
fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(sys.argv[1]),
                modelIdentifier=md.coSimulation.modelIdentifier, instanceName="x")
fmu.instantiate()
fmu.freeInstance()
print("freed")
"""


@pytest.mark.parametrize("name", NAMES)
def test_free_right_after_instantiate_does_not_crash_the_host(fmus, name):
    """fmi2FreeInstance straight after fmi2Instantiate killed the host with SIGSEGV (5 of 5
    runs) while a message logged at instantiation was still queued in pythonfmu; the slave
    now logs nothing before initialisation. Three fresh processes must each exit cleanly."""
    for _ in range(3):
        run = subprocess.run([sys.executable, "-c", FREE_AFTER_INSTANTIATE, str(fmus[name])],
                             capture_output=True, text=True, timeout=120, check=False)
        assert run.returncode == 0, (run.returncode, run.stderr[-2000:])
        assert "freed" in run.stdout


def test_an_unknown_value_reference_is_an_error_message_not_a_crash(fmus):
    """pythonfmu made an unknown value reference fmi2Fatal without a message, freed the
    Python side, and the third call crashed the host. Now the guard library answers fmi2Error
    with a logged reason (nothing is got or set), and the instance steps on."""
    t = terrain(fmus, "vr")
    try:
        for _ in range(3):
            with pytest.raises(FMICallException) as info:
                t.fmu.getReal([9999, t.vr["drawbar_pull"]])
            assert info.value.status == 3
            assert math.isfinite(t.value("drawbar_pull"))
        assert any("no variable of this type with value reference 9999" in m
                   for m in t.errors())
        with pytest.raises(FMICallException):
            t.fmu.setReal([9999, t.vr["sinkage"]], [1.0, 0.02])
        with pytest.raises(FMICallException):
            t.fmu.getInteger([t.vr["soil.phi"]])  # a Real asked as Integer
        with pytest.raises(FMICallException):
            t.fmu.setReal([t.vr["drawbar_pull"]], [1.0])  # an output
        assert any("drawbar_pull is computed by the model" in m for m in t.errors())
        t.fmu.doStep(0.0, 1e-3)
    finally:
        t.close()


@pytest.mark.parametrize("name", NAMES)
def test_a_non_ascii_unzip_path_runs(fmus, name, tmp_path):
    """pythonfmu decodes only %20 of the resource URI, so under a non-ASCII folder (which
    fmpy percent-encodes) it did not find its slave and crashed the host (SIGSEGV). The guard
    library decodes the URI whole. In a fresh process, so a crash fails the test."""
    script = ("import sys, math\nfrom fmpy import extract\n"
              "from wheelterrain.fmu.instance import Instance\n"
              "d = extract(sys.argv[1], unzipdir=sys.argv[2])\n"
              "with Instance(sys.argv[1], d, 'x') as i:\n"
              "    i.start({})\n    i.fmu.doStep(0.0, 1e-3)\n"
              "    print(i.get([sys.argv[3]])[0])\n")
    output = {"WheelTerrain": "normal_force", "SingleWheelRig": "carriage_speed"}[name]
    run = subprocess.run([sys.executable, "-c", script, str(fmus[name]),
                          str(tmp_path / "rover wheel ünï €"), output],
                         capture_output=True, text=True, timeout=120, check=False)
    assert run.returncode == 0, (run.returncode, run.stderr[-2000:])
    assert math.isfinite(float(run.stdout.split()[-1]))


def test_wrong_guid_is_refused_with_a_reason(fmus, capfd):
    """pythonfmu instantiated whatever GUID it was given; the guard library refuses."""
    from fmpy.fmi2 import FMU2Slave

    fmu = FMU2Slave(guid="{not-the-guid}", unzipDirectory=fmus["unzip"]["WheelTerrain"],
                    modelIdentifier="WheelTerrain", instanceName="g")
    with pytest.raises(Exception, match="Failed to instantiate"):
        fmu.instantiate()
    fmu.freeLibrary()
    assert "wrong GUID '{not-the-guid}' for WheelTerrain" in capfd.readouterr().out


CALLS_OUT_OF_ORDER = {
    # (what has been called, the call out of order)
    "doStep before initialisation": ("instantiated", lambda f: f.doStep(0.0, 1e-3)),
    "exit before enter": ("instantiated", lambda f: f.exitInitializationMode()),
    "enter twice": ("initialization", lambda f: f.enterInitializationMode()),
    "setupExperiment in initialisation": ("initialization",
                                          lambda f: f.setupExperiment(startTime=0.0)),
    "doStep in initialisation": ("initialization", lambda f: f.doStep(0.0, 1e-3)),
    "enter after initialisation": ("stepping", lambda f: f.enterInitializationMode()),
    "doStep after terminate": ("terminated", lambda f: f.doStep(0.0, 1e-3)),
    "terminate twice": ("terminated", lambda f: f.terminate()),
    "setReal after terminate": ("terminated", lambda f: f.setReal([30], [0.02])),
}


@pytest.mark.parametrize("case", list(CALLS_OUT_OF_ORDER))
def test_calls_out_of_order_are_refused_with_a_reason(fmus, case):
    """pythonfmu keeps no call sequence: each of these returned OK. The guard library
    answers fmi2Error and logs 'illegal call sequence'."""
    stage, call = CALLS_OUT_OF_ORDER[case]
    t = Instance(fmus["WheelTerrain"], fmus["unzip"]["WheelTerrain"], "seq", log=True)
    try:
        if stage != "instantiated":
            t.fmu.setupExperiment(startTime=0.0)
            t.fmu.enterInitializationMode()
        if stage in ("stepping", "terminated"):
            t.fmu.exitInitializationMode()
        if stage == "terminated":
            t.fmu.terminate()
        with pytest.raises(FMICallException) as info:
            call(t.fmu)
        assert info.value.status == 3
        assert any("illegal call sequence" in m for m in t.errors()), t.log
    finally:
        t.fmu.freeInstance()
        t._remove_unzip()


def test_another_models_state_is_refused_not_deserialised(fmus):
    """A serialized SingleWheelRig state given to WheelTerrain deserialised, and a later
    getReal crashed the host. Its bytes carry the model's GUID now; another's are refused."""
    t = terrain(fmus, "own")
    r = rig(fmus, "other")
    try:
        foreign = r.fmu.serializeFMUstate(r.fmu.getFMUstate())
        own = t.fmu.serializeFMUstate(t.fmu.getFMUstate())
        with pytest.raises(FMICallException):
            t.fmu.deSerializeFMUstate(foreign)
        assert any("not a state of WheelTerrain" in m for m in t.errors()), t.log
        t.fmu.setFMUstate(t.fmu.deSerializeFMUstate(own))  # its own still round-trips
        t.fmu.doStep(0.0, 1e-3)
        assert math.isfinite(t.value("normal_force"))
    finally:
        t.close()
        r.close()
