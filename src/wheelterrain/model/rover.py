"""The rover's chassis: a rigid body in the vertical plane of travel on four driven wheels.

Written once as plain arithmetic on numbers or CasADi symbols (:func:`step`, :func:`rates`), as
the rig is (:mod:`wheelterrain.model.rig`): the pythonfmu slave, the generated C of the native
RoverChassis.fmu and the in-process rover all run these expressions.

Frame: the terrain's. x runs along the slope (forward, uphill for a positive slope), z is
normal to it, positive *into* the soil (as sinkage). The slope angle is an input; gravity is
``rover.gravity``. The chassis has three degrees of freedom and their rates:

- x, u: position and speed along the terrain of the chassis' reference point (the point of
  the axle line below the centre of mass);
- z, w: that point's sinkage and its rate;
- theta, q: pitch, positive nose down, and its rate;
- the elapsed time, a state (rate 1) so that the chassis' input profile (a slope or towing
  ramp, :func:`effective_inputs`) runs in any engine, model exchange included.

Wheels: four, on two axles (front_left, front_right at l_f = wheelbase/2 - cg_forward ahead of
the centre of mass; rear_left, rear_right at l_r = -wheelbase/2 - cg_forward), rigidly mounted
(no suspension: the soil is the spring and its damper C_f the damper; documented choice). In
the vertical plane the left and right wheel of an axle sink alike; their soils, and so their
forces, may differ. Wheel k's axle sits at l_k along the axle line from the reference point:
its sinkage z_k = z + l_k*sin(theta), its rate w + l_k*cos(theta)*q, and it moves along the
terrain at u_k = u - l_k*sin(theta)*q (:func:`wheel_kinematics`, :func:`axle_speed`): the
speed each wheel's contact is given, exactly.

Forces of the soil on wheel k (from its WheelTerrain): N_k up (normal_force), P_k forward
(drawbar_pull), T_k the resistive torque about its axle. The axle passes N_k and P_k to the
chassis; the motor applies M_k to the wheel and -M_k to the chassis. With d = ``rover.cg_height``
(the centre of mass above the axle line), r_k = (l_k*cos(theta) - d*sin(theta), l_k*sin(theta) +
d*cos(theta)) the axle's offset from the centre of mass (forward, down)::

    I*dq/dt  = sum_k [-r_k,x*N_k - r_k,z*P_k - M_k]          (nose down positive)
    m*(du/dt + d*cos(theta)*dq/dt - d*sin(theta)*q**2) = sum P_k - m*g*sin(slope) - F_tow
    m*(dw/dt + d*sin(theta)*dq/dt + d*cos(theta)*q**2) = m*g*cos(slope) - sum N_k
    J*domega_k/dt = M_k - T_k

(an upward force ahead of the centre of mass lifts the nose; a forward force below it, and the
reaction of a driving motor, lift it too). The brackets on the left are the centre of mass'
acceleration, (u + d*cos(theta)*q, w + d*sin(theta)*q) its velocity: the reference point lies
d below it along the body. Gravity and the towing force act at the centre of mass. Each
motor is the rig's speed loop (PI, both poles at -``rover.speed_bandwidth``), or the input
speed or torque command (``rover.drive``), its torque limited to +-``rover.motor_torque_limit``
(the loop's integrator stops while saturated).

Integration over a communication step h with the soil's forces held: semi-implicit Euler for
the chassis (rates first, then positions), implicit Euler for the unsaturated speed loops (the
rig's closed form), explicit Euler for a torque-driven or saturated wheel: first order, so
halving h is how the co-simulation's convergence is checked.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import casadi as ca

from wheelterrain.model.rig import pick
from wheelterrain.parameters import ROVER_TABLE

WHEELS = ("front_left", "front_right", "rear_left", "rear_right")
FRONT = ("front_left", "front_right")
TRACKS = {"left": ("front_left", "rear_left"), "right": ("front_right", "rear_right")}
"""The rover's tracks: the wheels that run in each other's ruts, the leading one first."""
LEADING = {rear: front for front, rear in TRACKS.values()}
"""The wheel whose rut each following wheel runs in."""
TRACK_OF = {w: track for track, pair in TRACKS.items() for w in pair}
"""Each wheel's track."""
ROVER_NAMES = tuple(p.name for p in ROVER_TABLE)
CHASSIS_STATES = ("position", "speed", "heave", "heave_rate", "pitch", "pitch_rate",
                  "elapsed")
WHEEL_STATES = ("wheel_speed", "speed_error_integral")
STATES = (*CHASSIS_STATES, *(f"{w}.{s}" for w in WHEELS for s in WHEEL_STATES))
WHEEL_FORCES = ("normal_force", "drawbar_pull", "torque")
WHEEL_COMMANDS = ("wheel_speed_command", "motor_torque_command")
VEHICLE_INPUTS = ("slope", "towing_force")
INPUTS = (*VEHICLE_INPUTS, *(f"{w}.{n}" for w in WHEELS for n in (*WHEEL_FORCES,
                                                                    *WHEEL_COMMANDS)))
DRIVE_COMMON, DRIVE_SPEED, DRIVE_TORQUE = 0, 1, 2


def _trig(angle):
    if isinstance(angle, (int, float)):
        return math.sin(angle), math.cos(angle)
    return ca.sin(angle), ca.cos(angle)


def named(p) -> dict:
    """The rover parameter vector ``p`` (ROVER_NAMES order) by name."""
    return {name: p[k] for k, name in enumerate(ROVER_NAMES)}


def grouser_phase(p, wheel: str):
    """``wheel``'s grouser phase [rad] (``rover.grouser_phase.<wheel>``): added to its
    WheelTerrain's ``ripple.phase``."""
    return p[f"rover.grouser_phase.{wheel}"]


def lever(p, wheel: str):
    """l_k: the wheel's axle ahead of the centre of mass [m] (negative behind)."""
    half = p["rover.wheelbase"] / 2
    return (half if wheel in FRONT else -half) - p["rover.cg_forward"]


def wheel_position(p, position, wheel: str):
    """Where ``wheel``'s axle is along the path [m] with the chassis' reference point (the axle
    line below the centre of mass) at ``position``."""
    return position + lever(p, wheel) + p["rover.cg_forward"]


def wheel_kinematics(x, p, wheel: str) -> tuple:
    """(sinkage, sinkage_rate) of ``wheel`` from the chassis state ``x``."""
    s = dict(zip(STATES, x, strict=True))
    sin_t, cos_t = _trig(s["pitch"])
    lk = lever(p, wheel)
    return s["heave"] + lk * sin_t, s["heave_rate"] + lk * cos_t * s["pitch_rate"]


def axle_speed(x, p, wheel: str):
    """The speed [m/s] along the terrain of ``wheel``'s axle in the chassis state ``x``: the
    reference point's, less the pitch rate's share, u - l_k*sin(theta)*q."""
    s = dict(zip(STATES, x, strict=True))
    sin_t, _ = _trig(s["pitch"])
    return s["speed"] - lever(p, wheel) * sin_t * s["pitch_rate"]


def centre_of_mass_velocity(x, p) -> tuple:
    """(along the terrain, into it) [m/s]: the centre of mass' velocity in the chassis state
    ``x`` (d above the reference point along the body)."""
    s = dict(zip(STATES, x, strict=True))
    sin_t, cos_t = _trig(s["pitch"])
    d, q = p["rover.cg_height"], s["pitch_rate"]
    return s["speed"] + d * cos_t * q, s["heave_rate"] + d * sin_t * q


def gains(p) -> tuple:
    """(Kp, Ki) of each speed loop: both closed-loop poles at -rover.speed_bandwidth."""
    w, J = p["rover.speed_bandwidth"], p["rover.wheel_inertia"]
    return 2 * w * J, w * w * J


def _speed_reference(u, p, wheel: str):
    common = p["rover.rim_speed"] / p["rover.slip_radius"]
    return pick(p["rover.drive"] == DRIVE_SPEED, u[f"{wheel}.wheel_speed_command"], common)


def _limit(torque, p):
    lim = p["rover.motor_torque_limit"]
    if isinstance(torque, (int, float)):
        return min(max(torque, -lim), lim)
    return ca.fmin(ca.fmax(torque, -lim), lim)


def motor_torque(x, u, p, wheel: str):
    """Torque of ``wheel``'s motor in state ``x`` with inputs ``u`` (by name)."""
    s = dict(zip(STATES, x, strict=True))
    kp, ki = gains(p)
    loop = kp * (_speed_reference(u, p, wheel) - s[f"{wheel}.wheel_speed"]) \
        + ki * s[f"{wheel}.speed_error_integral"]
    return _limit(pick(p["rover.drive"] == DRIVE_TORQUE, u[f"{wheel}.motor_torque_command"],
                       loop), p)


def _clip(value, bound):
    if isinstance(value, (int, float)) and isinstance(bound, (int, float)):
        return min(max(value, -bound), bound)
    return ca.fmin(ca.fmax(value, -bound), bound)


def _ramp_parts(t, p):
    """(time before the switch, time after it) of the profile at ``t``."""
    switch = p["rover.ramp_time"]
    if isinstance(t, (int, float)) and isinstance(switch, (int, float)):
        return min(t, switch), max(t - switch, 0.0)
    return ca.fmin(t, switch), ca.fmax(t - switch, 0)


def effective_inputs(x, u, p) -> tuple:
    """(slope [rad], towing force [N]) the chassis feels in state ``x``: the inputs plus the
    input profile of the ``rover.ramp_time`` ... ``rover.towing_rate`` rows at the state's
    elapsed time (what lets an SSP carry a whole scenario, in any engine)."""
    t = dict(zip(STATES, x, strict=True))["elapsed"]
    before, after = _ramp_parts(t, p)
    ramp = p["rover.slope_rate"] * before + p["rover.slope_rate_after"] * after
    return (u["slope"] + _clip(ramp, p["rover.slope_bound"]),
            u["towing_force"] + p["rover.towing_rate"] * t)


def chassis_accelerations(x, u, p, motor: dict) -> tuple:
    """(du/dt, dw/dt, dq/dt) of the chassis with the motors' torques ``motor`` (by wheel)."""
    s = dict(zip(STATES, x, strict=True))
    m, g, d = p["rover.mass"], p["rover.gravity"], p["rover.cg_height"]
    slope, towing = effective_inputs(x, u, p)
    sin_s, cos_s = _trig(slope)
    sin_t, cos_t = _trig(s["pitch"])
    pull = sum(u[f"{w}.drawbar_pull"] for w in WHEELS)
    normal = sum(u[f"{w}.normal_force"] for w in WHEELS)
    moment = 0.0
    for w in WHEELS:
        lk = lever(p, w)
        rx, rz = lk * cos_t - d * sin_t, lk * sin_t + d * cos_t
        moment = moment - rx * u[f"{w}.normal_force"] - rz * u[f"{w}.drawbar_pull"] - motor[w]
    dq = moment / p["rover.pitch_inertia"]
    q = s["pitch_rate"]
    # the reference point's accelerations: the centre of mass' less its offset's (d along
    # the body above it)
    return ((pull - m * g * sin_s - towing) / m - d * (cos_t * dq - sin_t * q * q),
            (m * g * cos_s - normal) / m - d * (sin_t * dq + cos_t * q * q),
            dq)


def rates(x, u, p) -> tuple:
    """dx/dt (STATES order) in state ``x`` with inputs ``u`` (by name): the continuous
    equations :func:`step` integrates (model exchange, controllers' prediction models)."""
    s = dict(zip(STATES, x, strict=True))
    motor = {w: motor_torque(x, u, p, w) for w in WHEELS}
    du, dw, dq = chassis_accelerations(x, u, p, motor)
    out = [s["speed"], du, s["heave_rate"], dw, s["pitch_rate"], dq, 1.0]
    loop = p["rover.drive"] != DRIVE_TORQUE
    kp, ki = gains(p)
    for w in WHEELS:
        error = _speed_reference(u, p, w) - s[f"{w}.wheel_speed"]
        unsaturated = kp * error + ki * s[f"{w}.speed_error_integral"]
        integrating = pick(loop, pick(_saturated(unsaturated, p), 0.0, 1.0), 0.0)
        out += [(motor[w] - u[f"{w}.torque"]) / p["rover.wheel_inertia"], integrating * error]
    return tuple(out)


def _saturated(torque, p):
    lim = p["rover.motor_torque_limit"]
    if isinstance(torque, (int, float)):
        return abs(torque) > lim
    return ca.fabs(torque) > lim


def step(x, u, p, h) -> tuple:
    """Advance the rover state ``x`` (STATES) over ``h`` with inputs ``u`` (a mapping by INPUTS
    name: soil forces held, commands, slope, towing force); ``p`` by rover parameter name.
    Floats or CasADi symbols. Returns (next state tuple, the four motor torques over the
    step)."""
    s = dict(zip(STATES, x, strict=True))
    kp, ki = gains(p)
    J = p["rover.wheel_inertia"]
    motor_next, nxt = {}, {}
    direct = p["rover.drive"] == DRIVE_TORQUE
    for w in WHEELS:
        omega, e_int = s[f"{w}.wheel_speed"], s[f"{w}.speed_error_integral"]
        ref, soil = _speed_reference(u, p, w), u[f"{w}.torque"]
        # implicit Euler of J*omega' = kp*(ref - omega) + ki*e - T, e' = ref - omega
        omega_loop = ((J / h) * omega + kp * ref + ki * (e_int + h * ref) - soil) \
            / (J / h + kp + ki * h)
        e_loop = e_int + h * (ref - omega_loop)
        torque_loop = kp * (ref - omega_loop) + ki * e_loop
        # saturated loop or torque command: the applied torque held, explicit Euler
        applied = _limit(pick(direct, u[f"{w}.motor_torque_command"], torque_loop), p)
        held = pick(direct, True, _saturated(torque_loop, p))
        nxt[f"{w}.wheel_speed"] = pick(held, omega + h * (applied - soil) / J, omega_loop)
        nxt[f"{w}.speed_error_integral"] = pick(held, e_int, e_loop)
        motor_next[w] = applied
    du, dw, dq = chassis_accelerations(x, u, p, motor_next)
    nxt["speed"] = s["speed"] + h * du
    nxt["position"] = s["position"] + h * nxt["speed"]
    nxt["heave_rate"] = s["heave_rate"] + h * dw
    nxt["heave"] = s["heave"] + h * nxt["heave_rate"]
    nxt["pitch_rate"] = s["pitch_rate"] + h * dq
    nxt["pitch"] = s["pitch"] + h * nxt["pitch_rate"]
    nxt["elapsed"] = s["elapsed"] + h
    return tuple(nxt[k] for k in STATES), tuple(motor_next[w] for w in WHEELS)


def initial_state(p, speed: float | None = None, heave: float = 0.0) -> tuple:
    """Level, ``heave`` m in the soil (default: on the surface), wheels turning at the common
    reference and the chassis moving at ``speed`` (default: the rim speed, no slip)."""
    omega = p["rover.rim_speed"] / p["rover.slip_radius"]
    v = p["rover.rim_speed"] if speed is None else speed
    s = dict.fromkeys(STATES, 0.0)
    s["speed"] = v
    s["heave"] = heave
    for w in WHEELS:
        s[f"{w}.wheel_speed"] = omega
    return tuple(s[k] for k in STATES)


def static_axle_loads(p, slope: float = 0.0) -> dict[str, float]:
    """Normal load per wheel [N] of the rover at rest on a rigid slope: the moment balance of
    the centre of mass about the contact line with the weight's along-slope part acting at the
    height of the centre of mass above the wheels' contacts (cg_height + contact radius is
    what the chassis feels; here the axle height is taken, as the chassis model does for the
    pulls). Two wheels per axle share alike."""
    m, g, d = p["rover.mass"], p["rover.gravity"], p["rover.cg_height"]
    lf, lr = lever(p, "front_left"), lever(p, "rear_left")
    weight_n, weight_t = m * g * math.cos(slope), m * g * math.sin(slope)
    base = lf - lr
    front = (weight_n * (-lr) - weight_t * d) / base
    rear = (weight_n * lf + weight_t * d) / base
    return {w: (front if w in FRONT else rear) / 2 for w in WHEELS}


def build() -> tuple[ca.Function, ca.Function]:
    """``rover_step(x, u, p, h) -> (x_next, motor_torques)`` and ``rover_rates(x, u, p) ->
    (dx, motor_torques)`` as CasADi Functions, traced from :func:`step` and :func:`rates`."""
    x, uu = ca.SX.sym("x", len(STATES)), ca.SX.sym("u", len(INPUTS))
    p, h = ca.SX.sym("p", len(ROVER_NAMES)), ca.SX.sym("h")
    xs = tuple(x[k] for k in range(len(STATES)))
    u = {n: uu[k] for k, n in enumerate(INPUTS)}
    pp = named(p)
    nxt, torques = step(xs, u, pp, h)
    fstep = ca.Function("rover_step", [x, uu, p, h], [ca.vertcat(*nxt), ca.vertcat(*torques)],
                        ["x", "u", "p", "h"], ["x_next", "motor_torques"])
    dx = rates(xs, u, pp)
    motors = [motor_torque(xs, u, pp, w) for w in WHEELS]
    frates = ca.Function("rover_rates", [x, uu, p], [ca.vertcat(*dx), ca.vertcat(*motors)],
                         ["x", "u", "p"], ["dx", "motor_torques"])
    return fstep, frates


def defaults() -> dict[str, float]:
    return {prm.name: prm.default for prm in ROVER_TABLE}


def steady_balance(terrain: Mapping, p: Mapping, slope: float, slip: float,
                   towing: float = 0.0, ruts: Mapping | None = None) -> dict:
    """The rover in steady motion at ``slip`` (the model's slip, :mod:`wheelterrain.model.slip`:
    traction driving, skid braking, -1 locked; all four wheels alike, as one speed
    loop reference gives them) on ``slope``: the wheel loads that satisfy the chassis' moment
    balance (load transfer by the centre of mass' height, the pulls below it and the motors'
    reactions, the pitch from the axles' sinkages), from the single-wheel steady states of
    each wheel's ``terrain`` parameters (a mapping wheel -> ParameterSet), each rear wheel in
    the rut its front wheel leaves (:data:`TRACKS`; a soil with memory) and ``terrain`` says
    so (the steady rover's soils: each rear wheel's with that rut). ``ruts``: per rear wheel
    the rut it runs in (a wheel's ``rut_left`` and ``rut_pressure_left``, e.g. another
    balance's front wheel), instead of the one its front wheel leaves at ``slip``: the rover
    whose slip changed faster than the rear wheels reach new ruts.

    Returns the loads, each wheel's steady state, and ``surplus`` = sum of the pulls minus the
    weight's part along the slope and the towing force [N] (0 in steady motion; > 0 the rover
    accelerates). Raises WheelTerrainError where a wheel cannot carry its load."""
    from scipy.optimize import brentq

    from wheelterrain.model import api

    m, g, d = p["rover.mass"], p["rover.gravity"], p["rover.cg_height"]
    weight_n = m * g * math.cos(slope)
    levers = {w: lever(p, w) for w in WHEELS}
    base = levers["front_left"] - levers["rear_left"]

    def state(front_load: float) -> tuple[float, dict]:
        loads = {w: (front_load if w in FRONT else weight_n / 2 - front_load) for w in WHEELS}
        out = {w: api.steady_state(terrain[w], loads[w], slip, "unified") for w in FRONT}
        for w, ahead in LEADING.items():  # in the rut the wheel ahead leaves (soil memory)
            met = out[ahead] if ruts is None else ruts[w]
            out[w] = api.steady_state(in_rut(terrain[w], met), loads[w], slip, "unified")
        zf = (out["front_left"]["sinkage"] + out["front_right"]["sinkage"]) / 2
        zr = (out["rear_left"]["sinkage"] + out["rear_right"]["sinkage"]) / 2
        sin_t = (zf - zr) / base
        cos_t = math.sqrt(max(1 - sin_t**2, 0.0))
        moment = 0.0
        for w in WHEELS:
            rx = levers[w] * cos_t - d * sin_t
            rz = levers[w] * sin_t + d * cos_t
            moment -= rx * loads[w] + rz * out[w]["drawbar_pull"] + out[w]["torque"]
        return moment, out

    lo, hi = 1e-6 * weight_n, weight_n / 2 * (1 - 1e-6)
    front = brentq(lambda f: state(f)[0], lo, hi, xtol=1e-12, rtol=1e-13)
    _, out = state(front)
    surplus = sum(out[w]["drawbar_pull"] for w in WHEELS) - m * g * math.sin(slope) - towing
    ground = {**{w: terrain[w] for w in FRONT},
              **{w: in_rut(terrain[w], out[a] if ruts is None else ruts[w])
                 for w, a in LEADING.items()}}
    return {"loads": {w: out[w]["load"] for w in WHEELS}, "wheels": out, "surplus": surplus,
            "slip": slip, "slope": slope, "terrain": ground}


def in_rut(params, ahead: Mapping):
    """``params`` (a ParameterSet) with the soil in the rut a wheel ahead left (``ahead``: its
    contact outputs, ``rut_left`` [m] and ``rut_pressure_left`` [Pa]): soil.rut_depth the
    deeper of its own and that, soil.rut_pressure that rut's (no change where the soil has no
    memory, whose wheels leave no rut)."""
    if ahead["rut_left"] <= params["soil.rut_depth"]:
        return params
    return params.with_values({"soil.rut_depth": ahead["rut_left"],
                               "soil.rut_pressure": ahead["rut_pressure_left"]})
