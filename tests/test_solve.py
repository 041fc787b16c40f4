"""The sinkage solve's shortcuts: the bound that prunes the scan, the pruned scan's bracket,
and how few contact evaluations a cold solve takes (counted, not timed)."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from wheelterrain import presets
from wheelterrain.model import contact, soil, solve
from wheelterrain.model import functions as model_functions
from wheelterrain.parameters import NAMES, TABLE

PRESETS = ("paper-table2-arc", "rashid-patch", "paper-table1", "paper-table2", "rashid-calibrated")


def random_parameters(rng: np.random.Generator) -> np.ndarray:
    """A parameter vector drawn from the table's declared ranges (switches over their values)."""
    return np.array([rng.integers(int(r.min), int(r.max) + 1)
                     if r.kind in ("integer", "enum") else rng.uniform(r.min, r.max)
                     for r in TABLE])


@pytest.fixture(scope="module")
def bound_and_force():
    th, sl, pp = ca.SX.sym("theta_f"), ca.SX.sym("slip"), ca.SX.sym("p", len(NAMES))
    bound = ca.Function("bound", [th, sl, pp], [contact.static_bound(th, sl, soil.Params(pp))])
    return bound, solve.static_functions(contact.DEFAULT_NODES)[1]


def test_the_bound_is_above_the_static_normal_force_everywhere_in_range(bound_and_force):
    """Every form, shear law, kinematics and grouser switch, driving and braking (reversals),
    entry angles from the solve's smallest to full burial: the quadrature never exceeds it."""
    bound, fz = bound_and_force
    rng = np.random.default_rng(11)
    n = 4000
    p = np.stack([random_parameters(rng) for _ in range(n)], axis=1)
    theta = np.exp(rng.uniform(np.log(solve.THETA_MIN), np.log(contact.FULL_BURIAL), n))
    theta[:50] = contact.FULL_BURIAL
    slip = rng.uniform(-1.0, 1.0, n)
    u = np.asarray(bound.map(n)(theta, slip, p)).ravel()
    f = np.asarray(fz.map(n)(theta, slip, p)).ravel()
    assert np.all(np.isfinite(u))
    assert np.all(np.isfinite(f))
    assert np.all(f <= u), (theta[f > u], slip[f > u], f[f > u], u[f > u])
    arc = p[NAMES.index("model.contact_form")] == 0
    assert arc.any()
    assert (~arc).any()


def test_the_bound_is_close_enough_to_prune(bound_and_force):
    """On the arc presets, wherever the force is a load of 1 N or more, the bound at a scan
    angle is below the force at the next one: the scan of such a load evaluates the
    crossing's neighbours only. (At tiny sinkage, cohesion makes the bound looser: there
    the full shear strength is assumed where little of it is mobilised.)"""
    bound, fz = bound_and_force
    scan = solve.scan_angles()[1:]
    for name in ("paper-table2-arc", "rashid-calibrated"):
        p = presets.load(name).vector()
        for slip in (-0.3, 0.0, 0.2, 0.5):
            u = np.array([float(bound(t, slip, p)) for t in scan])
            f = np.array([float(fz(t, slip, p)) for t in scan])
            assert np.all(u >= f)
            loads = f[1:] >= 1.0
            assert loads.sum() >= 2
            assert np.all(u[:-1][loads] < f[1:][loads]), (name, slip)


def full_scan_start(load, slip, p):
    fz = solve.static_functions(contact.DEFAULT_NODES)[1]
    values = [fz(t, slip, p) for t in solve.scan_angles()]
    return solve.solve_start(load, values)


@pytest.mark.parametrize("name", PRESETS)
def test_the_pruned_scan_brackets_exactly_as_the_full_scan(name):
    """The Newton state, capacity and load scale after the pruned scan are those of the full
    13-point scan, bit for bit: loads from 0 to past the capacity, driving and braking."""
    load, slip, pp = ca.MX.sym("load"), ca.MX.sym("slip"), ca.MX.sym("p", len(NAMES))
    P = soil.Params(pp)
    pruned = ca.Function("pruned", [load, slip, pp], list(solve.solve_start(
        load, solve.scan_values(load, slip, P, contact.DEFAULT_NODES))))
    full = ca.Function("full", [load, slip, pp], list(full_scan_start(load, slip, pp)))
    p = presets.load(name).vector()
    rng = np.random.default_rng(len(name))
    n = 400
    slip_v = rng.uniform(-0.9, 0.95, n)
    capacity = np.asarray(model_functions.build().capacity.map(n)(slip_v, np.tile(p[:, None], n)))
    load_v = rng.uniform(0.0, 1.2, n) * capacity.ravel()
    load_v[:5] = 0.0
    for a, b in zip(pruned.map(n)(load_v, slip_v, p), full.map(n)(load_v, slip_v, p),
                    strict=True):
        a, b = np.asarray(a), np.asarray(b)
        assert np.array_equal(a, b, equal_nan=True)


def count_evaluations(load: float, slip: float, p: np.ndarray) -> tuple[int, int]:
    """(Fz_static values, Fz_static-with-derivative evaluations) of a cold solve, replayed
    through the lane solve's pieces in the order the generated driver calls them."""
    k = solve.solve_lane_kernels(contact.DEFAULT_NODES)
    fz_d, fz, _ = solve.static_functions(contact.DEFAULT_NODES)
    scan = solve.scan_angles()
    plan = np.asarray(k["scan_plan"](load, slip, p)).ravel()
    values = [np.nan] + [float(fz(scan[j], slip, p)) if plan[j - 1] else np.nan
                         for j in range(1, len(scan) - 1)] + [float(fz(scan[-1], slip, p))]
    index, theta, absent = (float(x) for x in k["scan_low"](load, values, plan))
    if absent:
        values[int(index)] = float(fz(theta, slip, p))
    state, _, w_safe = k["start"](load, values)
    state = k["refine"](state, fz(np.exp(float(state[0])), slip, p), w_safe)
    newton = 0
    while float(state[solve.STATE_DONE]) == 0 and newton < solve.NEWTON_ITERATIONS:
        f, df = fz_d(np.exp(float(state[0])), slip, p)
        state = k["newton_update"](state, f, df, w_safe)
        newton += 1
    assert float(state[solve.STATE_DONE]) == 1
    return 1 + int(plan.sum()) + int(absent) + 1, newton


@pytest.mark.parametrize("name", ["paper-table2-arc", "paper-table2", "rashid-calibrated"])
def test_a_cold_driving_solve_takes_few_evaluations(name):
    """Driving loads of the rig (20-60 N): at most 4 values (two or three for the scan, one
    for the refined start) and 3 Newton steps with the derivative, where the full scan alone
    took 13 values and Newton 4-5 steps."""
    p = presets.load(name).vector()
    rng = np.random.default_rng(3)
    counts = [count_evaluations(w, s, p) for w, s in zip(rng.uniform(20.0, 60.0, 40),
                                                         rng.uniform(0.0, 0.5, 40),
                                                         strict=True)]
    values, newton = np.array(counts).T
    assert values.max() <= 4
    assert newton.max() <= 3
    assert np.mean(newton) <= 2.2


def test_a_braking_corner_where_the_force_crosses_zero_below_a_tiny_load_converges():
    """Braking (skid -0.47, the traction slip -0.9) on a cohesive (20 kPa), frictionless soil
    under a 1 cm wheel with 6 cm grousers: Fz_static is negative up to ~1.29 rad and crosses 0
    just below the 0.1 N load steeply, so the asinh residual is a steep step there and Newton
    alternates across it with regula falsi; it converges within the iterations the solve
    allows (it had 16, and the steady state was refused as unconverged). The sinkage exponent
    is n0 = 2 (in skid it is held at n0; the corner was found at n = 0.3 + 2*0.9)."""
    from wheelterrain import model
    from wheelterrain.parameters import ParameterSet

    values = {p.name: p.default for p in TABLE}
    values.update({"wheel.radius": 0.01, "wheel.width": 1.0, "grouser.count": 0.0,
                   "grouser.height": 0.0625, "soil.cohesion": 20000.0, "soil.phi": 0.0,
                   "soil.k_c": 0.0, "soil.k_phi": 10.0, "soil.n0": 2.0, "soil.n1": 2.0,
                   "soil.gamma": 5000.0, "soil.shear_modulus": 0.0005,
                   "soil.residual_ratio": 0.1, "soil.gamma_variation": 0.0,
                   "soil.damping": 0.0, "soil.unloading_stiffness": 1e5, "model.a0": 0.32,
                   "model.a1": 0.0, "model.soil_memory": 0, "model.interface_ratio": 0.1,
                   "model.diameter_exponent": -1.0})
    ps = ParameterSet(values)
    out = model.steady_state(ps, 0.1, -0.9)
    assert out["normal_force"] == pytest.approx(0.1, rel=1e-9)
    assert out["sinkage"] == pytest.approx(0.0072150, rel=1e-4)
    assert out["entry_angle"] > 1.28
