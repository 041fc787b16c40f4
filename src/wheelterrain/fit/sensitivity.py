"""Parameter sensitivity of the C1-C4 predictions, two ways.

- Local: elasticities (dy/dp)*(p/y) of drawbar pull and sinkage at a preset, from the exact
  CasADi Jacobian of the steady state (implicit function theorem).
- Global, one at a time: the swing (max - min) of drawbar pull and sinkage while one parameter
  sweeps its plausible range (calibration.PLAUSIBLE) through WheelTerrain.fmu (fmpy sweep), the
  others held at the preset; infeasible points (load beyond capacity) are left out and counted.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from wheelterrain import model
from wheelterrain.cosim import sweep as sweeper
from wheelterrain.fit import calibration
from wheelterrain.model.slip import traction_from_paper
from wheelterrain.parameters import INDEX, ParameterSet

SOIL = ("soil.phi", "soil.cohesion", "soil.k_phi", "soil.k_c", "soil.n0", "soil.n1",
        "soil.shear_modulus")


def elasticities(ps: ParameterSet, slip_paper: float, load: float = 62.0,
                 names=SOIL) -> dict[str, dict[str, float]]:
    i = traction_from_paper(slip_paper)
    out = model.steady_state(ps, load, i)
    jac = model.steady_jacobian(ps, load, i, state=out)["d_params"]
    rows = {"sinkage": 0, "drawbar_pull": 2}
    return {n: {k: float(jac[r, INDEX[n]] * ps[n] / out[k]) for k, r in rows.items()}
            for n in names}


def swings(fmu: Path, ps: ParameterSet, slip_paper: float, load: float = 62.0, points: int = 7,
           names=SOIL, workers: int = 1) -> dict[str, dict[str, float]]:
    result = {}
    for n in names:
        lo, hi, _ = calibration.PLAUSIBLE[n]
        axes = {"slip": [slip_paper], "load": [load], n: list(np.linspace(lo, hi, points))}
        rows = sweeper.run(fmu, sweeper.base_values(ps), axes, "paper", workers=workers)
        ok = [r for r in rows if r["status"] == "ok"]
        result[n] = {
            "drawbar_pull": (max(r["drawbar_pull"] for r in ok)
                             - min(r["drawbar_pull"] for r in ok)) if ok else math.nan,
            "sinkage": (max(r["contact_sinkage"] for r in ok)
                        - min(r["contact_sinkage"] for r in ok)) if ok else math.nan,
            "infeasible": len(rows) - len(ok)}
    return result


def ranking(values: dict[str, dict[str, float]], key: str) -> list[str]:
    """Names by decreasing |value[key]| (NaN last)."""
    return sorted(values, key=lambda n: -abs(values[n][key])
                  if math.isfinite(values[n][key]) else math.inf)
