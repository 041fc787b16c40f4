"""The quasi-static sinkage solve: the entry angle at which the ripple-free normal force of the
contact (:mod:`wheelterrain.model.contact`) carries the load, as CasADi expressions.

A bracketing scan of Fz_static over log-spaced entry angles (pruned by the contact's static
bound), a regula-falsi and inverse-quadratic start, then safeguarded Newton in log(theta_f),
unrolled and switched off once converged; and the acceptance test every caller applies
(:func:`solve_converged`). :func:`wheelterrain.model.functions.build` makes Functions of it;
:mod:`wheelterrain.model.lanes` generates C of the same pieces (:func:`solve_lane_kernels`).
"""

from __future__ import annotations

import math
from functools import lru_cache

import casadi as ca
import numpy as np

from wheelterrain.model.contact import (
    CONTACT_OUTPUTS,
    DEFAULT_NODES,
    FORMS,
    FULL_BURIAL,
    all_of,
    entry_angle,
    form_switch,
    radii,
    static_bound,
)
from wheelterrain.model.soil import Params, rut_surface
from wheelterrain.parameters import NAMES

STEADY_INPUTS = ("load", "slip", "p")
STEADY_OUTPUTS = ("sinkage", *CONTACT_OUTPUTS, "residual", "last_step", "capacity")
"""The steady state's inputs and outputs: the solved sinkage, the ripple-free contact there,
and the solve's residual, last Newton step and the capacity (the normal force fully buried)."""

NEWTON_ITERATIONS = 24  # at most; ~4 when driving (then it stops); a braking corner where
# Fz_static crosses 0 just below a tiny load (0.1 N against ~500 N/rad) needs 19
SCAN_POINTS = 12  # bracketing scan of the sinkage solve, log-spaced in the entry angle
SCAN_MIN = 1e-4  # rad: smallest scanned entry angle (below it the power-law regime holds)
THETA_MIN = 1e-12  # rad: lower end of the sinkage-solve bracket (z ~ 1e-26 m)


@lru_cache(maxsize=4)
def solve_lane_kernels(nodes: tuple[int, int] = DEFAULT_NODES) -> dict:
    """The sinkage solve (:func:`sinkage_solve_expr`) in pieces, as plain SX Functions for
    code generators that solve many points at once (:mod:`wheelterrain.model.lanes`); the
    generated driver calls them in the order ``build().sinkage_solve`` does.

    - ``case(theta_f, slip, p)``: the switch's case; ``fz[c](theta_f, slip, p)``: Fz_static
      with case c's kernel; ``fz_d[c]``: Fz_static and its derivative by theta_f;
      ``static[c]``: every CONTACT_OUTPUT, ripple-free (the steady state's contact).
    - ``scan_plan(load, slip, p)``, ``scan_low(load, values, plan)``: the pruned scan's decisions
      (:func:`scan_values`).
    - ``start(load, values)``: (state, capacity, w_safe) from Fz_static at :func:`scan_angles`;
      ``start_warm(load, f_first, f_last, guess, p)``: the same from the scan's two ends and a
      sinkage guess [m] (:func:`solve_start_warm`).
    - ``refine(state, f, w_safe)``: a cold start's second iterate from Fz_static at its first
      (:func:`refine`).
    - ``newton_angle(state)``: the entry angle of the state's iterate;
      ``newton_update(state, f, df, w_safe)``: the next state (state[STATE_DONE]: converged).
    - ``solve_angle(load, state)``, then ``finish(load, state, f, p)``: sinkage, residual,
      last_step."""
    pp = ca.SX.sym("p", len(NAMES))
    P = Params(pp)
    case, fz, fz_d, static = _static_kernels(nodes)
    load, values = ca.SX.sym("load"), ca.SX.sym("values", len(scan_angles()))
    f_first, f_last, guess = ca.SX.sym("f_first"), ca.SX.sym("f_last"), ca.SX.sym("guess")
    state, f, df, w_safe = (ca.SX.sym("state", STATE_SIZE), ca.SX.sym("f"), ca.SX.sym("df"),
                            ca.SX.sym("w_safe"))
    return {
        "case": case, "fz": fz, "fz_d": fz_d, "static": static, **_scan_kernels(),
        "start": ca.Function("solve_start", [load, values],
                             list(solve_start(load, ca.vertsplit(values))), {"cse": True}),
        "start_warm": ca.Function("solve_start_warm", [load, f_first, f_last, guess, pp],
                                  list(solve_start_warm(load, f_first, f_last, guess, P)),
                                  {"cse": True}),
        "refine": ca.Function("solve_refine", [state, f, w_safe], [refine(state, f, w_safe)],
                              {"cse": True}),
        "newton_angle": ca.Function("newton_angle", [state], [ca.exp(state[0])]),
        "newton_update": ca.Function("newton_update", [state, f, df, w_safe],
                                     [_newton_update(state, f, df, w_safe)], {"cse": True}),
        "solve_angle": ca.Function("solve_angle", [load, state], [_solve_angle(load, state)]),
        "finish": ca.Function("solve_finish", [load, state, f, pp],
                              list(solve_finish(load, state, f, P)), {"cse": True}),
    }


def sinkage_solve_expr(load, slip, P: Params, nodes: tuple[int, int], guess=None):
    """Quasi-static sinkage: the shallowest entry angle at which Fz_static equals the load
    (from a sinkage ``guess`` [m]: the root Newton reaches from it, :func:`solve_start_warm`).

    1. Scan Fz_static at SCAN_POINTS log-spaced entry angles up to full burial (pi/2) and keep the
       first interval in which it reaches the load: the equilibrium a wheel sinking from the
       surface meets first. (Fz_static(z) is monotone for driving wheels; in extreme braking
       corners the negative shear pulls the wheel down, it is not, and a load can have several
       equilibria.) Angles where :func:`static_bound` is below the load are not evaluated
       (:func:`scan_values`): the same bracket from 2-3 contact evaluations instead of 13.
       The bracket's regula falsi point, evaluated without derivative, then gives by inverse
       quadratic interpolation a second iterate close to the root (:func:`refine`).
    2. Safeguarded Newton in y = log(theta_f) on that bracket, on asinh(Fz/W) - asinh(1): monotone
       in Fz, ~log(Fz/W) and so nearly linear in y where Fz >> W (Fz grows like
       theta_f**(2n+1)), and of moderate size where braking shear makes Fz negative (a plain
       (Fz - W)/W there is huge next to the log branch and stalls regula falsi); a step that
       leaves the bracket is replaced by Illinois regula falsi on the bracket (whose end
       residuals are tracked), bisection if that fails. Unrolled to NEWTON_ITERATIONS
       iterations, each a switch that is the identity once a Newton step was below NEWTON_STOP
       or left a predicted residual below PREDICTED_STOP (:func:`_newton_update`): a pure
       CasADi expression that stops when it has converged, two Newton steps on a driving
       wheel.

    Returns ``(state, theta, capacity)``: the final Newton state, the entry angle and the
    capacity (Fz_static fully buried). :func:`solve_finish`, given Fz_static at ``theta``,
    makes of them the sinkage, the relative residual of the final iterate and the size of the
    last step in log(theta_f). Callers must check load <= capacity and convergence: a small
    residual, or a last step at rounding level (the root pinned in theta_f when the load is a
    vanishing fraction of force terms that cancel) (``model.steady_state`` does); convergence
    is a checked output, not an assumption.
    """
    _, fz_only, _ = static_functions(nodes)
    scan = scan_angles()
    if guess is None:
        state, capacity, w_safe = solve_start(load, scan_values(load, slip, P, nodes))
        state = refine(state, fz_only(ca.exp(state[0]), slip, P.p), w_safe)
    else:
        state, capacity, w_safe = solve_start_warm(load, fz_only(scan[0], slip, P.p),
                                                    fz_only(scan[-1], slip, P.p), guess, P)
    iteration = _newton_iteration(nodes)
    for _ in range(NEWTON_ITERATIONS):
        state = iteration(state[STATE_DONE], state, slip, P.p, w_safe)
    return state, _solve_angle(load, state), capacity


def scan_angles() -> np.ndarray:
    """The entry angles [rad] of the sinkage solve's bracketing scan: THETA_MIN, then
    SCAN_POINTS log-spaced from SCAN_MIN to full burial."""
    return np.concatenate([[THETA_MIN], np.geomspace(SCAN_MIN, FULL_BURIAL, SCAN_POINTS)])


MISSING = math.nan  # a scan value the pruned scan did not evaluate (not a crossing)


def scan_values(load, slip, P: Params, nodes: tuple[int, int]) -> list:
    """Fz_static at :func:`scan_angles` as far as :func:`solve_start` uses it, evaluating
    only what it can use (each a switch: a skipped angle costs no contact evaluation):

    1. fully buried (the capacity), and every inner angle where :func:`static_bound` does not
       rule out that Fz_static reaches the load (``scan_plan``);
    2. the low end of the bracket that leaves, if it was skipped (``scan_low``).

    Every other entry is MISSING: an angle where Fz_static < load, which is all solve_start
    needs of it. So the bracket, its end values and hence the solve are those of the full
    scan, bit for bit (tests check it); the deep sinkage of a heavy load is bracketed with
    2 contact evaluations instead of 13."""
    kernels = _scan_kernels()
    fz_only = static_functions(nodes)[1]
    missing = ca.Function("scan_missing", [ca.MX.sym("theta_f"), ca.MX.sym("slip"),
                                           ca.MX.sym("p", len(NAMES))], [MISSING])
    maybe = ca.Function.if_else("scan_value", fz_only, missing)
    scan = scan_angles()
    plan = ca.vertsplit(kernels["scan_plan"](load, slip, P.p))
    values = [ca.MX(MISSING)] + [maybe(plan[k - 1], scan[k], slip, P.p)
                                 for k in range(1, len(scan) - 1)] + [fz_only(scan[-1], slip,
                                                                               P.p)]
    index, theta, absent = kernels["scan_low"](load, ca.vertcat(*values), ca.vertcat(*plan))
    low = ca.Function.if_else("scan_low_value", fz_only, missing)(absent, theta, slip, P.p)
    # the low end is below the last angle: the capacity stays a function of slip and p only
    return [ca.if_else(ca.logic_and(absent, index == k), low, v)
            for k, v in enumerate(values[:-1])] + values[-1:]


@lru_cache(maxsize=1)
def _scan_kernels() -> dict:
    """The pruned scan's decisions as SX Functions (:func:`scan_values`; the lane solve
    calls the same): ``scan_plan(load, slip, p)``, 1 at each inner scan angle (1 .. last - 1)
    to evaluate; ``scan_low(load, values, plan)``, the index of the bracket's low end, its
    angle and 1 if its value is MISSING (the first angle, or an inner one the plan skipped)."""
    load, slip, pp = ca.SX.sym("load"), ca.SX.sym("slip"), ca.SX.sym("p", len(NAMES))
    scan = scan_angles()
    P = Params(pp)
    # an angle can be the crossing only where the bound reaches the load (or is NaN)
    maybe = [ca.logic_not(static_bound(ca.SX(t), slip, P) < load) for t in scan[1:-1]]
    plan = ca.Function("scan_plan", [load, slip, pp], [ca.vertcat(*maybe)], {"cse": True})
    values, kept = ca.SX.sym("values", len(scan)), ca.SX.sym("plan", len(scan) - 2)
    index = ca.SX(0)  # no crossing: the bracket is the whole scan, its low end THETA_MIN
    for k in range(len(scan) - 1, 0, -1):  # the last assignment is the shallowest crossing
        index = ca.if_else(values[k] >= load, k - 1, index)
    theta, absent = ca.SX(scan[0]), ca.SX(1)
    for k in range(1, len(scan) - 1):
        theta = ca.if_else(index == k, scan[k], theta)
        absent = ca.if_else(index == k, kept[k - 1] == 0, absent)
    low = ca.Function("scan_low", [load, values, kept], [index, theta, absent], {"cse": True})
    return {"scan_plan": plan, "scan_low": low}


def solve_start(load, values):
    """The bracket of the sinkage solve from Fz_static at :func:`scan_angles` (``values``):
    ``(state, capacity, w_safe)``, the Newton state of :func:`_newton_update` at its first
    iterate."""
    w_safe = _safe_load(load)
    scan = scan_angles()
    capacity = values[-1]
    lo, hi = _scan_range(load)
    f_lo, f_hi = values[0], values[-1]
    for k in range(len(scan) - 1, 0, -1):  # the last assignment is the shallowest crossing
        reached = values[k] >= load
        hi, f_hi = (ca.if_else(reached, a, b) for a, b in
                    ((math.log(scan[k]), hi), (values[k], f_hi)))
        lo, f_lo = (ca.if_else(reached, a, b) for a, b in
                    ((math.log(scan[k - 1]), lo), (values[k - 1], f_lo)))
    h_lo, h_hi = _residual(f_lo, w_safe), _residual(f_hi, w_safe)
    y = _fallback(lo, hi, h_lo, h_hi)
    return _first_state(y, lo, hi, h_lo, h_hi), capacity, w_safe


def _safe_load(load):
    """The load as a divisor (the relative residual's scale)."""
    return ca.fmax(load, 1e-300)


def _scan_range(load):
    """log of the scan's first and last angle: the widest bracket (constants of load's type)."""
    const, scan = type(load), scan_angles()
    return const(math.log(scan[0])), const(math.log(scan[-1]))


STATE_SIZE = 9  # the Newton state of the sinkage solve, :func:`_first_state`
STATE_DONE = 7  # its converged flag


def _first_state(y, lo, hi, h_lo, h_hi):
    """The Newton state (STATE_SIZE) at the first iterate ``y``: y, the bracket (lo, hi, h_lo,
    h_hi), which end the previous iterate replaced (1 lo, 0 hi, -1 none), the last step,
    converged, and whether the last step was Newton's (1) or the bracket's (0)."""
    return ca.vertcat(y, lo, hi, h_lo, h_hi, -1, math.inf, 0, 0)


def solve_start_warm(load, f_first, f_last, guess, P: Params):
    """The warm start: the bracket is the whole scan range, its ends' residuals from Fz_static
    there (``f_first`` at THETA_MIN, ``f_last`` fully buried: the capacity), and the first
    iterate the entry angle of the sinkage ``guess`` [m] when that lies inside the bracket,
    else regula falsi on it. ``(state, capacity, w_safe)`` as :func:`solve_start`."""
    w_safe = _safe_load(load)
    lo, hi = _scan_range(load)
    h_lo, h_hi = _residual(f_first, w_safe), _residual(f_last, w_safe)
    y = ca.log(ca.fmax(entry_angle(guess - rut_surface(P), P), THETA_MIN))
    y = ca.if_else(ca.logic_and(y > lo, y < hi), y, _fallback(lo, hi, h_lo, h_hi))
    return _first_state(y, lo, hi, h_lo, h_hi), f_last, w_safe


def _solve_angle(load, state):
    """The entry angle the solve ends at (0 for no load)."""
    return ca.if_else(load > 0, ca.exp(state[0]), 0)


def solve_finish(load, state, f, P: Params):
    """Sinkage, relative residual and last step at the final angle, where Fz_static is ``f``."""
    Rc, _, _ = radii(P)
    theta = _solve_angle(load, state)
    # R_c*(1 - cos(theta)) without cancellation, below the surface the contact begins at
    sinkage = rut_surface(P) + 2 * Rc * ca.sin(theta / 2) ** 2
    w_safe = _safe_load(load)
    residual = ca.if_else(load > 0, (f - load) / w_safe, 0)
    last_step = ca.if_else(load > 0, state[6], 0)
    return sinkage, residual, last_step


NEWTON_STOP = 1e-10  # a Newton step in log(theta_f) this small ends the solve: the next would
# be ~1e-20, below rounding (quadratic convergence); the result is still checked by the caller
PREDICTED_STOP = 1e-13  # ...as does a step after which the predicted relative residual is this
RESIDUAL_SCALE = 0.1  # of the load: where the Newton residual turns from log(F/W) to linear
# (1e-3 made the residual a steep step where Fz_static changes sign, and Newton oscillated
# across it in braking corners; 0.1 keeps both the small constant and those corners)


def _residual(f, w_safe):
    """asinh(F/(eps*W)) - asinh(1/eps), eps = RESIDUAL_SCALE: monotone in F, zero at F = W,
    log(F/W) to ~1e-2 for F > W/2 (where Fz_static ~ theta_f**q, nearly linear in log(theta_f):
    Newton converges with a small constant), finite and moderate for F <= 0 (braking corners),
    where a plain (F - W)/W would dwarf the log branch and stall regula falsi."""
    return ca.asinh(f / (RESIDUAL_SCALE * w_safe)) - math.asinh(1 / RESIDUAL_SCALE)


def _fallback(lo, hi, h_lo, h_hi):
    """Regula falsi on the bracket (an end with zero residual is the root itself); bisection if
    it would leave the bracket."""
    rf = lo - h_lo * (hi - lo) / ca.fmax(h_hi - h_lo, 1e-300)
    return ca.if_else(ca.logic_and(rf >= lo, rf <= hi), rf, (lo + hi) / 2)


def refine(state, f, w_safe):
    """The cold solve's second iterate, from Fz_static ``f`` (no derivative) at its first, the
    regula falsi point y0 of the scan's bracket [lo, hi]: y0 narrows the bracket, and inverse
    quadratic interpolation through the residuals at lo, y0 and hi (log(Fz) is smooth and
    nearly linear in log(theta_f)) gives an iterate ~1e-4 from the root, where two Newton
    steps with the derivative reach rounding; regula falsi on the narrowed bracket where the
    interpolation leaves it. Half the cost of a Newton iteration, and it saves one."""
    y, lo, hi, h_lo, h_hi = ca.vertsplit(state)[:5]
    h = _residual(f, w_safe)
    below = h <= 0
    iqi = (lo * h * h_hi / ((h_lo - h) * (h_lo - h_hi))
           + y * h_lo * h_hi / ((h - h_lo) * (h - h_hi))
           + hi * h_lo * h / ((h_hi - h_lo) * (h_hi - h)))
    lo, h_lo = ca.if_else(below, y, lo), ca.if_else(below, h, h_lo)
    hi, h_hi = ca.if_else(below, hi, y), ca.if_else(below, h_hi, h)
    inside = ca.logic_and(iqi > lo, iqi < hi)  # NaN (equal residuals) is not inside
    y_next = ca.if_else(inside, iqi, _fallback(lo, hi, h_lo, h_hi))
    return ca.vertcat(y_next, lo, hi, h_lo, h_hi, below, ca.fabs(y_next - y), 0, 0)


@lru_cache(maxsize=4)
def _newton_iteration(nodes: tuple[int, int]) -> ca.Function:
    """One safeguarded Newton iteration of the sinkage solve (:func:`sinkage_solve_expr`) as a
    switch on its converged flag: ``iteration(done, state, slip, p, w_safe) -> state``. While
    ``done`` is 0 it iterates; once a Newton step (not a fallback step) inside the bracket was
    shorter than NEWTON_STOP, ``done`` is 1 and the remaining iterations are the identity,
    evaluated as such (no contact evaluation): the solve stops when it has converged."""
    fz_fun = static_functions(nodes)[0]
    state, sl, pp, w_safe = (ca.MX.sym("state", STATE_SIZE), ca.MX.sym("slip"),
                             ca.MX.sym("p", len(NAMES)), ca.MX.sym("w_safe"))
    f, df = fz_fun(ca.exp(state[0]), sl, pp)
    next_state = _newton_update(state, f, df, w_safe)
    args = [state, sl, pp, w_safe]
    iterate = ca.Function("newton_step", args, [next_state])
    converged = ca.Function("newton_converged", args, [state])
    return ca.Function.conditional("newton_iteration", [iterate], converged)


def _newton_update(state, f, df, w_safe):
    """One safeguarded Newton iteration's algebra: the next state from ``state`` and Fz_static
    ``f`` and its derivative ``df`` by theta_f at theta_f = exp(state[0]).

    It is the last (``done``) when its step is a Newton step inside the bracket and either
    shorter than NEWTON_STOP, or, after a previous Newton step d0, the relative residual this
    step d leaves is predicted below PREDICTED_STOP: quadratic convergence gives an error
    ~C*d**2 with C ~ d/d0**2, i.e. a residual ~|theta*dF/dtheta/W|*d**3/d0**2 (required with
    d <= d0/2, the contraction that makes the estimate meaningful). That saves the confirming
    evaluation the NEWTON_STOP test needs; the caller still checks the final residual."""
    y, lo, hi, h_lo, h_hi, last_below, step_before, _, newton_before = ca.vertsplit(state)
    theta = ca.exp(y)
    h = _residual(f, w_safe)
    # sqrt(1 + u**2) without overflow (libm's hypot is not used: the native FMUs bind libm to
    # versions old glibc has, and hypot changed version in glibc 2.35)
    u = ca.fabs(f / (RESIDUAL_SCALE * w_safe))
    big, small = ca.fmax(u, 1), ca.fmin(u, 1)
    slope = theta * df / (RESIDUAL_SCALE * w_safe * big * ca.sqrt(1 + (small / big) ** 2))
    below = h <= 0
    # Illinois: an end kept twice in a row has its residual halved, so regula falsi cannot
    # stagnate against it.
    h_hi = ca.if_else(ca.logic_and(below, last_below == 1), h_hi / 2, h_hi)
    h_lo = ca.if_else(ca.logic_and(1 - below, last_below == 0), h_lo / 2, h_lo)
    lo, h_lo = ca.if_else(below, y, lo), ca.if_else(below, h, h_lo)
    hi, h_hi = ca.if_else(below, hi, y), ca.if_else(below, h_hi, h)
    step = y - h / ca.fmax(slope, 1e-12)  # F' <= 0 (non-monotone corner): fall back
    inside = ca.logic_and(step >= lo, step <= hi)
    y_next = ca.if_else(inside, step, _fallback(lo, hi, h_lo, h_hi))
    last_step = ca.fabs(y_next - y)
    predicted = (ca.fabs(theta * df / w_safe) * last_step**3
                 / ca.fmax(step_before, 1e-300) ** 2)
    quadratic = all_of([newton_before == 1, last_step <= step_before / 2,
                      predicted <= PREDICTED_STOP])
    done = ca.logic_and(inside, ca.logic_or(last_step <= NEWTON_STOP, quadratic))
    return ca.vertcat(y_next, lo, hi, h_lo, h_hi, below, last_step, done, inside)


@lru_cache(maxsize=4)
def _static_kernels(nodes: tuple[int, int]) -> tuple:
    """The ripple-free contact at entry angle theta_f, per case of :func:`form_switch`' switch, as
    SX Functions of (theta_f, slip, p): ``(case, fz, fz_d, static)``, ``fz[c]`` Fz_static
    with case c's kernel, ``fz_d[c]`` Fz_static and its derivative by theta_f (SX forward
    mode, with common subexpressions shared), ``static[c]`` every CONTACT_OUTPUT."""
    th, sl, pp = ca.SX.sym("theta_f"), ca.SX.sym("slip"), ca.SX.sym("p", len(NAMES))
    case, switch = form_switch(nodes, False)
    at = CONTACT_OUTPUTS.index("normal_force_static")
    fz, fz_d, static = [], [], []
    for name in FORMS:
        out = switch.find_function(name + "_static")(th, sl, 0, pp)
        static.append(ca.Function(f"static_{name}", [th, sl, pp], [out], {"cse": True}))
        f = out[at]
        fz.append(ca.Function(f"fz_{name}", [th, sl, pp], [f], {"cse": True}))
        fz_d.append(ca.Function(f"fz_d_{name}", [th, sl, pp], [f, ca.jacobian(f, th)],
                                {"cse": True}))
    return (ca.Function("static_case", [th, sl, pp], [case(th, sl, pp)]), tuple(fz),
            tuple(fz_d), tuple(static))


@lru_cache(maxsize=4)
def static_functions(nodes: tuple[int, int]) -> tuple[ca.Function, ca.Function, ca.Function]:
    """Functions of the ripple-free contact at entry angle theta_f: (Fz_static and its
    d/d(theta_f)), Fz_static alone, and every CONTACT_OUTPUT; each a switch over
    :func:`_static_kernels` (the derivative differentiated per kernel in SX: half the cost
    of differentiating the MX switch)."""
    th, sl, pp = ca.MX.sym("theta_f"), ca.MX.sym("slip"), ca.MX.sym("p", len(NAMES))
    case, fz, fz_d, static = _static_kernels(nodes)
    c = case(th, sl, pp)

    def switched(kernels) -> list:
        out = ca.Function.conditional(kernels[0].name() + "_switch", list(kernels[:2]),
                                      kernels[2])(c, th, sl, pp)
        return out if isinstance(out, (list, tuple)) else [out]

    return (ca.Function("fz_static", [th, sl, pp], switched(fz_d)),
            ca.Function("fz_static_value", [th, sl, pp], switched(fz)),
            ca.Function("arc_static", [th, sl, pp], ca.vertsplit(switched(static)[0])))


def steady_expr(load, slip, P: Params, nodes: tuple[int, int], guess=None, solve=None) -> list:
    """STEADY_OUTPUTS of the solve (cold, or from a sinkage ``guess``; ``solve``: the result
    of :func:`sinkage_solve_expr` when the caller has it already), the contact taken at the
    solved angle: no round trip through the sinkage. The residual is that contact's own
    normal_force_static (no separate Fz_static evaluation there, as in the lane solve)."""
    state, theta, capacity = solve or sinkage_solve_expr(load, slip, P, nodes, guess)
    quasi = static_functions(nodes)[2](theta, slip, P.p)
    f = quasi[CONTACT_OUTPUTS.index("normal_force_static")]
    sink, residual, last_step = solve_finish(load, state, f, P)
    return [sink, *quasi, residual, last_step, capacity]


def steady_from(steady: ca.Function, nodes: tuple[int, int]) -> ca.Function:
    """``steady_from(load, slip, p, guess)``: ``steady`` started warm from a sinkage guess [m]
    (finite and > 0; else cold, exactly ``steady``). The warm start evaluates of the scan only
    its two ends and starts Newton at the guess; where it does not converge (and the wheel can
    carry the load) the cold solve runs instead. Both are switches, so a call runs only the
    branch it takes."""
    load, slip, p, guess = (ca.MX.sym("load"), ca.MX.sym("slip"), ca.MX.sym("p", len(NAMES)),
                            ca.MX.sym("guess"))
    rows = ca.MX.sym("rows", len(STEADY_OUTPUTS))
    args = [load, slip, p, guess]
    warm = ca.Function("steady_warm", args,
                       [ca.vertcat(*steady_expr(load, slip, Params(p), nodes, guess))])
    cold = ca.Function("steady_cold", args, [ca.vertcat(*steady(load, slip, p))])
    valid = ca.logic_and(guess > 0, guess < math.inf)  # NaN compares false
    first = ca.Function.if_else("steady_start", warm, cold)(valid, *args)
    out = dict(zip(STEADY_OUTPUTS, ca.vertsplit(first), strict=True))
    retry = ca.logic_and(ca.logic_and(valid, load <= out["capacity"]),
                         ca.logic_not(solve_converged(out["residual"], out["last_step"])))
    again = ca.Function("steady_again", [rows, *args], [ca.vertcat(*steady(load, slip, p))])
    kept = ca.Function("steady_kept", [rows, *args], [rows])
    final = ca.Function.if_else("steady_retry", again, kept)(retry, first, *args)
    return ca.Function("steady_from", args, ca.vertsplit(final), [*STEADY_INPUTS, "guess"],
                       list(STEADY_OUTPUTS))


RESIDUAL_TOLERANCE = 1e-9
"""Largest accepted relative normal-force residual of the sinkage solve (it reaches ~1e-15)."""
STEP_TOLERANCE = 1e-13
"""Alternatively accepted: last Newton step in log(entry angle) at rounding level, i.e. the root
is pinned in sinkage although the load is too small a part of cancelling force terms for the
relative force residual to reach RESIDUAL_TOLERANCE."""


def solve_converged(residual, last_step):
    """The sinkage solve's acceptance test, on floats, arrays or CasADi symbols: a small
    relative residual, or a last Newton step at rounding level."""
    if isinstance(residual, (ca.SX, ca.MX)):
        return ca.logic_or(ca.fabs(residual) <= RESIDUAL_TOLERANCE, last_step <= STEP_TOLERANCE)
    return (np.abs(residual) <= RESIDUAL_TOLERANCE) | (np.asarray(last_step) <= STEP_TOLERANCE)
