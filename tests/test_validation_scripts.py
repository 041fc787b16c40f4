"""The validation scripts run as users run them and report what the library computes."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from wheelterrain import model, presets

ROOT = Path(__file__).resolve().parents[1]


def test_quasistatic_c1_c4_prints_and_writes_the_library_values(tmp_path):
    out_file = tmp_path / "c1c4.json"
    run = subprocess.run([sys.executable, str(ROOT / "validation" / "quasistatic_c1_c4.py"),
                          "--json", str(out_file)], capture_output=True, text=True, check=True)
    for case in ("C1", "C2", "C3", "C4"):
        assert f"\n{case} " in run.stdout
    result = json.loads(out_file.read_text())
    params = presets.load(result["preset"])
    assert [c["case"] for c in result["cases"]] == ["C1", "C2", "C3", "C4"]
    for case in result["cases"]:
        lib = model.steady_state(params, 62.0, case["slip_paper"], "paper")
        assert case["sinkage"] == lib["sinkage"]
        assert case["drawbar_pull"] == lib["drawbar_pull"]
    # the paper's own errors, recomputed from the transcribed Table III (digest: 0.48/2.9/0.85)
    mae = result["mean_absolute_error"]
    assert mae["drawbar_pull_paper_simulation"] == pytest.approx(0.4775, abs=1e-9)
    assert mae["sinkage_paper_simulation"] == pytest.approx(0.00085, abs=1e-12)


def test_calibration_protocols_report_held_out_errors_of_the_fitted_values(tmp_path):
    from wheelterrain.fit import calibration

    out_file = tmp_path / "protocols.json"
    subprocess.run([sys.executable, str(ROOT / "validation" / "calibration_protocols.py"),
                    "--params", "soil.phi,soil.k_phi", "--starts", "1", "--json",
                    str(out_file)], capture_output=True, text=True, check=True)
    report = json.loads(out_file.read_text())["protocols"]
    assert report[0]["protocol"] == "paper protocol (fit C2)"
    assert len(report) == 6  # C2-only, four leave-one-out fits, all cases
    base = presets.load(presets.DEFAULT_PRESET)  # the script's default
    for p in report:
        for name, value in p["values"].items():
            lo, hi, _ = calibration.PLAUSIBLE[name]
            assert lo <= value <= hi
        # the held-out errors are those of the fitted values, recomputed here
        held = calibration.errors_on(base.with_values(p["values"]), list(p["held_out_errors"]))
        for case, err in p["held_out_errors"].items():
            assert err["drawbar_pull"] == pytest.approx(held[case]["drawbar_pull"], rel=1e-12)


@pytest.mark.parametrize(("rms", "verdict"), [(3.97, "keeps the smaller set"),
                                              (3.5, "should be refitted with it"),
                                              (4.2, "")])
def test_report_weighs_a_left_out_mechanism_by_its_figures(monkeypatch, rms, verdict):
    monkeypatch.syspath_prepend(str(ROOT / "validation"))
    import make_report
    import model_form_study

    def row(name, rms_objective, dp):
        return {"variant": name, "all_case": {"mae_drawbar_pull": dp},
                "leave_one_out": {"rms_objective": rms_objective}}

    rows = [row(model_form_study.CHOSEN, 4.0, 1.46)]
    rows += [row(label, rms + 1.0 + k, 2.0) for k, (label, _, _) in
             enumerate(model_form_study.ON_TOP[1:])]
    rows.append(row(model_form_study.ON_TOP[0][0], rms, 1.40))
    text = make_report.on_top_verdict(rows)
    assert f"'{model_form_study.ON_TOP[0][0]}' does best" in text
    assert f"RMS {rms:.2f} against 4.00" in text
    assert "1.40 N against 1.46 N" in text
    if verdict:
        assert verdict in text
    else:
        assert "preset" not in text  # worse than the chosen set: nothing to weigh


@pytest.mark.parametrize(("floor", "sinkage", "verdict"), [
    (0.55, 15.1, "still above the 0.48 N bar"),
    (0.40, 15.1, "at or below the 0.48 N bar, but only with the sinkage given up"),
    (0.40, 0.70, "at or below the 0.48 N bar."),
])
def test_report_states_the_pull_floor_from_its_figures(monkeypatch, floor, sinkage, verdict):
    monkeypatch.syspath_prepend(str(ROOT / "validation"))
    import make_report

    def row(name, dp, z):
        fit = {"mae_drawbar_pull": dp, "mae_sinkage_mm": z,
               "drawbar_pull_residuals": [-dp, 0.0, dp, 0.0]}
        return {"variant": name, "least_squares": fit, "least_absolute": fit}

    rows = [row("chosen", floor + 0.1, 15.0), row("every", floor, sinkage)]
    text = "\n".join(make_report.pull_floor_lines(rows))
    assert f"The lowest pull MAE is {floor:.2f} N (every, least absolute error; sinkage MAE " \
           f"{sinkage:.2f} mm there)" in text
    assert verdict in text
    assert text.count("| chosen |") == 1
    assert text.count("| every |") == 1


@pytest.mark.slow
def test_modelica_examples_runs_the_examples_in_rumoca_and_draws_them(tmp_path):
    """With MSL (the tests' MODELICAPATH) the script runs SlipRamp, RoverSlope and RigC2 (its
    first second here) at their own tolerances and prints and writes the measured difference
    from the Python model; without MSL it says what it needs, exit 2."""
    pytest.importorskip("rumoca")
    from wheelterrain.modelica import reference

    script = str(ROOT / "validation" / "modelica_examples.py")
    bare = {k: v for k, v in os.environ.items() if k != "MODELICAPATH"}
    refused = subprocess.run([sys.executable, script], capture_output=True, text=True,
                             env=bare, timeout=300)
    assert refused.returncode == 2
    assert "need the Modelica Standard Library 4.x" in refused.stderr
    if reference.find_msl() is None:
        pytest.skip("no MSL 4.x on MODELICAPATH (the shared archive unpacks it in CI)")
    out, figures = tmp_path / "examples.png", tmp_path / "figures.json"
    run = subprocess.run([sys.executable, script, "--out", str(out), "--json", str(figures),
                          "--stop", "1"], capture_output=True, text=True, check=True,
                         timeout=1500)
    result = json.loads(figures.read_text())
    assert set(result) == {"SlipRamp", "RoverSlope", "RigC2"}
    for example in result.values():
        assert 0 <= example["sinkage"] < 1e-8
        assert 0 <= example["drawbar_pull"] < 1e-8
    assert f"sinkage {result['SlipRamp']['sinkage']:.1e}" in run.stdout
    assert out.stat().st_size > 10_000
