"""The validated Python face of the model: plain numbers in, named results out.

These functions check every input and parameter, call the CasADi Functions of
:mod:`wheelterrain.model.contact`, and turn the solver's diagnostics into clear errors, so a
caller never receives a wrong number silently.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from wheelterrain.errors import InputError, LoadTooLargeError, SolveError
from wheelterrain.model import contact as _contact
from wheelterrain.model.slip import paper_from_traction, to_traction
from wheelterrain.parameters import ParameterSet

RESIDUAL_TOLERANCE = 1e-9
"""Largest accepted relative normal-force residual of the sinkage solve (it reaches ~1e-15)."""
STEP_TOLERANCE = 1e-13
"""Alternatively accepted: last Newton step in log(entry angle) at rounding level, i.e. the root
is pinned in sinkage although the load is too small a part of cancelling force terms for the
relative force residual to reach RESIDUAL_TOLERANCE."""


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
                   slip_definition: str = "traction") -> dict[str, float]:
    """Forces and contact geometry at a given sinkage (the dynamic-sinkage face).

    sinkage [m] (to the contact circle; <= 0 means no contact), sinkage_rate [m/s], slip (see
    ``slip_definition``), wheel_angle [rad] (sets the grouser-ripple phase). Returns the
    ``contact.CONTACT_OUTPUTS`` in SI units.
    """
    ps = _params(params)
    z = _finite("sinkage", sinkage, hi=contact_radius(ps))
    rate = _finite("sinkage_rate", sinkage_rate)
    angle = _finite("wheel_angle", wheel_angle)
    i = to_traction(slip, slip_definition)
    fns = _contact.build()
    out = fns.contact(z, rate, i, angle, ps.vector())
    return _named(out, _contact.CONTACT_OUTPUTS)


def capacity(params: Mapping[str, float] | ParameterSet, slip: float,
             slip_definition: str = "traction") -> float:
    """Static normal force [N] with the wheel buried to its contact radius: the largest load."""
    ps = _params(params)
    i = to_traction(slip, slip_definition)
    return float(_contact.build().capacity(i, ps.vector()))


def steady_state(params: Mapping[str, float] | ParameterSet, load: float, slip: float,
                 slip_definition: str = "traction") -> dict[str, float]:
    """Quasi-static operating point: the sinkage at which the static normal force carries ``load``.

    load [N] >= 0 (0 gives zero sinkage and zero forces). The result is the grouser-period mean
    (ripple-free, zero sinkage rate) and holds every ``contact.STEADY_OUTPUTS`` plus ``load``,
    ``slip`` (traction) and ``slip_paper``.

    Raises LoadTooLargeError if the wheel cannot carry the load fully buried, SolveError if the
    solve did not reach RESIDUAL_TOLERANCE (never observed; it is checked, not assumed).
    """
    ps = _params(params)
    w = _finite("load", load, lo=0.0)
    i = to_traction(slip, slip_definition)
    out = _named(_contact.build().steady(w, i, ps.vector()), _contact.STEADY_OUTPUTS)
    if w > out["capacity"]:
        raise LoadTooLargeError(w, out["capacity"], contact_radius(ps))
    converged = (abs(out["residual"]) <= RESIDUAL_TOLERANCE
                 or out["last_step"] <= STEP_TOLERANCE)
    if not converged:
        raise SolveError(
            f"sinkage solve did not converge for load {w:g} N, slip {i:g}: relative residual "
            f"{out['residual']:.3g} > {RESIDUAL_TOLERANCE:g} and last step "
            f"{out['last_step']:.3g} > {STEP_TOLERANCE:g} in log(entry angle)")
    out.update(load=w, slip=i, slip_paper=paper_from_traction(i))
    return out


def steady_jacobian(params: Mapping[str, float] | ParameterSet, load: float, slip: float,
                    state: dict[str, float] | None = None) -> dict[str, np.ndarray]:
    """Exact derivatives of (sinkage, normal_force, drawbar_pull, torque) at the steady state.

    ``d_inputs`` is 4x2 (by load [N], traction slip), ``d_params`` 4 x len(TABLE) in table order.
    ``state``: the :func:`steady_state` result at the same point, if the caller has it (saves
    solving again).
    """
    ps = _params(params)
    state = state if state is not None else steady_state(ps, load, slip)
    jac = _contact.build().steady_jacobian(state["load"], state["slip"], ps.vector(),
                                           state["sinkage"])
    return {"d_inputs": np.array(jac[0]), "d_params": np.array(jac[1])}
