"""The rig's equations (wheelterrain.model.rig): one set of expressions on floats (the pythonfmu
slave), traced to CasADi (the native FMU, the MPC's prediction model), in every drive and
carriage mode."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from wheelterrain.model import rig

MODES = list(itertools.product((rig.DRIVE_PAPER, rig.DRIVE_SPEED, rig.DRIVE_TORQUE),
                               (rig.CARRIAGE_KINEMATIC, rig.CARRIAGE_FREE)))


def params(drive, carriage, **extra):
    p = rig.defaults()
    p.update({"rig.drive": drive, "rig.carriage": carriage, "rig.towing_force": 3.0,
              "rig.slope": 0.1, **extra})
    return p


@pytest.mark.parametrize(("drive", "carriage"), MODES)
def test_float_step_equals_the_casadi_function(drive, carriage):
    fn = rig.build()
    p = params(drive, carriage)
    vector = [p[name] for name in rig.RIG_NAMES]
    rng = np.random.default_rng(drive * 2 + carriage)
    for _ in range(20):
        x = tuple(rng.uniform([0, -0.01, 0.1, -0.01, 0.0], [0.03, 0.01, 1.0, 0.01, 0.05]))
        u = tuple(rng.uniform([40, -10, 0, 0.1, -1], [80, 20, 2, 1.0, 2]))
        h = rng.uniform(1e-4, 1e-2)
        expected, torque = rig.step(x, u, p, h)
        got = fn(x, u, vector, h)
        np.testing.assert_allclose(np.array(got[0]).ravel(), expected, rtol=1e-13, atol=1e-15)
        assert float(got[1]) == pytest.approx(torque, rel=1e-13, abs=1e-15)


@pytest.mark.parametrize(("drive", "carriage"), MODES)
def test_step_converges_to_the_rates_as_the_step_shrinks(drive, carriage):
    """step() integrates rates(): (x(h) - x)/h -> dx/dt, first order in h."""
    p = params(drive, carriage)
    x = (0.012, 0.002, 0.7, 0.003, 0.025)
    u = (60.0, 4.0, 1.1, 0.65, 1.3)
    dx = np.array(rig.rates(x, u, p), dtype=float)
    errors = []
    for h in (1e-5, 1e-6):
        nxt, _ = rig.step(x, u, p, h)
        errors.append(np.max(np.abs((np.array(nxt) - x) / h - dx) / (1 + np.abs(dx))))
    assert errors[1] < 1e-3
    assert errors[1] < 0.2 * errors[0] or errors[1] < 1e-12  # first order, or exact


def test_torque_drive_applies_the_command_and_ignores_the_loop():
    p = params(rig.DRIVE_TORQUE, rig.CARRIAGE_KINEMATIC)
    x = (0.01, 0.0, 0.6, 0.5, 0.03)
    nxt, torque = rig.step(x, (62.0, 5.0, 1.0, 99.0, 1.25), p, 1e-3)
    assert torque == 1.25
    assert nxt[2] == pytest.approx(0.6 + 1e-3 * 0.25 / p["rig.wheel_inertia"], rel=1e-14)
    assert nxt[3] == 0.5  # the loop's integrator is frozen
    assert nxt[4] == 0.03  # kinematic carriage


def test_speed_command_is_tracked_without_steady_error():
    p = params(rig.DRIVE_SPEED, rig.CARRIAGE_KINEMATIC)
    x = rig.initial_state(p)
    for _ in range(2000):  # 2 s, 400 loop time constants
        x, torque = rig.step(x, (62.0, 0.0, 1.3, 0.75, 0.0), p, 1e-3)
    assert x[2] == pytest.approx(0.75, rel=1e-9)
    assert torque == pytest.approx(1.3, rel=1e-9)  # the loop supplies the soil torque


def test_free_carriage_accelerates_with_the_net_force():
    p = params(rig.DRIVE_PAPER, rig.CARRIAGE_FREE)
    mass = p["rig.mass"]
    resistance = mass * rig.STANDARD_GRAVITY * math.sin(0.1) + 3.0
    x = rig.initial_state(p)
    balanced, _ = rig.step(x, (62.0, resistance, 0.5, 0, 0), p, 1e-2)
    assert balanced[4] == pytest.approx(x[4], abs=1e-15)
    pushed, _ = rig.step(x, (62.0, resistance + 2.0, 0.5, 0, 0), p, 1e-2)
    assert pushed[4] == pytest.approx(x[4] + 1e-2 * 2.0 / mass, rel=1e-12)


def test_an_unknown_rig_parameter_is_named_with_its_close_matches():
    from wheelterrain.errors import ParameterError

    with pytest.raises(ParameterError, match=r"rig\.lod = 62.0 is not a rig parameter; did you "
                                             r"mean rig\.load"):
        rig.check("rig.lod", 62.0)
