"""Prediction protocols: how well a model predicts data it was not fitted on.

Four rig cases cannot tell a good model from a flexible one by in-sample error, so every model
is judged held out and beside a baseline (shared protocol of the project's README):

- ``all-case``: fitted on C1-C4 and judged on them (in-sample; with nothing free it is a pure
  prediction);
- ``leave-one-out``: for each case, fitted on the other three and judged on the one left out;
- ``c2-only``: the source paper's protocol, fitted on C2 alone and judged on C1, C3, C4, with at
  most the two parameters the paper names as most influential (phi and the sinkage exponent);
- ``transfer``: another wheel on another soil (Ding et al. 2011), with that soil's own measured
  parameters and the model form of the preset, nothing refitted.

The baseline is a straight line in the paper's slip, ``y = a + b*s``, fitted the same way (two
parameters; on C2 alone only its constant ``a`` can be fitted). Model fits are those of
:func:`wheelterrain.fit.calibration.fit` on the quasi-static steady state, inside the plausible
ranges. A held-out case's data never reach its fit: the fold is given the other cases' rows
only (tests/test_prediction.py corrupts the held-out row and checks that the fit is unchanged).
"""

from __future__ import annotations

import csv
import io
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np

from wheelterrain import data, model, presets
from wheelterrain.errors import CalibrationError, WheelTerrainError
from wheelterrain.fit import calibration, crosswheel, datasets
from wheelterrain.parameters import DEG, GRAVITY, NO_RIPPLE, ParameterSet

CASES = ("C1", "C2", "C3", "C4")
PAPER_FREE = ("soil.phi", "soil.n0")
"""The paper's two most influential parameters (phi, the sinkage exponent): its protocol's
free set, and the leave-one-out free set of presets that fitted nothing."""
OUTPUTS = calibration.OUTPUTS
LOAD = 62.0  # N, the rig's normal force in every case (validation data)

DING_FILE = "ding2011_single_wheel.csv"
DING_LOAD = 80.0  # N, the vertical load of every Ding et al. 2011 run
DING_SOURCE = ("Ding, Gao, Deng, Tao 2011, J. Terramechanics 48(1):27-45, Table 2 and figures "
               "(digitised, approximate)")
_DING_BEKKER = {"n": 1.10, "k_c": 15.6e3, "k_phi": 2407.4e3, "cohesion": 250.0,
                "phi_deg": 31.9, "density": 1605.0, "shear_modulus": 0.011}
"""The soil of Ding et al. 2011 (their Table 2, as in the data file's header): Bekker form
p = (k_c/b + k_phi)*z**n with k_c in N/m^(n+1), k_phi in N/m^(n+2); cohesion Pa; bulk density
kg/m3; Janosi K m."""


def ding_soil(width: float) -> dict[str, float]:
    """Ding et al. 2011's soil in the table's Reece form, for a wheel of ``width`` b [m].

    Bekker's p = (k_c/b + k_phi)*z**n equals Reece's p = (c*k_c' + gamma*b*k_phi')*(z/b)**n
    term by term when k_c' = k_c*b**(n-1)/c and k_phi' = k_phi*b**(n-1)/gamma (Reece 1965;
    Wong, *Theory of Ground Vehicles*, ch. 2): exact at the wheel's own width, which is the
    same for both of Ding's wheels. gamma = density*g.
    """
    s = _DING_BEKKER
    gamma = s["density"] * GRAVITY["earth"]  # the data were taken on Earth
    scale = width ** (s["n"] - 1)
    return {"soil.cohesion": s["cohesion"], "soil.phi": s["phi_deg"] * DEG,
            "soil.k_c": s["k_c"] * scale / s["cohesion"], "soil.k_phi": s["k_phi"] * scale / gamma,
            "soil.n0": s["n"], "soil.gamma": gamma, "soil.shear_modulus": s["shear_modulus"]}


def ding_rows() -> list[dict]:
    """The Ding et al. 2011 rows (SI units, traction slip), from the shipped data file."""
    text = data.path(DING_FILE).read_text(encoding="utf-8")
    lines = [line for line in text.splitlines() if line and not line.startswith("#")]
    return [{k: (v if k == "case" else float(v)) for k, v in row.items()}
            for row in csv.DictReader(io.StringIO("\n".join(lines)))]


def transfer_errors(ps: ParameterSet, wheel: str) -> dict:
    """Mean absolute errors of ``ps``'s model form on Ding's ``wheel`` ("smooth" or "lug10"),
    with that soil's and wheel's own values and the grouser ripple off (the data are means)."""
    rows = [r for r in ding_rows() if r["case"].startswith(wheel + "_")]
    if not rows:
        raise ValueError(f"no Ding 2011 rows for wheel {wheel!r}")
    first = rows[0]
    values = {**ding_soil(first["wheel_width_m"]), "wheel.radius": first["wheel_radius_m"],
              "wheel.width": first["wheel_width_m"], "grouser.height": first["grouser_height_m"],
              "grouser.count": first["grouser_count"], **NO_RIPPLE}
    other = ps.with_values(values)
    err = {"drawbar_pull": [], "sinkage": [], "torque": []}
    for r in rows:
        out = model.steady_state(other, DING_LOAD, r["slip"])
        err["drawbar_pull"].append(out["drawbar_pull"] - r["drawbar_pull_n"])
        err["sinkage"].append(out["sinkage"] - r["sinkage_m"])
        err["torque"].append(out["torque"] - r["torque_nm"])
    return {"cases": [r["case"] for r in rows],
            **{f"{k}_mae": float(np.mean(np.abs(v))) for k, v in err.items()},
            "errors": {k: [float(x) for x in v] for k, v in err.items()}}


# --- the straight-line baseline --------------------------------------------------------------

def _line_predict(train: Sequence[dict], test: Sequence[dict], key: str) -> list[float]:
    """``y = a + b*s`` fitted to ``train`` by least squares (a constant if it has one case),
    evaluated at ``test``'s slips."""
    s = np.array([c["slip_paper"] for c in train])
    y = np.array([c["experiment"][key] for c in train])
    coef = np.polyfit(s, y, 1) if len(train) > 1 else np.array([0.0, y[0]])
    return [float(np.polyval(coef, c["slip_paper"])) for c in test]


# --- protocols -------------------------------------------------------------------------------

@dataclass
class Row:
    """One line of the prediction table."""

    model: str
    protocol: str
    free: list[str]
    errors: dict[str, dict[str, float]]  # judged case -> output -> model minus data (N, m)
    in_sample: bool
    fitted: list[dict[str, float]]  # the fitted values of each fold
    data: str = "paper Table III, experiment"
    error: str | None = None  # why the row has no figures (a fold's fit failed)

    def as_dict(self) -> dict:
        mae = (calibration.mean_absolute(self.errors) if self.error is None
               else dict.fromkeys(OUTPUTS))
        row = {"model": self.model, "protocol": self.protocol, "free": self.free,
               "drawbar_pull_mae": mae["drawbar_pull"], "sinkage_mae": mae["sinkage"],
               "in_sample": self.in_sample, "judged_on": list(self.errors), "data": self.data,
               "errors": self.errors,
               # what each fold fitted, one object per fold (none where nothing was fitted)
               "fitted": {"per_fold": self.fitted} if self.fitted else {}}
        if self.error is not None:
            row["error"] = self.error
        return row


def _folds(protocol: str) -> list[tuple[list[str], list[str]]]:
    """(fitted on, judged on) per fold."""
    if protocol == "all-case":
        return [(list(CASES), list(CASES))]
    if protocol == "leave-one-out":
        return [([c for c in CASES if c != out], [out]) for out in CASES]
    if protocol == "c2-only":
        return [(["C2"], ["C1", "C3", "C4"])]
    raise ValueError(f"unknown protocol {protocol!r}; valid: all-case, leave-one-out, c2-only")


def _rows_of(cases: Sequence[dict], names: Sequence[str]) -> list[dict]:
    by_name = {c["case"]: c for c in cases}
    return [by_name[n] for n in names]


def line_row(protocol: str, cases: Sequence[dict]) -> Row:
    errors: dict[str, dict[str, float]] = {}
    for train, test in _folds(protocol):
        tr, te = _rows_of(cases, train), _rows_of(cases, test)
        for key in OUTPUTS:
            for c, y in zip(te, _line_predict(tr, te, key), strict=True):
                errors.setdefault(c["case"], {})[key] = y - c["experiment"][key]
    free = ["a"] if protocol == "c2-only" else ["a", "b"]
    return Row("line", protocol, free, errors, protocol == "all-case", [])


def model_row(label: str, base: ParameterSet, free: Sequence[str], protocol: str,
              cases: Sequence[dict], starts: int = 4) -> Row:
    """``base`` with ``free`` fitted per fold of ``protocol`` (none free: evaluated as it is).
    Each fold's fit sees only its training rows of ``cases``."""
    errors: dict[str, dict[str, float]] = {}
    fitted: list[dict[str, float]] = []
    for train, test in _folds(protocol):
        ps = base
        if free:
            try:
                result = calibration.fit(base, list(free), train, starts=starts, load=LOAD,
                                         data=_rows_of(cases, train))
            except CalibrationError as err:  # reported in the row, never hidden or guessed
                return Row(label, protocol, list(free), {}, False, fitted,
                           error=f"fit on {', '.join(train)} failed: {err}")
            ps = base.with_values(result.values)
            fitted.append(result.values)
        errors.update(calibration.errors_on(ps, test, LOAD, data=list(cases)))
    return Row(label, protocol, list(free), errors, bool(free) and protocol == "all-case",
               fitted)


def preset_free(name: str) -> list[str]:
    """The parameters a preset's own fit freed (its provenance), else the paper's pair."""
    fitted = presets.read(name)["provenance"].get("fitted")
    return list(fitted) if fitted else list(PAPER_FREE)


def unfitted(name: str) -> ParameterSet:
    """A preset as it was before its own fit: its base preset with the overrides the fit ran
    with (the model form), none of the fitted values. A held-out fold starts from here, so no
    value (and no starting point) fitted on all four cases reaches a fold that must not see
    one of them. A preset that fitted nothing is returned as it is."""
    provenance = presets.read(name)["provenance"]
    if not provenance.get("fitted"):
        return presets.load(name)
    return presets.load(provenance["base_preset"]).with_values(provenance.get("overrides", {}))


TABLE2_TUNED_ON = ("C2",)
"""The paper's authors tuned Table II on C2 (the paper's protocol): a preset built on Table II
has seen C2 before any fit of ours."""


def tuned_on(name: str) -> list[str]:
    """The rig cases a shipped preset's values were tuned on by someone else: C2 for the
    paper's Table II and every preset built on it; [] otherwise."""
    seen, at = [], name
    while at:
        if at.startswith("paper-table2"):
            seen = list(TABLE2_TUNED_ON)
        at = presets.read(at)["provenance"].get("base_preset")
    return seen


def step_count() -> int:
    """How many rows :func:`run` reports progress for: the line's three protocols, per
    shipped preset three protocols and two transfer wheels, per cross-wheel form and the
    cross-wheel line one fold per shipped data set, and per shipped data set the nested
    protocol's three rows (the rule's pick, classical Wong-Reece's and the line's)."""
    sets = len(datasets.shipped())
    return (3 + 5 * len(presets.available())
            + (len(crosswheel.FORMS) + 1) * sets  # leave-one-dataset-out
            + len(crosswheel.ROLES) * sets)  # nested: the rule's, classical's and line's


def run(progress: Callable[[str], None] | None = None, starts: int = 4) -> dict:
    """Every row of ``wheelterrain validate``: the line, each shipped preset as it is, the
    paper's protocol per preset, leave-one-out per preset, and the Ding 2011 transfer."""
    cases = calibration.paper_cases()
    rows: list[dict] = []

    def add(row: Row | dict) -> None:
        rows.append(row.as_dict() if isinstance(row, Row) else row)
        if progress:
            progress(f"{rows[-1]['model']} {rows[-1]['protocol']}")

    for protocol in ("all-case", "leave-one-out", "c2-only"):
        add(line_row(protocol, cases))
    for name in presets.available():
        ps = presets.load(name)
        fitted = presets.read(name)["provenance"].get("fitted")
        free = preset_free(name)
        # as shipped: in-sample where its values were fitted to these cases, else a prediction
        # (in-sample too where Table II's values, tuned on C2 by the paper's authors, are used)
        seen = tuned_on(name)
        add(replace(model_row(name, ps, [], "all-case", cases),
                    in_sample=bool(fitted) or bool(seen), free=list(fitted or [])))
        rows[-1]["tuned_on"] = seen
        start = unfitted(name)
        add(model_row(name, start, PAPER_FREE, "c2-only", cases, starts))
        rows[-1]["tuned_on"] = seen
        add(model_row(name, start, free, "leave-one-out", cases, starts))
        rows[-1]["tuned_on"] = seen
    for name in presets.available():
        ps = presets.load(name)
        for wheel, label in (("smooth", "ding2011-smooth"), ("lug10", "ding2011-lugged")):
            try:
                t = transfer_errors(ps, wheel)
                by_case = {case: {k: t["errors"][k][i] for k in t["errors"]}
                           for i, case in enumerate(t["cases"])}
                t = {**t, "errors": by_case, "judged_on": t["cases"]}
            except WheelTerrainError as exc:  # reported, not hidden
                t = {"drawbar_pull_mae": None, "sinkage_mae": None, "error": str(exc),
                     "errors": {}, "judged_on": []}
            # nothing is refitted: the preset's values, that soil's own
            add({"model": name, "protocol": "transfer", "free": [], "in_sample": False,
                 "data": f"{label} ({DING_SOURCE})", "fitted": {}, **t})
    shipped = datasets.shipped()
    for row in crosswheel.lodo_rows(shipped, starts=min(starts, 3)):
        add(row)
    # the headline: every choice made inside each fold (nested), first in the rows
    nested = crosswheel.nested_rows(shipped, starts=min(starts, 3), progress=progress)
    every: dict[str, list] = {}  # every candidate held out on each data set, in hindsight
    default, scores = crosswheel.choose(shipped, starts=min(starts, 3), folds=every)
    rows[:0] = nested
    return {"rows": rows, "load": LOAD, "transfer_load": DING_LOAD,
            "sinkage_datum": crosswheel.datum_check(shipped),
            "soil_sources": {ds.name: ds.soil_source for ds in shipped},
            "default_form": default,
            "default_form_rule": {"rule": crosswheel.SELECTION, "scores": scores,
                                  "judged_by": nested_summary(nested)},
            "paired": crosswheel.paired(nested),
            "oracle": crosswheel.oracle(every, nested),
            "units": {"drawbar_pull_mae": "N", "sinkage_mae": "m", "torque_mae": "N.m",
                      "drawbar_pull_mae_per_load": "1", "sinkage_mae_per_radius": "1"}}


def nested_summary(rows: Sequence[dict]) -> dict:
    """The means over data sets of the nested rows, per role ('rule': the forms the folds'
    rule chose; 'classical'; 'line'): what judges the selection rule, in N and mm and as shares
    of the load and the radius; the sinkage also without the data sets whose datum is inferred
    (``sinkage_from`` rest) and judged from each set's lowest slip (no datum at all)."""
    out = {}
    for role in crosswheel.ROLES:
        chosen = [r for r in rows if r["protocol"] == crosswheel.NESTED
                  and r.get("role") == role]
        if not chosen:
            continue
        entry = {"datasets": len(chosen), "forms": sorted({r["model"] for r in chosen})}
        if role == "rule":  # constants that end at a bound in most folds
            counts: dict[str, int] = {}
            for r in chosen:
                for name in r.get("at_bound", []):
                    counts[name] = counts.get(name, 0) + 1
            entry["at_bound_in_most_folds"] = sorted(
                n for n, c in counts.items() if c > len(chosen) / 2)
        entry.update(_means(chosen, (
            "drawbar_pull_mae", "sinkage_mae", "drawbar_pull_mae_per_load",
            "sinkage_mae_per_radius", "sinkage_increment_mae",
            "sinkage_increment_mae_per_radius", "interval_coverage")))
        measured = [r for r in chosen if r.get("sinkage_from") != "rest"]
        entry["inferred_datum"] = sorted(r["dataset"] for r in chosen
                                         if r.get("sinkage_from") == "rest")
        entry["without_inferred_datum"] = {
            "datasets": len(measured),
            **_means(measured, ("sinkage_mae", "sinkage_mae_per_radius"))}
        entry["interval_coverage_by_dataset"] = {r["dataset"]: r["interval_coverage"]
                                                 for r in chosen}
        out[role] = entry
    return out


def _summary_line(label: str, entry: dict) -> str:
    """One role of :func:`nested_summary` as text."""
    def fig(key: str, scale: float, fmt: str) -> str:
        v = entry.get(key)
        return "-" if v is None else format(scale * v, fmt)
    cover = entry.get("interval_coverage")
    return (f"{label}: pull {fig('drawbar_pull_mae', 1, '.2f')} N (pull/W "
            f"{fig('drawbar_pull_mae_per_load', 1, '.3f')}), sinkage "
            f"{fig('sinkage_mae', 1e3, '.1f')} mm (z/R {fig('sinkage_mae_per_radius', 1, '.3f')}"
            f"), from the lowest slip {fig('sinkage_increment_mae', 1e3, '.1f')} mm (z/R "
            f"{fig('sinkage_increment_mae_per_radius', 1, '.3f')})"
            + ("" if cover is None else f"; 90 % intervals cover {100 * cover:.0f} %"))


def _means(rows: Sequence[dict], keys: Sequence[str]) -> dict:
    """Per key the mean of ``rows``' values; None if a row lacks one or there is no row."""
    out = {}
    for key in keys:
        values = [r.get(key) for r in rows]
        out[key] = (None if not values or any(v is None for v in values)
                    else float(sum(values) / len(values)))
    return out


def format_table(result: dict) -> str:
    """The rows of :func:`run` as a text table, held-out and in-sample labelled."""
    head = (f"{'model':25} {'protocol':14} {'free':>4} | {'pull MAE [N]':>12} "
            f"{'sinkage MAE [mm]':>16} | judged on")
    lines = [head, "-" * len(head)]
    for r in result["rows"]:
        label = "in-sample" if r["in_sample"] else "held-out"
        if r.get("tuned_on"):  # Table II: tuned by the paper's authors on C2
            label += f" (values tuned on {', '.join(r['tuned_on'])} by the paper's authors)"
        data_name = r["data"].split(" (")[0] if r["protocol"] == "transfer" else label
        if r["protocol"] in ("leave-one-dataset-out", "user-data", crosswheel.NESTED):
            cover = r["interval_coverage"]
            share = r.get("drawbar_pull_mae_per_load")
            per_load = "" if share is None else (
                f"pull/W {share:.3f}, z/R {r['sinkage_mae_per_radius']:.3f}; ")
            role = {"rule": "the rule's pick, ", "classical": "baseline, ",
                    "line": "baseline, "}.get(r.get("role", ""), "")
            datum = ", sinkage datum inferred" if r.get("sinkage_from") == "rest" else ""
            data_name = (f"{'held-out' if r['protocol'] != 'user-data' else 'user data'} "
                         f"{r['dataset']} ({role}{r['points']} points, {per_load}90 % interval "
                         "covers " + ("-" if cover is None else f"{100 * cover:.0f} %")
                         + f"{datum})")
        if r.get("error"):
            figures = f"{'failed':>12} {'':16} | {r['error']}"
        else:
            figures = (f"{r['drawbar_pull_mae']:12.2f} {1e3 * r['sinkage_mae']:16.2f} | "
                       f"{data_name}")
        protocol = {"leave-one-dataset-out": "leave-data-out",
                    crosswheel.NESTED: "nested"}.get(r["protocol"], r["protocol"])
        lines.append(f"{r['model']:25} {protocol:14} {len(r['free']):4d} | {figures}")
    judged = result.get("default_form_rule", {}).get("judged_by", {})
    if "rule" in judged and "line" in judged:
        lines += ["", "nested (every choice made inside each fold; rule: lowest mean held-out "
                  "pull/W), means over data sets:"]
        for role, entry in judged.items():
            label = {"rule": f"the rule ({', '.join(entry['forms'])})",
                     "classical": "classical Wong-Reece", "line": "the line"}[role]
            lines.append("  " + _summary_line(label, entry))
        rule = judged["rule"]
        lines.append(
            f"  On all data sets the rule picks {result['default_form']}. Constants at a bound "
            f"of their plausible range in most folds: "
            f"{', '.join(rule['at_bound_in_most_folds']) or 'none'}.")
        if rule["inferred_datum"]:
            lines.append(f"  Sinkage datum inferred (measured from the wheel at rest) on "
                         f"{', '.join(rule['inferred_datum'])}; without them:")
            for role, entry in judged.items():
                rest = entry["without_inferred_datum"]
                if rest["sinkage_mae"] is not None:
                    lines.append(f"    {role}: sinkage {1e3 * rest['sinkage_mae']:.1f} mm "
                                 f"(z/R {rest['sinkage_mae_per_radius']:.3f}) on "
                                 f"{rest['datasets']} data sets")
    if result.get("paired"):
        lines += ["", f"paired over data sets (rule - baseline per data set, mean ± standard "
                  f"error; a verdict where beyond the two-sided "
                  f"{100 * crosswheel.CONFIDENCE:.0f} % t bound):"]
        lines += ["  " + line for line in crosswheel.format_paired(result["paired"])]
    oracle = result.get("oracle")
    if oracle and oracle.get("mean") is not None:
        se = ("" if oracle["standard_error"] is None
              else f" ± {oracle['standard_error']:.3f}")
        lines += ["", f"oracle (with hindsight the best candidate form on each held-out data "
                  f"set): pull/W {oracle['mean']:+.3f}{se} against the line over "
                  f"{oracle['datasets']} data sets: the most these forms can gain on it with "
                  f"these data."]
    reach = crosswheel.format_reach(result["rows"])
    if reach:
        lines += ["", "reach (each data set's values beyond its training sets' range: a fold "
                  "that predicts it extrapolates; nothing fitted):"]
        lines += ["  " + line for line in reach]
    if result.get("soil_sources"):
        lines += ["", "soil values (where each data set's come from; validation/DATA.md):"]
        lines += [f"  {name}: {source}: {datasets.SOIL_SOURCES[source]}"
                  for name, source in result["soil_sources"].items()]
    if result.get("sinkage_datum"):
        lines += ["", "sinkage datum check (lowest slip against the static sinkage, nothing "
                  "fitted):"]
        lines += ["  " + line for line in crosswheel.format_datum_check(result["sinkage_datum"])]
    return "\n".join(lines)
