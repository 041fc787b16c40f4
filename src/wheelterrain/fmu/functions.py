"""What each FMU computes per step, as CasADi Functions shared by both FMU flavours.

The pythonfmu slaves (:mod:`wheelterrain.fmu.slaves`) and the native C wrapper
(fmu_src/native/) call the same Functions: the pythonfmu flavour through the CasADi VM or the
same generated C, the native flavour through the generated C only. So the two flavours agree by
construction, and the glue in each wrapper is bookkeeping (values, modes, messages), not
arithmetic.

WheelTerrain
    ``terrain_dynamic(u, angle, plastic, p) -> (y, status, info, plastic_rate)``,
    ``terrain_memory(u, plastic, p, h) -> plastic_next`` and
    ``terrain_quasi_static(u, p, guess) -> (y, status, info)`` with u = TERRAIN_INPUTS, y =
    TERRAIN_OUTPUTS (without wheel_angle and plastic_sinkage, the wrapper's states); ``guess``
    the sinkage [m] the solve starts Newton from (``warm_start``: the last contact_sinkage
    output), 0 for a cold solve (``model_functions.build().steady_from``). ``status``: STATUS_OK,
    STATUS_SLIP (the slip outside [-1, 1]: the wheel turning against the carriage's motion
    beyond the slip's regularisation speed, :func:`slips`; a wheel rolling backward is the
    mirror image of one rolling forward, MIRRORED;
    ``info`` is the slip), STATUS_ANGLE (the slip_angle input beyond SLIP_ANGLE_LIMIT; ``info``
    is the limit), STATUS_TURN (the yaw_rate input over the carriage speed beyond
    TURN_SLIP_LIMIT; ``info`` is the limit), STATUS_LOAD (load beyond the capacity; ``info``
    is the capacity),
    STATUS_UNCONVERGED (the solve's convergence check failed), STATUS_BURIED (dynamic mode:
    sinkage beyond full burial, R_c; ``info`` is R_c), STATUS_NONFINITE (an output is NaN or
    infinite: a last guard, so that no non-finite value is served). On a status other than OK the
    wrappers keep their previous outputs and refuse the next step with the reason.
SingleWheelRig, RoverChassis (state models, :class:`StateModel`)
    ``<prefix>_step(x, u, p, h) -> (x_next, memory)``, ``<prefix>_outputs(x, u, p, memory) ->
    y``, ``<prefix>_initial(p) -> x0`` and ``<prefix>_rates(x, u, p) -> (xdot, memory)``; the
    memory is what a step leaves besides the state (the motors' torques over the step).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache

import casadi as ca

from wheelterrain.fmu.variables import (
    GROUND_OUTPUTS,
    RIG_INPUTS,
    RIG_OUTPUTS,
    ROVER_INPUTS,
    ROVER_OUTPUTS,
    SINKAGE_RANGE,
    TERRAIN_INPUTS,
    TERRAIN_OUTPUTS,
)
from wheelterrain.model import contact, ground, rig, rover, soil, solve
from wheelterrain.model import functions as model_functions
from wheelterrain.model.slip import reference_radius
from wheelterrain.parameters import INDEX, NAMES, SLIP_ANGLE_LIMIT, TURN_SLIP_LIMIT

if RIG_INPUTS != rig.INPUTS:  # the FMU's inputs are the rig model's, in the same order
    raise ImportError(f"SingleWheelRig's inputs {RIG_INPUTS} differ from the rig model's "
                      f"{rig.INPUTS}")
if ROVER_INPUTS != rover.INPUTS:
    raise ImportError(f"RoverChassis' inputs {ROVER_INPUTS} differ from the rover model's "
                      f"{rover.INPUTS}")

SPEED_FLOOR = 1e-9  # m/s: below this a speed is at rest (the paper's slip 0, the turn slip's floor)
SLIP_SPEED_FLOOR = 1e-5
"""m/s: the model's slip is regularised below this speed (:func:`slips`), the way PlanarMechanics'
SlipBasedWheelJoint floors the speed its slip is divided by (vAdhesion_min): a tenth of the
slowest rim speed the rig and the rover declare (rig.rim_speed, rover.rim_speed >= 1e-4 m/s),
so no declared operating point moves, and a wheel and its axle pass through standstill with a
continuous slip."""
STATUS_OK, STATUS_SLIP, STATUS_LOAD, STATUS_UNCONVERGED, STATUS_BURIED, STATUS_NONFINITE = (
    0, 1, 2, 3, 4, 5)
STATUS_ANGLE, STATUS_TURN = 6, 7
FINITE_LIMIT = 1e300  # |y| at or above this (or NaN) is not a finite output
# What each status tells the user, as printf templates that both FMU flavours fill (the
# pythonfmu slaves with %, the native wrapper with snprintf), so both print one sentence.
# Arguments: SLIP wheel_speed, carriage_speed, slip; LOAD load, capacity, capacity;
# UNCONVERGED load; BURIED sinkage, full-burial depth; NONFINITE sinkage, wheel_speed,
# carriage_speed, load.
STATUS_MESSAGES = {
    STATUS_SLIP: ("wheel speed %g rad/s with carriage speed %g m/s gives slip %g, outside "
                  "the model's domain: the model covers rolling forward or backward, its slip "
                  "(omega*R_ref - V)/max(|omega*R_ref|, |V|, " f"{SLIP_SPEED_FLOOR:g}" " m/s) "
                  "along the rolling in [-1, 1], from a locked wheel (-1) to spinning in "
                  "place (1); a wheel turning against its carriage's motion only within "
                  f"{SLIP_SPEED_FLOOR:g}" " m/s of rest (|omega*R_ref| + |V|)"),
    STATUS_LOAD: ("load %g N exceeds what the wheel can carry fully buried (%.6g N); valid range "
                  "[0, %.6g] N"),
    STATUS_UNCONVERGED: "sinkage solve did not converge for load %g N",
    STATUS_BURIED: ("sinkage %g m is beyond full burial (%.6g m, the contact radius): the "
                    "contact model covers sinkage up to the depth at which the soil reaches "
                    "the axle; a wheel pushed deeper is outside its domain"),
    STATUS_NONFINITE: ("the model's outputs are not finite at sinkage %g m, wheel speed %g "
                       "rad/s, carriage speed %g m/s, load %g N"),
    STATUS_ANGLE: ("slip angle %g rad is outside the lateral contact's range [-%.6g, %.6g] "
                   "rad (80 deg): a wheel moving sideways has no heading to slip along"),
    STATUS_TURN: ("yaw rate %g rad/s at carriage speed %g m/s is a turn slip (yaw rate over "
                  "speed) outside the lateral contact's range [-%.6g, %.6g] rad/m: the wheel's "
                  "path may curve no tighter than a 0.1 m radius; a wheel yawing on the spot "
                  "or at rest is outside the model"),
}


def status_message(status: int, info: float, u) -> str:
    """STATUS_MESSAGES filled for a status of the terrain Functions with their inputs ``u``
    (TERRAIN_INPUTS); the native wrapper fills the same templates in C."""
    v = dict(zip(TERRAIN_INPUTS, u, strict=True))
    if status == STATUS_SLIP:
        return STATUS_MESSAGES[status] % (v["wheel_speed"], v["carriage_speed"], info)
    if status == STATUS_LOAD:
        return STATUS_MESSAGES[status] % (v["load"], info, info)
    if status == STATUS_BURIED:
        return STATUS_MESSAGES[status] % (v["sinkage"], info)
    if status == STATUS_NONFINITE:
        return STATUS_MESSAGES[status] % (v["sinkage"], v["wheel_speed"], v["carriage_speed"],
                                          v["load"])
    if status == STATUS_ANGLE:
        return STATUS_MESSAGES[status] % (v["slip_angle"], info, info)
    if status == STATUS_TURN:
        return STATUS_MESSAGES[status] % (v["yaw_rate"], v["carriage_speed"], info, info)
    return STATUS_MESSAGES[STATUS_UNCONVERGED] % v["load"]


def _finite(y, names):
    """1 when every entry of ``y`` (named ``names``) is finite (NaN compares false), else 0;
    UNDEFINED_OUTPUTS are not checked."""
    finite = 1
    for k, name in enumerate(names):
        if name not in UNDEFINED_OUTPUTS:
            finite = ca.logic_and(finite, ca.fabs(y[k]) < FINITE_LIMIT)
    return finite


MIRRORED = ("drawbar_pull", "torque", "gross_thrust", "compaction_resistance", "entry_angle",
            "exit_angle", "max_stress_angle", "aligning_moment", "turning_moment")
"""The WheelTerrain outputs that change sign for a wheel rolling backward: it is the mirror
image (x -> -x) of the wheel rolling forward at the speeds' magnitudes, its slip angle negated
(atan(v_y/v_x) with v_x < 0) and its yaw rate negated (a reflection reverses rotations about the
vertical; the turn slip r/V is unchanged) and its grousers mirrored (:func:`mirrored_grousers`:
the ripple's phase negated). Its forces along x, its torque, the contact's angles
(the contact begins behind the axle) and its moments about the vertical change sign; the
normal and lateral forces, the sinkage and the rut do not. The resistances keep the balance
drawbar_pull = gross_thrust - compaction_resistance - bulldozing (each along x, forward
positive). The slip output is the slip relative to the direction of rolling."""


def backward(wheel_speed, carriage_speed, slip_radius):
    """True where the wheel rolls backward: the rim's speed omega*R and the carriage's V sum
    below 0 (both <= 0, one below; within SLIP_SPEED_FLOOR of rest, the faster of the two
    moving backward). Plain arithmetic on floats or CasADi symbols."""
    return wheel_speed * slip_radius + carriage_speed < 0


def turning_weight(wheel_speed, carriage_speed, slip_radius):
    """The share of the wheel rolling forward in its contact, (1 + w)/2 with w = (omega*R + V)
    clipped to [-1, 1] over SLIP_SPEED_FLOOR: 1 rolling forward, 0 backward (the mirror image,
    MIRRORED), between them within SLIP_SPEED_FLOOR of the sum's turn, where the contact is the
    blend of the two. So the direction of rolling turns as a regularised friction law turns
    its force: continuously over a small speed, not at once. At rest (w = 0) the wheel sits in
    a symmetric imprint, the two contacts' halves: no compaction resistance, as a wheel at rest
    has none. Without it an ODE solver chatters where a driven wheel and its axle meet rest
    together (the contact's resistance and torque flip there: a sliding mode at omega*R = -V)."""
    w = (wheel_speed * slip_radius + carriage_speed) / SLIP_SPEED_FLOOR
    return (1 + ca.fmin(ca.fmax(w, -1), 1)) / 2


def slips(wheel_speed, carriage_speed, slip_radius):
    """(the model's slip, the paper's slip) from the wheel's and the carriage's speeds.

    The model's slip sigma = (omega*R - V)/max(|omega*R|, |V|, SLIP_SPEED_FLOOR)
    (:mod:`wheelterrain.model.slip`): the traction slip driving, the skid braking, so the
    forces are those of the true kinematics on either side, from a locked wheel (omega = 0: -1)
    to spinning in place (V = 0: 1). Below SLIP_SPEED_FLOOR the denominator is that speed: the
    slip is regularised, a continuous function of the two speeds through standstill (0 at
    rest), and a wheel turning against its axle's motion has a slip in [-1, 1] while the two
    speeds' magnitudes sum to no more than the floor (the wheel and its axle passing through
    rest a little apart, as when a vehicle reverses); beyond, |sigma| > 1, outside the model.
    Rolling backward (:func:`backward`) is taken as the mirror image: call this with both
    speeds negated. The paper's s = (omega*R - V)/V: NaN with the carriage at rest and the
    wheel turning (:func:`paper_slip`).
    """
    rim = wheel_speed * slip_radius
    scale = ca.fmax(ca.fmax(ca.fabs(rim), ca.fabs(carriage_speed)), SLIP_SPEED_FLOOR)
    return (rim - carriage_speed) / scale, paper_slip(wheel_speed, carriage_speed, slip_radius)


def paper_slip(wheel_speed, carriage_speed, slip_radius):
    """The paper's slip s = (omega*R - V)/V, 0 with both at rest; plain arithmetic on floats or
    CasADi symbols (:func:`slips` and the rig's outputs). With the carriage at rest and the
    wheel turning it has no value (s -> +-inf): NaN, which both FMU flavours serve with a
    logged warning (UNDEFINED_OUTPUTS), never a large number that looks like a result."""
    difference = wheel_speed * slip_radius - carriage_speed
    at_rest = rig.pick(abs(wheel_speed * slip_radius) < SPEED_FLOOR,
                       abs(carriage_speed) < SPEED_FLOOR, False)
    still = abs(carriage_speed) < SPEED_FLOOR
    return rig.pick(at_rest, 0.0, rig.pick(
        still, math.nan, difference / rig.pick(still, 1.0, carriage_speed)))


# Outputs that have no value at some operating points: NaN there, served with fmi2Warning and
# a logged reason (native flavour; the pythonfmu flavour logs the warning, its getters cannot
# return a status), and left out of the terrain's finiteness check. Each Var's description
# says where.
UNDEFINED_OUTPUTS = ("slip_paper", "sensor.slip_paper")


def slip_radius(p):
    """Radius R_ref the slip is referenced to, from the table parameter vector ``p``."""
    return reference_radius(soil.Params(p))


def with_rut_met(p, met):
    """The parameter vector ``p`` (table order) with the rut a terrain with memory says the
    wheel meets (``met``: WheelTerrain's inputs rut_met and rut_pressure_met) where it is
    deeper than its own: soil.rut_depth the deeper of the two, soil.rut_pressure that rut's."""
    rut_met, pressure_met = met
    k, j = INDEX["soil.rut_depth"], INDEX["soil.rut_pressure"]
    assert j == k + 1, "soil.rut_pressure follows soil.rut_depth in the table"
    deeper = rut_met > p[k]
    return ca.vertcat(p[:k], ca.fmax(p[k], rut_met), ca.if_else(deeper, pressure_met, p[j]),
                      p[j + 1:])


def mirrored_grousers(p, angle, sign):
    """(p, angle) for the contact of a wheel rolling in the direction ``sign`` (1 forward, -1
    backward): backward, the wheel's angle and its ripple.phase negated, the grousers' positions
    in the mirror image (the ripple's phase n_g*angle + phase negated), so that the wheel
    rolling backward is the mirror of one rolling forward over time, not only at an instant."""
    k = INDEX["ripple.phase"]
    return ca.vertcat(p[:k], sign * p[k], p[k + 1:]), sign * angle


def with_grouser_phase(p, phase):
    """The parameter vector ``p`` (table order) with ``phase`` [rad] added to its
    ripple.phase: a rover wheel's own grouser phase (rover.grouser_phase.<wheel>)."""
    k = INDEX["ripple.phase"]
    return ca.vertcat(p[:k], p[k] + phase, p[k + 1:])


@lru_cache(maxsize=4)
def terrain_functions(smooth: float | None = None
                      ) -> tuple[ca.Function, ca.Function, ca.Function]:
    """(terrain_dynamic, terrain_quasi_static, terrain_memory): see the module's docstring.
    ``smooth``: the smooth yield of that width [m] in terrain_dynamic (the slip NMPC's
    prediction model, :func:`wheelterrain.model.functions.contact_memory_smooth`); None, the
    FMU's own law.
    ``terrain_dynamic(u, angle, plastic, p) -> (y, status, info, plastic_rate)`` takes the
    wheel's plastic sinkage (WheelTerrain's second state) and gives its rate (model exchange);
    ``terrain_memory(u, plastic, p, h) -> plastic_next`` advances it over a co-simulation
    step with the inputs held, :func:`wheelterrain.model.contact.plastic_update`."""
    fns = model_functions.build()
    u, angle, given = ca.MX.sym("u", len(TERRAIN_INPUTS)), ca.MX.sym("angle"), ca.MX.sym(
        "p", len(NAMES))
    plastic = ca.MX.sym("plastic")
    named = {name: u[k] for k, name in enumerate(TERRAIN_INPUTS)}
    sinkage, rate, omega, speed, load = (named[n] for n in (
        "sinkage", "sinkage_rate", "wheel_speed", "carriage_speed", "load"))
    # the rut met: the parameter's or the input's
    p = with_rut_met(given, (named["rut_met"], named["rut_pressure_met"]))
    radius = slip_radius(p)
    held = (fns.contact_memory if smooth is None
            else model_functions.contact_memory_smooth(smooth))
    # sinkage R_c below the surface the contact begins at (a rut's): the soil at the axle
    full_burial = contact.radii(soil.Params(p))[0] + soil.rut_surface(soil.Params(p))

    def rolling(sign):
        """The wheel taken to roll in the direction ``sign`` (1 forward; -1 backward, the
        mirror image, MIRRORED): its slip and checks, its contact's outputs by name."""
        om, v = sign * omega, sign * speed
        unified, paper = slips(om, v, radius)
        beta = sign * named["slip_angle"]
        yaw = sign * named["yaw_rate"]  # turn slip yaw/V; a wheel at rest has none in range
        f = {"unified": unified, "paper": paper, "speed": v,
             "slip_bad": ca.logic_or(unified < -1, unified > 1),
             "angle_bad": ca.fabs(beta) > SLIP_ANGLE_LIMIT,
             "turn_bad": ca.fabs(yaw) > TURN_SLIP_LIMIT * ca.fmax(v, 0)}
        f["safe_slip"] = ca.fmin(ca.fmax(unified, -1), 1)  # only used when the status is OK
        f["safe_beta"] = ca.if_else(f["angle_bad"], 0, beta)
        f["turn_slip"] = ca.if_else(f["turn_bad"], 0, yaw / ca.fmax(v, SPEED_FLOOR))
        rolled, rolled_angle = mirrored_grousers(p, angle, sign)
        out = dict(zip((*contact.CONTACT_OUTPUTS, *contact.MEMORY_OUTPUTS),
                       held(sinkage, rate, f["safe_slip"], rolled_angle, plastic, v, rolled),
                       strict=True))
        out.update(zip(contact.LATERAL_OUTPUTS, fns.lateral_memory(
            sinkage, f["safe_slip"], f["safe_beta"], f["turn_slip"], plastic,
            out["mean_pressure"], p), strict=True))
        out.update(contact_sinkage=sinkage, slip=unified, slip_paper=paper)
        out.update({k: sign * out[k] for k in MIRRORED})
        return f, out

    # rolling backward (omega*R + V < 0): the mirror image of rolling forward (MIRRORED);
    # within SLIP_SPEED_FLOOR of that sum's turn, the two blended (:func:`turning_weight`)
    sign = ca.if_else(backward(omega, speed, radius), -1, 1)
    f, out = rolling(sign)
    weight = turning_weight(omega, speed, radius)
    (f_ahead, ahead), (f_behind, behind) = rolling(1), rolling(-1)
    blended = {k: weight * ahead[k] + (1 - weight) * behind[k] for k in out}
    blended.update(slip=out["slip"], slip_paper=out["slip_paper"])  # along the rolling
    within = ca.logic_and(weight > 0, weight < 1)
    y_one = ca.vertcat(*(out[k] for k in TERRAIN_OUTPUTS), out["plastic_rate"])
    y_two = ca.vertcat(*(blended[k] for k in TERRAIN_OUTPUTS), blended["plastic_rate"])
    y_all = ca.if_else(within, y_two, y_one, True)  # the second contact only near the turn
    y, plastic_rate = y_all[:len(TERRAIN_OUTPUTS)], y_all[len(TERRAIN_OUTPUTS)]
    unified, slip_bad, angle_bad, turn_bad = (f[k] for k in (
        "unified", "slip_bad", "angle_bad", "turn_bad"))
    status = ca.if_else(slip_bad, STATUS_SLIP, ca.if_else(
        angle_bad, STATUS_ANGLE, ca.if_else(turn_bad, STATUS_TURN, ca.if_else(
            sinkage > full_burial, STATUS_BURIED, ca.if_else(
                _finite(y, TERRAIN_OUTPUTS), STATUS_OK, STATUS_NONFINITE)))))
    info = ca.if_else(slip_bad, unified, ca.if_else(angle_bad, SLIP_ANGLE_LIMIT, ca.if_else(
        turn_bad, TURN_SLIP_LIMIT, full_burial)))
    dynamic = ca.Function("terrain_dynamic", [u, angle, plastic, given],
                          [y, status, info, plastic_rate],
                          ["u", "angle", "plastic", "p"], ["y", "status", "info", "plastic_rate"])
    h = ca.MX.sym("h")
    # the imprint relaxing toward the soil ahead needs the contact's mean pressure and exponent
    # at the step's start, which depend on neither the wheel angle nor the damper
    # (contact.yield_pressure: those two alone, the contact's numbers); toward the wheel it
    # needs neither, and the contact is not evaluated (a short-circuit switch)
    pressure, exponent = contact.yield_pressure(sinkage, f["safe_slip"], plastic,
                                                soil.Params(p), fns.nodes, smooth)
    toward_soil = fns.plastic_step(sinkage, plastic, f["speed"], pressure, exponent, p, h)
    toward_wheel = fns.plastic_step(sinkage, plastic, f["speed"], 1, 0, p, h)
    relaxation = p[INDEX["model.imprint_relaxation"]]
    memory = ca.Function("terrain_memory", [u, plastic, given, h],
                         [ca.if_else(relaxation == 1, toward_soil, toward_wheel, True)],
                         ["u", "plastic", "p", "h"], ["plastic_next"])

    guess = ca.MX.sym("guess")

    def steady_rolling(sign, f):
        """The quasi-static wheel rolling in the direction ``sign`` (``f``: its slip and
        checks from :func:`rolling`): its outputs by name."""
        steady = dict(zip(solve.STEADY_OUTPUTS, fns.steady_from(load, f["safe_slip"], p,
                                                                guess), strict=True))
        steady.update(contact_sinkage=steady["sinkage"], slip=f["unified"],
                      slip_paper=f["paper"], ripple_amplitude=0)
        steady.update(zip(contact.LATERAL_OUTPUTS, fns.lateral(
            steady["sinkage"], f["safe_slip"], f["safe_beta"], f["turn_slip"], p), strict=True))
        steady.update({k: sign * steady[k] for k in MIRRORED})
        return steady

    steady = steady_rolling(sign, f)
    ahead, behind = steady_rolling(1, f_ahead), steady_rolling(-1, f_behind)
    blended = {k: weight * ahead[k] + (1 - weight) * behind[k] for k in steady}
    blended.update(slip=steady["slip"], slip_paper=steady["slip_paper"])

    def solved(steady):
        return solve.solve_converged(steady["residual"], steady["last_step"])

    y_one = ca.vertcat(*(steady[k] for k in TERRAIN_OUTPUTS), steady["capacity"],
                       solved(steady))
    y_two = ca.vertcat(*(blended[k] for k in TERRAIN_OUTPUTS),
                       ca.fmin(ahead["capacity"], behind["capacity"]),
                       ca.logic_and(solved(ahead), solved(behind)))
    y_all = ca.if_else(within, y_two, y_one, True)  # the second solve only near the turn
    n = len(TERRAIN_OUTPUTS)
    y, capacity, converged = y_all[:n], y_all[n], y_all[n + 1]
    too_heavy = load > capacity
    status = ca.if_else(slip_bad, STATUS_SLIP, ca.if_else(angle_bad, STATUS_ANGLE, ca.if_else(
        turn_bad, STATUS_TURN, ca.if_else(too_heavy, STATUS_LOAD, ca.if_else(
            converged, ca.if_else(_finite(y, TERRAIN_OUTPUTS), STATUS_OK, STATUS_NONFINITE),
            STATUS_UNCONVERGED)))))
    info = ca.if_else(slip_bad, unified, ca.if_else(angle_bad, SLIP_ANGLE_LIMIT, ca.if_else(
        turn_bad, TURN_SLIP_LIMIT, capacity)))
    quasi = ca.Function("terrain_quasi_static", [u, given, guess], [y, status, info],
                        ["u", "p", "guess"], ["y", "status", "info"])
    return dynamic, quasi, memory


# The rig's own domain: a state outside it means the terrain no longer holds the wheel (or
# is not connected); both flavours refuse the next step with these messages. The sinkage
# limit is the pair's declared sinkage range (variables.SINKAGE_RANGE).
RIG_SINKAGE_LIMIT = SINKAGE_RANGE[1]
RIG_MESSAGES = {
    "depth": ("the wheel's sinkage %g m left the rig's range [-%g, %g] m: the soil's normal "
              "force no longer holds the load (is WheelTerrain connected, and can it carry "
              "rig.load?)"),
    "nonfinite": ("the rig's state is not finite (sinkage %g m, wheel speed %g rad/s, carriage "
                  "speed %g m/s)"),
}


def _contact_with_damper(z, z_rate, unified, angle, plastic, speed, p) -> dict:
    """``contact_memory``'s outputs by name, and ``damper_force``: the contact damper's share
    of the normal force (the normal force less its value at zero sinkage rate)."""
    fns = model_functions.build()
    names = (*contact.CONTACT_OUTPUTS, *contact.MEMORY_OUTPUTS)
    out = dict(zip(names, fns.contact_memory(z, z_rate, unified, angle, plastic, speed, p),
                   strict=True))
    still = fns.contact_memory(z, 0, unified, angle, plastic, speed, p)
    out["damper_force"] = out["normal_force"] - still[names.index("normal_force")]
    return out


RIG_LOOP_STATES = (*rig.RIG_STATES[:4], "wheel_angle", "plastic_sinkage")
"""The states of :func:`rig_on_contact`: the rig's (the carriage is kinematic), then
WheelTerrain's."""


def rig_on_contact(p, rig_values, sinkage_start: float) -> dict:
    """The paper's rig in continuous time on the contact with the soil's memory: the
    SingleWheelRig FMU's model-exchange rates (:func:`wheelterrain.model.rig.rates`) coupled to
    WheelTerrain's (``contact_memory``, its wheel angle and plastic sinkage states), the
    carriage kinematic. ``p``: the table's parameter vector; ``rig_values``: rig.* by name (its
    slip radius is set to the contact's own). Returns ``state`` and ``rate`` (SX, RIG_LOOP_STATES
    order), ``start`` (at rest in the soil at ``sinkage_start``, no memory yet, the wheel at its
    reference speed) and ``values``: every contact output, ``damper_force`` (the contact
    damper's share of the normal force), ``motor_torque`` and ``carriage_speed`` as SX of the
    state."""
    rp = {**rig_values, "rig.slip_radius": float(slip_radius(p))}
    x = ca.SX.sym("x", len(rig.RIG_STATES))
    angle, plastic = ca.SX.sym("wheel_angle"), ca.SX.sym("plastic_sinkage")
    omega_ref, speed = rig.references(rp)
    unified = slips(x[2], speed, rp["rig.slip_radius"])[0]
    values = _contact_with_damper(x[0], x[1], unified, angle, plastic, speed, p)
    u = [*(values[k] for k in rig.FORCE_INPUTS), 0, 0]
    rates = rig.rates(x, u, rp)
    values.update(motor_torque=rig.motor_torque(x, u, rp), carriage_speed=speed)
    return {"state": ca.vertcat(x[:4], angle, plastic),
            "rate": ca.vertcat(*rates[:4], x[2], values["plastic_rate"]),
            "start": [sinkage_start, 0.0, omega_ref, 0.0, 0.0, 0.0], "values": values,
            "rig": rp}


def _soil_from_map(p, position, g: dict):
    """The parameter vector ``p`` with its soil rows the map ``g``'s (ground.NAMES by name) at
    ``position`` (the rows are side by side in the table)."""
    first, last = INDEX[ground.SOIL_NAMES[0]], INDEX[ground.SOIL_NAMES[-1]]
    return ca.vertcat(p[:first], *ground.soil_at(position, g), p[last + 1:])


def rover_on_contact(p, r, g: dict | None = None, heave_start: float = 0.0, slope=0.0,
                     met=None) -> dict:
    """The rover in continuous time on four contacts with the soil's memory: the RoverChassis
    FMU's model-exchange rates (:func:`wheelterrain.model.rover.rates`) with each wheel's
    WheelTerrain (``contact_memory``, its wheel angle and plastic sinkage states), every wheel
    on the soil of ``p`` (the table's parameter vector), or where a terrain map ``g``
    (ground.NAMES by name) is given on its soil at the wheel's position, and the rover's
    parameters ``r`` (by name), on the slope ``slope`` [rad]. Without ``met`` no rut profile
    along the tracks (model exchange records none); with it (a CasADi vector: per wheel a
    table of the profile, :func:`wheelterrain.model.ground.met_in_table`, side by side) each
    wheel meets the rut the table gives at its position, as the Terrain FMU serves it.
    Returns ``state`` and ``rate`` (SX: rover.STATES, the four wheel angles, the four plastic
    sinkages), ``start`` (rover.initial_state ``heave_start`` m in the soil, no memory yet),
    ``x`` (the chassis' states by name), ``u`` (the chassis' inputs by name: the
    forces as SX of the state) and ``wheels`` (per wheel: every contact output,
    ``damper_force``, ``sinkage``, ``sinkage_rate``, ``wheel_speed``, ``axle_speed``)."""
    radius = slip_radius(p)
    x = ca.SX.sym("x", len(rover.STATES))
    angles, plastics = ca.SX.sym("angle", len(rover.WHEELS)), ca.SX.sym(
        "plastic", len(rover.WHEELS))
    xs = tuple(x[k] for k in range(len(rover.STATES)))
    u = {"slope": slope, "towing_force": 0.0}
    extra, wheels = [], {}
    for k, wheel in enumerate(rover.WHEELS):
        z, z_rate = rover.wheel_kinematics(xs, r, wheel)
        speed = rover.axle_speed(xs, r, wheel)
        omega = xs[rover.STATES.index(f"{wheel}.wheel_speed")]
        unified = slips(omega, speed, radius)[0]
        where = rover.wheel_position(r, xs[rover.STATES.index("position")], wheel)
        pk = p if g is None else _soil_from_map(p, where, g)
        pk = with_grouser_phase(pk, rover.grouser_phase(r, wheel))
        if met is not None:  # the rut the Terrain serves this wheel
            size = met.numel() // len(rover.WHEELS)
            table = met[k * size:(k + 1) * size]
            pk = with_rut_met(pk, ground.met_in_table(where, g or ground.defaults(), table))
        out = _contact_with_damper(z, z_rate, unified, angles[k], plastics[k], speed, pk)
        for name in rover.WHEEL_FORCES:
            u[f"{wheel}.{name}"] = out[name]
        u[f"{wheel}.wheel_speed_command"] = 0.0
        u[f"{wheel}.motor_torque_command"] = 0.0
        extra.append(out["plastic_rate"])
        wheels[wheel] = {**out, "sinkage": z, "sinkage_rate": z_rate, "wheel_speed": omega,
                         "axle_speed": speed}
    omegas = [wheels[w]["wheel_speed"] for w in rover.WHEELS]
    return {"state": ca.vertcat(x, angles, plastics),
            "rate": ca.vertcat(*rover.rates(xs, u, r), *omegas, *extra),
            "start": [*rover.initial_state(r, heave=heave_start),
                      *([0.0] * (2 * len(rover.WHEELS)))],
            "x": dict(zip(rover.STATES, xs, strict=True)), "u": u, "wheels": wheels}


def rig_state_problem(x) -> str | None:
    """Why the rig state ``x`` (rig.RIG_STATES, floats) is outside the rig's domain, or None.
    The native wrapper makes the same two checks with the same messages (state_hooks.c)."""
    state = dict(zip(rig.RIG_STATES, x, strict=True))
    if not all(abs(v) < FINITE_LIMIT for v in x):
        return RIG_MESSAGES["nonfinite"] % (state["sinkage"], state["wheel_speed"],
                                            state["carriage_speed"])
    if abs(state["sinkage"]) > RIG_SINKAGE_LIMIT:
        return RIG_MESSAGES["depth"] % (state["sinkage"], RIG_SINKAGE_LIMIT, RIG_SINKAGE_LIMIT)
    return None


def rig_outputs(x, u, p, motor_torque):
    """RIG_OUTPUTS, in that order, from the rig state x (rig.RIG_STATES), the inputs u
    (RIG_INPUTS), the rig parameters ``p[name]`` and the motor torque; plain arithmetic on
    floats or CasADi symbols. Named, so an output reaches the right place whatever the order."""
    state = dict(zip(rig.RIG_STATES, x, strict=True))
    inputs = dict(zip(RIG_INPUTS, u, strict=True))
    out = {"sinkage": state["sinkage"], "sinkage_rate": state["sinkage_rate"],
           "wheel_speed": state["wheel_speed"], "carriage_speed": state["carriage_speed"],
           "motor_torque": motor_torque, "speed_error_integral": state["speed_error_integral"],
           "sensor.drawbar_pull": inputs["drawbar_pull"],
           "sensor.normal_force": inputs["normal_force"], "sensor.sinkage": state["sinkage"],
           "sensor.slip_paper": paper_slip(state["wheel_speed"], state["carriage_speed"],
                                           p["rig.slip_radius"])}
    return tuple(out[name] for name in RIG_OUTPUTS)


@lru_cache(maxsize=1)
def rig_functions() -> tuple[ca.Function, ca.Function, ca.Function]:
    """(rig_step, rig_outputs, rig_initial(p) -> x0)."""
    x, u = ca.SX.sym("x", len(rig.RIG_STATES)), ca.SX.sym("u", len(rig.INPUTS))
    p, torque = ca.SX.sym("p", len(rig.RIG_NAMES)), ca.SX.sym("motor_torque")
    named = rig.named(p)
    y = rig_outputs(tuple(x[k] for k in range(len(rig.RIG_STATES))),
                    tuple(u[k] for k in range(len(rig.INPUTS))), named, torque)
    outputs = ca.Function("rig_outputs", [x, u, p, torque], [ca.vertcat(*y)],
                          ["x", "u", "p", "motor_torque"], ["y"])
    initial = ca.Function("rig_initial", [p], [ca.vertcat(*rig.initial_state(named))], ["p"],
                          ["x0"])
    return rig.build(), outputs, initial


@lru_cache(maxsize=1)
def rig_rates_function() -> ca.Function:
    """``rig_rates(x, u, p) -> (xdot, motor_torque)``: the rig's continuous equations
    (:func:`wheelterrain.model.rig.rates`, the ones its co-simulation step integrates) and the
    motor torque in that state, for the model-exchange interface."""
    x, u = ca.SX.sym("x", len(rig.RIG_STATES)), ca.SX.sym("u", len(rig.INPUTS))
    p = ca.SX.sym("p", len(rig.RIG_NAMES))
    named = rig.named(p)
    xs, us = tuple(x[k] for k in range(x.numel())), tuple(u[k] for k in range(u.numel()))
    return ca.Function("rig_rates", [x, u, p],
                       [ca.vertcat(*rig.rates(xs, us, named)), rig.motor_torque(xs, us, named)],
                       ["x", "u", "p"], ["xdot", "motor_torque"])


# --- RoverChassis ------------------------------------------------------------------------------

ROVER_HEAVE_LIMIT = SINKAGE_RANGE[1]
ROVER_MESSAGES = {
    "depth": ("the rover's heave %g m left its range [-%g, %g] m: the soils no longer carry "
              "it (are the four WheelTerrain connected, and can they carry the rover?)"),
    "nonfinite": ("the rover's state is not finite (heave %g m, speed %g m/s, pitch %g rad)"),
}


def rover_state_problem(x) -> str | None:
    """Why the rover state ``x`` (rover.STATES, floats) is outside its domain, or None; the
    native wrapper makes the same checks with the same messages."""
    state = dict(zip(rover.STATES, x, strict=True))
    if not all(abs(v) < FINITE_LIMIT for v in x):
        return ROVER_MESSAGES["nonfinite"] % (state["heave"], state["speed"], state["pitch"])
    if abs(state["heave"]) > ROVER_HEAVE_LIMIT:
        return ROVER_MESSAGES["depth"] % (state["heave"], ROVER_HEAVE_LIMIT, ROVER_HEAVE_LIMIT)
    return None


def rover_outputs(x, u, p, motor_torques):
    """ROVER_OUTPUTS, in that order, from the rover state (rover.STATES), the inputs u
    (ROVER_INPUTS), the rover parameters ``p[name]`` and the four motor torques."""
    state = dict(zip(rover.STATES, x, strict=True))
    out = {name: state[name] for name in rover.CHASSIS_STATES}
    out["effective_slope"], out["effective_towing_force"] = rover.effective_inputs(x, u, p)
    for k, w in enumerate(rover.WHEELS):
        z, rate = rover.wheel_kinematics(x, p, w)
        out.update({f"{w}.sinkage": z, f"{w}.sinkage_rate": rate,
                    f"{w}.wheel_speed": state[f"{w}.wheel_speed"],
                    f"{w}.carriage_speed": rover.axle_speed(x, p, w),
                    f"{w}.motor_torque": motor_torques[k],
                    f"{w}.speed_error_integral": state[f"{w}.speed_error_integral"],
                    f"{w}.position": rover.wheel_position(p, state["position"], w)})
    return tuple(out[name] for name in ROVER_OUTPUTS)


@lru_cache(maxsize=1)
def rover_functions() -> tuple[ca.Function, ca.Function, ca.Function, ca.Function]:
    """(rover_step, rover_outputs, rover_initial, rover_rates)."""
    x, u = ca.SX.sym("x", len(rover.STATES)), ca.SX.sym("u", len(rover.INPUTS))
    p, torques = ca.SX.sym("p", len(rover.ROVER_NAMES)), ca.SX.sym("memory", len(rover.WHEELS))
    named = rover.named([p[k] for k in range(p.numel())])
    xs = tuple(x[k] for k in range(x.numel()))
    us = {n: u[k] for k, n in enumerate(rover.INPUTS)}
    y = rover_outputs(xs, us, named, [torques[k] for k in range(torques.numel())])
    outputs = ca.Function("rover_outputs", [x, u, p, torques], [ca.vertcat(*y)],
                          ["x", "u", "p", "memory"], ["y"])
    initial = ca.Function("rover_initial", [p], [ca.vertcat(*rover.initial_state(named))],
                          ["p"], ["x0"])
    step, rates = rover.build()
    return step, outputs, initial, rates


# --- Terrain (a terrain map and the rut profile of one track: model.ground) --------------------


def ground_outputs(x, u, p, memory):
    """GROUND_OUTPUTS, in that order: each query point's soil (ground.outputs)."""
    del memory  # the record is the state
    return ground.outputs(x, u, p)


def _ground_step(x, u, p, h):
    del h  # the record keeps the rut left at each step, whatever its length
    return ground.lay_ruts(x, u, p), ()


@lru_cache(maxsize=1)
def ground_functions() -> tuple[ca.Function, ca.Function, ca.Function, ca.Function]:
    """(ground_step, ground_outputs, ground_initial, ground_rates): the rut profile is the
    state; the step records each query point's rut; it has no rates (model exchange has no
    step: the record stays as it is)."""
    # MX: the record's slot is read by a symbolic index, not by a switch over every slot
    x, u = ca.MX.sym("x", len(ground.STATES)), ca.MX.sym("u", len(ground.INPUTS))
    p, h, memory = ca.MX.sym("p", len(ground.NAMES)), ca.MX.sym("h"), ca.MX.sym("memory", 0)
    named = {name: p[k] for k, name in enumerate(ground.NAMES)}
    us = ca.vertsplit(u)
    y = ca.vertcat(*ground_outputs(x, us, named, memory))
    empty = ca.MX(0, 1)
    x0 = ca.DM(ground.no_ruts())
    return (ca.Function("ground_step", [x, u, p, h], [ground.lay_ruts(x, us, named), empty],
                        ["x", "u", "p", "h"], ["x_next", "memory"]),
            ca.Function("ground_outputs", [x, u, p, memory], [y], ["x", "u", "p", "memory"],
                        ["y"]),
            ca.Function("ground_initial", [p], [x0], ["p"], ["x0"]),
            ca.Function("ground_rates", [x, u, p], [ca.MX.zeros(x.numel()), empty],
                        ["x", "u", "p"], ["xdot", "memory"]))


@dataclass(frozen=True)
class StateModel:
    """A state-space FMU (SingleWheelRig, RoverChassis): what both flavours need to run it.
    ``step(x, u, p, h)`` -> (x_next, memory) on floats (u a tuple in ``inputs`` order, p by
    name); ``outputs(x, u, p, memory)`` -> y in ``outputs`` order; ``problem(x)`` -> why the
    state is outside the model's domain, or None. The native wrapper runs the generated C of
    ``functions()`` (prefix_step, prefix_outputs, prefix_initial, prefix_rates) and makes the
    ``problem`` checks from ``depth_state``, ``depth_limit``, ``nonfinite_states`` and
    ``messages``."""

    name: str
    prefix: str
    states: tuple[str, ...]
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    parameters: tuple[str, ...]
    memory: int
    depth_state: str | None  # None: a model without states (nothing to check)
    depth_limit: float
    nonfinite_states: tuple[str, ...]
    messages: dict
    step: Callable
    output_values: Callable
    initial: Callable
    problem: Callable
    functions: Callable


def _rig_step(x, u, p, h):
    nxt, torque = rig.step(x, u, p, h)
    return nxt, (torque,)


def _rig_outputs(x, u, p, memory):
    return rig_outputs(x, u, p, memory[0])


def _rover_step(x, u, p, h):
    return rover.step(x, dict(zip(rover.INPUTS, u, strict=True)), p, h)


def _rover_outputs(x, u, p, memory):
    return rover_outputs(x, dict(zip(rover.INPUTS, u, strict=True)), p, memory)


STATE_MODELS = {
    "SingleWheelRig": StateModel(
        "SingleWheelRig", "rig", rig.RIG_STATES, rig.INPUTS, RIG_OUTPUTS, rig.RIG_NAMES, 1,
        "sinkage", RIG_SINKAGE_LIMIT, ("sinkage", "wheel_speed", "carriage_speed"),
        RIG_MESSAGES, _rig_step, _rig_outputs, rig.initial_state, rig_state_problem,
        lambda: (*rig_functions(), rig_rates_function())),
    "RoverChassis": StateModel(
        "RoverChassis", "rover", rover.STATES, rover.INPUTS, ROVER_OUTPUTS, rover.ROVER_NAMES,
        len(rover.WHEELS), "heave", ROVER_HEAVE_LIMIT, ("heave", "speed", "pitch"),
        ROVER_MESSAGES, _rover_step, _rover_outputs, rover.initial_state, rover_state_problem,
        rover_functions),
    "Terrain": StateModel(
        "Terrain", "ground", ground.STATES, ground.INPUTS, GROUND_OUTPUTS, ground.NAMES, 0,
        None, 0.0, (), {}, _ground_step, ground_outputs,
        lambda p: ground.no_ruts(), lambda x: None, ground_functions),
}
"""The state-space FMUs by model name."""
