"""The rover: chassis equations, the in-process system, the steady-state predictions."""

from __future__ import annotations

import math

import numpy as np
import pytest

from wheelterrain import model, presets
from wheelterrain.cosim import rover as rover_system
from wheelterrain.cosim import rover_limits, rover_scenarios
from wheelterrain.model import ground, rover
from wheelterrain.parameters import GRAVITY


@pytest.fixture(scope="module")
def quiet():
    """The default wheel and soil, grouser ripple off: the steady state is an equilibrium."""
    return presets.load("rashid-patch").with_values(rover_scenarios.NO_RIPPLE)


@pytest.fixture(scope="module")
def level(quiet):
    return rover_system.simulate(rover_system.Soil(quiet), {}, stop=20.0)


@pytest.fixture(scope="module")
def level_elastic(quiet):
    """The level run on the elastic soil: every wheel meets virgin soil, and it settles on
    the single-wheel steady states (on the soil with memory a front wheel whose equilibrium
    moves up, once the rear wheels run in its rut and the slip shifts, rises only as its
    imprint relaxes: docs/rover.md)."""
    soil = quiet.with_values({"model.soil_memory": 0})
    return rover_system.simulate(rover_system.Soil(soil), {}, stop=20.0), soil


def test_level_traverse_is_four_single_wheel_steady_states(level_elastic):
    """Each wheel ends where the single-wheel model puts it at that wheel's load and slip."""
    level, quiet = level_elastic
    for w in rover.WHEELS:
        s = {k: v[-1] for k, v in level.wheels[w].items()}
        ref = model.steady_state(quiet, s["normal_force"], s["slip"], "unified")
        assert s["sinkage"] == pytest.approx(ref["sinkage"], rel=1e-3)
        assert s["drawbar_pull"] == pytest.approx(ref["drawbar_pull"], rel=1e-3, abs=1e-6)
        assert s["torque"] == pytest.approx(ref["torque"], rel=1e-3)


def test_level_loads_are_the_moment_balance(level, quiet):
    """The axle loads of the run are those of rover.steady_balance at its slip (the motors'
    reactions and the pulls below the centre of mass shift load off the front)."""
    p = rover.defaults()
    slip = level.wheels["front_left"]["slip"][-1]
    b = rover.steady_balance({w: quiet for w in rover.WHEELS}, p, 0.0, slip)
    for w in rover.WHEELS:
        assert level.wheels[w]["normal_force"][-1] == pytest.approx(b["loads"][w], rel=1e-3)
    total = sum(b["loads"].values())
    assert total == pytest.approx(p["rover.mass"] * p["rover.gravity"], rel=1e-12)


def test_motor_power_is_traction_power_plus_losses(level_elastic):
    """Steady, patch form (T = R_s*H): motor power = pull*V + compaction and bulldozing
    loss (R*V) + slip loss H*(omega*R_s - V), per wheel, to 1e-6."""
    level, quiet = level_elastic
    radius_s = quiet["wheel.radius"] + quiet["model.shear_radius_factor"] * quiet[
        "grouser.height"]
    speed = level.chassis["speed"][-1]
    for w in rover.WHEELS:
        s = {k: v[-1] for k, v in level.wheels[w].items()}
        out = model.contact_forces(quiet, s["sinkage"], s["slip"], slip_definition="unified")
        thrust = out["gross_thrust"]
        motor = s["motor_torque"] * s["wheel_speed"]
        parts = (out["drawbar_pull"] * speed
                 + (out["compaction_resistance"] + out["bulldozing_resistance"]) * speed
                 + thrust * (s["wheel_speed"] * radius_s - speed))
        assert motor == pytest.approx(parts, rel=1e-6)


def test_the_pull_at_the_wheels_sinkage_falls_with_slip_where_the_pressing_rover_grows(quiet):
    """The disturbance that ends the climb on the soil with memory (rover_limits.unstable_cause):
    on Earth, the wheels inheriting their rut's shear, the rover's pull at its wheels'
    steady sinkages rises with slip at 26 deg and falls at 30.5 deg, and the rover linearised
    on the pressing branch (growth_rate) is stable at the one and grows at the other, so a
    disturbance that grows at 30.5 deg is named slip_sinkage; with model.rut_shear 0 the
    pull rises at 30.5 deg too, the rover is stable there, and a disturbance that grew would
    be named stability."""
    p = rover.defaults()
    for values, deg, falls in (({}, 26.0, False), ({}, 30.5, True),
                               ({"model.rut_shear": 0.0}, 30.5, False)):
        terrain = rover_scenarios.terrain_of(quiet.with_values(values))
        slope = math.radians(deg)
        slip = rover_limits.steady_slip(terrain, p, slope)
        balance = rover.steady_balance(terrain, p, slope, slip)
        assert (rover_limits.pull_slope_at_sinkage(balance) < 0) == falls, (values, deg)
        assert (rover_limits.growth_rate(terrain, p, slope, slip)["rate"] > 0) == falls
        assert rover_limits.steady_cause(terrain, p, slope, slip) is None
        named = rover_limits.unstable_cause(terrain, p, slope, slip)
        assert named == ("slip_sinkage" if falls else "stability")
    elastic = rover_scenarios.terrain_of(quiet.with_values({"model.soil_memory": 0}))
    assert rover_limits.unstable_cause(elastic, p, math.radians(30.5)) == "stability"


@pytest.mark.slow
@pytest.mark.parametrize(("gravity", "memory"), [
    ("earth", 0), ("moon", 0), ("earth", 1), ("moon", 1)],
    ids=["earth-elastic-soil", "moon-elastic-soil", "earth-soil-with-memory",
         "moon-soil-with-memory"])
def test_simulated_stall_slope_is_the_predicted_one(quiet, gravity, memory):
    """The slope rises until the rover stalls; the steady-state prediction (traction limit,
    the force balance's slope, and the stability of the steady motion) is within 0.5 deg.
    On the soil with memory each rut keeps the pressure it carried, the imprint relaxes
    toward the soil ahead and each wheel meets the rut averaged over the leading half of its
    reach (ground.met): both climbs hold it. With the rut read at one point the Moon's ramped
    climb stalled 1 deg early (27.29 against 28.33 deg), the cell-by-cell marks of the record
    growing a loop through the ruts; with the rut read from its depth both had held it at an
    early divergence (26.96 against 27.01 deg on Earth, 25.09 against 25.22 deg on the Moon),
    a rut read with the rear wheel's own slip."""
    run = rover_scenarios.run_scenario("slope", quiet.with_values({"model.soil_memory": memory}),
                                    gravity)
    r = run["figures"]
    # the scenario's own step: finer on the Moon, where the one-step-late engines need it
    step = rover_scenarios.FINE_STEP if gravity == "moon" else rover_system.STEP
    assert r["step_s"] == run["step"] == step
    assert np.diff(run["result"].time[:3]) == pytest.approx([step, step])
    assert r["stall_slope_deg"] is not None
    assert r["stall_cause"] in rover_limits.STALL_CAUSES
    assert abs(r["stall_slope_deg"] - r["predicted_stall_slope_deg"]) < 0.5
    assert r["stall_slope_deg"] > 1.0
    rows = r["slip_vs_slope"]  # one row per whole degree reached, the slip rising with it
    assert [row["slope_deg"] for row in rows] == list(range(len(rows)))
    assert len(rows) == int(r["stall_slope_deg"]) + 1
    assert rows[-1]["mean_slip"] > rows[len(rows) // 2]["mean_slip"] > rows[1]["mean_slip"]


@pytest.mark.slow
def test_the_climb_limit_does_not_hang_on_the_rut_record_s_cell(quiet, monkeypatch):
    """Earth's climb limit on the soil with memory (the probe's, :func:`limit_slope`) with the
    rut record's cells 2.5, 5 and 10 mm long: within 0.5 deg (the prediction's tolerance
    against the run; measured 30.09 / 30.23 / 30.26 deg). Each wheel meets the rut averaged
    over the leading half of its reach, so it does not meet the record's cell-by-cell marks;
    read at one point the same limit was 28.86 / 29.53 / 29.97 deg."""
    p = {**rover.defaults(), "rover.gravity": GRAVITY["earth"]}
    terrain = rover_scenarios.terrain_of(quiet)
    defaults = ground.defaults
    limits = []
    for cell in (0.0025, 0.005, 0.01):
        monkeypatch.setattr(ground, "defaults",
                            lambda cell=cell: {**defaults(), "terrain.cell": cell})
        assert rover_system.Soil(quiet).map_values()["terrain.cell"] == cell
        limit = rover_limits.limit_slope(terrain, p, 1)
        assert limit["limit"] == "slip_sinkage", (cell, limit)
        limits.append(math.degrees(limit["slope"]))
    assert max(limits) - min(limits) < 0.5, limits


@pytest.mark.slow
@pytest.mark.parametrize("gravity", ["earth", "moon"])
def test_the_descent_approached_slowly_slides_at_the_predicted_limit(quiet, gravity):
    """The descent scenario tilts at 1 deg/s towards the 20 deg the Rashid rover is specified
    for: not quasi-static, so not a measure of the steady limit. Approached as the climb is
    (:func:`rover_scenarios.approach`: 0.1 deg/s to KNEE_MARGIN before the prediction, then 0.002
    deg/s), ripple-free on the soil with memory, the rover slides (its slip, braking, passes
    SLIDE_SLIP: it moves at ten times its rims' speed) within 0.5 deg of the steady
    prediction, in the slow ramp."""
    p = {**rover.defaults(), "rover.gravity": GRAVITY[gravity]}
    pred = math.degrees(rover_limits.limit_slope(rover_scenarios.terrain_of(quiet), p, -1)["slope"])
    knee = abs(pred) - rover_scenarios.KNEE_MARGIN
    values = {"rover.gravity": p["rover.gravity"], **rover_scenarios.approach(knee, -1),
              "rover.slope_bound": math.radians(30.0)}
    step = rover_scenarios.FINE_STEP if gravity == "moon" else rover_system.STEP

    def slid(last: dict) -> bool:
        return min(last[f"{w}.slip"] for w in rover.WHEELS) <= rover_limits.SLIDE_SLIP

    res = rover_system.simulate(rover_system.Soil(quiet), values,
                                rover_scenarios.approach_stop(knee), step=step, stop_when=slid)
    assert res.left_domain is None
    assert min(v["slip"][-1] for v in res.wheels.values()) <= rover_limits.SLIDE_SLIP
    slide = math.degrees(res.inputs["slope"][-1])
    assert slide < -knee  # past the knee: in the slow ramp
    assert abs(slide - pred) < 0.5, (slide, pred)


def test_the_rear_wheels_run_in_the_front_wheels_ruts(level, quiet):
    """On the soil with memory each wheel leaves a rut at least 95 % of its deepest sinkage,
    and the rear wheels run in the front wheels' ruts: their sinkage, from the original
    surface, is deeper than the rut they meet, and they press the soil less deep below it
    than the front wheels below the surface (the multi-pass effect). The steady balance
    does the same (each rear wheel's soil carries its front wheel's rut; the run's rear wheels
    end 2 % deeper than it at 20 s: a wheel whose equilibrium moves up rises only as its
    imprint relaxes, docs/rover.md)."""
    assert quiet["model.soil_memory"] == 1
    keep = level.time >= 15.0  # the rear wheels reach the front wheels' ruts at ~12 s
    for w in rover.WHEELS:
        rut = level.wheels[w]["rut_left"][keep]
        assert rut.min() >= 0.95 * level.wheels[w]["sinkage"][keep].max()
    for front, rear in rover.TRACKS.values():
        rut = level.wheels[front]["rut_left"][keep].mean()
        z_front = level.wheels[front]["sinkage"][keep].mean()
        z_rear = level.wheels[rear]["sinkage"][keep].mean()
        assert z_rear > rut
        assert z_rear - rut < z_front
    p = rover.defaults()
    slip = level.wheels["front_left"]["slip"][-1]
    b = rover.steady_balance({w: quiet for w in rover.WHEELS}, p, 0.0, slip)
    assert b["terrain"]["rear_left"]["soil.rut_depth"] == b["wheels"]["front_left"]["rut_left"]
    assert b["wheels"]["rear_left"]["sinkage"] > b["wheels"]["front_left"]["rut_left"]


def _pull_per_load(run, wheel, since):
    keep = run.time >= since
    w = run.wheels[wheel]
    return w["drawbar_pull"][keep].mean() / w["normal_force"][keep].mean()


def test_rear_wheels_pull_more_per_newton_with_the_shear_the_rut_remembers(quiet):
    """The multi-pass effect on a level traverse. With the default model.rut_shear = 1 the rear
    wheels, in the front wheels' ruts, count their shear displacement on from the front wheels'
    and pull more per newton of load than the front wheels, in the run (settled from ~25 s)
    and in the steady balance at its slip, the direction of SCM's node law
    (tests/test_multipass_scm.py). With 0 they pull less: the contact from the rut's surface
    is short and mobilises less shear (docs/rover.md)."""
    assert quiet["model.rut_shear"] == 1
    off = rover_system.simulate(rover_system.Soil(quiet.with_values({"model.rut_shear": 0})),
                                {}, stop=20.0)
    for front, rear in rover.TRACKS.values():
        assert _pull_per_load(off, rear, 15.0) < _pull_per_load(off, front, 15.0)
    run = rover_system.simulate(rover_system.Soil(quiet), {}, stop=40.0)
    slip = run.wheels["front_left"]["slip"][-1]
    b = rover.steady_balance({w: quiet for w in rover.WHEELS}, rover.defaults(), 0.0, slip)
    for front, rear in rover.TRACKS.values():
        assert _pull_per_load(run, rear, 25.0) > _pull_per_load(run, front, 25.0)
        steady = {w: b["wheels"][w]["drawbar_pull"] / b["loads"][w] for w in (front, rear)}
        assert steady[rear] > steady[front]
        assert run.wheels[rear]["normal_force"][-1] == pytest.approx(b["loads"][rear], rel=1e-3)


@pytest.mark.slow
def test_a_stall_inside_a_block_of_steps_ends_the_run(quiet):
    """With the rut's shear remembered (the default) the rover stalls on the slope by sliding
    back within a block of the in-process run's steps, further than the rut profile's two
    cells: the run ends at the stall with its cause, it does not fail on the record."""
    run = rover_scenarios.run_scenario("slope", quiet, "earth")
    r = run["figures"]
    assert r["stall_slope_deg"] is not None
    assert r["stall_cause"] in rover_limits.STALL_CAUSES


def test_pull_test_curve_is_four_single_wheel_curves(quiet):
    r = rover_scenarios.run_scenario("pull-test", quiet, "earth")["figures"]
    assert len(r["pull_curve"]) >= 8
    assert r["pull_curve_max_error_n"] < 0.05  # N, of a 30 N curve: the quasi-static lag


@pytest.mark.parametrize("memory", [1, 0], ids=["soil-with-memory", "elastic-soil"])
def test_descent_that_the_wheels_cannot_brake_ends_cleanly(quiet, memory):
    """Beyond what the wheels can brake the run stops where the rover slides (its slip passes
    SLIDE_SLIP: ten times its rims' speed), inside the model's domain (braking runs to the
    locked wheel): no clamped slip, no NaN means. On the 1 deg/s ramp the rover lags its
    steady motion, so it slides no earlier than the prediction, by more than the prediction's
    small disturbance (0.5 deg on the soil with memory, :func:`rover_limits.holds`), and holds
    20 deg only where the prediction does."""
    soil = quiet.with_values({"model.soil_memory": memory})
    r = rover_scenarios.run_scenario("descent", soil, "earth")["figures"]
    assert r["left_domain"] is None
    if r["slide_slope_deg"] is None:
        assert r["predicted_descent_limit_deg"] <= -20
        return
    assert r["slide_slope_deg"] <= r["predicted_descent_limit_deg"] + (0.5 if memory else 0.05)
    assert r["stall_cause"] in rover_limits.STALL_CAUSES
    assert all(w["mean_slip"] is None for w in r["wheels"])  # ended before the window


@pytest.mark.parametrize("gravity", ["earth", "moon"])
def test_locked_wheels_hold_the_rover_where_their_braking_meets_the_weight(quiet, gravity):
    """The soil's own braking limit, whatever the drive: four locked wheels (slip -1) hold the
    rover on every descent down to locked_limit, where their steady braking force equals the
    weight's part along the slope, and no steeper; the speed loops' steady braking (a slip
    between 0 and -1) holds no steeper a slope than that."""
    p = {**rover.defaults(), "rover.gravity": GRAVITY[gravity]}
    terrain = rover_scenarios.terrain_of(quiet)
    locked = rover_limits.locked_limit(terrain, p)
    assert locked is not None
    assert -math.radians(60) < locked < 0
    for slope, holds in ((locked + 0.01, True), (locked - 0.01, False)):
        surplus = rover.steady_balance(terrain, p, slope, rover_limits.LOCKED)["surplus"]
        assert (surplus < 0) == holds, (slope, surplus)
    braking = rover_limits.limit_slope(terrain, p, -1)["slope"]
    assert braking >= locked - 1e-6


def test_the_earth_descent_holds_the_specified_20_deg_over_its_unmeasured_values(quiet):
    """limit_band: the Earth's descent at the default values and at each end of the unmeasured
    values' bands (K_u over its plausible range, the grouser phases aligned, C_f halved and
    doubled, the rut's shear not remembered). Where a run holds the specified 20 deg, the
    prediction puts the soil's braking limit (`traction`) beyond it; where one slides, it
    slides by the soil's braking, beyond 19 deg and short of the slope four locked wheels
    hold. The defaults hold (measured 2026-11-28: predicted 25.3 deg, locked wheels 26.5
    deg); without the rut's shear the rover slides at 19.5 deg (predicted 18.7)."""
    band = rover_scenarios.limit_band("descent", presets.load(presets.DEFAULT_PRESET))
    runs = band["runs"]
    assert [r["variant"] for r in runs] == ["default", *rover_scenarios.BAND_VARIANTS]
    assert runs[0]["limit_deg"] is None
    assert {r["predicted_limit"] for r in runs} == {"traction"}
    for r in runs:
        if r["limit_deg"] is None:
            assert abs(r["predicted_deg"]) > 20.0, r
        else:
            assert r["cause"] == "traction", r
            assert 19.0 < abs(r["limit_deg"]) <= abs(r["locked_limit_deg"]), r
    assert band["without_limit"] == sum(r["limit_deg"] is None for r in runs)
    with pytest.raises(ValueError, match="limit_band runs slope, descent"):
        rover_scenarios.limit_band("level", quiet)


def test_halving_the_step_changes_the_level_means_little(quiet):
    a = rover_system.simulate(rover_system.Soil(quiet), {}, stop=10.0, step=2e-3)
    b = rover_system.simulate(rover_system.Soil(quiet), {}, stop=10.0, step=1e-3, block=100)
    for w in rover.WHEELS:
        for key in ("sinkage", "slip", "normal_force"):
            assert a.wheels[w][key][-1] == pytest.approx(b.wheels[w][key][-1], rel=1e-3)


def test_soft_patch_passes_under_the_front_then_the_rear(quiet):
    r = rover_scenarios.run_scenario("soft-patch", quiet, "earth")["result"]
    front, rear = r.wheels["front_left"]["sinkage"], r.wheels["rear_left"]["sinkage"]

    def enters(z):  # the first step half-way from the settled sinkage to the deepest
        settled = z[(r.time > 3) & (r.time < 6)].mean()
        return r.time[np.argmax(z >= (settled + z.max()) / 2)]

    t_front, t_rear = enters(front), enters(rear)
    base = rover.defaults()["rover.wheelbase"]
    speed = float(np.median(r.chassis["speed"]))
    assert t_rear - t_front == pytest.approx(base / speed, rel=0.15)
    settled = front[(r.time > 3) & (r.time < 6)].mean()  # before the patch (~10 s)
    assert front.max() > settled * 1.2  # it sinks deeper in the looser soil


def test_chassis_static_loads_split_by_the_centre_of_mass():
    p = {**rover.defaults(), "rover.cg_forward": 0.05}
    loads = rover.static_axle_loads(p)
    weight = p["rover.mass"] * p["rover.gravity"]
    assert sum(loads.values()) == pytest.approx(weight)
    assert loads["front_left"] > loads["rear_left"]
    uphill = rover.static_axle_loads(rover.defaults(), math.radians(10))
    assert uphill["rear_left"] > uphill["front_left"]  # load moves to the rear uphill


def test_cli_rover_json_contract(tmp_path):
    import json
    import subprocess
    import sys

    run = subprocess.run([sys.executable, "-m", "wheelterrain.cli", "rover", "--scenario",
                          "level", "--out", str(tmp_path), "--json"], capture_output=True,
                         text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    # in a log (standard error not a terminal) the progress is lines, not a bar's label alone
    assert run.stderr.splitlines()[:2] == ["simulating level ...", "simulating level: 100 %"]
    out = json.loads(run.stdout)
    for key in ("scenario", "gravity", "engine", "simulated_time_s", "wall_time_s",
                "real_time_factor", "wheels"):
        assert key in out
    assert [w["name"] for w in out["wheels"]] == list(rover.WHEELS)
    for w in out["wheels"]:
        assert {"mean_slip", "mean_sinkage", "mean_normal_force", "mean_drawbar_pull"} <= set(w)
    assert (tmp_path / "level-earth.png").is_file()
    header = (tmp_path / "level-earth.csv").read_text().splitlines()[0]
    assert "front_left.sinkage [m]" in header
    bad = subprocess.run([sys.executable, "-m", "wheelterrain.cli", "rover", "--scenario",
                          "level", "--set", "rover.mass=-3", "--out", str(tmp_path)],
                         capture_output=True, text=True, timeout=600)
    assert bad.returncode == 2
    assert bad.stderr.startswith("error: parameter rover.mass")


def test_cli_rover_band_reports_the_descents_limit_over_its_unmeasured_values(tmp_path):
    """`rover --scenario descent --band --json`: the figures gain limit_band, the run at the
    defaults first and the same limit as the scenario's own run; --band where it cannot run
    (a scenario without a limit, another engine, --step) is one line, exit 2, before any work."""
    import json
    import subprocess
    import sys

    run = subprocess.run([sys.executable, "-m", "wheelterrain.cli", "rover", "--scenario",
                          "descent", "--band", "--out", str(tmp_path), "--json"],
                         capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, run.stderr
    out = json.loads(run.stdout)
    band = out["limit_band"]
    assert [r["variant"] for r in band["runs"]] == ["default", *rover_scenarios.BAND_VARIANTS]
    assert band["runs"][0]["limit_deg"] == out["slide_slope_deg"]
    assert band["without_limit"] == sum(r["limit_deg"] is None for r in band["runs"])
    for args, named in ((["--scenario", "level"], "--scenario level"),
                        (["--scenario", "slope", "--engine", "ecos"], "--engine ecos"),
                        (["--scenario", "slope", "--step", "0.0005"], "--step")):
        bad = subprocess.run([sys.executable, "-m", "wheelterrain.cli", "rover", "--band",
                              *args, "--out", str(tmp_path / "no")],
                             capture_output=True, text=True, timeout=600)
        assert bad.returncode == 2
        assert bad.stderr.startswith("error: --band runs slope and descent")
        assert named in bad.stderr
        assert not (tmp_path / "no").exists()
