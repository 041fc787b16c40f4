"""Exact derivatives of the wheel-soil forces from the CasADi model (copy and adapt).

    python casadi_models/jacobian_demo.py

Prints the sensitivity of sinkage and drawbar pull at the paper's C2 operating point (62 N,
s = 0.25) to the load, the slip and the five most influential parameters, per 1 % change.
"""

from __future__ import annotations

import numpy as np

from wheelterrain import model, presets
from wheelterrain.model.slip import traction_from_paper
from wheelterrain.parameters import NAMES


def main() -> None:
    params = presets.load("paper-table2")
    slip = traction_from_paper(0.25)
    jac = model.steady_jacobian(params, 62.0, slip)
    values = params.vector()
    rows = ("sinkage [m]", "normal_force [N]", "drawbar_pull [N]", "torque [N.m]")
    print("d(output) per 1 % change of load and slip:")
    for k, name in enumerate(rows):
        print(f"  {name:18} load {jac['d_inputs'][k, 0] * 0.62:+.4g}   "
              f"slip {jac['d_inputs'][k, 1] * slip * 0.01:+.4g}")
    # parameters at zero have no 1 % change (and d/d exit_ratio is infinite at 0): skip them
    per_pct = np.multiply(jac["d_params"], values * 0.01, out=np.zeros_like(jac["d_params"]),
                          where=values != 0)
    order = np.argsort(-np.abs(per_pct[2]))[:5]
    print("drawbar pull per 1 % change of the most influential parameters:")
    for j in order:
        print(f"  {NAMES[j]:28} {per_pct[2, j]:+.4g} N   (sinkage {per_pct[0, j] * 1e3:+.4g} mm)")


if __name__ == "__main__":
    main()
