"""The validated Python face of the model: plain numbers in, named results out.

These functions check every input and parameter, call the CasADi Functions of
:mod:`wheelterrain.model.contact`, and turn the solver's diagnostics into clear errors, so a
caller never receives a wrong number silently.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from functools import lru_cache

import casadi as ca
import numpy as np

from wheelterrain.errors import InputError, LoadTooLargeError, SolveError
from wheelterrain.model import contact as _contact
from wheelterrain.model import functions as _functions
from wheelterrain.model import solve as _solve
from wheelterrain.model.slip import (
    DEFAULT_DEFINITION,
    RANGES,
    paper_from_unified,
    to_unified,
)
from wheelterrain.model.solve import RESIDUAL_TOLERANCE, STEP_TOLERANCE  # noqa: F401 (public)
from wheelterrain.parameters import SLIP_ANGLE_LIMIT, TURN_SLIP_LIMIT, ParameterSet


def _params(params: Mapping[str, float] | ParameterSet) -> ParameterSet:
    return params if isinstance(params, ParameterSet) else ParameterSet(params)


def _finite(name: str, value: float, lo: float = -math.inf, hi: float = math.inf) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise InputError(name, value, "is not a number") from None
    valid = (f"valid range {'(' if math.isinf(lo) else '['}{lo:g}, "
             f"{hi:g}{')' if math.isinf(hi) else ']'}")
    if not math.isfinite(number):
        raise InputError(name, value, f"must be finite; {valid}")
    if not lo <= number <= hi:
        raise InputError(name, value, f"is out of range; {valid}")
    return number


def contact_radius(params: ParameterSet) -> float:
    """R_c = R + model.contact_radius_factor * h_g [m]: the circle sinkage is measured to."""
    return params["wheel.radius"] + params["model.contact_radius_factor"] * params["grouser.height"]


def _named(values, names) -> dict[str, float]:
    return {k: float(v) + 0.0 for k, v in zip(names, values, strict=True)}  # no -0.0


def contact_forces(params: Mapping[str, float] | ParameterSet, sinkage: float, slip: float, *,
                   sinkage_rate: float = 0.0, wheel_angle: float = 0.0,
                   slip_definition: str = DEFAULT_DEFINITION) -> dict[str, float]:
    """Forces and contact geometry at a given sinkage (the dynamic-sinkage face).

    sinkage [m] (to the contact circle; <= 0 means no contact), sinkage_rate [m/s], slip (see
    ``slip_definition``), wheel_angle [rad] (sets the grouser-ripple phase). Returns the
    ``contact.CONTACT_OUTPUTS`` in SI units.
    """
    ps = _params(params)
    z = _finite("sinkage", sinkage, hi=contact_radius(ps))
    rate = _finite("sinkage_rate", sinkage_rate)
    angle = _finite("wheel_angle", wheel_angle)
    i = to_unified(slip, slip_definition)
    fns = _functions.build()
    out = fns.contact(z, rate, i, angle, ps.vector())
    return _named(out, _contact.CONTACT_OUTPUTS)


def capacity(params: Mapping[str, float] | ParameterSet, slip: float,
             slip_definition: str = DEFAULT_DEFINITION) -> float:
    """Static normal force [N] with the wheel buried to its contact radius: the largest load."""
    ps = _params(params)
    i = to_unified(slip, slip_definition)
    return float(_functions.build().capacity(i, ps.vector()))


def steady_state(params: Mapping[str, float] | ParameterSet, load: float, slip: float,
                 slip_definition: str = DEFAULT_DEFINITION,
                 slip_angle: float | None = None,
                 turn_slip: float | None = None) -> dict[str, float]:
    """Quasi-static operating point: the sinkage at which the static normal force carries ``load``.

    load [N] >= 0 (0 gives zero sinkage and zero forces). The result is the grouser-period mean
    (ripple-free, zero sinkage rate) and holds every ``solve.STEADY_OUTPUTS`` plus ``load``,
    ``slip`` (the model's sigma: the traction slip driving, the skid braking,
    :mod:`wheelterrain.model.slip`) and ``slip_paper``. ``slip_angle`` [rad], |beta| <=
    SLIP_ANGLE_LIMIT: the angle between the wheel's heading and its velocity (positive: it
    moves toward its left), ``slip`` then the slip along its heading; the result adds
    ``slip_angle`` and ``contact.LATERAL_OUTPUTS`` at the solved sinkage (the longitudinal
    results are those without it, bit for bit: the slip angle does not change the normal
    stress or the longitudinal shear). ``turn_slip`` [rad/m], |phi| <= TURN_SLIP_LIMIT: the
    wheel's yaw rate over its forward speed (positive counter-clockwise seen from above); with
    either given, the other is taken as 0 and the result adds both and LATERAL_OUTPUTS.

    Raises LoadTooLargeError if the wheel cannot carry the load fully buried, SolveError if the
    solve did not reach RESIDUAL_TOLERANCE (never observed; it is checked, not assumed).
    """
    ps = _params(params)
    w = _finite("load", load, lo=0.0)
    i = to_unified(slip, slip_definition)
    beta = None if slip_angle is None else _finite("slip_angle", slip_angle,
                                                   -SLIP_ANGLE_LIMIT, SLIP_ANGLE_LIMIT)
    phi = None if turn_slip is None else _finite("turn_slip", turn_slip, -TURN_SLIP_LIMIT,
                                                 TURN_SLIP_LIMIT)
    out = _named(_functions.build().steady(w, i, ps.vector()), _solve.STEADY_OUTPUTS)
    if w > out["capacity"]:
        raise LoadTooLargeError(w, out["capacity"], contact_radius(ps))
    if not _converged(out["residual"], out["last_step"]):
        raise SolveError(f"sinkage solve did not converge for load {w:g} N, slip {i:g}: "
                         + _unconverged(out["residual"], out["last_step"]))
    out.update(load=w, slip=i, slip_paper=paper_from_unified(i))
    if beta is not None or phi is not None:
        beta, phi = beta or 0.0, phi or 0.0
        side = _functions.build().lateral(out["sinkage"], i, beta, phi, ps.vector())
        out.update(slip_angle=beta, turn_slip=phi, **_named(side, _contact.LATERAL_OUTPUTS))
    return out


_converged = _solve.solve_converged


def _unconverged(residual: float, last_step: float) -> str:
    return (f"relative residual {residual:.3g} > {_solve.RESIDUAL_TOLERANCE:g} and last step "
            f"{last_step:.3g} > {_solve.STEP_TOLERANCE:g} in log(entry angle)")


def steady_jacobian(params: Mapping[str, float] | ParameterSet, load: float, slip: float,
                    state: dict[str, float] | None = None) -> dict[str, np.ndarray]:
    """Exact derivatives of (sinkage, normal_force, drawbar_pull, torque) at the steady state.

    ``d_inputs`` is 4x2 (by load [N], the model's slip sigma), ``d_params`` 4 x len(TABLE)
    in table order.
    ``state``: the :func:`steady_state` result at the same point, if the caller has it (saves
    solving again).
    """
    ps = _params(params)
    state = state if state is not None else steady_state(ps, load, slip)
    jac = _functions.build().steady_jacobian(state["load"], state["slip"], ps.vector(),
                                           state["sinkage"])
    return {"d_inputs": np.array(jac[0]), "d_params": np.array(jac[1])}


def _unified_array(name: str, values, definition: str) -> np.ndarray:
    """The model's slips sigma from an array in any definition (as :func:`to_unified`)."""
    to_unified(0.0, definition)  # checks the definition's name
    values = _as_floats(name, values)
    lo, hi = RANGES[definition]
    ok = np.isfinite(values) & (values >= lo) & (values <= hi)
    if not np.all(ok):  # the scalar check words the message (name, range)
        to_unified(float(values.flat[np.flatnonzero(~ok)[0]]), definition)
    return np.vectorize(lambda v: to_unified(v, definition), otypes=[float])(values)


def steady_states(params: Mapping[str, float] | ParameterSet, load, slip, *,
                  slip_definition: str = DEFAULT_DEFINITION, guess=None,
                  over_capacity: str = "raise") -> dict[str, np.ndarray]:
    """:func:`steady_state` at many points at once: ``load`` and ``slip`` are arrays of one
    length (or scalars, shared). Returns one array per ``solve.STEADY_OUTPUTS`` key plus
    ``load``, ``slip`` (the model's sigma) and ``slip_paper``.

    Runs the lane-parallel C of :mod:`wheelterrain.model.lanes` (compiled on first use, about
    80 s, then cached; ~12 us a point cold on one core), or CasADi's virtual machine where it
    cannot be compiled (same numbers to rounding, ~40x slower). ``guess``: sinkage [m] per
    point to start Newton from (a neighbouring solution in a sweep; NaN for none); a warm start
    that does not converge is solved again cold. With a guess the solve returns the root Newton
    reaches from it; cold, the shallowest (they are the same wherever Fz_static grows with
    sinkage, as the tests find for driving wheels on every preset).

    ``over_capacity``: "raise" (LoadTooLargeError for the first load the wheel cannot carry
    fully buried) or "nan" (those points' outputs are NaN; ``capacity`` is still given).
    Raises SolveError if a point did not converge (never observed; it is checked).
    """
    ps = _params(params)
    if over_capacity not in ("raise", "nan"):
        raise InputError("over_capacity", over_capacity, "must be 'raise' or 'nan'")
    load = _finite_array("load", load, lo=0.0)
    i = _unified_array("slip", slip, slip_definition)
    guess = _as_floats("guess", np.nan if guess is None else guess)  # NaN, <= 0: none
    load, i, guess = _one_length(load=load, slip=i, guess=guess)
    return _solve_points(ps, load, i, guess, (np.nan, np.nan), over_capacity)


_STEADY_ROW = {name: k for k, name in enumerate(_solve.STEADY_OUTPUTS)}


def _solve_points(ps: ParameterSet, load: np.ndarray, i: np.ndarray, guess, ends,
                  over_capacity: str) -> dict[str, np.ndarray]:
    """:func:`steady_states` after its checks; ``ends``: the scan's end values per point
    (:func:`_scan_ends`) or NaN."""
    n = load.size
    guess_in = np.broadcast_to(np.asarray(guess, dtype=float), (n,))
    solve = _steady_many()
    p = ps.vector()
    out = solve(load, i, guess_in, *ends, p)
    row = _STEADY_ROW
    carried = load <= out[row["capacity"]]

    def converged(o):
        return _converged(o[row["residual"]], o[row["last_step"]])

    retry = np.flatnonzero(np.isfinite(guess_in) & carried & ~converged(out))
    if retry.size:  # a warm start that failed: the cold solve
        out[:, retry] = solve(load[retry], i[retry], np.nan, np.nan, np.nan, p)
    if not np.all(carried):
        first = np.flatnonzero(~carried)[0]
        if over_capacity == "raise":
            raise LoadTooLargeError(float(load[first]), float(out[row["capacity"], first]),
                                    contact_radius(ps))
        keep = out[row["capacity"]].copy()
        out[:, ~carried] = np.nan
        out[row["capacity"]] = keep
    bad = np.flatnonzero(carried & ~converged(out))
    if bad.size:
        k = bad[0]
        raise SolveError(f"sinkage solve did not converge at {bad.size} of {n} points, first "
                         f"at load {load[k]:g} N, slip {i[k]:g}: "
                         + _unconverged(out[row["residual"], k], out[row["last_step"], k]))
    np.add(out, 0.0, out=out)  # no -0.0
    result = {name: out[k] for name, k in row.items()}
    result.update(load=load, slip=i,
                  slip_paper=np.vectorize(paper_from_unified, otypes=[float])(i))
    return result


def _as_floats(name: str, values) -> np.ndarray:
    """A scalar or 1-D array of numbers, or an InputError naming the input."""
    try:
        array = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise InputError(name, values, "is not a number or an array of numbers") from None
    if array.ndim > 1:
        raise InputError(name, f"array of shape {array.shape}",
                         "must be a number or a 1-D array") from None
    return array


def _one_length(**columns: np.ndarray) -> list[np.ndarray]:
    """The columns as contiguous arrays of one length: a number (or one value) is shared by
    every point; arrays of different lengths are an InputError naming them."""
    lengths = {name: a.size for name, a in columns.items() if a.size != 1}
    if len(set(lengths.values())) > 1:
        shown = ", ".join(f"{name} {size}" for name, size in lengths.items())
        raise InputError(", ".join(lengths), f"lengths {shown}",
                         "must be numbers or arrays of one length")
    n = next(iter(lengths.values()), 1)
    return [np.ascontiguousarray(np.broadcast_to(a.reshape(-1), (n,))) for a in
            columns.values()]


def _finite_array(name: str, values, lo: float = -math.inf, hi: float = math.inf) -> np.ndarray:
    """As :func:`_finite`, for an array: the first offending value is refused by name."""
    values = _as_floats(name, values)
    ok = np.isfinite(values) & (values >= lo) & (values <= hi)
    if not np.all(ok):
        _finite(name, float(values.flat[np.flatnonzero(~ok)[0]]), lo, hi)
    return values


def contact_forces_many(params: Mapping[str, float] | ParameterSet, sinkage, slip, *,
                        sinkage_rate=0.0, wheel_angle=0.0,
                        slip_definition: str = DEFAULT_DEFINITION) -> dict[str, np.ndarray]:
    """:func:`contact_forces` at many points at once (arrays of one length, or scalars shared):
    one array per ``contact.CONTACT_OUTPUTS`` key. Lane-parallel C (:mod:`.lanes`, compiled on
    first use, about 20 s, then cached; ~0.7 us a point on one core), or CasADi's virtual
    machine without a C compiler (same numbers to rounding)."""
    ps = _params(params)
    z = _finite_array("sinkage", sinkage, hi=contact_radius(ps))
    rate = _finite_array("sinkage_rate", sinkage_rate)
    angle = _finite_array("wheel_angle", wheel_angle)
    i = _unified_array("slip", slip, slip_definition)
    columns = _one_length(sinkage=z, sinkage_rate=rate, slip=i, wheel_angle=angle)
    out = _contact_many()(*columns, ps.vector())
    return {name: out[k] + 0.0 for k, name in enumerate(_contact.CONTACT_OUTPUTS)}


def _falling_back(reason: Exception) -> None:
    warnings.warn(f"the lane-parallel C is not available ({reason}); evaluating on CasADi's "
                  "virtual machine instead (the same numbers, about 30x slower)", stacklevel=4)


@lru_cache(maxsize=1)
def _contact_many():
    """The lane-parallel contact, or (no C compiler) CasADi's map of build().contact."""
    from wheelterrain.model import lanes

    return _lanes_or_vm(lanes.compiled_contact, _functions.build().contact, used=(0, 1, 2, 3))


def _lanes_or_vm(compiled, function: ca.Function, used: tuple[int, ...]):
    """``compiled()`` (a lanes.LaneFunction), or where it cannot be compiled, with a warning,
    the same call on CasADi's map of ``function``: per-point columns and ``p`` in, one row per
    output out; ``used`` picks the columns ``function`` takes (the others, a warm start's
    guess and scan ends, only speed the C)."""
    from wheelterrain.compiled import CompileError

    try:
        return compiled()
    except CompileError as err:
        _falling_back(err)

    def vm(*args):
        *columns, p = args
        n = max(np.size(c) for c in columns)
        taken = [np.broadcast_to(np.asarray(columns[k], dtype=float), (n,)) for k in used]
        return np.array(function.map(n)(*taken, np.tile(p[:, None], (1, n)))).reshape(
            function.n_out(), n)

    return vm


def steady_map(params: Mapping[str, float] | ParameterSet, loads, slips, *,
               slip_definition: str = DEFAULT_DEFINITION) -> dict[str, np.ndarray]:
    """Steady states on the grid loads x slips (two 1-D arrays): each output an array of shape
    (len(loads), len(slips)); NaN where the wheel cannot carry the load (``capacity`` says
    what it can carry there).

    A continuation along the loads: the two smallest loads are solved cold, each next one
    warm-started from the sinkage extrapolated linearly from the two before it, for all slips
    at once (:func:`steady_states` with ``guess``)."""
    ps = _params(params)
    loads = _finite_array("loads", loads, lo=0.0).reshape(-1)
    slips = _unified_array("slips", slips, slip_definition).reshape(-1)
    for name, axis in (("loads", loads), ("slips", slips)):
        if axis.size == 0:
            raise InputError(name, [], "must hold at least one value")
    ends = _scan_ends(slips, ps.vector())  # depend on slip and p only: once for every row
    order = np.argsort(loads, kind="stable")
    rows: list[dict[str, np.ndarray]] = []
    guess = np.nan
    for k, at in enumerate(order):
        rows.append(_solve_points(ps, np.full(slips.size, loads[at]), slips, guess, ends,
                                  "nan"))
        if k >= 1:
            w0, w1 = loads[order[k - 1]], loads[at]
            z0, z1 = rows[-2]["sinkage"], rows[-1]["sinkage"]
            w2 = loads[order[k + 1]] if k + 1 < len(order) else w1
            slope = (z1 - z0) / (w1 - w0) if w1 > w0 else 0.0 * z1
            guess = z1 + slope * (w2 - w1)  # NaN where either was not carried: cold
    result = {name: np.empty((loads.size, slips.size)) for name in rows[0]}
    for k, at in enumerate(order):
        for name, values in rows[k].items():
            result[name][at] = values
    return result


def _scan_ends(slips: np.ndarray, p: np.ndarray) -> tuple:
    """Fz_static at the solve's scan ends for each slip (NaN on CasADi's VM, which does not
    use them)."""
    from wheelterrain.model import lanes

    if not isinstance(_steady_many(), lanes.LaneFunction):
        return np.nan, np.nan
    ends = lanes.compiled_scan_ends()(slips, p)
    return ends[0], ends[1]


@lru_cache(maxsize=1)
def _steady_many():
    """The lane-parallel steady state, or (no C compiler) CasADi's map of build().steady_from
    (the same warm start) with the same call (load, slip, guess, first, last, p) ->
    STEADY_OUTPUTS rows; the scan's ends are then unused."""
    from wheelterrain.model import lanes

    steady_from = _functions.build().steady_from
    load, slip, guess = ca.MX.sym("load"), ca.MX.sym("slip"), ca.MX.sym("guess")
    p = ca.MX.sym("p", steady_from.size1_in(2))
    in_lane_order = ca.Function("steady_guess", [load, slip, guess, p],
                                steady_from(load, slip, p, guess))
    return _lanes_or_vm(lanes.compiled_solve, in_lane_order, used=(0, 1, 2))
