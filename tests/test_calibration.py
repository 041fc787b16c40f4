"""Calibration (wheelterrain calibrate): exact Jacobians, recovery of known parameters, bounds,
the preset file it writes."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner

from wheelterrain import model, presets
from wheelterrain.cli import main
from wheelterrain.fit import calibration
from wheelterrain.model.slip import traction_from_paper
from wheelterrain.parameters import DEG

SLIPS = {"C1": 0.0, "C2": 0.25, "C3": 0.5, "C4": 0.75}


def synthetic(ps):
    """Cases in the Table III format whose 'experiment' is the model itself at ``ps``."""
    rows = []
    for case, s in SLIPS.items():
        out = model.steady_state(ps, 62.0, traction_from_paper(s))
        rows.append({"case": case, "slip_paper": s,
                     "experiment": {"drawbar_pull": out["drawbar_pull"],
                                    "sinkage": out["sinkage"], "normal_force": 62.0}})
    return rows


def test_the_jacobian_is_the_derivative_of_the_residuals():
    base = presets.load("paper-table2-arc")
    names = ["soil.phi", "soil.k_phi", "soil.n1", "model.shear_radius_factor"]
    cases = calibration.paper_cases()
    x = np.array([30 * DEG, 400.0, 0.8, 0.5])
    _, J = calibration._residuals_and_jacobian(x, names, base, cases, 62.0)
    for k in range(len(names)):
        h = 1e-6 * max(abs(x[k]), 1.0)
        up, down = x.copy(), x.copy()
        up[k] += h
        down[k] -= h
        r_up, _ = calibration._residuals_and_jacobian(up, names, base, cases, 62.0, False)
        r_dn, _ = calibration._residuals_and_jacobian(down, names, base, cases, 62.0, False)
        np.testing.assert_allclose(J[:, k], (r_up - r_dn) / (2 * h), rtol=1e-6,
                                   atol=1e-6 * np.abs(J).max())


def test_fit_recovers_known_parameters_from_model_data():
    truth = presets.load("paper-table2-arc").with_values({"soil.phi": 35 * DEG,
                                                         "soil.k_phi": 600.0})
    data = synthetic(truth)
    result = calibration.fit(presets.load("paper-table2-arc"), ["soil.phi", "soil.k_phi"],
                             list(SLIPS), starts=3, data=data)
    assert result.values["soil.phi"] == pytest.approx(35 * DEG, rel=1e-6)
    assert result.values["soil.k_phi"] == pytest.approx(600.0, rel=1e-6)
    assert result.cost < 1e-12
    assert result.at_bound == []
    assert result.correlation is not None
    np.testing.assert_allclose(np.diag(result.correlation), 1.0)


def test_fit_to_the_paper_stays_in_the_plausible_ranges_and_flags_bounds():
    result = calibration.fit(presets.load("paper-table2-arc"), ["soil.phi", "soil.k_phi"], ["C2"],
                             starts=3)
    for name, value in result.values.items():
        lo, hi, _ = calibration.PLAUSIBLE[name]
        assert lo <= value <= hi
    # m = 2 residuals, p = 2 parameters: no residual variance, no standard errors
    assert result.standard_errors is None
    for name in result.at_bound:
        lo, hi, _ = calibration.PLAUSIBLE[name]
        assert math.isclose(result.values[name], lo) or math.isclose(result.values[name], hi)


def test_cli_writes_a_preset_with_provenance(tmp_path):
    out = tmp_path / "fit.json"
    run = CliRunner().invoke(main, ["calibrate", "--params", "soil.phi,soil.k_phi", "--cases",
                                    "C2", "--starts", "2", "--out", str(out), "--name", "c2"])
    assert run.exit_code == 0, run.output
    assert "held out C1" in run.output
    doc = json.loads(out.read_text())
    prov = doc["provenance"]
    assert prov["fitted_on"] == ["C2"]
    assert {"data", "protocol", "date_of_fit", "code_version"} <= set(prov)
    for name in ("soil.phi", "soil.k_phi"):
        assert "plausible_range" in prov["fitted"][name]
    ps = presets.load(str(out))
    assert ps["soil.phi"] == pytest.approx(prov["fitted"]["soil.phi"]["value"])


def test_written_preset_keeps_the_overrides_the_fit_ran_with(tmp_path):
    """A --set switch (here the soil-element shear) is part of the fitted model: the preset must
    reproduce the fit's residuals, not the base preset's model with the fitted values."""
    out = tmp_path / "fit.json"
    run = CliRunner().invoke(main, ["calibrate", "--preset", "paper-table2-arc", "--params",
                                    "soil.phi", "--cases", "C2",
                                    "--set", "model.shear_kinematics=1", "--set",
                                    "model.shear_radius_factor=0.5", "--starts", "1",
                                    "--out", str(out)])
    assert run.exit_code == 0, run.output
    doc = json.loads(out.read_text())
    assert doc["provenance"]["overrides"] == {"model.shear_kinematics": 1,
                                              "model.shear_radius_factor": 0.5}
    ps = presets.load(str(out))
    assert ps["model.shear_kinematics"] == 1
    err = calibration.errors_on(ps, ["C2"])["C2"]["drawbar_pull"]
    assert err == pytest.approx(doc["provenance"]["residuals"]["C2"]["drawbar_pull"], abs=1e-9)


@pytest.mark.parametrize(("args", "needle"), [
    (["--params", "soil.gamma"], "cannot be calibrated"),
    (["--params", "soil.phi", "--cases", "C9"], "unknown case"),
    (["--params", "soil.phi", "--outputs", "normal_force"], "give one or both of drawbar_pull"),
    (["--params", "soil.phi", "--outputs", "sinkage,sinkage"], "each once"),
])
def test_cli_refuses_bad_requests(args, needle):
    run = CliRunner().invoke(main, ["calibrate", *args])
    assert run.exit_code == 2
    assert needle in run.output


def test_profile_finds_the_true_value_and_brackets_it():
    truth = presets.load("paper-table2-arc").with_values({"soil.phi": 35 * DEG,
                                                         "soil.k_phi": 600.0})
    data = synthetic(truth)
    names = ["soil.phi", "soil.k_phi"]
    best = {"soil.phi": 35 * DEG, "soil.k_phi": 600.0}
    points = calibration.profile(presets.load("paper-table2-arc"), names, list(SLIPS), best,
                                 "soil.phi", points=6, data=data)  # 25, 30, ..., 50 deg
    values = [v for v, _ in points]
    ssr = [s for _, s in points]
    assert values[int(np.argmin(ssr))] == pytest.approx(35 * DEG)
    assert min(ssr) < 1e-10
    lo, hi = calibration.profile_interval(points, 0.0)
    assert lo <= 35 * DEG <= hi


def test_diagnostic_bounds_let_a_fit_leave_the_plausible_box():
    """Data made at K = 80 mm (beyond the plausible 40 mm): the plausible fit stops at the bound
    and flags it; with the bound widened for diagnosis the fit recovers the value."""
    base = presets.load("rashid-calibrated")
    data = synthetic(base.with_values({"soil.shear_modulus": 0.08}))
    boxed = calibration.fit(base, ["soil.shear_modulus"], list(SLIPS), starts=1, data=data)
    assert boxed.values["soil.shear_modulus"] == pytest.approx(0.04)
    assert boxed.at_bound == ["soil.shear_modulus"]
    wide = calibration.fit(base, ["soil.shear_modulus"], list(SLIPS), starts=1, data=data,
                           bounds={"soil.shear_modulus": (0.002, 0.1)})
    assert wide.values["soil.shear_modulus"] == pytest.approx(0.08, rel=1e-6)
    assert wide.bounds["soil.shear_modulus"] == (0.002, 0.1)


def test_a_fit_to_one_output_recovers_what_that_output_determines():
    """Sinkage data alone pin k_phi' (phi fixed at the truth); both outputs are reported."""
    base = presets.load("paper-table2-arc").with_values({"soil.phi": 35 * DEG})
    data = synthetic(base.with_values({"soil.k_phi": 600.0}))
    result = calibration.fit(base, ["soil.k_phi"], list(SLIPS), starts=2, data=data,
                             outputs=("sinkage",))
    assert result.outputs == ("sinkage",)
    assert result.values["soil.k_phi"] == pytest.approx(600.0, rel=1e-6)
    assert set(result.residuals["C2"]) == {"drawbar_pull", "sinkage"}
    assert abs(result.residuals["C2"]["drawbar_pull"]) < 1e-6


def test_a_pull_only_fit_matches_the_pull_at_least_as_well_as_the_joint_fit():
    """Started from the joint optimum, the pull-only fit can only lower the pull's squares; the
    sinkage it leaves is reported, not fitted."""
    base = presets.load("rashid-calibrated")
    names = ["soil.phi", "soil.k_phi", "soil.cohesion"]
    joint = calibration.fit(base, names, list(SLIPS), starts=1)
    pull = calibration.fit(base, names, list(SLIPS), starts=1, initial=joint.values,
                           outputs=("drawbar_pull",))

    def squares(fit, key):
        return sum(r[key] ** 2 for r in fit.residuals.values())

    assert squares(pull, "drawbar_pull") <= squares(joint, "drawbar_pull") + 1e-9
    assert pull.cost == pytest.approx(squares(pull, "drawbar_pull") / 2, rel=1e-9)
    assert squares(pull, "sinkage") > 0


def test_least_absolute_loss_ignores_one_bad_case_that_least_squares_follows():
    """Pull data from the model at phi = 35 deg with C3 off by 5 N: the soft-L1 fit (scale far
    below the residuals, ~ least absolute error) keeps phi, least squares is pulled away."""
    base = presets.load("paper-table2-arc")
    data = synthetic(base.with_values({"soil.phi": 35 * DEG}))
    data[2]["experiment"]["drawbar_pull"] += 5.0
    kwargs = {"starts": 1, "data": data, "outputs": ("drawbar_pull",),
              "initial": {"soil.phi": 30 * DEG}}
    robust = calibration.fit(base, ["soil.phi"], list(SLIPS), loss="soft_l1", loss_scale=1e-4,
                             **kwargs)
    squares = calibration.fit(base, ["soil.phi"], list(SLIPS), **kwargs)
    assert robust.values["soil.phi"] == pytest.approx(35 * DEG, rel=1e-4)
    assert abs(squares.values["soil.phi"] - 35 * DEG) > 100 * abs(robust.values["soil.phi"]
                                                                   - 35 * DEG)
    assert robust.residuals["C3"]["drawbar_pull"] == pytest.approx(-5.0, abs=1e-2)
    assert robust.standard_errors is None  # they assume squares


@pytest.mark.parametrize(("loss", "scale"), [("cauchy", 1.0), ("soft_l1", 0.0)])
def test_an_unsupported_loss_is_refused(loss, scale):
    with pytest.raises(calibration.CalibrationError, match="give 'linear' or 'soft_l1'"):
        calibration.fit(presets.load("paper-table2-arc"), ["soil.phi"], ["C2"], loss=loss,
                        loss_scale=scale)
