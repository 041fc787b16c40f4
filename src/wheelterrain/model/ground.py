"""A terrain map along the path: the soil under a query point (a wheel's axle) at its position.

The query-point pattern of vehicle co-simulation: the vehicle reports where each wheel is, the
map answers with the ground there, and each wheel's contact model takes that ground as its
soil. Here the map is one soil (the ``soil.*`` rows) with a patch of another (the ``patch.*``
rows) on [``patch.start``, ``patch.end``) along the path: a soft patch under the front axle and
then the rear in the rover's ``soft-patch`` scenario.

Written once as plain arithmetic on numbers or CasADi symbols: Terrain.fmu (both flavours, a
state model without states: its outputs are its inputs' image) and the in-process rover
(:mod:`wheelterrain.cosim.rover`, evaluated at every step, as the FMU is) run :func:`soil_at`.
"""

from __future__ import annotations

from wheelterrain.model.rig import pick
from wheelterrain.parameters import GROUND_TABLE, TABLE

SOIL_NAMES = tuple(p.name for p in TABLE if p.name.startswith("soil."))
"""The soil rows the map supplies, in table order."""
PATCH_NAMES = tuple(f"patch.{n.split('.', 1)[1]}" for n in SOIL_NAMES)
"""The patch's rows, in the order of :data:`SOIL_NAMES`."""
NAMES = (*SOIL_NAMES, *(p.name for p in GROUND_TABLE))
"""The map's parameters: the soil rows, then the map's own (patch.start, patch.end, patch.*)."""
STATES: tuple[str, ...] = ()
INPUTS = ("position",)


def in_patch(position, p):
    """True where ``position`` [m] lies on the patch [patch.start, patch.end)."""
    return (position >= p["patch.start"]) * (position < p["patch.end"])


def soil_at(position, p) -> tuple:
    """The soil (:data:`SOIL_NAMES` order) at ``position`` [m] along the path, from the map's
    parameters ``p[name]``: the patch's where it lies, the soil rows' elsewhere."""
    inside = in_patch(position, p)
    return tuple(pick(inside, p[patch], p[soil])
                 for soil, patch in zip(SOIL_NAMES, PATCH_NAMES, strict=True))


def defaults() -> dict[str, float]:
    """The map's parameters at their rows' defaults: one soil, no patch."""
    rows = {p.name: p for p in (*TABLE, *GROUND_TABLE)}
    return {name: float(rows[name].default) for name in NAMES}
