"""`wheelterrain validate`: its contract, and that a held-out case never reaches its fit."""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest
from click.testing import CliRunner

from wheelterrain import model, presets
from wheelterrain.cli import main
from wheelterrain.fit import calibration, prediction

PROTOCOLS = {"all-case", "leave-one-out", "c2-only", "transfer", "leave-one-dataset-out",
             "nested-leave-one-dataset-out"}


@pytest.fixture(scope="module")
def validate_json():
    run = CliRunner().invoke(main, ["validate", "--json", "--starts", "2"])
    assert run.exit_code == 0, run.output
    return json.loads(run.stdout)


@pytest.mark.slow
def test_validate_prints_every_contract_row(validate_json):
    rows = validate_json["rows"]
    assert len(rows) == prediction.step_count()  # the progress bar's length
    for r in rows:
        # every documented key, of one type in every row (40 of 58 rows lacked some, and
        # `fitted` was [] in some rows and {} in others)
        assert {"model", "protocol", "free", "drawbar_pull_mae", "sinkage_mae", "in_sample",
                "judged_on", "data", "errors", "fitted"} <= set(r), (r["model"], r["protocol"])
        assert isinstance(r["fitted"], dict)
        assert isinstance(r["errors"], dict)
        assert isinstance(r["judged_on"], list)
        assert set(r["errors"]) == set(r["judged_on"]), (r["model"], r["protocol"])
        assert r["protocol"] in PROTOCOLS
        assert "error" not in r, r["error"]
        assert r["drawbar_pull_mae"] >= 0
        assert r["sinkage_mae"] >= 0
    have = {(r["model"], r["protocol"]) for r in rows}
    for protocol in ("all-case", "leave-one-out", "c2-only"):
        assert ("line", protocol) in have
    for name in presets.available():
        for protocol in ("all-case", "leave-one-out", "c2-only", "transfer"):
            assert (name, protocol) in have, (name, protocol)
    # the headline first: the nested rows, the line beside, in both units
    nested = [r for r in rows if r["protocol"] == "nested-leave-one-dataset-out"]
    assert rows[:len(nested)] == nested
    assert len(nested) == 12
    assert sum(r["model"] == "line" for r in nested) == 6
    for r in nested:
        assert r["drawbar_pull_mae_per_load"] >= 0
        assert r["sinkage_mae_per_radius"] >= 0
        assert r["dataset"] not in r["trained_on"]
    judged = validate_json["default_form_rule"]["judged_by"]
    assert judged["rule"]["datasets"] == judged["line"]["datasets"] == 6
    picks = [r for r in nested if r["model"] != "line"]
    assert judged["rule"]["drawbar_pull_mae"] == pytest.approx(
        sum(r["drawbar_pull_mae"] for r in picks) / 6)
    assert judged["rule"]["forms"] == sorted({r["model"] for r in picks})
    paper = next(r for r in rows if r["model"] == "paper-table2" and r["protocol"] == "all-case")
    assert paper["free"] == []
    assert paper["tuned_on"] == ["C2"]  # Table II was tuned on C2 by the paper's authors
    assert paper["in_sample"] is True
    for r in rows:
        if r["protocol"] == "c2-only" and r["model"] != "line":
            assert set(r["free"]) <= {"soil.phi", "soil.n0"}
            assert r["judged_on"] == ["C1", "C3", "C4"]
        # only an all-case row of something fitted (by us or the paper's authors) is in-sample
        assert r["in_sample"] == (r["protocol"] == "all-case"
                                  and bool(r["free"] or r.get("tuned_on")))


@pytest.mark.slow
def test_the_line_baseline_is_the_least_squares_line(validate_json):
    """The README quotes the line at 0.61 N in-sample and 1.45 N leave-one-out."""
    line = {r["protocol"]: r for r in validate_json["rows"] if r["model"] == "line"}
    cases = calibration.paper_cases()
    s = np.array([c["slip_paper"] for c in cases])
    dp = np.array([c["experiment"]["drawbar_pull"] for c in cases])
    coef = np.polyfit(s, dp, 1)
    assert line["all-case"]["drawbar_pull_mae"] == pytest.approx(
        np.mean(np.abs(np.polyval(coef, s) - dp)), rel=1e-12)
    assert line["all-case"]["drawbar_pull_mae"] == pytest.approx(0.6075, abs=1e-9)
    assert line["leave-one-out"]["drawbar_pull_mae"] == pytest.approx(1.4464, abs=1e-4)


@pytest.mark.slow
def test_the_shipped_all_case_rows_are_the_presets_own_errors(validate_json):
    row = next(r for r in validate_json["rows"]
               if r["model"] == presets.DEFAULT_PRESET and r["protocol"] == "all-case")
    ps = presets.load(presets.DEFAULT_PRESET)
    errs = calibration.errors_on(ps, ["C1", "C2", "C3", "C4"])
    assert row["drawbar_pull_mae"] == pytest.approx(
        np.mean([abs(e["drawbar_pull"]) for e in errs.values()]), rel=1e-12)
    assert row["in_sample"] is True  # its phi was fitted on these four cases


def _corrupted(cases, case):
    out = copy.deepcopy(cases)
    for c in out:
        if c["case"] == case:
            c["experiment"]["drawbar_pull"] += 100.0
            c["experiment"]["sinkage"] += 0.01
    return out


@pytest.mark.parametrize("left_out", ["C1", "C3"])
def test_a_left_out_case_never_reaches_its_fit(left_out):
    """Corrupt the held-out case's data: the fold's fitted values do not move, and the whole
    corruption shows in that case's error."""
    cases = calibration.paper_cases()
    base = prediction.unfitted(presets.DEFAULT_PRESET)
    free = prediction.preset_free(presets.DEFAULT_PRESET)
    clean = prediction.model_row("t", base, free, "leave-one-out", cases, starts=1)
    dirty = prediction.model_row("t", base, free, "leave-one-out", _corrupted(cases, left_out),
                                 starts=1)
    fold = ["C1", "C2", "C3", "C4"].index(left_out)
    assert dirty.fitted[fold] == clean.fitted[fold]
    shift = clean.errors[left_out]["drawbar_pull"] - dirty.errors[left_out]["drawbar_pull"]
    assert shift == pytest.approx(100.0, rel=1e-12)
    others = [k for k in range(4) if k != fold]
    assert all(dirty.fitted[k] != clean.fitted[k] for k in others)  # they did see it


def test_c2_only_fits_on_c2_alone():
    cases = calibration.paper_cases()
    base = prediction.unfitted("paper-table2")
    clean = prediction.model_row("t", base, prediction.PAPER_FREE, "c2-only", cases, starts=1)
    dirty_cases = cases
    for case in ("C1", "C3", "C4"):
        dirty_cases = _corrupted(dirty_cases, case)
    dirty = prediction.model_row("t", base, prediction.PAPER_FREE, "c2-only", dirty_cases,
                                 starts=1)
    assert dirty.fitted == clean.fitted
    line_clean = prediction.line_row("leave-one-out", cases)
    line_dirty = prediction.line_row("leave-one-out", _corrupted(cases, "C2"))
    assert line_dirty.errors["C2"]["drawbar_pull"] == pytest.approx(
        line_clean.errors["C2"]["drawbar_pull"] - 100.0, rel=1e-12)


def test_a_fitted_preset_is_held_out_from_its_unfitted_base():
    """rashid-patch fitted phi on all four cases: its folds start from paper-table2's phi."""
    base = prediction.unfitted(presets.DEFAULT_PRESET)
    assert base["soil.phi"] == presets.load("paper-table2")["soil.phi"]
    assert base["soil.phi"] != presets.load(presets.DEFAULT_PRESET)["soil.phi"]
    assert prediction.unfitted("paper-table2")["soil.phi"] == base["soil.phi"]


def test_ding_soil_in_reece_form_is_bekkers_pressure_at_the_wheel_width():
    soil = prediction.ding_soil(0.165)
    bekker = prediction._DING_BEKKER
    for z in (0.002, 0.01, 0.03):
        reece = (soil["soil.cohesion"] * soil["soil.k_c"]
                 + soil["soil.gamma"] * 0.165 * soil["soil.k_phi"]) * (z / 0.165) ** soil[
                     "soil.n0"]
        want = (bekker["k_c"] / 0.165 + bekker["k_phi"]) * z ** bekker["n"]
        assert reece == pytest.approx(want, rel=1e-12)


def test_transfer_uses_the_other_wheel_and_soil_with_the_presets_model_form():
    rows = prediction.ding_rows()
    assert len(rows) == 12
    assert {r["load_n"] for r in rows} == {80.0}
    result = prediction.transfer_errors(presets.load("paper-table2"), "lug10")
    lug = [r for r in rows if r["case"].startswith("lug10_")]
    other = presets.load("paper-table2").with_values({
        **prediction.ding_soil(0.165), "wheel.radius": 0.15735, "wheel.width": 0.165,
        "grouser.height": 0.01, "grouser.count": 30, "ripple.k_g": 0.0, "ripple.k_0": 0.0})
    first = model.steady_state(other, 80.0, lug[1]["slip"])
    assert result["errors"]["drawbar_pull"][1] == pytest.approx(
        first["drawbar_pull"] - lug[1]["drawbar_pull_n"], rel=1e-12)
    assert result["cases"] == [r["case"] for r in lug]


def test_a_fold_no_start_can_fit_is_reported_not_guessed():
    """rashid-calibrated's unfitted start cannot carry 62 N at C4 in the arc form with the
    soil-element shear: one start alone fails, and the row says so instead of a figure."""
    cases = calibration.paper_cases()
    base = prediction.unfitted("rashid-calibrated")
    with pytest.raises(calibration.CalibrationError, match="none of the 1 starts"):
        calibration.fit(base, prediction.preset_free("rashid-calibrated"), ["C2", "C3", "C4"],
                        starts=1)
    row = prediction.model_row("rashid-calibrated", base,
                               prediction.preset_free("rashid-calibrated"), "leave-one-out",
                               cases, starts=1).as_dict()
    assert row["drawbar_pull_mae"] is None
    assert "failed" in row["error"]
    assert "failed" in prediction.format_table({"rows": [row]})
