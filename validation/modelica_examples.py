"""The Modelica library's examples in a Modelica tool (rumoca) against the Python model.

    python validation/modelica_examples.py [--out validation/report/modelica_examples.png]
                                           [--stop 4] [--json FILE]

Builds the library (as `wheelterrain build --flavor modelica`) into a temporary folder, runs
Examples.SlipRamp, Examples.FMUTwin.RoverSlope and Examples.RigC2 with rumoca, each at its own
experiment tolerance, with the Modelica Standard Library 4.x from MODELICAPATH (the blocks'
connectors are MSL's); prints the largest relative difference from the reference results the
library ships (Resources/Reference, written by the Python model) and plots them.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import numpy as np

from wheelterrain import plots
from wheelterrain.modelica import library, reference
from wheelterrain.modelica.names import path as library_name


def _own(example: str):
    """rumoca's settings at the example's own experiment tolerance (reference.tolerance)."""
    import rumoca

    tolerance = reference.tolerance(example)
    return rumoca.SimConfig(solver="rk-like", rtol=tolerance,
                            atol=tolerance * reference.ABSOLUTE_SHARE)


def _relative(got, want) -> float:
    return float(np.max(np.abs(np.asarray(got) - want)) / np.max(np.abs(want)))


SHOWN = ("sinkage", "drawbar_pull")
"""The model's quantities drawn and compared (the library names them in its own convention)."""


def _named(source, keys) -> dict[str, np.ndarray]:
    """``keys`` (the model's names) read from a result or a reference by the library's names."""
    return {k: np.asarray(source[library_name(k)]) for k in keys}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path,
                        default=Path("validation/report/modelica_examples.png"))
    parser.add_argument("--stop", type=float, default=reference.RIG_STOP,
                        help="how long to run RigC2 [s]")
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args()
    import rumoca

    msl = reference.find_msl()
    if msl is None:
        print("error: the examples need the Modelica Standard Library 4.x: put a folder holding "
              "Modelica/, ModelicaServices/ and Complex.mo on MODELICAPATH", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        library.write(root / "lib")
        path = reference.one_root(msl, root / "lib", root / "path")
        session = rumoca.Session(roots=[str(path)])
        model = session.loads("model Run\n  extends WheelTerrain.Examples.SlipRamp;\nend Run;\n",
                              model="Run")
        result = model.simulate((0.0, 1.0), dt=0.05, config=_own("SlipRamp"))
        ref = _named(reference.read(root / "lib", "SlipRamp"), ("time", "slip", *SHOWN))
        ramp = {"name": f"rumoca {rumoca.version()}", "python": ref,
                "tool": _named(result, SHOWN)}
        figures = {"SlipRamp": {k: _relative(ramp["tool"][k], ref[k])
                                for k in SHOWN}}
        model = session.loads("model Run\n  extends WheelTerrain.Examples.FMUTwin.RoverSlope;\n"
                              "end Run;\n", model="Run")
        result = model.simulate((0.0, reference.ROVER_STOP), dt=reference.ROVER_INTERVAL,
                                config=_own("RoverSlope"))
        ref = reference.read(root / "lib", "RoverSlope")
        columns = {"drawbar_pull": ("rear_left.drawbar_pull", "rear_left.drawbar_pull"),
                   "sinkage": ("chassis.sinkage[3]", "rear_left.sinkage")}
        tool = {"time": np.asarray(result.time)}
        tool.update({k: np.asarray(result[library_name(name)])
                     for k, (name, _) in columns.items()})
        python = {"time": ref["time"],
                  **{k: ref[library_name(col)] for k, (_, col) in columns.items()}}
        climb = {"name": ramp["name"], "tool": tool, "python": python}
        figures["RoverSlope"] = {k: _relative(tool[k], python[k]) for k in columns}
        model = session.loads("model Run\n  extends WheelTerrain.Examples.RigC2;\nend Run;\n",
                              model="Run")
        result = model.simulate((0.0, args.stop), dt=reference.RIG_INTERVAL,
                                config=_own("RigC2"))
        ref = _named(reference.read(root / "lib", "RigC2"), ("time", *SHOWN))
        n = len(result.time)
        tool = {"time": np.asarray(result.time), **_named(result, SHOWN)}
        rig = {"name": ramp["name"], "tool": tool,
               "python": {k: v[:n] for k, v in ref.items()}}
        figures["RigC2"] = {k: _relative(tool[k], ref[k][:n]) for k in SHOWN}
    for name, errors in figures.items():
        print(f"{name}: largest difference from the Python model, relative to the largest "
              "value: " + ", ".join(f"{k} {v:.1e}" for k, v in errors.items()))
    plots.modelica_examples(ramp, rig, args.out, rover=climb)
    print(f"wrote {args.out}")
    if args.json:
        args.json.write_text(json.dumps(figures, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
