"""RoverChassis.fmu in both flavours, the rover's FMU master, Rover.ssp in libcosim and ecos,
and a soil map along the path through Terrain.fmu."""

from __future__ import annotations

import shutil

import numpy as np
import pytest
from fmpy import simulate_fmu
from fmpy.validation import validate_fmu

from wheelterrain import compiled as native
from wheelterrain import presets
from wheelterrain.cosim import rover as rover_system
from wheelterrain.cosim import rover_fmus, rover_scenarios, ssp
from wheelterrain.errors import UsageError
from wheelterrain.model import rover

pytestmark = pytest.mark.skipif(native.compiler() is None, reason="needs a C compiler")
STOP = 4.0  # s: the drop into the soil and the settling, about 4000 steps


@pytest.fixture(scope="module")
def built(built_root):
    return built_root  # both flavours, built once per test run (conftest.py)


@pytest.fixture(scope="module")
def terrain():
    return presets.load(presets.DEFAULT_PRESET)


@pytest.fixture(scope="module")
def in_process(terrain):
    return rover_system.simulate(rover_system.Soil(terrain), {}, STOP)


@pytest.mark.parametrize("path", ["pythonfmu/RoverChassis.fmu", "native/RoverChassis.fmu",
                                  "native/fmi3/RoverChassis.fmu"])
def test_rover_fmus_validate(built, path):
    assert validate_fmu(str(built / path)) == []


@pytest.mark.parametrize("flavour", ["pythonfmu", "native"])
def test_our_master_gives_the_in_process_rover_bit_for_bit(built, terrain, in_process,
                                                           flavour):
    """Same Functions, same coupling: the FMU route and the in-process one are the same
    numbers (the pythonfmu WheelTerrain runs the CasADi VM or the same C: rounding only)."""
    res = rover_fmus.simulate(built / flavour, rover_system.Soil(terrain), {}, STOP)
    assert len(res.time) == len(in_process.time)
    tol = 0.0 if flavour == "native" else 1e-9
    for w in rover.WHEELS:
        for key in ("sinkage", "slip", "normal_force", "drawbar_pull", "motor_torque"):
            a, b = res.wheels[w][key], in_process.wheels[w][key]
            np.testing.assert_allclose(a, b, rtol=tol, atol=tol * 1e-3, err_msg=f"{w}.{key}")


def _means(res, start: float = 2.0) -> dict:
    keep = res.time >= start
    return {f"{w}.{k}": float(np.mean(v[keep])) for w, d in res.wheels.items()
            for k, v in d.items() if k in ("normal_force", "sinkage", "slip", "drawbar_pull")}


def _assert_same_means(ours, theirs) -> None:
    """Both runs to the end, every wheel's mean slip, sinkage, load and pull from 2 s on within
    1e-3 relative (a pull that averages to ~0 on level ground judged on the wheel's normal
    force): the measure of the README's engine table (rover.difference)."""
    d = rover_scenarios.difference(ours, theirs, 2.0)
    assert d["window"][1] > STOP - 0.01, d
    assert d["worst"] <= 1e-3, d


def _skip_unless_installed(engine: str) -> None:
    missing = ssp.engine_missing(engine)
    if missing:
        pytest.skip(missing)
    if engine == "ecos" and not shutil.which("ldconfig"):
        pytest.skip("ecos needs its runtime (libtbb)")


@pytest.mark.parametrize("engine", ["libcosim", "ecos", "omsimulator", "fmpy-ssp"])
def test_rover_ssp_runs_unchanged_in_other_engines_with_the_same_means(built, terrain,
                                                                        in_process, engine):
    """libcosim, ecos, OMSimulator and fmpy's own SSP runner (fmpy.ssp) run Rover.ssp as
    written."""
    _skip_unless_installed(engine)
    res = rover_fmus.simulate_ssp(engine, built / "native", "level",
                                  rover_system.Soil(terrain), {}, STOP)
    _assert_same_means(in_process, res)


@pytest.mark.parametrize("engine", ["libcosim", "ecos", "omsimulator"])
def test_a_ramp_in_the_chassis_profile_runs_alike_in_every_engine(built, terrain, engine):
    """The scenario's ramps are the chassis' input profile, so an SSP carries them: a towing
    force rising at 0.05 N/s and the slope at 0.1 deg/s after 1 s (the pull test's and the
    slope scenario's rates) give the in-process means in other engines."""
    _skip_unless_installed(engine)
    values = {"rover.towing_rate": 0.05, "rover.ramp_time": 1.0,
              "rover.slope_rate_after": np.radians(0.1)}
    soil = rover_system.Soil(terrain)
    ours = rover_system.simulate(soil, values, STOP)
    theirs = rover_fmus.simulate_ssp(engine, built / "native", "ramp", soil, values, STOP)
    assert theirs.inputs["towing_force"][-1] == pytest.approx(0.05 * STOP, rel=1e-3)
    assert theirs.inputs["slope"][-1] == pytest.approx(np.radians(0.1 * (STOP - 1.0)),
                                                       rel=1e-3)
    _assert_same_means(ours, theirs)


def _patched(terrain, in_process) -> rover_system.Soil:
    """A looser soil from where the front axle is at 1 s to where it is at 3 s of the short
    run: the front wheels cross both edges of the patch within it."""
    p = rover.defaults()
    x = in_process.chassis["position"]
    front = [rover.wheel_position(p, float(np.interp(t, in_process.time, x)), "front_left")
             for t in (1.0, 3.0)]
    assert front[1] - front[0] > 0.05  # m: the crossing is not a formality
    soft = {k: terrain[k] * f for k, f in rover_scenarios.SOFT.items()}
    return rover_system.Soil(terrain, soft, front[0], front[1])


@pytest.mark.parametrize("flavour", ["pythonfmu", "native"])
def test_a_soil_map_runs_through_terrain_fmus_as_in_process(built, terrain, in_process,
                                                            flavour):
    """Soil that changes along the path: each wheel's Terrain.fmu answers at the wheel's
    position, the wheels take their soil from it (soil_from_inputs). Our master gives the
    in-process rover (the map evaluated at every step inside the stepped system) to rounding,
    and the patch does change the run."""
    soil = _patched(terrain, in_process)
    ours = rover_system.simulate(soil, {}, STOP)
    res = rover_fmus.simulate(built / flavour, soil, {}, STOP)
    tol = 0.0 if flavour == "native" else 1e-9
    for w in rover.WHEELS:
        for key in ("sinkage", "slip", "normal_force", "drawbar_pull"):
            np.testing.assert_allclose(res.wheels[w][key], ours.wheels[w][key], rtol=tol,
                                       atol=tol * 1e-3, err_msg=f"{w}.{key}")
    change = np.max(np.abs(ours.wheels["front_left"]["sinkage"]
                           - in_process.wheels["front_left"]["sinkage"]))
    assert change > 1e-4  # m: the looser soil lets the front wheels sink deeper


@pytest.mark.parametrize("engine", ["libcosim", "ecos", "omsimulator"])
def test_a_soil_map_in_rover_ssp_gives_the_same_means_in_other_engines(built, terrain,
                                                                       in_process, engine):
    """Rover.ssp with four Terrain.fmu (the soil map's query points) runs unchanged in libcosim,
    ecos and OMSimulator, with the in-process means within 1e-3. libcosim and ecos see the soil
    two steps late and hand the forces over one step late: where the front wheels drop into
    the patch, the rear wheels' load swings 16.6-32.4 N in libcosim at 1 ms against 23.1-26.7 N
    in process, and the rear soil remembers the peak (rear sinkage 4.8e-3 off, measured
    2026-11-28, since the chassis counts the pitch rate in its axle and centre-of-mass
    velocities); at 0.5 ms 26.9 N at most, as in process. So libcosim runs at 0.5 ms here,
    both sides, and ecos, whose lag costs more where the front wheels leave the patch with
    the imprint relaxing toward the soil ahead, at 0.125 ms: its worst difference
    (front_right.normal_force) halves with the step, 2.5e-3, 1.26e-3, 6.3e-4 at 0.5, 0.25,
    0.125 ms (libcosim 2.6e-4, 1.1e-4, 5.4e-5; measured 2026-11-29), the first-order error of
    a one-step-late coupling, not a different answer (docs/rover.md, engines)."""
    _skip_unless_installed(engine)
    soil = _patched(terrain, in_process)
    step = {"omsimulator": 1e-3, "ecos": 1.25e-4}.get(engine, 5e-4)
    _assert_same_means(rover_system.simulate(soil, {}, STOP, step=step, block=round(0.1 / step)),
                       rover_fmus.simulate_ssp(engine, built / "native", "soft-patch", soil,
                                               {}, STOP, step=step))


@pytest.mark.parametrize("engine", ["libcosim", "ecos"])
def test_halving_the_step_shrinks_what_a_one_step_late_engine_differs_by(built, terrain,
                                                                         engine):
    """libcosim and ecos hand each output over one step late (Jacobi), our master chassis
    first (Gauss-Seidel). At 1 ms the level means differ by ~1e-4 relative; at 0.5 ms by
    less (measured: libcosim 1.3e-4 -> 6.7e-5, ecos 6.8e-5 -> 4.9e-5; at 2 ms the bounce
    grows there, 3 %)."""
    _skip_unless_installed(engine)
    soil = rover_system.Soil(terrain)
    worst = {}
    for h in (1e-3, 5e-4):
        ours = _means(rover_system.simulate(soil, {}, STOP, step=h, block=round(0.1 / h)))
        theirs = _means(rover_fmus.simulate_ssp(engine, built / "native", "level", soil, {},
                                                STOP, step=h))
        worst[h] = max(abs(theirs[k] - v) / abs(v) for k, v in ours.items()
                       if "pull" not in k)
    assert worst[1e-3] <= 1e-3
    assert worst[5e-4] < worst[1e-3]


@pytest.mark.parametrize("engine", ["libcosim", "ecos", "omsimulator"])
def test_an_engine_s_run_ends_where_a_wheel_leaves_the_model_s_domain(built, terrain, engine,
                                                                      tmp_path):
    """A climb steeper than the wheels can take: the rover stops and rolls back, its axles move
    backward at 5.84 s and the WheelTerrains refuse the step (fmi2Discard). libcosim then
    stepped again from the same time, which the FMUs that had stepped refused, at every step
    to the end (a slope run logged 84 MB of errors); now the run ends there. ecos and
    OMSimulator go on with the refusing FMU's outputs frozen; the record is cut there. Every
    engine's record ends within a few steps of the in-process one's, with the reason: 10 ms
    (measured 2026-11-28: ecos 6 ms after in process; the axles start backward slowly, so the
    one-step-late engines' small differences move that moment by steps, where a slip passing
    1 moved it by less than 5 ms)."""
    _skip_unless_installed(engine)
    values = {"rover.ramp_time": 1.0, "rover.slope_rate_after": np.radians(5.0),
              "rover.slope_bound": np.radians(40.0)}
    soil = rover_system.Soil(terrain)
    ours = rover_system.simulate(soil, values, 8.0)
    theirs = rover_fmus.simulate_ssp(engine, built / "native", "ramp", soil, values, 8.0)
    assert ours.left_domain
    assert "the rover moves backward" in ours.left_domain
    assert theirs.left_domain
    assert 5.0 < ours.time[-1] < 7.0
    assert abs(theirs.time[-1] - ours.time[-1]) <= 1e-2, (theirs.time[-1], ours.time[-1])
    for w in rover.WHEELS:
        assert np.all(np.abs(theirs.wheels[w]["slip"]) <= 1.0)
    if engine == "libcosim":  # the engine itself stops (before, it ran on to the end)
        path = rover_fmus.write_ssp(tmp_path / "Rover.ssp", built / "native", "ramp", soil,
                                    values, 8.0)
        raw = ssp.simulate_with_libcosim(path, 8.0, 1e-3, ("front_left.slip",))
        assert raw["time"][-1] < 7.0
    if engine == "ecos":  # stopped where it is asked to (it would go on to 6 s)
        path = rover_fmus.write_ssp(tmp_path / "Rover.ssp", built / "native", "ramp", soil,
                                    values, 6.0)
        asked = []

        def go_on(get) -> bool:
            asked.append(get("chassis::speed"))
            return len(asked) < 2

        ssp.simulate_with_ecos(path, "ramp", 6.0, 1e-3, tmp_path / "ecos.csv",
                               ("chassis::speed",), go_on)
        rows = ssp.read_csv_columns(tmp_path / "ecos.csv", ("time",))[0]
        assert len(asked) == 2
        assert all(np.isfinite(asked))
        assert rows[-1] == pytest.approx(2.0, abs=1.5e-3)


@pytest.mark.slow
@pytest.mark.parametrize("engine", ["libcosim", "ecos"])
def test_a_whole_moon_stall_scenario_agrees_in_the_one_step_late_engines(built, terrain,
                                                                        engine):
    """A whole stall scenario at its own step: the Moon's descent (the braking speed loops
    hold the rover to the end of the tilt and it slides at 20.00 deg, 31.9 s, 0.25 ms; before
    the rut's shear was remembered by default, at 15.08 deg, 25 s). Its Rover-descent.ssp in
    libcosim and ecos gives the in-process means within 1e-3 over the whole run and the slide
    within 0.01 deg (measured 2026-11-28 before that change: 15.082025 against 15.082000
    deg). The slide is read at the first step
    a wheel's slip passes SLIDE_SLIP in every engine: read at the record's end, the in-process
    run (which checks its stop condition once a block of 100 steps) put it 18 ms later."""
    _skip_unless_installed(engine)
    ref = rover_scenarios.run_scenario("descent", terrain, "moon")
    run = rover_scenarios.run_scenario("descent", terrain, "moon",
                                    engine=rover_fmus.runner(engine, built / "native",
                                                             "descent"))
    assert run["figures"]["step_s"] == ref["figures"]["step_s"] == rover_scenarios.FINE_STEP
    d = rover_scenarios.difference(ref["result"], run["result"],
                                rover_scenarios.scenarios("moon")["descent"].settle)
    assert d["window"][1] > 15.0  # compared up to the slide
    assert d["worst"] <= 1e-3, d
    assert run["figures"]["slide_slope_deg"] == pytest.approx(
        ref["figures"]["slide_slope_deg"], abs=0.01)


@pytest.mark.slow
def test_earth_s_stall_in_a_one_step_late_engine_agrees_with_ours_at_both_steps(built,
                                                                               terrain):
    """With the soil's memory a wheel that lifts meets a stiff elastic line, handed over one
    step late by ecos. Since the climb ends in a divergence (the rear wheels unloading, 0 Hz)
    rather than the stiff line's oscillation, the one-step delay no longer stalls it early:
    measured 2026-11-28, in process / ecos 25.414 / 25.468 deg at 1 ms and 25.717 / 25.490 deg
    at 0.5 ms. The stall itself moves 0.3 deg in process when the step halves (the run meets
    the divergence at a trough of the grouser ripple), so the engines are held to 0.5 deg of
    each other at each step, and the means over the window both runs cover to 1e-3 (measured
    4.2e-5 and 7.4e-5). Before the rut's shear was remembered, ecos stalled 4.6 deg early at
    1 ms and the gap halved with the step (docs/rover.md)."""
    _skip_unless_installed("ecos")
    for h in (1e-3, 5e-4):
        ref = rover_scenarios.run_scenario("slope", terrain, "earth", step=h)
        run = rover_scenarios.run_scenario("slope", terrain, "earth", step=h,
                                        engine=rover_fmus.runner("ecos", built / "native",
                                                                 "slope"))
        assert run["figures"]["step_s"] == ref["figures"]["step_s"] == h
        d = rover_scenarios.difference(ref["result"], run["result"],
                                    rover_scenarios.scenarios("earth")["slope"].settle)
        assert d["worst"] <= 1e-3, d
        gap = ref["figures"]["stall_slope_deg"] - run["figures"]["stall_slope_deg"]
        assert abs(gap) <= 0.5, (h, gap)


def test_fmpy_ssp_runner_refuses_a_soil_map_with_the_reason(built, terrain, in_process):
    """fmpy.ssp starts every connection at 0, outside the ground.* inputs' ranges: refused
    before anything runs, with that reason."""
    with pytest.raises(UsageError, match="sets every connected input to 0"):
        rover_fmus.simulate_ssp("fmpy-ssp", built / "native", "soft-patch",
                                _patched(terrain, in_process), {}, STOP)


@pytest.mark.parametrize("scenario", rover_scenarios.LIMIT_SCENARIOS)
def test_fmpy_ssp_runner_refuses_a_scenario_that_ends_at_a_limit_before_running(built, terrain,
                                                                                scenario):
    """slope, descent and pull-test end at a step a wheel refuses, where fmpy.ssp raises and
    returns nothing: it ran the whole simulation (219 s quiet, > 900 s loaded) before
    failing, with another message. Refused before anything runs now."""
    with pytest.raises(UsageError, match=r"fmpy's SSP runner cannot run"):
        rover_fmus.simulate_ssp("fmpy-ssp", built / "native", scenario,
                                rover_system.Soil(terrain), {}, 0.05)


def test_model_exchange_agrees_with_co_simulation(built):
    """The native RoverChassis alone under constant forces: the co-simulation steps (first
    order) converge to what CVode makes of the model-exchange interface, their error halving
    with the step."""
    forces = {f"{w}.{n}": v for w in rover.WHEELS
              for n, v in (("normal_force", 24.0), ("drawbar_pull", 1.0), ("torque", 0.1))}
    out = ["speed", "heave", "pitch", "front_left.wheel_speed"]
    path = str(built / "native" / "RoverChassis.fmu")
    me = simulate_fmu(path, fmi_type="ModelExchange", stop_time=1.0, output_interval=1e-3,
                      start_values=forces, output=out, relative_tolerance=1e-10)
    # s, a time on both grids. These forces do not balance the chassis: it tips over (pitch
    # -0.2 rad at 0.3 s, -5 rad at 0.9 s, where the heave of the axle line passes through 0 and
    # no relative error means anything)
    at = 0.3

    def value(r, n):
        return float(np.interp(at, r["time"], r[n]))

    errors = []
    for h in (1e-3, 5e-4):
        cs = simulate_fmu(path, stop_time=1.0, step_size=h, output_interval=h,
                          start_values=forces, output=out)
        errors.append({n: abs(value(cs, n) - value(me, n)) for n in out})
    for n in out:
        scale = max(abs(value(me, n)), 1e-9)
        assert errors[1][n] <= 1e-2 * scale, (n, errors)
        if errors[0][n] > 1e-9 * scale:  # not exact already: first order, the error halves
            assert errors[1][n] < 0.6 * errors[0][n], (n, errors)


def test_an_unconnected_rover_falls_out_of_its_range_and_is_refused(built):
    """Without soil the chassis free-falls; once the heave leaves its range the next step is
    refused with the reason, in both flavours (no crash, no value past the range)."""
    for flavour in ("pythonfmu", "native"):
        # the wheels' loads start at the static loads (the FMU stands alone): no soil is 0
        no_soil = {f"{w}.normal_force": 0.0 for w in rover.WHEELS}
        r = simulate_fmu(str(built / flavour / "RoverChassis.fmu"), stop_time=2.0,
                         step_size=1e-3, output=["heave"], start_values=no_soil)
        assert r["time"][-1] < 0.5  # g*t**2/2 = 1 m at 0.45 s: the run ends there
        assert np.all(np.abs(r["heave"]) <= 1.0)


@pytest.mark.parametrize("scenario", list(rover_scenarios.scenarios()))
def test_ecos_runs_every_rover_ssp_on_the_pythonfmu_fmus_as_on_the_native_ones(built, terrain,
                                                                              scenario):
    """Each Rover SSP holds four instances of WheelTerrain and two of Terrain. ecos unloads an
    FMU's library between two instances of it: on the pythonfmu FMUs the outputs froze at
    0.565 s, the rear wheels read 156 N instead of 24.5 N, then SIGSEGV (the guard's exit
    handler freed a live instance). The first 0.5 s of each scenario's SSP, in ecos on both
    flavours: the same record to rounding (the pythonfmu WheelTerrain runs the same C)."""
    _skip_unless_installed("ecos")
    sc = rover_scenarios.scenarios()[scenario]
    soil = rover_scenarios.scenario_soil(scenario, terrain)
    runs = {flavour: rover_fmus.simulate_ssp("ecos", built / flavour, scenario, soil,
                                             sc.profile, 0.5)
            for flavour in ("pythonfmu", "native")}
    py, nat = runs["pythonfmu"], runs["native"]
    assert py.left_domain is None
    assert nat.left_domain is None
    assert py.time.size == nat.time.size == 501  # t = 0 and each of the 500 steps
    for w in rover.WHEELS:
        for key, values in nat.wheels[w].items():
            np.testing.assert_allclose(py.wheels[w][key], values, rtol=1e-9,
                                       atol=1e-9 * max(1.0, float(np.max(np.abs(values)))),
                                       err_msg=f"{scenario}: {w}.{key}")


ECOS_UNDER = """
import sys
from pathlib import Path
from wheelterrain import presets
from wheelterrain.cosim import rover as engine, rover_fmus
res = rover_fmus.simulate_ssp("ecos", Path(sys.argv[1]), "level",
                              engine.Soil(presets.load(presets.DEFAULT_PRESET)), {}, 0.2)
print(res.time.size)
"""


def test_ecos_under_a_temporary_folder_with_a_space_prints_no_chmod_lines(built, tmp_path):
    """ecos runs chmod on what it unzips through a shell, the path unquoted: with a space in
    the temporary folder it printed 35 'chmod: cannot access' lines a run. Its scratch folder
    is taken where the path has no white space."""
    import os
    import subprocess
    import sys

    _skip_unless_installed("ecos")
    spaced = tmp_path / "a b"
    spaced.mkdir()
    run = subprocess.run([sys.executable, "-c", ECOS_UNDER, str(built / "native")],
                         capture_output=True, text=True, timeout=300, check=False,
                         env={**os.environ, "TMPDIR": str(spaced)})
    assert run.returncode == 0, run.stderr[-2000:]
    assert run.stdout.split() == ["201"]
    assert "chmod" not in run.stdout + run.stderr
