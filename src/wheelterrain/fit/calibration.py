"""Least-squares calibration of table parameters against the rig's C1-C4 means.

The model side of each case is the quasi-static steady state at the case's slip and load. The
co-simulation's window means equal it to < 1e-3 relative (tests/test_cosim.py), and one
evaluation costs ~1 ms instead of ~2 s. Residuals are drawbar pull in N and sinkage in mm: both
are measured to about that resolution (a fit can also be asked to match one of them alone). The
normal force is the rig's load in every case, so it carries no information about the soil.

The fit uses scipy's trust-region reflective least squares with the exact Jacobian
(:func:`wheelterrain.model.steady_jacobian`, implicit function theorem) inside bounds. Several
starts are drawn over the box. The bounds are the *physically plausible* ranges of
:data:`PLAUSIBLE`, each with its source; they are narrower than the table's validity ranges.
Standard errors come from the Gauss-Newton covariance s^2 (J^T J)^-1, where s^2 = RSS/(m - p)
and m > p. With m <= p there is no residual variance and none are reported. Correlations come
from the same matrix. A parameter at a bound is flagged: the data want it outside the plausible
range.
"""

from __future__ import annotations

import datetime
import math
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

from wheelterrain import __version__, model
from wheelterrain.errors import CalibrationError, WheelTerrainError
from wheelterrain.model.slip import traction_from_paper
from wheelterrain.parameters import INDEX, NAMES, TABLE, ParameterSet

SCALES = {"drawbar_pull": 1.0, "sinkage": 1e-3}  # N, m: one unit of residual each
OUTPUTS = ("drawbar_pull", "sinkage")  # what a fit can be asked to match, in residual order
RESIDUAL_UNITS = {"drawbar_pull": "drawbar pull [N]", "sinkage": "sinkage [mm]"}
OUTPUT_ROW = {"sinkage": 0, "drawbar_pull": 2}  # rows of steady_jacobian's d_params

PLAUSIBLE: dict[str, tuple[float, float, str]] = {
    p.name: p.plausible for p in TABLE if p.plausible is not None}
"""The plausible ranges (min, max, source): a column of the parameter table."""


@dataclass
class Fit:
    names: list[str]
    cases: list[str]
    values: dict[str, float]
    bounds: dict[str, tuple[float, float]]
    at_bound: list[str]
    standard_errors: dict[str, float] | None
    correlation: np.ndarray | None
    residuals: dict[str, dict[str, float]]  # case -> {"drawbar_pull": N, "sinkage": m}
    cost: float
    starts: int
    converged_starts: int
    spread: dict[str, float] = field(default_factory=dict)  # of near-optimal starts
    outputs: tuple[str, ...] = OUTPUTS  # the quantities the residuals compared


def paper_cases() -> list[dict]:
    from wheelterrain.cosim.master import table3

    return table3()["cases"]


def _case_rows(case_names: list[str], data: list[dict] | None = None) -> list[dict]:
    rows = {c["case"]: c for c in (data if data is not None else paper_cases())}
    unknown = [c for c in case_names if c not in rows]
    if unknown:
        raise CalibrationError(f"unknown case(s) {unknown}; valid: {sorted(rows)}")
    return [rows[c] for c in case_names]


def check_free(names: list[str]) -> None:
    unknown = [n for n in names if n not in PLAUSIBLE]
    if unknown:
        raise CalibrationError(f"parameter {unknown[0]} cannot be calibrated; calibratable "
                               f"parameters: {', '.join(PLAUSIBLE)}")
    if not names:
        raise CalibrationError("no parameter to fit; give --params NAME[,NAME...]")
    if len(set(names)) != len(names):
        raise CalibrationError(f"a parameter is listed twice: {names}")


def predictions(ps: ParameterSet, cases: list[dict], load: float = 62.0
                ) -> list[dict[str, float]]:
    return [model.steady_state(ps, load, traction_from_paper(c["slip_paper"])) for c in cases]


def check_outputs(outputs) -> tuple[str, ...]:
    """``outputs`` as a tuple in residual order; an unknown or repeated name is refused."""
    outputs = tuple(outputs)
    unknown = [o for o in outputs if o not in OUTPUTS]
    if unknown or not outputs or len(set(outputs)) != len(outputs):
        raise CalibrationError(f"outputs {list(outputs)} invalid: give one or both of "
                               f"{', '.join(OUTPUTS)}, each once")
    return tuple(o for o in OUTPUTS if o in outputs)


def _residuals_and_jacobian(x, names, base, cases, load, want_jac=True, outputs=OUTPUTS):
    ps = base.with_values(dict(zip(names, x, strict=True)))
    r, rows = [], []
    for c in cases:
        slip = traction_from_paper(c["slip_paper"])
        out = model.steady_state(ps, load, slip)
        if want_jac:
            jac = model.steady_jacobian(ps, load, slip, state=out)["d_params"]
        for key in outputs:
            r.append((out[key] - c["experiment"][key]) / SCALES[key])
            if want_jac:
                rows.append([jac[OUTPUT_ROW[key], INDEX[n]] / SCALES[key] for n in names])
    return np.array(r), (np.array(rows) if want_jac else None)


def fit(base: ParameterSet, names: list[str], case_names: list[str], starts: int = 8,
        seed: int = 0, load: float = 62.0, data: list[dict] | None = None,
        initial: dict[str, float] | None = None,
        bounds: dict[str, tuple[float, float]] | None = None,
        outputs: tuple[str, ...] = OUTPUTS, loss: str = "linear",
        loss_scale: float = 1.0) -> Fit:
    """Fit ``names`` to the drawbar pull and sinkage of ``case_names`` (see module docstring).

    ``data``: cases in the form of wheelterrain/data/paper_table3.json (default: that file).
    ``initial``: the first start (e.g. the optimum of a nested model); the base preset's values
    for names it omits. The other starts are random over the plausible box.
    ``bounds``: replaces the plausible range of the parameters it names (diagnostics: what the
    data would want outside the plausible box; never for a preset).
    ``outputs``: the measured quantities the residuals compare (default both). A fit to the
    drawbar pull alone asks how well the model's pull-slip curve can follow the rig's at all,
    whatever it does to the sinkage. ``Fit.residuals`` holds both outputs either way.
    ``loss``, ``loss_scale``: scipy's robust loss and its scale in residual units (N, mm).
    "soft_l1" with a scale far below the residuals minimises ~ the sum of absolute residuals,
    i.e. the mean absolute error a target is stated in; ``Fit.cost`` is then that loss, and
    standard errors and profiles (which assume squares) are for "linear" fits only."""
    check_free(names)
    outputs = check_outputs(outputs)
    if loss not in ("linear", "soft_l1") or not loss_scale > 0:
        raise CalibrationError(f"loss {loss!r} with scale {loss_scale}: give 'linear' or "
                               "'soft_l1' and a scale > 0")
    cases = _case_rows(case_names, data)
    box = {n: (bounds or {}).get(n, PLAUSIBLE[n][:2]) for n in names}
    lo = np.array([box[n][0] for n in names])
    hi = np.array([box[n][1] for n in names])
    rng = np.random.default_rng(seed)
    first = np.clip(np.array([(initial or {}).get(n, base[n]) for n in names]), lo, hi)
    candidates = [first] + [lo + rng.uniform(0.05, 0.95, len(names)) * (hi - lo)
                            for _ in range(max(starts, 1) - 1)]
    cache: dict[bytes, tuple] = {}

    def both(x):
        key = np.asarray(x).tobytes()
        if key not in cache:
            try:
                cache[key] = _residuals_and_jacobian(x, names, base, cases, load,
                                                     outputs=outputs)
            except WheelTerrainError:  # e.g. the load is beyond capacity at this trial point
                m = len(outputs) * len(cases)
                cache[key] = (np.full(m, 1e3), np.zeros((m, len(names))))
        return cache[key]

    results = []
    for x0 in candidates:
        sol = least_squares(lambda x: both(x)[0], x0, jac=lambda x: both(x)[1],
                            bounds=(lo, hi), x_scale="jac", max_nfev=200, loss=loss,
                            f_scale=loss_scale)
        results.append(sol)
    best, r, J = None, None, None
    for sol in sorted(results, key=lambda s: s.cost):  # the best start that ended feasible
        try:
            r, J = _residuals_and_jacobian(sol.x, names, base, cases, load, outputs=outputs)
        except WheelTerrainError:
            continue
        best = sol
        break
    if best is None:
        raise CalibrationError(
            f"none of the {len(candidates)} starts reached parameters at which the wheel "
            f"carries {load:g} N in every fitted case ({', '.join(case_names)}); give more "
            "starts or a base preset that carries the load")
    near = [s for s in results if s.cost <= best.cost * (1 + 1e-3) + 1e-12]
    spread = {n: float(np.ptp([s.x[k] for s in near])) for k, n in enumerate(names)}
    m, p = len(r), len(names)
    errors, corr = None, None
    if m > p and loss == "linear":
        s2 = float(r @ r) / (m - p)
        try:
            inverse = np.linalg.inv(J.T @ J)
            errors = {n: float(math.sqrt(max(s2 * inverse[k, k], 0.0)))
                      for k, n in enumerate(names)}
            d = np.sqrt(np.clip(np.diag(inverse), 1e-300, None))
            corr = inverse / np.outer(d, d)  # independent of s2
        except np.linalg.LinAlgError:
            errors = None
    tol = 1e-6 * (hi - lo)
    at_bound = [n for k, n in enumerate(names)
                if best.x[k] <= lo[k] + tol[k] or best.x[k] >= hi[k] - tol[k]]
    every = r if outputs == OUTPUTS else _residuals_and_jacobian(
        best.x, names, base, cases, load, want_jac=False)[0]
    residuals = {c["case"]: {key: float(every[len(OUTPUTS) * k + o] * SCALES[key])
                             for o, key in enumerate(OUTPUTS)}
                 for k, c in enumerate(cases)}
    return Fit(list(names), list(case_names), dict(zip(names, map(float, best.x), strict=True)),
               {n: (float(lo[k]), float(hi[k])) for k, n in enumerate(names)}, at_bound,
               errors, corr, residuals, float(best.cost), len(candidates),
               sum(s.success for s in results), spread, outputs)


def errors_on(ps: ParameterSet, case_names: list[str], load: float = 62.0,
              data: list[dict] | None = None) -> dict[str, dict[str, float]]:
    """Model minus experiment (drawbar pull N, sinkage m) on ``case_names`` (rows of ``data``,
    default the paper's Table III)."""
    cases = _case_rows(case_names, data)
    out = predictions(ps, cases, load)
    return {c["case"]: {k: o[k] - c["experiment"][k] for k in ("drawbar_pull", "sinkage")}
            for c, o in zip(cases, out, strict=True)}


def mean_absolute(errors) -> dict[str, float]:
    """Mean absolute error of each of OUTPUTS over ``errors``: a mapping case -> {output: model
    minus data} (as :func:`errors_on` and ``Fit.residuals`` give) or an iterable of such
    dicts. NaN for no errors."""
    rows = list(errors.values()) if isinstance(errors, dict) else list(errors)
    return {k: float(np.mean([abs(e[k]) for e in rows])) if rows else math.nan
            for k in OUTPUTS}


def code_version() -> str:
    try:
        rev = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                             text=True, check=False, cwd=Path(__file__).parent).stdout.strip()
    except OSError:
        rev = ""
    return f"wheelterrain {__version__}" + (f" (git {rev})" if rev else "")


def preset_document(name: str, base_name: str, base: ParameterSet, result: Fit,
                    protocol: str) -> dict:
    """A preset file: the base preset's values, the overrides the fit ran with (``base``'s values
    that differ from the base preset's, e.g. ``--set``), the fitted ones, and the provenance."""
    from wheelterrain import presets

    base_doc = presets.read(base_name)
    stock = presets.load(base_name)
    overrides = {n: base[n] for n in NAMES if base[n] != stock[n] and n not in result.values}
    values = dict(base_doc["values"])
    values.update(overrides)
    values.update(result.values)
    return {
        "name": name,
        "description": f"{base_name} with {', '.join(result.names)} fitted to the rig's "
                       f"{', '.join(result.cases)} ({protocol}).",
        "provenance": {
            "base_preset": base_name,
            "overrides": overrides,
            "data": "wheelterrain/data/paper_table3.json (the paper's Table III means)",
            "protocol": protocol,
            "fitted_on": result.cases,
            "fitted": {n: {"value": result.values[n], "plausible_range": list(result.bounds[n]),
                           "range_source": PLAUSIBLE[n][2],
                           "standard_error": (result.standard_errors or {}).get(n),
                           "at_bound": n in result.at_bound} for n in result.names},
            "residuals": result.residuals,
            "date_of_fit": datetime.date.today().isoformat(),
            "code_version": code_version(),
            "method": "scipy least_squares (trf) with the exact CasADi Jacobian, "
                      f"{result.starts} starts; residuals "
                      + " and ".join(RESIDUAL_UNITS[o] for o in result.outputs),
        },
        "values": values,
    }


def profile(base: ParameterSet, names: list[str], case_names: list[str], best: dict[str, float],
            name: str, points: int = 7, load: float = 62.0, data: list[dict] | None = None,
            outputs: tuple[str, ...] = OUTPUTS) -> list[tuple[float, float]]:
    """Profile of ``name``: (value, sum of squared residuals) with ``name`` fixed at ``points``
    values across its plausible range, plus its best value, and the other parameters refitted
    from ``best``. The interval's resolution is the grid step.

    Identifiability where standard errors do not exist (m <= p): a flat profile means the data
    cannot pin the parameter down."""
    lo, hi, _ = PLAUSIBLE[name]
    others = [n for n in names if n != name]
    out = []
    grid = sorted({*np.linspace(lo, hi, points).tolist(), float(best[name])})
    for value in grid:  # the optimum itself is a grid point: the profile's minimum
        fixed = base.with_values({name: float(value)})
        try:
            if others:
                r = fit(fixed, others, case_names, starts=1, load=load, data=data,
                        initial={n: best[n] for n in others}, outputs=outputs)
                ssr = 2 * r.cost
            else:
                res, _ = _residuals_and_jacobian(np.array([]), [], fixed,
                                                 _case_rows(case_names, data), load,
                                                 want_jac=False,
                                                 outputs=check_outputs(outputs))
                ssr = float(res @ res)
        except WheelTerrainError:  # no feasible fit with this value (load beyond capacity)
            ssr = math.inf
        out.append((float(value), ssr))
    return out


def profile_interval(points: list[tuple[float, float]], best_ssr: float,
                     delta: float = 1.0) -> tuple[float, float]:
    """The span of profiled values whose sum of squares is within ``delta`` (one residual unit
    squared: 1 N or 1 mm) of the best fit."""
    inside = [v for v, ssr in points if ssr <= best_ssr + delta]
    return (min(inside), max(inside)) if inside else (math.nan, math.nan)
