"""The two slip definitions, named explicitly.

- Traction slip ``i = (omega*R - V)/(omega*R)``: the usual terramechanics slip, the model's input.
  In [0, 1) when driving, negative when braking; 1 is spinning in place.
- The paper's slip ``s = (omega*R - V)/V`` (Abubakar et al., eq. 4), in which C1-C4 are given
  (s = 0, 0.25, 0.5, 0.75). ``i = s/(1 + s)``, ``s = i/(1 - i)``, so ``1 - i = 1/(1 + s)``.
"""

from __future__ import annotations

import math

from wheelterrain.errors import InputError

TRACTION_RANGE = (-1.0, 1.0)
"""Valid traction slip: from a wheel turning at half the carriage speed (-1) to spinning (1)."""
PAPER_RANGE = (-0.5, math.inf)
"""Valid paper slip, the image of TRACTION_RANGE: s = -0.5 <-> i = -1; s -> inf <-> i -> 1."""

DEFINITIONS = ("traction", "paper")
DEFAULT_DEFINITION = "traction"
"""The slip every command and API takes unless told otherwise: the model's own (and the FMU's
``slip`` output); the paper's s is one option away (``--slip-definition paper``)."""


def reference_radius(values):
    """The radius R_ref = R + f_ref*h_g both slips are referenced to (``omega*R_ref`` is the rim
    speed in them): the rim (f_ref = 0) up to the grouser tips (1). ``values``: anything indexed
    by table name (a ParameterSet, a dict, the model's symbolic parameters)."""
    return values["wheel.radius"] + values["model.slip_radius_factor"] * values["grouser.height"]


def traction_from_paper(s: float) -> float:
    """Traction slip i = s/(1 + s) from the paper's slip s."""
    return s / (1.0 + s)


def paper_from_traction(i: float) -> float:
    """The paper's slip s = i/(1 - i) from traction slip i (infinite at i = 1)."""
    return math.inf if i == 1.0 else i / (1.0 - i)


def to_traction(value: float, definition: str) -> float:
    """Validate a slip given in ``definition`` ('traction' or 'paper') and return traction slip."""
    if definition not in DEFINITIONS:
        raise InputError("slip_definition", definition, f"must be one of {', '.join(DEFINITIONS)}")
    name = "slip" if definition == "traction" else "slip (paper definition)"
    lo, hi = TRACTION_RANGE if definition == "traction" else PAPER_RANGE
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise InputError(name, value, "is not a number") from None
    shown_hi = "inf)" if math.isinf(hi) else f"{hi:g}]"
    if not math.isfinite(number) or not (lo <= number <= hi):
        raise InputError(name, value, f"is out of range; valid range [{lo:g}, {shown_hi}")
    return number if definition == "traction" else traction_from_paper(number)
