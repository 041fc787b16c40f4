"""The package as a user installs it: a wheel (no -e) in a fresh venv, run from an empty
folder. Everything the package reads at run time must ship inside it."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _run(args, cwd, timeout=600):
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    return subprocess.run(args, cwd=cwd, capture_output=True, text=True, check=False,
                          timeout=timeout, env=env)


@pytest.mark.slow
def test_an_installed_wheel_works_from_an_empty_folder(tmp_path):
    dist = tmp_path / "dist"
    built = _run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(dist),
                  str(ROOT)], cwd=tmp_path)
    assert built.returncode == 0, built.stderr[-2000:]
    wheel = next(dist.glob("wheelterrain-*.whl"))
    venv = tmp_path / "venv"
    # the dependencies (numpy, casadi, fmpy, ...) come from this environment; the package itself
    # only from the wheel
    made = _run([sys.executable, "-m", "venv", "--system-site-packages", str(venv)], cwd=tmp_path)
    assert made.returncode == 0, made.stderr
    python, cli = venv / "bin" / "python", venv / "bin" / "wheelterrain"
    installed = _run([str(python), "-m", "pip", "install", "--no-deps", "-q", str(wheel)],
                     cwd=tmp_path)
    assert installed.returncode == 0, installed.stderr[-2000:]
    work = tmp_path / "empty"
    work.mkdir()
    where = _run([str(python), "-c", "import wheelterrain; print(wheelterrain.__file__)"],
                 cwd=work)
    assert Path(where.stdout.strip()).is_relative_to(venv), where.stdout  # not the checkout

    steps = {
        "build": [str(cli), "build", "--out", "fmus"],
        "reproduce": [str(cli), "reproduce", "--fmu-dir", "fmus", "--stop", "12", "--out",
                      "out", "--json", "r.json"],
        "steady": [str(cli), "steady", "--slip", "0.2", "--load", "62", "--json"],
        # the MPC's goal on the plant it is designed for, the soil without memory
        "mpc": [str(cli), "mpc", "--plant", "casadi", "--set", "model.soil_memory=0", "--out",
                "mpc", "--json"],
        "validate": [str(cli), "validate", "--starts", "1", "--json"],
    }
    out = {}
    for name, args in steps.items():
        run = _run(args, cwd=work)
        assert run.returncode == 0, f"{name}: {run.stderr[-2000:]}"
        out[name] = run.stdout
    assert (work / "fmus" / "WheelTerrain.fmu").is_file()
    assert (work / "fmus" / "SingleWheelRig.fmu").is_file()
    assert json.loads((work / "r.json").read_text())["cases"][3]["case"] == "C4"
    assert json.loads(out["steady"])["preset"] == json.loads(out["mpc"])["preset"]
    assert json.loads(out["mpc"])["slip_rms_error"] < 5e-4
    assert any(r["protocol"] == "transfer" for r in json.loads(out["validate"])["rows"])
