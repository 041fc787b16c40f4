"""The CLI contract (README, "Contract"): `params --json`, `steady --json`, errors, exit codes."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import pytest
from click.testing import CliRunner

from wheelterrain import model, presets
from wheelterrain.cli import main
from wheelterrain.model import solve
from wheelterrain.parameters import NAMES, ROWS

STEADY_KEYS = {"sinkage", "drawbar_pull", "normal_force", "torque", "slip", "slip_paper",
               "entry_angle", "exit_angle"}


def run(*args: str):
    return CliRunner().invoke(main, list(args))


def test_params_json_lists_every_parameter_with_the_contract_fields():
    result = run("params", "--preset", "paper-table2", "--json")
    assert result.exit_code == 0, result.output
    rows = json.loads(result.output)
    # the wheel and soil first, then the rig's, the rover's and the terrain map's rows
    assert [r["name"] for r in rows] == [*NAMES, *(p.name for p in ROWS if p.name not in NAMES)]
    assert {r["fmu"] for r in rows} == {"WheelTerrain", "SingleWheelRig", "RoverChassis",
                                        "Terrain"}
    assert any(r["name"] == "rover.gravity" for r in rows)
    for row in rows:
        assert {"name", "unit", "value", "min", "max", "description", "source"} <= set(row)
        assert row["min"] <= row["value"] <= row["max"]
    by_name = {r["name"]: r for r in rows}
    assert by_name["soil.phi"]["value"] == pytest.approx(math.radians(23))
    assert by_name["wheel.width"]["value"] == 0.075


def test_params_human_table_shows_readings():
    result = run("params", "--preset", "paper-table1")
    assert result.exit_code == 0
    assert "soil.phi" in result.output
    assert "28 deg" in result.output
    assert "readings of the source's symbols" in result.output


def test_steady_json_holds_the_contract_keys_and_matches_the_library():
    result = run("steady", "--preset", "paper-table2", "--slip", "0.25", "--slip-definition",
                 "paper", "--load", "62", "--json")
    assert result.exit_code == 0, result.output
    out = json.loads(result.output)
    assert set(out) >= STEADY_KEYS
    assert out["slip_paper"] == pytest.approx(0.25)
    assert out["slip"] == pytest.approx(0.2)
    lib = model.steady_state(presets.load("paper-table2"), 62.0, 0.2)
    for key in ("sinkage", "drawbar_pull", "normal_force", "torque"):
        assert out[key] == lib[key]


def test_set_overrides_by_table_name_and_accepts_degrees():
    t2 = ("--preset", "paper-table2", "--slip", "0.2", "--load", "62", "--json")  # phi 23 deg
    a = json.loads(run("steady", *t2, "--set", "soil.phi=30deg").output)
    b = json.loads(run("steady", *t2, "--set", f"soil.phi={math.radians(30)!r}").output)
    base = json.loads(run("steady", *t2).output)
    assert a["drawbar_pull"] == pytest.approx(b["drawbar_pull"], rel=1e-12)
    assert a["drawbar_pull"] > base["drawbar_pull"]  # more friction, more pull


@pytest.mark.parametrize(("args", "code", "needle"), [
    (["--set", "soil.phii=0.4"], 2, "soil.phii is not a parameter; did you mean soil.phi"),
    (["--set", "soil.phi=nan"], 2, "soil.phi = nan must be finite; valid range [0, 1.0472] rad"),
    (["--set", "wheel.width=-0.1"], 2, "wheel.width = -0.1 is out of range; valid range"),
    (["--set", "soil.phi=90deg"], 2, "([0, 60] deg)"),
    (["--set", "soil.phi"], 2, "is not of the form NAME=VALUE"),
    (["--set", "model.shear_model=0.5"], 2, "must be a whole number"),
    (["--load", "-1"], 2, "input load = -1.0 is out of range"),
    (["--load", "nan"], 2, "input load = nan must be finite"),
    (["--load", "inf"], 2, "input load = inf must be finite"),
    (["--slip", "1.5"], 2, "input slip = 1.5 is out of range; valid range (-inf, 1]"),
    (["--slip", "-1.2", "--slip-definition", "paper"], 2, "valid range [-1, inf)"),
    (["--slip", "-1.2", "--slip-definition", "unified"], 2, "valid range [-1, 1]"),
    (["--load", "1000"], 3, "exceeds what the wheel can carry even fully buried"),
    (["--preset", "nope"], 2, "is neither a preset"),
])
def test_bad_input_exits_nonzero_naming_the_problem(args, code, needle):
    base = {"--slip": "0.2", "--load": "62"}
    for i in range(0, len(args) - 1):
        base.pop(args[i], None)
    argv = ["steady"] + [x for kv in base.items() for x in kv] + args
    result = run(*argv)
    assert result.exit_code == code, result.output
    assert needle in result.output


def test_console_script_runs_as_installed():
    out = subprocess.run([sys.executable, "-m", "wheelterrain.cli", "steady", "--slip", "0",
                          "--load", "62", "--json"], capture_output=True, text=True, check=True)
    assert json.loads(out.stdout)["normal_force"] == pytest.approx(62.0, rel=1e-12)


def test_solve_error_is_a_clear_numerical_failure(monkeypatch):
    """A non-converged solve is refused with exit code 4 and the residual, never printed as data."""
    monkeypatch.setattr(solve, "RESIDUAL_TOLERANCE", -1.0)  # no residual can pass now
    monkeypatch.setattr(solve, "STEP_TOLERANCE", -1.0)  # nor any step
    result = run("steady", "--slip", "0.3", "--load", "62", "--json")
    assert result.exit_code == 4
    assert "did not converge" in result.output
    assert "relative residual" in result.output
