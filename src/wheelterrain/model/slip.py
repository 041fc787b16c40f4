"""The slip definitions, named explicitly, and the model's own.

- Traction slip ``i = (omega*R - V)/(omega*R)``: the usual terramechanics slip of a driven
  wheel. In [0, 1] when driving (1 spinning in place); negative when braking, down to -inf for a
  locked wheel (omega = 0).
- The paper's slip ``s = (omega*R - V)/V`` (Abubakar et al., eq. 4), in which C1-C4 are given
  (s = 0, 0.25, 0.5, 0.75); for a braked wheel it is Wong's skid i_s (Wong, *Theory of Ground
  Vehicles*, ch. 4), -1 for a locked wheel. ``i = s/(1 + s)``, ``s = i/(1 - i)``.
- The model's slip ``sigma = (omega*R - V)/max(omega*R, V)`` (definition ``unified``): the
  traction slip i when driving and the skid s when braking, so one bounded number runs from a
  locked wheel (-1) through free rolling (0) to spinning in place (1). Both agree to first order
  at 0 (sigma, i and s have the same derivative there), and the kinematics are exact on either
  side: V/(omega*R) = 1 - sigma driving, 1/(1 + sigma) braking. Every Function of the model
  takes sigma; the Python API, the CLI and the FMUs convert.
"""

from __future__ import annotations

import math

from wheelterrain.errors import InputError

MODEL_RANGE = (-1.0, 1.0)
"""The model's slip sigma: from a locked wheel (-1) to spinning in place (1)."""
TRACTION_RANGE = (-math.inf, 1.0)
"""Traction slip i: any braking value (a locked wheel is i -> -inf: give it as paper slip -1
or unified -1) up to spinning (1)."""
PAPER_RANGE = (-1.0, math.inf)
"""The paper's slip s: a locked wheel (-1) to spinning (s -> inf)."""
RANGES = {"traction": TRACTION_RANGE, "paper": PAPER_RANGE, "unified": MODEL_RANGE}

DEFINITIONS = tuple(RANGES)
DEFAULT_DEFINITION = "traction"
"""The slip every command and API takes unless told otherwise; for a driven wheel it is the
model's own (the FMU's ``slip`` output); the paper's s is one option away
(``--slip-definition paper``), the model's sigma another (``unified``)."""


def reference_radius(values):
    """The radius R_ref = R + f_ref*h_g both slips are referenced to (``omega*R_ref`` is the rim
    speed in them): the rim (f_ref = 0) up to the grouser tips (1). ``values``: anything indexed
    by table name (a ParameterSet, a dict, the model's symbolic parameters)."""
    return values["wheel.radius"] + values["model.slip_radius_factor"] * values["grouser.height"]


def traction_from_paper(s: float) -> float:
    """Traction slip i = s/(1 + s) from the paper's slip s (-inf at s = -1, a locked wheel)."""
    return -math.inf if s == -1.0 else s / (1.0 + s)


def paper_from_traction(i: float) -> float:
    """The paper's slip s = i/(1 - i) from traction slip i (infinite at i = 1, -1 at -inf)."""
    if i == 1.0:
        return math.inf
    return -1.0 if i == -math.inf else i / (1.0 - i)


def unified_from_traction(i: float) -> float:
    """The model's slip sigma from traction slip i: i driving, the skid i/(1 - i) braking."""
    return i if i >= 0 else paper_from_traction(i)


def unified_from_paper(s: float) -> float:
    """The model's slip sigma from the paper's slip s: s/(1 + s) driving, s braking."""
    return s if s < 0 else s / (1.0 + s)


def paper_from_unified(sigma: float) -> float:
    """The paper's slip s from the model's sigma (infinite at sigma = 1)."""
    return sigma if sigma < 0 else paper_from_traction(sigma)


def traction_from_unified(sigma: float) -> float:
    """Traction slip i from the model's sigma (-inf at sigma = -1, a locked wheel)."""
    return sigma if sigma >= 0 else traction_from_paper(sigma)


def ground_speed(sigma: float, rim_speed: float) -> float:
    """The ground speed V [m/s] of a wheel at the model's slip ``sigma`` with its rim at
    ``rim_speed`` (omega*R): (1 - sigma)*rim driving, rim/(1 + sigma) braking (inf for a
    locked wheel's rim turning: no finite speed gives it)."""
    if sigma >= 0:
        return (1 - sigma) * rim_speed
    return math.inf if sigma <= -1 else rim_speed / (1 + sigma)


def speeds(sigma: float, faster: float) -> tuple[float, float]:
    """(rim speed omega*R, ground speed V) at the model's slip ``sigma`` with the faster of the
    two at ``faster``: the rim driving (V = (1 - sigma)*rim), the ground braking
    (rim = (1 + sigma)*V, 0 for a locked wheel)."""
    return (faster, (1 - sigma) * faster) if sigma >= 0 else ((1 + sigma) * faster, faster)


_TO_UNIFIED = {"traction": unified_from_traction, "paper": unified_from_paper,
               "unified": lambda sigma: sigma}


def to_unified(value: float, definition: str) -> float:
    """Validate a slip given in ``definition`` (:data:`DEFINITIONS`) and return the model's slip
    sigma (:data:`MODEL_RANGE`)."""
    if definition not in DEFINITIONS:
        raise InputError("slip_definition", definition, f"must be one of {', '.join(DEFINITIONS)}")
    name = "slip" if definition == "traction" else f"slip ({definition} definition)"
    lo, hi = RANGES[definition]
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise InputError(name, value, "is not a number") from None
    shown_lo = "(-inf" if math.isinf(lo) else f"[{lo:g}"
    shown_hi = "inf)" if math.isinf(hi) else f"{hi:g}]"
    if not math.isfinite(number) or not (lo <= number <= hi):
        lock = (" (a locked wheel is traction slip -inf: give it as --slip-definition paper "
                "-1)" if definition == "traction" else "")
        raise InputError(name, value, f"is out of range; valid range {shown_lo}, {shown_hi}"
                                      + lock)
    return _TO_UNIFIED[definition](number)


def in_definition(sigma: float, definition: str) -> float:
    """The model's slip ``sigma`` in ``definition``."""
    return {"traction": traction_from_unified, "paper": paper_from_unified,
            "unified": lambda x: x}[definition](sigma)
