"""Braking down to the locked wheel: the model's slip runs from -1 (omega = 0) to 1, every face
takes it, and the braking force behaves as a soil's can."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner

from classical_reference import Classical
from conftest import classical_set
from test_classical import SOILS
from wheelterrain import compiled, model, presets
from wheelterrain.cli import main

LOCKED_TRACTION = -1e12  # the reference takes traction slip: a locked wheel is i -> -inf


@pytest.mark.parametrize("row", SOILS, ids=[s[0] for s in SOILS])
@pytest.mark.parametrize("kinematics", ["wheel", "soil"])
def test_a_locked_wheel_is_the_classical_references_limit(row, kinematics):
    """At the lock (the paper's slip -1) the classical model gives the independent reference's
    forces in the limit of traction slip -> -inf, at several sinkages, both kinematics."""
    _, R, b, c, phi, kc, kphi, n, gamma, K, a0, a1 = row
    ref = Classical(R=R, b=b, c=c, phi=math.radians(phi), kc=kc, kphi=kphi, n=n, gamma=gamma,
                    K=K, a0=a0, a1=a1, kinematics=kinematics)
    ps = classical_set(R, b, c, phi, kc, kphi, n, gamma, K, a0, a1).with_values(
        {"model.shear_kinematics": int(kinematics == "soil")})
    for frac in (0.05, 0.3, 0.8):
        want = ref.forces(frac * R, LOCKED_TRACTION)
        got = model.contact_forces(ps, frac * R, -1.0, slip_definition="paper")
        for key, value in want.items():
            scale = abs(want["normal_force"]) * (R if key == "torque" else 1.0)
            assert abs(got[key] - value) <= 1e-6 * max(abs(value), scale), (key, frac)


CASES = [(name, kin) for name in presets.available() for kin in (0, 1)]


@pytest.mark.parametrize(("preset", "kinematics"), CASES, ids=[f"{p}-{k}" for p, k in CASES])
@pytest.mark.parametrize("load", [24.5, 62.0])
def test_the_braking_force_is_continuous_and_grows_to_the_lock_within_coulomb(preset, kinematics,
                                                                             load):
    """Steady states from free rolling to the locked wheel: the drawbar pull is continuous
    through slip 0 (both sides within 1e-6 of the load), the braking force (-pull) does not
    fall as the skid grows to -1, and the shear part of it (the gross thrust) stays within the
    soil's Coulomb limit at the contact, c*b*l + W*tan(phi)."""
    ps = presets.load(preset).with_values({"model.shear_kinematics": kinematics})
    slips = np.linspace(-1.0, 0.0, 41)
    out = model.steady_states(ps, load, slips, slip_definition="unified")
    braking = -out["drawbar_pull"]
    assert np.all(np.diff(braking) <= 1e-9 * load), braking  # slips rise: braking falls
    near = model.steady_states(ps, load, [-1e-9, 0.0, 1e-9], slip_definition="unified")
    assert np.ptp(near["drawbar_pull"]) <= 1e-6 * load
    limit = (ps["soil.cohesion"] * ps["wheel.width"] * out["contact_length"]
             + load * math.tan(ps["soil.phi"]))
    assert np.all(np.abs(out["gross_thrust"]) <= limit)
    assert braking[0] > braking[-1]  # the lock brakes harder than free rolling


def test_steady_and_sweep_take_a_locked_wheel_in_every_definition(tmp_path):
    """`steady` takes the lock as the paper's -1 or the unified -1 (the same point), the
    traction definition refuses it with the way to say it; its JSON says slip -1."""
    runner = CliRunner()
    got = []
    for definition in ("paper", "unified"):
        run = runner.invoke(main, ["steady", "--slip", "-1", "--slip-definition", definition,
                                   "--load", "24.5", "--json"])
        assert run.exit_code == 0, run.output
        got.append(json.loads(run.stdout))
    assert got[0] == got[1]
    assert got[0]["slip"] == -1.0
    assert got[0]["slip_paper"] == -1.0
    assert got[0]["drawbar_pull"] < 0
    refused = runner.invoke(main, ["steady", "--slip", "-inf", "--load", "24.5"])
    assert refused.exit_code == 2
    assert "a locked wheel is traction slip -inf: give it as --slip-definition paper -1" \
        in refused.output


@pytest.mark.skipif(compiled.compiler() is None, reason="no C compiler")
@pytest.mark.parametrize("path", ["native/WheelTerrain.fmu", "native/fmi3/WheelTerrain.fmu",
                                  "pythonfmu/WheelTerrain.fmu"])
@pytest.mark.parametrize("kind", ["CoSimulation", "ModelExchange"])
def test_every_fmu_serves_a_locked_wheel(built_root, path, kind):
    """A wheel that does not turn under a moving axle: slip -1 and the contact model's forces,
    in co-simulation and model exchange, FMI 2 and 3, both flavours."""
    from fmpy import read_model_description, simulate_fmu

    fmu = str(built_root / path)
    if kind == "ModelExchange" and read_model_description(fmu).modelExchange is None:
        pytest.skip("the pythonfmu flavour is co-simulation only")
    inputs = {"sinkage": 0.015, "wheel_speed": 0.0, "carriage_speed": 0.02}
    names = ["slip", "slip_paper", "normal_force", "drawbar_pull", "torque"]
    run = simulate_fmu(fmu, fmi_type=kind, stop_time=0.1, output_interval=1e-2,
                       start_values=inputs, output=names)
    want = model.contact_forces(presets.load(presets.DEFAULT_PRESET), 0.015, -1.0,
                                slip_definition="unified")
    assert np.all(run["slip"] == -1.0)
    assert np.all(run["slip_paper"] == -1.0)
    for key in ("normal_force", "drawbar_pull", "torque"):
        assert run[key] == pytest.approx(want[key], rel=1e-9), key


def test_the_slip_is_regularised_through_standstill_and_unchanged_where_it_was_defined():
    """The model's slip in the frame of the faster motion (functions.backward: the mirror image
    where omega*R + V < 0), (omega*R - V)/max(|omega*R|, |V|, v0) with v0 = SLIP_SPEED_FLOOR:
    - where both speeds have one sign and the faster is at least v0 (every declared operating
      point), bit for bit (omega*R - V)/max(omega*R, V) along the rolling, the slip before
      the regularisation;
    - within v0 of rest (|omega*R| + |V| <= v0) in [-1, 1] whatever the signs, and a
      continuous function of the speeds on either side of the line where the rolling flips:
      no step between neighbouring grid points larger than its Lipschitz bound 2*step/v0;
    - 0 at rest, and the wheel turning against its axle's motion beyond v0 outside [-1, 1]."""
    from wheelterrain.fmu import functions

    v0 = functions.SLIP_SPEED_FLOOR

    def sigma(rim, speed):
        sign = np.where(functions.backward(rim, speed, 1.0), -1.0, 1.0)
        got, _ = functions.slips(sign * rim, sign * speed, 1.0)
        return np.asarray(got, dtype=float).reshape(np.shape(rim))

    assert sigma(np.array(0.0), np.array(0.0)) == 0.0
    # the declared operating points: one sign, the faster at least v0
    rng = np.random.default_rng(7)
    faster = v0 * 10 ** rng.uniform(0, 6, 4000)
    ratio = rng.uniform(0, 1, 4000)
    for sign in (1.0, -1.0):
        for rim, speed in ((faster, faster * ratio), (faster * ratio, faster)):
            want = (rim - speed) / np.maximum(rim, speed)  # along the rolling
            np.testing.assert_array_equal(sigma(sign * rim, sign * speed), want)
    # through rest: a grid over [-3 v0, 3 v0]^2
    step = v0 / 50
    axis = np.arange(-150, 151) * step
    rim, speed = np.meshgrid(axis, axis, indexing="ij")
    s = sigma(rim, speed)
    near = np.abs(rim) + np.abs(speed) <= v0 * (1 - 1e-12)
    assert np.all(np.abs(s[near]) <= 1)
    against = (rim * speed < 0) & (np.abs(rim) + np.abs(speed) > v0 * (1 + 1e-9))
    assert np.all(np.abs(s[against]) > 1)
    flips = np.sign(rim + speed)
    for axis_k in (0, 1):
        jump = np.abs(np.diff(s, axis=axis_k))
        same_side = np.diff(flips, axis=axis_k) == 0
        assert np.all(jump[same_side] <= 2 * step / v0 * (1 + 1e-9))


def test_a_driven_wheel_on_a_free_carriage_stops_and_reverses_through_the_turn_of_rolling():
    """WheelTerrain's model-exchange contact (functions.terrain_dynamic, what both FMU flavours
    run) under a wheel on a free carriage: its load, the carriage's mass and a PI speed loop of
    the rig's, the command ramped from 0.03 m/s to -0.03 m/s over 1-3 s. An ODE solver (LSODA)
    passes the reversal and the carriage runs backward at the speed the same run with the
    command held reaches forward (rolling backward is the mirror of rolling forward; within
    1 %, the imprint's history differs). Without the blend of the two
    directions of rolling over SLIP_SPEED_FLOOR (functions.turning_weight) it stalled at the
    turn: a sliding mode at omega*R = -V, some 1e6 evaluations for 5e-6 s. At rest the contact
    is the symmetric imprint: no pull and no torque."""
    from scipy.integrate import solve_ivp

    from wheelterrain.fmu import functions
    from wheelterrain.fmu.variables import TERRAIN_INPUTS, TERRAIN_OUTPUTS
    from wheelterrain.model import rig
    from wheelterrain.parameters import NAMES

    dynamic, _, _ = functions.terrain_functions()
    values = presets.load(presets.DEFAULT_PRESET)
    p = [values[n] for n in NAMES]
    radius = float(functions.slip_radius(p))
    r = rig.defaults()
    load, mass, inertia = r["rig.load"], r["rig.mass"], r["rig.wheel_inertia"]
    gain, integral_time = 2 * r["rig.speed_bandwidth"] * inertia, 2 / r["rig.speed_bandwidth"]
    pull, torque, normal = (TERRAIN_OUTPUTS.index(n) for n in (
        "drawbar_pull", "torque", "normal_force"))
    calls = []

    reverse = [True]

    def command(t):
        return 0.03 * (1 - reverse[0] * min(max(t - 1.0, 0.0), 2.0)) / radius

    def contact(z, z_rate, omega, speed, angle, plastic):
        u = dict.fromkeys(TERRAIN_INPUTS, 0.0)
        u.update(sinkage=z, sinkage_rate=z_rate, wheel_speed=omega, carriage_speed=speed,
                 load=load)
        y, status, _, rate = dynamic([u[n] for n in TERRAIN_INPUTS], angle, plastic, p)
        assert int(status) == functions.STATUS_OK, (omega, speed)
        return np.asarray(y, dtype=float).ravel(), float(rate)

    def rates(t, x):
        z, z_rate, speed, omega, error, angle, plastic = x
        calls.append(t)
        y, plastic_rate = contact(z, z_rate, omega, speed, angle, plastic)
        e = command(t) - omega
        motor = gain * (e + error / integral_time)
        return [z_rate, (load - y[normal]) / mass, y[pull] / mass,
                (motor - y[torque]) / inertia, e, omega, plastic_rate]

    start = [0.0137, 0.0, 0.03, 0.03 / radius, 0.0, 0.0, 0.0137]
    run = solve_ivp(rates, (0.0, 4.0), start, method="LSODA", rtol=1e-6, atol=1e-10,
                    max_step=0.01, dense_output=True)
    assert run.status == 0, run.message
    assert len(calls) < 50_000  # chattering at the turn took ~1e6 for 5e-6 s
    backward = run.y[2, -1]
    reverse[0] = False  # the same run with the command held: where the mirror ends
    held = solve_ivp(rates, (0.0, 4.0), start, method="LSODA", rtol=1e-6, atol=1e-10,
                     max_step=0.01)
    forward = held.y[2, -1]
    assert forward > 0.029
    assert backward < -0.029
    # not the mirror to the digit: the reversed wheel travelled less, so its imprint settled
    # less (measured: 12.66 against 12.50 mm, speeds 0.52 % apart)
    assert run.y[0, -1] > held.y[0, -1]
    assert backward == pytest.approx(-forward, rel=0.01)
    at_rest, _ = contact(0.0137, 0.0, 0.0, 0.0, 0.0, 0.0137)
    assert at_rest[pull] == 0
    assert at_rest[torque] == 0
    assert at_rest[normal] > 0
