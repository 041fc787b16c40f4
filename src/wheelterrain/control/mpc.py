"""Slip-control NMPC on the CasADi twin: the prediction model is the FMUs' own Functions.

Prediction model
    The WheelTerrain FMU's Function ``terrain_dynamic`` (the full contact model, grouser ripple
    included, at the wheel's sinkage, sinkage rate, speeds and angle, with the soil's memory)
    closed by the rig's equations :func:`wheelterrain.model.rig.rates` in the same drive and
    carriage mode as the plant. States (MPC_STATES): sinkage, sinkage rate, wheel speed, the
    speed loop's integral, carriage speed, wheel angle, plastic sinkage (the soil's memory,
    the plant's own state, measured). No surrogate: the prediction differs from the
    co-simulated plant by its discretisation and by the yield's corner, rounded over
    YIELD_WIDTH so that a linearisation can cross it.

Why a speed command (the stiffness analysis, :func:`stiffness`)
    With the motor torque as the input, the wheel on the calibrated soil has eigenvalues down to
    -314 1/s at C1 and -152 1/s at C4 (a step of 0.02 s multiplies them by 3 to 6): the slip
    moves within a few ms of a torque change, far inside a 50 Hz controller's hold. The
    eigenstructure is the soil's: on the earlier calibration (wheel-element shear, whose pull
    saturates with slip) the C4 sinkage-slip pair was unstable (+6.7 +- 35j 1/s), slip-sinkage
    softening the soil faster than the wheel slows. The drive's own speed loop (rig.drive = 1,
    poles at -rig.speed_bandwidth) holds the slip on either soil, so the MPC commands the wheel
    speed and keeps the loop, with its torque, in the prediction and in the constraints.

Discretisation
    Backward Euler on each interval (the states at the end of the interval are decision
    variables, the forces are evaluated there): L-stable, so the stiff loop and soil modes decay
    in the prediction as they do in the plant, with no substeps. Multiple shooting: the NLP
    holds the states, the interval residuals are equality constraints.

Objectives
    ``track``: sum of ((slip - reference)/SLIP_SCALE)^2 plus a small penalty on command moves.
    ``efficiency``: maximise the tractive efficiency DP*V/(T_motor*omega) (drawbar pull per unit
    of motor power, times the carriage speed), with the same move penalty.
Constraints: |motor torque| <= torque_limit, motor power <= power_limit, sinkage <=
sinkage_limit, 0 <= speed command <= speed_limit.

Solvers
    ``sqpmethod`` (CasADi's SQP with the qrqp QP solver, Gauss-Newton Hessian for ``track``),
    ``ipopt``, and ``rti``: the real-time iteration, one Gauss-Newton QP per sample from the
    shifted warm start, as sqpmethod with max_iterations = 1 takes it, but with the QP's
    structure used. The interval residuals are equality constraints whose Jacobian in the
    states is block bidiagonal; they are eliminated (condensing: the state steps as an affine
    function of the command steps, a sparse LU), which leaves a dense QP in the horizon's
    commands only (at the default horizon 30 variables, the torque, power and sinkage limits
    as 90 rows) for DAQP, a dual active-set solver for small dense QPs. The QP is the same one
    (the elimination is exact), so the iterate is sqpmethod's to rounding; linearisation,
    condensing, QP and update are one CasADi Function, one call per sample. Least squares
    (``track``) only: the Gauss-Newton Hessian needs no multipliers.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from functools import lru_cache

import casadi as ca
import numpy as np

from wheelterrain import compiled as native
from wheelterrain.fmu import functions as fmu_model
from wheelterrain.model import rig
from wheelterrain.parameters import NAMES

MPC_STATES = (*rig.RIG_STATES, "wheel_angle")
"""The prediction's states without the soil's memory (the default, Settings.memory False)."""
MEMORY_STATES = (*MPC_STATES, "plastic_sinkage")
"""The prediction's states with it (Settings.memory True): the plant's plastic sinkage too."""
YIELD_WIDTH = 1e-5
"""m: the memory prediction's smooth yield (contact.soft_max of the sinkage and the plastic
sinkage over it): the plant's law has a corner at z = z_p that a linearisation cannot cross.
A hundredth of a millimetre, small against the ripple's digging (0.5-0.7 mm). Measured on the
nominal scenario: 3e-6 m tracks to 1.1e-4 with rti but sqpmethod diverges; 1e-6 m leaves 28
of 300 rti QPs unsolved; 1e-5 m, 4.1e-4 with both; 3e-5 m, 1.6e-3. Chosen on that scenario,
so its figure is in-sample; terrain-change (4.3e-3) did not see the choice."""


def states(memory: bool = False) -> tuple[str, ...]:
    """The prediction's states: MEMORY_STATES with the soil's memory, else MPC_STATES."""
    return MEMORY_STATES if memory else MPC_STATES
OUTPUTS = ("slip", "drawbar_pull", "normal_force", "soil_torque", "motor_torque", "power")
REGULARISATION = 1e-4  # Levenberg-Marquardt term on the Gauss-Newton Hessian (slip terms ~1e6)
SLIP_SCALE = 1e-3  # slip error of weight 1 in the tracking objective
SOLVERS = ("sqpmethod", "ipopt", "rti")
RTI_QP = "daqp"  # CasADi's plugin of DAQP, a dual active-set solver for small dense QPs
RTI_VIOLATION = 1e-6  # largest violation of the condensed QP's constraints still called solved
QP_DUAL_TOLERANCE = 1e-7  # sqpmethod's tol_du and qrqp's dual_inf_tol (see Controller._options)
OBJECTIVES = ("track", "efficiency")


class MPCError(ValueError):
    """A controller setting is out of its valid range; the message names it and the range."""


class PlantError(RuntimeError):
    """The plant left the model's domain or refused a step; the message says where."""


@dataclass(frozen=True)
class Settings:
    """NMPC settings; every field is checked by :meth:`check`."""

    horizon: int = 30  # intervals
    interval: float = 0.02  # s
    solver: str = "sqpmethod"  # sqpmethod (with qrqp) | ipopt
    compiled: bool = False  # generate and compile C for the NLP's functions
    objective: str = "track"  # track | efficiency
    torque_limit: float = 3.0  # N.m, the wheel motor's
    power_limit: float = 5.0  # W, the wheel motor's mechanical output
    sinkage_limit: float = 0.04  # m
    speed_limit: float = 5.0  # rad/s, largest speed command
    move_weight: float = 1e-2  # weight of (command move / command scale)^2
    max_iterations: int = 20
    memory: bool = False
    """The prediction carries the soil's memory (the plant's plastic sinkage a state, the yield
    smoothed over YIELD_WIDTH): False, the soil yields at the wheel's sinkage (the loading
    branch). With it the nominal scenario tracks to 4.1e-4 on the memory plant (in-sample: the
    smoothing width was chosen on it; 6.3e-3 without); free-carriage leaves the domain and
    efficiency's solves fail, so off by default (docs/mpc.md)."""
    speed_weight: float = 0.0
    """track: weight of ((carriage speed - speed reference)/(speed reference*SLIP_SCALE))^2, a
    relative speed error weighed like a slip error of the same size. 0 (the rig): slip only.
    On a vehicle the slip of steady motion is set by the force balance, so a controller that
    tracks slip alone leaves the speed free to drift; this term holds it."""

    def check(self) -> Settings:
        def need(ok: bool, name: str, value, valid: str) -> None:
            if not ok:
                raise MPCError(f"{name} = {value!r} is out of range; valid: {valid}")

        need(isinstance(self.horizon, int) and 1 <= self.horizon <= 500, "horizon", self.horizon,
             "a whole number in [1, 500]")
        need(1e-4 <= self.interval <= 1.0, "interval", self.interval, "[1e-4, 1] s")
        need(self.solver in SOLVERS, "solver", self.solver, ", ".join(SOLVERS))
        need(self.objective in OBJECTIVES, "objective", self.objective, ", ".join(OBJECTIVES))
        need(self.solver != "rti" or self.objective == "track", "objective", self.objective,
             "track with solver 'rti' (its Gauss-Newton QP needs a least-squares objective; "
             "for efficiency use sqpmethod or ipopt)")
        need(0 < self.torque_limit <= 1e4, "torque_limit", self.torque_limit, "(0, 1e4] N.m")
        need(0 < self.power_limit <= 1e6, "power_limit", self.power_limit, "(0, 1e6] W")
        need(0 < self.sinkage_limit <= 1.0, "sinkage_limit", self.sinkage_limit, "(0, 1] m")
        need(0 < self.speed_limit <= 1e3, "speed_limit", self.speed_limit, "(0, 1e3] rad/s")
        need(0 <= self.move_weight <= 1e6, "move_weight", self.move_weight, "[0, 1e6]")
        need(1 <= self.max_iterations <= 1000, "max_iterations", self.max_iterations,
             "[1, 1000]")
        need(0 <= self.speed_weight <= 1e6, "speed_weight", self.speed_weight, "[0, 1e6]")
        need(self.speed_weight == 0 or self.objective == "track", "speed_weight",
             self.speed_weight, "0 with the efficiency objective")
        return self


def terrain_inputs(states: dict, load):
    """The terrain Functions' ``u`` (TERRAIN_INPUTS, in order) from states by name and the
    load (no rut met: the rig's strip is virgin soil)."""
    given = {**states, "load": load, "rut_met": 0.0, "rut_pressure_met": 0.0, "slip_angle": 0.0,
             "yaw_rate": 0.0}
    return ca.vertcat(*(given[n] for n in fmu_model.TERRAIN_INPUTS))


@lru_cache(maxsize=2)
def dynamics(memory: bool = False) -> ca.Function:
    """``dynamics(x, command, p_terrain, p_rig) -> (xdot, y)``: the continuous prediction model
    (x = :func:`states`, y = OUTPUTS) from the FMUs' Functions: terrain_dynamic and rig.rates.
    Without ``memory`` the soil yields at the wheel's sinkage (the loading branch); with it,
    the plastic sinkage is a state, its rate the model's, the yield smoothed (YIELD_WIDTH)."""
    names = states(memory)
    terrain = fmu_model.terrain_functions(YIELD_WIDTH if memory else None)[0]
    x = ca.MX.sym("x", len(names))
    command = ca.MX.sym("command")
    pt, pr = ca.MX.sym("p_terrain", len(NAMES)), ca.MX.sym("p_rig", len(rig.RIG_NAMES))
    named = rig.named(pr)
    xs = dict(zip(names, ca.vertsplit(x), strict=True))
    # with memory: the plastic sinkage as the plant keeps it, its yield smoothed; without, the
    # soil yields at the wheel's sinkage (the loading branch)
    evaluated = terrain(terrain_inputs(xs, named["rig.load"]), xs["wheel_angle"],
                        xs["plastic_sinkage"] if memory else xs["sinkage"], pt)
    out = dict(zip(fmu_model.TERRAIN_OUTPUTS, ca.vertsplit(evaluated[0]), strict=True))
    # the command is the speed loop's reference (rig.drive 1) or the torque (rig.drive 2)
    given = {**out, "wheel_speed_command": command, "motor_torque_command": command}
    inputs = tuple(given[n] for n in rig.INPUTS)
    x_rig = tuple(xs[n] for n in rig.RIG_STATES)
    xdot = ca.vertcat(*rig.rates(x_rig, inputs, named), xs["wheel_speed"],
                      *((evaluated[3],) if memory else ()))
    motor = rig.motor_torque(x_rig, inputs, named)
    y = {**out, "soil_torque": out["torque"], "motor_torque": motor,
         "power": motor * xs["wheel_speed"]}
    outputs = ca.vertcat(*(y[n] for n in OUTPUTS))
    return ca.Function("wheel_dynamics", [x, command, pt, pr], [xdot, outputs],
                       ["x", "command", "p_terrain", "p_rig"], ["xdot", "y"])


@lru_cache(maxsize=2)
def interval_residual(memory: bool = False) -> ca.Function:
    """``interval(x0, x1, command, p_terrain, p_rig, h) -> (residual, y1)``: backward Euler
    x1 - x0 - h*f(x1, command) and the outputs at the interval's end."""
    f = dynamics(memory)
    nx = len(states(memory))
    x0, x1 = ca.MX.sym("x0", nx), ca.MX.sym("x1", nx)
    command, h = ca.MX.sym("command"), ca.MX.sym("h")
    pt, pr = ca.MX.sym("p_terrain", len(NAMES)), ca.MX.sym("p_rig", len(rig.RIG_NAMES))
    xdot, y = f(x1, command, pt, pr)
    return ca.Function("interval", [x0, x1, command, pt, pr, h], [x1 - x0 - h * xdot, y],
                       ["x0", "x1", "command", "p_terrain", "p_rig", "h"], ["residual", "y"])


@lru_cache(maxsize=2)
def interval_step(memory: bool = False) -> ca.Function:
    """``step(x0, command, p_terrain, p_rig, h) -> (x1, y1)``: one backward-Euler interval
    solved by Newton (for forward rollouts: the first guess and the shift's last interval)."""
    residual = interval_residual(memory)
    nx = len(states(memory))
    x0, x1 = ca.MX.sym("x0", nx), ca.MX.sym("x1", nx)
    command, h = ca.MX.sym("command"), ca.MX.sym("h")
    pt, pr = ca.MX.sym("p_terrain", len(NAMES)), ca.MX.sym("p_rig", len(rig.RIG_NAMES))
    g = ca.Function("g", [x1, ca.vertcat(x0, command, pt, pr, h)],
                    [residual(x0, x1, command, pt, pr, h)[0]])
    solve = ca.rootfinder("solve", "newton", g, {"abstol": 1e-12, "max_iter": 50,
                                                  "error_on_fail": False})
    params = ca.vertcat(x0, command, pt, pr, h)
    x_new = solve(x0, params)
    return ca.Function("interval_step", [x0, command, pt, pr, h],
                       [x_new, residual(x0, x_new, command, pt, pr, h)[1]],
                       ["x0", "command", "p_terrain", "p_rig", "h"], ["x1", "y"])


@lru_cache(maxsize=2)
def compiled_interval(memory: bool = False) -> ca.Function:
    """:func:`interval_residual` as generated C with its Jacobian, compiled once per model
    version (the C's SHA-256 names the cache entry) and loaded with ``ca.external``.

    Not expanded to SX: the contact stays a switch over its forms (``contact.form_switch``), so an
    evaluation and its derivative run the preset's form only (on the default preset 0.8 us and
    5 us per interval, against 12 us and 54 us expanded, where every form is evaluated). The
    soil and rig parameters and the interval length are declared non-differentiable: the NLP
    differentiates by its variables only, and their Jacobian blocks would be half the code.
    Compiled at -O1: the arc forms' derivatives make ~170 000 lines of C, which -O2 takes
    twice as long over (~2 min) for no measurable gain on this model."""
    f = interval_residual(memory)
    args = [ca.MX.sym(name, f.sparsity_in(k)) for k, name in enumerate(f.name_in())]
    fn = ca.Function(f.name(), args, f(*args), f.name_in(), f.name_out(),
                     {"is_diff_in": [name in ("x0", "x1", "command") for name in f.name_in()]})
    library = native.cached_library(fn, "mpc", jacobian=True, optimisation="-O1")
    return ca.external(fn.name(), str(library))


def stiffness(pt: np.ndarray, pr: dict, x: np.ndarray, command: float) -> np.ndarray:
    """Eigenvalues [1/s] of the prediction model's Jacobian d(xdot)/dx at ``x`` (without the
    wheel angle, a pure integrator), in the drive mode of ``pr``."""
    f = dynamics()
    xs = ca.MX.sym("x", len(MPC_STATES))
    jac = ca.Function("a", [xs], [ca.jacobian(f(xs, command, pt, _vector(pr))[0], xs)])
    a = np.array(jac(x))[:5, :5]
    keep = [0, 1, 2] + ([3] if pr["rig.drive"] != rig.DRIVE_TORQUE else []) + (
        [4] if pr["rig.carriage"] == rig.CARRIAGE_FREE else [])
    return np.linalg.eigvals(a[np.ix_(keep, keep)])


def _vector(pr: dict) -> np.ndarray:
    return np.array([float(pr[name]) for name in rig.RIG_NAMES])


@dataclass
class Step:
    """One solve: the command to apply and what it cost."""

    command: float
    solve_time: float  # s, wall time of the solver call
    iterations: int
    success: bool
    status: str
    predicted: dict[str, np.ndarray] = field(repr=False, default_factory=dict)


class Controller:
    """The NMPC: one NLP built once, solved each interval with a shifted warm start.

    ``p_rig`` are the rig parameters of the plant (with rig.drive = 1, speed command);
    ``p_terrain`` the soil the controller believes (an estimator may update it per solve).
    """

    def __init__(self, settings: Settings, p_rig: dict) -> None:
        self.settings = settings.check()
        if p_rig["rig.drive"] != rig.DRIVE_SPEED:
            raise MPCError(f"rig.drive = {p_rig['rig.drive']!r}: the NMPC commands the wheel "
                           f"speed; valid: {rig.DRIVE_SPEED} (speed-command)")
        self.p_rig = _vector(p_rig)
        self.command_scale = p_rig["rig.rim_speed"] / p_rig["rig.slip_radius"]
        self._build()
        self.guess: np.ndarray | None = None

    # --- the NLP --------------------------------------------------------------------------
    def _build(self) -> None:
        self.states = states(self.settings.memory)
        s, n, nx = self.settings, self.settings.horizon, len(self.states)
        # scale of each state in the NLP's variables: m, m/s, rad/s, rad, m/s, rad (, m)
        self.x_scale = x_scale = np.array([1e-2, 1e-2, self.command_scale, 1e-2, 1e-2, 1.0,
                                           1e-2][:nx])
        u_hat, x_hat = ca.MX.sym("u", n), ca.MX.sym("x", nx, n)
        x0, pt = ca.MX.sym("x_now", nx), ca.MX.sym("p_terrain", len(NAMES))
        reference, previous = ca.MX.sym("slip_reference", n), ca.MX.sym("previous_command")
        speed_reference = ca.MX.sym("speed_reference")
        pr = ca.DM(self.p_rig)
        u = u_hat * self.command_scale
        xs = ca.diag(ca.DM(x_scale)) @ x_hat
        starts = ca.horzcat(x0, xs[:, :-1])
        interval = (compiled_interval(s.memory) if s.compiled
                    else interval_residual(s.memory)).map(n)
        residual, y = interval(starts, xs, u.T, pt, pr, s.interval)
        residual = ca.diag(ca.DM(1 / x_scale)) @ residual
        # slip, motor torque and power from the states (the same expressions as the plant's),
        # so the objective's and the limits' derivatives skip the contact model
        named = rig.named(pr)
        omega, speed = xs[2, :].T, xs[4, :].T
        slip, _ = fmu_model.slips(omega, speed, fmu_model.slip_radius(pt))
        motor = rig.motor_torque(tuple(xs[k, :].T for k in range(len(rig.RIG_STATES))),
                                 (0, 0, 0, u, u), named)
        power = motor * omega
        moves = ca.diff(ca.vertcat(previous, u)) / self.command_scale
        if s.objective == "track":
            terms = [(slip - reference) / SLIP_SCALE, math.sqrt(s.move_weight) * moves]
            if s.speed_weight > 0:  # built only when weighed: the rig's NLP stays as it was
                terms.append(math.sqrt(s.speed_weight) * (speed - speed_reference)
                             / (ca.fmax(ca.fabs(speed_reference), 1e-9) * SLIP_SCALE))
            residuals = ca.vertcat(*terms)
            cost = ca.sumsqr(residuals)
        else:
            residuals = None
            efficiency = y[1, :].T * speed / ca.fmax(power, 1e-6)
            cost = -100 * ca.sum1(efficiency) + s.move_weight * ca.sumsqr(moves)
        g = ca.vertcat(ca.vec(residual), motor, power)
        w = ca.vertcat(u_hat, ca.vec(x_hat))
        p = ca.vertcat(x0, pt, reference, previous, speed_reference)
        nlp = {"x": w, "p": p, "f": cost, "g": g}
        self.gauss_newton = None
        if residuals is not None:  # least squares: the Gauss-Newton Hessian 2*J'J
            jac = ca.jacobian(residuals, w)
            lam_f, lam_g = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", g.numel())
            # plus a Levenberg-Marquardt term: the states outside the objective would leave the
            # Hessian singular, which slows qrqp's active set down by 100x after a soil change
            regularisation = REGULARISATION * ca.DM.eye(w.numel())
            hessian = 2 * lam_f * (jac.T @ jac) + regularisation
            if s.solver == "ipopt":  # ipopt reads the upper triangle, sqpmethod the whole
                hessian = ca.triu(hessian)
            self.gauss_newton = ca.Function("gauss_newton", [w, p, lam_f, lam_g], [hessian],
                                            ["x", "p", "lam_f", "lam_g"], ["hess_gamma_x_x"])
        self.lbg = np.concatenate([np.zeros(nx * n), -s.torque_limit * np.ones(n),
                                   -np.inf * np.ones(n)])
        self.ubg = np.concatenate([np.zeros(nx * n), s.torque_limit * np.ones(n),
                                   s.power_limit * np.ones(n)])
        upper = np.array([s.sinkage_limit / x_scale[0]] + [np.inf] * (nx - 1))
        self.lbx = np.concatenate([np.zeros(n), np.tile(np.full(nx, -np.inf), n)])
        self.ubx = np.concatenate([s.speed_limit / self.command_scale * np.ones(n),
                                   np.tile(upper, n)])
        if s.solver == "rti":
            self.solver = None
            self.iteration = self._real_time_iteration(
                w, p, cost, g, 2 * (jac.T @ jac) + regularisation)
        else:
            self.solver = ca.nlpsol("mpc", s.solver, nlp, self._options())

    def _real_time_iteration(self, w, p, cost, g, hessian) -> ca.Function:
        """``iteration(w, p) -> (w_next, violation)``: one Gauss-Newton SQP step from ``w``
        with the states condensed out (see the module's Solvers), and the largest violation
        of the condensed QP's constraints by its solution (a solved QP leaves ~1e-12)."""
        if not ca.has_conic(RTI_QP):
            raise MPCError(f"solver = 'rti' needs CasADi's {RTI_QP} QP plugin, which this "
                           f"CasADi {ca.__version__} lacks; valid: sqpmethod, ipopt")
        n, nx = self.settings.horizon, len(self.states)
        ne = n * nx  # the interval residuals: the first ne rows of g; the commands: w[:n]
        jac_g = ca.jacobian(g, w)
        jac_u, jac_x = jac_g[:ne, :n], jac_g[:ne, n:]
        # linearised residuals g + jac_u du + jac_x dx = 0: dx = S du + s0 (jac_x is block
        # bidiagonal and invertible: identity minus h*df/dx on the diagonal blocks)
        sensitivity = -ca.solve(jac_x, ca.densify(jac_u), "csparse")
        offset = -ca.solve(jac_x, g[:ne], "csparse")
        z = ca.vertcat(ca.DM.eye(n), sensitivity)  # d(w)/d(du)
        z0 = ca.vertcat(ca.DM.zeros(n), offset)
        gradient = ca.gradient(cost, w) + hessian @ z0
        # the limits left: torque and power (the rows of g after the residuals), the sinkage
        sinkage = [n + k * nx for k in range(n)]
        rows = ca.vertcat(jac_g[ne:, :], ca.DM.eye(n + ne)[sinkage, :])
        values = ca.vertcat(g[ne:], w[sinkage])
        lower = ca.vertcat(ca.DM(self.lbg[ne:]), ca.DM(self.lbx[sinkage]))
        upper = ca.vertcat(ca.DM(self.ubg[ne:]), ca.DM(self.ubx[sinkage]))
        a = ca.densify(rows @ z)
        start = values + rows @ z0
        h = ca.densify(z.T @ hessian @ z)
        qp = ca.conic("rti_qp", RTI_QP, {"h": h.sparsity(), "a": a.sparsity()},
                      {"error_on_fail": False})
        lbu, ubu = ca.DM(self.lbx[:n]) - w[:n], ca.DM(self.ubx[:n]) - w[:n]
        du = qp(h=h, g=z.T @ gradient, a=a, lba=lower - start, uba=upper - start,
                lbx=lbu, ubx=ubu)["x"]
        reached = a @ du + start
        violation = ca.mmax(ca.vertcat(ca.fmax(lower - reached, 0), ca.fmax(reached - upper, 0),
                                       ca.fmax(lbu - du, 0), ca.fmax(du - ubu, 0)))
        return ca.Function("rti", [w, p], [w + z @ du + z0, violation], ["w", "p"],
                           ["w_next", "violation"])

    def _options(self) -> dict:
        s = self.settings
        # not expanded to SX: the contact's switch then runs the preset's form only (expanded,
        # every form is evaluated: ipopt on the VM 88 ms per solve instead of 40 ms)
        # calc_lam_p off: the parameters' multipliers are not used, and their gradient is NaN
        # where a parameter's derivative is not defined (the exit ratio at 0, virgin soil's rut
        # depth): CasADi then printed a "NaN detected" warning per solve (600-800 a run)
        common: dict = {"expand": False, "calc_lam_p": False}
        if self.gauss_newton is not None:
            common["hess_lag"] = self.gauss_newton
        if s.solver == "sqpmethod":
            if self.gauss_newton is not None:
                # full Gauss-Newton steps from the shifted warm start (2 iterations per solve
                # in every scenario, as with the line search, which cost ~1.5 ms per solve)
                common["max_iter_ls"] = 0
            return {**common, "qpsol": "qrqp", "print_header": False, "print_iteration": False,
                    "print_status": False, "print_time": False, "max_iter": s.max_iterations,
                    "error_on_fail": False,
                    # qrqp's own dual tolerance (default 1e-8) no looser than the SQP's tol_du:
                    # at 1e-8, with a torque or power limit weakly active (zero multiplier),
                    # its active set cycled (enforce/drop the same bound) to its 1000-iteration
                    # limit, ~0.5 s, and the SQP ended Search_Direction_Becomes_Too_Small
                    "qpsol_options": {"print_iter": False, "print_header": False,
                                      "print_info": False, "error_on_fail": False,
                                      "dual_inf_tol": QP_DUAL_TOLERANCE},
                    "tol_pr": 1e-9, "tol_du": QP_DUAL_TOLERANCE, "min_step_size": 1e-12}
        return {**common, "print_time": False, "error_on_fail": False,
                "ipopt": {"print_level": 0, "sb": "yes", "max_iter": 10 * s.max_iterations,
                          "tol": 1e-9, "warm_start_init_point": "yes", "mu_init": 1e-4}}

    # --- solving -----------------------------------------------------------------------------
    def rollout(self, x_now: np.ndarray, commands: np.ndarray, pt: np.ndarray) -> np.ndarray:
        """States (len(self.states) x horizon) of the prediction model under ``commands``."""
        step = interval_step(self.settings.memory)
        xs, x = [], np.asarray(x_now, dtype=float)
        for c in commands:
            x = np.array(step(x, c, pt, self.p_rig, self.settings.interval)[0]).ravel()
            xs.append(x)
        return np.array(xs).T

    def solve(self, x_now, pt, reference, previous: float,
              speed_reference: float = 0.0) -> Step:
        """Solve the NLP at state ``x_now`` (:func:`states`; a longer state, the plastic sinkage
        appended, is cut to them) with soil ``pt`` and the slip ``reference`` (scalar or one per
        interval); ``previous`` is the command applied until now; ``speed_reference`` [m/s] the
        carriage speed the speed term holds (Settings.speed_weight > 0)."""
        n = self.settings.horizon
        x_now = np.asarray(x_now, dtype=float)[:len(self.states)]
        reference = np.broadcast_to(np.asarray(reference, dtype=float), (n,))
        if self.guess is None:  # forward rollout, not a constant state (a bad local minimum)
            commands = np.full(n, previous)
            xs = self.rollout(x_now, commands, pt)
            self.guess = np.concatenate([commands / self.command_scale,
                                         (xs.T / self.x_scale).ravel()])
        else:
            self._align_turns(x_now)
        args = {"x0": self.guess,
                "p": np.concatenate([x_now, pt, reference, [previous, speed_reference]]),
                "lbx": self.lbx, "ubx": self.ubx, "lbg": self.lbg, "ubg": self.ubg}
        if self.solver is None:  # the real-time iteration
            started = time.perf_counter()
            try:
                w_next, violation = self.iteration(args["x0"], args["p"])
                w, violation = np.array(w_next).ravel(), float(violation)
                problem = None
            except RuntimeError:  # csparse refuses a linearisation that is not finite
                w, violation = self.guess, math.inf
                problem = ("the linearisation is not finite (the plan left the contact "
                           "model's domain, e.g. the wheel out of the soil)")
            elapsed = time.perf_counter() - started
            solved = bool(np.all(np.isfinite(w))) and violation <= RTI_VIOLATION
            if not solved:  # keep the shifted warm start: its first command is the plan's
                w = self.guess
            status = "Solve_Succeeded" if solved else (
                f"QP not solved: {problem or f'its limits violated by {violation:.3g}'}; the "
                "shifted plan kept")
            stats = {"iter_count": 1, "success": solved, "return_status": status}
        else:
            # primal warm start only: qrqp warm-started with the last multipliers cycled (200
            # ms QPs, iteration limits) once the estimator moved the soil between solves
            started = time.perf_counter()
            result = self.solver(**args)
            elapsed = time.perf_counter() - started
            stats = self.solver.stats()
            w = np.array(result["x"]).ravel()
        commands = w[:n] * self.command_scale
        xs = (w[n:].reshape(n, -1) * self.x_scale).T
        self._shift(w, pt)
        return Step(float(commands[0]), elapsed, int(stats.get("iter_count", -1)),
                    bool(stats.get("success", False)), str(stats.get("return_status", "")),
                    {"command": commands, "states": xs})

    def _align_turns(self, x_now: np.ndarray) -> None:
        """Move the warm start's wheel angles by the whole turns that ``x_now``'s angle was
        wrapped by (:func:`wrap_angle`), so that they continue from it. Without this, the
        guess's first interval starts 2*pi away from the state once per turn, and one
        Gauss-Newton step (the real-time iteration) linearises the ripple over that jump:
        a wild command (seen on the rover after 10.5 s)."""
        n, nx = self.settings.horizon, len(self.states)
        angle = self.states.index("wheel_angle")
        scale = self.x_scale[angle]
        first = self.guess[n + angle] * scale  # the guess's angle at the first interval's end
        turns = round((first - x_now[angle]) / (2 * math.pi))
        if turns:
            self.guess[n + angle::nx] -= turns * 2 * math.pi / scale

    def _shift(self, w: np.ndarray, pt: np.ndarray) -> None:
        """Warm start for the next solve: the solution moved one interval on, its last
        interval repeated with the last command."""
        n, nx = self.settings.horizon, len(self.states)
        u, x = w[:n], w[n:].reshape(n, nx)
        last = self.rollout(x[-1] * self.x_scale, [u[-1] * self.command_scale], pt)[:, 0]
        self.guess = np.concatenate([np.append(u[1:], u[-1]),
                                     np.vstack([x[1:], last / self.x_scale]).ravel()])

    def reset(self) -> None:
        self.guess = None


def wrap_angle(angle: float) -> float:
    """The wheel angle the prediction starts from: the ripple has period 2*pi/n_g, so any
    whole turn can be dropped (keeps the state small and well scaled)."""
    return math.fmod(angle, 2 * math.pi)
