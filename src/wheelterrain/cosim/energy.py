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

The rover (the centre of mass' velocity v = (v_x, v_z) along and into the terrain, pitch rate
q, the motors' torques M_k reacting on the chassis, each wheel's axle moving at its own speed
u_k = u - l_k*sin(theta)*q, exact rigid-body kinematics, :mod:`wheelterrain.model.rover`)::

    motor + gravity = kinetic + towing + sum over wheels (slip + ... + pressing)
    motor = int sum M_k*(omega_k - q) dt, gravity = int m*g*(v_z*cos(slope) - v_x*sin(slope)) dt,
    towing = int F*v_x dt, kinetic = m*|v|**2/2 + I*q**2/2 + J*sum omega_k**2/2 (gained)

each wheel's soil terms with its own axle speed u_k. With ``ruts`` (the default) the rover runs
with the rut profile, as it is simulated: each wheel meets the rut the tracks' profiles hold
where it is (the rear wheels the front wheels' ruts), the profiles replayed from the ruts the
wheels left after every RUT_SEGMENT s of the integration, as the in-process engine does
between its blocks of steps (:mod:`wheelterrain.cosim.ruts`); no term is added for it, the
ruts being laid behind the wheels.

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
from wheelterrain.parameters import NO_RIPPLE, ParameterSet

SOIL_TERMS = ("slip", "compaction", "bulldozing", "damping", "pressing")
"""Where a wheel's contact takes the energy, per wheel [J]."""
TERMS = ("motor", "load", "kinetic", "pull", *SOIL_TERMS)
"""The rig ledger's terms [J], supplied first."""
ROVER_TERMS = ("motor", "gravity", "kinetic", "towing", *SOIL_TERMS)
"""The rover ledger's terms [J], supplied first (the soil terms summed over the wheels)."""
SUPPLIED = ("motor", "load", "gravity")
SINKAGE_START = 0.01
"""m: where the rig's wheel starts (at rest in the soil, as the rig's reference results)."""
STOP = 4.0
"""s: the rig's run, as the rig's reference results (the paper's runs last about as long)."""
TOLERANCE = 1e-10
"""CVODES' relative tolerance for the states and the works."""
INTERVAL = 0.01
RUT_SEGMENT = 0.1
"""s: the rover's integration with ruts, in segments of this length (the in-process engine's
block), the rut profiles replayed between them from the ruts left every RUT_SAMPLE s."""
RUT_SAMPLE = 1e-3


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
                 stop: float = 20.0, heave_start: float = 1e-3, slope: float = 0.0,
                 ruts: bool = True) -> dict:
    """The energy ledger of the rover over ``stop`` s (the table's defaults and
    ``rover_values``, every wheel on ``params``' soil) on the slope ``slope`` [rad] (uphill
    > 0), with the rut profiles (``ruts``; without: no wheel meets a rut, model exchange):
    each of ROVER_TERMS [J], ``wheels`` (per wheel its SOIL_TERMS), ``residual``,
    ``relative_residual``, ``ruts``, ``slope_deg``, ``start`` and ``rut_met`` (per wheel the
    rut it meets at the end [m]). On level ground the rover
    starts at rest with the chassis ``heave_start`` in the soil; on a slope in its steady
    motion there (:func:`wheelterrain.cosim.rover_limits.steady_slip`, each rear wheel in its
    front wheel's steady rut): a rover started at rest on a slope slides back before its
    wheels have sunk in. A slope without a steady motion is a WheelTerrainError."""
    from wheelterrain.cosim import ruts as rut_profile
    from wheelterrain.model import ground

    r = {**rover.defaults(), **(rover_values or {})}
    met = ca.SX.sym("met", rut_profile.N_MET) if ruts else None
    loop = rover_on_contact(ca.DM(params.vector()), r, heave_start=heave_start, slope=slope,
                            met=met)
    terrain_map, profiles = ground.defaults(), None  # no soil map: the ruts' cells only
    if slope != 0:
        loop["start"], profiles = _steady_start(params, r, slope, terrain_map)
    x, u = loop["x"], loop["u"]
    xs = tuple(x.values())
    effective_slope, towing = rover.effective_inputs(xs, u, r)
    m, g = r["rover.mass"], r["rover.gravity"]
    q = x["pitch_rate"]
    vx, vz = rover.centre_of_mass_velocity(xs, r)
    powers = {"motor": sum(rover.motor_torque(xs, u, r, w)
                           * (x[f"{w}.wheel_speed"] - q) for w in rover.WHEELS),
              "gravity": m * g * (vz * ca.cos(effective_slope) - vx * ca.sin(effective_slope)),
              "towing": towing * vx}
    for w in rover.WHEELS:
        wheel = loop["wheels"][w]
        for term, power in soil_powers(wheel, wheel["axle_speed"], wheel["wheel_speed"],
                                       wheel["sinkage_rate"]).items():
            powers[f"{w}.{term}"] = power
    n = len(loop["start"])
    met_at_end = dict.fromkeys(rover.WHEELS, 0.0)
    if ruts:
        end, profiles = _with_ruts(loop, powers, met, r, terrain_map, stop, profiles)
        first = np.array([*loop["start"], *([0.0] * len(powers))])
        at = float(end[rover.STATES.index("position")])
        met_at_end = {w: float(ground.met(profiles[rover.TRACK_OF[w]],
                                          rover.wheel_position(r, at, w), terrain_map)[0])
                      for w in rover.WHEELS}
    else:
        _, path = _integrate(loop["state"], loop["rate"], powers, loop["start"], stop)
        first, end = path[:, 0], path[:, -1]
    out = dict(zip(powers, (float(w) for w in end[n:]), strict=True))
    speed_of_mass = ca.Function("com", [loop["state"]], [vx, vz])

    def kinetic(column) -> float:
        s = dict(zip(rover.STATES, column[:len(rover.STATES)], strict=True))
        cx, cz = (float(v) for v in speed_of_mass(column[:n]))
        return (m * (cx**2 + cz**2) / 2
                + r["rover.pitch_inertia"] * s["pitch_rate"] ** 2 / 2
                + sum(r["rover.wheel_inertia"] * s[f"{w}.wheel_speed"] ** 2 / 2
                      for w in rover.WHEELS))

    out["kinetic"] = kinetic(end) - kinetic(first)
    wheels = {w: {t: out[f"{w}.{t}"] for t in SOIL_TERMS} for w in rover.WHEELS}
    for t in SOIL_TERMS:
        out[t] = sum(wheels[w][t] for w in rover.WHEELS)
    result = {k: out[k] for k in ROVER_TERMS}
    result.update(_close(out, ROVER_TERMS), wheels=wheels, stop=float(stop), ruts=bool(ruts),
                  slope_deg=float(np.degrees(slope)),
                  start="steady motion" if slope != 0 else "rest", rut_met=met_at_end)
    return result


def _steady_start(params: ParameterSet, r: Mapping[str, float], slope: float,
                  g: Mapping[str, float]) -> tuple[list[float], dict]:
    """The rover's steady motion on ``slope``, ripple-free (rover_limits): its state (with the
    wheel angles 0 and each wheel's plastic sinkage at its sinkage) and the tracks' rut
    profiles of it."""
    from wheelterrain.cosim import ruts as rut_profile
    from wheelterrain.cosim.rover_limits import steady_slip, steady_state_vector
    from wheelterrain.errors import InputError

    quiet = {w: params.with_values(NO_RIPPLE) for w in rover.WHEELS}
    slip = steady_slip(quiet, r, slope)
    if slip is None:
        raise InputError(
            "slope [deg]", float(np.degrees(slope)), "leaves the rover no steady motion (it "
            "stalls or slides there: wheelterrain rover --scenario slope|descent finds where); "
            "choose a gentler one")
    balance = rover.steady_balance(quiet, r, slope, slip)
    x = steady_state_vector(balance, r)
    plastics = [float(rover.wheel_kinematics(list(x), r, w)[0]) for w in rover.WHEELS]
    start = [*x, *([0.0] * len(rover.WHEELS)), *plastics]
    return start, rut_profile.steady_ruts(balance, r, x, g)


def _with_ruts(loop: dict, powers: dict, met, r: Mapping[str, float], g: Mapping[str, float],
               stop: float, profiles: dict | None = None) -> tuple[np.ndarray, dict]:
    """The rover's state and the works at ``stop``, integrated in RUT_SEGMENT pieces, each with
    the rut profiles' tables (``met``, its parameter) at its start, the ruts the wheels left
    (sampled every RUT_SAMPLE s) replayed into the profiles after it; and the profiles."""
    from wheelterrain.cosim import ruts as rut_profile
    from wheelterrain.model import ground

    state, n = loop["state"], len(loop["start"])
    work = ca.SX.sym("work", len(powers))
    problem = {"x": ca.vertcat(state, work), "p": met,
               "ode": ca.vertcat(loop["rate"], *powers.values())}
    samples = round(RUT_SEGMENT / RUT_SAMPLE)
    grid = np.linspace(0.0, RUT_SEGMENT, samples + 1)
    integrator = ca.integrator("ledger_ruts", "cvodes", problem, 0.0, grid[1:].tolist(),
                               {"abstol": 1e-14, "reltol": TOLERANCE, "max_num_steps": 10**7})
    position = rover.STATES.index("position")
    left = ca.Function("left", [state, met], [ca.vertcat(
        *(loop["wheels"][w][k] for k in ("rut_left", "rut_pressure_left")
          for w in rover.WHEELS))])
    profiles = ({track: ground.no_ruts() for track in rover.TRACKS} if profiles is None
                else {track: list(p) for track, p in profiles.items()})
    column = np.array([*loop["start"], *([0.0] * len(powers))])
    for _ in range(max(1, round(stop / RUT_SEGMENT))):
        at = {w: rover.wheel_position(r, column[position], w) for w in rover.WHEELS}
        table = rut_profile.met_table(profiles, at, g)
        path = np.column_stack([column, np.array(integrator(x0=column, p=table)["xf"])])
        steps = path[:, :-1]  # the state at the start of each sample step
        lefts = np.array(left.map(samples)(steps[:n], ca.repmat(ca.DM(table), 1, samples)))
        wheels = len(rover.WHEELS)
        rut_profile.remember(profiles, steps[position],
                             {w: lefts[k] for k, w in enumerate(rover.WHEELS)},
                             {w: lefts[wheels + k] for k, w in enumerate(rover.WHEELS)},
                             table, r, g)
        column = path[:, -1]
    return column, profiles
