"""The ruts along the rover's tracks, as Terrain.fmu keeps them: a rut profile per track (the
deepest rut left in each cell), the rut each wheel meets (:mod:`wheelterrain.model.ground`'s
cells, read linear between cells' middles), and the bookkeeping the in-process engine
(:mod:`wheelterrain.cosim.rover`) does between blocks of steps: the table of cells a wheel may
meet within a block (:func:`met_table`), the ruts the block's steps left replayed into the
profiles (:func:`remember`), the checks that the profile can serve the rover
(:func:`check_profile`), and the profiles of a rover already in steady motion
(:func:`steady_ruts`).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from wheelterrain.errors import ParameterError, WheelTerrainError
from wheelterrain.model import ground, rover

MOTION_CELLS = 9
"""Cells of the rut profile a wheel may move within one block of steps: the profile is replayed
between blocks (:func:`replay`), exactly as Terrain.fmu keeps it step by step, where a wheel
moves less than this a block (9 cells of 5 mm in 0.1 s: 0.45 m/s, 15 times the default rim
speed; a rover sliding downhill on braked or locked wheels moves faster than its rims)."""
NEAR = ground.MET_CELLS + MOTION_CELLS + 1
"""Cells of the rut profile a wheel's table holds for one block of steps (:func:`met_table`):
from the one before the first its window touches at the block's start, the cells its window
touches (ground.MET_CELLS at most) and those it may move on by (MOTION_CELLS)."""
TABLE = 2 * NEAR + 1
"""A wheel's table in a block's ``met`` input (:func:`met_table`)."""
N_MET = len(rover.WHEELS) * TABLE


def met_table(profiles: dict, positions: dict[str, float], g: Mapping[str, float]) -> list:
    """The ``met`` input of a block (N_MET): per wheel (TABLE values), the number of the cell
    before the first its window touches at the block's start (ground.window_cells), then the
    profile's ruts of NEAR cells from there, then those ruts' pressures (ground.met_in_table
    reads it)."""
    out = []
    for w in rover.WHEELS:
        first = ground.window_cells(positions[w], g)[0] - 1
        cells = ground.ruts_in_cells(profiles[rover.TRACK_OF[w]], first, NEAR)
        out += [float(first), *(rut for rut, _ in cells), *(pressure for _, pressure in cells)]
    return out


def replay(profiles: dict, wheel_positions: dict, ruts: dict, pressures: dict,
           g: Mapping[str, float]) -> None:
    """Terrain.fmu's rut profile of each track after a block: every step, each wheel of the track
    (the leading one first) left its rut (``ruts``) pressed to its pressure (``pressures``) at
    its position. Steps in one cell leave their deepest rut once, with the largest pressure
    among the deepest (ground.lay_rut, ground.cell_after); within a block the leading and the
    following wheel never write the same slot (the profile is longer than the wheelbase)."""
    for track, pair in rover.TRACKS.items():
        x = profiles[track]
        for w in pair:
            numbers = ground.cell_number(wheel_positions[w], g)
            starts = np.concatenate(([0], np.flatnonzero(np.diff(numbers)) + 1))
            ends = np.append(starts[1:], len(numbers))
            for a, e in zip(starts, ends, strict=True):  # per run of steps in one cell
                rut = np.max(ruts[w][a:e])
                pressure = np.max(pressures[w][a:e][ruts[w][a:e] == rut])
                x = ground.lay_rut(x, float(wheel_positions[w][a]), float(rut),
                                   float(pressure), g)
        profiles[track] = x


def check_profile(p: Mapping[str, float], g: Mapping[str, float]) -> None:
    """Refuse, with the parameters to change, a rover the rut profile cannot serve: a wheel
    must meet the rut at least three cells ahead of where it leaves its own, and the profile
    must be longer than a track (the wheelbase and the lookahead, two cells to spare)."""
    cell, ahead = g["terrain.cell"], g["terrain.lookahead"]
    if ahead < 3 * cell:
        raise ParameterError(
            "terrain.lookahead", ahead, f"m is less than three cells of terrain.cell = "
            f"{cell:g} m: a wheel would meet the rut it leaves itself; make it at least "
            f"{3 * cell:g} m")
    span = p["rover.wheelbase"] + ahead + 2 * cell
    if span >= ground.RUT_CELLS * cell:
        raise ParameterError(
            "terrain.cell", cell, f"m is too short: the rut profile holds {ground.RUT_CELLS} "
            f"cells ({ground.RUT_CELLS * cell:g} m), less than the wheelbase and lookahead "
            f"({span:g} m); make terrain.cell (a Terrain FMU parameter) at least "
            f"{span / ground.RUT_CELLS:.3g} m, or rover.wheelbase shorter")


def remember(profiles: dict, position: np.ndarray, left: Mapping[str, np.ndarray],
             pressures: Mapping[str, np.ndarray], met: list, p: Mapping[str, float],
             g: Mapping[str, float]) -> None:
    """After a block of steps: the ruts its steps left (``left``: per wheel, the rut left at
    each step; ``pressures``: the pressure it was pressed to; ``position``: the chassis' at
    each step), into the tracks' profiles (:func:`replay`); refused where a wheel's window
    touched a cell outside the block's table (it moved more than MOTION_CELLS cells)."""
    positions = {w: rover.wheel_position(p, position, w) for w in rover.WHEELS}
    for j, w in enumerate(rover.WHEELS):
        lowest, highest = ground.window_cells(positions[w], g)
        first = met[j * TABLE]
        if np.any(lowest < first) or np.any(highest > first + NEAR - 1):
            raise WheelTerrainError(
                f"{w} moved more than {MOTION_CELLS} cells of the rut profile (terrain.cell = "
                f"{g['terrain.cell']:g} m) in one block of {len(position)} steps: make "
                "terrain.cell larger or the block shorter")
    replay(profiles, positions, left, pressures, g)


def steady_ruts(balance: dict, p: Mapping[str, float], x, g: Mapping[str, float]) -> dict:
    """The tracks' rut profiles of a rover in steady motion (``balance``) at the state ``x``:
    the track behind each leading wheel holds its steady rut (and its pressure), back past the
    wheel behind."""
    profiles = {}
    position = x[rover.STATES.index("position")]
    for track, (front, rear) in rover.TRACKS.items():
        rut = balance["wheels"][front]["rut_left"]
        pressure = balance["wheels"][front]["rut_pressure_left"]
        profile = ground.no_ruts()
        first = ground.cell_number(rover.wheel_position(p, position, rear), g) - 2
        last = ground.cell_number(rover.wheel_position(p, position, front), g)
        for number in range(first, last + 1):  # at each cell's middle: its own number
            profile = ground.lay_rut(profile, (number + 0.5) * g["terrain.cell"], rut,
                                     pressure, g)
        profiles[track] = profile
    return profiles
