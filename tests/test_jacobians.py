"""Exact CasADi Jacobians agree with central finite differences (step 1e-6, relative 1e-6)."""

from __future__ import annotations

import numpy as np
import pytest

from wheelterrain import model
from wheelterrain.model import functions as model_functions
from wheelterrain.model import solve
from wheelterrain.parameters import INDEX, NAMES, TABLE

STEP = 1e-6
RTOL = 1e-6

# A point where every extension is on and every derivative is finite and smooth: exit ratio > 0
# (d theta_r / d lambda is infinite at lambda = 0), slip != 0 (|i| has a kink), a ripple phase
# where sigma + ripple > 0 on the whole arc (max(., 0) inactive), hump shear.
POINT = {
    "model.exit_ratio": 0.6, "model.shear_model": 1, "model.contact_radius_factor": 0.5,
    "model.shear_radius_factor": 0.7, "model.slip_radius_factor": 0.2, "soil.cohesion": 500.0,
    "soil.residual_ratio": 0.7,
    # the cross-wheel mechanisms on, away from their exact-reduction values
    "model.shear_length_ratio": 0.4, "model.interface_ratio": 0.7,
    "model.grouser_shear_height": 0.005, "model.diameter_exponent": -0.3,
    "model.bulldozing": 0.5,
    # the wheel in a rut (soil memory on): below every sinkage of the test, and deeper than the
    # rut's elastic layer, so that no node crosses the reloading line's kink
    "soil.rut_depth": 0.001,
}
KEPT = 1.2e3
"""Pa: the pressure the rut keeps in half the points (soil.rut_pressure; the law reads ~0.8 kPa
from the rut's depth at this point); the other half read it from the depth (0)."""
SWITCH = INDEX["soil.rut_pressure"]
"""soil.rut_pressure = 0 is a switch (not known: read from the depth), not the limit of a kept
pressure: there the exact Jacobians give the reading's derivative, 0 for this column."""


@pytest.fixture(scope="module", params=[(0, 0, KEPT), (1, 0, 0.0), (0, 1, KEPT), (1, 1, 0.0)],
                ids=["arc-wheel-element-j-kept", "arc-soil-element-j", "patch-wheel-element-j-kept",
                     "patch-soil-element-j"])
def point_params(table2, request):
    kinematics, form, kept = request.param
    return table2.with_values({**POINT, "model.shear_kinematics": kinematics,
                               "model.contact_form": form, "soil.rut_pressure": kept})


def _at_the_switch(p: np.ndarray, analytic: np.ndarray, numeric: np.ndarray) -> None:
    """Where the rut's pressure is not known (0), its column is no derivative: the exact one is
    0 (checked here), the differences straddle the switch (left out of the comparison)."""
    if p[SWITCH] == 0:
        assert np.all(analytic[:, SWITCH] == 0)
        numeric[:, SWITCH] = 0.0


def _scales(p: np.ndarray) -> np.ndarray:
    """Finite-difference step per parameter: relative to its size, absolute for zeros."""
    return np.array([max(abs(v), 1e-2 * (t.max - t.min), 1e-3) for v, t in
                     zip(p, TABLE, strict=True)])


def _check(name: str, analytic: np.ndarray, numeric: np.ndarray, out_scale: np.ndarray) -> None:
    """Compare derivatives already scaled to a change of one input scale (columns), within RTOL of
    the larger of the derivative and the output's size (rows)."""
    where = np.argwhere(~np.isfinite(analytic))
    assert not where.size, f"{name}: not finite at {where[:3].tolist()}"
    tol = RTOL * np.maximum(np.abs(analytic), out_scale[:, None])
    bad = ~(np.abs(analytic - numeric) <= tol)  # a NaN on either side fails
    if bad.any():
        r, c = np.argwhere(bad)[0]
        raise AssertionError(f"{name}[{r},{c}]: AD {analytic[r, c]!r} vs FD {numeric[r, c]!r}")


@pytest.mark.parametrize("slip", [0.05, 0.3, 0.8, -0.4])
@pytest.mark.parametrize("sinkage", [0.002, 0.02, 0.05])
def test_contact_jacobian_matches_central_differences(point_params, slip, sinkage):
    fns = model_functions.build()
    p = point_params.vector()
    x = np.array([sinkage, 0.01, slip])
    angle = 0.13 / 12 * 2 * np.pi  # ripple near its crest: sigma + ripple > 0 everywhere

    def forces(x_, p_):
        out = fns.contact(x_[0], x_[1], x_[2], angle, p_)
        return np.array([float(out[0]), float(out[1]), float(out[2])])

    d_state, d_params = (np.array(m) for m in fns.contact_jacobian(x[0], x[1], x[2], angle, p))
    f0 = forces(x, p)
    x_scale = np.array([sinkage, 0.01, 1.0])  # m, m/s, slip
    num_state = np.column_stack([
        (forces(x + STEP * s * e, p) - forces(x - STEP * s * e, p)) / (2 * STEP * s)
        for s, e in zip(x_scale, np.eye(3), strict=True)])
    _check("d_state", d_state * x_scale, num_state * x_scale, np.abs(f0))

    h = STEP * _scales(p)
    num_params = np.column_stack([
        (forces(x, p + hk * e) - forces(x, p - hk * e)) / (2 * hk)
        for hk, e in zip(h, np.eye(len(p)), strict=True)])
    _at_the_switch(p, d_params, num_params)
    # scale columns: derivative per relative change of the parameter, compared on |force|
    _check("d_params", d_params * _scales(p), num_params * _scales(p), np.abs(f0))


@pytest.mark.parametrize("slip", [0.05, 0.3, 0.8])
@pytest.mark.parametrize("load", [5.0, 30.0, 62.0])
def test_steady_jacobian_matches_central_differences(point_params, slip, load):
    fns = model_functions.build()
    p = point_params.vector()
    keys = ("sinkage", "normal_force", "drawbar_pull", "torque")

    def steady(load_, slip_, p_):
        out = dict(zip(solve.STEADY_OUTPUTS, fns.steady(load_, slip_, p_), strict=True))
        return np.array([float(out[k]) for k in keys])

    jac = model.steady_jacobian(point_params, load, slip)
    y0 = steady(load, slip, p)
    num_inputs = np.column_stack([
        (steady(load + STEP * load, slip, p) - steady(load - STEP * load, slip, p))
        / (2 * STEP * load),
        (steady(load, slip + STEP, p) - steady(load, slip - STEP, p)) / (2 * STEP)])
    _check("d_inputs", jac["d_inputs"] * [load, 1.0], num_inputs * [load, 1.0], np.abs(y0))
    h = STEP * _scales(p)
    num_params = np.column_stack([
        (steady(load, slip, p + hk * e) - steady(load, slip, p - hk * e)) / (2 * hk)
        for hk, e in zip(h, np.eye(len(p)), strict=True)])
    _at_the_switch(p, jac["d_params"], num_params)
    _check("d_params", jac["d_params"] * _scales(p), num_params * _scales(p), np.abs(y0))


def test_jacobians_cover_every_soil_parameter():
    """The params Jacobian has one column per table row, in table order."""
    fns = model_functions.build()
    assert fns.contact_jacobian.size_out("d_params") == (3, len(NAMES))
    assert fns.steady_jacobian.size_out("d_params") == (4, len(NAMES))
    assert fns.steady_jacobian.size_out("d_inputs") == (4, 2)


@pytest.mark.parametrize("name", ["paper-table2-arc", "rashid-patch", "paper-table2",
                                  "rashid-calibrated", "paper-table1"])
@pytest.mark.parametrize("slip", [0.0, 0.3, -0.3])
def test_every_parameter_column_is_finite_on_virgin_soil(name, slip):
    """The calibration's Jacobians at the presets as shipped (virgin soil, rut_shear off): the
    columns of wheel.radius, grouser.height and model.contact_radius_factor were NaN in reverse
    mode (the rut maker's angle, 0 there, took the square root of 0), and the check above let a
    NaN pass (NaN > tol is false); the model-form study's fit stopped on it."""
    from wheelterrain import presets

    ps = presets.load(name)
    state = model.steady_state(ps, 40.0, slip)
    fns = model_functions.build()
    d_contact = np.asarray(fns.contact_jacobian(state["sinkage"], 0.0, state["slip"], 0.3,
                                                ps.vector())[1])
    d_steady = np.asarray(fns.steady_jacobian(40.0, state["slip"], ps.vector(),
                                              state["sinkage"])[1])
    for label, d in (("contact", d_contact), ("steady", d_steady)):
        bad = [NAMES[c] for c in range(d.shape[1]) if not np.all(np.isfinite(d[:, c]))]
        assert not bad, f"{label} Jacobian not finite by {bad}"
