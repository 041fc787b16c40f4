"""Model forms judged across wheels and soils: leave-one-dataset-out, with prediction intervals.

A *model form* is the contact form and its extensions (the ``model.*`` rows of the parameter
table, and the slip-sinkage coefficient ``soil.n1``, which no soil test measures): a few global
constants, the same for every wheel and soil. A *data set* brings its wheel and its soil's own
measured values (:mod:`wheelterrain.fit.datasets`); those are never fitted.

Leave-one-dataset-out: for each data set, the form's free constants are fitted (least squares on
drawbar pull [N] and sinkage [mm], each data set weighted equally) on all the *other* data sets,
then the form predicts the held-out one with its own soil values. Only the other data sets'
points reach the fit (tests/test_crosswheel.py corrupts the held-out set and checks that the
constants do not move).

Prediction intervals (90 %), per point, from two sources added in quadrature:

1. the soil values' uncertainty: each value's standard deviation (the data set's ``sd.``
   columns, else :data:`wheelterrain.fit.datasets.DEFAULT_SPREAD`) propagated through the exact
   CasADi Jacobian of the steady state (linear, independent values): 1.645 sigma;
2. the model-form discrepancy learned from the other data sets (:class:`Discrepancy`,
   :func:`held_out_discrepancy`): what the soil spread does not explain of the form's
   *held-out* residuals on the fold's training sets (each predicted with the constants fitted
   on the other training sets, the same leave-one-dataset-out one level down), at their 90 %
   quantile with each data set weighing the same; for the pull as a share of the load (pull
   scales with load), for the sinkage in metres. Learned from the residuals of the fit itself
   (in-sample), it was narrower than the errors on an unseen data set: nested coverage 73 %,
   78 % held out (`wheelterrain validate`).

In the nested protocol the interval also carries the uncertainty of the form choice: it is
widened to the union of the intervals of every candidate the rule cannot tell from its
choice (:func:`within_reach`: a score within one standard error of the chosen one's).

Coverage is the share of held-out points inside their interval; its nominal value is 90 %.

The nested protocol puts two baselines beside the rule under the same protocol (:data:`ROLES`):
classical Wong-Reece (nothing to choose or fit; its discrepancy learned on the other data sets)
and the line. :func:`paired` compares the rule with each, data set by data set (mean difference,
its standard error over data sets, a verdict at the Student-t bound); :func:`oracle` is the most
these forms could gain on the line, picking the best one per data set with hindsight.

Every comparison is made in the terms each point was measured in (:func:`as_measured`): a
sinkage measured from the wheel at rest (the data's ``sinkage_from``) is compared with the
prediction less its sinkage at zero slip, the interval widened by that datum's uncertainty
(:data:`REST_DATUM_SPREAD`); :func:`datum_check` is the check, with no fitted constant, that
flags a data set whose sinkage looks measured so; :func:`increment_errors` judges a sinkage by
what it gains from the data set's lowest slip, where no datum enters.
"""

from __future__ import annotations

import hashlib
import math
import threading
from collections import OrderedDict
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
from scipy.optimize import least_squares

from wheelterrain import model
from wheelterrain.errors import WheelTerrainError
from wheelterrain.fit.datasets import DEFAULT_SPREAD, Dataset, Point
from wheelterrain.model import functions as model_functions
from wheelterrain.parameters import BY_NAME, INDEX, NO_RIPPLE, ParameterSet

Z90 = 1.6448536269514722  # two-sided 90 % of a normal distribution
COVERAGE = 0.9
SCALES = {"drawbar_pull": 1.0, "sinkage": 1e-3}  # residual units: N and mm


@dataclass(frozen=True)
class Form:
    """A model form: ``values`` fixed (the form's switches), ``free`` fitted across data sets
    inside their plausible ranges."""

    name: str
    description: str
    values: dict[str, float]
    free: tuple[str, ...] = ()


_PATCH = {"model.contact_form": 1, "model.exit_ratio": 1.0, "model.shear_kinematics": 1,
          "model.shear_radius_factor": 1.0}
_TIPS = {"model.contact_radius_factor": 1.0, "model.shear_radius_factor": 1.0,
         "model.grouser_thrust": 1}
CROSS = ("soil.n1", "model.shear_length_ratio", "model.interface_ratio", "model.bulldozing")
"""The cross-wheel constants: slip-sinkage coefficient, shear modulus growing with contact
length, rim-soil interface friction, bulldozing share. The small-wheel diameter law
(``model.diameter_exponent``) is not one of them: bounded to its source's sign (a softer soil
under a smaller wheel, exponent >= 0) it fitted to 0 in every fold of the nested protocol, and
its earlier fits (-0.53 to -1) had the opposite sign, absorbing the training data's errors."""
FORMS: tuple[Form, ...] = (
    Form("classical", "Wong-Reece arc, every extension off (the physical baseline)", {}),
    Form("patch", "the paper-faithful patch form of the rashid-patch preset, the paper's eta "
         "read as n1 = 1.15; nothing fitted", {**_PATCH, "soil.n1": 1.15}),
    Form("patch-cross", "the patch form with the cross-wheel constants fitted across data sets",
         _PATCH, CROSS),
    Form("arc-cross", "the arc at the grouser tips with passive grouser thrust, n1 and "
         "interface friction fitted across data sets (the shear-length growth fits to 0 in "
         "the arc; bulldozing is the arc-cross-bulldozing candidate of the nested rule)", _TIPS,
         ("soil.n1", "model.interface_ratio")),
)
BY_FORM = {f.name: f for f in FORMS}


def parameters(form: Form, point: Point, constants: dict[str, float] | None = None
               ) -> ParameterSet:
    """The parameter set of ``point`` (its wheel and soil) in ``form`` with ``constants``."""
    return ParameterSet({**form.values, **NO_RIPPLE, **(constants or {}), **point.values})


PREDICTED = ("drawbar_pull", "sinkage", "torque")


def steady(form: Form, point: Point, constants: dict[str, float] | None = None) -> dict:
    """The whole steady state of ``point`` in ``form`` (:func:`wheelterrain.model.steady_state`)."""
    return model.steady_state(parameters(form, point, constants), point.load, point.slip)


def lateral(form: Form, point: Point, constants: dict[str, float] | None, state: dict) -> float:
    """The lateral force [N] of ``point`` at its slip angle in ``form``, at the sinkage of its
    steady ``state`` (the slip angle does not move the sinkage)."""
    ps = parameters(form, point, constants)
    side = model_functions.build().lateral(state["sinkage"], state["slip"], point.slip_angle,
                                           0.0, ps.vector())
    return float(side[0])


def predict(form: Form, point: Point, constants: dict[str, float] | None = None) -> dict:
    """Steady-state drawbar pull, sinkage and torque of ``point`` in ``form``, as ``point``'s
    measurements report them (:func:`as_measured`)."""
    return as_measured(form, point, constants, steady(form, point, constants))


def as_measured(form: Form, point: Point, constants: dict[str, float] | None,
                state: dict) -> dict[str, float]:
    """The pull, sinkage and torque of the steady ``state`` of ``point`` in the terms its
    measurements are in: a sinkage measured from the wheel at rest (``sinkage_from`` ``rest``,
    :data:`wheelterrain.fit.datasets.SINKAGE_FROM`) is the predicted sinkage less the
    sinkage at zero slip under the same load, :func:`rest_sinkage`."""
    out = {k: state[k] for k in PREDICTED}
    if point.sinkage_from == "rest":
        out["sinkage"] -= rest_sinkage(form, point, constants)
    return out


def rest_sinkage(form: Form, point: Point, constants: dict[str, float] | None = None) -> float:
    """Where a sinkage measured from the wheel at rest starts: the sinkage of ``point``'s wheel
    under its load at zero slip. That is the rolling wheel's; a wheel standing still has a
    symmetric contact and sinks somewhat less, which no form here models, so the conversion
    may take off a little too much. The points of a data set share it (one solve)."""
    return _rest_sinkage(form.name, tuple(sorted(form.values.items())),
                         tuple(sorted((constants or {}).items())),
                         tuple(sorted(point.values.items())), point.load)


@lru_cache(maxsize=4096)
def _rest_sinkage(name: str, values: tuple, constants: tuple, point: tuple, load: float
                  ) -> float:
    ps = ParameterSet({**dict(values), **NO_RIPPLE, **dict(constants), **dict(point)})
    return float(model.steady_state(ps, load, 0.0)["sinkage"])


def _residuals(form: Form, names: Sequence[str], x, sets: Sequence[Dataset]) -> np.ndarray:
    constants = dict(zip(names, map(float, x), strict=True))
    r = []
    for ds in sets:
        weight = 1 / math.sqrt(len(ds.points))
        for pt in ds.points:
            try:
                out = predict(form, pt, constants)
                r += [weight * (out[k] - getattr(pt, k)) / SCALES[k] for k in SCALES]
            except WheelTerrainError:  # not carried at this trial point: a large residual
                r += [weight * 1e3] * len(SCALES)
    return np.array(r)


_FITS: OrderedDict[str, dict[str, float]] = OrderedDict()
_FITS_LOCK = threading.Lock()
FITS_KEPT = 512
"""How many fits :func:`fit_constants` remembers (least recently used dropped first)."""


def _fit_key(form: Form, sets: Sequence[Dataset], starts: int, seed: int) -> str:
    """What a fit depends on, by content: the form, its constants' ranges, the training sets'
    every point (not only their names: the tests corrupt a data set under its own name), the
    starts and the seed (a digest of their exact repr: floats print round-trip)."""
    content = repr((form.name, sorted(form.values.items()), form.free,
                    [BY_NAME[n].plausible for n in form.free], starts, seed,
                    [(ds.name, ds.points) for ds in sets]))
    return hashlib.sha256(content.encode()).hexdigest()


def clear_fits() -> None:
    """Forget every remembered fit (:func:`fit_constants`)."""
    with _FITS_LOCK:
        _FITS.clear()


def fit_constants(form: Form, sets: Sequence[Dataset], starts: int = 3, seed: int = 0
                  ) -> dict[str, float]:
    """``form``'s free constants fitted on ``sets`` (least squares, several starts inside the
    plausible ranges); {} for a form with nothing free.

    A fit is remembered by its content (:func:`_fit_key`): the nested protocol asks for the
    same fit several times (the fit on "all but A and B" is an inner fold of the held-out
    discrepancy in outer folds A and B, and of the rule in both), and `wheelterrain validate`
    spent 61 % of its fitting time on repeats before (benchmarks/crosswheel.py)."""
    names = form.free
    if not names:
        return {}
    key = _fit_key(form, sets, starts, seed)
    with _FITS_LOCK:
        if key in _FITS:
            _FITS.move_to_end(key)
            return dict(_FITS[key])
    fitted = _fit(form, sets, starts, seed)
    with _FITS_LOCK:
        _FITS[key] = dict(fitted)
        while len(_FITS) > FITS_KEPT:
            _FITS.popitem(last=False)
    return fitted


def _fit(form: Form, sets: Sequence[Dataset], starts: int, seed: int) -> dict[str, float]:
    names = form.free
    lo = np.array([BY_NAME[n].plausible[0] for n in names])
    hi = np.array([BY_NAME[n].plausible[1] for n in names])
    rng = np.random.default_rng(seed)
    first = np.clip([ParameterSet(form.values)[n] for n in names], lo, hi)
    candidates = [first] + [lo + rng.uniform(0.1, 0.9, len(names)) * (hi - lo)
                            for _ in range(max(starts, 1) - 1)]
    best = None
    for x0 in candidates:
        sol = least_squares(lambda x: _residuals(form, names, x, sets), x0, bounds=(lo, hi),
                            diff_step=1e-4, max_nfev=60 * len(names))
        if best is None or sol.cost < best.cost:
            best = sol
    return dict(zip(names, map(float, best.x), strict=True))


def soil_sigma(form: Form, point: Point, constants: dict[str, float],
               state: dict | None = None) -> dict[str, float]:
    """One standard deviation of the pull [N] and sinkage [m] of ``point`` from its soil
    values' spreads, through the exact Jacobian of the steady state (``state``: that steady
    state, :func:`steady`, if the caller has it; else it is solved here)."""
    ps = parameters(form, point, constants)
    jac = model.steady_jacobian(ps, point.load, point.slip, state=state)["d_params"]
    if point.sinkage_from == "rest":  # the sinkage as measured: less the sinkage at rest
        jac = jac.copy()
        jac[0] -= model.steady_jacobian(ps, point.load, 0.0)["d_params"][0]
    rows = {"sinkage": 0, "drawbar_pull": 2}  # steady_jacobian rows: sinkage, Fz, DP, T
    var = dict.fromkeys(rows, 0.0)
    for name, (rel, absolute) in DEFAULT_SPREAD.items():
        sd = point.spread.get(name, math.hypot(rel * ps[name], absolute))
        for key, row in rows.items():
            var[key] += (jac[row, INDEX[name]] * sd) ** 2
    return {k: math.sqrt(v) for k, v in var.items()}


REST_DATUM_SPREAD = 0.2
"""Where a sinkage is measured from the wheel at rest, the datum's uncertainty as a share of the
sinkage taken off (the rolling wheel's at zero slip, :func:`rest_sinkage`): a wheel standing
still has a symmetric contact and sinks less than a rolling one, about 0.8 of it in single-wheel
press tests (not a figure any source here gives: this project's assumption, its band 0 to 0.2).
Added to the sinkage's 90 % half-width in quadrature."""


def datum_half_width(form: Form, point: Point, constants: dict[str, float] | None) -> float:
    """The sinkage datum's share of ``point``'s 90 % half-width [m]: REST_DATUM_SPREAD of the
    sinkage at rest where the sinkage is measured from the wheel at rest, else 0."""
    if point.sinkage_from != "rest":
        return 0.0
    return REST_DATUM_SPREAD * abs(rest_sinkage(form, point, constants))


def _quantile(values: Sequence[float], weights: Sequence[float], q: float) -> float:
    """The smallest value v with at least a share ``q`` of the total weight at or below it."""
    order = np.argsort(values)
    cumulative = np.cumsum(np.asarray(weights, dtype=float)[order])
    k = int(np.searchsorted(cumulative, q * cumulative[-1] * (1 - 1e-12)))
    return float(np.asarray(values, dtype=float)[order][min(k, len(order) - 1)])


@dataclass
class Discrepancy:
    """The model-form discrepancy of a fold, learned from predictions of its training points
    (:func:`held_out_discrepancy`: each with constants not fitted on it): per output the
    smallest D such that 90 % of them lie within sqrt((D*scale)**2 + (1.645*sigma_soil)**2)
    of the prediction, i.e. what the soil values' spread does not explain. ``scale`` is the
    load for the pull (D a share of the load) and 1 for the sinkage (D in metres)."""

    pull_share: float
    sinkage: float

    @classmethod
    def learn(cls, form: Form, judged: Sequence[tuple[dict[str, float], Dataset]]
              ) -> Discrepancy:
        """From ``judged``: (constants, data set) pairs, each data set predicted with the
        constants given beside it. Each data set weighs the same in the quantile, whatever its
        number of points."""
        pull, sink, weight = [], [], []
        for constants, ds in judged:
            kept = 0  # the points of ds the form predicts
            for pt in ds.points:
                try:
                    state = steady(form, pt, constants)
                    sigma = soil_sigma(form, pt, constants, state)
                    out = as_measured(form, pt, constants, state)
                except WheelTerrainError:
                    continue
                datum = {"drawbar_pull": 0.0, "sinkage": datum_half_width(form, pt, constants)}
                for key, scale, needed in (("drawbar_pull", pt.load, pull),
                                           ("sinkage", 1.0, sink)):
                    excess = ((out[key] - getattr(pt, key)) ** 2 - (Z90 * sigma[key]) ** 2
                              - datum[key] ** 2)
                    needed.append(math.sqrt(max(excess, 0.0)) / scale)
                kept += 1
            weight += [1 / kept] * kept if kept else []
        if not pull:
            return cls(math.inf, math.inf)
        return cls(_quantile(pull, weight, COVERAGE), _quantile(sink, weight, COVERAGE))

    def half_widths(self, sigma: dict[str, float], load: float, datum: float = 0.0
                    ) -> dict[str, float]:
        """The 90 % half-widths: the discrepancy, the soil's spread and (sinkage from the wheel
        at rest) the datum's uncertainty ``datum`` [m], in quadrature."""
        return {"drawbar_pull": math.hypot(self.pull_share * load, Z90 * sigma["drawbar_pull"]),
                "sinkage": math.hypot(self.sinkage, Z90 * sigma["sinkage"], datum)}


@dataclass
class Fold:
    """One held-out data set: the constants fitted without it, its predictions and intervals."""

    form: str
    dataset: str
    constants: dict[str, float]
    discrepancy: Discrepancy
    points: list[dict] = field(default_factory=list)
    error: str | None = None

    def mae(self, key: str) -> float | None:
        errs = [abs(p[key] - p["measured"][key]) for p in self.points if p.get(key) is not None]
        return float(np.mean(errs)) if errs and len(errs) == len(self.points) else None

    def mae_per_scale(self, key: str) -> float | None:
        """The mean absolute error as a share of the load (pull) or of the wheel's radius
        (sinkage): comparable across wheels and loads."""
        errs = [abs(p[key] - p["measured"][key]) / p["scale"][key] for p in self.points
                if p.get(key) is not None]
        return float(np.mean(errs)) if errs and len(errs) == len(self.points) else None

    def coverage(self, keys: Sequence[str] = ("drawbar_pull", "sinkage")) -> float | None:
        """The share of the points' ``keys`` measurements inside their intervals."""
        inside = [p["inside"][k] for p in self.points for k in keys if p.get("inside")]
        return float(np.mean(inside)) if inside else None

    def at_bound(self) -> list[str]:
        """The fitted constants that ended at an end of their plausible range."""
        out = []
        for name, value in sorted(self.constants.items()):
            lo, hi, _ = BY_NAME[name].plausible
            if min(abs(value - lo), abs(value - hi)) <= 1e-6 * max(hi - lo, 1e-12):
                out.append(name)
        return out

    def lateral_mae(self) -> float | None:
        """The mean absolute error of the lateral force [N] over the points that measured one
        (None where none did, or where a point could not be predicted)."""
        errs = [abs(p["lateral_force"] - p["measured"]["lateral_force"]) for p in self.points
                if "lateral_force" in p["measured"] and p.get("lateral_force") is not None]
        wanted = sum("lateral_force" in p["measured"] for p in self.points)
        return float(np.mean(errs)) if errs and len(errs) == wanted else None

    def as_row(self) -> dict:
        cases = [p["case"] for p in self.points]
        if len(set(cases)) < len(cases):  # a user's data set may repeat a case name
            cases = [f"{case} ({k + 1})" for k, case in enumerate(cases)]
        row = {"model": self.form, "protocol": "leave-one-dataset-out", "dataset": self.dataset,
               "points": len(self.points), "free": sorted(self.constants),
               "drawbar_pull_mae": self.mae("drawbar_pull"), "sinkage_mae": self.mae("sinkage"),
               "drawbar_pull_mae_per_load": self.mae_per_scale("drawbar_pull"),
               "sinkage_mae_per_radius": self.mae_per_scale("sinkage"),
               # a row with no figures (a point the form cannot predict) has no coverage either
               "interval_coverage": None if self.error else self.coverage(),
               "interval_coverage_by_output": {
                   k: None if self.error else self.coverage((k,)) for k in SCALES},
               "in_sample": False, "fitted": self.constants, "at_bound": self.at_bound(),
               "judged_on": cases, "data": self.dataset,
               "errors": {case: {k: p[k] - p["measured"][k] for k in SCALES
                                 if p.get(k) is not None}
                          for case, p in zip(cases, self.points, strict=True)}}
        if any("lateral_force" in p["measured"] for p in self.points):
            row["lateral_force_mae"] = self.lateral_mae()
        if self.error:
            row["error"] = self.error
        return row


def lateral_baseline(pt: Point) -> float:
    """The baseline a predicted lateral force is judged beside: Coulomb friction on the whole
    load, turned by the slip angle, -W*tan(phi)*sin(beta) (against the sideways motion)."""
    return -pt.load * math.tan(pt.values["soil.phi"]) * math.sin(pt.slip_angle)


def lateral_table(user: Sequence[Dataset], rows: Sequence[dict]) -> dict[str, dict]:
    """Per user data set that measured a lateral force: ``points`` (how many), ``baseline``
    (the MAE [N] of :func:`lateral_baseline`) and each form's ``lateral_force_mae`` [N] from
    ``rows`` (:func:`user_rows`')."""
    out = {}
    for ds in user:
        pts = [p for p in ds.points if math.isfinite(p.lateral_force)]
        if not pts:
            continue
        forms = {r["model"]: r.get("lateral_force_mae") for r in rows
                 if r.get("dataset") == ds.name and "lateral_force_mae" in r}
        out[ds.name] = {"points": len(pts), "baseline": float(np.mean(
            [abs(lateral_baseline(p) - p.lateral_force) for p in pts])), "forms": forms}
    return out


def _scale(pt: Point) -> dict[str, float]:
    """What each output's error is a share of: the load for the pull, the radius for the
    sinkage."""
    return {"drawbar_pull": pt.load, "sinkage": pt.values["wheel.radius"]}


def judge(form: Form, constants: dict[str, float], discrepancy: Discrepancy, held: Dataset,
          intervals: bool = True) -> Fold:
    """``form`` with ``constants`` predicting every point of ``held``, with intervals."""
    fold = Fold(form.name, held.name, constants, discrepancy)
    for pt in held.points:
        entry = {"case": pt.case, "load": pt.load, "slip": pt.slip,
                 "measured": {"drawbar_pull": pt.drawbar_pull, "sinkage": pt.sinkage},
                 "sinkage_from": pt.sinkage_from, "scale": _scale(pt)}
        sideways = math.isfinite(pt.lateral_force)  # a side force was measured
        if sideways:
            entry["measured"]["lateral_force"] = pt.lateral_force
        try:
            state = steady(form, pt, constants)
            out = as_measured(form, pt, constants, state)
            if sideways:
                out["lateral_force"] = lateral(form, pt, constants, state)
        except WheelTerrainError as err:
            fold.error = f"{pt.case}: {err}"
            entry.update(drawbar_pull=None, sinkage=None)
            fold.points.append(entry)
            continue
        entry.update(out)
        if intervals:
            half = discrepancy.half_widths(soil_sigma(form, pt, constants, state), pt.load,
                                           datum_half_width(form, pt, constants))
            entry["interval"] = {k: [out[k] - h, out[k] + h] for k, h in half.items()}
            entry["inside"] = {k: bool(abs(out[k] - entry["measured"][k]) <= h)
                               for k, h in half.items()}
        fold.points.append(entry)
    return fold


def held_out(form: Form, sets: Sequence[Dataset], held: Dataset, starts: int = 3,
             intervals: bool = True, inner: Sequence[dict[str, float]] | None = None) -> Fold:
    """``held`` predicted by ``form`` with its constants (and, with ``intervals``, its
    discrepancy, :func:`held_out_discrepancy`) learned on the other data sets of ``sets`` only.
    ``inner``: the inner folds' constants if the caller has them (:func:`choose` does)."""
    train = [ds for ds in sets if ds.name != held.name]
    constants = fit_constants(form, train, starts)
    discrepancy = (held_out_discrepancy(form, train, starts, inner) if intervals
                   else Discrepancy(0.0, 0.0))
    return judge(form, constants, discrepancy, held, intervals)


def held_out_discrepancy(form: Form, train: Sequence[Dataset], starts: int = 3,
                         inner: Sequence[dict[str, float]] | None = None) -> Discrepancy:
    """The discrepancy learned from held-out residuals: each training data set predicted
    with the constants fitted on the *other* training sets (``inner``, in ``train``'s order,
    if already fitted), so that the interval is as wide as the form's errors on a data set it
    has not seen, not as its smaller errors on the data it was fitted to. A form with nothing
    to fit has the same residuals either way. With fewer than two training sets there is no
    held-out residual: the discrepancy is unbounded (an interval that claims nothing)."""
    if not form.free:
        return Discrepancy.learn(form, [({}, ds) for ds in train])
    if len(train) < 2:
        return Discrepancy(math.inf, math.inf)
    if inner is None:
        inner = [fit_constants(form, [o for o in train if o.name != ds.name], starts)
                 for ds in train]
    return Discrepancy.learn(form, list(zip(inner, train, strict=True)))


def leave_one_dataset_out(form: Form, sets: Sequence[Dataset], starts: int = 3,
                          progress: Callable[[str], None] | None = None) -> list[Fold]:
    """One :class:`Fold` per data set: ``form``'s constants fitted on the others only."""
    folds = []
    for held in sets:
        folds.append(held_out(form, sets, held, starts))
        if progress:
            progress(f"{form.name} without {held.name}")
    return folds


DEFAULT_FORM = "patch-cross"
"""The form the selection rule (:func:`choose`, :data:`SELECTION`) picks on all the shipped
data sets (tests/test_crosswheel.py reruns it); judged by the nested protocol's figures
(`wheelterrain validate`, ``default_form_rule``). The form `validate --data` lists first."""


def line_rows(sets: Sequence[Dataset], judged: Sequence[Dataset] | None = None) -> list[dict]:
    """The simple baseline held out data set by data set: pull/load = a + b*i and
    sinkage/R = a + b*i (dimensionless, so that one line spans wheels and loads), least squares
    on the other data sets' points; no physics, no soil values, no interval. A sinkage
    measured from the wheel at rest is b*i (its datum takes a off, as :func:`as_measured`
    takes the sinkage at zero slip off a form's). ``judged``: the data sets to predict (a
    user's), each from ``sets`` less any of its name; default ``sets`` themselves."""
    rows = []
    for held in (sets if judged is None else judged):
        train = [p for ds in sets if ds.name != held.name for p in ds.points]
        slips = np.array([p.slip for p in train])
        from_surface = np.array([p.sinkage_from == "surface" for p in train], dtype=float)
        fits = {"drawbar_pull": np.polyfit(slips, [p.drawbar_pull / p.load for p in train], 1),
                "sinkage": np.linalg.lstsq(
                    np.column_stack([slips, from_surface]),
                    [p.sinkage / p.values["wheel.radius"] for p in train], rcond=None)[0]}

        errors = {p.case: {k: float(_on_line(fits[k], k, p) - getattr(p, k)) for k in fits}
                  for p in held.points}
        mae = {k: float(np.mean([abs(e[k]) for e in errors.values()])) for k in fits}
        share = {k: float(np.mean([abs(errors[p.case][k]) / _scale(p)[k] for p in held.points]))
                 for k in fits}
        rows.append({"model": "line", "protocol": "leave-one-dataset-out",
                     "dataset": held.name, "points": len(held.points), "free": ["a", "b"],
                     "drawbar_pull_mae": mae["drawbar_pull"], "sinkage_mae": mae["sinkage"],
                     "drawbar_pull_mae_per_load": share["drawbar_pull"],
                     "sinkage_mae_per_radius": share["sinkage"],
                     "interval_coverage": None, "in_sample": False,
                     "fitted": {k: [float(x) for x in c] for k, c in fits.items()},
                     "judged_on": [p.case for p in held.points], "data": held.name,
                     "errors": errors})
    return rows


def _on_line(fit, key: str, p: Point) -> float:
    """The line ``fit`` = (b, a) at ``p``, in ``key``'s unit: (a + b*i) times the load or the
    radius; a sinkage from the wheel at rest without the intercept."""
    b, a = fit
    at_rest = key == "sinkage" and p.sinkage_from == "rest"
    return (b * p.slip + (0.0 if at_rest else a)) * _scale(p)[key]


CANDIDATES: tuple[Form, ...] = (
    *FORMS,
    Form("patch-cross-no-bulldozing", "patch-cross without the bulldozing share",
         _PATCH, tuple(n for n in CROSS if n != "model.bulldozing")),
    Form("arc-cross-bulldozing", "arc-cross with the bulldozing share fitted too", _TIPS,
         (*BY_FORM["arc-cross"].free, "model.bulldozing")),
)
"""Every form the selection rule chooses among: the shipped forms and the two mechanism
variants that were compared when they were built (bulldozing on or off)."""
BY_CANDIDATE = {f.name: f for f in CANDIDATES}
NESTED = "nested-leave-one-dataset-out"
SELECTION = "drawbar_pull_mae_per_load"
"""The rule, written once: on the training data sets alone, each candidate is held out data
set by data set (its constants fitted on the others); the candidate with the lowest mean,
over those inner data sets, of its pull MAE as a share of the load wins (ties: the earlier in
CANDIDATES, the one with fewer constants first). A candidate that cannot predict an inner
data set cannot win."""


def _inner_folds(form: Form, sets: Sequence[Dataset], starts: int) -> list[Fold]:
    """``form`` held out on each of ``sets`` in turn (constants fitted on the others)."""
    return [held_out(form, sets, held, starts, intervals=False) for held in sets]


def _score(folds: Sequence[Fold]) -> float:
    """The mean held-out pull MAE per load of ``folds``; inf if any cannot be predicted."""
    shares = [f.mae_per_scale("drawbar_pull") for f in folds]
    return math.inf if any(s is None for s in shares) else float(np.mean(shares))


def choose(sets: Sequence[Dataset], starts: int = 3,
           progress: Callable[[str], None] | None = None,
           folds: dict[str, list[Fold]] | None = None) -> tuple[str, dict[str, float]]:
    """The :data:`SELECTION` rule on ``sets`` only: (the chosen candidate, every candidate's
    score). ``folds``, if given, receives every candidate's inner folds."""
    scores = {}
    for form in CANDIDATES:
        inner = _inner_folds(form, sets, starts)
        scores[form.name] = _score(inner)
        if folds is not None:
            folds[form.name] = inner
        if progress:
            progress(f"rule: {form.name} on {len(sets)} data sets")
    return min(scores, key=lambda name: scores[name]), scores


ROLES = ("rule", "classical", "line")
"""The nested protocol's rows per data set (their ``role``): the form the rule picks, and the
two baselines beside it under the same protocol: classical Wong-Reece (physics, nothing to
choose or fit) and the line (no physics)."""


def nested_rows(sets: Sequence[Dataset], starts: int = 3,
                progress: Callable[[str], None] | None = None) -> list[dict]:
    """Nested leave-one-dataset-out: for each held-out data set, the rule (:func:`choose`)
    picks a form on the other data sets alone, that form's constants are fitted on them, and it
    predicts the held-out one with intervals. Beside it, under the same protocol, the two
    baselines, which have nothing to choose: the line and classical Wong-Reece (its
    discrepancy learned on the other data sets). Each row says its ``role``
    (:data:`ROLES`)."""
    rows = []
    for row in line_rows(sets):
        held = next(ds for ds in sets if ds.name == row["dataset"])
        train = [ds for ds in sets if ds.name != row["dataset"]]
        rows.append({**row, "protocol": NESTED, "role": "line",
                     "trained_on": [ds.name for ds in train],
                     "outside_training": outside_training(held, train)})
        if progress:
            progress(f"line without {row['dataset']}")
    for held in sets:
        train = [ds for ds in sets if ds.name != held.name]
        row = held_out(BY_FORM["classical"], sets, held, starts).as_row()
        row.update(protocol=NESTED, role="classical", trained_on=[ds.name for ds in train],
                   outside_training=outside_training(held, train))
        rows.append(row)
        if progress:
            progress(f"classical without {held.name}")
    for held in sets:
        rows.append(nested_fold(sets, held.name, starts))
        if progress:
            progress(f"rule and {rows[-1]['model']} without {held.name}")
    return described(rows, sets)


def described(rows: list[dict], sets: Sequence[Dataset]) -> list[dict]:
    """``rows`` (each judging one of ``sets``), each given its data set's ``soil_source`` and
    ``sinkage_from`` (one word, or "mixed") and the sinkage judged without a datum
    (:func:`increment_errors`): ``sinkage_increment_mae`` [m] and
    ``sinkage_increment_mae_per_radius``, None where a point has no prediction. In place;
    returned."""
    by_name = {ds.name: ds for ds in sets}
    for row in rows:
        ds = by_name[row["dataset"]]
        datums = {p.sinkage_from for p in ds.points}
        row["soil_source"] = ds.soil_source
        row["sinkage_from"] = datums.pop() if len(datums) == 1 else "mixed"
        steps = increment_errors(row, ds)
        row["sinkage_increment_from"] = steps["from"]
        row["sinkage_increment_mae"] = steps["mae"]
        row["sinkage_increment_mae_per_radius"] = steps["mae_per_radius"]
    return rows


def increment_errors(row: dict, ds: Dataset) -> dict:
    """The sinkage judged by what it gains from ``ds``'s lowest measured slip (no datum
    needed: a datum, measured or inferred, cancels): per point above that slip, the error of
    the predicted increment, ``row``'s sinkage error there less its error at the lowest slip.
    Returns the reference case (``from``), the errors by case [m], their mean absolute value
    [m] and its mean as a share of the wheel's radius; None where there is no point above the
    lowest slip or a point has no prediction."""
    cases = row["judged_on"]
    slips = [p.slip for p in ds.points]
    first = int(np.argmin(slips))
    out = {"from": cases[first], "errors": {}, "mae": None, "mae_per_radius": None}
    errors = [row["errors"].get(case, {}).get("sinkage") for case in cases]
    if errors[first] is None or any(e is None for e in errors):
        return out
    steps = {case: errors[k] - errors[first] for k, case in enumerate(cases)
             if k != first and slips[k] > slips[first]}
    if not steps:
        return out
    radius = {case: p.values["wheel.radius"] for case, p in zip(cases, ds.points, strict=True)}
    out["errors"] = steps
    out["mae"] = float(np.mean([abs(e) for e in steps.values()]))
    out["mae_per_radius"] = float(np.mean([abs(e) / radius[c] for c, e in steps.items()]))
    return out


PAIRED = (("rule", "classical"), ("rule", "line"))
"""The nested protocol's paired comparisons (:func:`paired`): the rule against each baseline."""
PAIRED_METRICS = {"drawbar_pull_mae_per_load": "pull/W",
                  "sinkage_mae_per_radius": "z/R",
                  "sinkage_increment_mae_per_radius": "z/R from the lowest slip"}
"""What :func:`paired` compares, with its short name: per data set, dimensionless."""
CONFIDENCE = 0.95


def paired(rows: Sequence[dict]) -> dict[str, dict]:
    """The rule against each baseline, data set by data set (nested rows, by ``role``): per
    :data:`PAIRED_METRICS` metric the differences rule - baseline per data set, their mean,
    its standard error over data sets (sample standard deviation / sqrt(n)), on how many data
    sets the rule is lower (better), and a verdict: "better" or "worse" where the mean is
    beyond the two-sided :data:`CONFIDENCE` Student-t bound (n - 1 degrees of freedom), else
    "indistinguishable". A metric a data set lacks (None) leaves that set out of it."""
    from scipy.stats import t as student

    by_role: dict[str, dict[str, dict]] = {}
    for r in rows:
        if r.get("protocol") == NESTED and r.get("role") in ROLES:
            by_role.setdefault(r["role"], {})[r["dataset"]] = r
    out = {}
    for mine, other in PAIRED:
        if mine not in by_role or other not in by_role:
            continue
        entry = {}
        for metric in PAIRED_METRICS:
            diffs = {name: r[metric] - by_role[other][name][metric]
                     for name, r in by_role[mine].items()
                     if name in by_role[other] and r.get(metric) is not None
                     and by_role[other][name].get(metric) is not None}
            n = len(diffs)
            values = list(diffs.values())
            mean = float(np.mean(values)) if n else None
            se = float(np.std(values, ddof=1) / math.sqrt(n)) if n > 1 else None
            verdict = "indistinguishable"
            if se is not None:
                bound = float(student.ppf(0.5 + CONFIDENCE / 2, n - 1)) * se
                verdict = ("better" if mean < -bound else "worse" if mean > bound
                           else "indistinguishable")
            entry[metric] = {"mean": mean, "standard_error": se, "datasets": n,
                             "better_on": sum(v < 0 for v in values), "verdict": verdict,
                             "differences": diffs}
        out[f"{mine}-{other}"] = entry
    return out


def format_paired(result: dict[str, dict]) -> list[str]:
    """:func:`paired` as one verdict line per comparison."""
    lines = []
    for name, entry in result.items():
        mine, other = name.split("-", 1)
        parts = []
        for metric, short in PAIRED_METRICS.items():
            e = entry.get(metric)
            if not e or e["mean"] is None:
                continue
            se = "" if e["standard_error"] is None else f" ± {e['standard_error']:.3f}"
            parts.append(f"{short} {e['mean']:+.3f}{se} ({e['verdict']}; lower on "
                         f"{e['better_on']} of {e['datasets']})")
        lines.append(f"{mine} - {other}: " + "; ".join(parts))
    return lines


def oracle(folds: dict[str, list[Fold]], rows: Sequence[dict]) -> dict:
    """The most these forms could gain on the line with these data: an oracle that picks,
    with hindsight, the candidate with the lowest held-out pull/W on each data set
    (``folds``: every candidate's leave-one-dataset-out folds on all the data sets, as
    :func:`choose` returns them), against the nested line rows of ``rows``. Per data set the
    oracle's form and its pull/W less the line's; their mean and standard error."""
    line = {r["dataset"]: r["drawbar_pull_mae_per_load"] for r in rows
            if r.get("protocol") == NESTED and r.get("role") == "line"}
    best: dict[str, tuple[float, str]] = {}
    for name, per_set in folds.items():
        for fold in per_set:
            share = fold.mae_per_scale("drawbar_pull")
            if share is not None and fold.dataset in line and (
                    fold.dataset not in best or share < best[fold.dataset][0]):
                best[fold.dataset] = (share, name)
    diffs = {ds: share - line[ds] for ds, (share, _) in best.items()}
    n = len(diffs)
    return {"metric": "drawbar_pull_mae_per_load", "forms": {ds: f for ds, (_, f) in best.items()},
            "differences": diffs, "datasets": n,
            "mean": float(np.mean(list(diffs.values()))) if n else None,
            "standard_error": (float(np.std(list(diffs.values()), ddof=1) / math.sqrt(n))
                               if n > 1 else None)}


def nested_fold(sets: Sequence[Dataset], held_name: str, starts: int = 3,
                progress: Callable[[str], None] | None = None) -> dict:
    """The nested row of the data set ``held_name``: the rule and the fit on the others."""
    held = next(ds for ds in sets if ds.name == held_name)
    train = [ds for ds in sets if ds.name != held_name]
    inner: dict[str, list[Fold]] = {}
    chosen, scores = choose(train, starts, progress, inner)
    near = within_reach(scores, inner, chosen)
    folds = [held_out(BY_CANDIDATE[name], sets, held, starts,
                      inner=[f.constants for f in inner[name]]) for name in near]
    row = widened(folds[0], folds[1:]).as_row()
    row.update(protocol=NESTED, role="rule", trained_on=[ds.name for ds in train],
               selection={"rule": SELECTION, "scores": scores, "within_reach": near},
               outside_training=outside_training(held, train))
    return row


def within_reach(scores: dict[str, float], folds: dict[str, list[Fold]], chosen: str
                 ) -> list[str]:
    """The candidates the rule cannot tell from its choice, the chosen one first: a score
    within one standard error of the chosen one's (the one-standard-error rule; the error of
    the mean of the chosen candidate's inner per-data-set pull shares)."""
    shares = [f.mae_per_scale("drawbar_pull") for f in folds[chosen]]
    se = (float(np.std(shares, ddof=1)) / math.sqrt(len(shares))
          if len(shares) > 1 and None not in shares else 0.0)
    return [chosen, *(name for name, score in scores.items()
                      if name != chosen and score <= scores[chosen] + se)]


def widened(fold: Fold, others: Sequence[Fold]) -> Fold:
    """``fold`` with each point's interval widened to hold the intervals the ``others`` (the
    same held-out points, predicted by the forms within reach of the choice) give it: their
    union, so that the interval carries the uncertainty of the form choice. The prediction
    stays ``fold``'s; a point another form cannot predict keeps its interval."""
    if not others:
        return fold
    for k, entry in enumerate(fold.points):
        if "interval" not in entry:
            continue
        for other in others:
            theirs = other.points[k].get("interval", {})
            for key, (lo, hi) in theirs.items():
                a, b = entry["interval"][key]
                entry["interval"][key] = [min(a, lo), max(b, hi)]
        entry["inside"] = {key: bool(lo <= entry["measured"][key] <= hi)
                           for key, (lo, hi) in entry["interval"].items()}
    return fold


def lodo_rows(sets: Sequence[Dataset], starts: int = 3,
              progress: Callable[[str], None] | None = None) -> list[dict]:
    """The line and every shipped form held out data set by data set: the rows of
    `wheelterrain validate`."""
    return described([*line_rows(sets), *(fold.as_row() for form in FORMS for fold in
                                          leave_one_dataset_out(form, sets, starts, progress))],
                     sets)


def user_rows(user: Sequence[Dataset], shipped: Sequence[Dataset], starts: int = 3,
              progress: Callable[[str], None] | None = None) -> list[dict]:
    """Every shipped form predicting each of the user's data sets, with intervals:
    `validate --data`'s rows. The constants are fitted on the shipped data sets, leaving out
    any that bears the user's data set's name (a shipped data set given back is judged held
    out, so its row reproduces the leave-one-dataset-out row); never on the user's data."""
    trains = [[s for s in shipped if s.name != ds.name] for ds in user]
    reach = [outside_training(ds, train) for ds, train in zip(user, trains, strict=True)]
    rows = []
    for row, train, beyond in zip(line_rows(shipped, user), trains, reach, strict=True):
        row.update(protocol="user-data", trained_on=[s.name for s in train],
                   outside_training=beyond)
        rows.append(row)
    for form in sorted(FORMS, key=lambda f: f.name != DEFAULT_FORM):
        fits: dict[tuple[str, ...], tuple] = {}
        for ds, train, beyond in zip(user, trains, reach, strict=True):
            key = tuple(s.name for s in train)
            if key not in fits:
                fits[key] = (fit_constants(form, train, starts),
                             held_out_discrepancy(form, train, starts))
            row = judge(form, *fits[key], ds).as_row()
            row.update(protocol="user-data", trained_on=list(key), outside_training=beyond)
            rows.append(row)
        if progress:
            progress(form.name)
    return described(rows, user)


REACH = {"wheel.radius": "m", "wheel.width": "m", "grouser.height": "m", "load": "N",
         "slip": "1", "pressure": "Pa", "soil.n0": "1", "soil.k_phi": "1", "soil.cohesion": "Pa",
         "soil.phi": "rad"}
"""What :func:`outside_training` compares: the wheel, the test, the nominal ground pressure
(load / (width * diameter)) and the soil values of the pressure and the shear."""


def _described(pt: Point) -> dict[str, float]:
    out = {name: pt.values[name] for name in REACH if name in pt.values}
    out.update(load=pt.load, slip=pt.slip,
               pressure=pt.load / (2 * pt.values["wheel.radius"] * pt.values["wheel.width"]))
    return out


def outside_training(held: Dataset, train: Sequence[Dataset]) -> dict[str, dict]:
    """Where ``held`` lies outside every one of its ``train`` sets: per :data:`REACH` name
    with a value beyond the training points' range, ``held``'s range and the training range.
    A fold that predicts such a data set extrapolates; nothing here is fitted, and nothing in a
    fold's choice or interval depends on it (it explains a miss, it does not widen it)."""
    inside = [_described(p) for ds in train for p in ds.points]
    if not inside:
        return {}
    mine = [_described(p) for p in held.points]
    out = {}
    for name in REACH:
        values = [d[name] for d in mine]
        lo, hi = (min(d[name] for d in inside), max(d[name] for d in inside))
        tol = 1e-9 * max(abs(lo), abs(hi), 1e-12)
        if min(values) < lo - tol or max(values) > hi + tol:
            out[name] = {"value": [min(values), max(values)], "trained": [lo, hi]}
    return out


def format_reach(rows: Sequence[dict]) -> list[str]:
    """One text line per data set of ``rows`` (nested or user-data rows, which carry
    ``outside_training``): the values it holds beyond its training sets' range."""
    seen: dict[str, dict] = {}
    for r in rows:
        if "outside_training" in r and r["dataset"] not in seen:
            seen[r["dataset"]] = r["outside_training"]
    lines = []
    for name, beyond in seen.items():
        if not beyond:
            lines.append(f"{name}: inside its training sets' range")
            continue
        parts = []
        for key, entry in beyond.items():
            (a, b), (lo, hi) = entry["value"], entry["trained"]
            value = f"{a:.4g}" if a == b else f"{a:.4g}-{b:.4g}"
            unit = "" if REACH[key] == "1" else f" {REACH[key]}"
            parts.append(f"{key} {value}{unit} (trained on {lo:.4g}-{hi:.4g})")
        lines.append(f"{name}: extrapolates in " + ", ".join(parts))
    return lines


DATUM_WORDS = {"surface": "the surface", "rest": "the wheel at rest"}
DATUM_SUSPECT = 1 / 3
"""A sinkage from the surface below this share of the static sinkage its own soil values give
(:func:`datum_check`) is flagged: on the shipped data sets the four read from the surface
start at 0.85-1.12 of it, KLS-1 at 0.09 and 0.21 (validation/DATA.md, "Sinkage datum")."""


def datum_check(sets: Sequence[Dataset]) -> list[dict]:
    """Per data set, a check of its sinkage datum that uses no fitted constant: its sinkage at
    its lowest slip beside the static sinkage (zero slip, :func:`rest_sinkage`) that its own
    wheel and soil values give in the ``patch`` form (and in the classical arc, for
    comparison). A sinkage read from the surface far below it (``ratio`` <
    :data:`DATUM_SUSPECT`) suggests a rig that zeroes its sensor once the wheel rests on the
    soil (``sinkage_from`` = ``rest``), or soil values much stiffer than the test's soil."""
    rows = []
    for ds in sets:
        first = min(ds.points, key=lambda p: p.slip)
        static = {}
        for name in ("patch", "classical"):
            try:
                static[name] = rest_sinkage(BY_FORM[name], first)
            except WheelTerrainError:
                static[name] = None
        ratio = (first.sinkage / static["patch"] if static["patch"] and
                 math.isfinite(first.sinkage) else None)
        rows.append({"dataset": ds.name, "slip": first.slip, "sinkage": first.sinkage,
                     "sinkage_from": first.sinkage_from, "static_patch": static["patch"],
                     "static_classical": static["classical"], "ratio": ratio,
                     "suspect": bool(first.sinkage_from == "surface" and ratio is not None
                                     and ratio < DATUM_SUSPECT)})
    return rows


def format_datum_check(rows: Sequence[dict]) -> list[str]:
    """:func:`datum_check`'s rows as text lines, a flagged data set saying what to check."""
    lines = []
    for r in rows:
        static = ("-" if r["static_patch"] is None else f"{1e3 * r['static_patch']:.1f} mm")
        ratio = "-" if r["ratio"] is None else f"{r['ratio']:.2f}"
        line = (f"{r['dataset']}: sinkage {1e3 * r['sinkage']:.1f} mm at slip {r['slip']:g} "
                f"(from {DATUM_WORDS[r['sinkage_from']]}), the patch form's static sinkage "
                f"with its "
                f"own soil values {static} (ratio {ratio})")
        if r["suspect"]:
            line += ("; far below it: if the rig zeroed its sinkage once the wheel rested on "
                     "the soil, mark the rows sinkage_from = rest")
        lines.append(line)
    return lines


def verdicts(rows: Sequence[dict]) -> dict[str, list[str]]:
    """Per data set, the forms whose pull MAE is below the line's there (rows of one protocol:
    user data or nested)."""
    line = {r["dataset"]: r["drawbar_pull_mae"] for r in rows if r["model"] == "line"}
    out: dict[str, list[str]] = {name: [] for name in line}
    for r in rows:
        if r["model"] == "line" or r["dataset"] not in line:
            continue
        if r.get("drawbar_pull_mae") is not None and r["drawbar_pull_mae"] < line[r["dataset"]]:
            out[r["dataset"]].append(r["model"])
    return out


def preset_form(ps: ParameterSet) -> Form:
    """A preset's own model form (its model.* switches and constants and its n1), for judging
    it across the shipped data sets with each soil's own values."""
    keep = {k: ps[k] for k in ps if k.startswith("model.") or k == "soil.n1"}
    return Form("preset", "the preset's model form", keep)


def preset_interval(ps: ParameterSet, load: float, slip: float,
                    shipped: Sequence[Dataset]) -> dict[str, list[float]]:
    """A 90 % interval for ``ps``'s steady pull and sinkage at (load, the model's slip): its soil
    values' default spreads through the exact Jacobian, and the discrepancy of its model form
    on the shipped data sets (each with its own soil values; nothing fitted)."""
    form = preset_form(ps)
    discrepancy = Discrepancy.learn(form, [({}, ds) for ds in shipped])
    point = Point("steady", "steady", {k: ps[k] for k in ps}, {}, load, slip, math.nan,
                  math.nan)
    out = model.steady_state(ps, load, slip, "unified")
    sigma = soil_sigma(Form("preset", "", {}), point, {}, out)
    half = discrepancy.half_widths(sigma, load)
    return {k: [out[k] - h, out[k] + h] for k, h in half.items()}
