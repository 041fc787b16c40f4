"""Multi-pass against an independent reference: the Soil Contact Model's node law on a
discretised rim (wheelterrain.fit.scm_reference, written from the published algorithm, not from
the contact forms), the same wheel and soil, five passes."""

import itertools
import json

import pytest
from click.testing import CliRunner

from wheelterrain import presets
from wheelterrain.cli import main
from wheelterrain.fit import scm_reference
from wheelterrain.model import multipass

SLIPS = (0.1, 0.3, 0.5)
LOADS = (62.0, 24.5)  # N: the rig's load, the rover's wheel on Earth


def _pulls(rows):
    return [r["traction_coefficient"] for r in rows]


def _increments(rows):
    return [r["sinkage_increment"] for r in rows]


def _rising(values):
    return all(b >= a for a, b in itertools.pairwise(values))


def _falling(values):
    return all(b < a for a, b in itertools.pairwise(values))


@pytest.mark.parametrize("load", LOADS)
@pytest.mark.parametrize("slip", SLIPS)
def test_the_default_contact_follows_the_scm_node_law_pass_after_pass(load, slip):
    """With the defaults (patch form, soil memory, the shear a rut remembers at SCM's share 1)
    every later pass pulls at least as much per newton as the one before and sinks less than
    the one before, as the SCM node law does on the same wheel and soil."""
    p = presets.load()
    ours = multipass.run(p, load, slip)
    scm = scm_reference.passes(p, load, slip)
    for rows in (ours, scm):
        assert _rising(_pulls(rows)), _pulls(rows)
        assert _falling(_increments(rows)), _increments(rows)


@pytest.mark.parametrize("slip", SLIPS)
def test_the_arc_form_sinks_less_each_pass_and_pulls_more_than_its_first(slip):
    """The arc form (rashid-calibrated) follows the node law's sinkage (each increment smaller)
    and pulls more per newton on every later pass than on the first; at slip 0.5 its pull
    per newton falls slightly from pass 2 on (0.632 to 0.612 at 62 N, README's multi-pass
    section), where the node law's still rises."""
    p = presets.load("rashid-calibrated")
    rows = multipass.run(p, 62.0, slip)
    pulls = _pulls(rows)
    assert _falling(_increments(rows))
    assert all(later > pulls[0] for later in pulls[1:])


def test_without_the_shear_memory_neither_pulls_more_on_the_second_pass():
    """The direction comes from the shear the rut remembers: with model.rut_shear = 0 both
    the contact and the node law pull less per newton on pass 2 than on pass 1 at slip 0.3
    (the contact from the rut's surface is short and mobilises its shear afresh)."""
    p = presets.load().with_values({"model.rut_shear": 0.0})
    for rows in (multipass.run(p, 62.0, 0.3, passes=2), scm_reference.passes(p, 62.0, 0.3, 2)):
        assert rows[1]["traction_coefficient"] < rows[0]["traction_coefficient"]


def test_a_share_of_the_shear_lies_between_none_and_all():
    """model.rut_shear is a share: at 0.5 the second pass's pull per newton lies strictly
    between the values at 0 and 1, in both the contact and the node law."""
    p = presets.load()
    for run in (lambda q: multipass.run(q, 62.0, 0.3, passes=2),
                lambda q: scm_reference.passes(q, 62.0, 0.3, 2)):
        second = [run(p.with_values({"model.rut_shear": s}))[1]["traction_coefficient"]
                  for s in (0.0, 0.5, 1.0)]
        assert second[0] < second[1] < second[2]


def test_the_node_law_converges_in_its_nodes_and_carries_the_load():
    p = presets.load()
    coarse = scm_reference.passes(p, 62.0, 0.3, 3, nodes=2000)
    fine = scm_reference.passes(p, 62.0, 0.3, 3, nodes=8000)
    for a, b in zip(coarse, fine, strict=True):
        assert a["normal_force"] == pytest.approx(62.0, rel=1e-8)
        assert a["traction_coefficient"] == pytest.approx(b["traction_coefficient"], abs=5e-4)
        assert a["sinkage"] == pytest.approx(b["sinkage"], rel=1e-4)
        # the rut left lies above the deepest point by the elastic rebound, below the pass
        assert 0 < a["sinkage"] - a["rut_left"] < 2e-3


def test_the_node_law_refuses_what_it_does_not_model():
    p = presets.load()
    with pytest.raises(ValueError, match="driving slips"):
        scm_reference.one_pass(p, 62.0, -0.2)
    with pytest.raises(ValueError, match="cannot carry"):
        scm_reference.one_pass(p, 1e5, 0.3)


def test_multipass_cli_shows_the_scm_reference(tmp_path):
    runner = CliRunner()
    result = runner.invoke(main, ["multipass", "--slip", "0.3", "--passes", "3",
                                  "--scm-reference", "--out", str(tmp_path), "--json"])
    assert result.exit_code == 0, result.output
    doc = json.loads(result.output)
    rows = doc["scm_reference"]["runs"][0]["passes"]
    assert [r["pass"] for r in rows] == [1, 2, 3]
    assert rows == scm_reference.passes(presets.load(), 62.0, 0.3, 3)
    text = runner.invoke(main, ["multipass", "--slip", "0.3", "--passes", "2",
                                "--scm-reference", "--out", str(tmp_path)])
    assert "SCM reference" in text.output
    bad = runner.invoke(main, ["multipass", "--slip", "-0.2", "--scm-reference",
                               "--out", str(tmp_path)])
    assert bad.exit_code == 2
    assert "driving slips" in bad.output
    assert "Traceback" not in bad.output
