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
