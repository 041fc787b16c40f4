"""No NaN, no exception users did not ask for, anywhere users reach (property-based).

Parameters are drawn from the table's corners, defaults and interiors; slips over [-0.9, 0.99];
sinkage from 1e-6 m to the contact radius; loads from 0.1 N to the wheel's capacity.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from wheelterrain import model, presets
from wheelterrain.errors import LoadTooLargeError
from wheelterrain.model import functions as model_functions
from wheelterrain.parameters import TABLE, ParameterSet


def _value(p):
    if p.kind in ("integer", "enum"):
        return st.integers(int(p.min), int(p.max))
    return st.one_of(st.sampled_from([p.min, p.max, p.default]),
                     st.floats(p.min, p.max, allow_nan=False))


parameter_sets = st.fixed_dictionaries({p.name: _value(p) for p in TABLE}).map(ParameterSet)
slips = st.one_of(st.sampled_from([-0.9, 0.0, 0.99]), st.floats(-0.9, 0.99))
fractions = st.one_of(st.sampled_from([0.0, 1.0]), st.floats(0.0, 1.0))
# derandomize: the same 300 examples on every run, so CI judges what was seen here; explore new
# corners locally with `pytest tests/test_robustness.py --hypothesis-seed=N`.
common = settings(max_examples=300, deadline=None, derandomize=True,
                  suppress_health_check=[HealthCheck.too_slow])


@common
@given(ps=parameter_sets, slip=slips, frac=fractions, rate=st.floats(-1.0, 1.0),
       angle=st.floats(-100.0, 100.0))
def test_contact_outputs_are_finite(ps, slip, frac, rate, angle):
    rc = model.contact_radius(ps)
    z = 1e-6 + frac * (rc - 1e-6)  # 1e-6 m .. contact radius
    out = model.contact_forces(ps, z, slip, sinkage_rate=rate, wheel_angle=angle)
    bad = {k: v for k, v in out.items() if not math.isfinite(v)}
    assert not bad, f"non-finite outputs {bad} at z={z!r}, slip={slip!r}, {ps!r}"
    assert out["normal_force"] >= 0.0


@common
@given(ps=parameter_sets, slip=slips, frac=st.one_of(st.sampled_from([0.0, 1.0]),
                                                     st.floats(0.0, 1.0)))
def test_steady_state_is_finite_or_clearly_infeasible(ps, slip, frac):
    cap = model.capacity(ps, slip)
    assert math.isfinite(cap)
    # Below 0.1 N (even <= 0: braking shear pulling down more than the soil bears) this wheel
    # cannot carry the smallest load users ask for; that must be a clear error.
    if cap < 0.1:
        with pytest.raises(LoadTooLargeError):
            model.steady_state(ps, 0.1, slip)
        return
    load = 0.1 + frac * (cap - 0.1)
    out = model.steady_state(ps, load, slip)
    bad = {k: v for k, v in out.items() if k != "slip_paper" and not math.isfinite(v)}
    assert not bad, f"non-finite outputs {bad} at load={load!r}, slip={slip!r}, {ps!r}"
    # the contact begins at the rut's surface where the soil remembers one
    rut = ps["soil.rut_depth"] if ps["model.soil_memory"] == 1 else 0.0
    assert 0.0 < out["sinkage"] - rut <= model.contact_radius(ps) * (1 + 1e-12)
    assert out["normal_force"] == pytest.approx(load, rel=1e-9)


@common
@given(ps=parameter_sets, slip=slips, excess=st.floats(1.0 + 1e-9, 1e3))
def test_loads_beyond_capacity_are_refused_with_the_capacity(ps, slip, excess):
    cap = model.capacity(ps, slip)
    load = cap * excess if cap > 0 else 0.1 * excess  # capacity <= 0: any load is too large
    with pytest.raises(LoadTooLargeError, match="exceeds what the wheel can carry"):
        model.steady_state(ps, load, slip)


@pytest.mark.parametrize("preset", presets.available())
@pytest.mark.parametrize("slip", [-0.9, -0.5, 0.0, 0.5, 0.99, 1.0, -1.0])
def test_presets_at_edge_slips(preset, slip):
    ps = presets.load(preset)
    for load in (0.0, 0.1, 62.0):
        if load > model.capacity(ps, slip):
            continue
        out = model.steady_state(ps, load, slip)
        assert all(math.isfinite(v) for k, v in out.items() if k != "slip_paper")
    for z in (-0.01, 0.0, 1e-6, model.contact_radius(ps)):
        out = model.contact_forces(ps, z, slip, sinkage_rate=-5.0)
        assert all(math.isfinite(v) for v in out.values())


def test_no_contact_means_no_force(table2):
    for z in (-0.02, 0.0):
        out = model.contact_forces(table2, z, 0.3, sinkage_rate=-1.0, wheel_angle=0.4)
        assert out["normal_force"] == 0.0
        assert out["drawbar_pull"] == 0.0
        assert out["torque"] == 0.0


def test_zero_load_gives_zero_sinkage(table2):
    out = model.steady_state(table2, 0.0, 0.2)
    assert out["sinkage"] == 0.0
    assert out["normal_force"] == 0.0


def test_all_table_minima_and_maxima():
    lo = ParameterSet({p.name: p.min for p in TABLE})
    hi = ParameterSet({p.name: p.max for p in TABLE})
    for ps in (lo, hi):
        for slip in (-0.9, 0.99):
            out = model_functions.build().contact(model.contact_radius(ps) / 2, 0.0, slip, 1.0,
                                          ps.vector())
            assert np.all(np.isfinite([float(v) for v in out]))
