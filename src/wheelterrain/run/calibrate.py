"""``wheelterrain calibrate`` as one call: the fit, its errors on the cases it did not see, the
profiles, and the fitted preset written whole."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from wheelterrain import files
from wheelterrain.fit import calibration
from wheelterrain.parameters import ParameterSet

CASES = ("C1", "C2", "C3", "C4")


@dataclass
class Calibration:
    """What :func:`calibrate` did: the fit, the held-out errors, the profiles, the document
    ``--json`` prints, and the preset file written (or None)."""

    result: calibration.Fit
    held_out: dict
    profiles: dict
    document: dict
    written: Path | None


def calibrate(base: ParameterSet, preset: str, names: list[str], cases: list[str],
              starts: int = 8, seed: int = 0, outputs: tuple[str, ...] = ("drawbar_pull",
                                                                          "sinkage"),
              profile_points: int = 0, out_file: Path | None = None, name: str = "fitted",
              protocol: str | None = None) -> Calibration:
    """Fit ``names`` on ``cases`` (:func:`wheelterrain.fit.calibration.fit`), judge the fit on
    the other cases, profile each parameter at ``profile_points`` values where asked, and write
    the fitted preset (values and provenance) to ``out_file`` where given."""
    result = calibration.fit(base, names, cases, starts=starts, seed=seed, outputs=outputs)
    fitted = base.with_values(result.values)
    held_out_cases = [c for c in CASES if c not in cases]
    held = calibration.errors_on(fitted, held_out_cases) if held_out_cases else {}
    profiles = {}
    for n in names if profile_points >= 2 else []:
        points = calibration.profile(base, names, cases, result.values, n, profile_points,
                                     outputs=result.outputs)
        profiles[n] = {"points": points,
                       "interval": calibration.profile_interval(points, 2 * result.cost)}
    document = {
        "preset": preset, "fitted_on": list(cases), "outputs": list(result.outputs),
        "values": result.values,
        "plausible_ranges": result.bounds, "at_bound": result.at_bound,
        "standard_errors": result.standard_errors,
        "correlation": None if result.correlation is None else result.correlation.tolist(),
        "residuals": result.residuals, "held_out_errors": held,
        "starts": result.starts, "spread_of_best_starts": result.spread,
        "profiles": profiles,
    }
    if out_file is not None:
        doc = calibration.preset_document(name, preset, base, result,
                                          protocol or f"least squares on {', '.join(cases)}")
        for n, prof in profiles.items():
            doc["provenance"]["fitted"][n]["profile_interval"] = list(prof["interval"])
        files.write_atomic(out_file, json.dumps(doc, indent=2) + "\n")
    return Calibration(result, held, profiles, document, out_file)
