"""Slip-tracking NMPC on the full wheel-terrain model: a script to copy from.

    python casadi_models/slip_mpc.py [--plant casadi|fmu] [--reference 0.25] [--seconds 3]

Builds the controller (wheelterrain.control.mpc: the FMUs' own terrain Function closed by the rig's
equations, backward Euler over 30 x 20 ms, Gauss-Newton SQP with qrqp), then runs it in closed
loop against the in-process plant (or the two FMUs, after `wheelterrain build`), printing slip,
command and solve time as it goes. Swap in your own rig parameters, limits or objective.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from wheelterrain import presets
from wheelterrain.control import closed_loop, mpc
from wheelterrain.model import rig
from wheelterrain.parameters import NAMES


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--plant", choices=("casadi", "fmu"), default="casadi")
    parser.add_argument("--reference", type=float, default=0.25, help="traction slip to hold")
    parser.add_argument("--seconds", type=float, default=3.0)
    parser.add_argument("--fmu-dir", default="build")
    args = parser.parse_args()

    soil = presets.load(presets.DEFAULT_PRESET)  # the default Rashid wheel on its soil
    scenario = closed_loop.Scenario("script", "a constant slip reference", args.seconds,
                                    ((0.0, args.reference),))
    p_rig = closed_loop.rig_parameters(soil, scenario)  # the rig with rig.drive = speed command
    settings = mpc.Settings(horizon=30, interval=0.02, solver="sqpmethod",
                            torque_limit=3.0, power_limit=5.0, sinkage_limit=0.04)

    # the controller alone: one solve from a settled state, to see what it returns
    controller = mpc.Controller(settings, p_rig)
    p_terrain = np.array([soil[name] for name in NAMES])
    omega, speed = rig.references(p_rig)
    x_now = np.array([0.0144, 0.0, omega, 0.0027, speed, 0.0])  # mpc.MPC_STATES
    step = controller.solve(x_now, p_terrain, args.reference, omega)
    print(f"one solve: command {step.command:.4f} rad/s in {1e3 * step.solve_time:.1f} ms, "
          f"{step.iterations} SQP iterations ({step.status})")

    # the closed loop the library runs (settling, then one solve per 20 ms)
    result = closed_loop.run(scenario, soil, args.plant, settings, Path(args.fmu_dir))
    figures = result.figures(scenario)
    s = result.series
    for t in np.arange(0.0, args.seconds, 0.5):
        k = int(np.searchsorted(s["time"], t))
        print(f"t {s['time'][k]:4.1f} s  slip {s['slip'][k]:.5f}  command {s['command'][k]:.4f} "
              f"rad/s  motor torque {s['motor_torque'][k]:.3f} N.m  sinkage "
              f"{1e3 * s['sinkage'][k]:.2f} mm")
    print(f"slip RMS error after {scenario.score_after:g} s: {figures['slip_rms_error']:.2e}; "
          f"solve time median {1e3 * figures['solve_time_median_s']:.1f} ms, p90 "
          f"{1e3 * figures['solve_time_p90_s']:.1f} ms")


if __name__ == "__main__":
    main()
