"""The model's CasADi Functions, assembled once: the contact (:mod:`wheelterrain.model.contact`,
on the soil's laws of :mod:`wheelterrain.model.soil`), the quasi-static sinkage solve and steady
state (:mod:`wheelterrain.model.solve`), and their exact Jacobians.

Everything that computes a force in this project (the Python API, the CLI, the FMUs, the MPC,
the calibration, the rover) calls :func:`build`'s Functions; nothing else re-derives a formula.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import casadi as ca

from wheelterrain.model import solve
from wheelterrain.model.contact import (
    CONTACT_INPUTS,
    CONTACT_OUTPUTS,
    DEFAULT_NODES,
    FORCES,
    LATERAL_INPUTS,
    LATERAL_MEMORY_INPUTS,
    LATERAL_OUTPUTS,
    LATERAL_RESULTANTS,
    MEMORY_OUTPUTS,
    contact_at,
    lateral_at,
    plastic_rate,
    plastic_update,
)
from wheelterrain.model.soil import Params
from wheelterrain.model.solve import STEADY_INPUTS, STEADY_OUTPUTS
from wheelterrain.parameters import NAMES


@dataclass(frozen=True)
class ModelFunctions:
    """The CasADi Functions of the model, built once per quadrature order.

    - ``contact(sinkage, sinkage_rate, slip, wheel_angle, p)`` -> CONTACT_OUTPUTS (ripple on).
    - ``contact_memory(sinkage, sinkage_rate, slip, wheel_angle, plastic_sinkage,
      carriage_speed, p)`` -> CONTACT_OUTPUTS and MEMORY_OUTPUTS: the same with the wheel's
      plastic sinkage (the elastic-plastic soil of :func:`_contact`); ``contact`` exactly where
      sinkage >= plastic_sinkage.
    - ``plastic_step(sinkage, plastic_sinkage, carriage_speed, mean_pressure,
      sinkage_exponent, p, h)`` -> ``plastic_sinkage_next`` after a co-simulation step
      (:func:`plastic_update`; ``mean_pressure`` and ``sinkage_exponent``: ``contact_memory``'s
      outputs at the step's start).
    - ``contact_jacobian`` -> ``d_state`` (3x3: normal_force, drawbar_pull, torque by sinkage,
      sinkage_rate, slip) and ``d_params`` (3 x len(p)).
    - ``sinkage_solve(load, slip, p)`` -> ``sinkage``, ``residual`` (relative), ``last_step``
      (last Newton step in log(theta_f)), ``capacity`` (normal force fully buried). Ripple-free,
      zero sinkage rate.
    - ``capacity(slip, p)`` -> ``capacity``: static normal force fully buried (sinkage = R_c),
      the largest load the wheel can carry; the same expression the solve checks against.
    - ``steady(load, slip, p)`` -> STEADY_OUTPUTS: the solve plus the ripple-free contact there.
    - ``steady_from(load, slip, p, guess)`` -> STEADY_OUTPUTS: the same started warm from a
      sinkage guess (:func:`wheelterrain.model.solve.steady_from`); ``steady`` itself where
      the guess is not > 0.
    - ``steady_jacobian(load, slip, p, sinkage)`` -> ``d_inputs`` (4x2: sinkage, normal_force,
      drawbar_pull, torque by load, slip) and ``d_params`` (4 x len(p)), by the implicit function
      theorem at a solved ``sinkage``.
    - ``lateral(sinkage, slip, slip_angle, turn_slip, p)`` -> LATERAL_OUTPUTS: a wheel at a
      slip angle and a turn slip (:func:`wheelterrain.model.contact.lateral_at`),
      quasi-static, ripple-free.
    - ``lateral_jacobian(sinkage, slip, slip_angle, turn_slip, p)`` -> ``d_state`` (4x4:
      LATERAL_RESULTANTS by sinkage, slip, slip_angle, turn_slip), exact.
    - ``lateral_memory(sinkage, slip, slip_angle, turn_slip, plastic_sinkage, mean_pressure,
      p)`` -> LATERAL_OUTPUTS: the same at the yield sinkage with the elastic unloading of the soil
      with memory (``mean_pressure``: ``contact_memory``'s output at the same state).

    All are MX graphs over the SX Functions of :func:`form_switch`: the contact is a called switch,
    not inlined, so each evaluation runs the one form and rule that apply.
    """

    contact: ca.Function
    contact_memory: ca.Function
    plastic_step: ca.Function
    contact_jacobian: ca.Function
    sinkage_solve: ca.Function
    capacity: ca.Function
    steady: ca.Function
    steady_from: ca.Function
    steady_jacobian: ca.Function
    lateral: ca.Function
    lateral_jacobian: ca.Function
    lateral_memory: ca.Function
    nodes: tuple[int, int]


@lru_cache(maxsize=4)
def contact_memory_smooth(width: float, nodes: tuple[int, int] = DEFAULT_NODES) -> ca.Function:
    """``contact_memory`` with the smooth yield of width ``width`` [m] (:func:`contact_at`'s
    ``smooth``, :func:`plastic_rate`'s): the same inputs and outputs, derivatives continuous
    across z = z_p, for a prediction model that linearises across the yield (the slip NMPC);
    within ~``width`` of the yield it differs from ``contact_memory``, elsewhere to rounding."""
    z, z_rate, slip, angle, p = _symbols()
    plastic, speed = ca.MX.sym("plastic_sinkage"), ca.MX.sym("carriage_speed")
    return _contact_memory("contact_memory_smooth", z, z_rate, slip, angle, plastic, speed, p,
                           nodes, width)


def _contact_memory(name: str, z, z_rate, slip, angle, plastic, speed, p,
                    nodes: tuple[int, int], smooth: float | None) -> ca.Function:
    """The contact with the soil's memory and the plastic sinkage's rate (``smooth``: the
    smooth yield's width, None for the law) as the Function ``name`` of those symbols."""
    P = Params(p)
    held = contact_at(z, z_rate, slip, angle, P, nodes, ripple=True, plastic=plastic,
                      smooth=smooth)
    held["plastic_rate"] = plastic_rate(z, z_rate, plastic, speed, P, held["imprint_target"],
                                        smooth=smooth)
    return ca.Function(
        name, [z, z_rate, slip, angle, plastic, speed, p],
        [held[k] for k in (*CONTACT_OUTPUTS, *MEMORY_OUTPUTS)],
        [*CONTACT_INPUTS[:4], "plastic_sinkage", "carriage_speed", "p"],
        [*CONTACT_OUTPUTS, *MEMORY_OUTPUTS])


def _symbols():
    return (ca.MX.sym("sinkage"), ca.MX.sym("sinkage_rate"), ca.MX.sym("slip"),
            ca.MX.sym("wheel_angle"), ca.MX.sym("p", len(NAMES)))


@lru_cache(maxsize=4)
def build(nodes: tuple[int, int] = DEFAULT_NODES) -> ModelFunctions:
    """Build (once per ``nodes``) every CasADi Function of the model: the contact of
    :mod:`wheelterrain.model.contact`, the sinkage solve of :mod:`wheelterrain.model.solve`."""
    z, z_rate, slip, angle, p = _symbols()
    P = Params(p)
    out = contact_at(z, z_rate, slip, angle, P, nodes, ripple=True)
    contact = ca.Function("contact", [z, z_rate, slip, angle, p],
                          [out[k] for k in CONTACT_OUTPUTS], list(CONTACT_INPUTS),
                          list(CONTACT_OUTPUTS))

    plastic, speed, h = (ca.MX.sym("plastic_sinkage"), ca.MX.sym("carriage_speed"),
                         ca.MX.sym("h"))
    contact_memory = _contact_memory("contact_memory", z, z_rate, slip, angle, plastic, speed,
                                     p, nodes, None)
    pressure, exponent = ca.MX.sym("mean_pressure"), ca.MX.sym("sinkage_exponent")
    plastic_step = ca.Function(
        "plastic_step", [z, plastic, speed, pressure, exponent, p, h],
        [plastic_update(z, plastic, speed, P, h, pressure, exponent)],
        ["sinkage", "plastic_sinkage", "carriage_speed", "mean_pressure", "sinkage_exponent",
         "p", "h"], ["plastic_sinkage_next"])

    forces = ca.vertcat(*(out[k] for k in FORCES))
    contact_jacobian = ca.Function(
        "contact_jacobian", [z, z_rate, slip, angle, p],
        [ca.jacobian(forces, ca.vertcat(z, z_rate, slip)), ca.jacobian(forces, p)],
        list(CONTACT_INPUTS), ["d_state", "d_params"])

    load = ca.MX.sym("load")
    solution = solve.sinkage_solve_expr(load, slip, P, nodes)
    rows = solve.steady_expr(load, slip, P, nodes, solve=solution)
    solved = ("sinkage", "residual", "last_step", "capacity")
    # the same solve alone: Fz_static at the final angle, not the whole contact there
    state, theta, capacity = solution
    fz_static = solve.static_functions(nodes)[1](theta, slip, p)
    sinkage_solve = ca.Function(
        "sinkage_solve", [load, slip, p],
        [*solve.solve_finish(load, state, fz_static, P), capacity],
        list(STEADY_INPUTS), list(solved))
    capacity_fn = ca.Function("capacity", [slip, p], [rows[-1]], ["slip", "p"], ["capacity"])
    steady = ca.Function("steady", [load, slip, p], rows, list(STEADY_INPUTS),
                         list(STEADY_OUTPUTS))

    # Implicit function theorem at a solved sinkage: Fz_static(z, slip, p) = load.
    at = contact_at(z, 0, slip, 0, P, nodes, ripple=False)
    q = ca.vertcat(load, slip)
    balance = at["normal_force_static"] - load
    dz_dq = -ca.jacobian(balance, q) / ca.jacobian(balance, z)
    dz_dp = -ca.jacobian(balance, p) / ca.jacobian(balance, z)
    ys = ca.vertcat(*(at[k] for k in FORCES))
    dy_dz = ca.jacobian(ys, z)
    d_inputs = ca.vertcat(dz_dq, ca.jacobian(ys, q) + dy_dz @ dz_dq)
    d_params = ca.vertcat(dz_dp, ca.jacobian(ys, p) + dy_dz @ dz_dp)
    steady_jacobian = ca.Function("steady_jacobian", [load, slip, p, z], [d_inputs, d_params],
                                  [*STEADY_INPUTS, "sinkage"], ["d_inputs", "d_params"])
    angle_of_slip, turn_slip = ca.MX.sym("slip_angle"), ca.MX.sym("turn_slip")
    side = lateral_at(z, slip, angle_of_slip, turn_slip, P, nodes)
    lateral = ca.Function("lateral", [z, slip, angle_of_slip, turn_slip, p],
                          [side[k] for k in LATERAL_OUTPUTS], list(LATERAL_INPUTS),
                          list(LATERAL_OUTPUTS))
    resultants = ca.vertcat(*(side[k] for k in LATERAL_RESULTANTS))
    lateral_jacobian = ca.Function(
        "lateral_jacobian", [z, slip, angle_of_slip, turn_slip, p],
        [ca.jacobian(resultants, ca.vertcat(z, slip, angle_of_slip, turn_slip))],
        list(LATERAL_INPUTS), ["d_state"])
    held_side = lateral_at(z, slip, angle_of_slip, turn_slip, P, nodes, plastic=plastic,
                           mean_pressure=pressure)
    lateral_memory = ca.Function(
        "lateral_memory", [z, slip, angle_of_slip, turn_slip, plastic, pressure, p],
        [held_side[k] for k in LATERAL_OUTPUTS], list(LATERAL_MEMORY_INPUTS),
        list(LATERAL_OUTPUTS))
    return ModelFunctions(contact, contact_memory, plastic_step, contact_jacobian, sinkage_solve,
                          capacity_fn, steady, solve.steady_from(steady, nodes), steady_jacobian,
                          lateral, lateral_jacobian, lateral_memory, nodes)
