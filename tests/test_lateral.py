"""A wheel at a slip angle: the lateral contact of the one core (contact.lateral_at), against an
independent implementation of Ishigami et al. 2007's side-force integrals
(tests/classical_reference.py, scipy's adaptive quadrature), and its properties in both forms."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from classical_reference import Classical
from conftest import classical_set
from test_classical import SOILS
from wheelterrain import model, presets
from wheelterrain.model import contact, functions

RTOL = 1e-6
ANGLES = (math.radians(3.0), math.radians(20.0), math.radians(-35.0))


def _lateral(ps, z, slip, beta, turn=0.0):
    out = functions.build().lateral(z, slip, beta, turn, ps.vector())
    return {k: float(v) for k, v in zip(contact.LATERAL_OUTPUTS, out, strict=True)}


@pytest.mark.parametrize("row", SOILS, ids=[s[0] for s in SOILS])
@pytest.mark.parametrize("slip", [0.0, 0.2, 0.7])
@pytest.mark.parametrize("ratio", [1.0, 0.4])
def test_the_arc_form_is_ishigamis_side_force(row, slip, ratio):
    """Classical wheel (every extension off), driving: the side force and its moment match the
    reference's adaptive quadrature within 1e-6 of the full lateral strength, over sinkages
    from 5 % to 70 % of the radius, three slip angles and two lateral moduli."""
    _, R, b, c, phi, kc, kphi, n, gamma, K, a0, a1 = row
    ref = Classical(R=R, b=b, c=c, phi=math.radians(phi), kc=kc, kphi=kphi, n=n, gamma=gamma,
                    K=K, a0=a0, a1=a1)
    ps = classical_set(R, b, c, phi, kc, kphi, n, gamma, K, a0, a1).with_values(
        {"model.lateral_shear_ratio": ratio})
    for frac in (0.05, 0.3, 0.7):
        z = frac * R
        normal = ref.forces(z, slip)["normal_force"]
        scale = c * b * R + normal * math.tan(math.radians(phi))  # the lateral strength's size
        for beta in ANGLES:
            want = ref.lateral(z, slip, beta, ratio * K)
            got = _lateral(ps, z, slip, beta)
            assert abs(got["lateral_force"] - want["lateral_force"]) <= RTOL * scale, (
                z, beta, got, want)
            assert abs(got["aligning_moment"] - want["aligning_moment"]) <= RTOL * scale * R, (
                z, beta, got, want)


@pytest.mark.parametrize("preset", ["rashid-patch", "rashid-calibrated"])
def test_zero_at_no_slip_angle_odd_in_it_and_bounded(preset):
    """At slip angle 0 every lateral output is 0 exactly; each is odd in the slip angle; the
    lateral shear never exceeds the contact's full lateral strength c*A + W*tan(phi) (A the
    contact area: the patch's b*l, at most b*R_s*(theta_f - theta_r) on the arc), and the
    force opposes the sideways motion."""
    ps = presets.load(preset)
    for load, slip in ((62.0, 0.2), (24.5, -0.4), (24.5, 0.8)):
        st = model.steady_state(ps, load, slip, "unified")
        z = st["sinkage"]
        zero = _lateral(ps, z, slip, 0.0)
        assert all(v == 0.0 for v in zero.values()), zero
        for beta in (math.radians(1.0), math.radians(30.0), math.radians(80.0)):
            plus, minus = _lateral(ps, z, slip, beta), _lateral(ps, z, slip, -beta)
            for k in plus:
                assert plus[k] == -minus[k], k
            assert plus["lateral_force"] < 0
            strength = (ps["soil.cohesion"] * ps["wheel.width"] * st["contact_length"] * 2
                        + st["normal_force"] * math.tan(ps["soil.phi"]))
            assert abs(plus["lateral_shear_force"]) <= strength


@pytest.mark.parametrize("preset", ["rashid-patch", "rashid-calibrated"])
def test_the_side_force_grows_with_the_slip_angle_toward_its_strength(preset):
    """Steady wheel, 62 N, slip 0.2: |F_y| rises with the slip angle from 0 to 60 deg."""
    ps = presets.load(preset)
    z = model.steady_state(ps, 62.0, 0.2)["sinkage"]
    forces = [-_lateral(ps, z, 0.2, math.radians(d))["lateral_force"] for d in range(0, 61, 5)]
    assert np.all(np.diff(forces) > 0), forces


def test_the_slip_angle_leaves_the_longitudinal_contact_alone():
    """The steady state at a slip angle is the steady state without it, bit for bit, with the
    lateral outputs added."""
    ps = presets.load()
    plain = model.steady_state(ps, 62.0, 0.3)
    turned = model.steady_state(ps, 62.0, 0.3, slip_angle=math.radians(10.0))
    assert {k: turned[k] for k in plain} == plain
    assert turned["slip_angle"] == math.radians(10.0)
    assert turned["lateral_force"] < 0 < turned["aligning_moment"]
    assert model.steady_state(ps, 62.0, 0.3, slip_angle=0.0)["lateral_force"] == 0.0


@pytest.mark.parametrize("preset", ["rashid-patch", "rashid-calibrated"])
def test_the_exact_jacobian_in_the_slip_angle_matches_finite_differences(preset):
    ps = presets.load(preset)
    z = model.steady_state(ps, 62.0, 0.25)["sinkage"]
    fns = functions.build()
    for beta in (math.radians(0.5), math.radians(12.0), math.radians(-40.0)):
        jac = np.array(fns.lateral_jacobian(z, 0.25, beta, 0.0, ps.vector()))[:2, :3]
        for col, (dz, ds, db) in enumerate(((1e-7, 0, 0), (0, 1e-6, 0), (0, 0, 1e-7))):
            up = np.array([float(v) for v in fns.lateral(z + dz, 0.25 + ds, beta + db, 0.0,
                                                          ps.vector())[:2]])
            down = np.array([float(v) for v in fns.lateral(z - dz, 0.25 - ds, beta - db, 0.0,
                                                            ps.vector())[:2]])
            fd = (up - down) / (2 * (dz + ds + db))
            assert np.allclose(jac[:, col], fd, rtol=1e-5, atol=1e-6 * np.abs(fd).max()), (
                col, jac[:, col], fd)


def test_the_side_bulldozing_is_a_share():
    """model.side_bulldozing = 0 leaves the lateral shear alone; 1 adds the side face's
    bulldozing, against the motion."""
    ps = presets.load()
    z = model.steady_state(ps, 62.0, 0.2)["sinkage"]
    on = _lateral(ps, z, 0.2, math.radians(15.0))
    off = _lateral(ps.with_values({"model.side_bulldozing": 0.0}), z, 0.2, math.radians(15.0))
    assert off["side_bulldozing"] == 0.0
    assert off["lateral_force"] == off["lateral_shear_force"] == on["lateral_shear_force"]
    assert on["side_bulldozing"] < 0


def test_steady_cli_takes_a_slip_angle():
    import json

    from click.testing import CliRunner

    from wheelterrain.cli import main

    runner = CliRunner()
    result = runner.invoke(main, ["steady", "--slip", "0.2", "--load", "62",
                                  "--slip-angle", "15", "--json"])
    assert result.exit_code == 0, result.output
    doc = json.loads(result.output)
    want = model.steady_state(presets.load(), 62.0, 0.2, slip_angle=math.radians(15.0))
    assert doc["lateral_force"] == want["lateral_force"]
    assert doc["aligning_moment"] == want["aligning_moment"]
    plain = json.loads(runner.invoke(main, ["steady", "--slip", "0.2", "--load", "62",
                                            "--json"]).output)
    assert "lateral_force" not in plain
    text = runner.invoke(main, ["steady", "--slip", "0.2", "--load", "62", "--slip-angle", "-5"])
    assert "lateral_force" in text.output
    for bad in ("95", "nan"):
        wrong = runner.invoke(main, ["steady", "--slip", "0.2", "--load", "62",
                                     "--slip-angle", bad])
        assert wrong.exit_code == 2
        assert "--slip-angle" in wrong.output
        assert "Traceback" not in wrong.output


def _user_csv(tmp_path, extra_header: str, extra_cells) -> str:
    from wheelterrain import data

    lines = [ln for ln in data.path("wheel_tests.csv").read_text().splitlines()
             if ln.strip() and not ln.startswith("#")]
    rows = [ln for ln in lines[1:] if ln.startswith("rashid-rig")][:4]
    text = "\n".join([lines[0] + extra_header,
                      *(r + cell for r, cell in zip(rows, extra_cells, strict=True))])
    path = tmp_path / "tests.csv"
    path.write_text(text + "\n")
    return str(path)


@pytest.mark.slow
def test_validate_data_judges_the_lateral_force_beside_its_baseline(tmp_path):
    """`validate --data` with slip_angle and lateral_force columns: every form's
    lateral_force_mae, computed at the point's steady sinkage, beside the baseline
    -W*tan(phi)*sin(beta); the rows without those columns are what they were."""
    import json
    import subprocess
    import sys

    from wheelterrain.fit import crosswheel, datasets

    angles = [math.radians(a) for a in (5.0, 10.0, 15.0, 20.0)]
    measured = [-3.0, -6.0, -9.0, -11.0]
    path = _user_csv(tmp_path, ",slip_angle [rad],lateral_force [N]",
                     [f",{a!r},{f!r}" for a, f in zip(angles, measured, strict=True)])
    run = subprocess.run([sys.executable, "-m", "wheelterrain.cli", "validate", "--data", path,
                          "--json"], capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    doc = json.loads(run.stdout)
    lateral = doc["lateral"]["rashid-rig"]
    pts = datasets.read(path)[0].points
    baseline = np.mean([abs(crosswheel.lateral_baseline(p) - p.lateral_force) for p in pts])
    assert lateral["points"] == 4
    assert lateral["baseline"] == pytest.approx(baseline, rel=1e-12)
    forms = {r["model"]: r for r in doc["rows"] if r["model"] != "line"}
    assert set(lateral["forms"]) == set(forms)
    for name, row in forms.items():
        assert row["lateral_force_mae"] == lateral["forms"][name]
        assert row["lateral_force_mae"] > 0
    text = subprocess.run([sys.executable, "-m", "wheelterrain.cli", "validate", "--data", path],
                          capture_output=True, text=True, timeout=600)
    assert "lateral force MAE" in text.stdout


def test_the_lateral_columns_are_checked():
    from wheelterrain.errors import WheelTerrainError
    from wheelterrain.fit import datasets

    def parse(extra_header, cell):
        from wheelterrain import data

        lines = [ln for ln in data.path("wheel_tests.csv").read_text().splitlines()
                 if ln.strip() and not ln.startswith("#")]
        row = next(ln for ln in lines[1:] if ln.startswith("rashid-rig"))
        return datasets.parse(lines[0] + extra_header + "\n" + row + cell + "\n")

    ok = parse(",slip_angle [rad],lateral_force [N]", ",0.2,-4.5")[0].points[0]
    assert (ok.slip_angle, ok.lateral_force) == (0.2, -4.5)
    plain = parse("", "")[0].points[0]
    assert plain.slip_angle == 0.0
    assert math.isnan(plain.lateral_force)
    for header, cell, words in ((",lateral_force [N]", ",-4.5", "without its slip_angle"),
                                (",slip_angle [rad]", ",2.0", "beyond"),
                                (",slip_angle [deg]", ",20", "[rad]"),
                                (",slip_angle [rad],lateral_force [N]", ",0.2,-1e6", "beyond")):
        with pytest.raises(WheelTerrainError, match=re.escape(words)):
            parse(header, cell)


@pytest.mark.parametrize("hump", [0, 1])
def test_the_patch_moment_of_the_shear_is_its_quadrature_on_both_sides_of_the_series(hump):
    """The centred first moment of the mobilised shear over the patch (the patch form's
    aligning moment) against an 80-node Gauss-Legendre quadrature of its integrand (smooth:
    exact to rounding), on both sides of SMALL_CENTRED, where the series hands over to the
    closed form: within 1e-11 relative."""
    import casadi as ca

    from wheelterrain.model import contact, soil

    nodes, weights = np.polynomial.legendre.leggauss(80)
    s_nodes, s_weights = (nodes + 1) / 2, weights / 2

    P = soil.Params(ca.DM(presets.load().with_values({"model.shear_model": hump}).vector()))
    edge = contact.SMALL_CENTRED
    for a in (1e-4, 0.01, edge * (1 - 1e-9), edge, edge * (1 + 1e-9), 0.3, 2.0, 40.0, -0.7):
        got = float(contact.patch_shear_centred_moment(ca.DM(a), P))
        g = np.array([float(soil.shear_function(ca.DM(a * s), P, ca.DM(1.0)))
                      for s in s_nodes])
        ref = float(s_weights @ ((s_nodes - 0.5) * g))
        assert got == pytest.approx(ref, rel=1e-11), a


def test_the_modelica_export_is_the_models_lateral_contact():
    """contact.lateral_export (what the Modelica library's Functions.lateral reproduces)
    against build().lateral, every preset, both signs of the slip angle, 0, with and without a
    turn slip: within 1e-12."""
    from wheelterrain.model import contact

    export, model_fn = contact.lateral_export(), functions.build().lateral
    for name in presets.available():
        v = presets.load(name).vector()
        for z in (0.0, 1e-7, 0.006, 0.04):
            for slip in (-0.6, 0.3, 0.8):
                for beta, turn in ((0.0, 0.0), (0.3, 0.0), (-0.5, 0.0), (0.0, 3.0),
                                   (-0.5, -6.0)):
                    a = np.array(export(z, slip, beta, turn, v)).ravel()
                    b = np.array([float(x) for x in model_fn(z, slip, beta, turn, v)])
                    assert np.all(np.abs(a - b) <= 1e-12 * np.maximum(np.abs(b), 1e-300)), (
                        name, z, slip, beta, turn, a, b)
