"""Where the motor's energy goes: the energy ledgers of the paper's rig and of the rover.

Each system runs in continuous time on the contact with the soil's memory (the FMUs' model
exchange: :func:`wheelterrain.fmu.functions.rig_on_contact`, ``rover_on_contact``), integrated
by CVODES together with the work of each power term. Per wheel, with omega its speed, V the
axle's forward speed, z the sinkage (down), T the soil's resisting torque, DP the drawbar pull,
H the gross thrust, R_c and R_b the compaction and bulldozing resistances (DP = H - R_c - R_b),
Fz the normal force and D the contact damper's share of it::

    slip       = int (T*omega - H*V) dt     the shear stresses' (and the grousers') work
                                            against the slip: friction in the soil
    compaction = int R_c*V dt               pressing the soil ahead to the rut's depth
    bulldozing = int R_b*V dt               pushing the soil ahead aside
    damping    = int D*dz/dt dt             the contact damper (soil.damping)
    pressing   = int (Fz - D)*dz/dt dt      pressing the soil vertically: plastic where it
                                            yields, elastic (returned) where it unloads

The rig (its carriage kinematic, its load W on the moving mass m, the wheel's inertia J)::

    motor + load = kinetic + pull + slip + compaction + bulldozing + damping + pressing
    motor = int M*omega dt,  load = W*(z1 - z0),  pull = int DP*V dt (the work on the carriage)

The rover (chassis speed u, heave rate w, pitch rate q, the motors' torques M_k reacting on
the chassis)::

    motor + gravity = kinetic + towing + sum over wheels (slip + ... + pressing) + pitch
    motor = int sum M_k*(omega_k - q) dt, gravity = int m*g*(w*cos(slope) - u*sin(slope)) dt,
    towing = int F*u dt

``pitch`` is the chassis model's own approximation: each wheel's contact sees its axle move
forward at u and sink at w + l_k*cos(theta)*q, while the chassis applies the wheel's forces at
the axle's offset r_k (rover.py neglects the pitch rate's share d*q of the axle's speed), so
pitch = int q*sum((l_k*sin(theta) + d*cos(theta))*P_k - d*sin(theta)*N_k) dt.

Both ledgers hold exactly for the continuous equations; ``residual`` is what the integration
leaves (CVODES at 1e-10: ~1e-11 of the motor's work), and a force applied with the wrong sign
or arm, or a resistance missing from DP, would leave a residual of its size.
"""

from __future__ import annotations

from collections.abc import Mapping

import casadi as ca
import numpy as np

from wheelterrain.fmu.functions import rig_on_contact, rover_on_contact
from wheelterrain.model import rig, rover
from wheelterrain.parameters import ParameterSet

SOIL_TERMS = ("slip", "compaction", "bulldozing", "damping", "pressing")
"""Where a wheel's contact takes the energy, per wheel [J]."""
TERMS = ("motor", "load", "kinetic", "pull", *SOIL_TERMS)
"""The rig ledger's terms [J], supplied first."""
ROVER_TERMS = ("motor", "gravity", "kinetic", "towing", *SOIL_TERMS, "pitch")
"""The rover ledger's terms [J], supplied first (the soil terms summed over the wheels)."""
SUPPLIED = ("motor", "load", "gravity")
SINKAGE_START = 0.01
"""m: where the rig's wheel starts (at rest in the soil, as the rig's reference results)."""
STOP = 4.0
"""s: the rig's run, as the rig's reference results (the paper's runs last about as long)."""
TOLERANCE = 1e-10
"""CVODES' relative tolerance for the states and the works."""
INTERVAL = 0.01


def soil_powers(wheel: dict, speed, omega, z_rate) -> dict:
    """The soil terms' powers [W] of one wheel's contact outputs ``wheel`` (with
    ``damper_force``) at its speed ``omega``, its axle's ``speed`` and sinkage rate."""
    return {
        "slip": wheel["torque"] * omega - wheel["gross_thrust"] * speed,
        "compaction": wheel["compaction_resistance"] * speed,
        "bulldozing": wheel["bulldozing_resistance"] * speed,
        "damping": wheel["damper_force"] * z_rate,
        "pressing": (wheel["normal_force"] - wheel["damper_force"]) * z_rate,
    }


def _integrate(state, rate, powers: dict, start, stop: float):
    """The state and each power's work over [0, stop] (every INTERVAL): (times, path), path's
    rows the state, then the works in ``powers``' order."""
    work = ca.SX.sym("work", len(powers))
    problem = {"x": ca.vertcat(state, work), "ode": ca.vertcat(rate, *powers.values())}
    times = np.linspace(0.0, stop, round(stop / INTERVAL) + 1)
    integrator = ca.integrator("ledger", "cvodes", problem, 0.0, times[1:].tolist(),
                               {"abstol": 1e-14, "reltol": TOLERANCE,
                                "max_num_steps": 10**7})
    x0 = [*start, *([0.0] * len(powers))]
    return times, np.column_stack([x0, np.array(integrator(x0=x0)["xf"])])


def _close(out: dict, terms) -> dict:
    supplied = sum(out[k] for k in terms if k in SUPPLIED)
    spent = sum(out[k] for k in terms if k not in SUPPLIED)
    return {"residual": supplied - spent, "relative_residual": (supplied - spent) / out["motor"]}


def rig_ledger(params: ParameterSet, slip_paper: float, stop: float = STOP,
               rig_values: Mapping[str, float] | None = None) -> dict:
    """The energy ledger of the rig at the paper's slip ``slip_paper`` over ``stop`` s from rest
    in the soil at SINKAGE_START: each of TERMS [J], ``residual`` (supplied less the rest) and
    ``relative_residual`` (over the motor's work), ``final_sinkage`` [m] and
    ``mean_drawbar_pull`` [N] over the last second."""
    rp = {**rig.defaults(), **(rig_values or {}), "rig.slip_paper": float(slip_paper)}
    loop = rig_on_contact(ca.DM(params.vector()), rp, SINKAGE_START)
    v, state = loop["values"], loop["state"]
    z_rate, omega, speed = state[1], state[2], v["carriage_speed"]
    powers = {"motor": v["motor_torque"] * omega, "load": loop["rig"]["rig.load"] * z_rate,
              "pull": v["drawbar_pull"] * speed, **soil_powers(v, speed, omega, z_rate)}
    times, path = _integrate(state, loop["rate"], powers, loop["start"], stop)
    n = len(loop["start"])
    first, end = path[:, 0], path[:, -1]
    out = dict(zip(powers, (float(w) for w in end[n:]), strict=True))
    J, m = loop["rig"]["rig.wheel_inertia"], loop["rig"]["rig.mass"]
    out["kinetic"] = float(J * (end[2] ** 2 - first[2] ** 2) / 2
                           + m * (end[1] ** 2 - first[1] ** 2) / 2)
    pull = ca.Function("pull", [state], [v["drawbar_pull"]])
    late = np.flatnonzero(times >= stop - 1.0)
    result = {k: out[k] for k in TERMS}
    result.update(_close(out, TERMS), final_sinkage=float(end[0]),
                  mean_drawbar_pull=float(np.mean([float(pull(path[:n, k])) for k in late])),
                  slip_paper=float(slip_paper), stop=float(stop))
    return result


def rover_ledger(params: ParameterSet, rover_values: Mapping[str, float] | None = None,
                 stop: float = 10.0, heave_start: float = 1e-3) -> dict:
    """The energy ledger of the rover over ``stop`` s from its start (the table's defaults and
    ``rover_values``; the chassis ``heave_start`` in the soil, every wheel on ``params``' soil,
    no rut profile: model exchange): each of ROVER_TERMS [J], ``wheels`` (per wheel its
    SOIL_TERMS), ``residual`` and ``relative_residual``."""
    r = {**rover.defaults(), **(rover_values or {})}
    loop = rover_on_contact(ca.DM(params.vector()), r, heave_start=heave_start)
    x, u = loop["x"], loop["u"]
    xs = tuple(x.values())
    slope, towing = rover.effective_inputs(xs, u, r)
    m, g, d = r["rover.mass"], r["rover.gravity"], r["rover.cg_height"]
    sin_t, cos_t = ca.sin(x["pitch"]), ca.cos(x["pitch"])
    q = x["pitch_rate"]
    powers = {"motor": sum(rover.motor_torque(xs, u, r, w)
                           * (x[f"{w}.wheel_speed"] - q) for w in rover.WHEELS),
              "gravity": m * g * (x["heave_rate"] * ca.cos(slope)
                                  - x["speed"] * ca.sin(slope)),
              "towing": towing * x["speed"], "pitch": 0}
    for w in rover.WHEELS:
        wheel = loop["wheels"][w]
        lk = rover.lever(r, w)
        powers["pitch"] += q * ((lk * sin_t + d * cos_t) * wheel["drawbar_pull"]
                                - d * sin_t * wheel["normal_force"])
        for term, power in soil_powers(wheel, x["speed"], wheel["wheel_speed"],
                                       wheel["sinkage_rate"]).items():
            powers[f"{w}.{term}"] = power
    _, path = _integrate(loop["state"], loop["rate"], powers, loop["start"], stop)
    n = len(loop["start"])
    first, end = path[:, 0], path[:, -1]
    out = dict(zip(powers, (float(w) for w in end[n:]), strict=True))

    def kinetic(column) -> float:
        s = dict(zip(rover.STATES, column[:len(rover.STATES)], strict=True))
        return (m * (s["speed"] ** 2 + s["heave_rate"] ** 2) / 2
                + r["rover.pitch_inertia"] * s["pitch_rate"] ** 2 / 2
                + sum(r["rover.wheel_inertia"] * s[f"{w}.wheel_speed"] ** 2 / 2
                      for w in rover.WHEELS))

    out["kinetic"] = kinetic(end) - kinetic(first)
    wheels = {w: {t: out[f"{w}.{t}"] for t in SOIL_TERMS} for w in rover.WHEELS}
    for t in SOIL_TERMS:
        out[t] = sum(wheels[w][t] for w in rover.WHEELS)
    result = {k: out[k] for k in ROVER_TERMS}
    result.update(_close(out, ROVER_TERMS), wheels=wheels, stop=float(stop))
    return result
