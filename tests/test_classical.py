"""With every extension off the model is the classical Wong-Reece rigid wheel, exactly.

Checked against tests/classical_reference.py: an independent plain-Python implementation using
scipy's adaptive quadrature and Brent's method, over a grid of slips, loads and soils.
"""

from __future__ import annotations

import math

import pytest

from classical_reference import Classical
from conftest import classical_set
from wheelterrain import model

# (id, wheel radius, width, cohesion, phi [deg], k_c', k_phi', n, gamma, K, a0, a1)
SOILS = [
    ("rashid-table2", 0.05, 0.075, 0.0, 23.0, 0.63, 80.0, 1.1, 15620.0, 0.036, 0.40, 0.15),
    ("dry-sand-wong", 0.25, 0.15, 1040.0, 28.0, 0.99, 1528.43, 1.1, 15690.0, 0.025, 0.43, 0.32),
    ("cohesive-loam", 0.15, 0.10, 3000.0, 20.0, 30.0, 300.0, 0.8, 17000.0, 0.02, 0.40, 0.15),
    ("soft-low-n", 0.10, 0.08, 200.0, 33.0, 5.0, 60.0, 0.5, 9000.0, 0.05, 0.35, 0.25),
]
DRIVING_SLIPS = [0.0, 0.05, 0.2, 0.45, 0.7, 0.9, 0.99]
LOAD_FRACTIONS = [0.02, 0.25, 0.6, 0.95]  # of the wheel's capacity at that slip
RTOL = 1e-6  # the bar; measured agreement is ~1e-11


def _pair(row):
    _, R, b, c, phi, kc, kphi, n, gamma, K, a0, a1 = row
    ref = Classical(R=R, b=b, c=c, phi=math.radians(phi), kc=kc, kphi=kphi, n=n, gamma=gamma, K=K,
                    a0=a0, a1=a1)
    return ref, classical_set(R, b, c, phi, kc, kphi, n, gamma, K, a0, a1)


def _close(got: float, want: float, scale: float) -> bool:
    return abs(got - want) <= RTOL * max(abs(want), scale)


@pytest.mark.parametrize("row", SOILS, ids=[s[0] for s in SOILS])
@pytest.mark.parametrize("slip", DRIVING_SLIPS)
def test_forces_at_given_sinkage_match_reference(row, slip):
    ref, ps = _pair(row)
    R = row[1]
    for frac in (1e-4, 0.05, 0.3, 0.7, 1.0):
        z = frac * R
        want, got = ref.forces(z, slip), model.contact_forces(ps, z, slip)
        for key in want:
            # Drawbar pull passes through zero as slip grows: compare it on the scale of the
            # thrust/resistance it is the difference of (the normal force), not on its own size.
            scale = abs(want["normal_force"]) if key == "drawbar_pull" else 0.0
            assert _close(got[key], want[key], scale), (
                f"{key} at z={z:g} m, i={slip}: model {got[key]!r} vs reference {want[key]!r}")


@pytest.mark.parametrize("row", SOILS, ids=[s[0] for s in SOILS])
@pytest.mark.parametrize("slip", [-0.5, -0.1, 0.0, 0.2, 0.7, 0.99])
@pytest.mark.parametrize("load_fraction", LOAD_FRACTIONS)
def test_quasi_static_sinkage_matches_reference(row, slip, load_fraction):
    ref, ps = _pair(row)
    load = load_fraction * model.capacity(ps, slip)
    got = model.steady_state(ps, load, slip)
    z_ref = ref.sinkage(load, slip)
    assert _close(got["sinkage"], z_ref, 0.0), f"sinkage {got['sinkage']!r} vs {z_ref!r}"
    want = ref.forces(z_ref, slip)
    R = row[1]
    for key in want:
        scale = abs(want["normal_force"]) if key == "drawbar_pull" else 0.0
        if key == "torque" and slip < 0:  # braking torque passes through zero, as in the test below
            scale = abs(want["normal_force"]) * R
        assert _close(got[key], want[key], scale), f"{key}: {got[key]!r} vs {want[key]!r}"


# Braking (i < 0): the shear displacement j changes sign inside the arc, where the odd shear law
# has a kink; the model splits its quadrature there (the reference splits there too, independently,
# with brentq). Held to the same 1e-6 bar as driving; measured worst ~6e-8 (dry sand, K/R = 0.1).


@pytest.mark.parametrize("row", SOILS, ids=[s[0] for s in SOILS])
@pytest.mark.parametrize("slip", [-0.9, -0.5, -0.1])
def test_braking_forces_match_reference(row, slip):
    ref, ps = _pair(row)
    R = row[1]
    for frac in (0.05, 0.3, 0.6, 1.0):
        want, got = ref.forces(frac * R, slip), model.contact_forces(ps, frac * R, slip)
        for key in want:
            # torque is compared on the scale normal force x radius, forces on the normal force
            ref_scale = abs(want["normal_force"]) * (R if key == "torque" else 1.0)
            assert abs(got[key] - want[key]) <= RTOL * max(abs(want[key]), ref_scale), (
                f"{key} at z={frac * R:g}, i={slip}: {got[key]!r} vs {want[key]!r}")


# The soil-element shear kinematics (model.shear_kinematics = 1, the Soil Contact Model's way of
# counting the Janosi displacement) against the same reference with its j integrated numerically.
SOIL_KINEMATICS_SLIPS = [-0.5, 0.0, 0.2, 0.7, 0.99]


@pytest.mark.parametrize("row", SOILS, ids=[s[0] for s in SOILS])
@pytest.mark.parametrize("slip", SOIL_KINEMATICS_SLIPS)
def test_soil_element_kinematics_matches_reference(row, slip):
    _, R, b, c, phi, kc, kphi, n, gamma, K, a0, a1 = row
    ref = Classical(R=R, b=b, c=c, phi=math.radians(phi), kc=kc, kphi=kphi, n=n, gamma=gamma,
                    K=K, a0=a0, a1=a1, kinematics="soil")
    ps = classical_set(R, b, c, phi, kc, kphi, n, gamma, K, a0, a1).with_values(
        {"model.shear_kinematics": 1})
    for frac in (0.01, 0.3, 0.9):
        z = frac * R
        want, got = ref.forces(z, slip), model.contact_forces(ps, z, slip)
        for key in want:
            scale = abs(want["normal_force"]) * (R if key == "torque" else 1.0)
            scale = scale if key != "normal_force" else 0.0
            assert _close(got[key], want[key], scale), (
                f"{key} at z={z:g} m, i={slip}: model {got[key]!r} vs reference {want[key]!r}")


def test_soil_element_kinematics_gains_pull_with_slip_faster_than_the_wheel_element():
    """The switch really changes the model: the soil element's j grows like 1/(1 - i) = 1 + s,
    the wheel element's like (1 - i), so the soil-element pull overtakes at higher slip."""
    _, R, b, c, phi, kc, kphi, n, gamma, K, a0, a1 = SOILS[0]
    wheel = classical_set(R, b, c, phi, kc, kphi, n, gamma, K, a0, a1)
    soil = wheel.with_values({"model.shear_kinematics": 1})
    gaps = [model.contact_forces(soil, 0.02, i)["drawbar_pull"]
            - model.contact_forces(wheel, 0.02, i)["drawbar_pull"] for i in (0.1, 0.5, 0.9)]
    assert gaps[0] < 0 < gaps[1] < gaps[2]  # measured -0.34, 1.38, 5.06 N
