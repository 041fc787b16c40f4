"""The single-wheel test rig of the paper: carriage, wheel drive and the wheel's vertical motion.

Written once as plain arithmetic on numbers or CasADi symbols (:func:`step`), so the pythonfmu
slave runs it on floats and the CasADi Function (:func:`build`) traces the very same expressions.

The rig (Abubakar et al., the Rashid wheel study, "Test rig and experiments"):

- The **carriage** is position-controlled by its own motor: its speed is set from the commanded
  wheel rim speed and the commanded slip in the paper's definition s = (omega*R - V)/V, so
  V = rim_speed/(1 + s). It is an exact kinematic constraint, not a state.
- The **wheel motor** is in closed-loop speed control around omega_ref = rim_speed/R_ref (R_ref
  the radius slip is referenced to, ``rig.slip_radius``): a PI controller with both closed-loop
  poles at -``rig.speed_bandwidth`` on the wheel's rotational inertia J,
  J*d(omega)/dt = T_motor - T_soil, T_motor = Kp*(omega_ref - omega) + Ki*int(omega_ref - omega),
  Kp = 2*w*J, Ki = w**2*J. It outputs the motor torque it needs.
- The **vertical motion**: the mass M (``rig.mass``) carried on the wheel moves freely up and
  down under the rig's normal load W and the soil's normal force Fz (which includes the contact
  damper C_f*dz/dt of the terrain model): M*d2z/dt2 = W - Fz, z the sinkage, positive down.

Two switches turn the rig into a controller's test bench (both default to the paper's rig):

- ``rig.drive`` = 1: the speed loop tracks the input ``wheel_speed_command`` instead of
  rim_speed/R_ref; = 2: the input ``motor_torque_command`` drives the wheel directly (no loop).
- ``rig.carriage`` = 1: the carriage is free, a rover wheel's share of the vehicle. Its speed V
  is a state: M*dV/dt = DP - M*g*sin(slope) - F_tow (``rig.slope``, ``rig.towing_force``), M
  the same ``rig.mass`` that moves vertically. ``rig.load`` stays as set (for a slope, set it to
  M*g*cos(slope)).

Integration over one communication step h, with the terrain's forces held (co-simulation):
semi-implicit Euler for the vertical motion, implicit Euler for the speed loop (solved in closed
form; unconditionally stable for the stiff controller), explicit Euler for a torque-driven wheel
and a free carriage (their right-hand sides are constant over the step: forces held). All are
first order: halving h is how the co-simulation's convergence is checked.
"""

from __future__ import annotations

import math

import casadi as ca

from wheelterrain.errors import ParameterError
from wheelterrain.parameters import RIG_NAMES, RIG_TABLE, STANDARD_GRAVITY

RIG_INDEX = {name: k for k, name in enumerate(RIG_NAMES)}

RIG_STATES = ("sinkage", "sinkage_rate", "wheel_speed", "speed_error_integral", "carriage_speed")
FORCE_INPUTS = ("normal_force", "drawbar_pull", "torque")
COMMANDS = ("wheel_speed_command", "motor_torque_command")
INPUTS = (*FORCE_INPUTS, *COMMANDS)
DRIVE_PAPER, DRIVE_SPEED, DRIVE_TORQUE = 0, 1, 2
CARRIAGE_KINEMATIC, CARRIAGE_FREE = 0, 1


def pick(condition, if_true, if_false):
    """``if_true if condition else if_false`` on floats, ca.if_else on CasADi symbols."""
    if isinstance(condition, (bool, int, float)):
        return if_true if condition else if_false
    return ca.if_else(condition, if_true, if_false)


def named(p) -> dict:
    """The rig parameter vector ``p`` (RIG_NAMES order, e.g. CasADi symbols) by name."""
    return {name: p[k] for k, name in enumerate(RIG_NAMES)}


def references(p) -> tuple:
    """omega_ref [rad/s] and carriage speed V [m/s] from the rig parameters ``p[name]``."""
    omega_ref = p["rig.rim_speed"] / p["rig.slip_radius"]
    carriage_speed = p["rig.rim_speed"] / (1 + p["rig.slip_paper"])
    return omega_ref, carriage_speed


def gains(p) -> tuple:
    """(Kp, Ki) of the speed loop: both closed-loop poles at -rig.speed_bandwidth on J."""
    w, J = p["rig.speed_bandwidth"], p["rig.wheel_inertia"]
    return 2 * w * J, w * w * J


def speed_reference(u, p):
    """The speed loop's reference: the paper's omega_ref, or the input command (rig.drive 1)."""
    return pick(p["rig.drive"] == DRIVE_SPEED, u[INPUTS.index("wheel_speed_command")],
                 references(p)[0])


def motor_torque(x, u, p):
    """Torque the wheel motor applies in state ``x`` with inputs ``u`` (INPUTS)."""
    kp, ki = gains(p)
    loop = kp * (speed_reference(u, p) - x[2]) + ki * x[3]
    return pick(p["rig.drive"] == DRIVE_TORQUE, u[INPUTS.index("motor_torque_command")], loop)


def carriage_acceleration(u, p):
    """dV/dt of the free carriage: (DP - M*g*sin(slope) - F_tow)/M; 0 when kinematic."""
    mass = p["rig.mass"]
    free = (u[1] - mass * STANDARD_GRAVITY * _sin(p["rig.slope"]) - p["rig.towing_force"]) / mass
    return pick(p["rig.carriage"] == CARRIAGE_FREE, free, 0.0)


def _sin(angle):
    return math.sin(angle) if isinstance(angle, (int, float)) else ca.sin(angle)


def rates(x, u, p) -> tuple:
    """dx/dt of the rig (RIG_STATES) in state ``x`` with inputs ``u`` (INPUTS): the continuous
    equations that :func:`step` integrates, for controllers' prediction models."""
    z_rate, omega = x[1], x[2]
    loop = p["rig.drive"] != DRIVE_TORQUE
    return (z_rate,
            (p["rig.load"] - u[0]) / p["rig.mass"],
            (motor_torque(x, u, p) - u[2]) / p["rig.wheel_inertia"],
            pick(loop, speed_reference(u, p) - omega, 0.0),
            carriage_acceleration(u, p))


def step(x, u, p, h):
    """Advance the rig state ``x`` (RIG_STATES) over ``h`` with inputs ``u`` (INPUTS: soil forces
    and commands) held. ``p`` maps rig parameter names to values. Works on floats and on CasADi
    symbols.

    Returns (next state tuple, motor torque at the end of the step).
    """
    z, z_rate, omega, e_int, speed = x
    soil_torque = u[2]
    J = p["rig.wheel_inertia"]
    kp, ki = gains(p)
    omega_ref = speed_reference(u, p)
    dx = rates(x, u, p)  # the explicit parts below step along these

    z_rate_next = z_rate + h * dx[1]
    z_next = z + h * z_rate_next
    # implicit Euler of J*omega' = kp*(ref - omega) + ki*e - T_soil, e' = ref - omega
    omega_loop = ((J / h) * omega + kp * omega_ref + ki * (e_int + h * omega_ref)
                  - soil_torque) / (J / h + kp + ki * h)
    e_loop = e_int + h * (omega_ref - omega_loop)
    torque_loop = kp * (omega_ref - omega_loop) + ki * e_loop
    # torque-driven: the applied torque and the soil's are both held over the step
    direct = p["rig.drive"] == DRIVE_TORQUE
    omega_next = pick(direct, omega + h * dx[2], omega_loop)
    e_next = pick(direct, e_int, e_loop)
    torque = pick(direct, u[INPUTS.index("motor_torque_command")], torque_loop)
    speed_next = speed + h * dx[4]
    return (z_next, z_rate_next, omega_next, e_next, speed_next), torque


def initial_state(p) -> tuple:
    """Wheel resting on the surface, not moving vertically, already turning at omega_ref, the
    carriage at rim_speed/(1 + slip_paper)."""
    omega_ref, carriage = references(p)
    return (0.0, 0.0, omega_ref, 0.0, carriage)


def build() -> ca.Function:
    """``rig_step(x, u, p, h) -> (x_next, motor_torque)`` as a CasADi Function, traced from
    :func:`step` (for generated C)."""
    x, u = ca.SX.sym("x", len(RIG_STATES)), ca.SX.sym("u", len(INPUTS))
    p, h = ca.SX.sym("p", len(RIG_NAMES)), ca.SX.sym("h")
    nxt, torque = step(tuple(x[k] for k in range(len(RIG_STATES))),
                       tuple(u[k] for k in range(len(INPUTS))), named(p), h)
    return ca.Function("rig_step", [x, u, p, h], [ca.vertcat(*nxt), torque],
                       ["x", "u", "p", "h"], ["x_next", "motor_torque"])


def defaults() -> dict[str, float]:
    return {prm.name: prm.default for prm in RIG_TABLE}


def check(name: str, value: float) -> float:
    """Validated value of rig parameter ``name`` (ParameterError naming the range otherwise, or
    the close names of an unknown one)."""
    if name not in RIG_INDEX:
        import difflib

        close = difflib.get_close_matches(name, RIG_NAMES, n=3)
        hint = f"; did you mean {', '.join(close)}?" if close else ""
        raise ParameterError(name, value, f"is not a rig parameter{hint} (valid: "
                                          f"{', '.join(RIG_NAMES)})")
    return RIG_TABLE[RIG_INDEX[name]].check(value)


