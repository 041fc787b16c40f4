"""Quadrature error against adaptive quadrature, per number of nodes: what the node count of
``contact.DEFAULT_NODES`` is chosen from.

    python benchmarks/quadrature.py [--nodes 12,14,16] [--json]

The grid is the classical test grid of tests/test_classical.py (four soils, driving slips
0 ... 0.99, sinkage 1e-4 R ... R); the reference is tests/classical_reference.py (scipy's adaptive
quad). The error of an output is |model - reference| / |reference|, the drawbar pull's on the
scale of the normal force (it passes through zero); printed per node count: the median and the
three worst points with where they are. ``--json`` prints {"nodes": {N: {"median", "worst"}}}.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

from wheelterrain.model import contact
from wheelterrain.model import functions as model_functions

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nodes", default="12,14,16",
                        help="node counts per panel before the shear reversal to compare")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    sys.path.insert(0, str(ROOT / "tests"))  # the reference and the grid live with the tests
    from classical_reference import Classical
    from conftest import classical_set
    from test_classical import DRIVING_SLIPS, SOILS

    points = []
    for row in SOILS:
        name, R, b, c, phi, kc, kphi, n, gamma, K, a0, a1 = row
        ref = Classical(R=R, b=b, c=c, phi=math.radians(phi), kc=kc, kphi=kphi, n=n,
                        gamma=gamma, K=K, a0=a0, a1=a1)
        ps = classical_set(R, b, c, phi, kc, kphi, n, gamma, K, a0, a1)
        for slip in DRIVING_SLIPS:
            for frac in (1e-4, 0.05, 0.3, 0.7, 1.0):
                points.append((name, ps, frac * R, frac, slip, ref.forces(frac * R, slip)))
    figures = {}
    for count in (int(x) for x in args.nodes.split(",")):
        nodes = (count, contact.DEFAULT_NODES[1])
        fn = model_functions.build(nodes).contact
        errors = []
        for name, ps, z, frac, slip, want in points:
            values = np.array(fn(z, 0, slip, 0, ps.vector())).ravel()
            got = dict(zip(contact.CONTACT_OUTPUTS, values, strict=True))
            for key, value in want.items():
                scale = abs(want["normal_force"]) if key == "drawbar_pull" else 0.0
                error = abs(got[key] - value) / max(abs(value), scale, 1e-300)
                errors.append((error, f"{name} i={slip:g} z/R={frac:g} {key}"))
        errors.sort(reverse=True)
        median = float(np.median([e for e, _ in errors]))
        figures[count] = {"median": median, "worst": errors[0][0]}
        print(f"{nodes} nodes: median {median:.1e}, worst "
              + "; ".join(f"{e:.1e} ({where})" for e, where in errors[:3]),
              file=sys.stderr if args.json else sys.stdout)
    if args.json:
        print(json.dumps({"nodes": figures}, indent=2))


if __name__ == "__main__":
    main()
