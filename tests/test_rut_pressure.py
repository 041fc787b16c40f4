"""A rut keeps the pressure it carried (soil.rut_pressure, the wheel's rut_pressure_left, the
Terrain's record): a wheel meeting it reloads it up to that pressure whatever its own slip, not
up to what its own pressure-sinkage law reads from the rut's depth."""

from __future__ import annotations

import itertools

import pytest

from conftest import first_steps
from wheelterrain import presets
from wheelterrain.model import api, multipass

FORMS = {"patch": "rashid-patch", "arc": "rashid-calibrated"}
LOAD = 62.0


def _rut(ps, slip: float) -> tuple[float, float, float]:
    """(rut depth, its pressure, the maker's sinkage) a wheel at ``slip`` leaves on virgin soil."""
    made = api.steady_state(ps, LOAD, slip)
    return made["rut_left"], made["rut_pressure_left"], made["sinkage"]


@pytest.mark.parametrize(("made_at", "met_at"), [(0.3, 0.3), (0.5, 0.0), (0.0, 0.5)])
def test_a_wheel_meets_a_kept_rut_at_the_pressure_it_carried_whatever_its_slip(made_at, met_at):
    """Patch form (a uniform pressure): a wheel at the depth its rut's maker reached meets the
    maker's pressure exactly, at its own slip or another; read from the depth with the wheel's
    own law it is another pressure where the slips differ (the rut made at 0 read at 0.5 is
    read as carrying 35 % of what it carried)."""
    ps = presets.load(FORMS["patch"])
    rut, pressure, depth = _rut(ps, made_at)
    assert rut > 0
    assert pressure > 0
    kept = ps.with_values({"soil.rut_depth": rut, "soil.rut_pressure": pressure})
    at = api.contact_forces(kept, depth, met_at)
    assert at["mean_pressure"] == pytest.approx(pressure, rel=1e-12)
    # 1 mm deeper it yields again: along the law, above what it carried
    assert api.contact_forces(kept, depth + 1e-3, met_at)["mean_pressure"] > pressure
    unknown = ps.with_values({"soil.rut_depth": rut})
    read = api.contact_forces(unknown, depth, met_at)["mean_pressure"]
    if made_at == met_at:  # the unknown reading: the rebound at the rut's surface, first order
        assert read == pytest.approx(pressure, rel=1e-3)
    else:
        assert abs(read / pressure - 1) > 0.02


@pytest.mark.parametrize("form", FORMS)
def test_at_the_maker_s_slip_the_kept_and_the_read_rut_agree_to_first_order(form):
    """A wheel in the rut of a wheel at its own slip: keeping the pressure changes the steady
    sinkage only by the first-order rebound of the read one (the yield depth read as the
    surface's rebound, p(rut)/K_u, instead of the carried p(deepest)/K_u): less than 0.05 mm of
    23 (patch) and 32 (arc) mm."""
    ps = presets.load(FORMS[form])
    rut, pressure, _ = _rut(ps, 0.3)
    kept = api.steady_state(ps.with_values({"soil.rut_depth": rut, "soil.rut_pressure": pressure}),
                            LOAD, 0.3)
    read = api.steady_state(ps.with_values({"soil.rut_depth": rut}), LOAD, 0.3)
    assert abs(kept["sinkage"] - read["sinkage"]) < 5e-5
    assert kept["sinkage"] > rut


@pytest.mark.parametrize("form", FORMS)
def test_the_pressure_left_is_the_deepest_point_s_or_the_rut_s_own(form):
    """A wheel that presses the rut deeper leaves the pressure of its deepest point (more than
    the rut carried); one that only reloads it elastically leaves it as it was, with its
    pressure (and 0, not known, where the rut's was not known)."""
    ps = presets.load(FORMS[form])
    rut, pressure, depth = _rut(ps, 0.3)
    kept = ps.with_values({"soil.rut_depth": rut, "soil.rut_pressure": pressure})
    deeper = api.steady_state(kept, LOAD, 0.3)
    assert deeper["rut_left"] > rut
    assert deeper["rut_pressure_left"] > pressure
    inside = rut + 0.5 * (depth - rut)  # within the elastic layer: reloaded, not yielded
    for values, left in ((kept, pressure), (ps.with_values({"soil.rut_depth": rut}), 0.0)):
        out = api.contact_forces(values, inside, 0.3)
        assert out["rut_left"] == rut
        assert out["rut_pressure_left"] == left


def test_a_soil_without_memory_leaves_neither():
    ps = presets.load(FORMS["patch"]).with_values({"model.soil_memory": 0})
    out = api.steady_state(ps, LOAD, 0.3)
    assert out["rut_left"] == 0
    assert out["rut_pressure_left"] == 0


@pytest.mark.parametrize("form", FORMS)
def test_multipass_hands_each_pass_the_pressure_the_pass_before_left(form):
    ps = presets.load(FORMS[form])
    rows = multipass.run(ps, LOAD, 0.3, passes=3)
    for before, after in itertools.pairwise(rows):
        here = ps.with_values({"soil.rut_depth": before["rut_left"],
                               "soil.rut_pressure": before["rut_pressure_left"]})
        assert api.steady_state(here, LOAD, 0.3)["drawbar_pull"] == after["drawbar_pull"]
        assert after["rut_pressure_left"] > before["rut_pressure_left"]


FLAVOURS = ["pythonfmu", "native", "native/fmi3"]


@pytest.mark.parametrize("flavour", FLAVOURS)
@pytest.mark.parametrize("quasi_static", [False, True])
def test_the_fmu_meets_the_rut_its_inputs_give_as_the_same_rut_as_parameters(
        built_root, flavour, quasi_static):
    """WheelTerrain's inputs rut_met and rut_pressure_met (a Terrain's record) give the forces
    and the rut left of the same rut set as soil.rut_depth and soil.rut_pressure, exactly; a
    pressure met with a rut no deeper than the wheel's own is not taken."""
    ps = presets.load(FORMS["patch"])
    rut, pressure, depth = _rut(ps, 0.5)
    common = {"quasi_static": quasi_static, "sinkage": depth + 1e-3, "load": LOAD}
    outputs = ["normal_force", "drawbar_pull", "torque", "contact_sinkage", "rut_left",
               "rut_pressure_left"]
    results = first_steps(built_root / flavour / "WheelTerrain.fmu", (
        {**common, "soil.rut_depth": rut, "soil.rut_pressure": pressure},
        {**common, "rut_met": rut, "rut_pressure_met": pressure},
        {**common, "rut_met": rut},
        {**common, "soil.rut_depth": rut, "rut_met": rut, "rut_pressure_met": pressure}),
        outputs)
    assert results[1] == results[0]
    assert results[2] != results[0]  # the pressure not known: read from the depth
    assert results[3] == results[2]  # no deeper than its own: its own rut (pressure 0) stays
    # never less than the rut carried; pressed 1 mm past the maker's depth, more
    assert results[0][-1] >= pressure
    if not quasi_static:
        assert results[0][-1] > pressure
