"""A wheel that yaws: the turn slip (yaw rate over forward speed) in the one core's lateral
contact (contact.lateral_at), against an independent implementation of the brush model of turn
slip on Ishigami et al. 2007's side force (tests/classical_reference.py, scipy's adaptive
quadrature), and its properties in both forms: the turning moment resists the yawing, rises with
the load and the sinkage (Ding et al. 2013's trend), its Jacobian is exact, and a turn slip 0
leaves every figure of the slip angle alone."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from classical_reference import Classical
from conftest import classical_set
from test_classical import SOILS
from wheelterrain import model, presets
from wheelterrain.model import contact, functions
from wheelterrain.parameters import TURN_SLIP_LIMIT

CASES = ((0.0, 0.2), (0.0, -0.5), (math.radians(10.0), 0.3), (math.radians(-20.0), 0.5),
         (math.radians(5.0), -1.0), (math.radians(15.0), 0.0))
"""(slip angle [rad], turn slip times the wheel radius): yawing alone both ways, with a slip
angle of the same sign and of the opposite sign (the lateral displacement then reverses on the
arc), a slip angle alone."""


def _lateral(ps, z, slip, beta, turn):
    out = functions.build().lateral(z, slip, beta, turn, ps.vector())
    return dict(zip(contact.LATERAL_OUTPUTS, (float(v) for v in out), strict=True))


@pytest.mark.parametrize("row", SOILS, ids=[s[0] for s in SOILS])
@pytest.mark.parametrize("slip", [0.0, 0.2, 0.7])
def test_the_arc_form_is_the_brush_model_of_turn_slip(row, slip):
    """Classical wheel (every extension off), driving: the side force, the aligning, turning
    and overturning moments match the reference's adaptive quadrature over sinkages from 5 % to 70 %
    of the radius and CASES. The tolerances are the core's quadrature error, measured: the
    arc's rule is not split where the lateral displacement reverses (a kink of the odd shear
    law), 1.7e-5 of the lateral strength at most there, 3e-7 elsewhere; the width's 6-point
    rule (contact.WIDTH_NODES) 1.0e-4 of the width moment at most (at slip 0, where the
    longitudinal displacement changes sign across the tread)."""
    _, R, b, c, phi, kc, kphi, n, gamma, K, a0, a1 = row
    ref = Classical(R=R, b=b, c=c, phi=math.radians(phi), kc=kc, kphi=kphi, n=n, gamma=gamma,
                    K=K, a0=a0, a1=a1)
    ps = classical_set(R, b, c, phi, kc, kphi, n, gamma, K, a0, a1)
    for frac in (0.05, 0.3, 0.7):
        z = frac * R
        normal = ref.forces(z, slip)["normal_force"]
        scale = c * b * R + normal * math.tan(math.radians(phi))  # the lateral strength's size
        for beta, turn_r in CASES:
            turn = turn_r / R
            want = ref.turning(z, slip, beta, turn, K)
            got = _lateral(ps, z, slip, beta, turn)
            reverses = beta * turn < 0
            tol = (5e-5 if reverses else 1e-6) * scale
            assert abs(got["lateral_force"] - want["lateral_force"]) <= tol, (z, beta, turn)
            assert abs(got["aligning_moment"] - want["aligning_moment"]) <= tol * R, (
                z, beta, turn)
            assert abs(got["overturning_moment"] - want["overturning_moment"]) <= tol * R, (
                z, beta, turn, got["overturning_moment"], want["overturning_moment"])
            width = want["turning_moment"] - want["aligning_moment"]
            got_width = got["turning_moment"] - got["aligning_moment"]
            assert abs(got_width - width) <= 3e-4 * abs(width) + 1e-6 * scale * R, (
                z, beta, turn, got_width, width)


@pytest.mark.parametrize("preset", ["rashid-patch", "rashid-calibrated"])
def test_the_turning_moment_resists_the_yawing_and_is_odd(preset):
    """At a turn slip alone the turning moment opposes the yaw, grows with the turn slip up to
    the limit, and flips with it exactly (odd in the pair slip angle, turn slip); at turn slip
    0 it is the aligning moment, bit for bit, and the slip angle's outputs are unchanged."""
    ps = presets.load(preset)
    for load, slip in ((62.0, 0.2), (24.5, -0.4), (40.0, 0.6)):
        z = model.steady_state(ps, load, slip)["sinkage"]
        moments = []
        for turn in np.linspace(0.5, TURN_SLIP_LIMIT, 8):
            plus, minus = _lateral(ps, z, slip, 0.0, turn), _lateral(ps, z, slip, 0.0, -turn)
            assert all(plus[k] == -minus[k] for k in plus)
            assert plus["turning_moment"] < 0
            moments.append(-plus["turning_moment"])
        assert np.all(np.diff(moments) > 0), moments
        beta = math.radians(12.0)
        plain = _lateral(ps, z, slip, beta, 0.0)
        assert plain["turning_moment"] == plain["aligning_moment"]
        both = _lateral(ps, z, slip, beta, 3.0)
        assert {k: -v for k, v in both.items()} == _lateral(ps, z, slip, -beta, -3.0)


@pytest.mark.parametrize("form", [0, 1], ids=["arc", "patch"])
def test_the_turning_moment_rises_with_load_and_sinkage(form):
    """Ding et al. 2013 (Int. J. Robotics Research 32(6)) measure the steering resistance
    moment of a lugged wheel rising with its vertical load and its sinkage; the turning moment
    at a turn slip of 4 rad/m (slip 0.1) does too, from 10 N to 100 N, in both forms."""
    ps = presets.load().with_values({"model.contact_form": form})
    sinkages, moments = [], []
    for load in (10.0, 25.0, 40.0, 62.0, 80.0, 100.0):
        st = model.steady_state(ps, load, 0.1, turn_slip=4.0)
        sinkages.append(st["sinkage"])
        moments.append(-st["turning_moment"])
    assert np.all(np.diff(sinkages) > 0)
    assert np.all(np.diff(moments) > 0), moments


@pytest.mark.parametrize("preset", ["rashid-patch", "rashid-calibrated"])
def test_the_exact_jacobian_in_the_turn_slip_matches_finite_differences(preset):
    """build().lateral_jacobian: the lateral force, aligning and turning moments by sinkage,
    slip, slip angle and turn slip, against central differences."""
    ps = presets.load(preset)
    z = model.steady_state(ps, 62.0, 0.25)["sinkage"]
    fns = functions.build()
    rows = [contact.LATERAL_OUTPUTS.index(k) for k in contact.LATERAL_RESULTANTS]
    for beta, turn in ((0.0, 1.5), (math.radians(12.0), -4.0), (math.radians(-30.0), 7.0)):
        jac = np.array(fns.lateral_jacobian(z, 0.25, beta, turn, ps.vector()))
        steps = np.diag([1e-7, 1e-6, 1e-7, 1e-5])
        for col in range(4):
            dz, ds, db, dt = steps[col]
            up = np.array([float(v) for v in fns.lateral(z + dz, 0.25 + ds, beta + db,
                                                          turn + dt, ps.vector())])[rows]
            down = np.array([float(v) for v in fns.lateral(z - dz, 0.25 - ds, beta - db,
                                                            turn - dt, ps.vector())])[rows]
            fd = (up - down) / (2 * steps[col, col])
            assert np.allclose(jac[:, col], fd, rtol=1e-5, atol=1e-6 * np.abs(fd).max()), (
                beta, turn, col, jac[:, col], fd)


def test_steady_cli_takes_a_turn_slip():
    from click.testing import CliRunner

    from wheelterrain.cli import main

    runner = CliRunner()
    out = runner.invoke(main, ["steady", "--slip", "0.2", "--load", "62", "--turn-slip", "5",
                               "--json", "-"])
    assert out.exit_code == 0, out.output
    got = json.loads(out.output)
    want = model.steady_state(presets.load(), 62.0, 0.2, turn_slip=5.0)
    for key in ("turning_moment", "aligning_moment", "lateral_force", "turn_slip"):
        assert got[key] == want[key], key
    assert got["slip_angle"] == 0.0
    assert got["turning_moment"] < 0
    for bad in ("11", "nan", "-10.5"):
        out = runner.invoke(main, ["steady", "--slip", "0.2", "--load", "62",
                                   "--turn-slip", bad])
        assert out.exit_code == 2
        assert "--turn-slip" in out.output
        assert "rad/m" in out.output
        assert "Traceback" not in out.output


@pytest.mark.parametrize("form", [0, 1], ids=["arc", "patch"])
def test_the_declared_ranges_hold_to_the_locked_wheel(form):
    """Turn slips over the whole declared range, with slip angles over theirs, from the locked
    wheel (-1) to spinning (0.999), sinkages from 0 to deep: every lateral output finite, the
    turning moment against the yaw where the wheel yaws alone and the moment is above
    rounding (spinning, the longitudinal shear is fully mobilised everywhere, so the yaw's
    extra displacement across the width moves it by nothing: 1e-28 N.m at slip 0.999 and
    turn slip -1e-9 rad/m, of either sign)."""
    from wheelterrain.parameters import SLIP_ANGLE_LIMIT

    ps = presets.load().with_values({"model.contact_form": form})
    for z in (0.0, 1e-7, 0.01, 0.05):
        for slip in (-1.0, -0.5, 0.0, 0.5, 0.999):
            for turn in (-TURN_SLIP_LIMIT, -1e-9, 3.0, TURN_SLIP_LIMIT):
                for beta in (-SLIP_ANGLE_LIMIT, 0.0, 0.2, SLIP_ANGLE_LIMIT):
                    out = _lateral(ps, z, slip, beta, turn)
                    assert all(math.isfinite(v) for v in out.values()), (z, slip, turn, beta)
                    if beta == 0.0 and z > 0 and abs(out["turning_moment"]) > 1e-15:
                        assert out["turning_moment"] * turn < 0, (z, slip, turn, out)


@pytest.mark.parametrize("form", [0, 1], ids=["arc", "patch"])
def test_the_overturning_moment_is_the_side_force_at_a_depth_within_the_contact(form):
    """M_x over F_y, the depth below the centre the side force acts at, lies between the
    surface the contact begins at (R_c*cos(theta_f)) and the rim's lowest point (R_c), at slip
    angles and turn slips of either sign, driving and braking; M_x is 0 at slip angle and turn
    slip 0 and odd in the pair, as the lateral force is."""
    from wheelterrain.model import contact as c

    ps = presets.load().with_values({"model.contact_form": form})
    Rc = float(ps["wheel.radius"] + ps["model.contact_radius_factor"] * ps["grouser.height"])
    for load, slip in ((62.0, 0.2), (24.5, -0.4), (40.0, 0.7)):
        st = model.steady_state(ps, load, slip)
        z = st["sinkage"]
        top = Rc * math.cos(st["entry_angle"])
        assert _lateral(ps, z, slip, 0.0, 0.0)["overturning_moment"] == 0.0
        for beta, turn in ((0.3, 0.0), (-0.6, 2.0), (0.0, -5.0), (1.2, 9.0)):
            out = _lateral(ps, z, slip, beta, turn)
            depth = out["overturning_moment"] / out["lateral_force"]
            assert top - 1e-9 <= depth <= Rc + 1e-9, (slip, beta, turn, top, depth, Rc)
            assert _lateral(ps, z, slip, -beta, -turn)["overturning_moment"] == (
                -out["overturning_moment"])
    assert "overturning_moment" in c.LATERAL_RESULTANTS
