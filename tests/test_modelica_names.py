"""The Modelica library's names (wheelterrain.modelica.names): MSL's naming convention derived
from the model's snake_case names by one rule, applied to the code and never to other
libraries' names, strings' table names or comments."""

from __future__ import annotations

import pytest

from wheelterrain.modelica import library, names, reference


@pytest.mark.parametrize(("model", "modelica"), [
    ("drawbar_pull", "drawbarPull"),
    ("plastic_sinkage_start", "plasticSinkage_start"),  # a subscript at the end
    ("change_start_time", "changeStartTime"),           # not a subscript: words follow
    ("rim_speed_end", "rimSpeed_end"),
    ("der_slip_angle", "der_slipAngle"),                # MSL's der_u
    ("der_y", "der_y"),
    ("k_phi", "k_phi"), ("tau_max", "tau_max"), ("x_start", "x_start"), ("k_0", "k_0"),
    ("frame_a", "frame_a"), ("flange_b", "flange_b"), ("from_deg", "from_deg"),
    ("p_front_left", "pFrontLeft"), ("front_left_drive", "frontLeftDrive"),
    ("sinkage", "sinkage"), ("Frame_a", "Frame_a"), ("record_", "record_"),
])
def test_a_name_in_the_library_is_the_models_in_msls_convention(model, modelica):
    assert names.identifier(model) == modelica
    assert names.identifier(modelica) == modelica  # the rule is idempotent


def test_the_rule_reaches_code_only():
    text = ('model M "the drawbar_pull, as soil.k_phi says"\n'
            "  Real drawbar_pull = front_left.normal_force[2] * 1e-3; // drawbar_pull here\n"
            "  Modelica.Units.NonSI.Angle_deg a_b = Modelica.Units.Conversions.to_deg(x_start);\n"
            "  /* plastic_sinkage */ Real 'odd_name';\nend M;\n")
    out = names.code(text)
    assert "Real drawbarPull = frontLeft.normalForce[2] * 1e-3; // drawbar_pull here" in out
    assert "Modelica.Units.NonSI.Angle_deg a_b = Modelica.Units.Conversions.to_deg(x_start)" \
        in out
    assert '"the drawbar_pull, as soil.k_phi says"' in out
    assert "/* plastic_sinkage */ Real 'odd_name'" in out
    prose = names.prose(out, frozenset({"drawbar_pull"}), frozenset({"soil"}))
    assert '"the drawbarPull, as soil.k_phi says"' in prose  # the table's name stays


def test_two_names_that_would_become_one_are_refused():
    names.check_distinct({"slip_angle", "slipAngle", "sinkage"})  # one is the other's form
    with pytest.raises(ValueError, match="'slip_Angle' and 'slip_angle' would both be"):
        names.check_distinct({"slip_angle", "slip_Angle"})


def test_the_built_library_speaks_the_convention_everywhere():
    """Every identifier of every class file is its own library name (nothing left in
    snake_case outside a subscript), and the references' columns and compared signals are the
    library's names too."""
    lib = library.build_library()
    left = {n for path, text in lib.files.items() if path.endswith(".mo")
            for n in names.identifiers(text) if names.identifier(n) != n}
    assert not left
    files = reference.files()
    folder = reference.location("Rover")
    assert folder == "WheelTerrain/Examples/FMUTwin/Rover"  # the example's class path
    header = files[f"{folder}/Rover.csv"].splitlines()[0].split(",")
    assert "frontLeft.drawbarPull" in header
    assert "front_left.drawbar_pull" not in header
    signals = files[f"{folder}/comparisonSignals.txt"].split()
    assert signals == [names.path(s) for s in reference.compared("Rover")]


def test_every_other_librarys_name_the_rule_would_change_is_kept():
    """Of the names the library writes (its class files before the renaming), those MSL or
    PlanarMechanics declare and the rule would change are other libraries' names it must not
    touch (a modifier of an MSL component): each is in FOREIGN_NAMES. The library's own names
    that MSL happens to use too (PlanarMechanics' v_long, v_lat in HorizontalWheel's own
    variables) are the library's and follow the rule."""
    import re

    msl = reference.find_msl()
    if msl is None:
        pytest.skip("needs the Modelica Standard Library 4.x on MODELICAPATH")
    declared = set()
    for root in (msl / "Modelica", msl / "PlanarMechanics"):
        for path in root.rglob("*.mo"):
            declared.update(re.findall(r"\b([a-z]\w*_\w*)\s*[(=;]",
                                       path.read_text(encoding="utf-8", errors="replace")))
    lib = library.build_library(named=False)
    written = set().union(*(names.identifiers(text) for path, text in lib.files.items()
                            if path.endswith(".mo")))
    own = {"v_long", "v_lat"}  # HorizontalWheel's own variables, not PlanarMechanics'
    foreign = (declared & written) - own
    assert {n for n in foreign if names.identifier(n) != n} == set()
    assert foreign >= names.FOREIGN_NAMES  # none listed that the library no longer writes
    assert {names.identifier(n) for n in own} == {"vLong", "vLat"}
