"""The FMU variables table (wheelterrain.fmu.variables) is the single source of every list of
FMU variable names: the derived lists match the faces that use them, and an output added to the
table alone reaches every face (both FMU flavours, the sweep, the SSP files, the units)."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from wheelterrain import compiled as native
from wheelterrain.cosim import ssp
from wheelterrain.cosim import sweep as sweeper
from wheelterrain.fmu import functions as fmu_model
from wheelterrain.fmu import variables
from wheelterrain.model import rig

ROOT = Path(__file__).resolve().parents[1]


def _parameters_used(functions) -> set[int]:
    """Indices of the ``p`` input that some output of ``functions`` depends on (structurally)."""
    import casadi as ca
    import numpy as np

    used: set[int] = set()
    for fn in functions:
        p = fn.index_in("p")
        for out in range(fn.n_out()):
            columns = np.asarray(ca.DM(fn.jac_sparsity(out, p), 1).full()).any(axis=0)
            used |= set(np.flatnonzero(columns).tolist())
    return used


def test_each_fmu_carries_only_parameters_its_model_uses():
    """An FMU parameter that no output depends on would be a promise the model does not keep
    (a user sets it and nothing happens): every terrain row reaches the terrain Functions,
    every rig row the rig Functions, whatever the switches select."""
    from wheelterrain.parameters import NAMES

    unused = set(range(len(NAMES))) - _parameters_used(fmu_model.terrain_functions())
    assert not unused, [NAMES[k] for k in sorted(unused)]
    unused = set(range(len(rig.RIG_NAMES))) - _parameters_used(fmu_model.rig_functions())
    assert not unused, [rig.RIG_NAMES[k] for k in sorted(unused)]


def test_the_derived_lists_are_the_ones_the_faces_use():
    assert variables.RIG_INPUTS == rig.INPUTS
    assert variables.COUPLED_FORCES == rig.FORCE_INPUTS
    assert variables.COUPLED_STATES == ("sinkage", "sinkage_rate", "wheel_speed",
                                        "carriage_speed")
    dynamic, quasi, _ = fmu_model.terrain_functions()
    for fn in (dynamic, quasi):
        assert fn.size1_in(0) == len(variables.TERRAIN_INPUTS)
        assert fn.size1_out(0) == len(variables.TERRAIN_OUTPUTS)
    step, outputs, _ = fmu_model.rig_functions()
    assert step.size1_in(1) == len(variables.RIG_INPUTS)
    assert outputs.size1_out(0) == len(variables.RIG_OUTPUTS)
    assert sweeper.OUTPUTS == variables.TERRAIN_OUTPUTS
    assert set(ssp.TERRAIN_OUTPUTS) == {v.name for v in variables.TERRAIN_IO
                                        if v.causality == "output"}
    names = [v.name for v in variables.VARIABLES["WheelTerrain"]()]
    assert names[-len(variables.TERRAIN_IO):] == [v.name for v in variables.TERRAIN_IO]


# the one line a user would add to the table: an output the contact model already computes
DUMMY = ('        Var("sinkage_exponent", "output", "Sinkage exponent n = n0 + n1*|i| (test '
         'row)", "1"),\n')
ANCHOR = '    ], (*_TERRAIN_INPUTS, *GROUND, "rut_pressure_met")),\n'

PROBE = r"""
import json, shutil, sys
from pathlib import Path
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
from wheelterrain import model, presets
from wheelterrain.cosim import ssp, sweep
from wheelterrain.fmu import build_native, build_pythonfmu, variables

out = Path(sys.argv[1])
build_pythonfmu.build(out / "pythonfmu")
build_native.build(out / "native")
ps = presets.load(presets.DEFAULT_PRESET)
values = {"sinkage": 0.015, "sinkage_rate": 0.0, "wheel_speed": 0.6, "carriage_speed": 0.02}
slip = (0.6 * ps["wheel.radius"] - 0.02) / (0.6 * ps["wheel.radius"])
result = {"expected": model.contact_forces(ps, 0.015, slip)["sinkage_exponent"],
          "sweep": "sinkage_exponent" in sweep.OUTPUTS,
          "ssp": "sinkage_exponent" in ssp.TERRAIN_OUTPUTS,
          "unit": variables.units().get("sinkage_exponent")}
for flavour in ("pythonfmu", "native"):
    path = str(out / flavour / "WheelTerrain.fmu")
    md = read_model_description(path)
    vr = {v.name: v for v in md.modelVariables}
    unzipped = extract(path)
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipped,
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="probe")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    fmu.setReal([vr[k].valueReference for k in values], list(values.values()))
    fmu.doStep(0.0, 1e-3)
    [got] = fmu.getReal([vr["sinkage_exponent"].valueReference])
    fmu.terminate()
    fmu.freeInstance()
    shutil.rmtree(unzipped, ignore_errors=True)
    result[flavour] = {"causality": vr["sinkage_exponent"].causality,
                       "unit": vr["sinkage_exponent"].unit, "value": got}
print(json.dumps(result))
"""


@pytest.mark.slow
@pytest.mark.skipif(native.compiler() is None, reason="no C compiler")
def test_an_output_added_to_the_table_alone_reaches_every_face(tmp_path):
    copy = tmp_path / "copy"
    shutil.copytree(ROOT / "src", copy / "src",
                    ignore=shutil.ignore_patterns("__pycache__", "_compiled", "*.egg-info"))
    shutil.copytree(ROOT / "fmu_src", copy / "fmu_src")
    table = copy / "src" / "wheelterrain" / "fmu" / "variables.py"
    text = table.read_text()
    assert text.count(ANCHOR) == 1
    table.write_text(text.replace(ANCHOR, DUMMY + ANCHOR))
    env = {**os.environ, "PYTHONPATH": str(copy / "src")}
    run = subprocess.run([sys.executable, "-c", PROBE, str(tmp_path / "fmus")], cwd=tmp_path,
                         env=env, capture_output=True, text=True, check=False, timeout=900)
    assert run.returncode == 0, run.stderr[-3000:]
    result = json.loads(run.stdout.strip().splitlines()[-1])
    assert result["sweep"]
    assert result["ssp"]
    assert result["unit"] == "1"
    for flavour in ("pythonfmu", "native"):
        assert result[flavour]["causality"] == "output"
        assert result[flavour]["unit"] == "1"
        assert result[flavour]["value"] == pytest.approx(result["expected"], rel=1e-12)
    assert result["expected"] > 1.0  # n0 + n1*|i| of the default preset, a real number
