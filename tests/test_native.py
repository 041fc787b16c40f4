"""The compiled-C route (wheelterrain.compiled) gives the CasADi VM's numbers."""

from __future__ import annotations

import numpy as np
import pytest

from wheelterrain import compiled as native
from wheelterrain import presets
from wheelterrain.model import functions as model_functions


@pytest.mark.skipif(native.compiler() is None, reason="no C compiler")
def test_compiled_contact_equals_the_vm(tmp_path):
    fn = model_functions.build().contact
    compiled = native.CompiledFunction(native.compile_function(fn, tmp_path), fn)
    rng = np.random.default_rng(7)
    base = presets.load("paper-table2-arc")
    for _ in range(200):
        ps = base.with_values({"soil.phi": rng.uniform(0.2, 0.7),
                               "soil.n1": rng.uniform(0.0, 1.5),
                               "ripple.phase": rng.uniform(-3, 3)})
        z, rate = rng.uniform(0.0, 0.05), rng.uniform(-0.1, 0.1)
        slip, angle = rng.uniform(-0.9, 0.99), rng.uniform(-50, 50)
        want = [float(x) for x in fn(z, rate, slip, angle, ps.vector())]
        got = compiled(z, rate, slip, angle, list(ps.vector()))
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12)


def test_missing_compiler_is_a_clear_error(tmp_path, monkeypatch):
    monkeypatch.setenv("CC", str(tmp_path / "no-such-cc"))
    with pytest.raises(native.CompileError, match=r"no C compiler: \$CC is .*no-such-cc"):
        native.compile_function(model_functions.build().contact, tmp_path)


@pytest.mark.slow
@pytest.mark.skipif(native.compiler() is None, reason="no C compiler")
@pytest.mark.parametrize("which", [0, 1, 2])
def test_compiled_fmu_functions_equal_the_vm(tmp_path, which):
    from wheelterrain.fmu import functions as fmu_model

    fn = fmu_model.terrain_functions()[which]
    compiled = native.CompiledFunction(native.compile_function(fn, tmp_path), fn)
    rng = np.random.default_rng(11)
    p = list(presets.load("paper-table2-arc").vector())
    for _ in range(30):
        u = [rng.uniform(0, 0.04), rng.uniform(-0.05, 0.05), rng.uniform(0.1, 1.0),
             rng.uniform(0.0, 0.04), rng.uniform(1.0, 100.0),
             rng.choice([0.0, rng.uniform(0.0, 0.02)]),  # rut_met: none, or a rut
             rng.choice([0.0, rng.uniform(-0.7, 0.7)]),  # slip_angle: straight, or turned
             rng.choice([0.0, rng.uniform(-0.3, 0.3)]),  # yaw_rate: none, or yawing (or refused)
             rng.choice([0.0, rng.uniform(1e3, 5e4)])]  # rut_pressure_met: not known, or kept
        # quasi-static: cold (guess 0) and warm-started from a guess
        guess = rng.choice([0.0, rng.uniform(0.002, 0.06)])
        plastic = rng.choice([0.0, u[0] + rng.uniform(0.0, 3e-4)])  # pressed deeper before
        args = ((u, rng.uniform(-10, 10), plastic, p), (u, p, guess),
                (u, plastic, p, rng.uniform(1e-4, 1e-2)))[which]
        want = [np.asarray(x, dtype=float).ravel() for x in fn.call(list(args))]
        got = compiled(*args)
        np.testing.assert_allclose(np.asarray(got[0]), want[0], rtol=1e-12, atol=1e-12)
        assert got[1:] == pytest.approx([float(w[0]) for w in want[1:]], rel=1e-12)
