"""The lane-parallel C (wheelterrain.model.lanes) against the CasADi Functions it is generated from.

The bar: every output within 1e-12 of its largest magnitude over the sample, and within 1e-9
relative at every point. (Pointwise 1e-12 is not a property of any reordering of the sums: where
drawbar pull or torque cancel to ~1e-8 of their terms, CasADi's own generated C differs from its
virtual machine by 3.5e-11 relative.)
"""

from __future__ import annotations

import ctypes

import casadi as ca
import numpy as np
import pytest

from wheelterrain import presets
from wheelterrain.fmu import compiled as native
from wheelterrain.model import api as model_api
from wheelterrain.model import contact, lanes

pytestmark = pytest.mark.skipif(native.compiler() is None, reason="no C compiler")

PRESETS = ("paper-table2-arc", "rashid-patch", "paper-table1", "paper-table2", "rashid-calibrated")


@pytest.fixture(scope="session")
def lane_cache(tmp_path_factory):
    """A fresh cache for the session, so that the compile path is exercised."""
    return tmp_path_factory.mktemp("lanes_cache")


@pytest.fixture(scope="session")
def lane_contact(lane_cache):
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("WHEELTERRAIN_CACHE", str(lane_cache))
        lanes.compiled_contact.cache_clear()
        return lanes.compiled_contact()


@pytest.fixture(scope="session")
def lane_solve(lane_cache):
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("WHEELTERRAIN_CACHE", str(lane_cache))
        lanes.compiled_solve.cache_clear()
        return lanes.compiled_solve()


def random_points(n: int, seed: int):
    rng = np.random.default_rng(seed)
    return (rng.uniform(-0.005, 0.06, n), rng.uniform(-0.1, 0.1, n), rng.uniform(-0.6, 0.9, n),
            rng.uniform(0.0, 7.0, n))


def reference(points, P: np.ndarray) -> np.ndarray:
    n = len(points[0])
    P = P if P.ndim == 2 else np.tile(P[:, None], (1, n))
    return np.array(contact.build().contact.map(n)(*points, P)).reshape(-1, n)


def assert_agrees(got: np.ndarray, ref: np.ndarray) -> None:
    assert got.shape == ref.shape
    assert np.array_equal(np.isnan(got), np.isnan(ref))
    scale = np.max(np.abs(np.nan_to_num(ref)), axis=1, keepdims=True)
    difference = np.abs(np.nan_to_num(got) - np.nan_to_num(ref))
    assert np.all(difference <= 1e-12 * scale), np.max(difference / np.maximum(scale, 1e-300))
    relative = np.where(difference == 0, 0, difference / np.maximum(np.abs(ref), 1e-300))
    assert np.nanmax(relative) <= 1e-9


def cases(points, P: np.ndarray) -> np.ndarray:
    n = len(points[0])
    P = P if P.ndim == 2 else np.tile(P[:, None], (1, n))
    case, _ = contact.lane_kernels()
    return np.array(case.map(n)(*points, P)).ravel().astype(int)


@pytest.mark.parametrize("name", PRESETS)
def test_lane_contact_equals_the_switch_at_random_points(lane_contact, name):
    p = presets.load(name).vector()
    points = random_points(4003, seed=len(name))  # not a multiple of LANES
    got = lane_contact(*points, p)
    assert_agrees(got, reference(points, p))
    present = set(cases(points, p))
    # the arc presets put points in both arc kernels (braking reverses the shear), so both
    # queues and the switch between them are exercised; the patch presets use the patch only
    assert present == ({contact.PATCH} if p[contact.NAMES.index("model.contact_form")] == 1
                       else {contact.ARC, contact.ARC_REVERSAL})


def test_per_point_parameters_mix_every_case_within_a_block(lane_contact):
    """Each point takes its parameters from a random preset, so one block of LANES points
    holds arc, reversal and patch points: each goes to its own queue and comes back in place."""
    n = 997
    rng = np.random.default_rng(7)
    table = np.array([presets.load(name).vector() for name in PRESETS]).T
    P = np.ascontiguousarray(table[:, rng.integers(0, len(PRESETS), n)])
    points = random_points(n, seed=11)
    first = lanes.LANES * 4
    assert set(cases([x[:first] for x in points], P[:, :first])) == {
        contact.ARC, contact.ARC_REVERSAL, contact.PATCH}
    assert_agrees(lane_contact(*points, P), reference(points, P))


def test_scalars_broadcast_and_short_inputs(lane_contact, table2):
    p = table2.vector()
    for n in (1, lanes.LANES - 1, lanes.LANES + 1):
        z = np.linspace(0.001, 0.03, n)
        got = lane_contact(z, 0.0, 0.2, 0.0, p)
        ref = reference((z, np.zeros(n), np.full(n, 0.2), np.zeros(n)), p)
        assert_agrees(got, ref)


def test_inputs_of_different_lengths_are_refused(lane_contact, table2):
    with pytest.raises(ValueError, match="one length"):
        lane_contact(np.zeros(3), 0.0, np.zeros(4), 0.0, table2.vector())
    with pytest.raises(ValueError, match="rows"):
        lane_contact(0.01, 0.0, 0.2, 0.0, table2.vector()[:5])


def test_every_translated_operation_matches_casadi(tmp_path):
    """The instruction table, operation by operation, including the NaN, infinity and signed
    cases where C's operators and CasADi's differ unless written with care."""
    x, y = ca.SX.sym("x"), ca.SX.sym("y")
    exprs = [x + y, x - y, x * y, x / y, x ** y, x ** 3, ca.atan2(x, y), x < y, x <= y,
             x == y, x != y, ca.logic_and(x, y), ca.logic_or(x, y), ca.if_else(x, y, 0),
             ca.fmin(x, y), ca.fmax(x, y), ca.copysign(x, y), ca.fmod(x, y), ca.hypot(x, y),
             -x, x ** 2, 2 * x, 1 / x, ca.logic_not(x), ca.fabs(x), ca.sign(x), ca.sqrt(x),
             ca.exp(x), ca.log(x), ca.sin(x), ca.cos(x), ca.tan(x), ca.asin(x), ca.acos(x),
             ca.atan(x), ca.sinh(x), ca.cosh(x), ca.tanh(x), ca.asinh(x), ca.acosh(x),
             ca.atanh(x), ca.erf(x), ca.log1p(x), ca.expm1(x), ca.floor(x), ca.ceil(x),
             ca.inf * x, ca.if_else(x > 0, ca.inf, -ca.inf)]
    fn = ca.Function("ops", [x, y], [ca.vertcat(*exprs)])
    source = lanes._PRELUDE.format(lanes=lanes.LANES, declarations="", args=lanes._KERNEL_ARGS)
    body = lanes.kernel_c(fn, "k_ops") + """
int run(long n, const double* const* in, double* const* out) {
  long js[2] = {n, n}, is[2] = {1, 1}, ix[WT_LANES];
  for (long i0 = 0; i0 < n; i0 += WT_LANES) {
    int m = n - i0 < WT_LANES ? (int)(n - i0) : WT_LANES;
    for (int l = 0; l < WT_LANES; ++l) ix[l] = i0 + (l < m ? l : m - 1);
    k_ops(ix, m, in, js, is, out, ix, n);
  }
  return 0;
}
"""
    source += lanes._declarations(body) + "\n" + body
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("WHEELTERRAIN_CACHE", str(tmp_path))
        library, _ = lanes.compile_source(source, "ops")
    values = np.array([-2.5, -1.0, -0.5, -0.0, 0.0, 0.3, 0.5, 1.0, 2.0, np.inf, -np.inf, np.nan])
    xs, ys = (a.ravel().copy() for a in np.meshgrid(values, values))
    n = len(xs)
    out = np.empty((len(exprs), n))
    dbl_p = ctypes.POINTER(ctypes.c_double)
    run = ctypes.CDLL(str(library)).run
    run.argtypes = [ctypes.c_long, ctypes.c_void_p, ctypes.c_void_p]
    ins = (dbl_p * 2)(xs.ctypes.data_as(dbl_p), ys.ctypes.data_as(dbl_p))
    outs = (dbl_p * 1)(out.ctypes.data_as(dbl_p))
    assert run(n, ctypes.cast(ins, ctypes.c_void_p), ctypes.cast(outs, ctypes.c_void_p)) == 0
    with np.errstate(all="ignore"):
        ref = np.array(fn.map(n)(xs, ys)).reshape(len(exprs), n)
    for k in range(len(exprs)):
        same_nan = np.isnan(out[k]) == np.isnan(ref[k])
        close = np.isclose(out[k], ref[k], rtol=1e-14, atol=0, equal_nan=True)
        assert np.all(same_nan & close), (exprs[k], xs[~close], ys[~close], out[k][~close],
                                          ref[k][~close])


def converged(out: np.ndarray) -> np.ndarray:
    """model.steady_state's acceptance test, per point."""
    return (np.abs(out[1]) <= model_api.RESIDUAL_TOLERANCE) | (out[2] <= model_api.STEP_TOLERANCE)


@pytest.mark.parametrize("name", PRESETS)
def test_lane_solve_equals_the_sinkage_solve(lane_solve, name):
    """Loads from 0 to past the capacity, driving and braking: the same sinkage and capacity
    to 1e-12 relative, residual and last step (rounding-level numbers) to 1e-12 absolute, and
    the same convergence verdict at every point."""
    p = presets.load(name).vector()
    rng = np.random.default_rng(len(name))
    n = 1501
    slip = rng.uniform(-0.6, 0.9, n)
    capacity = np.array(contact.build().capacity.map(n)(slip, np.tile(p[:, None], (1, n))))
    load = rng.uniform(0.0, 1.2, n) * capacity.ravel()  # a sixth past the capacity
    load[:7] = 0.0
    got = lane_solve(load, slip, p)
    ref = np.array(contact.build().sinkage_solve.map(n)(
        load, slip, np.tile(p[:, None], (1, n)))).reshape(4, n)
    assert np.array_equal(np.isnan(got), np.isnan(ref))
    for row in (0, 3):  # sinkage, capacity
        assert np.allclose(got[row], ref[row], rtol=1e-12, atol=0)
    assert np.max(np.abs(got[1:3] - ref[1:3])) <= 1e-12
    assert np.array_equal(converged(got), converged(ref))
    assert np.all(got[0][:7] == 0)


def test_lane_solve_with_per_point_parameters(lane_solve):
    n = 203
    rng = np.random.default_rng(5)
    table = np.array([presets.load(name).vector() for name in PRESETS]).T
    P = np.ascontiguousarray(table[:, rng.integers(0, len(PRESETS), n)])
    load, slip = rng.uniform(1.0, 120.0, n), rng.uniform(-0.3, 0.8, n)
    got = lane_solve(load, slip, P)
    ref = np.array(contact.build().sinkage_solve.map(n)(load, slip, P)).reshape(4, n)
    assert np.allclose(got[0], ref[0], rtol=1e-12, atol=0)
    assert np.array_equal(converged(got), converged(ref))
