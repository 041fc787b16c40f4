"""The parameter table, the presets and the slip definitions."""

from __future__ import annotations

import math

import pytest

from wheelterrain import presets
from wheelterrain.errors import InputError, ParameterError
from wheelterrain.model import slip as slips
from wheelterrain.model.slip import paper_from_traction, to_unified, traction_from_paper
from wheelterrain.parameters import TABLE, ParameterSet, lookup, parse_assignments


def test_every_row_is_complete_and_its_default_valid():
    assert len({p.name for p in TABLE}) == len(TABLE)
    for p in TABLE:
        assert p.unit, p.name
        assert p.description, p.name
        assert p.source, p.name
        assert p.min <= p.default <= p.max, p.name
        assert "." in p.name, p.name


def test_paper_presets_carry_the_paper_values():
    t1, t2 = presets.load("paper-table1"), presets.load("paper-table2")
    expected2 = {"soil.k_c": 0.63, "soil.k_phi": 80, "soil.shear_modulus": 0.036, "soil.n0": 1.1,
                 "soil.gamma": 15620, "soil.gamma_variation": 1562, "soil.n1": 1.15,
                 "soil.phi": math.radians(23), "soil.cohesion": 0, "grouser.height": 0.01,
                 "soil.damping": 800, "ripple.k_g": 0.07, "ripple.k_0": 0.035,
                 "wheel.radius": 0.05, "wheel.width": 0.075, "grouser.count": 12}
    for name, value in expected2.items():
        assert t2[name] == pytest.approx(value, rel=1e-15), name
    expected1 = {"soil.k_c": 0, "soil.n0": 1.0, "soil.gamma": 13734, "soil.phi": math.radians(28),
                 "ripple.k_g": 0.06, "ripple.k_0": 0.03, "soil.gamma_variation": 1373.4}
    for name, value in expected1.items():
        assert t1[name] == pytest.approx(value, rel=1e-15), name


def test_preset_documents_its_readings():
    doc = presets.read("paper-table2")
    assert "0.0075" in doc["provenance"]["readings"]["wheel.width"]


def test_parameter_set_rejects_bad_values_with_the_range():
    with pytest.raises(ParameterError, match=r"wheel.width = -1 is out of range; valid range"):
        ParameterSet({"wheel.width": -1})
    with pytest.raises(ParameterError, match="is not a parameter"):
        ParameterSet({"wheel.diameter": 0.1})
    with pytest.raises(ParameterError, match="must be a whole number"):
        ParameterSet({"grouser.count": 2.5})


def test_assignments_parse_degrees_only_for_angles():
    assert parse_assignments(["soil.phi=45deg"])["soil.phi"] == pytest.approx(math.pi / 4)
    with pytest.raises(ParameterError, match="takes m, not deg"):
        parse_assignments(["wheel.radius=3deg"])


@pytest.mark.parametrize("s", [0.0, 0.25, 0.5, 0.75, -0.4, -0.999, -1.0, 10.0])
def test_slip_definitions_are_inverse(s):
    """Traction i, the paper's s and the model's sigma (i driving, s braking) convert both
    ways, the locked wheel included (s = -1, i = -inf, sigma = -1)."""
    i = traction_from_paper(s)
    assert paper_from_traction(i) == pytest.approx(s, rel=1e-14)
    if s > -1:
        assert 1 - i == pytest.approx(1 / (1 + s), rel=1e-14)
    sigma = to_unified(s, "paper")
    assert sigma == pytest.approx(s if s < 0 else i, rel=1e-15)
    assert slips.in_definition(sigma, "paper") == pytest.approx(s, rel=1e-14)
    assert slips.in_definition(sigma, "traction") == pytest.approx(i, rel=1e-14)
    if math.isfinite(i):
        assert to_unified(i, "traction") == pytest.approx(sigma, rel=1e-14)
    assert -1 <= sigma <= 1


def test_slip_validation():
    assert math.isinf(paper_from_traction(1.0))
    assert paper_from_traction(-math.inf) == -1.0
    with pytest.raises(InputError, match="slip_definition"):
        to_unified(0.1, "wheel")
    with pytest.raises(InputError, match=r"valid range \[-1, 1\]"):
        to_unified(-1.2, "unified")
    with pytest.raises(InputError, match=r"valid range \[-1, inf\)"):
        to_unified(-1.2, "paper")
    with pytest.raises(InputError, match="locked wheel is traction slip -inf"):
        to_unified(1.2, "traction")
    assert to_unified(-3.0, "traction") == pytest.approx(-0.75)  # s = i/(1 - i)


def test_plausible_ranges_are_a_column_inside_the_validity_range():
    """calibration.PLAUSIBLE is read from the table; each plausible range lies inside the
    parameter's validity range and carries a source."""
    from wheelterrain.fit import calibration
    from wheelterrain.parameters import BY_NAME

    assert calibration.PLAUSIBLE
    for name, (lo, hi, source) in calibration.PLAUSIBLE.items():
        p = BY_NAME[name]
        assert p.plausible == (lo, hi, source)
        assert p.min <= lo < hi <= p.max, name
        assert source


def test_rig_parameters_are_rows_of_the_one_table_and_each_fmu_takes_its_own():
    """The rig's parameters are rows of parameters.ROWS (fmu column SingleWheelRig); each FMU's
    parameter variables are exactly its rows, in table order, and the terrain model's parameter
    vector (TABLE) holds no rig row."""
    from wheelterrain.fmu import variables
    from wheelterrain.model import rig
    from wheelterrain.parameters import (
        GROUND_FMU,
        GROUND_TABLE,
        RIG_FMU,
        ROVER_FMU,
        ROVER_TABLE,
        ROWS,
        TABLE,
        TERRAIN_FMU,
    )

    assert tuple(p for p in ROWS if p.fmu == RIG_FMU) == rig.RIG_TABLE
    assert tuple(p for p in ROWS if p.fmu == TERRAIN_FMU) == TABLE
    assert tuple(p for p in ROWS if p.fmu == ROVER_FMU) == ROVER_TABLE
    assert tuple(p for p in ROWS if p.fmu == GROUND_FMU) == GROUND_TABLE
    assert {p.fmu for p in ROWS} == {RIG_FMU, TERRAIN_FMU, ROVER_FMU, GROUND_FMU}
    # the terrain map's own rows follow the soil rows it shares with WheelTerrain
    map_params = [v.name for v in variables.ground_variables() if v.causality == "parameter"]
    assert map_params == [*(p.name for p in variables.SOIL_ROWS),
                          *(p.name for p in GROUND_TABLE)]
    for fmu, build in ((TERRAIN_FMU, variables.terrain_variables),
                       (RIG_FMU, variables.rig_variables)):
        params = [v.name for v in build() if v.causality == "parameter"]
        assert params[:len([p for p in ROWS if p.fmu == fmu])] == [
            p.name for p in ROWS if p.fmu == fmu]
    with pytest.raises(ParameterError, match="belongs to the rig"):
        lookup("rig.load")
    with pytest.raises(ParameterError, match="belongs to the rover"):
        lookup("rover.mass")
