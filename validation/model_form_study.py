"""Model-form study: what each mechanism adds to the fit and to the held-out error.

    python validation/model_form_study.py [--starts 4] [--json FILE]

Every variant frees the classical soil parameters (phi, k_phi', n0, c, K) and adds mechanisms
one at a time, then all together; then (ON_TOP) each mechanism the chosen set leaves out is added
to that set. For each variant:
- the all-case fit (in-sample MAE over C1-C4);
- leave-one-out (each case predicted by a fit to the other three; pooled held-out MAE);
- the count of parameters that end at a plausible bound;
- the selection criterion: the RMS over the held-out cases of the fit's own objective
  (drawbar pull in N and sinkage in mm), pooled over the four leave-one-out folds.
Then (PULL_FLOOR) how closely the model's pull-slip curve can follow the rig's at all: fits to
the drawbar pull alone, the sinkage free to go wrong, by least squares and by least absolute
error (the MAE a target is stated in), of the chosen set and of every mechanism at once.
Mechanisms switched off keep their classical value (n1 = 0, radius factors 0, Janosi shear,
exit angle 0). Each variant's first start is the classical optimum (it nests the classical
model), the others are random over the plausible box; a variant can still land in another local
minimum, which the table then shows. Sources of each mechanism: src/wheelterrain/contact.py.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from wheelterrain import presets
from wheelterrain.files import write_atomic
from wheelterrain.fit import calibration

SOIL = ["soil.phi", "soil.k_phi", "soil.n0", "soil.cohesion", "soil.shear_modulus"]
CLASSICAL = {"soil.n1": 0.0, "model.contact_radius_factor": 0.0,
             "model.shear_radius_factor": 0.0, "model.slip_radius_factor": 0.0,
             "model.shear_model": 0, "model.exit_ratio": 0.0, "model.grouser_thrust": 0,
             "model.shear_kinematics": 0}
VARIANTS = [
    ("classical Wong-Reece", [], {}),
    ("+ slip-sinkage n1 (Ding 2011)", ["soil.n1"], {}),
    ("+ shear radius at grousers", ["model.shear_radius_factor"], {}),
    ("+ contact radius at grousers", ["model.contact_radius_factor"], {}),
    ("+ slip radius factor", ["model.slip_radius_factor"], {}),
    ("+ Wong hump shear", [], {"model.shear_model": 1}),
    ("+ exit angle (Ishigami)", ["model.exit_ratio"], {}),
    ("+ grouser passive thrust (Bekker)", [], {"model.grouser_thrust": 1}),
    ("+ soil-element shear (SCM)", [], {"model.shear_kinematics": 1}),
    ("n1 + shear radius + exit angle", ["soil.n1", "model.shear_radius_factor",
                                        "model.exit_ratio"], {}),
    ("n1 + shear radius + exit + SCM shear", ["soil.n1", "model.shear_radius_factor",
                                               "model.exit_ratio"],
     {"model.shear_kinematics": 1}),
    ("all of the above", ["soil.n1", "model.shear_radius_factor", "model.contact_radius_factor",
                          "model.slip_radius_factor", "model.exit_ratio"],
     {"model.shear_model": 1, "model.grouser_thrust": 1, "model.shear_kinematics": 1}),
]
CHOSEN = "n1 + shear radius + exit + SCM shear"  # the set rashid-calibrated is fitted with
# What the mechanisms left out add on top of the chosen set (rows added after the preset was
# fitted): each variant's first starts are the chosen set's optima (all-case and per fold). Only
# a0, a1 nest it (the chosen values 0.40, 0.15 lie inside their ranges); the switches change the
# model, so their fits can also end worse.
ON_TOP = [
    ("chosen + grouser passive thrust", [], {"model.grouser_thrust": 1}),
    ("chosen + Wong hump shear", [], {"model.shear_model": 1}),
    ("chosen + max-stress angle a0, a1", ["model.a0", "model.a1"], {}),
]
CASES = ["C1", "C2", "C3", "C4"]
CALIBRATED = "rashid-calibrated"  # the eight-parameter arc-form fit this study is about
# How closely can the model's pull-slip curve follow the rig's at all? Pull-only fits (the
# sinkage left free to go wrong) of the chosen set and of every mechanism at once, each
# continuous one free in its plausible range, the switches as named.
EVERY = ["soil.n1", "model.shear_radius_factor", "model.contact_radius_factor",
         "model.slip_radius_factor", "model.exit_ratio", "model.a0", "model.a1"]
PULL_FLOOR = [
    ("every mechanism, Janosi shear, soil-element j", EVERY,
     {"model.grouser_thrust": 1, "model.shear_kinematics": 1}),
    ("every mechanism, Wong hump shear, soil-element j", EVERY,
     {"model.grouser_thrust": 1, "model.shear_kinematics": 1, "model.shear_model": 1}),
    ("every mechanism, Janosi shear, wheel-element j", EVERY,
     {"model.grouser_thrust": 1, "model.shear_kinematics": 0}),
]
LEAST_ABSOLUTE_SCALE = 0.005  # N: soft-L1 scale far below the residuals, ~ least absolute


def mae(errors) -> tuple[float, float]:
    """(drawbar pull N, sinkage mm) mean absolute errors: calibration.mean_absolute, in the
    units this script prints."""
    out = calibration.mean_absolute(errors)
    return out["drawbar_pull"], 1e3 * out["sinkage"]


def study(starts: int = 4, echo=print) -> list[dict]:
    """Run every variant; returns one row per variant (see the module docstring)."""
    base = presets.load("paper-table2-arc").with_values({**CLASSICAL, "ripple.k_g": 0.0,
                                                     "ripple.k_0": 0.0})
    rows = []
    nested: dict[str, dict] = {}  # the classical optima (all-case and each fold): first starts
    nested_chosen: dict[str, dict] = {}  # the chosen set's, for the ON_TOP variants
    echo(f"{'variant':34} {'all-case MAE':>20} {'leave-one-out MAE':>22} {'at bound':>9} "
         f"{'LOO RMS':>8}")
    chosen = next(v for v in VARIANTS if v[0] == CHOSEN)
    on_top = [(label, chosen[1] + extra, {**chosen[2], **switches}) for label, extra, switches
              in ON_TOP]
    runs = [(*v, False) for v in VARIANTS] + [(*v, True) for v in on_top]
    for label, extra, switches, from_chosen in runs:
        names = SOIL + extra
        ps = base.with_values(switches)
        first = nested_chosen if from_chosen else nested
        full = calibration.fit(ps, names, CASES, starts=starts, initial=first.get("all"))
        held, optima = [], {"all": full.values}
        for out in CASES:
            r = calibration.fit(ps, names, [c for c in CASES if c != out], starts=starts,
                                initial=first.get(out))
            held.append(calibration.errors_on(ps.with_values(r.values), [out])[out])
            optima[out] = r.values
        if not extra and not switches:
            nested = optima
        if label == CHOSEN:
            nested_chosen = optima
        fit_dp, fit_z = mae(full.residuals.values())
        out_dp, out_z = mae(held)
        # the selection criterion, fixed before looking: the fit's own objective (N and mm
        # residuals) on the held-out cases, pooled over the four folds
        rms = float(np.sqrt(np.mean([e["drawbar_pull"] ** 2 + (1e3 * e["sinkage"]) ** 2
                                     for e in held])))
        echo(f"{label:34} {fit_dp:7.2f} N {fit_z:6.2f} mm {out_dp:10.2f} N {out_z:6.2f} mm "
             f"{len(full.at_bound):>5}/{len(names)} {rms:8.2f}")
        rows.append({"variant": label, "free": names, "switches": switches,
                     "all_case": {"values": full.values, "at_bound": full.at_bound,
                                  "mae_drawbar_pull": fit_dp, "mae_sinkage_mm": fit_z},
                     "leave_one_out": {"mae_drawbar_pull": out_dp, "mae_sinkage_mm": out_z,
                                       "rms_objective": rms}})
    best = min(rows, key=lambda r: r["leave_one_out"]["rms_objective"])
    echo(f"\nbest by leave-one-out RMS of the fit objective: {best['variant']}")
    return rows


def pull_floor(starts: int = 16, echo=print) -> list[dict]:
    """Pull-only fits: the least-squares optimum and the least-absolute one (soft-L1, scale
    LEAST_ABSOLUTE_SCALE; it minimises ~ the MAE itself), from the chosen set's all-case optimum
    and ``starts - 1`` random starts. One row per variant (the chosen set first)."""
    base = presets.load("paper-table2-arc").with_values({**CLASSICAL, "ripple.k_g": 0.0,
                                                     "ripple.k_0": 0.0})
    chosen = next(v for v in VARIANTS if v[0] == CHOSEN)
    runs = [(f"chosen set ({CHOSEN})", chosen[1], chosen[2]), *PULL_FLOOR]
    reference = _chosen_preset_values()
    echo(f"{'pull-only fit':50} {'least squares':>24} {'least absolute':>24}")
    rows = []
    for label, extra, switches in runs:
        names = SOIL + extra
        ps = base.with_values(switches)
        row = {"variant": label, "free": names, "switches": switches}
        for key, loss, scale in (("least_squares", "linear", 1.0),
                                 ("least_absolute", "soft_l1", LEAST_ABSOLUTE_SCALE)):
            r = calibration.fit(ps, names, CASES, starts=starts, initial=reference,
                                outputs=("drawbar_pull",), loss=loss, loss_scale=scale)
            dp, z = mae(r.residuals.values())
            row[key] = {"mae_drawbar_pull": dp, "mae_sinkage_mm": z,
                        "drawbar_pull_residuals": [r.residuals[c]["drawbar_pull"]
                                                   for c in CASES],
                        "at_bound": r.at_bound, "values": r.values}
        echo(f"{label:50} {row['least_squares']['mae_drawbar_pull']:7.2f} N "
             f"{row['least_squares']['mae_sinkage_mm']:7.2f} mm "
             f"{row['least_absolute']['mae_drawbar_pull']:7.2f} N "
             f"{row['least_absolute']['mae_sinkage_mm']:7.2f} mm")
        rows.append(row)
    return rows


def _chosen_preset_values() -> dict[str, float]:
    doc = presets.read(CALIBRATED)
    return {n: f["value"] for n, f in doc["provenance"]["fitted"].items()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--starts", type=int, default=4)
    ap.add_argument("--json", type=Path)
    args = ap.parse_args()
    rows = study(args.starts)
    print()
    floor = pull_floor(4 * args.starts)
    if args.json:
        write_atomic(args.json, json.dumps({"variants": rows, "pull_floor": floor}, indent=2)
                     + "\n")


if __name__ == "__main__":
    main()
