"""The single-wheel test rig of the paper: carriage, wheel drive and the wheel's vertical motion.

Written once as plain arithmetic on numbers or CasADi symbols (:func:`step`), so the pythonfmu
slave runs it on floats and the CasADi Function (:func:`build`) traces the very same expressions.

The rig (shared/spec/paper-digest.md, "Test rig and experiments"):

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

Integration over one communication step h, with the terrain's forces held (co-simulation):
semi-implicit Euler for the vertical motion, implicit Euler for the speed loop (solved in closed
form; unconditionally stable for the stiff controller). Both are first order: halving h is how the
co-simulation's convergence is checked.
"""

from __future__ import annotations

import casadi as ca

from .parameters import Parameter

STANDARD_GRAVITY = 9.80665  # m/s2

_RIG = "The paper's single-wheel rig (shared/spec/paper-digest.md)"
RIG_TABLE: tuple[Parameter, ...] = (
    Parameter("rig.load", "N", 62.0, 0.0, 1.0e5,
              "Vertical load the rig applies to the wheel axle (the paper's normal force).",
              f"{_RIG}: ~62 N measured in every case", quantity="Force"),
    Parameter("rig.mass", "kg", 62.0 / STANDARD_GRAVITY, 0.01, 1.0e4,
              "Mass that moves vertically with the wheel (wheel, axle, dead weight).",
              "Dead-weight reading: load / standard gravity; the paper does not state it",
              quantity="Mass"),
    Parameter("rig.rim_speed", "m/s", 0.03, 1.0e-4, 10.0,
              "Commanded wheel rim speed omega_ref*R_ref.",
              f"{_RIG}: 3 cm/s in C1-C4", quantity="Velocity"),
    Parameter("rig.slip_paper", "1", 0.0, 0.0, 10.0,
              "Commanded slip in the paper's definition s = (omega*R - V)/V; sets the carriage "
              "speed V = rim_speed/(1 + s). Traction slip i = s/(1 + s).",
              f"{_RIG}: 0, 0.25, 0.5, 0.75 in C1-C4"),
    Parameter("rig.slip_radius", "m", 0.05, 0.01, 1.0,
              "Radius R_ref the rig's slip is referenced to; must equal the terrain model's "
              "wheel.radius + model.slip_radius_factor*grouser.height.",
              f"{_RIG}: rim radius 0.05 m", quantity="Length"),
    Parameter("rig.wheel_inertia", "kg.m2", 0.01, 1.0e-6, 100.0,
              "Rotational inertia of wheel and motor about the axle.",
              "Estimate: 1 kg wheel of 5 cm radius plus geared motor; the paper does not state it",
              quantity="MomentOfInertia"),
    Parameter("rig.speed_bandwidth", "rad/s", 200.0, 0.1, 1.0e4,
              "Closed-loop bandwidth of the wheel speed controller (both poles at -bandwidth).",
              "Design choice for a stiff geared servo. It must be: with the slip-dependent "
              "exponent the soil softens as slip grows, so the soil torque falls with wheel "
              "speed (dT/domega ~ -0.4 N.m.s at C2); a 20 rad/s loop (Kp = 0.4 N.m.s) then "
              "limit-cycles, as measured", quantity="AngularVelocity"),
)
RIG_NAMES = tuple(p.name for p in RIG_TABLE)
RIG_INDEX = {name: k for k, name in enumerate(RIG_NAMES)}

STATES = ("sinkage", "sinkage_rate", "wheel_speed", "speed_error_integral")
STATE_START = (0.0, 0.0, None, 0.0)  # wheel_speed starts at omega_ref (None: from parameters)
FORCE_INPUTS = ("normal_force", "drawbar_pull", "torque")


def references(p) -> tuple:
    """omega_ref [rad/s] and carriage speed V [m/s] from the rig parameters ``p[name]``."""
    omega_ref = p["rig.rim_speed"] / p["rig.slip_radius"]
    carriage_speed = p["rig.rim_speed"] / (1 + p["rig.slip_paper"])
    return omega_ref, carriage_speed


def step(x, u, p, h):
    """Advance the rig state ``x`` (STATES) over ``h`` with the soil forces ``u`` (FORCE_INPUTS)
    held. ``p`` maps rig parameter names to values. Works on floats and on CasADi symbols.

    Returns (next state tuple, motor torque at the end of the step).
    """
    z, z_rate, omega, e_int = x
    normal_force, _, soil_torque = u
    load, mass, J = p["rig.load"], p["rig.mass"], p["rig.wheel_inertia"]
    w = p["rig.speed_bandwidth"]
    kp, ki = 2 * w * J, w * w * J
    omega_ref, _ = references(p)

    z_rate_next = z_rate + h * (load - normal_force) / mass
    z_next = z + h * z_rate_next
    # implicit Euler of J*omega' = kp*(ref - omega) + ki*e - T_soil, e' = ref - omega
    omega_next = ((J / h) * omega + kp * omega_ref + ki * (e_int + h * omega_ref) - soil_torque) / (
        J / h + kp + ki * h)
    e_next = e_int + h * (omega_ref - omega_next)
    motor_torque = kp * (omega_ref - omega_next) + ki * e_next
    return (z_next, z_rate_next, omega_next, e_next), motor_torque


def initial_state(p) -> tuple[float, float, float, float]:
    """Wheel resting on the surface, not moving vertically, already turning at omega_ref."""
    omega_ref, _ = references(p)
    return (0.0, 0.0, omega_ref, 0.0)


def build() -> ca.Function:
    """``rig_step(x, u, p, h) -> (x_next, motor_torque, carriage_speed)`` as a CasADi Function,
    traced from :func:`step` (for generated C)."""
    x, u = ca.SX.sym("x", len(STATES)), ca.SX.sym("u", len(FORCE_INPUTS))
    p, h = ca.SX.sym("p", len(RIG_NAMES)), ca.SX.sym("h")
    named = {name: p[k] for k, name in enumerate(RIG_NAMES)}
    nxt, torque = step(tuple(x[k] for k in range(len(STATES))),
                       tuple(u[k] for k in range(len(FORCE_INPUTS))), named, h)
    _, carriage = references(named)
    return ca.Function("rig_step", [x, u, p, h], [ca.vertcat(*nxt), torque, carriage],
                       ["x", "u", "p", "h"], ["x_next", "motor_torque", "carriage_speed"])


def defaults() -> dict[str, float]:
    return {prm.name: prm.default for prm in RIG_TABLE}


def check(name: str, value: float) -> float:
    """Validated value of rig parameter ``name`` (ParameterError naming the range otherwise)."""
    return RIG_TABLE[RIG_INDEX[name]].check(value)


