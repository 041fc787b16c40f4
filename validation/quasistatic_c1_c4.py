"""C1-C4 with the quasi-static core model, next to the paper's Table III; nothing fitted here.

    python validation/quasistatic_c1_c4.py [--preset paper-table2] [--json FILE]

For each case the sinkage that carries the rig's 62 N is solved at the case's slip (paper
definition) and the drawbar pull, normal force and sinkage are printed beside the experimental
means and the paper's own simulation, with the mean absolute errors (the co-simulation's own
comparison, cosim.comparison). Nothing is fitted here: a preset fitted on C1-C4 gives in-sample
figures, and `wheelterrain validate` gives the held-out ones.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from wheelterrain import files, model, presets
from wheelterrain.cosim import master as cosim


def compare(preset: str = presets.DEFAULT_PRESET) -> dict:
    """Quasi-static model vs Table III: the rows and mean absolute errors of the co-simulation's
    own comparison (cosim.comparison), with the quasi-static means in place of the FMUs'."""
    paper = cosim.table3()
    params = presets.load(preset)
    results = []
    for case in paper["cases"]:
        out = model.steady_state(params, paper["load_N"], case["slip_paper"], "paper")
        means = {k: out[k] for k in ("drawbar_pull", "normal_force", "sinkage")}
        results.append(cosim.CaseResult(case["case"], case["slip_paper"], means, (0.0, 0.0), {}))
    rows = cosim.comparison(results)
    return {"preset": preset, "source": paper["source"], "cases": rows,
            "mean_absolute_error": cosim.mean_absolute_errors(rows)}


def render(result: dict) -> str:
    return (f"C1-C4, quasi-static core model, preset {result['preset']}, load 62 N"
            f"\n{cosim.format_table(result['cases'], result['mean_absolute_error'])}")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--preset", default=presets.DEFAULT_PRESET)
    parser.add_argument("--json", type=Path, help="also write the comparison as JSON here")
    args = parser.parse_args(argv)
    result = compare(args.preset)
    print(render(result))
    if args.json:
        files.write_atomic(args.json, json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
