"""Traction control on the rover: the slip NMPC per wheel (control.rover_mpc) against the
in-process rover, and the warm start's wheel angle across a wrapped turn."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner

from wheelterrain import presets
from wheelterrain.cli import main
from wheelterrain.control import mpc, rover_mpc
from wheelterrain.cosim import rover as rover_system
from wheelterrain.cosim import rover_scenarios
from wheelterrain.model import rover

STOP = 7.0  # s: 2 s on the speed loops, then 5 s of control across the patch


@pytest.fixture(scope="module")
def patched():
    """A looser soil (the soft-patch scenario's) under the front axle from 2.5 s to 5.5 s of
    a speed-loop run, so the controllers meet both of its edges."""
    terrain = presets.load(presets.DEFAULT_PRESET)
    p = rover.defaults()
    probe = rover_system.simulate(rover_system.Soil(terrain), {}, STOP)
    x = probe.chassis["position"]
    edges = [rover.wheel_position(p, float(np.interp(t, probe.time, x)), "front_left")
             for t in (2.5, 5.5)]
    soft = {k: terrain[k] * f for k, f in rover_scenarios.SOFT.items()}
    return rover_system.Soil(terrain, soft, edges[0], edges[1])


@pytest.fixture(scope="module")
def runs(patched):
    p = rover.defaults()
    loops = rover_system.simulate(patched, {}, STOP)
    control = rover_mpc.run(patched, {}, STOP)
    return {"speed": (loops, rover_scenarios.tracking(loops, patched, p)),
            "mpc": (control, rover_scenarios.tracking(control.result, patched, p))}


def test_the_controllers_hold_the_speed_that_the_speed_loops_let_drop(runs):
    """The speed term does its job: across the patch the rover's speed strays less from its
    steady level speed under the NMPC than under the speed loops (10.8x less, measured
    2026-11-28), every solve succeeds, and the run stays in the model's domain."""
    control, score = runs["mpc"]
    _, loops = runs["speed"]
    assert control.failures == 0
    assert control.result.left_domain is None
    assert control.solve_times.size == 4 * round((STOP - rover_mpc.SETTLE) / 0.02)
    assert score["speed_rms_relative"] < 0.5 * loops["speed_rms_relative"]
    assert math.isfinite(score["slip_rms"])


def test_the_controllers_hold_the_speed_four_times_better_than_the_speed_loops(runs):
    """A speed RMS below a quarter of the speed loops'. Measured 2026-11-28: 0.57 % against
    6.1 % (0.092x). The NMPC's own figure is what it was before the rear wheels inherited the
    front wheels' shear (0.57 %); the speed loops' grew from 2.0 % (0.285x then, this test a
    strict expected failure): with the rut's shear remembered the rear wheels pull harder in
    the ruts and the loops' rover brakes its front wheels against them, so it strays further
    across the patch. The NMPC's prediction still lacks the soil's memory (docs/mpc.md)."""
    _, score = runs["mpc"]
    _, loops = runs["speed"]
    assert score["speed_rms_relative"] < 0.25 * loops["speed_rms_relative"]


def test_the_controllers_put_the_patch_s_extra_slip_on_the_wheels_on_it(runs, patched):
    """What holding the speed costs (README): on the patch the front wheels' controllers drive
    them harder (slip well above the rear wheels'), where the speed loops give every wheel the
    same slip (one chassis speed, one wheel speed)."""
    p = rover.defaults()

    def on_patch(res):
        x = np.array([rover.wheel_position(p, v, "front_left") for v in res.chassis["position"]])
        return (x >= patched.start + 0.005) & (x < patched.end) & (res.time >= rover_mpc.SETTLE)

    control = runs["mpc"][0].result
    front, rear = (control.wheels[w]["slip"][on_patch(control)] for w in
                   ("front_left", "rear_left"))
    assert np.mean(front) - np.mean(rear) > 0.01
    loops = runs["speed"][0]
    front, rear = (loops.wheels[w]["slip"][on_patch(loops)] for w in ("front_left", "rear_left"))
    assert abs(np.mean(front) - np.mean(rear)) < 1e-3


def test_a_wrapped_wheel_angle_does_not_jolt_the_warm_start():
    """The state's wheel angle is wrapped to one turn; the warm start's angles are moved by the
    same whole turns. Passing the angle one turn on gives the same command to rounding (the
    ripple is periodic); before, one real-time iteration linearised the ripple across 2*pi and
    commanded 1.02 rad/s instead of 0.60 (the rover after 10.5 s)."""
    p = rover.defaults()
    rig_values = rover_mpc.wheel_rig(p, "front_left")
    settings = mpc.Settings(solver="rti", horizon=10, speed_weight=1.0)
    terrain = presets.load(presets.DEFAULT_PRESET).vector()
    x = np.array([0.0074, 0.0, 0.6, 1e-3, 0.032, 6.2])
    commands = []
    for shift in (0.0, 2 * math.pi):
        controller = mpc.Controller(settings, rig_values)
        controller.solve(x, terrain, -0.064, 0.6, 0.032)
        later = x.copy()
        later[5] += 0.6 * settings.interval - shift  # the next state, wrapped by `shift`
        commands.append(controller.solve(later, terrain, -0.064, 0.6, 0.032).command)
    assert commands[1] == pytest.approx(commands[0], rel=1e-9)


def test_speed_weight_is_a_checked_setting():
    with pytest.raises(mpc.MPCError, match=r"speed_weight = -1"):
        mpc.Settings(speed_weight=-1).check()
    with pytest.raises(mpc.MPCError, match=r"0 with the efficiency objective"):
        mpc.Settings(objective="efficiency", speed_weight=1.0).check()


@pytest.mark.parametrize(("args", "message"), [
    (["--scenario", "slope"], "runs level and soft-patch"),
    (["--scenario", "level", "--engine", "fmus"], "runs with --engine in-process"),
    (["--scenario", "level", "--step", "5e-4"], "rover's step"),
])
def test_cli_refuses_what_the_controllers_do_not_run(tmp_path, args, message):
    run = CliRunner().invoke(main, ["rover", *args, "--controller", "mpc", "--out",
                                    str(tmp_path / "out")])
    assert run.exit_code == 2
    assert message in run.output
    assert not (tmp_path / "out").exists()


@pytest.mark.slow
def test_cli_mpc_json_reports_the_controllers_and_the_score(tmp_path):
    run = CliRunner().invoke(main, ["rover", "--scenario", "level", "--controller", "mpc",
                                    "--out", str(tmp_path), "--json", str(tmp_path / "f.json")])
    assert run.exit_code == 0, run.output
    figures = json.loads((tmp_path / "f.json").read_text())
    assert figures["controller"] == "mpc"
    assert figures["failed_solves"] == 0
    assert figures["solves"] > 0
    for key in ("slip_rms", "speed_rms_relative", "slip_reference", "speed_reference",
                "solve_time_median_s"):
        assert math.isfinite(figures[key]), key
    assert (tmp_path / "level-earth-mpc.png").is_file()
