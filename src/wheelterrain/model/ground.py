"""A terrain along the path: the soil under a query point (a wheel's axle) at its position, and
the ruts the wheels leave in it.

The query-point pattern of vehicle co-simulation: the vehicle reports where each wheel is, the
map answers with the ground there, and each wheel's contact model takes that ground as its
soil. Here the map is one soil (the ``soil.*`` rows) with a patch of another (the ``patch.*``
rows) on [``patch.start``, ``patch.end``) along the path: a soft patch under the front axle and
then the rear in the rover's ``soft-patch`` scenario.

The rut profile (the soil's memory along a track): a Terrain answers the query points of one
track, QUERY (the leading wheel, then the one behind it). Each step it lays, at each query
point's position, the rut that wheel leaves (WheelTerrain's ``rut_left``) with the pressure
that wheel pressed it to (``rut_pressure_left``): the track is cut into cells of
``terrain.cell``, each keeping the deepest rut left in it and that rut's pressure. A wheel
meets the rut under the leading half of its contact: the profile (linear between the cells'
middles) averaged from ``terrain.lookahead`` / 2 to ``terrain.lookahead`` ahead of its axle (the
front of its contact; :func:`met_window`, :func:`met`), WheelTerrain's inputs
``rut_met`` and ``rut_pressure_met`` (its contact takes the deeper of it and its soil's
``soil.rut_depth``, with that rut's pressure), so the wheel behind runs in the rut of the wheel
ahead, the query-point pattern of vehicle-terrain co-simulation, and meets it as carrying the
pressure it did carry, whatever its own slip (the Soil Contact Model's node keeps its yield
pressure so). The rut profile is a ring of RUT_CELLS cells (the track's last RUT_CELLS * cell
metres), each holding the rut, the number of the cell it belongs to and the rut's pressure
(:func:`cell_after`).

Written once as plain arithmetic on numbers or CasADi symbols: Terrain.fmu (both flavours, a
state model whose state is the rut profile) and the in-process rover
(:mod:`wheelterrain.cosim.rover`, which replays the same rut profile between its blocks of
steps) run :func:`soil_at`, :func:`met`, :func:`outputs` and :func:`lay_ruts`.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from wheelterrain.model.rig import pick
from wheelterrain.parameters import GROUND_TABLE, TABLE

SOIL_NAMES = tuple(p.name for p in TABLE if p.name.startswith("soil."))
"""The soil rows the map supplies, in table order."""
PATCH_NAMES = tuple(f"patch.{n.split('.', 1)[1]}" for n in SOIL_NAMES)
"""The patch's rows, in the order of :data:`SOIL_NAMES`."""
NAMES = (*SOIL_NAMES, *(p.name for p in GROUND_TABLE))
"""The map's parameters: the soil rows, then the map's own (patch.start, patch.end, the rut
rut profile's terrain.cell and terrain.lookahead, patch.*)."""
QUERY = ("q1", "q2")
"""A Terrain's query points: the wheels of one track, the leading one first."""
RUT_CELLS = 256
"""Cells of the rut profile: it remembers the track's last RUT_CELLS * terrain.cell metres."""
EMPTY = -1.0e15
"""The cell number of a cell no wheel has left a rut in yet (no cell has this number:
|position| <= 1e6 m, terrain.cell >= 1 mm)."""
STATES: tuple[str, ...] = (*(f"rut[{k}]" for k in range(RUT_CELLS)),
                           *(f"cell[{k}]" for k in range(RUT_CELLS)),
                           *(f"pressure[{k}]" for k in range(RUT_CELLS)))
"""The rut profile: the rut of each ring slot [m], the number of the cell it holds, the
pressure the rut carried [Pa] (0: not known, read from its depth)."""
RUT_LEFT = ("rut_left", "rut_pressure_left")
"""What a wheel leaves that the record keeps (its WheelTerrain's outputs, a query point's
inputs): the rut's depth [m] and the pressure it carried [Pa]."""
RUT_MET = ("rut_met", "rut_pressure_met")
"""What the record serves a wheel (a query point's outputs, its WheelTerrain's inputs): the
same pair, for the rut the wheel meets."""
INPUTS = tuple(f"{q}.{n}" for q in QUERY for n in ("position", *RUT_LEFT))


def in_patch(position, p):
    """True where ``position`` [m] lies on the patch [patch.start, patch.end)."""
    return (position >= p["patch.start"]) * (position < p["patch.end"])


def soil_at(position, p) -> tuple:
    """The soil (:data:`SOIL_NAMES` order) at ``position`` [m] along the path, from the map's
    parameters ``p[name]``: the patch's where it lies, the soil rows' elsewhere."""
    inside = in_patch(position, p)
    return tuple(pick(inside, p[patch], p[soil])
                 for soil, patch in zip(SOIL_NAMES, PATCH_NAMES, strict=True))


SOFT_PATCH = {"soil.k_phi": 0.5, "soil.phi": 0.85}
"""The rover's soft patch: k_phi' and phi scaled by these factors (a looser soil)."""
SOFT_PATCH_START, SOFT_PATCH_LENGTH = 0.50, 0.30
"""m along the path: where the soft patch lies (the rover's front axle starts at 0.2 m)."""


def map_values(base, patched, start: float, end: float) -> dict[str, float]:
    """The map's parameters (NAMES) for a soil ``base`` with a patch of the soil ``patched``
    on [start, end) m (both indexed by table name; start = end: no patch), the rut profile's
    rows at their defaults."""
    out = {**defaults(), **{name: base[name] for name in SOIL_NAMES}}
    out.update({patch: patched[soil] for soil, patch in zip(SOIL_NAMES, PATCH_NAMES,
                                                             strict=True)})
    out.update({"patch.start": start, "patch.end": end})
    return out


def soft_values(base) -> dict[str, float]:
    """The soft patch's soil values that differ from the soil ``base`` (by table name)."""
    return {k: base[k] * f for k, f in SOFT_PATCH.items()}


def soft_patch(base) -> dict[str, float]:
    """The map of the rover's soft-patch scenario over the soil ``base`` (by table name)."""
    patched = {**{n: base[n] for n in SOIL_NAMES}, **soft_values(base)}
    return map_values(base, patched, SOFT_PATCH_START, SOFT_PATCH_START + SOFT_PATCH_LENGTH)


def defaults() -> dict[str, float]:
    """The map's parameters at their rows' defaults: one soil, no patch."""
    rows = {p.name: p for p in (*TABLE, *GROUND_TABLE)}
    return {name: float(rows[name].default) for name in NAMES}


def no_ruts() -> list[float]:
    """The rut profile before any wheel passed: no rut, every slot empty."""
    return [0.0] * RUT_CELLS + [EMPTY] * RUT_CELLS + [0.0] * RUT_CELLS


def _split(x):
    """(ruts, cells, pressures) of a rut profile ``x`` (:data:`STATES`)."""
    return x[:RUT_CELLS], x[RUT_CELLS:2 * RUT_CELLS], x[2 * RUT_CELLS:]


def cell_number(position, p):
    """The number of the cell of the track that ``position`` [m] lies in (a float, a numpy
    array of positions, or a CasADi symbol)."""
    return _floor(position / p["terrain.cell"])


def _floor(x):
    if isinstance(x, (int, float)):
        return math.floor(x)
    return np.floor(x) if isinstance(x, np.ndarray) else ca.floor(x)


def _slot(number):
    """The ring slot that holds cell ``number``."""
    return number - RUT_CELLS * _floor(number / RUT_CELLS)


def cell_after(rut, cell, pressure, number, left, left_pressure):
    """One slot of the rut profile after a wheel left the rut ``left`` [m] pressed to
    ``left_pressure`` [Pa] in cell ``number``, the slot holding ``rut`` (pressed to
    ``pressure``) for cell ``cell``: the deeper of the two with its pressure where the slot
    holds that cell (equally deep: the larger pressure), else (a cell the ring comes round to
    again) the new rut alone. ``(rut, cell, pressure)``."""
    values = (rut, cell, pressure, number, left, left_pressure)
    if not any(isinstance(v, (ca.SX, ca.MX)) for v in values):
        rut, cell, pressure, number, left, left_pressure = (float(v) for v in values)
        if cell != number or left > rut:
            return left, number, left_pressure
        return rut, number, (max(pressure, left_pressure) if left == rut else pressure)
    same = cell == number
    kept = ca.if_else(left < rut, pressure, ca.fmax(pressure, left_pressure))
    return (ca.if_else(same, ca.fmax(left, rut), left), number,
            ca.if_else(ca.logic_and(same, left <= rut), kept, left_pressure))


def rut_in_cell(x, number):
    """``(rut, pressure)``: the rut [m] the rut profile ``x`` (:data:`STATES`: a list of
    floats, or a CasADi MX vector) holds for cell ``number``, and the pressure it carried [Pa];
    both 0 where no wheel has left one there (or the ring has come round since). MX: the slot
    is read by a symbolic index (one lookup, not one switch a slot)."""
    if isinstance(number, (int, float)):
        return ruts_in_cells(x, number, 1)[0]
    ruts, cells, pressures = _split(x)
    slot = _slot(number)
    here = cells[slot] == number
    return ca.if_else(here, ruts[slot], 0), ca.if_else(here, pressures[slot], 0)


def ruts_in_cells(x, first: float, count: int) -> list[tuple[float, float]]:
    """:func:`rut_in_cell` of the ``count`` cells from number ``first`` on, of a rut profile
    ``x`` of floats (the record split once, not once a cell: the in-process rover reads a
    table of them for every wheel and block)."""
    ruts, cells, pressures = _split(x)
    out = []
    for number in (first + k for k in range(count)):
        slot = int(_slot(number))
        here = float(cells[slot]) == number
        out.append((float(ruts[slot]), float(pressures[slot])) if here else (0.0, 0.0))
    return out


def lay_ruts(x, u, p):
    """The rut profile after a step: each query point (in QUERY order) leaves its input rut_left at
    its position (:func:`lay_rut`). ``x`` a list of floats or an MX vector, as returned."""
    inputs = dict(zip(INPUTS, u, strict=True))
    x = list(x) if isinstance(x, (list, tuple)) else x
    for q in QUERY:
        x = lay_rut(x, inputs[f"{q}.position"], inputs[f"{q}.rut_left"],
                    inputs[f"{q}.rut_pressure_left"], p)
    return x


def lay_rut(x, position, left, pressure, p):
    """The rut profile ``x`` after a wheel at ``position`` left the rut ``left`` pressed to
    ``pressure``: only the slot of its cell changes (:func:`cell_after`). On floats that slot
    is written; on an MX vector it is read by a symbolic index and written by a switch over the
    slots. Leaving the ruts r1, r2, ... in one cell one after the other is leaving their
    deepest once (with the largest pressure among the deepest; the in-process rover replays
    its steps so)."""
    number = cell_number(position, p)
    if isinstance(number, (int, float)):
        ruts, cells, pressures = (list(v) for v in _split(x))
        slot = int(_slot(number))
        ruts[slot], cells[slot], pressures[slot] = cell_after(
            ruts[slot], cells[slot], pressures[slot], number, left, pressure)
        return ruts + cells + pressures
    ruts, cells, pressures = _split(x)
    slot = _slot(number)
    new = cell_after(ruts[slot], cells[slot], pressures[slot], number, left, pressure)
    hit = ca.DM(list(range(RUT_CELLS))) == slot
    return ca.vertcat(*(ca.if_else(hit, ca.repmat(v, RUT_CELLS, 1), old)
                        for v, old in zip(new, (ruts, cells, pressures), strict=True)))


WINDOW_CELLS = 10
"""Cells of the rut profile the window a wheel meets spans at most (:func:`met_window`): its
rut is read from at most WINDOW_CELLS + 3 cells (MET_CELLS) whatever the cell's length."""
MET_CELLS = WINDOW_CELLS + 3
"""Cells a wheel's window touches at most (:func:`window_cells`)."""


def met_window(position, p):
    """``(a, b)`` [m]: the stretch of the track whose rut a wheel at ``position`` [m] meets: the
    leading half of its reach ahead, from terrain.lookahead / 2 to terrain.lookahead (the front
    of its contact) ahead of its axle, or its last WINDOW_CELLS cells where that half is
    longer. It starts at least 1.5 cells ahead of the axle (terrain.lookahead is at least three
    cells), clear of the cells the wheel's own rut is laid in."""
    cell, ahead = p["terrain.cell"], p["terrain.lookahead"]
    half = ahead / 2
    width = pick(half < WINDOW_CELLS * cell, half, WINDOW_CELLS * cell)
    return position + ahead - width, position + ahead


def window_cells(position, p):
    """``(first, last)``: the numbers of the first and the last cell whose rut enters the rut a
    wheel at ``position`` meets (:func:`met_window`: the cells whose middles lie within a cell
    of it); at most MET_CELLS of them."""
    a, b = met_window(position, p)
    cell = p["terrain.cell"]
    return _floor(a / cell - 0.5), _floor(b / cell - 0.5) + 1


def _met_over(cells, read, position, p):
    """``(rut, pressure)`` a wheel at ``position`` meets: the mean over its window (a, b)
    (:func:`met_window`) of the rut profile linear between the cells' middles, the pressure
    the same mean, 0 (not known) where a cell of the window holds a rut whose pressure is not
    known. With u = x/cell - 1/2 the profile's coordinate (the cells' middles at whole u),
    n = floor(u) and f = u - n at each end, the integral over the window in cells is the
    sum of the cells na .. nb - 1 and the hats' shares at the ends: + (1 - (1 - fb)^2/2) of
    cell nb, + fb^2/2 of nb + 1, - (1 - (1 - fa)^2/2) of na, - fa^2/2 of na + 1. ``cells``:
    (number, rut, pressure) of consecutive cells holding na .. nb - 1 (in the order of their
    numbers; any others count 0, added as exact zeros, so a longer list gives the same
    numbers to the bit); ``read(number)``: (rut, pressure) of any cell, for the ends."""
    cell = p["terrain.cell"]
    a, b = met_window(position, p)
    ua, ub = a / cell - 0.5, b / cell - 0.5
    na, nb = _floor(ua), _floor(ub)
    fa, fb = ua - na, ub - nb
    rut = pressure = unknown = 0
    for number, r, q in cells:
        inside = (number >= na) * (number < nb)
        rut = rut + pick(inside, r, 0)
        pressure = pressure + pick(inside, q, 0)
        weighs = (number >= na) * (number <= nb)
        unknown = unknown + pick(weighs, pick(r > 0, pick(q > 0, 0, 1), 0), 0)
    ends = ((na, -(1 - (1 - fa) * (1 - fa) / 2)), (na + 1, -(fa * fa / 2)),
            (nb, 1 - (1 - fb) * (1 - fb) / 2), (nb + 1, fb * fb / 2))
    for number, share in ends:
        r, q = read(number)
        rut = rut + share * r
        pressure = pressure + share * q
    # r, q: cell nb + 1's, the last end read; it weighs where the window reaches past nb's
    # middle
    unknown = unknown + pick(fb > 0, pick(r > 0, pick(q > 0, 0, 1), 0), 0)
    scale = cell / (b - a)
    return rut * scale, pick(unknown > 0, 0, pressure * scale)


def met(x, position, p):
    """``(rut, pressure)``: the rut a wheel at ``position`` meets and the pressure it carried:
    the rut profile's, linear between the cells' middles, averaged over the window ahead of
    the wheel (:func:`met_window`, :func:`_met_over`), read from MET_CELLS cells from the
    window's first. Not read at one point: the contact spans a stretch of the rut, and a rut
    read at one point served the wheels the cell-by-cell marks of the record, a disturbance
    of the rover's steady motion that depended on the cell's length (the Earth's climb limit
    moved 28.9-30.1 deg for cells of 2.5-20 mm; read as a staircase, the Moon's climb had
    stalled 23.3-25.4 deg for cells of 10-2 mm)."""
    first = window_cells(position, p)[0]
    cells = [(first + k, *rut_in_cell(x, first + k)) for k in range(MET_CELLS)]
    return _met_over(cells, lambda number: rut_in_cell(x, number), position, p)


def met_in_table(position, p, table):
    """:func:`met` from a table of the rut profile instead of the profile: ``table`` is the
    number of a cell, then the ruts of the m cells from it on (the cells a wheel's window
    touches within a short stretch of travel), then their pressures (any sequence or CasADi
    vector of 2m + 1). The same numbers as :func:`met` to the bit where the table holds every
    cell the window touches. On an MX vector the MET_CELLS cells from the window's first, and
    its ends, are read by a symbolic index, as :func:`met` reads the record (an index past the
    table reads its last cells: a wheel that moved beyond its table is refused after its
    block, by ``cosim.ruts.remember``); elsewhere every cell of the table is summed (the
    cells outside the window add exact zeros) and the ends picked from the table."""
    start = table[0]
    m = ((table.shape[0] if hasattr(table, "shape") else len(table)) - 1) // 2

    if isinstance(table, ca.MX):
        def read(number):
            k = ca.fmin(ca.fmax(number - start, 0), m - 1)
            return table[1 + k], table[1 + m + k]
    elif isinstance(table, ca.SX):
        def read(number):
            here = [number == start + k for k in range(m)]
            return (sum(pick(h, table[1 + k], 0) for k, h in enumerate(here)),
                    sum(pick(h, table[1 + m + k], 0) for k, h in enumerate(here)))
    else:
        def read(number):
            k = int(number - start)
            return (table[1 + k], table[1 + m + k]) if 0 <= k < m else (0.0, 0.0)

    if isinstance(table, ca.MX) and m >= MET_CELLS:
        first = window_cells(position, p)[0]
        cells = [(first + k, *read(first + k)) for k in range(MET_CELLS)]
    else:
        cells = [(start + k, table[1 + k], table[1 + m + k]) for k in range(m)]
    return _met_over(cells, read, position, p)


def outputs(x, u, p) -> tuple:
    """Every query point's outputs, QUERY order: the map's soil at its position
    (:func:`soil_at`), then the rut it meets and that rut's pressure (:func:`met`). A wheel's
    contact takes the deeper of the two ruts (WheelTerrain's rut_met input against its
    soil.rut_depth), with its pressure."""
    inputs = dict(zip(INPUTS, u, strict=True))
    out = []
    for q in QUERY:
        position = inputs[f"{q}.position"]
        out += (*soil_at(position, p), *met(x, position, p))
    return tuple(out)
