"""The validation scripts run as users run them and report what the library computes."""

from __future__ import annotations

import json
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
        assert case["model"]["sinkage"] == lib["sinkage"]
        assert case["model"]["drawbar_pull"] == lib["drawbar_pull"]
    # the paper's own errors, recomputed from the transcribed Table III (digest: 0.48/2.9/0.85)
    paper = result["mean_absolute_error"]["paper_simulation"]
    assert paper["drawbar_pull"] == pytest.approx(0.4775, abs=1e-9)
    assert paper["sinkage"] == pytest.approx(0.00085, abs=1e-12)


def test_calibration_protocols_report_held_out_errors_of_the_fitted_values(tmp_path):
    from wheelterrain import calibration

    out_file = tmp_path / "protocols.json"
    subprocess.run([sys.executable, str(ROOT / "validation" / "calibration_protocols.py"),
                    "--params", "soil.phi,soil.k_phi", "--starts", "1", "--json",
                    str(out_file)], capture_output=True, text=True, check=True)
    report = json.loads(out_file.read_text())["protocols"]
    assert report[0]["protocol"] == "paper protocol (fit C2)"
    assert len(report) == 6  # C2-only, four leave-one-out fits, all cases
    base = presets.load("paper-table2")
    for p in report:
        for name, value in p["values"].items():
            lo, hi, _ = calibration.PLAUSIBLE[name]
            assert lo <= value <= hi
        # the held-out errors are those of the fitted values, recomputed here
        held = calibration.errors_on(base.with_values(p["values"]), list(p["held_out_errors"]))
        for case, err in p["held_out_errors"].items():
            assert err["drawbar_pull"] == pytest.approx(held[case]["drawbar_pull"], rel=1e-12)
