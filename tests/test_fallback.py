"""Without a working C compiler every compiled path falls back to CasADi's VM and gives the
compiled path's numbers (a PATH without gcc is a set-up the README supports). The compiler is
hidden by pointing $CC at nothing and the compiled-library cache at an empty folder."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from wheelterrain import compiled, presets
from wheelterrain.cosim import rover as rover_system
from wheelterrain.fmu import slaves
from wheelterrain.model import ground

pytestmark = pytest.mark.skipif(compiled.compiler() is None, reason="compares with the "
                                "compiled path, which needs a C compiler")


@pytest.fixture
def no_compiler(monkeypatch, tmp_path):
    """The compiler hidden for the test: $CC names nothing, the cache is empty."""
    monkeypatch.setenv("CC", str(tmp_path / "no-such-cc"))
    monkeypatch.setenv("WHEELTERRAIN_CACHE", str(tmp_path / "cache"))
    rover_system._evaluator.cache_clear()
    yield
    rover_system._evaluator.cache_clear()


def test_a_cc_that_does_not_exist_is_no_compiler(no_compiler):
    assert compiled.compiler() is None
    with pytest.raises(compiled.CompileError, match="no C compiler"):
        compiled.cached_library(ca.Function("f", [ca.SX.sym("x")], [1]), "test")


def test_without_a_compiler_the_master_keeps_its_python_loop(no_compiler):
    """The rig-terrain master's compiled loop (coupling.c) is not to be had: the master then
    runs its loop in Python (tests/test_native_fmus.py: the same series)."""
    from wheelterrain.cosim import master

    master._coupling_loop.cache_clear()
    try:
        with pytest.raises(compiled.CompileError, match="no C compiler"):
            compiled.cached_source(master.Path(master.__file__).with_name("coupling.c"))
        assert master._coupling_loop() is None
    finally:
        master._coupling_loop.cache_clear()


@pytest.mark.parametrize("patch", [False, True], ids=["level", "soft-patch"])
def test_the_rover_on_casadis_vm_gives_the_compiled_runs(monkeypatch, tmp_path, patch):
    """The in-process rover's record on the VM equals the compiled block's to 1e-9 (it once
    read the VM's record transposed: the level run left the domain after 5 ms)."""
    base = presets.load(presets.DEFAULT_PRESET)
    soil = (rover_system.Soil(base, ground.soft_values(base), 0.005, 0.05) if patch
            else rover_system.Soil(base))
    fast = rover_system.simulate(soil, {}, 0.6)
    assert fast.engine == "in-process (compiled C)"
    monkeypatch.setenv("CC", str(tmp_path / "no-such-cc"))
    monkeypatch.setenv("WHEELTERRAIN_CACHE", str(tmp_path / "cache"))
    rover_system._evaluator.cache_clear()
    try:
        slow = rover_system.simulate(soil, {}, 0.6)
    finally:
        rover_system._evaluator.cache_clear()
    assert slow.engine == "in-process (CasADi VM)"
    assert slow.left_domain is None
    assert fast.left_domain is None
    assert slow.time.size == fast.time.size == 600
    for w, series in fast.wheels.items():
        for key, values in series.items():
            scale = max(1.0, float(np.max(np.abs(values))))
            assert np.max(np.abs(slow.wheels[w][key] - values)) <= 1e-9 * scale, (w, key)
    for key, values in fast.chassis.items():
        assert np.allclose(slow.chassis[key], values, rtol=1e-9, atol=1e-12), key


def test_the_fmus_vm_keeps_casadis_order_for_matrix_outputs(no_compiler):
    """The pythonfmu slaves' VM evaluator flattens a matrix output column by column, as the
    compiled buffers hold it."""
    x = ca.SX.sym("x", 2)
    fn = ca.Function("m", [x], [ca.horzcat(x, 2 * x, 3 * x), x[0] + x[1]])
    evaluate, how = slaves.compiled_or_vm(fn)
    assert how == "CasADi VM"
    matrix, total = evaluate([1.0, 2.0])
    assert matrix == [1.0, 2.0, 2.0, 4.0, 3.0, 6.0]
    assert total == 3.0
