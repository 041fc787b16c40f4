"""The soil with memory: elastic-plastic contact in a rut, the wheel's plastic sinkage, multi-pass
on the rig (model.soil_memory, soil.rut_depth, soil.unloading_stiffness)."""

from __future__ import annotations

import dataclasses
import itertools
import json
import math

import casadi as ca
import numpy as np
import pytest
from click.testing import CliRunner

from wheelterrain import model, presets
from wheelterrain.cli import main
from wheelterrain.model import contact, multipass, soil
from wheelterrain.model import functions as model_functions
from wheelterrain.parameters import INDEX

FORMS = {"patch": "rashid-patch", "arc": "rashid-calibrated"}
OUTPUTS = (*contact.CONTACT_OUTPUTS, *contact.MEMORY_OUTPUTS)
LEFT = ("rut_left", "rut_pressure_left")
"""What a wheel leaves in a soil with memory (0 without): the rut and its pressure."""


def _vector(preset: str, **values) -> np.ndarray:
    ps = presets.load(preset).with_values({k.replace("__", "."): v for k, v in values.items()})
    return ps.vector()


def _memory(fns, z, rate, slip, plastic, p, angle=0.3, speed=0.03) -> dict:
    return dict(zip(OUTPUTS, (float(v) for v in fns.contact_memory(
        z, rate, slip, angle, plastic, speed, p)), strict=True))


def _contact(fns, z, rate, slip, p, angle=0.3) -> dict:
    return dict(zip(contact.CONTACT_OUTPUTS, (float(v) for v in fns.contact(
        z, rate, slip, angle, p)), strict=True))


@pytest.mark.parametrize("form", FORMS)
def test_memory_off_is_the_elastic_soil_bit_for_bit(form):
    """model.soil_memory = 0: the rut and the plastic sinkage change nothing, to the bit."""
    fns = model_functions.build()
    off = _vector(FORMS[form], model__soil_memory=0)
    rutted = _vector(FORMS[form], model__soil_memory=0, soil__rut_depth=0.012)
    for z, rate, slip in ((0.004, 0.01, 0.2), (0.02, -0.02, 0.6), (0.013, 0.0, -0.3)):
        ref = _contact(fns, z, rate, slip, off)
        assert _contact(fns, z, rate, slip, rutted) == {**ref, "rut_left": 0.0}
        for plastic in (0.0, z + 2e-4, 0.05):
            got = _memory(fns, z, rate, slip, plastic, rutted)
            assert {k: got[k] for k in ref} == {**ref, "rut_left": 0.0}
            assert got["plastic_rate"] == 0.0
    for slip in (0.1, 0.5):
        a = model.steady_state(presets.load(FORMS[form]).with_values(
            {"model.soil_memory": 0}), 62.0, slip)
        b = model.steady_state(presets.load(FORMS[form]).with_values(
            {"model.soil_memory": 0, "soil.rut_depth": 0.01}), 62.0, slip)
        assert a == b


@pytest.mark.parametrize("form", FORMS)
def test_memory_on_without_a_rut_or_unloading_is_the_elastic_soil_bit_for_bit(form):
    """Virgin soil, a wheel that presses at least as deep as it ever did: the same numbers
    as without memory (the switch's default changes nothing there)."""
    fns = model_functions.build()
    on, off = _vector(FORMS[form]), _vector(FORMS[form], model__soil_memory=0)
    for z, rate, slip in ((0.004, 0.01, 0.2), (0.02, -0.02, 0.6)):
        ref = _contact(fns, z, rate, slip, off)
        for plastic in (0.0, z, z * 0.5):
            got = _memory(fns, z, rate, slip, plastic, on)
            assert {k: got[k] for k in ref if k not in LEFT} == \
                {k: v for k, v in ref.items() if k not in LEFT}
    a = model.steady_state(presets.load(FORMS[form]), 62.0, 0.3)
    b = model.steady_state(presets.load(FORMS[form]).with_values({"model.soil_memory": 0}),
                           62.0, 0.3)
    assert {k: v for k, v in a.items() if k not in LEFT} == \
        {k: v for k, v in b.items() if k not in LEFT}


def test_unloading_follows_the_elastic_line_of_the_unloading_stiffness():
    """Patch form, no cohesion, ripple and damper off: lifted by d from where it yielded, the
    wheel's normal force falls along F0*(1 - K_u*d/p) = F0 - K_u*b*l*d, the elastic line of
    the table's stiffness per contact area, to 0 at d = p/K_u (it lifts off)."""
    fns = model_functions.build()
    p = _vector("rashid-patch", ripple__k_g=0.0, ripple__k_0=0.0, soil__cohesion=0.0)
    ku, b = p[INDEX["soil.unloading_stiffness"]], p[INDEX["wheel.width"]]
    zy = 0.015
    top = _memory(fns, zy, 0.0, 0.2, zy, p)
    for d in (1e-5, 5e-5, 1e-4):
        got = _memory(fns, zy - d, 0.0, 0.2, zy, p)
        want = top["normal_force"] - ku * b * top["contact_length"] * d
        assert got["normal_force"] == pytest.approx(want, rel=1e-10)
        assert got["yield_sinkage"] == zy
    lift = top["mean_pressure"] / ku
    assert lift < 1e-3  # a fraction of a millimetre springs back
    assert _memory(fns, zy - 1.01 * lift, 0.0, 0.2, zy, p)["normal_force"] == 0.0


@pytest.mark.parametrize("form", FORMS)
def test_in_a_rut_the_pressure_is_continuous_and_the_contact_begins_at_its_surface(form):
    fns = model_functions.build()
    rut = 0.01
    p = _vector(FORMS[form], soil__rut_depth=rut, ripple__k_g=0.0, ripple__k_0=0.0)
    # above the rut's surface the wheel touches nothing
    assert _contact(fns, rut - 1e-4, 0.0, 0.2, p)["normal_force"] == 0.0
    # the normal force rises continuously from the surface through the elastic layer
    depths = rut + np.linspace(1e-7, 2e-3, 400)
    forces = np.array([_contact(fns, z, 0.0, 0.2, p)["normal_force"] for z in depths])
    assert np.all(np.diff(forces) > 0)
    assert np.max(np.abs(np.diff(forces, 2))) < 0.05 * np.max(forces)  # no jump
    # a wheel in the rut carries a load with less extra sinkage than on virgin soil
    virgin = model.steady_state(presets.load(FORMS[form]), 62.0, 0.2)
    in_rut = model.steady_state(presets.load(FORMS[form]).with_values(
        {"soil.rut_depth": virgin["rut_left"]}), 62.0, 0.2)
    assert in_rut["sinkage"] > virgin["rut_left"]
    assert in_rut["sinkage"] - virgin["rut_left"] < 0.5 * virgin["sinkage"]
    assert in_rut["normal_force"] == pytest.approx(62.0, rel=1e-9)


def _step(fns, z, zp, v, p, h, slip=0.2):
    """plastic_step with the contact's mean pressure and exponent at the step's start."""
    out = _memory(fns, z, 0.0, slip, zp, p, speed=v)
    return float(fns.plastic_step(z, zp, v, out["mean_pressure"], out["sinkage_exponent"], p, h))


@pytest.mark.parametrize("smooth", [None, 1e-5], ids=["law", "smooth-yield"])
@pytest.mark.parametrize("form", FORMS)
def test_the_yield_pressure_alone_is_the_contact_s_to_the_bit(form, smooth):
    """The memory's co-simulation step takes the mean pressure and the exponent from kernels
    that compute only those two (contact.yield_pressure, the forces not evaluated): the
    contact's values, bit for bit, pressed and lifted, in a kept rut and in a read one, at
    every slip of the domain and whatever the wheel's angle; with the slip MPC's smooth yield
    (1e-5 m, mpc.YIELD_WIDTH) as with the law."""
    fns = model_functions.build()
    if smooth is not None:
        fns = dataclasses.replace(fns, contact_memory=model_functions.contact_memory_smooth(
            smooth))
    z, slip, plastic = (ca.MX.sym(n) for n in ("z", "slip", "plastic"))
    p = ca.MX.sym("p", len(INDEX))
    alone = ca.Function("alone", [z, slip, plastic, p], list(contact.yield_pressure(
        z, slip, plastic, soil.Params(p), fns.nodes, smooth)))
    rng = np.random.default_rng(7)
    compared = 0
    for rut, pressure in ((0.0, 0.0), (0.004, 0.0), (0.004, 6e3)):
        pv = _vector(FORMS[form], soil__rut_depth=rut, soil__rut_pressure=pressure)
        for k in range(60):
            zz, zp = rng.uniform(0, 0.03, 2)
            if k % 2:  # every other point within the smooth yield's width of the yield
                zp = zz + rng.uniform(-3e-5, 3e-5)
            s = rng.uniform(-1, 1)
            full = _memory(fns, zz, rng.uniform(-0.01, 0.01), s, zp, pv,
                           angle=rng.uniform(0, 7))
            got = [float(v) for v in alone(zz, s, zp, pv)]
            assert got == [full["mean_pressure"], full["sinkage_exponent"]], (zz, zp, s)
            compared += full["mean_pressure"] > 0
    assert compared > 100  # most points are in contact: the pressures are not all zero


def test_the_plastic_sinkage_yields_at_once_and_is_replaced_over_a_contact_length():
    """Pressed deeper, z_p follows at once. Lifted by d while rolling at V, the imprint is
    replaced by the soil ahead: after h, z_t + (z_y - z_t)*exp(-V*h/l), l the contact length
    at z_y and z_t the sinkage at which unpressed soil carries the force the wheel carries now:
    Bekker's rigid wheel, F ~ z**((2n+1)/2), with F = share*F(z_y), share = 1 - K_u*d/p_mean
    (written here from those formulas, not from the model's code)."""
    fns = model_functions.build()
    p = _vector("rashid-patch", model__imprint_relaxation=1)
    assert _step(fns, 0.02, 0.015, 0.03, p, 1e-3) == 0.02
    zp, z, v = 0.02, 0.0199, 0.03
    top = _memory(fns, zp, 0.0, 0.2, zp, p)
    length, n = top["contact_length"], top["sinkage_exponent"]
    share = 1 - p[INDEX["soil.unloading_stiffness"]] * (zp - z) / top["mean_pressure"]
    assert 0 < share < 1
    target = zp * share ** (2 / (2 * n + 1))
    assert target < z  # the soil ahead carries the wheel's present force above where it is
    h = length / v  # one contact length of travel
    assert _step(fns, z, zp, v, p, h) == pytest.approx(
        target + (zp - target) * math.exp(-1), rel=1e-12)
    # the force the wheel carries, on soil it has not pressed, at that target
    fresh = _memory(fns, target, 0.0, 0.2, 0.0, p)["normal_force_static"]
    lifted = _memory(fns, z, 0.0, 0.2, zp, p)["normal_force_static"]
    assert fresh == pytest.approx(lifted, rel=0.02)  # the power law's approximation
    # lifted off the soil (share 0): the soil ahead is the surface
    assert _step(fns, 0.015, zp, v, p, h) == pytest.approx(zp * math.exp(-1), rel=1e-12)
    # standing still: the imprint stays
    assert _step(fns, z, zp, 0.0, p, 10.0) == zp
    # model.imprint_relaxation 0: toward the wheel, z + (z_y - z)*exp(-V*h/l), lifted off too
    toward = _vector("rashid-patch", model__imprint_relaxation=0)
    assert _step(fns, z, zp, v, toward, h) == pytest.approx(z + (zp - z) * math.exp(-1),
                                                            rel=1e-12)
    assert _step(fns, 0.015, zp, v, toward, h) == pytest.approx(
        0.015 + (zp - 0.015) * math.exp(-1), rel=1e-12)


@pytest.mark.parametrize("relaxation", [0, 1])
def test_a_wheel_out_of_the_soil_leaves_the_imprint_at_the_surface(relaxation):
    """Lifted out of the soil (z < 0), the imprint relaxes toward the surface, never above it;
    an imprint at the surface (no contact length) stays, its rate 0, not |V|/0 (it was -2e295
    m/s, which stopped a wheel dropped onto the soil in model exchange)."""
    fns = model_functions.build()
    p = _vector("rashid-patch", model__imprint_relaxation=relaxation)
    for z, plastic in ((-0.002, 0.0), (-1e-9, 0.0), (-0.002, -0.001)):
        assert _memory(fns, z, -0.1, 0.2, plastic, p)["plastic_rate"] == 0
        if plastic == 0:  # the co-simulation step keeps it at the surface too
            assert _step(fns, z, plastic, 0.03, p, 1e-3) == 0
    # pressed to 1 mm and lifted 2 mm above the surface: relaxes toward the surface at |V|/l
    rate = _memory(fns, -0.002, 0.0, 0.2, 0.001, p)["plastic_rate"]
    length = _memory(fns, 0.001, 0.0, 0.2, 0.001, p)["contact_length"]
    assert rate == pytest.approx(-0.03 / length * 0.001, rel=1e-12)
    assert 0.0 < _step(fns, -0.002, 0.001, 0.03, p, length / 0.03) < 0.001


@pytest.mark.parametrize("form", FORMS)
def test_a_rolling_wheel_settles_after_a_load_step_within_a_few_contact_lengths(form):
    """A wheel rolling at 3 cm/s, slip 0.2, its load stepped from 62 N: with
    model.imprint_relaxation 1 the rise (to 40 N) and the sinking (to 80 N) close most of the
    way to the new steady sinkage within one contact length of travel, as a wheel that rolls
    onto soil it has not pressed (explicit
    integration of the wheel's heave on the co-simulation law, ripple off). Measured, rise:
    62 % of the step closed after one contact length, 99 % after five (with
    model.imprint_relaxation 0, toward the wheel, 4 % and 12 %: checked below); sinking, all
    of it within one."""
    fns = model_functions.build()
    quiet = presets.load(FORMS[form]).with_values({"ripple.k_g": 0.0, "ripple.k_0": 0.0})
    v, slip, h = 0.03, 0.2, 1e-3
    mass = 62.0 / 9.81
    start = model.steady_state(quiet, 62.0, slip)
    for relaxation, load, closed_in_one, closed_in_five in (
            (1, 40.0, 0.55, 0.97), (1, 80.0, 0.95, 0.999), (0, 40.0, 0.0, 0.0)):
        ps = quiet.with_values({"model.imprint_relaxation": relaxation})
        p = ps.vector()
        end = model.steady_state(ps, load, slip)["sinkage"]
        z, zd, zp = start["sinkage"], 0.0, start["sinkage"]
        length = start["contact_length"]
        at = {}
        for k in range(1, int(5 * length / v / h) + 2):
            out = _memory(fns, z, zd, slip, zp, p, speed=v)
            zp = float(fns.plastic_step(z, zp, v, out["mean_pressure"],
                                        out["sinkage_exponent"], p, h))
            zd += h * (load - out["normal_force"]) / mass
            z += h * zd
            for lengths in (1, 5):
                if lengths not in at and k * h * v >= lengths * length:
                    at[lengths] = (z - start["sinkage"]) / (end - start["sinkage"])
        if relaxation == 0:  # toward the wheel: a few per cent a contact length
            assert 0.01 < at[1] < 0.1, at
            assert at[5] < 0.25, at
            continue
        assert at[1] > closed_in_one, (load, at)
        assert at[5] > closed_in_five, (load, at)
        assert at[5] < 1.01, (load, at)  # no overshoot past the new steady sinkage


def test_the_model_exchange_rate_integrates_to_the_co_simulation_step():
    """d(z_p)/dt (model exchange) integrated with small steps over an input that goes down
    and up converges to the co-simulation steps of the same input (first order in the step)."""
    fns = model_functions.build()
    p = _vector("rashid-patch")
    t_end, v = 2.0, 0.03

    def z_of(t):
        return 0.015 + 0.0004 * math.sin(2 * math.pi * 1.5 * t)

    def rate_of(t):
        return 0.0004 * 2 * math.pi * 1.5 * math.cos(2 * math.pi * 1.5 * t)

    def me(n):
        zp, h = 0.0, t_end / n
        for k in range(n):
            t = k * h
            zp = max(zp, z_of(t)) if k == 0 else zp
            out = _memory(fns, z_of(t), rate_of(t), 0.2, zp, p, speed=v)
            zp += h * out["plastic_rate"]
        return zp

    def cs(n):
        zp, h = 0.0, t_end / n
        for k in range(n):
            zp = _step(fns, z_of(k * h), zp, v, p, h)
        return zp

    ref = cs(20000)
    errors = [abs(me(n) - ref) for n in (500, 2000)]
    assert errors[1] < 0.5 * errors[0] + 1e-9
    assert errors[1] < 2e-6


@pytest.mark.parametrize("form", FORMS)
def test_multipass_sinks_less_each_pass_and_leaves_a_rut_near_its_sinkage(form):
    rows = multipass.run(presets.load(FORMS[form]), 62.0, 0.3, passes=5)
    assert [r["pass"] for r in rows] == [1, 2, 3, 4, 5]
    increments = [r["sinkage_increment"] for r in rows]
    assert all(b < a for a, b in itertools.pairwise(increments))
    assert all(i > 0 for i in increments)
    for r in rows:
        assert r["rut_left"] >= 0.95 * r["sinkage"]
        assert r["traction_coefficient"] == pytest.approx(r["drawbar_pull"] / 62.0)
    assert rows[1]["rut_met"] == rows[0]["rut_left"]
    off = multipass.run(presets.load(FORMS[form]).with_values({"model.soil_memory": 0}),
                        62.0, 0.3, passes=3)
    assert off[0] == {**off[1], "pass": 1, "sinkage_increment": off[0]["sinkage"]}


@pytest.mark.parametrize("hump", [0, 1])
def test_the_patch_mean_after_a_sheared_rut_is_the_mean_of_the_shear_law(hump):
    """patch_shear_mean_after(a0, a) is the mean of g over [a0, a0 + a] (Gauss-Legendre, 200
    nodes), odd in (a0, a) together, and at a0 = 0 the patch mean of virgin soil."""
    P = soil.Params(ca.DM(_vector("rashid-patch", model__shear_model=hump)))
    K = float(P["soil.shear_modulus"])
    x, w = np.polynomial.legendre.leggauss(200)
    for a0, a in ((0.3, 0.7), (2.0, 0.05), (1e-4, 3.0), (0.8, 1e-5), (0.0, 0.4)):
        u = a0 + a * (x + 1) / 2
        g = np.array([float(soil.shear_function(ca.DM(v * K), P)) for v in u])
        mean = float(np.dot(w, g) / 2)
        got = float(contact.patch_shear_mean_after(ca.DM(a0), ca.DM(a), P))
        assert got == pytest.approx(mean, rel=1e-9, abs=1e-12)
        assert float(contact.patch_shear_mean_after(ca.DM(-a0), ca.DM(-a), P)) == -got
    assert float(contact.patch_shear_mean_after(ca.DM(0.0), ca.DM(0.4), P)) == pytest.approx(
        float(contact.patch_shear_mean(ca.DM(0.4), P)), rel=1e-14)


@pytest.mark.parametrize("form", FORMS)
def test_the_shear_a_rut_remembers_raises_the_thrust_in_a_rut_only(form):
    """model.rut_shear (default 1): on virgin soil it changes nothing, bit for bit; in a rut,
    a wheel that counts its shear on from the rut maker's has more gross thrust at the same
    sinkage and slip, and (patch form, where the shear adds nothing to them) the same normal
    force and compaction resistance."""
    fns = model_functions.build()
    for z, rate, slip in ((0.004, 0.0, 0.2), (0.02, 0.01, 0.6)):
        on, off = _vector(FORMS[form]), _vector(FORMS[form], model__rut_shear=0)
        assert _memory(fns, z, rate, slip, z, on) == _memory(fns, z, rate, slip, z, off)
        on, off = (_vector(FORMS[form], soil__rut_depth=0.008),
                   _vector(FORMS[form], soil__rut_depth=0.008, model__rut_shear=0))
        a = _contact(fns, 0.008 + z, rate, slip, on)
        b = _contact(fns, 0.008 + z, rate, slip, off)
        assert a["gross_thrust"] > b["gross_thrust"] > 0
        if form == "patch":  # the arc's shear adds to its normal force and ripple
            assert a["normal_force"] == b["normal_force"]
            assert a["compaction_resistance"] == b["compaction_resistance"]


@pytest.mark.parametrize("form", FORMS)
def test_a_rut_deeper_than_the_wheel_keeps_the_remembered_shear_finite(form):
    """A rut deeper than the contact radius (soil.rut_depth up to 0.5 m, a 1 cm wheel): its
    maker is taken buried to the axle, so the shear it left, and every output, stays finite
    (the property tests found NaN here before the maker's depth was capped)."""
    fns = model_functions.build()
    p = _vector(FORMS[form], wheel__radius=0.01, wheel__width=0.005, grouser__height=0.0,
                grouser__count=0.0, soil__rut_depth=0.5, model__rut_shear=1)
    for z, slip in ((0.5 + 1e-6, -0.9), (0.505, 0.3), (1e-6, 0.5)):
        out = _contact(fns, z, 0.0, slip, p)
        assert all(math.isfinite(v) for v in out.values()), out


def test_multipass_traction_rises_with_the_shear_the_rut_remembers():
    """Rig, 62 N, slip 0.3: with the rut's shear remembered every later pass pulls more per
    newton than the first (the multi-pass effect Holm 1969 reports); without it, less."""
    off = multipass.run(presets.load("rashid-patch").with_values({"model.rut_shear": 0}),
                        62.0, 0.3, passes=3)
    on = multipass.run(presets.load("rashid-patch"), 62.0, 0.3, passes=3)
    assert on[0] == off[0]  # the first pass meets virgin soil
    assert all(r["traction_coefficient"] > on[0]["traction_coefficient"] for r in on[1:])
    assert all(r["traction_coefficient"] < off[0]["traction_coefficient"] for r in off[1:])
    assert [r["sinkage"] for r in on] == [r["sinkage"] for r in off]  # patch: shear-free Fz


def test_multipass_cli_json_and_mistakes(tmp_path):
    runner = CliRunner()
    result = runner.invoke(main, ["multipass", "--slip", "0.2,0.4", "--passes", "3", "--out",
                                  str(tmp_path), "--json"])
    assert result.exit_code == 0, result.output
    doc = json.loads(result.output)
    assert [len(r["passes"]) for r in doc["runs"]] == [3, 3]
    assert set(multipass.KEYS) <= set(doc["runs"][0]["passes"][0])
    assert doc["units"]["sinkage"] == "m"
    assert doc["soil_memory"] == 1
    assert (tmp_path / "multipass.png").stat().st_size > 0
    bad = runner.invoke(main, ["multipass", "--slip", "fast", "--out", str(tmp_path)])
    assert bad.exit_code == 2
    assert "comma-separated" in bad.output
    heavy = runner.invoke(main, ["multipass", "--slip", "0.2", "--load", "1e5", "--out",
                                 str(tmp_path)])
    assert heavy.exit_code == 3
    assert "Traceback" not in heavy.output
    both = runner.invoke(main, ["multipass", "--slip", "0.3", "--passes", "2", "--compare",
                                "model.rut_shear=0", "--out", str(tmp_path), "--json"])
    assert both.exit_code == 0, both.output
    doc = json.loads(both.output)
    assert (doc["rut_shear"], doc["compare"]["rut_shear"]) == (1, 0)
    assert doc["compare"]["set"] == ["model.rut_shear=0"]
    first, other = doc["runs"][0]["passes"], doc["compare"]["runs"][0]["passes"]
    assert other[0] == first[0]  # the first pass meets virgin soil
    assert first[1]["traction_coefficient"] > other[1]["traction_coefficient"]
    text = runner.invoke(main, ["multipass", "--slip", "0.3", "--passes", "2", "--compare",
                                "model.rut_shear=0", "--out", str(tmp_path)])
    assert "compared: model.rut_shear=0" in text.output
    assert "rut shear 1\n" in text.output
    assert "rut shear 0\n" in text.output
    wrong = runner.invoke(main, ["multipass", "--slip", "0.3", "--compare", "model.rut_shear=7",
                                 "--out", str(tmp_path)])
    assert wrong.exit_code == 2
    assert "model.rut_shear" in wrong.output
    assert "Traceback" not in wrong.output


# --- WheelTerrain.fmu carries the plastic sinkage as its state (both flavours) --------------

def _wheel(folder, tag):
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    path = str(folder / "WheelTerrain.fmu")
    md = read_model_description(path)
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(path),
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName=tag)
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    return fmu, {v.name: v.valueReference for v in md.modelVariables}


PROFILE = [0.012 + 0.0004 * math.sin(2 * math.pi * k / 40) for k in range(120)]
"""A sinkage that goes down and up: the wheel presses, lifts (elastic), presses deeper."""


def _drive(fmu, vr, profile, t0=0.0, h=1e-3):
    rows = []
    names = ("normal_force", "drawbar_pull", "plastic_sinkage", "rut_left")
    for k, z in enumerate(profile):
        fmu.setReal([vr["sinkage"], vr["sinkage_rate"]], [z, 0.0])
        fmu.doStep(t0 + k * h, h)
        rows.append(fmu.getReal([vr[n] for n in names]))
    return np.array(rows)


@pytest.fixture(scope="module", params=["pythonfmu", "native"])
def flavour_dir(request, fmu_dir):
    if request.param == "pythonfmu":
        return fmu_dir
    return request.getfixturevalue("native_dir")


def test_the_fmu_keeps_the_plastic_sinkage_and_restores_it_bit_for_bit(flavour_dir):
    fmu, vr = _wheel(flavour_dir, "memory")
    try:
        first = _drive(fmu, vr, PROFILE[:60])
        # lifted from its deepest point, the soil unloads: the force falls below the
        # elastic soil's at the same sinkage, and the plastic sinkage stays above it
        assert first[:, 2].max() >= max(PROFILE[:60]) - 1e-12
        state = fmu.getFMUstate()
        blob = fmu.serializeFMUstate(state)
        a = _drive(fmu, vr, PROFILE[60:], t0=0.06)
        fmu.setFMUstate(state)
        b = _drive(fmu, vr, PROFILE[60:], t0=0.06)
        fmu.setFMUstate(fmu.deSerializeFMUstate(blob))
        c = _drive(fmu, vr, PROFILE[60:], t0=0.06)
        np.testing.assert_array_equal(a, b)
        np.testing.assert_array_equal(a, c)
        fmu.freeFMUstate(state)
    finally:
        fmu.terminate()
        fmu.freeInstance()


def test_both_flavours_and_the_core_give_the_same_memory(fmu_dir, request):
    native_dir = request.getfixturevalue("native_dir")
    runs = []
    for folder in (fmu_dir, native_dir):
        fmu, vr = _wheel(folder, "agree")
        try:
            runs.append(_drive(fmu, vr, PROFILE))
        finally:
            fmu.terminate()
            fmu.freeInstance()
    np.testing.assert_allclose(runs[1], runs[0], rtol=1e-12, atol=1e-15)
    # the elastic unloading is there: on the way up the force is below the elastic soil's
    rising = [k for k in range(1, len(PROFILE)) if PROFILE[k] < PROFILE[k - 1]]
    assert any(runs[0][k, 0] < runs[0][k - 1, 0] * 0.5 for k in rising)
