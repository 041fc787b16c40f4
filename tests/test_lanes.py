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

from wheelterrain import compiled as native
from wheelterrain import presets
from wheelterrain.model import api as model_api
from wheelterrain.model import contact, lanes, solve
from wheelterrain.model import functions as model_functions
from wheelterrain.parameters import TURN_SLIP_LIMIT

pytestmark = pytest.mark.skipif(native.compiler() is None, reason="no C compiler")

PRESETS = ("paper-table2-arc", "rashid-patch", "paper-table1", "paper-table2", "rashid-calibrated")


@pytest.fixture(scope="session")
def lane_cache():
    """The machine's cache of compiled libraries (``compiled.cache_directory()``): a fresh
    machine (CI) compiles the lanes here once, which exercises the compile path, and every
    other test that evaluates many points reuses them (a cache of its own compiled them twice,
    ~100 s)."""
    return native.cache_directory()


def compiled_in(cache, factory):
    """``factory()`` with ``cache`` as the cache of compiled libraries (not the object an earlier
    call in this process kept: its library is looked up, or compiled, anew)."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("WHEELTERRAIN_CACHE", str(cache))
        factory.cache_clear()
        return factory()


@pytest.fixture(scope="session")
def lane_contact(lane_cache):
    return compiled_in(lane_cache, lanes.compiled_contact)


@pytest.fixture(scope="session")
def lane_solve(lane_cache):
    return compiled_in(lane_cache, lanes.compiled_solve)


def random_points(n: int, seed: int):
    rng = np.random.default_rng(seed)
    return (rng.uniform(-0.005, 0.06, n), rng.uniform(-0.1, 0.1, n), rng.uniform(-0.6, 0.9, n),
            rng.uniform(0.0, 7.0, n))


def reference(points, P: np.ndarray) -> np.ndarray:
    n = len(points[0])
    P = P if P.ndim == 2 else np.tile(P[:, None], (1, n))
    return np.array(model_functions.build().contact.map(n)(*points, P)).reshape(-1, n)


def assert_agrees(got: np.ndarray, ref: np.ndarray, noise: float = 0.0) -> None:
    """Within 1e-12 of each output's largest value, and within 1e-9 relative wherever the
    reference exceeds ``noise`` times that largest value (a value the model makes exactly 0 by
    a symmetry comes out as rounding noise, different in each evaluation order)."""
    assert got.shape == ref.shape
    assert np.array_equal(np.isnan(got), np.isnan(ref))
    scale = np.max(np.abs(np.nan_to_num(ref)), axis=1, keepdims=True)
    difference = np.abs(np.nan_to_num(got) - np.nan_to_num(ref))
    assert np.all(difference <= 1e-12 * scale), np.max(difference / np.maximum(scale, 1e-300))
    relative = np.where(difference == 0, 0, difference / np.maximum(np.abs(ref), 1e-300))
    relative = np.where(np.abs(np.nan_to_num(ref)) > noise * scale, relative, 0)
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
    source = lanes._PRELUDE.format(lanes=lanes.LANES, max_forms=lanes.MAX_FORMS, declarations="",
                                   args=lanes._KERNEL_ARGS)
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


ROW = {name: row for row, name in enumerate(solve.STEADY_OUTPUTS)}
CONTACT_ROWS = slice(ROW["normal_force"], ROW["normal_force_static"] + 1)


def converged(out: np.ndarray) -> np.ndarray:
    """model.steady_state's acceptance test, per point."""
    return solve.solve_converged(out[ROW["residual"]], out[ROW["last_step"]])


def steady_reference(load, slip, P: np.ndarray) -> np.ndarray:
    n = len(load)
    P = P if P.ndim == 2 else np.tile(P[:, None], (1, n))
    return np.array(model_functions.build().steady.map(n)(load, slip, P)).reshape(-1, n)


def assert_same_steady_state(got: np.ndarray, ref: np.ndarray) -> None:
    """Sinkage and capacity to 1e-12 relative, the contact outputs as assert_agrees, residual
    and last step (rounding-level numbers) to 1e-12 absolute, the same convergence verdict."""
    assert np.array_equal(np.isnan(got), np.isnan(ref))
    for name in ("sinkage", "capacity"):
        assert np.allclose(got[ROW[name]], ref[ROW[name]], rtol=1e-12, atol=0), name
    assert_agrees(got[CONTACT_ROWS], ref[CONTACT_ROWS])
    for name in ("residual", "last_step"):
        assert np.max(np.abs(got[ROW[name]] - ref[ROW[name]])) <= 1e-12, name
    assert np.array_equal(converged(got), converged(ref))


@pytest.mark.parametrize("name", PRESETS)
def test_lane_solve_equals_the_steady_state(lane_solve, name):
    """Loads from 0 to a sixth past the capacity, driving and braking, solved cold: every
    output of build().steady."""
    p = presets.load(name).vector()
    rng = np.random.default_rng(len(name))
    n = 1501
    slip = rng.uniform(-0.6, 0.9, n)
    capacity = np.array(model_functions.build().capacity.map(n)(slip, np.tile(p[:, None], (1, n))))
    load = rng.uniform(0.0, 1.2, n) * capacity.ravel()
    load[:7] = 0.0
    got = lane_solve(load, slip, np.nan, np.nan, np.nan, p)
    assert_same_steady_state(got, steady_reference(load, slip, p))
    assert np.all(got[ROW["sinkage"]][:7] == 0)


def test_lane_solve_with_per_point_parameters(lane_solve):
    n = 203
    rng = np.random.default_rng(5)
    table = np.array([presets.load(name).vector() for name in PRESETS]).T
    P = np.ascontiguousarray(table[:, rng.integers(0, len(PRESETS), n)])
    load, slip = rng.uniform(1.0, 120.0, n), rng.uniform(-0.3, 0.8, n)
    assert_same_steady_state(lane_solve(load, slip, np.nan, np.nan, np.nan, P),
                             steady_reference(load, slip, P))


@pytest.mark.parametrize("name", PRESETS)
def test_a_warm_start_reaches_the_cold_solution(lane_solve, name):
    """Driving (0 <= slip <= 0.8, where Fz_static grows with sinkage and the root is unique),
    from guesses 0.5x to 2x the solution, from a far one (a tenth of the contact radius) and with
    no guess (NaN) mixed in one call: the cold solution, to rounding."""
    p = presets.load(name).vector()
    rng = np.random.default_rng(17 + len(name))
    n = 999
    slip = rng.uniform(0.0, 0.8, n)
    capacity = np.array(model_functions.build().capacity.map(n)(slip, np.tile(p[:, None], (1, n))))
    load = rng.uniform(0.01, 0.9, n) * capacity.ravel()
    cold = lane_solve(load, slip, np.nan, np.nan, np.nan, p)
    guess = cold[ROW["sinkage"]] * rng.uniform(0.5, 2.0, n)
    guess[::7] = np.nan
    guess[3::7] = 0.1 * presets.load(name)["wheel.radius"]
    warm = lane_solve(load, slip, guess, np.nan, np.nan, p)
    assert np.all(converged(warm))
    assert np.allclose(warm[ROW["sinkage"]], cold[ROW["sinkage"]], rtol=1e-12, atol=0)
    assert_agrees(warm[CONTACT_ROWS], cold[CONTACT_ROWS])
    assert np.array_equal(warm[:, ::7], cold[:, ::7])  # no guess: the cold solve itself
    # the scan's ends given (as a sweep passes them): the same numbers, bit for bit
    ends = lanes.compiled_scan_ends()(slip, p)
    assert np.array_equal(ends[1], cold[ROW["capacity"]])
    assert np.array_equal(lane_solve(load, slip, guess, ends[0], ends[1], p), warm,
                          equal_nan=True)


@pytest.mark.parametrize("name", PRESETS[:2])
def test_the_lane_warm_start_is_steady_from(lane_solve, name):
    """The warm start the FMUs run (build().steady_from, CasADi) and the lanes' are the same
    algebra: the same outputs to rounding, driving and braking, from guesses 0.3x to 3x."""
    p = presets.load(name).vector()
    rng = np.random.default_rng(29 + len(name))
    n = 60
    slip = rng.uniform(-0.6, 0.9, n)
    capacity = np.array(model_functions.build().capacity.map(n)(slip, np.tile(p[:, None], (1, n))))
    load = rng.uniform(0.01, 0.9, n) * capacity.ravel()
    cold = lane_solve(load, slip, np.nan, np.nan, np.nan, p)
    guess = cold[ROW["sinkage"]] * rng.uniform(0.3, 3.0, n)
    got = lane_solve(load, slip, guess, np.nan, np.nan, p)
    assert np.all(converged(got))  # so steady_from keeps its warm result: no retry
    steady_from = model_functions.build().steady_from.map(n)
    ref = np.array(steady_from(load, slip, np.tile(p[:, None], (1, n)), guess)).reshape(-1, n)
    assert_same_steady_state(got, ref)


def test_steady_from_solves_again_cold_where_the_warm_start_fails(monkeypatch, table2):
    """With one Newton iteration allowed, a warm start from the root converges and stands; one
    from 30 % off does not, and steady_from returns the cold solve's outputs, bit for bit."""
    root = model_functions.build().steady(40.0, 0.3, table2.vector())[0]
    monkeypatch.setattr(solve, "NEWTON_ITERATIONS", 1)
    fns = model_functions.build.__wrapped__(contact.DEFAULT_NODES)  # not the cached build
    p = table2.vector()
    cold = np.array(fns.steady(40.0, 0.3, p)).ravel()
    assert not converged(cold)  # one iteration is not enough from the scan's bracket
    exact = np.array(fns.steady_from(40.0, 0.3, p, root)).ravel()
    assert converged(exact)
    assert exact[ROW["sinkage"]] == pytest.approx(float(root), rel=1e-12)
    off = np.array(fns.steady_from(40.0, 0.3, p, 1.3 * float(root))).ravel()
    assert np.array_equal(off, cold)
    assert np.array_equal(np.array(fns.steady_from(40.0, 0.3, p, np.nan)).ravel(), cold)


def test_steady_states_equals_steady_state_point_by_point(lane_cache, table2):
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("WHEELTERRAIN_CACHE", str(lane_cache))
        loads = np.array([0.0, 5.0, 30.0, 45.0, 25.0])
        slips = np.array([-0.4, 0.0, 0.2, 0.4, 0.8])
        many = model_api.steady_states(table2, loads, slips)
        for k, (w, i) in enumerate(zip(loads, slips, strict=True)):
            one = model_api.steady_state(table2, w, i)
            for name in ("sinkage", "drawbar_pull", "torque", "normal_force", "capacity"):
                assert many[name][k] == pytest.approx(one[name], rel=1e-12, abs=1e-12), name
        paper = model_api.steady_states(table2, 30.0, [0.25, 0.5], slip_definition="paper")
        assert paper["slip"] == pytest.approx([0.2, 1 / 3], rel=1e-15)
        assert paper["slip_paper"] == pytest.approx([0.25, 0.5], rel=1e-15)


def test_steady_states_refuses_bad_inputs_and_overloads(lane_cache, table2):
    from wheelterrain.errors import InputError, LoadTooLargeError

    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("WHEELTERRAIN_CACHE", str(lane_cache))
        with pytest.raises(InputError, match="load"):
            model_api.steady_states(table2, [10.0, -1.0], 0.2)
        with pytest.raises(InputError, match="slip"):
            model_api.steady_states(table2, 10.0, [0.2, np.nan])
        with pytest.raises(InputError, match="slip"):
            model_api.steady_states(table2, 10.0, [0.2, 1.5])
        with pytest.raises(InputError, match="slip_definition"):
            model_api.steady_states(table2, 10.0, 0.2, slip_definition="skid")
        with pytest.raises(InputError, match="over_capacity"):
            model_api.steady_states(table2, 10.0, 0.2, over_capacity="clip")
        capacity = model_api.capacity(table2, 0.3)
        with pytest.raises(LoadTooLargeError):
            model_api.steady_states(table2, [10.0, 1.5 * capacity], 0.3)
        out = model_api.steady_states(table2, [10.0, 1.5 * capacity], 0.3, over_capacity="nan")
        assert np.isfinite(out["sinkage"][0])
        assert np.isnan(out["sinkage"][1])
        assert out["capacity"][1] == pytest.approx(capacity, rel=1e-12)


def test_steady_map_is_the_cold_solve_on_the_grid(lane_cache, table2):
    """The continuation (warm starts along the loads, given unsorted) reaches the cold
    solution at every carried point; NaN exactly where the load exceeds the capacity."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("WHEELTERRAIN_CACHE", str(lane_cache))
        loads = np.array([40.0, 5.0, 70.0, 20.0, 30.0, 60.0, 50.0, 10.0])
        slips = np.linspace(0.0, 0.8, 9)
        grid = model_api.steady_map(table2, loads, slips)
        L, S = np.meshgrid(loads, slips, indexing="ij")
        cold = model_api.steady_states(table2, L.ravel(), S.ravel(), over_capacity="nan")
        for name in ("sinkage", "drawbar_pull", "torque", "capacity"):
            assert grid[name].shape == (loads.size, slips.size)
            assert np.allclose(grid[name], cold[name].reshape(L.shape), rtol=1e-12, atol=1e-12,
                               equal_nan=True), name
        assert np.array_equal(np.isnan(grid["sinkage"]), grid["capacity"] < L)
        assert np.any(np.isnan(grid["sinkage"]))
        assert np.any(np.isfinite(grid["sinkage"]))


def test_a_warm_start_that_fails_is_solved_again_cold(monkeypatch, lane_cache, table2):
    """The policy, with a solver whose warm starts never converge."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("WHEELTERRAIN_CACHE", str(lane_cache))
        real = lanes.compiled_solve()
    calls = []

    def failing_when_warm(load, slip, guess, first, last, p):
        out = real(load, slip, guess, first, last, p)
        warm = np.isfinite(np.broadcast_to(guess, load.shape))
        calls.append(int(np.sum(warm)))
        out[solve.STEADY_OUTPUTS.index("residual"), warm] = 1.0
        out[solve.STEADY_OUTPUTS.index("last_step"), warm] = 1.0
        return out

    monkeypatch.setattr(model_api, "_steady_many", lambda: failing_when_warm)
    loads = np.array([10.0, 20.0, 30.0])
    out = model_api.steady_states(table2, loads, 0.2, guess=[0.01, np.nan, 0.02])
    assert calls == [2, 0]  # the two warm points, then both again cold
    for k, w in enumerate(loads):
        assert out["sinkage"][k] == pytest.approx(model_api.steady_state(table2, w, 0.2)[
            "sinkage"], rel=1e-12)


def no_compiler(*args, **kwargs):
    """Stands in for a compiled_* factory on a machine without a C compiler."""
    raise native.CompileError("no C compiler (cc/gcc, or $CC) on PATH")


def test_without_a_c_compiler_steady_states_uses_casadi(monkeypatch, table2):
    monkeypatch.setattr(lanes, "compiled_solve", no_compiler)
    model_api._steady_many.cache_clear()
    try:
        with pytest.warns(UserWarning, match="virtual machine"):
            out = model_api.steady_states(table2, [10.0, 30.0], [0.1, 0.4],
                                          guess=[0.01, np.nan])
        for k, (w, i) in enumerate(((10.0, 0.1), (30.0, 0.4))):
            assert out["sinkage"][k] == pytest.approx(
                model_api.steady_state(table2, w, i)["sinkage"], rel=1e-12)
    finally:
        model_api._steady_many.cache_clear()


def test_contact_forces_many_equals_contact_forces(lane_cache, table2, monkeypatch):
    from wheelterrain.errors import InputError

    z = np.array([-0.001, 0.0, 0.004, 0.02, 0.04])
    slip = np.array([0.1, -0.3, 0.2, 0.5, 0.9])
    rate, angle = 0.05, np.linspace(0.0, 3.0, 5)
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("WHEELTERRAIN_CACHE", str(lane_cache))
        many = model_api.contact_forces_many(table2, z, slip, sinkage_rate=rate,
                                             wheel_angle=angle)
        with pytest.raises(InputError, match="sinkage"):
            model_api.contact_forces_many(table2, [0.01, 1.0], 0.2)
        with pytest.raises(InputError, match="wheel_angle"):
            model_api.contact_forces_many(table2, 0.01, 0.2, wheel_angle=[0.0, np.inf])

    monkeypatch.setattr(lanes, "compiled_contact", no_compiler)
    model_api._contact_many.cache_clear()
    try:
        with pytest.warns(UserWarning, match="no C compiler"):
            on_vm = model_api.contact_forces_many(table2, z, slip, sinkage_rate=rate,
                                                  wheel_angle=angle)
    finally:
        model_api._contact_many.cache_clear()
    for k in range(z.size):
        one = model_api.contact_forces(table2, z[k], slip[k], sinkage_rate=rate,
                                       wheel_angle=angle[k])
        for name, value in one.items():
            assert many[name][k] == pytest.approx(value, rel=1e-12, abs=1e-12), name
            assert on_vm[name][k] == pytest.approx(value, rel=1e-12, abs=1e-12), name


def test_an_unwritable_cache_is_a_compile_error_naming_the_setting(tmp_path, monkeypatch):
    blocked = tmp_path / "file"
    blocked.write_text("not a directory")
    monkeypatch.setenv("WHEELTERRAIN_CACHE", str(blocked))
    with pytest.raises(native.CompileError, match="WHEELTERRAIN_CACHE"):
        lanes.compile_source("int f(void) { return 0; }\n", "blocked")
    source = tmp_path / "blocked.c"  # the package's own C files (the master's loop) alike
    source.write_text("int f(void) { return 0; }\n")
    with pytest.raises(native.CompileError, match="WHEELTERRAIN_CACHE"):
        native.cached_source(source)


def test_steady_map_refuses_an_empty_axis(table2):
    from wheelterrain.errors import InputError

    with pytest.raises(InputError, match="loads"):
        model_api.steady_map(table2, [], [0.1, 0.2])
    with pytest.raises(InputError, match="slips"):
        model_api.steady_map(table2, [10.0], [])


def test_many_point_inputs_of_other_lengths_or_shapes_are_refused_by_name(table2):
    from wheelterrain.errors import InputError

    with pytest.raises(InputError, match=r"load, slip.*one length"):
        model_api.steady_states(table2, [10.0, 20.0, 30.0], [0.1, 0.2])
    with pytest.raises(InputError, match=r"load, guess.*one length"):
        model_api.steady_states(table2, [10.0, 20.0], 0.2, guess=[0.01, 0.02, 0.03])
    with pytest.raises(InputError, match=r"sinkage, slip.*one length"):
        model_api.contact_forces_many(table2, [0.01, 0.02], [0.1, 0.2, 0.3])
    with pytest.raises(InputError, match="1-D"):
        model_api.steady_states(table2, [[10.0, 20.0]], 0.2)
    with pytest.raises(InputError, match=r"loads.*1-D"):
        model_api.steady_map(table2, [[10.0, 20.0]], [0.1])
    with pytest.raises(InputError, match="not a number"):
        model_api.steady_states(table2, "heavy", 0.2)


@pytest.mark.parametrize("preset", ["paper-table2-arc", "rashid-patch"])
def test_the_lane_side_force_is_the_casadi_functions_at_every_case(lane_cache, preset):
    """lanes.compiled_lateral against build().lateral (the CasADi VM) at random points: both
    forms' kernels, their turn-slip kernels and the zero case at slip angle and turn slip 0,
    driving and braking, slip angles and turn slips over the declared ranges, wheels out of the
    soil; the same values to rounding."""
    lateral = compiled_in(lane_cache, lanes.compiled_lateral)
    rng = np.random.default_rng(7)
    n = 3000
    z = rng.uniform(-0.005, 0.06, n)
    slip = rng.uniform(-1.0, 1.0, n)
    beta = np.radians(rng.uniform(-80.0, 80.0, n))
    beta[:200] = 0.0
    turn = rng.uniform(-TURN_SLIP_LIMIT, TURN_SLIP_LIMIT, n)
    turn[:200] = 0.0
    turn[200:1200] = 0.0  # a slip angle alone: the plain kernels
    beta[1200:1400] = 0.0  # and yawing alone
    p = presets.load(preset).vector()
    ref = np.array(model_functions.build().lateral.map(n)(
        z, slip, beta, turn, np.tile(p[:, None], (1, n)))).reshape(-1, n)
    got = lateral(z, slip, beta, turn, p)
    assert np.all(got[:, :200] == 0.0)
    assert np.count_nonzero(ref[0]) > n // 2  # the kernels ran, not only the zero case
    # the symmetric patch's aligning moment at a turn slip alone is 0 by symmetry, ~1e-17 N.m
    # of rounding in either evaluation: not compared relatively below 1e-12 of its largest
    assert_agrees(got, ref, noise=1e-12)
