"""The terrain map (model.ground, Terrain.fmu) and WheelTerrain's soil from its ground.* inputs."""

from __future__ import annotations

import math

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from conftest import first_steps
from wheelterrain import presets
from wheelterrain.fmu import functions as fmu_model
from wheelterrain.fmu import variables
from wheelterrain.fmu.instance import Instance
from wheelterrain.model import ground

FLAVOURS = ["pythonfmu", "native", "native/fmi3"]


@pytest.fixture(scope="module")
def built(built_root):
    return built_root  # both flavours, built once per test run (conftest.py)


def _map(**changes) -> dict:
    return {**ground.defaults(), "patch.start": 1.0, "patch.end": 2.0, "patch.phi": 0.3,
            "patch.k_phi": 40.0, **changes}


def test_the_map_is_the_patch_on_its_half_open_interval_and_the_soil_elsewhere():
    p = _map()
    phi = ground.SOIL_NAMES.index("soil.phi")
    for position, inside in ((0.999, False), (1.0, True), (1.5, True), (2.0, False),
                             (-5.0, False)):
        soil = ground.soil_at(position, p)
        assert soil[phi] == (0.3 if inside else p["soil.phi"]), position
    # a patch whose end is not after its start is no patch
    assert ground.soil_at(1.5, _map(**{"patch.end": 1.0})) == ground.soil_at(0.0, p)


def test_the_fmu_function_is_the_model_on_floats():
    """Terrain.fmu's generated Functions and the slave's float path are one expression: the
    map at both query points, and the rut profile step by step."""
    model = fmu_model.STATE_MODELS["Terrain"]
    step, outputs, initial, _ = model.functions()
    p = _map()
    pv = [p[n] for n in ground.NAMES]
    x_fn = initial(pv).full().ravel()
    x_py = list(model.initial(p))
    assert list(x_fn) == x_py
    for k, position in enumerate((0.5, 1.0, 1.7, 2.0, 2.003, 2.2)):
        u = (position, 0.001 * k, 2e4 * k, position - 0.4, 0.002 * k, 3e4 * k)
        y = [float(v) for v in outputs(x_fn, u, pv, []).full().ravel()]
        assert y == list(model.output_values(x_py, u, p, ()))
        x_fn = step(x_fn, u, pv, 1e-3)[0].full().ravel()
        x_py, _ = model.step(x_py, u, p, 1e-3)
        assert list(x_fn) == list(x_py)
    assert model.outputs == tuple(n for q in variables.QUERY_POINTS
                                  for n in (*variables.query_ground(q), f"{q}.rut_met",
                                            f"{q}.rut_pressure_met"))


def _window_mean(x, position, p, samples=200_001):
    """An independent reading of the rut a wheel at ``position`` meets: the record's cells at
    their middles, numpy's linear interpolation between them, its trapezoidal mean over the
    leading half of terrain.lookahead (not more than 10 cells)."""
    cell, ahead = p["terrain.cell"], p["terrain.lookahead"]
    width = min(ahead / 2, 10 * cell)
    a, b = position + ahead - width, position + ahead
    numbers = np.arange(math.floor(a / cell) - 2, math.floor(b / cell) + 3)
    cells = [ground.rut_in_cell(x, float(n)) for n in numbers]
    s = np.linspace(a, b, samples)
    middles = (numbers + 0.5) * cell
    return tuple(float(np.trapezoid(np.interp(s, middles, [c[j] for c in cells]), s) / (b - a))
                 for j in (0, 1))


def test_the_record_keeps_the_deepest_rut_per_cell_and_serves_its_mean_ahead():
    """Each cell keeps the deepest rut left in it (as deep again: the larger pressure); a
    wheel meets the record, linear between the cells' middles, averaged over the leading half
    of its reach ahead (terrain.lookahead / 2 to terrain.lookahead): an independent quadrature
    of that mean agrees. A cell nobody has passed, or one the ring has come round since, has
    none."""
    p = ground.defaults()
    x = ground.no_ruts()
    cell, ahead = p["terrain.cell"], p["terrain.lookahead"]
    # three ruts left in one cell: the deepest stays, with its own pressure
    for rut, pressure in ((0.004, 9e3), (0.006, 2e4), (0.005, 3e4)):
        x = ground.lay_rut(x, 1.0 + cell / 2, rut, pressure, p)
    assert ground.rut_in_cell(x, math.floor(1.0 / cell)) == (0.006, 2e4)
    # as deep again: the larger pressure stays
    x = ground.lay_rut(x, 1.0 + cell / 2, 0.006, 2.5e4, p)
    assert ground.rut_in_cell(x, math.floor(1.0 / cell)) == (0.006, 2.5e4)
    # a rut along a few cells, each of its own depth and pressure
    for k, (rut, pressure) in enumerate(((0.003, 1e4), (0.009, 4e4), (0.007, 3e4))):
        x = ground.lay_rut(x, 1.0 + (k + 1.5) * cell, rut, pressure, p)
    for at in np.linspace(1.0 - ahead - 2 * cell, 1.0 + 6 * cell - ahead / 2, 23):
        assert ground.met(x, at, p) == pytest.approx(_window_mean(x, at, p), rel=1e-8,
                                                     abs=1e-12), at
    # the window over the rut's middle holds all of it: a mean, not the deepest cell
    rut, pressure = ground.met(x, 1.0 + 2 * cell - 0.75 * ahead, p)
    assert 0.003 < rut < 0.009
    assert 1e4 < pressure < 4e4
    # well before and after: none
    assert ground.met(x, 1.0 - 2 * ahead, p) == (0.0, 0.0)
    assert ground.met(x, 1.0 + 10 * cell, p) == (0.0, 0.0)
    # the ring comes round: a cell RUT_CELLS further on takes the slot, and the old is gone
    x = ground.lay_rut(x, 1.0 + cell / 2 + ground.RUT_CELLS * cell, 0.001, 5e3, p)
    assert ground.rut_in_cell(x, math.floor(1.0 / cell)) == (0.0, 0.0)


def test_a_rut_of_unknown_pressure_in_the_window_is_met_as_unknown():
    """A rut recorded without its pressure (0: a wheel whose rut_pressure_left is not
    connected) makes the pressure met 0 while a cell of it weighs in the wheel's window, so
    that the wheel reads the rut from its depth, not as carrying a share of its neighbours'
    pressure. The rover's table of the record gives the same numbers to the bit."""
    p = ground.defaults()
    cell, ahead = p["terrain.cell"], p["terrain.lookahead"]
    x = ground.no_ruts()
    for k in range(20):
        x = ground.lay_rut(x, 1.0 + (k + 0.5) * cell, 0.006, 2e4, p)
    x = ground.lay_rut(x, 1.0 + 20.5 * cell, 0.006, 0.0, p)
    inside = 1.0 + 12 * cell - ahead  # a window over cells of known pressure only
    assert ground.met(x, inside, p) == pytest.approx((0.006, 2e4), rel=1e-13)
    reaching = 1.0 + 20 * cell - ahead  # its window reaches the cell of unknown pressure
    assert ground.met(x, reaching, p) == pytest.approx((0.006, 0.0), rel=1e-13)
    for at in (inside, reaching, inside + 0.3 * cell):  # a table as the rover's
        first = ground.window_cells(at, p)[0] - 3
        cells = [ground.rut_in_cell(x, first + k) for k in range(ground.MET_CELLS + 6)]
        table = [first, *(r for r, _ in cells), *(q for _, q in cells)]
        assert ground.met_in_table(at, p, table) == ground.met(x, at, p)


def test_the_rut_a_wheel_meets_has_no_step_at_a_cell_s_edge():
    """Along a rut that deepens cell by cell, the rut met is continuous: as the window's ends
    cross cells' middles and edges it changes by a sliver of a cell's step, not by the step
    (a staircase stepped the rut under a wheel at every edge, a disturbance that grew with
    the cell's length); where the window lies on the even slope the mean is the rut at its
    middle."""
    p = ground.defaults()
    cell, ahead = p["terrain.cell"], p["terrain.lookahead"]
    x = ground.no_ruts()
    for k in range(30):
        x = ground.lay_rut(x, (100 + k + 0.5) * cell, 1e-3 * (k + 1), 1e4 * (k + 1), p)
    for k in range(1000):  # positions a fortieth of a cell apart across the recorded rut
        at = (100.5 + k / 40) * cell - ahead / 2
        after, before = ground.met(x, at + 1e-9, p), ground.met(x, at - 1e-9, p)
        assert abs(after[0] - before[0]) < 1e-8, k  # a staircase would jump by 1e-3 here
        assert abs(after[1] - before[1]) < 1e-1, k  # ... and the pressure by 1e4 Pa
    for k in range(15):  # the window on the even slope: the rut at its middle
        at = (101 + k) * cell - ahead / 2
        middle = at + 0.75 * ahead
        assert ground.met(x, at, p)[0] == pytest.approx(1e-3 * (middle / cell - 99.5),
                                                        rel=1e-12)


@pytest.mark.parametrize("flavour", FLAVOURS)
def test_terrain_fmus_validate(built, flavour):
    assert validate_fmu(str(built / flavour / "Terrain.fmu")) == []


@pytest.mark.parametrize(("flavour", "interface"), [
    ("pythonfmu", "cs"), ("native", "cs"), ("native", "me"), ("native/fmi3", "cs"),
    ("native/fmi3", "me")])  # the pythonfmu flavour is co-simulation only
def test_terrain_fmu_answers_the_map_at_its_query_point(built, flavour, interface):
    p = _map()
    with Instance(built / flavour / "Terrain.fmu", log=True, interface=interface) as inst:
        inst.start({k: v for k, v in p.items() if not k.startswith("soil.")}, 1.0)
        for position in (0.5, 1.0, 1.99, 2.0):
            inst.set({"q1.position": position, "q2.position": position - 3.0})
            if interface == "cs":
                inst.fmu.doStep(0.0, 1e-3) if position == 0.5 else None
            got = inst.get(variables.query_ground("q1"))
            # the soil rows start at the default preset's values, as WheelTerrain's do
            want = ground.soil_at(position, {**p, **{
                n: v for n, v in presets.load(presets.DEFAULT_PRESET).items()
                if n in ground.SOIL_NAMES}})
            assert got == pytest.approx(list(want), rel=0, abs=0), position
        assert inst.errors() == []


@pytest.mark.parametrize("flavour", FLAVOURS)
@pytest.mark.parametrize("quasi_static", [False, True])
def test_wheel_soil_from_its_ground_inputs_equals_the_same_soil_as_parameters(
        built, flavour, quasi_static):
    """WheelTerrain with soil_from_inputs and another soil on its ground.* inputs gives the
    forces of that soil set as its soil.* parameters, exactly; with the switch off the inputs
    are ignored."""
    other = presets.load("paper-table1")
    soil = {row.name: other[row.name] for row in variables.SOIL_ROWS}
    inputs = {variables.ground_name(k): v for k, v in soil.items()}
    common = {"quasi_static": quasi_static, "sinkage": 0.015, "load": 40.0}
    outputs = ["normal_force", "drawbar_pull", "torque", "contact_sinkage"]
    results = first_steps(built / flavour / "WheelTerrain.fmu", (
        {**common, **soil}, {**common, "soil_from_inputs": True, **inputs},
        {**common, **inputs}), outputs)
    assert results[1] == results[0]
    assert results[2] != results[0]  # switch off: the default soil, not the inputs'
    assert all(math.isfinite(v) for v in results[1])


@pytest.mark.parametrize("flavour", FLAVOURS)
def test_a_ground_input_outside_the_soil_rows_range_is_refused_with_it(built, flavour):
    row = next(r for r in variables.SOIL_ROWS if r.name == "soil.phi")
    with Instance(built / flavour / "WheelTerrain.fmu", log=True) as inst:
        inst.start({"soil_from_inputs": True}, 1.0)
        with pytest.raises(FMICallException):  # refused at set time (fmi2Error)
            inst.set({"ground.phi": row.max + 0.1})
        assert any("ground.phi" in m for m in inst.errors()), inst.errors()
