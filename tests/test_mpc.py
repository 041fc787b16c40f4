"""The slip-control NMPC (issue 5): its derivatives, the stiffness that chose the speed command,
the closed loop against the FMU plant and against the same Functions in process."""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys

import numpy as np
import pytest
from click.testing import CliRunner

from wheelterrain import compiled as native
from wheelterrain import model, presets
from wheelterrain.cli import main
from wheelterrain.control import closed_loop, mpc
from wheelterrain.cosim import master as cosim
from wheelterrain.model import rig
from wheelterrain.parameters import INDEX, NAMES, TABLE

# The tracking gates are the controller's on the plant it is designed for: the soil without
# memory (the prediction's). On the default soil with memory the grouser ripple digs the
# wheel in, a disturbance the prediction does not model (test below, docs/mpc.md).
ELASTIC = {"model.soil_memory": 0}
PS = presets.load(presets.DEFAULT_PRESET).with_values(ELASTIC)
PT = np.array([PS[name] for name in NAMES])


def rig_params(slip_paper=0.25, drive=rig.DRIVE_SPEED):
    p = cosim.rig_parameters(PS, slip_paper, 62.0, 0.03)
    p["rig.drive"] = drive
    return p


def operating_state(slip_paper):
    """Steady sinkage at the case's slip, the wheel at the speed giving it."""
    p = rig_params(slip_paper)
    omega, speed = rig.references(p)
    steady = model.steady_state(PS, load=62.0, slip=slip_paper / (1 + slip_paper))
    _, ki = rig.gains(p)
    return np.array([steady["sinkage"], 0.0, omega, steady["torque"] / ki, speed, 0.3]), p


def test_interval_jacobian_matches_central_differences():
    """What the NLP differentiates: the backward-Euler interval residual with respect to the
    states at both ends, the command and every soil parameter, against central differences
    (step 1e-6 of each input's scale) within 1e-6 relative: each derivative is taken per unit
    of its input's scale and compared on the larger of itself and its row's state scale, the
    convention of tests/test_jacobians.py."""
    fn = mpc.interval_residual()
    x0, p = operating_state(0.5)
    pr = np.array([p[name] for name in rig.RIG_NAMES])
    x1 = x0 + np.array([2e-4, 1e-3, 0.01, 1e-5, 0.0, 0.01])
    args = [x0, x1, 0.95, PT, pr, 0.02]
    blocks = fn.jacobian()(*args, *fn(*args))
    state_scale = np.array([1e-2, 1e-2, 1.0, 1e-2, 1e-2, 1.0])
    input_scales = {0: state_scale, 1: state_scale, 2: np.array([1.0]),
                    3: np.array([max(abs(v), 1e-2 * (t.max - t.min), 1e-3)
                                 for v, t in zip(PT, TABLE, strict=True)])}
    for arg, scales in input_scales.items():
        analytic = np.array(blocks[arg]).reshape(len(mpc.MPC_STATES), -1) * scales
        base = np.atleast_1d(np.asarray(args[arg], dtype=float))
        numeric = np.zeros_like(analytic)
        for j in range(base.size):
            plus, minus = base.copy(), base.copy()
            plus[j] += 1e-6 * scales[j]
            minus[j] -= 1e-6 * scales[j]
            values = []
            for shifted in (plus, minus):
                a = list(args)
                a[arg] = shifted if base.size > 1 else shifted[0]
                values.append(np.array(fn(*a)[0]).ravel())
            numeric[:, j] = (values[0] - values[1]) / 2e-6
        tol = 1e-6 * np.maximum(np.abs(analytic), state_scale[:, None])
        if arg == 3:  # soil.rut_depth = 0 (virgin soil) is a kink: the Jacobians report the
            # virgin branch's 0 (contact.rut's note); central differences straddle it
            kink = INDEX["soil.rut_depth"]
            assert PT[kink] == 0.0
            assert np.all(analytic[:, kink] == 0.0)
            tol[:, kink] = np.inf
        bad = np.argwhere(np.abs(analytic - numeric) > tol)
        assert bad.size == 0, (f"input {arg}, entry {bad[0]}: AD {analytic[tuple(bad[0])]!r} "
                               f"vs FD {numeric[tuple(bad[0])]!r}")


@pytest.mark.slow
@pytest.mark.skipif(native.compiler() is None, reason="no C compiler")
def test_compiled_interval_and_jacobian_equal_the_vm(tmp_path, monkeypatch):
    monkeypatch.setenv("WHEELTERRAIN_CACHE", str(tmp_path))
    mpc.compiled_interval.cache_clear()
    try:
        compiled, vm = mpc.compiled_interval(), mpc.interval_residual()
        x0, p = operating_state(0.25)
        pr = np.array([p[name] for name in rig.RIG_NAMES])
        args = [x0, x0 * 1.01, 0.62, PT, pr, 0.02]
        for a, b in zip(compiled(*args), vm(*args), strict=True):
            np.testing.assert_allclose(np.array(a), np.array(b), rtol=1e-12, atol=1e-14)
        jac = compiled.jacobian()
        blocks = dict(zip(jac.name_out(), jac(*args, *compiled(*args)), strict=True))
        for name, b in zip(vm.jacobian().name_out(), vm.jacobian()(*args, *vm(*args)),
                           strict=True):
            if name.endswith(("_x0", "_x1", "_command")):  # what the NLP differentiates by
                np.testing.assert_allclose(np.array(blocks[name]), np.array(b), rtol=1e-10,
                                           atol=1e-12, err_msg=name)
            else:  # parameters: declared non-differentiable, no block compiled
                assert jac.sparsity_out(name).nnz() == 0, name
    finally:
        mpc.compiled_interval.cache_clear()


def test_stiffness_is_why_the_mpc_commands_speed():
    """Torque-driven, the wheel has modes far faster than a 20 ms interval (1/0.02 s = 50 1/s;
    measured -152 1/s at C4 on rashid-calibrated); under the drive's speed loop every mode is
    stable. (The earlier, wheel-element calibration also had an unstable pair at C4: mpc.py.)"""
    x, p = operating_state(0.75)
    torque_driven = mpc.stiffness(PT, {**p, "rig.drive": rig.DRIVE_TORQUE}, x, 1.8)
    assert torque_driven.real.min() < -100
    speed_driven = mpc.stiffness(PT, p, x, x[2])
    assert speed_driven.real.max() < 0


def test_settings_out_of_range_are_named():
    with pytest.raises(mpc.MPCError, match=r"horizon = 0 .*\[1, 500\]"):
        mpc.Settings(horizon=0).check()
    with pytest.raises(mpc.MPCError, match=r"solver = 'osqp'.*sqpmethod, ipopt"):
        mpc.Settings(solver="osqp").check()
    with pytest.raises(mpc.MPCError, match=r"rig\.drive"):
        mpc.Controller(mpc.Settings(), rig_params(drive=rig.DRIVE_PAPER))


@pytest.fixture(scope="module")
def nominal_runs(fmu_dir):
    scenario = closed_loop.SCENARIOS["nominal"]
    return scenario, {plant: closed_loop.run(scenario, PS, plant, fmu_dir=fmu_dir)
                      for plant in ("fmu", "casadi")}


def test_fmu_plant_and_in_process_plant_agree(nominal_runs):
    """Same Functions, same coupling: the two loops agree to 1e-6 (measured: bit-identical)."""
    _, runs = nominal_runs
    a, b = runs["fmu"].series, runs["casadi"].series
    for name in ("slip", "command", "motor_torque", "sinkage", "drawbar_pull", "normal_force"):
        scale = max(np.max(np.abs(b[name])), 1e-12)
        assert np.max(np.abs(a[name] - b[name])) / scale <= 1e-6, name


def test_nominal_tracking_on_the_fmu_plant(nominal_runs):
    scenario, runs = nominal_runs
    figures = runs["fmu"].figures(scenario)
    assert figures["failed_solves"] == 0
    assert figures["slip_rms_error"] <= 5e-4, figures


def test_terrain_change_is_estimated_and_tracked():
    scenario = closed_loop.SCENARIOS["terrain-change"]
    result = closed_loop.run(scenario, PS, "casadi")
    figures = result.figures(scenario)
    assert figures["phi_relative_error_final"] < 1e-3, figures
    assert figures["k_phi_relative_error_final"] < 1e-3, figures
    assert figures["slip_rms_error"] <= 5e-3, figures
    # qrqp cycled to its iteration limit in 3 of these solves with its default dual tolerance
    assert figures["failed_solves"] == 0, figures


def test_on_the_soil_with_memory_the_loop_holds_and_misses_the_goal_by_the_ratchet():
    """The default soil remembers: the grouser ripple's ratchet perturbs the torque the wheel
    needs at every grouser, which the memoryless prediction does not foresee. The loop stays
    closed (every solve succeeds), with the slip error after the transients measured at
    6.3e-3 RMS: the nominal goal, 5e-4, is not met there (docs/mpc.md)."""
    scenario = closed_loop.SCENARIOS["nominal"]
    ps = presets.load(presets.DEFAULT_PRESET)
    assert ps["model.soil_memory"] == 1
    result = closed_loop.run(scenario, ps, "casadi")
    figures = result.figures(scenario)
    assert figures["failed_solves"] == 0
    assert 5e-4 < figures["slip_rms_error"] < 1e-2, figures


@pytest.mark.parametrize("solver", ["sqpmethod", "rti"])
def test_predicting_with_the_soils_memory_meets_the_nominal_goal(solver):
    """Settings.memory: the plant's plastic sinkage a state of the prediction (the yield
    smoothed over YIELD_WIDTH) foresees the ratchet: on the default soil, which remembers, the
    nominal slip error after the transients falls to 4.1e-4 RMS (measured 2026-11-28, both
    solvers; 6.3e-3 without), under the goal 5e-4, every solve succeeding. In-sample: the
    smoothing width (mpc.YIELD_WIDTH) was chosen on this scenario."""
    scenario = closed_loop.SCENARIOS["nominal"]
    ps = presets.load(presets.DEFAULT_PRESET)
    result = closed_loop.run(scenario, ps, "casadi", mpc.Settings(solver=solver, memory=True))
    figures = result.figures(scenario)
    assert figures["memory"] is True
    assert figures["failed_solves"] == 0, figures
    assert figures["slip_rms_error"] <= 5e-4, figures


def test_free_carriage_tracks_while_the_vehicle_moves():
    scenario = dataclasses.replace(closed_loop.SCENARIOS["free-carriage"], duration=3.0)
    result = closed_loop.run(scenario, PS, "casadi")
    speed = result.series["carriage_speed"]
    assert np.ptp(speed) > 1e-4  # the carriage is a state, not held
    assert result.figures(scenario)["slip_rms_error"] <= 5e-4


@pytest.mark.parametrize("options", [["--iterations", "1"], ["--solver", "rti"]],
                         ids=["sqpmethod", "rti"])
def test_real_time_iteration_tracks_as_the_full_solve(tmp_path, options):
    """`wheelterrain mpc --iterations 1` (sqpmethod) and `--solver rti`: one SQP iteration
    per sample from the shifted warm start (the real-time iteration) tracks the nominal
    scenario within the same goal; the rti iteration reports every QP solved."""
    run = CliRunner().invoke(main, ["mpc", "--plant", "casadi", *options, "--set",
                                    "model.soil_memory=0", "--out", str(tmp_path), "--json",
                                    str(tmp_path / "f.json")])
    assert run.exit_code == 0, run.output
    figures = json.loads((tmp_path / "f.json").read_text())
    assert figures["iterations_median"] == 1
    assert figures["slip_rms_error"] <= 5e-4
    if "rti" in options:
        assert figures["failed_solves"] == 0


def test_rti_takes_sqpmethods_step():
    """Settings(solver="rti") condenses the states out of the same Gauss-Newton QP that
    sqpmethod solves with max_iterations = 1: from the same warm start, the same plan
    (measured: 6e-16 relative), reported as solved."""
    x, p = operating_state(0.25)
    plans = {}
    for solver in ("sqpmethod", "rti"):
        controller = mpc.Controller(mpc.Settings(solver=solver, max_iterations=1, horizon=10), p)
        step = controller.solve(x, PT, 0.3, x[2])
        plans[solver] = step.predicted
    assert step.success
    assert step.iterations == 1
    for name in ("command", "states"):
        a, b = plans["sqpmethod"][name], plans["rti"][name]
        scale = np.max(np.abs(a), axis=-1, keepdims=True)
        assert np.all(np.abs(a - b) <= 1e-9 * scale), name


def test_rti_reports_an_unsolvable_qp_and_keeps_the_plan():
    """A sinkage limit below the sinkage the wheel already has: no step satisfies it. The
    iteration says so (not solved, the violation named) and applies the shifted plan's first
    command, here the warm start's, instead of the QP solver's unfeasible point."""
    x, p = operating_state(0.25)
    controller = mpc.Controller(mpc.Settings(solver="rti", horizon=10, sinkage_limit=1e-3), p)
    step = controller.solve(x, PT, 0.3, x[2])
    assert not step.success
    assert "limits violated by" in step.status
    assert "shifted plan kept" in step.status
    assert step.command == pytest.approx(x[2], rel=1e-15)


def test_rti_needs_the_least_squares_objective():
    with pytest.raises(mpc.MPCError, match=r"objective = 'efficiency'.*track with solver 'rti'"):
        mpc.Settings(solver="rti", objective="efficiency").check()


def test_cli_refuses_rti_for_the_efficiency_scenario_before_running(tmp_path):
    run = CliRunner().invoke(main, ["mpc", "--plant", "casadi", "--solver", "rti",
                                    "--scenario", "efficiency", "--out", str(tmp_path)])
    assert run.exit_code == 2
    assert "track with solver 'rti'" in run.output
    assert "closed loop" not in run.output  # refused before the progress bar
    assert not list(tmp_path.iterdir())


def test_cli_choices_are_the_controllers_own_lists():
    """`wheelterrain mpc` spells its solver and scenario choices out (importing the controller
    would load CasADi for --help); they must stay the lists the controller accepts."""
    options = {param.name: param for param in main.commands["mpc"].params}
    assert tuple(options["solver"].type.choices) == mpc.SOLVERS
    assert set(options["scenario"].type.choices) == set(closed_loop.SCENARIOS)


def test_cli_refuses_iterations_with_rti(tmp_path):
    run = CliRunner().invoke(main, ["mpc", "--plant", "casadi", "--solver", "rti",
                                    "--iterations", "3", "--out", str(tmp_path)])
    assert run.exit_code == 2
    assert "--iterations 3 does not apply to --solver rti" in run.output


def test_cli_rejects_a_bad_interval_with_exit_code_2(tmp_path):
    run = CliRunner().invoke(main, ["mpc", "--plant", "casadi", "--interval", "0.0015",
                                    "--out", str(tmp_path)])
    assert run.exit_code == 2
    assert "interval = 0.0015 s is out of range" in run.output


def test_in_process_plant_refuses_a_wheel_turning_backward_with_the_fmus_sentence():
    """A wheel turning backward under a carriage moving forward is outside the model's domain
    (a locked wheel is inside it): the in-process plant says so in the words both FMU
    flavours use, naming both speeds."""
    ps = presets.load(presets.DEFAULT_PRESET)
    scenario = closed_loop.SCENARIOS["nominal"]
    plant = closed_loop.CasadiPlant(ps, closed_loop.rig_parameters(ps, scenario))
    z, z_rate, _, integral, _ = plant.x
    plant.x = (z, z_rate, -0.6, integral, 0.03)
    with pytest.raises(mpc.PlantError, match="refused the step") as err:
        plant.advance(0.5, 1, lambda *a: None)
    assert "wheel speed -0.6 rad/s with carriage speed 0.03 m/s" in str(err.value)
    assert "outside the model's domain" in str(err.value)


def test_the_default_solver_is_quiet(tmp_path):
    """`wheelterrain mpc` with the default solver printed 600-800 CasADi warnings ("nlp_grad
    failed: NaN detected for output grad_gamma_p") although every solve succeeded: the
    parameters' multipliers, which nothing uses, were computed from a gradient that is NaN where
    a parameter's derivative is not defined. Nothing but the progress bar on standard error."""
    run = subprocess.run([sys.executable, "-m", "wheelterrain.cli", "mpc", "--plant", "casadi",
                          "--out", str(tmp_path), "--json", "-"],
                         capture_output=True, text=True, timeout=600, check=False)
    assert run.returncode == 0, run.stderr[-2000:]
    assert "WARNING" not in run.stderr + run.stdout
    assert "NaN detected" not in run.stderr + run.stdout
    assert json.loads(run.stdout)["failed_solves"] == 0
