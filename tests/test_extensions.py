"""The extensions beyond the classical wheel behave as documented."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest

from wheelterrain import model
from wheelterrain.model import soil
from wheelterrain.parameters import INDEX


def test_ripple_follows_the_wheel_angle_with_the_grouser_period(table2):
    period = 2 * math.pi / table2["grouser.count"]
    angles = np.linspace(0, period, 7)
    fz = [model.contact_forces(table2, 0.03, 0.2, wheel_angle=a)["normal_force"] for a in angles]
    assert fz[0] == pytest.approx(fz[-1], rel=1e-12)  # periodic in the wheel angle
    assert max(fz) - min(fz) > 0.5  # and really rippling (N)
    static = model.contact_forces(table2, 0.03, 0.2)["normal_force_static"]
    # the clipped ripple averages close to, not exactly at, the ripple-free force
    mean = np.mean([model.contact_forces(table2, 0.03, 0.2, wheel_angle=a)["normal_force"]
                    for a in np.linspace(0, period, 64, endpoint=False)])
    assert mean == pytest.approx(static, rel=0.05)


def test_ripple_off_when_both_coefficients_are_zero(table2):
    ps = table2.with_values({"ripple.k_g": 0.0, "ripple.k_0": 0.0})
    a = model.contact_forces(ps, 0.03, 0.2, wheel_angle=0.1)
    b = model.contact_forces(ps, 0.03, 0.2, wheel_angle=1.3)
    assert a["normal_force"] == b["normal_force"]
    assert a["ripple_amplitude"] == 0.0


def test_wong_hump_peaks_at_K_and_tends_to_the_residual_ratio(table2):
    j = ca.SX.sym("j")
    p = ca.SX.sym("p", len(INDEX))
    g = ca.Function("g", [j, p], [soil.shear_function(j, soil.Params(p))])
    ps = table2.with_values({"model.shear_model": 1, "soil.residual_ratio": 0.6}).vector()
    K = table2["soil.shear_modulus"]
    assert float(g(K, ps)) == pytest.approx(1.0, rel=1e-14)
    assert float(g(50 * K, ps)) == pytest.approx(0.6, rel=1e-9)
    assert float(g(-K, ps)) == pytest.approx(-1.0, rel=1e-14)  # odd
    janosi = table2.with_values({"model.shear_model": 0}).vector()
    assert float(g(K, janosi)) == pytest.approx(1 - math.exp(-1), rel=1e-14)


def test_damping_acts_only_in_contact_and_never_pulls(table2):
    still = model.contact_forces(table2, 0.02, 0.2)["normal_force"]
    sinking = model.contact_forces(table2, 0.02, 0.2, sinkage_rate=0.01)["normal_force"]
    assert sinking - still == pytest.approx(table2["soil.damping"] * 0.01, rel=1e-3)
    rising = model.contact_forces(table2, 0.02, 0.2, sinkage_rate=-10.0)["normal_force"]
    assert rising == 0.0


def test_grouser_tip_radius_gives_positive_pull_at_zero_paper_slip(table2):
    """model-notes: contact at the tips with slip referenced to the rim gives traction at s = 0."""
    rim = model.steady_state(table2, 62, 0.0)
    tips = model.steady_state(table2.with_values({"model.contact_radius_factor": 1.0,
                                                  "model.shear_radius_factor": 1.0}), 62, 0.0)
    assert rim["drawbar_pull"] < 0 < tips["gross_thrust"]
    assert tips["drawbar_pull"] > rim["drawbar_pull"]


def test_slip_sinkage_exponent_deepens_with_slip(table2):
    flat = table2.with_values({"soil.n1": 0.0})
    z_flat = [model.steady_state(flat, 62, i)["sinkage"] for i in (0.0, 0.4)]
    z_n1 = [model.steady_state(table2, 62, i)["sinkage"] for i in (0.0, 0.4)]
    assert z_n1[0] == pytest.approx(z_flat[0], rel=1e-12)  # n1 has no effect at zero slip
    assert z_n1[1] - z_n1[0] > z_flat[1] - z_flat[0]


@pytest.mark.parametrize(("slip", "cohesion"), [(0.1, 0.0), (0.5, 800.0), (-0.3, 0.0),
                                                (-1.0, 0.0)])
def test_grouser_thrust_is_the_documented_passive_force_integral(table2, slip, cohesion):
    """Independent check with scipy quad of the grouser-thrust formula in contact.py
    (rim contact: every grouser on the arc is buried over its full height). ``slip`` is the
    model's: braking, the skid, down to the locked wheel (-1)."""
    from scipy.integrate import quad

    ps = table2.with_values({"soil.cohesion": cohesion, "model.exit_ratio": 0.0,
                             "soil.n1": 0.0, "ripple.k_g": 0.0, "ripple.k_0": 0.0})
    z = 0.03
    on = model.contact_forces(ps.with_values({"model.grouser_thrust": 1}), z, slip,
                              slip_definition="unified")
    off = model.contact_forces(ps, z, slip, slip_definition="unified")
    R, h, b = ps["wheel.radius"], ps["grouser.height"], ps["wheel.width"]
    K, gamma, c = ps["soil.shear_modulus"], ps["soil.gamma"], cohesion
    kp = math.tan(math.pi / 4 + ps["soil.phi"] / 2) ** 2
    tf = math.acos(1 - z / R)

    def integrand(t, part):
        top = R * math.cos(t) - R * math.cos(tf)
        height = (R + h) * math.cos(t) - R * math.cos(tf) - top
        force = (0.5 * gamma * height**2 * kp + 2 * c * height * math.sqrt(kp)
                 + gamma * top * height * kp)
        if slip >= 0:  # the wheel element; braking, per distance travelled
            j = R * ((tf - t) - (1 - slip) * (math.sin(tf) - math.sin(t)))
        else:
            j = R * ((1 + slip) * (tf - t) - (math.sin(tf) - math.sin(t)))
        g = math.copysign(1 - math.exp(-abs(j) / K), j)
        return force * g * {"x": math.cos(t), "z": math.sin(t), "t": R + h / 2}[part]

    density = b * ps["grouser.count"] / (2 * math.pi)
    breaks = [tf * 0.5]
    want = {k: density * quad(integrand, 0.0, tf, args=(k,), points=breaks, epsabs=1e-13,
                              epsrel=1e-12, limit=200)[0] for k in ("x", "z", "t")}
    assert on["drawbar_pull"] - off["drawbar_pull"] == pytest.approx(want["x"], rel=1e-6)
    assert on["normal_force"] - off["normal_force"] == pytest.approx(want["z"], rel=1e-6)
    assert on["torque"] - off["torque"] == pytest.approx(want["t"], rel=1e-6)
    if slip > 0:
        assert want["x"] > 0  # a driven wheel's grousers push: positive thrust


def test_grouser_thrust_vanishes_without_grousers(table2):
    ps = table2.with_values({"grouser.height": 0.0})
    on = model.contact_forces(ps.with_values({"model.grouser_thrust": 1}), 0.03, 0.3)
    off = model.contact_forces(ps, 0.03, 0.3)
    assert on["drawbar_pull"] == off["drawbar_pull"]
