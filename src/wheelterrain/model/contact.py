"""The rigid-wheel terramechanics contact model, written once in CasADi SX symbols.

Everything that computes a force in this project (the Python API, the CLI, the FMUs, the MPC, the
calibration) calls the functions built here. Nothing else re-derives a formula.

Conventions
-----------
- theta is measured from the downward vertical through the axle, positive toward the direction of
  travel. Entry angle theta_f = arccos(1 - z/R_c) > 0; exit angle
  theta_r = -arccos(1 - lambda*z/R_c) <= 0 (lambda = ``model.exit_ratio``; 0 gives the Wong-Reece
  theta_r = 0).
- ``slip`` is the model's slip sigma = (omega*R_ref - V)/max(omega*R_ref, V)
  (:mod:`wheelterrain.model.slip`): the traction slip i when driving (0 to 1, spinning), the
  skid s = (omega*R_ref - V)/V when braking (0 to -1, a locked wheel). Written i below where
  the driving formula is the familiar one.
- Forces are those of the soil on the wheel: normal force up, drawbar pull forward, torque the
  resistive torque the motor has to supply.

Equations (Wong & Reece 1967; Wong, *Theory of Ground Vehicles*; Ishigami et al. 2007; Ding et al.
2011; Irani et al. 2011)::

    R_c = R + f_c*h_g,  R_s = R + f_s*h_g,  R_ref = R + f_ref*h_g       (radii; all R when f = 0)
    n    = n0 + n1*max(i, 0)                                             (Ding et al. 2011)
    k_eq = (c*k_c' + gamma*b*k_phi') * (R_c/b)**n                        (Reece 1965)
    theta_m = (a0 + a1*i)*theta_f                                        (Wong & Reece 1967)
    sigma(theta) = k_eq*(cos(theta) - cos(theta_f))**n                   theta_m <= theta <= theta_f
    sigma(theta) = k_eq*(cos(theta*) - cos(theta_f))**n,                 theta_r <= theta < theta_m
        theta* = theta_f - (theta - theta_r)/(theta_m - theta_r)*(theta_f - theta_m)
    j(theta) = R_s*(theta_f - theta) - (1 - i)*R_ref*(sin(theta_f) - sin(theta))  (wheel element;
               braking: (1 + i)*R_s*(theta_f - theta) - R_ref*(sin(theta_f) - sin(theta)))
    j(theta) = R_c*[R_s/((1 - i)*R_ref)*(sin(theta_f) - sin(theta))                  (soil element,
               - (theta_f - theta)/2 - (sin(2*theta_f) - sin(2*theta))/4]           SCM; see below)
    tau = (c' + sigma*tan(phi')) * g(j),  g = 1 - exp(-j/K')  (Janosi)  or Wong's hump form
    K' = K + kappa*l_c                                                   (Wiendieck 1968)
    c' = c - (1 - chi)*(1 - rho)*c,  tan(phi') = tan(phi) - (1 - chi)*(tan(phi) - tan(rho*phi))
        chi = h_g/(h_g + h_e) (0 smooth)           (Potyondy 1961; Higa et al. 2019)
    k_eq also carries (2R/0.5 m)**m                       (Meirion-Griffith & Spenko 2011)
    DP -= R_b = beta*b*(gamma*z**2*K_p/2 + 2*c*z*sqrt(K_p))       (Bekker 1960, bulldozing)
    Fz = b*int(R_c*sigma*cos + R_s*tau*sin),  DP = b*int(R_s*tau*cos - R_c*sigma*sin),
    T  = b*R_s**2*int(tau)                                               over [theta_r, theta_f]

Two contact forms, selected by ``model.contact_form`` (both written here, once): 0, the arc
above; 1, the patch (:func:`_patch_form`), the Reece pressure acting uniformly on the flat
contact patch with Bekker's patch thrust and compaction resistance, the soft-soil reading of the
paper's eq. 1. Every Function below (contact, Jacobians, sinkage solve, steady state) takes the
switch from the parameter vector, so the FMUs, the MPC, the calibration and the sweeps get both.

The cross-wheel mechanisms (kappa = ``model.shear_length_ratio``, rho =
``model.interface_ratio``, h_e = ``model.grouser_shear_height``, m =
``model.diameter_exponent``, beta = ``model.bulldozing``; :func:`effective_shear_modulus`,
:func:`shear_strength`, :func:`reece`, :func:`bulldozing`) act in both forms and are off at
their defaults (kappa = 0, rho = 1, m = 0, beta = 0), where the expressions reduce to the
classical ones exactly.

The shear-displacement kinematics (``model.shear_kinematics``) is documented at
:class:`_Displacement`. With every extension off (n1 = 0, f_c = f_s = f_ref = 0, Janosi,
wheel-element kinematics, lambda = 0, no ripple) this is the
classical Wong-Reece rigid wheel, exactly.

Grouser ripple (Irani et al. 2011, as this project reads it): the normal stress on the
contact arc becomes max(sigma + A*sin(n_g*wheel_angle + Phi), 0), with
A = k_g'*p_mean + k_0'*l_c*d_gamma, p_mean = Fz_static/(b*l_c) the mean contact pressure of the
ripple-free stress and l_c = R_c*(sin(theta_f) - sin(theta_r)) the contact length. The phase follows
the wheel's rotation angle, not time. The ``max(., 0)`` (soil carries no tension) is the one
non-smooth operation; it is only active with the ripple on.

Choices where the equations are silent, each documented:
- The shear law is made odd in j, g(-j) = -g(j), so a braked wheel (negative j) gets a bounded,
  opposite shear instead of the exponential blow-up of the literal formula; identical for j >= 0.
- The slip-sinkage exponent is held at n0 in skid (:func:`wheelterrain.model.soil.reece`):
  the slip-sinkage law was fitted on driven wheels, and no source here gives one for skid.
- Braking runs to the locked wheel: the wheel element's shear displacement is then counted per
  distance travelled (the skid form, :func:`_kinematics`), finite at omega = 0.
- The damping term C_f*dz/dt acts only in contact (z > 0), and the total normal force is kept >= 0
  (the soil cannot pull the wheel down). Both are inactive in the quasi-static solve.
- cos(theta) - cos(theta_f) and sin(theta_f) - sin(theta) are formed from half angles, exactly
  non-negative and free of cancellation at small sinkage.

Quadrature: the arc is split at theta_m into a front panel [theta_m, theta_f] and a rear panel
[theta_r, theta_m]. Both are parametrised by one offset g in [0, 1] (front:
theta = theta_f - (theta_f - theta_m)*g, rear: theta = theta_r + (theta_m - theta_r)*g), so a rear
node's theta* is a front node's theta and the stress is computed once per node pair. g = 0 is the
(theta_f - theta)**n end-point singularity of the stress in both panels; graded Gauss-Legendre maps
(u**3-like at the singular end) remove it. Where the shear displacement j changes sign on the arc
(braking, or a slip radius larger than the shear radius) the odd shear law has a kink and, for a
small shear modulus K, a boundary layer of width ~K/|dj/dtheta| on both sides; both panels are then
split at the offset of that reversal (found by safeguarded Newton) into sub-panels graded toward
it. DEFAULT_NODES = (16, 10) nodes per panel before and after the split; measured against adaptive
quadrature over the test grid (tests/test_classical.py): ~1e-9 relative driving, ~1e-7 braking.

Evaluation: every Function of the model calls a CasADi switch over three SX Functions (the arc,
the arc split at a shear reversal, the patch; :func:`form_switch`), so an evaluation runs only
the form and the rule that apply: no reversal search and no second sub-panel where the shear
keeps its sign, no arc at all for the patch. A node costs one sine and one cosine. The sinkage
solve's Newton iterations are switches too and stop once converged
(:mod:`wheelterrain.model.solve`).

This module holds the contact's geometry and forms, on the soil's laws of
:mod:`wheelterrain.model.soil`; the quasi-static sinkage solve (scan, Newton, its acceptance
test) is :mod:`wheelterrain.model.solve`; :func:`wheelterrain.model.functions.build` assembles
the model's Functions from both (``build().contact`` below).
"""

from __future__ import annotations

import math
from functools import lru_cache

import casadi as ca
import numpy as np

from wheelterrain.model.slip import reference_radius
from wheelterrain.model.soil import (
    Params,
    Rut,
    bulldozing,
    effective_shear_modulus,
    in_rut,
    reece,
    rut,
    rut_surface,
    shear_function,
    shear_peak,
    shear_strength,
)
from wheelterrain.parameters import NAMES

DEFAULT_NODES = (16, 10)  # per panel: up to the shear reversal, after it
GRADING = 3
REVERSAL_ITERATIONS = 10  # safeguarded Newton steps locating the shear reversal
FULL_BURIAL = math.pi / 2  # entry angle at sinkage = contact radius

CONTACT_INPUTS = ("sinkage", "sinkage_rate", "slip", "wheel_angle", "p")
CONTACT_OUTPUTS = (
    "normal_force", "drawbar_pull", "torque", "gross_thrust", "compaction_resistance",
    "entry_angle", "exit_angle", "max_stress_angle", "contact_length", "mean_pressure",
    "sinkage_exponent", "ripple_amplitude", "normal_force_static", "bulldozing_resistance",
    "rut_left", "rut_pressure_left",
)
MEMORY_OUTPUTS = ("yield_sinkage", "plastic_rate")
"""``contact_memory``'s outputs beyond CONTACT_OUTPUTS: z_y = max(z_p, z) and d(z_p)/dt."""
FORCES = ("normal_force", "drawbar_pull", "torque")


def _split_rule(split: ca.SX, nodes: tuple[int, int]) -> tuple[ca.SX, ca.SX]:
    """Offsets g in [0, 1] and weights of a panel split at ``split`` into two graded
    Gauss-Legendre sub-panels of ``nodes[0]`` and ``nodes[1]`` nodes.

    [0, split]: quintic map 10u^3 - 15u^4 + 6u^5, graded like u^3 at both ends (the stress
    singularity at g = 0, the shear reversal at the split); it is the whole panel when the shear
    keeps its sign (split = 1). [split, 1]: u^3 graded toward the reversal.
    """
    s1, ds1 = _panel_rule(nodes[0])
    x2, w2 = np.polynomial.legendre.leggauss(nodes[1])
    u2, w2 = (x2 + 1.0) / 2.0, w2 / 2.0
    s2, ds2 = u2**GRADING, GRADING * u2 ** (GRADING - 1) * w2
    g = ca.vertcat(split * s1, split + (1 - split) * ca.DM(s2))
    weights = ca.vertcat(split * ds1, (1 - split) * ca.DM(ds2))
    return g, weights


def _panel_rule(nodes: int) -> tuple[ca.DM, ca.DM]:
    """Offsets and weights of a whole panel: Gauss-Legendre under the quintic map
    10u^3 - 15u^4 + 6u^5. The rule where the shear keeps its sign; also the first sub-panel of
    :func:`_split_rule`, which at split = 1 adds only zero-weight nodes to it (the same sums,
    term for term)."""
    x, w = np.polynomial.legendre.leggauss(nodes)
    u, w = (x + 1.0) / 2.0, w / 2.0
    return ca.DM(u**3 * (10 - 15 * u + 6 * u**2)), ca.DM(30 * u**2 * (1 - u) ** 2 * w)


def _falling_stretch(theta_f, theta_r, displacement) -> tuple[ca.SX, ca.SX]:
    """(theta_c, the end of the stretch on which j falls, as x = theta_f - theta): the peak of
    the shear displacement is at theta = theta_c (cos(theta_c) = R_s/v; pi when j never
    falls), and j falls from there until -theta_c or the exit (see :func:`_reversal_offset`)."""
    ratio = displacement.ratio  # R_s/v
    theta_c = ca.if_else(ratio < 1, ca.acos(ca.fmin(ratio, 1)), math.pi)
    return theta_c, ca.fmin(theta_f - theta_r, theta_f + theta_c)


def _reverses(theta_f, theta_r, displacement) -> ca.SX:
    """1 where the shear displacement changes sign on the arc [theta_r, theta_f] (see
    :func:`_reversal_offset`), else 0."""
    theta_c, end = _falling_stretch(theta_f, theta_r, displacement)
    return ca.logic_and(theta_c < theta_f, displacement.along(end) < 0)


def _reversal_offset(theta_f, theta_r, d_front, d_rear, displacement) -> ca.SX:
    """Where the shear displacement j changes sign on the arc, as the offset g in [0, 1] shared by
    both quadrature panels (front: theta = theta_f - d_front*g, rear: theta = theta_r + d_rear*g),
    so that a panel edge sits on the kink of the odd shear law; 1 when j keeps its sign.

    ``displacement`` is the :class:`_Displacement` of the arc. With x = theta_f - theta, under
    either kinematics j'(x) has the sign of R_s - v*cos(theta), v = V/omega: j rises from 0
    at the entry while v*cos(theta) < R_s, peaks where cos(theta) = R_s/v (theta = theta_c), and
    falls while |theta| < theta_c: a braked wheel (v > R_s) has its reversal on that falling
    stretch, found by Newton safeguarded by bisection. A second reversal beyond -theta_c needs an
    exit angle past -theta_c under deep braking; it is not split (its kink then costs accuracy,
    not robustness).
    """
    span = theta_f - theta_r
    theta_c, hi = _falling_stretch(theta_f, theta_r, displacement)
    lo = ca.fmax(theta_f - theta_c, 0)  # the peak of j
    crossing = _reverses(theta_f, theta_r, displacement)  # the same terms: merged by cse
    x = hi
    for _ in range(REVERSAL_ITERATIONS):
        f = displacement.along(x)
        lo, hi = ca.if_else(f > 0, x, lo), ca.if_else(f > 0, hi, x)
        step = x - f / displacement.slope(x)
        x = ca.if_else(ca.logic_and(step >= lo, step <= hi), step, (lo + hi) / 2)
    front = x / ca.fmax(d_front, 1e-300)
    rear = (span - x) / ca.fmax(d_rear, 1e-300)
    offset = ca.if_else(x <= d_front, front, rear)
    return ca.if_else(crossing, ca.fmin(ca.fmax(offset, 0), 1), 1)


SPIN_FLOOR = 1e-9  # soil-element kinematics: 1 - sigma is floored here (j -> inf as sigma -> 1)


def _kinematics(slip, Rs, Rref):
    """(a, v, R_s/v) of the model's slip sigma (:mod:`wheelterrain.model.slip`), the factors
    both contact forms count their shear displacement with:

    - the wheel element's displacement j = a*R_s*x - v*(sin(theta_f) - sin(theta)): driving,
      a = 1 and v = (1 - sigma)*R_ref = V/omega (time counted by the wheel's turning,
      dt = dtheta/omega, Wong & Reece 1967); braking, a = 1 + sigma and v = R_ref: the same
      displacement counted per distance the wheel travels (dt = R_ref*dtheta/V, the driving
      expression times omega*R_ref/V = 1 + sigma), the skid form, which stays finite down to
      the locked wheel (sigma = -1, omega = 0): there j = -R_ref*(sin(theta_f) - sin(theta)),
      the rim sliding over the soil by the distance travelled;
    - R_s/v = R_s*omega/V, the soil element's ratio: R_s/((1 - sigma)*R_ref) driving, with
      1 - sigma floored at SPIN_FLOOR (j -> inf as sigma -> 1), R_s*(1 + sigma)/R_ref braking
      (0 locked).
    The two branches meet at sigma = 0 with equal values and slopes."""
    braking = slip < 0
    a = ca.if_else(braking, 1 + slip, 1)
    v = ca.if_else(braking, Rref, (1 - slip) * Rref)
    ratio = ca.if_else(braking, Rs * (1 + slip) / Rref,
                       Rs / (ca.fmax(1 - slip, SPIN_FLOOR) * Rref))
    return a, v, ratio


class _Displacement:
    """Shear displacement j(theta) on the arc, x = theta_f - theta, under either kinematics
    (``model.shear_kinematics``):

    0, the wheel element (Wong & Reece 1967): the slip accumulated by the wheel-surface element
      now at theta since it entered the soil, dt = dtheta/omega:
      j = int (omega*R_s - V*cos(t)) dt = R_s*x - v*(sin(theta_f) - sin(theta)), v = V/omega;
      braking, counted per distance travelled instead (:func:`_kinematics`: a*R_s*x - R_ref*(...),
      a = 1 + sigma), which holds down to the locked wheel.
    1, the soil element: the slip accumulated over the soil element now at theta since the wheel
      reached it. The element stays put while the axle advances at V, so it moves along the
      contact circle with dt = R_c*cos(t)*dtheta/V:
      j = R_c*int_theta^theta_f (R_s/v - cos(t))*cos(t) dt
        = R_c*[(R_s/v)*(sin(theta_f) - sin(theta)) - x/2 - sin(x)*cos(theta_f + theta)/2].
      This is how the Soil Contact Model accumulates the Janosi displacement per soil node
      (Krenn & Hirzinger 2009; Project Chrono's SCMTerrain, ``kshear``). R_s/v = (R_s/R_ref)*
      (1 + s) is linear in the paper's slip s, 0 for a locked wheel; j grows without bound as
      sigma -> 1 (the soil under a spinning wheel is sheared for ever), so 1 - sigma is floored
      at SPIN_FLOOR, where the shear is fully mobilised to machine precision except within
      ~1e-9*R of the entry.
    Both vanish at the entry and are identical in sign pattern (same peak theta_c).
    """

    def __init__(self, theta_f, slip, P, Rc, Rs, Rref) -> None:
        self.theta_f, self.Rc, self.Rs = theta_f, Rc, Rs
        self.a, self.v, self.ratio = _kinematics(slip, Rs, Rref)
        self.soil = P["model.shear_kinematics"]
        self.cos_f, self.sin_f = ca.cos(theta_f), ca.sin(theta_f)  # once, not per node

    def at(self, o: dict) -> ca.SX:
        """j at the nodes of an :func:`_offset_trig` dict."""
        wheel = self.a * self.Rs * o["x"] - self.v * o["sin_drop"]
        cos_sum = self.cos_f * o["cos"] - self.sin_f * o["sin"]  # cos(theta_f + theta)
        soil = self.Rc * (self.ratio * o["sin_drop"] - o["x"] / 2 - o["sin_x"] * cos_sum / 2)
        return (1 - self.soil) * wheel + self.soil * soil

    def along(self, x: ca.SX) -> ca.SX:
        return self.at(_offset_trig(self.sin_f, self.cos_f, x))

    def slope(self, x: ca.SX) -> ca.SX:
        """dj/dx."""
        cos_t = ca.cos(self.theta_f - x)
        wheel = self.a * self.Rs - self.v * cos_t
        soil = self.Rc * cos_t * (self.ratio - cos_t)
        return (1 - self.soil) * wheel + self.soil * soil


def radii(P: Params) -> tuple[ca.SX, ca.SX, ca.SX]:
    R, h = P["wheel.radius"], P["grouser.height"]
    return (R + P["model.contact_radius_factor"] * h,
            R + P["model.shear_radius_factor"] * h,
            reference_radius(P))


def exit_angle(theta_f: ca.SX, P: Params) -> ca.SX:
    """theta_r = -arccos(1 - lambda*z/R_c), lambda = ``model.exit_ratio``, written through
    sin(theta_f/2) (finite derivatives in theta_f at lambda = 0).

    Its derivative in lambda, -theta_f/(2*sqrt(lambda)) near 0, is unbounded at lambda = 0:
    there the exact Jacobians report the derivative of the lambda = 0 branch, 0, for the
    exit-ratio column (an infinite entry would turn every other column into NaN wherever the
    chain rule multiplies it by a zero seed); calibrate lambda from a start above 0."""
    lam = P["model.exit_ratio"]
    root = ca.if_else(lam > 0, ca.sqrt(lam), 0)
    return -2 * ca.asin(root * ca.sin(theta_f / 2))


def rut_left(theta_f: ca.SX, ground: Rut, P: Params) -> tuple[ca.SX, ca.SX]:
    """The rut a wheel leaves at entry angle ``theta_f`` below ``ground``'s surface:
    ``(depth, pressure)``.

    Its depth (its free surface, from the original surface): the deepest point it pressed the
    soil to, surface + R_c*(1 - cos(theta_f)), less the elastic rebound p/K_u there; never
    shallower than the rut it met (a wheel that only reloaded the soil elastically leaves it
    as it was). Its pressure: the p it pressed the soil to there (the yield pressure the rut
    keeps, ``soil.rut_pressure`` for the next wheel); where it only reloaded the rut it met,
    that rut's own (``soil.rut_pressure``, 0 where not known). Both 0 with
    ``model.soil_memory`` = 0 (elastic soil closes behind the wheel)."""
    Rc, _, _ = radii(P)
    surface = rut_surface(P)
    depth = surface + 2 * Rc * ca.sin(theta_f / 2) ** 2
    carried = ground.plastic(ca.fmax(depth, 1e-300))
    rebound = carried / P["soil.unloading_stiffness"]
    left = ca.if_else(depth > 0, ca.fmax(surface, depth - rebound), surface)
    pressed = ca.logic_and(depth > 0, depth - rebound > surface)
    pressure = ca.if_else(pressed, carried, ca.if_else(ground.on, P["soil.rut_pressure"], 0))
    memory = P["model.soil_memory"] == 1
    return ca.if_else(memory, left, 0), ca.if_else(memory, pressure, 0)


def _max_stress_ratio(slip: ca.SX, P: Params) -> ca.SX:
    """theta_m/theta_f = a0 + a1*sigma (Wong & Reece 1967), in [a0 - a1, a0 + a1]: >= 0 down to
    the locked wheel within the parameters' ranges (model.a0 >= model.a1's largest value)."""
    return P["model.a0"] + P["model.a1"] * slip


def _offset_trig(sin_f: ca.SX, cos_f: ca.SX, x: ca.SX) -> dict:
    """cos/sin of theta = theta_f - x, sin(x), and the differences cos(theta) - cos(theta_f) and
    sin(theta_f) - sin(theta), through half angles so that no difference cancels at small angles
    (the plain difference loses ~eps/theta_f**2 relative: 1e-4 at theta_f = 1e-6).
    ``sin_f``, ``cos_f``: sin and cos of theta_f, shared by every node, so that a node costs one
    sine and one cosine (of x/2); a = theta_f - x/2 by the addition formulas."""
    sh, ch = ca.sin(x / 2), ca.cos(x / 2)
    sa, cs = sin_f * ch - cos_f * sh, cos_f * ch + sin_f * sh
    return {"x": x, "cos": cs * ch + sa * sh, "sin": sa * ch - cs * sh, "sin_x": 2 * sh * ch,
            "cos_drop": 2 * sa * sh, "sin_drop": 2 * cs * sh}


class _ArcNodes:
    """The arc form's quadrature at entry angle ``theta_f``: the nodes of its front and rear
    panels (:func:`_offset_trig` dicts ``front``, ``rear``; a rear node's theta* is the front
    node's theta), their weights, and the ripple-free normal stress ``sigma0`` at the front
    nodes (the rear nodes carry the same values, Wong & Reece's mapping), with the exit and
    max-stress angles, the exponent ``n``, the shear :class:`_Displacement` and the rut
    ``ground``. ``reversal``: split the panels at the shear reversal
    (:func:`_reversal_offset`). Shared by the longitudinal contact (:func:`_arc_form`) and the
    lateral one (:func:`_lateral_arc`)."""

    def __init__(self, theta_f, slip, P: Params, nodes: tuple[int, int], reversal: bool) -> None:
        Rc, Rs, Rref = radii(P)
        b = P["wheel.width"]
        n, modulus = reece(slip, P)
        k_eq = modulus * (Rc / b) ** n
        theta_r = exit_angle(theta_f, P)
        theta_m = _max_stress_ratio(slip, P) * theta_f
        displacement = _Displacement(theta_f, slip, P, Rc, Rs, Rref)
        d_front, d_rear = theta_f - theta_m, theta_m - theta_r
        if reversal:
            g, w = _split_rule(_reversal_offset(theta_f, theta_r, d_front, d_rear,
                                                displacement), nodes)
        else:
            g, w = _panel_rule(nodes[0])
        # x = theta_f - theta at each node, formed without cancellation
        trig_f = displacement.sin_f, displacement.cos_f
        self.front = _offset_trig(*trig_f, d_front * g)  # also theta* of the rear nodes
        self.rear = _offset_trig(*trig_f, (theta_f - theta_r) - d_rear * g)
        self.w_front, self.w_rear = d_front * w, d_rear * w
        # k_eq*drop**n, shared by both panels, as exp(n*log(drop)): the same number to
        # rounding, and its derivative by theta_f needs no second power (d pow(x, n) =
        # n*pow(x, n - 1)): the Newton steps of the sinkage solve cost ~15 % less. drop = 0
        # (theta_f = 0) gives 0 and a zero derivative, as the power did for n > 1.
        drop = self.front["cos_drop"]
        sigma0 = k_eq * ca.if_else(drop > 0, ca.exp(n * ca.log(drop)), 0)
        self.ground = rut(slip, P)  # in a rut: the elastic-plastic soil below its surface
        self.sigma0 = ca.if_else(self.ground.on, self.ground.pressure(Rc * drop), sigma0)
        self.n, self.theta_r, self.theta_m = n, theta_r, theta_m
        self.displacement = displacement


def _arc_form(theta_f: ca.SX, slip: ca.SX, wheel_angle: ca.SX, P: Params, nodes: tuple[int, int],
              ripple: bool, reversal: bool) -> dict:
    """The arc form: all contact quantities for a given entry angle (no damping).
    ``ripple=False`` drops the ripple. ``reversal=True`` splits the panels at the shear reversal
    (:func:`_reversal_offset`); ``False`` is the rule without it, exact where
    :func:`_reverses` is 0 (there the split rule's second sub-panel has zero weight)."""
    Rc, Rs, Rref = radii(P)
    b = P["wheel.width"]
    c, tan_phi = shear_strength(P)
    arc = _ArcNodes(theta_f, slip, P, nodes, reversal)
    n, theta_r, theta_m, displacement = arc.n, arc.theta_r, arc.theta_m, arc.displacement
    front, rear, w_front, w_rear = arc.front, arc.rear, arc.w_front, arc.w_rear
    cos_f, sin_f, cos_r, sin_r = front["cos"], front["sin"], rear["cos"], rear["sin"]
    sigma0, ground = arc.sigma0, arc.ground

    contact_length = Rc * (ca.sin(theta_f) - ca.sin(theta_r))
    K = effective_shear_modulus(contact_length, P)
    # model.rut_shear: the displacement the rut's maker, at this slip, left at its exit
    maker = _maker_angle(ground, P)
    made = _Displacement(maker, slip, P, Rc, Rs, Rref).along(maker - exit_angle(maker, P))
    made = ca.if_else(_cumulative(P), P["model.rut_shear"] * made, 0)
    g_front = shear_function(made + displacement.at(front), P, K)
    g_rear = shear_function(made + displacement.at(rear), P, K)

    def integrals(sigma: ca.SX) -> dict:
        tau_f, tau_r = (c + sigma * tan_phi) * g_front, (c + sigma * tan_phi) * g_rear
        return {
            "sig_cos": ca.dot(w_front, sigma * cos_f) + ca.dot(w_rear, sigma * cos_r),
            "sig_sin": ca.dot(w_front, sigma * sin_f) + ca.dot(w_rear, sigma * sin_r),
            "tau_cos": ca.dot(w_front, tau_f * cos_f) + ca.dot(w_rear, tau_r * cos_r),
            "tau_sin": ca.dot(w_front, tau_f * sin_f) + ca.dot(w_rear, tau_r * sin_r),
            "tau": ca.dot(w_front, tau_f) + ca.dot(w_rear, tau_r),
        }

    static = integrals(sigma0)
    normal_static = b * (Rc * static["sig_cos"] + Rs * static["tau_sin"])
    mean_pressure = normal_static / (b * ca.fmax(contact_length, 1e-300))
    amplitude = (P["ripple.k_g"] * mean_pressure
                 + P["ripple.k_0"] * contact_length * P["soil.gamma_variation"])
    if ripple:
        phase = P["grouser.count"] * wheel_angle + P["ripple.phase"]
        total = integrals(ca.fmax(sigma0 + amplitude * ca.sin(phase), 0))
    else:
        total = static
    g_x, g_z, g_t = _grouser_thrust(theta_f, front, rear, w_front, w_rear, g_front, g_rear, P,
                                    Rc)
    normal_static = normal_static + g_z
    thrust = b * Rs * total["tau_cos"] + g_x
    compaction = b * Rc * total["sig_sin"]
    dozing = bulldozing(2 * Rc * ca.sin(theta_f / 2) ** 2, P)  # z = R_c*(1 - cos(theta_f))
    return {
        "normal_force": b * (Rc * total["sig_cos"] + Rs * total["tau_sin"]) + g_z,
        "drawbar_pull": thrust - compaction - dozing,
        "torque": b * Rs**2 * total["tau"] + g_t,
        "gross_thrust": thrust,
        "compaction_resistance": compaction,
        "entry_angle": theta_f,
        "exit_angle": theta_r,
        "max_stress_angle": theta_m,
        "contact_length": contact_length,
        "mean_pressure": mean_pressure,
        "sinkage_exponent": n,
        "ripple_amplitude": amplitude if ripple else ca.SX(0),
        "normal_force_static": normal_static,
        "bulldozing_resistance": dozing,
        **dict(zip(("rut_left", "rut_pressure_left"), rut_left(theta_f, ground, P),
                   strict=True)),
    }


def _grouser_thrust(theta_f, front, rear, w_front, w_rear, g_front, g_rear, P: Params, Rc):
    """Grouser thrust by passive earth pressure (``model.grouser_thrust`` = 1), as the
    grouser-period mean: (horizontal, vertical, torque about the axle).

    A grouser at angle theta spans radii R .. R + h_g; its root lies R*cos(theta) - R_c*cos(theta_f)
    below the undisturbed surface (negative: above), its tip (R + h_g)*cos(theta) - ... . The
    buried vertical height h and the depth of its top d give the Rankine passive force per unit
    width F = gamma*h**2*K_p/2 + 2*c*h*sqrt(K_p) + gamma*d*h*K_p, K_p = tan(pi/4 + phi/2)**2
    (Bekker 1960; Wong, ch. 2). It is mobilised like the shear stress, F*g(j(theta)), acts along
    the rim's tangent (cos, sin) at moment arm R + h_g/2, and is spread over the grouser spacing:
    density n_g/(2*pi) per radian, integrated over the contact arc with the arc's quadrature.
    Choices: only grousers on the contact arc [theta_r, theta_f] count; the wall is taken as
    vertical (its tilt by theta is neglected in K_p).
    """
    R, h_g = P["wheel.radius"], P["grouser.height"]
    f_front = _grouser_force(front["cos"], theta_f, P, Rc) * g_front
    f_rear = _grouser_force(rear["cos"], theta_f, P, Rc) * g_rear
    scale = _grouser_density(P)
    horizontal = scale * (ca.dot(w_front, f_front * front["cos"])
                          + ca.dot(w_rear, f_rear * rear["cos"]))
    vertical = scale * (ca.dot(w_front, f_front * front["sin"])
                        + ca.dot(w_rear, f_rear * rear["sin"]))
    torque = scale * (R + h_g / 2) * (ca.dot(w_front, f_front) + ca.dot(w_rear, f_rear))
    return horizontal, vertical, torque


def _grouser_force(cos_t, theta_f, P: Params, Rc):
    """Passive earth force per unit width on a grouser at cos(theta) = ``cos_t`` (see
    :func:`_grouser_thrust`); non-decreasing in ``cos_t`` (soil parameters >= 0)."""
    R, h_g = P["wheel.radius"], P["grouser.height"]
    c, gamma = P["soil.cohesion"], P["soil.gamma"]
    k_p = ca.tan(math.pi / 4 + P["soil.phi"] / 2) ** 2
    surface = Rc * ca.cos(theta_f)
    top = ca.fmax(R * cos_t - surface, 0)
    height = ca.fmax((R + h_g) * cos_t - surface - top, 0)
    return (0.5 * gamma * height**2 * k_p + 2 * c * height * ca.sqrt(k_p)
            + gamma * top * height * k_p)


def _grouser_density(P: Params):
    """The grouser thrust's factor: on/off times width times grousers per radian."""
    return P["model.grouser_thrust"] * P["wheel.width"] * P["grouser.count"] / (2 * math.pi)


SMALL_MOBILISATION = 1e-3  # |x*l/K| below which the patch-mean shear uses its Taylor series


def patch_shear_mean(a: ca.SX, P: Params) -> ca.SX:
    """Mean mobilised shear fraction over a patch whose displacement grows linearly from 0 at
    the front to ``a`` = x*l/K at the rear (x the shearing slip, l the patch length):
    (1/a)*int_0^a g(u*K) du for the shear law of ``model.shear_model``, odd in ``a`` as g is.

    Janosi: 1 - (1 - exp(-a))/a, the bracket of Bekker's patch thrust
    H = (A*c + W*tan(phi))*[1 - K/(x*l)*(1 - exp(-x*l/K))] (Bekker 1960; Wong, *Theory of
    Ground Vehicles*, ch. 2). Wong's hump form g = K_r*[(1 - E) + C*e*(E - E**2)],
    E = exp(-j/K), C = 1/(K_r*(1 - 1/e)) - 1, integrates the same way:
    K_r*[1 - (1 - exp(-a))/a + C*e*((1 - exp(-a)) - (1 - exp(-2a))/2)/a].
    Below SMALL_MOBILISATION the 0/0 is replaced by the Taylor series (three terms, error
    ~a**4).
    """
    Kr, hump = P["soil.residual_ratio"], P["model.shear_model"]
    m = ca.fabs(a)
    small = m < SMALL_MOBILISATION
    safe = ca.if_else(small, 1, m)
    one_minus = -ca.expm1(-safe)  # 1 - exp(-a) without cancellation
    janosi = ca.if_else(small, m / 2 - m**2 / 6 + m**3 / 24, 1 - one_minus / safe)
    rise = ca.if_else(small, m / 2 - m**2 / 2 + 7 * m**3 / 24,
                      (one_minus + ca.expm1(-2 * safe) / 2) / safe)
    C = 1 / (Kr * (1 - math.exp(-1))) - 1
    wong = Kr * (janosi + C * math.e * rise)
    return ca.sign(a) * ((1 - hump) * janosi + hump * wong)


def _mean_decay(m: ca.SX) -> ca.SX:
    """(1 - exp(-m))/m for m >= 0, the mean of exp(-u) over [0, m]; its Taylor series below
    SMALL_MOBILISATION (error ~m**4)."""
    small = m < SMALL_MOBILISATION
    safe = ca.if_else(small, 1, m)
    return ca.if_else(small, 1 - m / 2 + m**2 / 6 - m**3 / 24, -ca.expm1(-safe) / safe)


def patch_shear_mean_after(a0: ca.SX, a: ca.SX, P: Params) -> ca.SX:
    """:func:`patch_shear_mean` for soil that arrives already sheared by ``a0`` = j0/K (the
    displacement a wheel before this one left, same sign as ``a``): the mean of g(u*K) over
    u in [a0, a0 + a], (G(a0 + a) - G(a0))/a with G the integral of g. With E the mean of
    exp(-u) over the patch, exp(-a0)*(1 - exp(-a))/a, and E2 that of exp(-2u)::

        Janosi: 1 - E          hump: K_r*[(1 - E) + C*e*(E - E2)]

    a0 = 0 gives :func:`patch_shear_mean`'s value (to rounding; that function is used there)."""
    Kr, hump = P["soil.residual_ratio"], P["model.shear_model"]
    m, m0 = ca.fabs(a), ca.fabs(a0)
    E = ca.exp(-m0) * _mean_decay(m)
    E2 = ca.exp(-2 * m0) * _mean_decay(2 * m)
    C = 1 / (Kr * (1 - math.exp(-1))) - 1
    janosi = 1 - E
    wong = Kr * (janosi + C * math.e * (E - E2))
    return ca.sign(a) * ((1 - hump) * janosi + hump * wong)


def _cumulative(P: Params) -> ca.SX:
    """1 where a wheel's shear counts on from the rut's (``model.rut_shear`` > 0 in a rut)."""
    return ca.logic_and(in_rut(P), P["model.rut_shear"] > 0)


def _contact_length(theta_f: ca.SX, P: Params) -> ca.SX:
    """R_c*(sin(theta_f) - sin(theta_r)): the contact length of both forms at entry angle
    ``theta_f`` (theta_r = :func:`exit_angle`)."""
    Rc, _, _ = radii(P)
    return Rc * (ca.sin(theta_f) - ca.sin(exit_angle(theta_f, P)))


def _maker_angle(ground: Rut, P: Params) -> ca.SX:
    """Entry angle of the wheel that made ``ground``'s rut, read as a wheel of this radius that
    pressed virgin soil to the rut's yield depth; at most FULL_BURIAL (a rut deeper than the
    contact radius R_c: its maker is taken buried to the axle); 0 where the shear is not
    cumulative."""
    Rc, _, _ = radii(P)
    depth = ca.if_else(_cumulative(P), ca.fmin(ground.yield_depth, Rc), 0)
    return entry_angle(depth, P)


def _patch_shear_slip(slip: ca.SX, P: Params) -> ca.SX:
    """The slip of the shearing surface that the patch's shear displacement counts,
    j = x*(distance from the patch's front), by ``model.shear_kinematics`` (see
    :func:`_patch_form`): 0, the wheel element's a - v/R_s; 1, the soil element's R_s/v - 1
    (:func:`_kinematics`)."""
    _, Rs, Rref = radii(P)
    a, v, soil_ratio = _kinematics(slip, Rs, Rref)
    kinematics = P["model.shear_kinematics"]
    return (1 - kinematics) * (a - v / Rs) + kinematics * (soil_ratio - 1)


def _patch_form(theta_f: ca.SX, slip: ca.SX, wheel_angle: ca.SX, P: Params, ripple: bool) -> dict:
    """The patch form (``model.contact_form`` = 1): all contact quantities for a given entry
    angle (no damping), the keys of :func:`_arc_form`.

    The soft-soil reading of the paper's eq. 1: the Reece pressure of the sinkage acts uniformly
    on the flat contact patch, as in Bekker's and Wong's flat-plate analysis of a wheel::

        z = R_c*(1 - cos(theta_f)),   theta_r as in the arc form (lambda = model.exit_ratio)
        l = R_c*(sin(theta_f) - sin(theta_r))   (lambda = 1: the chord 2*sqrt(2*R_c*z - z**2))
        p = (c*k_c' + gamma*b*k_phi')*(z/b)**n,  n = n0 + n1*max(i, 0)    (Reece 1965)
        Fz = b*l*max(p + A*sin(n_g*wheel_angle + Phi), 0)                 (ripple as the arc's)
        H  = (c*b*l + Fz*tan(phi))*m(x*l/K)                               (Bekker 1960)
        R_comp = b*int_0^z p dz' = b*p*z/(n + 1)                          (Bekker 1956)
        DP = H - R_comp,   T = R_s*H

    m is :func:`patch_shear_mean`. x is the slip of the shearing surface (radius R_s) that the
    shear displacement j = x*(distance from the patch front) counts, by
    ``model.shear_kinematics``: 0, the wheel element's a - v/R_s (:func:`_kinematics`: driving
    1 - v/R_s, v = (1 - i)*R_ref the carriage speed per wheel rad/s; braking, per distance
    travelled, (1 + sigma) - R_ref/R_s; with R_s = R_ref the model's slip sigma); 1, the soil
    element's s_s = R_s/v - 1, the slip velocity over the time the patch takes to pass a soil
    element (with R_s = R_ref the paper's slip s). Choices, documented: the compaction
    resistance is the ripple-free rut work; the shear acts horizontally, so it adds nothing to
    Fz; the grouser thrust of the arc form (``model.grouser_thrust``) and the max-stress angle
    (a0, a1) have no meaning on a uniform patch and are not used (max_stress_angle is reported
    as 0).
    """
    Rc, Rs, _ = radii(P)
    b = P["wheel.width"]
    c, tan_phi = shear_strength(P)
    n, modulus = reece(slip, P)
    half = ca.sin(theta_f / 2)
    z = 2 * Rc * half**2  # R_c*(1 - cos(theta_f)) without cancellation
    theta_r = exit_angle(theta_f, P)
    length = Rc * (ca.sin(theta_f) - ca.sin(theta_r))
    pressure = modulus * (z / b) ** n
    compaction = b * pressure * z / (n + 1)
    ground = rut(slip, P)  # in a rut: the elastic-plastic soil below its surface
    depth = ground.surface + z
    # the plastic work of the rut's deepening, b*int_y^depth p dz (the elastic part returns)
    # (in a rut that keeps its pressure, along the law from the depth that carries it)
    deepest = ground.work_depth(ca.fmax(depth, ground.yield_depth))
    yielded = ground.work_depth(ground.yield_depth)
    deepening = b * (ground.law(deepest) * deepest - ground.law(yielded) * yielded) / (n + 1)
    pressure = ca.if_else(ground.on, ground.pressure(z), pressure)
    compaction = ca.if_else(ground.on, deepening, compaction)
    normal_static = b * length * pressure
    amplitude = P["ripple.k_g"] * pressure + P["ripple.k_0"] * length * P["soil.gamma_variation"]
    if ripple:
        phase = P["grouser.count"] * wheel_angle + P["ripple.phase"]
        normal = b * length * ca.fmax(pressure + amplitude * ca.sin(phase), 0)
    else:
        normal = normal_static
    x = _patch_shear_slip(slip, P)
    K = effective_shear_modulus(length, P)
    mobilised = patch_shear_mean(x * length / K, P)
    # model.rut_shear: the share of j0 = x*(its contact length) that the rut's maker, at this
    # slip, left and this wheel inherits
    made = P["model.rut_shear"] * x * _contact_length(_maker_angle(ground, P), P)
    mobilised = ca.if_else(_cumulative(P), patch_shear_mean_after(made / K, x * length / K, P),
                           mobilised)
    thrust = (c * b * length + normal * tan_phi) * mobilised
    dozing = bulldozing(z, P)
    return {
        "normal_force": normal,
        "drawbar_pull": thrust - compaction - dozing,
        "torque": Rs * thrust,
        "gross_thrust": thrust,
        "compaction_resistance": compaction,
        "entry_angle": theta_f,
        "exit_angle": theta_r,
        "max_stress_angle": ca.SX(0),
        "contact_length": length,
        "mean_pressure": pressure,
        "sinkage_exponent": n,
        "ripple_amplitude": amplitude if ripple else ca.SX(0),
        "normal_force_static": normal_static,
        "bulldozing_resistance": dozing,
        **dict(zip(("rut_left", "rut_pressure_left"), rut_left(theta_f, ground, P),
                   strict=True)),
    }


# --- lateral mechanics: a wheel at a slip angle ------------------------------------------------

LATERAL_INPUTS = ("sinkage", "slip", "slip_angle", "turn_slip", "p")
LATERAL_OUTPUTS = ("lateral_force", "aligning_moment", "lateral_shear_force", "side_bulldozing",
                   "turning_moment", "overturning_moment")
"""The lateral contact of :func:`lateral_at`: the soil's force on the wheel along its axle
(positive to the wheel's left), the moment of the lateral stresses about the vertical through
the wheel's centre (the self-aligning moment, positive counter-clockwise seen from above), the
force's two parts (the lateral shear on the rim, the side face's bulldozing), and the soil's
whole moment about that vertical, the aligning moment plus the moment of the longitudinal shear
across the tread's width that a yawing wheel meets (:func:`_width_moment`): M_z, what resists
the wheel's yawing (equal to the aligning moment at turn slip 0); and the lateral stresses'
moment about the wheel's heading axis x through its centre, M_x (positive by the right-hand
rule, x forward: a force to the left acting below the centre gives a positive M_x), each
element's force times its depth below the centre (:func:`_side_bulldozing` for the side
face's)."""
LATERAL_RESULTANTS = ("lateral_force", "aligning_moment", "turning_moment", "overturning_moment")
"""The lateral outputs a vehicle takes (the rest are parts of them); the rows of
``functions.build().lateral_jacobian``."""
WIDTH_NODES = 6
"""Gauss-Legendre nodes over the half width of :func:`_width_moment` (measured against the
reference's adaptive quadrature in tests/test_turning.py: 1.0e-4 of the width's moment at
most, at slip 0 where the longitudinal displacement changes sign across the tread)."""


def _lateral_kinematics(slip, slip_angle, Rs, Rref):
    """(per radian, per metre): the lateral shear displacement j_y accumulated by a rim element
    per radian of x = theta_f - theta (wheel element) and per metre the wheel travels (soil
    element), times tan(slip angle). The wheel moves sideways by tan(beta) per metre forward.
    Wheel element (``model.shear_kinematics`` 0): in the time the rim turns dx, V*dx/omega
    forward, v*dx with v of :func:`_kinematics` (driving (1 - sigma)*R_ref; braking, counted
    per distance as the longitudinal shear, R_ref): j_y = tan(beta)*v*x, Ishigami et al.
    2007's j_y = r*(1 - s)*(theta_f - theta)*tan(beta) (driving). Soil element (1): the soil
    under the wheel is sheared by the wheel's sideways travel while it passes it:
    j_y = tan(beta)*R_c*(sin(theta_f) - sin(theta))."""
    _, v, _ = _kinematics(slip, Rs, Rref)
    tan_b = ca.tan(slip_angle)
    return tan_b * v, tan_b


class _Sideways:
    """The lateral shear displacement j_y of a wheel at slip angle beta and turn slip phi
    (``turn_slip`` [rad/m]: its yaw rate r over its forward speed V, the curvature of its path
    in the wheel's frame; Pacejka's turn slip without camber). A contact element at x [m] ahead
    of the axle moves sideways at V*(tan(beta) + phi*x), so per metre the wheel travels it
    slips tan(beta) + phi*x, and the displacement it accumulated since it entered the soil (as
    the longitudinal shear counts it, Wong & Reece 1967; for the yaw part, the brush model of
    turn slip, Pacejka, *Tire and Vehicle Dynamics*, ch. 3) is, x_f = R_c*sin(theta_f):

    - wheel element (``model.shear_kinematics`` 0), time counted by the wheel's turning (per
      distance travelled braking, :func:`_kinematics`' v):
      j_y = v*[tan(beta)*(theta_f - theta) + phi*R_c*(cos(theta) - cos(theta_f))];
    - soil element (1), sheared while the wheel passes it, s = x_f - x the distance passed:
      j_y = tan(beta)*s + phi*s*(x_f + x)/2.

    With ``turn`` False the phi terms are not formed (a kernel at turn slip 0: the slip angle's
    expressions as they were, bit for bit)."""

    def __init__(self, slip, slip_angle, turn_slip, P: Params, turn: bool) -> None:
        Rc, Rs, Rref = radii(P)
        _, self.v, _ = _kinematics(slip, Rs, Rref)
        self.per_radian, self.per_metre = _lateral_kinematics(slip, slip_angle, Rs, Rref)
        self.kin, self.Rc, self.phi, self.turn = P["model.shear_kinematics"], Rc, turn_slip, turn

    def at(self, o: dict, sin_f) -> ca.SX:
        """j_y at the nodes of an :func:`_offset_trig` dict (``sin_f`` = sin(theta_f))."""
        wheel = self.per_radian * o["x"]
        passed = self.Rc * o["sin_drop"]  # s = x_f - x
        soil = self.per_metre * passed
        if self.turn:
            wheel = wheel + self.phi * self.v * self.Rc * o["cos_drop"]
            soil = soil + self.phi * passed * self.Rc * (sin_f + o["sin"]) / 2
        return (1 - self.kin) * wheel + self.kin * soil

    def width_rate(self, o: dict) -> ca.SX:
        """D at the nodes: the longitudinal displacement per metre of lateral offset y per unit
        turn slip (a tread element at y, to the wheel's left, slips backward faster by r*y:
        j_x(y) = j_x + phi*y*D); D = v*(theta_f - theta) (wheel element), s (soil element)."""
        return (1 - self.kin) * self.v * o["x"] + self.kin * self.Rc * o["sin_drop"]


def _lateral_modulus(length, P: Params):
    """K_y: ``model.lateral_shear_ratio`` times the effective K of a contact of ``length``."""
    return P["model.lateral_shear_ratio"] * effective_shear_modulus(length, P)


def _hegedus_factors(P: Params) -> tuple[ca.SX, ca.SX]:
    """Hegedus's (D1, D2): D1 = cot(X) + tan(X + phi), D2 = cot(X) + cot(X)**2*tan(phi),
    X = pi/4 - phi/2 the soil's destructive angle."""
    phi = P["soil.phi"]
    x = math.pi / 4 - phi / 2
    cot = 1 / ca.tan(x)
    return cot + ca.tan(x + phi), cot + cot**2 * ca.tan(phi)


def _hegedus(h, P: Params):
    """Bulldozing resistance [N/m] of the side face at depth ``h`` [m] below the surface it
    meets (Hegedus 1960, as Ishigami et al. 2007 apply it to a wheel's side):
    D1*(c*h + D2*gamma*h**2/2) (:func:`_hegedus_factors`)."""
    c, gamma = P["soil.cohesion"], P["soil.gamma"]
    d1, d2 = _hegedus_factors(P)
    depth = ca.fmax(h, 0)
    return d1 * (c * depth + d2 * gamma * depth**2 / 2)


def _hegedus_depth(h, P: Params):
    """Depth [m] below the surface of the resultant of Hegedus's pressure on a face buried
    ``h`` deep (c uniform, gamma growing with depth): h*(c/2 + D2*gamma*h/3)/(c + D2*gamma*h/2),
    the pressure's first moment over its resultant (any value at h = 0, where it is 0)."""
    c, gamma = P["soil.cohesion"], P["soil.gamma"]
    _, d2 = _hegedus_factors(P)
    depth = ca.fmax(h, 0)
    below = c + d2 * gamma * depth / 2
    share = (c / 2 + d2 * gamma * depth / 3) / ca.if_else(below > 0, below, 1)
    return depth * share


def _side_bulldozing(nodes_weights, j_y, K_y, P: Params, Rc):
    """(force, moment, overturning) of the side face's bulldozing over the contact arc
    (Ishigami et al. 2007: int R_b(h)*(R - h*cos(theta)) dtheta, h = R_c*(cos(theta) -
    cos(theta_f))), each element mobilised like the lateral shear at its node, g(j_y), and
    opposing the sideways motion; the moment's lever the element's position along the wheel,
    R_c*sin(theta); the overturning moment's its resultant's depth below the centre,
    R_c*cos(theta_f) + :func:`_hegedus_depth` (the surface's depth and the pressure's
    centre below it). ``nodes_weights``: ((node dict, weights), ...) of :func:`_offset_trig`
    nodes; ``j_y``: the lateral displacement at each, in the same order."""
    force = moment = overturning = 0
    for (o, w), j in zip(nodes_weights, j_y, strict=True):
        h = Rc * o["cos_drop"]
        element = -_hegedus(h, P) * (Rc - h * o["cos"]) * shear_function(j, P, K_y)
        force = force + ca.dot(w, element)
        moment = moment + ca.dot(w, element * Rc * o["sin"])
        surface = Rc * (o["cos"] - o["cos_drop"])  # R_c*cos(theta_f)
        overturning = overturning + ca.dot(w, element * (surface + _hegedus_depth(h, P)))
    share = P["model.side_bulldozing"]
    return share * force, share * moment, share * overturning


def _width_moment(law, centre, spread, b):
    """int_{-b/2}^{b/2} y*law(centre + spread*y) dy [m2 times law's unit] for an odd ``law``
    (the mobilised shear fraction of a tread element at lateral offset y): the first moment
    across the width, as int_0^{b/2} y*(law(centre + spread*y) - law(centre - spread*y)) dy by
    WIDTH_NODES-point Gauss-Legendre. ``centre``, ``spread``: one value or a column per node;
    exactly 0 at spread 0."""
    x, w = np.polynomial.legendre.leggauss(WIDTH_NODES)
    half = b / 2
    total = 0
    for u, wk in zip((x + 1.0) / 2.0, w / 2.0, strict=True):
        y = half * float(u)
        total = total + half * float(wk) * y * (law(centre + spread * y)
                                                - law(centre - spread * y))
    return total


def _lateral_arc(theta_f, slip, slip_angle, turn_slip, P: Params, nodes: tuple[int, int],
                 turn: bool = False) -> dict:
    """The arc form's lateral contact (LATERAL_OUTPUTS) at entry angle ``theta_f``, ripple-free
    (the grouser-period mean): the lateral shear stress -(c + sigma*tan(phi))*g(j_y; K_y) on
    the rim, sigma the arc's own normal stress at each node (:class:`_ArcNodes`), j_y of
    :class:`_Sideways`, plus the side face's bulldozing (:func:`_side_bulldozing`). Ishigami
    et al. 2007's side force with the lateral shear law kept apart from the longitudinal one, as
    they do (the two are not combined into one resultant limited by Coulomb's strength: at a
    large slip angle and slip both can be near full, a known limit of the form).

    ``turn``: with the turn slip's terms (:class:`_Sideways`) and the moment of the
    longitudinal shear across the width: a tread element at y slips longitudinally by
    j_x + phi*y*D (:meth:`_Sideways.width_rate`), so the shear's moment about the vertical is
    -R_s*int (c + sigma*tan(phi))*cos(theta)*int y*g(j_x + phi*y*D; K) dy dtheta
    (:func:`_width_moment`; j_x the centre line's ripple-free displacement). Without it the
    turning moment is the aligning moment."""
    Rc, Rs, _ = radii(P)
    b = P["wheel.width"]
    c, tan_phi = shear_strength(P)
    arc = _ArcNodes(theta_f, slip, P, nodes, reversal=False)  # j_y keeps its sign
    side = _Sideways(slip, slip_angle, turn_slip, P, turn)
    sin_f = arc.displacement.sin_f
    length = _contact_length(theta_f, P)
    K_y = _lateral_modulus(length, P)
    strength = c + arc.sigma0 * tan_phi  # the rear nodes carry the front nodes' stress
    j_front, j_rear = side.at(arc.front, sin_f), side.at(arc.rear, sin_f)
    tau_f = -strength * shear_function(j_front, P, K_y)
    tau_r = -strength * shear_function(j_rear, P, K_y)
    shear = b * Rs * (ca.dot(arc.w_front, tau_f) + ca.dot(arc.w_rear, tau_r))
    moment = b * Rs * Rc * (ca.dot(arc.w_front, tau_f * arc.front["sin"])
                            + ca.dot(arc.w_rear, tau_r * arc.rear["sin"]))
    overturning = b * Rs * Rc * (ca.dot(arc.w_front, tau_f * arc.front["cos"])
                                 + ca.dot(arc.w_rear, tau_r * arc.rear["cos"]))
    side_force, side_moment, side_over = _side_bulldozing(((arc.front, arc.w_front),
                                                           (arc.rear, arc.w_rear)),
                                                          (j_front, j_rear), K_y, P, Rc)
    aligning = moment + side_moment
    turning = aligning
    if turn:
        K = effective_shear_modulus(length, P)

        def law(j):
            return shear_function(j, P, K)

        width = 0
        for o, w in ((arc.front, arc.w_front), (arc.rear, arc.w_rear)):
            first = _width_moment(law, arc.displacement.at(o), turn_slip * side.width_rate(o),
                                  b)
            width = width + ca.dot(w, strength * o["cos"] * first)
        turning = aligning - Rs * width
    return {"lateral_force": shear + side_force, "aligning_moment": aligning,
            "lateral_shear_force": shear, "side_bulldozing": side_force,
            "turning_moment": turning, "overturning_moment": overturning + side_over}


SMALL_CENTRED = 0.05
"""Below it, :func:`_centred_decay` is its Taylor series: above, its closed form loses at
most ~1e-13 relative to cancellation (also with an expm1 written as exp(x) - 1, as the
Modelica library's is)."""


def _centred_decay(m):
    """D(m) = int_0^1 (s - 1/2)*exp(-m*s) ds for m >= 0: (1 - exp(-m)*(1 + m))/m**2 -
    (1 - exp(-m))/(2*m) above SMALL_CENTRED, else its series
    sum_k>=1 (-m)**k*k/(2*k!*(k + 1)*(k + 2)) to k = 7 (next term < 1e-16 relative)."""
    small = m < SMALL_CENTRED
    safe = ca.if_else(small, 1, m)
    rise = -ca.expm1(-safe)  # 1 - exp(-m)
    exact = (rise - safe * ca.exp(-safe)) / safe**2 - rise / (2 * safe)
    series = 0
    for k in range(7, 0, -1):  # Horner, highest power first
        series = series * m + (-1) ** k * k / (2 * math.factorial(k) * (k + 1) * (k + 2))
    return ca.if_else(small, series * m, exact)


def patch_shear_centred_moment(a, P: Params):
    """int_0^1 (s - 1/2)*g(a*s*K) ds: the first moment, about the patch's middle, of the
    mobilised shear fraction whose displacement grows linearly from the front (s = 0) to ``a``
    = j(rear)/K at the rear (:func:`patch_shear_mean`'s zeroth moment); odd in ``a``, positive
    (the shear rises toward the rear). Janosi: -D(a); hump: K_r*[-D(a) + C*e*(D(a) - D(2a))],
    D = :func:`_centred_decay` (the constant part of g has no moment about the middle)."""
    Kr, hump = P["soil.residual_ratio"], P["model.shear_model"]
    m = ca.fabs(a)
    janosi = -_centred_decay(m)
    C = 1 / (Kr * (1 - math.exp(-1))) - 1
    wong = Kr * (janosi + C * math.e * (_centred_decay(m) - _centred_decay(2 * m)))
    return ca.sign(a) * ((1 - hump) * janosi + hump * wong)


def _lateral_patch(theta_f, slip, slip_angle, turn_slip, P: Params, nodes: tuple[int, int],
                   turn: bool = False) -> dict:
    """The patch form's lateral contact (LATERAL_OUTPUTS): Bekker's patch shear turned
    sideways, -(c*b*l + Fz_static*tan(phi))*m(y*l/K_y), y the lateral displacement per metre
    of the patch (:func:`_lateral_kinematics` over R_s, the rim's speed past the soil, as the
    patch's longitudinal shear counts it), m :func:`patch_shear_mean`; its moment from the
    first moment of the same distribution about the patch's middle
    (:func:`patch_shear_centred_moment`, free of cancellation) and the middle's position
    R_c*(sin(theta_f) + sin(theta_r))/2; the side face's bulldozing as in the arc form, over
    the same arc's geometry.

    ``turn``: at a turn slip phi the displacement s metres behind the patch's front is
    f*(tan(beta)*s + phi*s*(x_f + x)/2) (:class:`_Sideways` on the patch, f the factor above),
    no longer linear in s, so the uniform stress's mean and moment are taken by the arc
    quadrature's nodes over the patch (ds = R_c*cos(theta)*dtheta), and the turning moment adds
    the moment of the longitudinal shear across the width: a strip at y shears by
    (x_s + phi*f*y)*s, so it carries (c*l + Fz_static*tan(phi)/b)*m((x_s + phi*f*y)*l/K) per
    metre of width and the moment is -(that)*int y*m(...) dy (:func:`_width_moment`)."""
    Rc, Rs, Rref = radii(P)
    b = P["wheel.width"]
    c, tan_phi = shear_strength(P)
    static = _patch_form(theta_f, slip, 0, P, False)
    length, normal = static["contact_length"], static["normal_force_static"]
    per_radian, per_metre = _lateral_kinematics(slip, slip_angle, Rs, Rref)
    kin = P["model.shear_kinematics"]
    rate = (1 - kin) * per_radian / Rs + kin * per_metre  # j_y per metre of the patch
    K_y = _lateral_modulus(length, P)
    full = c * b * length + normal * tan_phi
    theta_r = static["exit_angle"]
    g, w = _panel_rule(nodes[0])
    trig_f = ca.sin(theta_f), ca.cos(theta_f)
    arc = _offset_trig(*trig_f, (theta_f - theta_r) * g)
    weights = (theta_f - theta_r) * w
    passed = Rc * arc["sin_drop"]  # s, metres behind the patch's front
    j_y = rate * passed
    along = weights * Rc * arc["cos"]  # ds
    stress = b * (c + static["mean_pressure"] * tan_phi)  # full/l, per metre of the patch
    if turn:
        _, v, _ = _kinematics(slip, Rs, Rref)
        factor = (1 - kin) * v / Rs + kin  # j per metre of the patch per unit tan(beta)
        j_y = j_y + factor * turn_slip * passed * Rc * (trig_f[0] + arc["sin"]) / 2
    mobilised = shear_function(j_y, P, K_y)  # at the nodes
    if turn:
        shear = -stress * ca.dot(along, mobilised)
        moment = -stress * ca.dot(along, mobilised * Rc * arc["sin"])
    else:
        a = rate * length / K_y
        mean = patch_shear_mean(a, P)
        shear = -full * mean
        middle = Rc * (ca.sin(theta_f) + ca.sin(theta_r)) / 2  # the patch's middle
        moment = -full * (middle * mean - length * patch_shear_centred_moment(a, P))
    # M_x: the same stress at each point of the patch times its depth, R_c*cos(theta), by the
    # quadrature's nodes in both cases (the patch lies on the arc's chord of nodes)
    overturning = -stress * ca.dot(along, mobilised * Rc * arc["cos"])
    side, side_moment, side_over = _side_bulldozing((((arc, weights)),), (j_y,), K_y, P, Rc)
    aligning = moment + side_moment
    turning = aligning
    if turn:
        K = effective_shear_modulus(length, P)

        def law(a):
            return patch_shear_mean(a, P)

        width = _width_moment(law, _patch_shear_slip(slip, P) * length / K,
                              turn_slip * factor * length / K, b)
        turning = aligning - full / b * width
    return {"lateral_force": shear + side, "aligning_moment": aligning,
            "lateral_shear_force": shear, "side_bulldozing": side,
            "turning_moment": turning, "overturning_moment": overturning + side_over}


LATERAL_FORMS = ("none", "arc", "patch", "turn_arc", "turn_patch")
"""The cases of the lateral switch, in case order: nothing (slip angle and turn slip 0), each
form at a slip angle alone, each form with the turn slip's terms."""
NO_SLIP_ANGLE, LATERAL_ARC, LATERAL_PATCH, TURN_ARC, TURN_PATCH = range(len(LATERAL_FORMS))


def _lateral_symbols():
    """Symbols of LATERAL_INPUTS (the first the sinkage or, for the switch, the entry angle)."""
    return [ca.SX.sym(n) for n in LATERAL_INPUTS[:-1]] + [ca.SX.sym("p", len(NAMES))]


@lru_cache(maxsize=8)
def lateral_switch(nodes: tuple[int, int]) -> tuple[ca.Function, ca.Function]:
    """``(case, switch)``: the lateral contact (LATERAL_OUTPUTS) at an entry angle, evaluating
    only what applies: zeros at slip angle and turn slip 0 (NO_SLIP_ANGLE: nothing computed,
    so a wheel driven straight pays nothing for it), the arc's or the patch's kernel at a slip
    angle alone, their turn-slip kernels (the width moment's extra shear laws) otherwise.
    ``case(theta_f, slip_angle, turn_slip, p)``,
    ``switch(case, theta_f, slip, slip_angle, turn_slip, p)``."""
    th, sl, beta, phi, pp = _lateral_symbols()
    P = Params(pp)

    def kernel(name: str, out: dict) -> ca.Function:
        return ca.Function(f"lateral_{name}", [th, sl, beta, phi, pp],
                           [ca.vertcat(*(out[k] for k in LATERAL_OUTPUTS))], {"cse": True})

    kernels = [kernel("none", dict.fromkeys(LATERAL_OUTPUTS, ca.SX(0)))]
    for turn in (False, True):
        kernels.append(kernel("turn_arc" if turn else "arc",
                              _lateral_arc(th, sl, beta, phi, P, nodes, turn)))
        kernels.append(kernel("turn_patch" if turn else "patch",
                              _lateral_patch(th, sl, beta, phi, P, nodes, turn)))
    patch = P["model.contact_form"] == 1
    case = ca.Function("lateral_case", [th, beta, phi, pp], [ca.if_else(
        ca.logic_and(beta == 0, phi == 0), NO_SLIP_ANGLE,
        ca.if_else(phi == 0, ca.if_else(patch, LATERAL_PATCH, LATERAL_ARC),
                   ca.if_else(patch, TURN_PATCH, TURN_ARC)))])
    return case, ca.Function.conditional("lateral_form", kernels[:-1], kernels[-1])


@lru_cache(maxsize=4)
def lateral_kernels(nodes: tuple[int, int] = DEFAULT_NODES) -> tuple[ca.Function, tuple]:
    """The lateral contact as plain SX Functions of LATERAL_INPUTS, for code generators:
    ``(case, forms)``, ``case`` giving :func:`lateral_switch`' case at each point (the index
    into LATERAL_FORMS) and ``forms[case]`` that case's kernel, the entry angle from the
    sinkage as :func:`lateral_at` takes it (the lane kernels of
    :mod:`wheelterrain.model.lanes`; :func:`lateral_export` selects among them)."""
    z, sl, beta, phi, pp = args = _lateral_symbols()
    P = Params(pp)
    theta_f = entry_angle(z - rut_surface(P), P)
    case, switch = lateral_switch(nodes)
    case_fn = ca.Function("lateral_case", args, [case(theta_f, beta, phi, pp)])
    forms = tuple(ca.Function(f"lateral_{name}", args, [switch.find_function(
        f"lateral_{name}")(theta_f, sl, beta, phi, pp)]) for name in LATERAL_FORMS)
    return case_fn, forms


@lru_cache(maxsize=4)
def lateral_export(nodes: tuple[int, int] = DEFAULT_NODES) -> ca.Function:
    """The quasi-static lateral contact as one plain SX Function of LATERAL_INPUTS, for code
    that is not CasADi's (the Modelica library): :func:`lateral_kernels`, the switch a select
    (every form evaluated)."""
    args = _lateral_symbols()
    case, forms = lateral_kernels(nodes)
    which = case(*args)
    y = ca.SX.zeros(len(LATERAL_OUTPUTS))  # NO_SLIP_ANGLE
    for k in range(len(LATERAL_FORMS) - 1, 0, -1):
        y = ca.if_else(which == k, forms[k](*args), y)
    return ca.Function("lateral", args, [y], list(LATERAL_INPUTS), ["y"], {"cse": True})


LATERAL_MEMORY_INPUTS = ("sinkage", "slip", "slip_angle", "turn_slip", "plastic_sinkage",
                         "mean_pressure", "p")
"""The inputs of :func:`lateral_memory_export`: the lateral contact on the soil with memory."""


@lru_cache(maxsize=4)
def lateral_memory_export(nodes: tuple[int, int] = DEFAULT_NODES) -> ca.Function:
    """:func:`lateral_export` on the soil with memory (``functions.build().lateral_memory``):
    the lateral contact at the yield sinkage max(z_p, z), scaled by the elastic unloading of
    the longitudinal forces (``mean_pressure``: the contact's, as ``contact_memory`` gives it
    at the same state), one plain SX Function of LATERAL_MEMORY_INPUTS for the Modelica
    library's wheels."""
    z, sl, beta, phi, plastic, pressure = (ca.SX.sym(n) for n in LATERAL_MEMORY_INPUTS[:-1])
    pp = ca.SX.sym("p", len(NAMES))
    P = Params(pp)
    yielded = _yield_sinkage(z, plastic, P)
    y = lateral_export(nodes)(yielded, sl, beta, phi, pp)
    y = unloading_share(z, yielded, pressure, P) * y  # as lateral_at scales it
    return ca.Function("lateralMemory", [z, sl, beta, phi, plastic, pressure, pp], [y],
                       list(LATERAL_MEMORY_INPUTS), ["y"], {"cse": True})


def soft_max(a, b, width):
    """max(a, b) with its corner rounded over ``width``: (a + b + sqrt((a - b)**2 +
    width**2))/2, above the max by at most width/2 (at a = b), smooth everywhere."""
    return (a + b + ca.sqrt((a - b) ** 2 + width**2)) / 2


SHARE_WIDTH = 1e-3
"""The smooth yield's rounding of the unloading share's corner at 0 (a wheel lifted off)."""


def unloading_share(z, yielded, mean_pressure, P: Params, smooth=None):
    """The share of the contact's forces a wheel lifted from where the soil yielded keeps:
    max(1 - K_u*(z_y - z)/p_mean, 0), every contact pressure falling by K_u*(z_y - z) along
    the elastic line (see :func:`contact_at`); ``mean_pressure`` the contact's at z_y.
    ``smooth`` (a width [m], the smooth yield of a prediction model): the corner at 0 rounded
    over SHARE_WIDTH (:func:`soft_max`)."""
    relief = P["soil.unloading_stiffness"] * (yielded - z)
    # no contact (p_mean = 0): every force the share scales is 0, so the share is taken as 1;
    # the division is made safe, not only not taken: CasADi differentiates the branch not
    # taken too (0 times the infinite derivative of relief/0 was NaN in every Jacobian of a
    # wheel out of the soil)
    touching = mean_pressure > 0
    safe = ca.if_else(touching, mean_pressure, 1)
    kept = ca.if_else(touching, 1 - relief / safe, 1)
    if smooth is None:
        return ca.fmax(kept, 0)
    # bounded below first: a wheel lifted far off a contact of no pressure makes kept ~ -1e300,
    # whose square in soft_max would overflow (the share is 0 there either way)
    return soft_max(ca.fmax(kept, -1), 0, SHARE_WIDTH)


def lateral_at(z, slip, slip_angle, turn_slip, P: Params,
               nodes: tuple[int, int] = DEFAULT_NODES, plastic=None, mean_pressure=None) -> dict:
    """The lateral contact (LATERAL_OUTPUTS) of a wheel at sinkage ``z`` [m] (from the original
    surface; its contact begins at the rut's surface as the longitudinal one's), the model's
    slip ``slip`` along its heading, the slip angle ``slip_angle`` [rad] between its heading
    and its velocity (positive: the wheel moves toward its left) and the turn slip
    ``turn_slip`` [rad/m] (its yaw rate over its forward speed, positive counter-clockwise
    seen from above; :class:`_Sideways`), in the form ``model.contact_form`` selects,
    ripple-free (the grouser-period mean). 0 at slip angle and turn slip 0, exactly; odd in
    the pair (slip angle, turn slip). The longitudinal contact is not changed by either (the
    slip is the one along the heading, the normal stress the same).

    ``plastic`` (with ``mean_pressure``, the longitudinal contact's at the yield sinkage, as
    :func:`contact_at` gives it): the wheel's plastic sinkage; the lateral contact is then
    that at the yield sinkage z_y = max(z_p, z), scaled by the same elastic unloading as the
    longitudinal forces (:func:`unloading_share`)."""
    yielded = _yield_sinkage(z, plastic, P)
    theta_f = entry_angle(yielded - rut_surface(P), P)
    case, switch = lateral_switch(nodes)
    values = switch(case(theta_f, slip_angle, turn_slip, P.p), theta_f, slip, slip_angle,
                    turn_slip, P.p)
    out = {k: values[i] for i, k in enumerate(LATERAL_OUTPUTS)}
    if plastic is not None:
        share = unloading_share(z, yielded, mean_pressure, P)
        out = {k: share * v for k, v in out.items()}
    return out


BOUND_MARGIN = 1 + 1e-9  # covers rounding where the bound is the value itself (the patch)


def static_bound(theta_f: ca.SX, slip: ca.SX, P: Params) -> ca.SX:
    """A cheap upper bound on Fz_static at entry angle ``theta_f`` in (0, pi/2], for either
    contact form and any quadrature rule with non-negative panel weights summing to one:
    the sinkage solve's scan skips angles where it is below the load (there Fz_static is too).

    Arc: every node lies in [-theta_f, theta_f] (exit ratio <= 1, |a0 + a1*i| <= 1), so
    0 <= cos <= 1 and |sin| <= sin(theta_f); the stress is at most k_eq*(1 - cos(theta_f))**n,
    the mobilised shear at most :func:`shear_peak`, the grouser force at most its value at
    cos = 1, and the weights of a panel sum to its width. Hence, with D = |theta_f - theta_m|
    + |theta_m - theta_r|, sigma_max and g_max::

        Fz_static <= b*D*(R_c*sigma_max + R_s*sin(theta_f)*(c + sigma_max*tan(phi))*g_max)
                     + density*D*F_grouser(1)*g_max*sin(theta_f)

    Patch: Fz_static itself (b*l*p, a few operations). Both times BOUND_MARGIN. Valid for
    parameters in their declared ranges (all soil parameters >= 0); tests check it against the
    quadrature over random points of those ranges; where an assumption above fails (inputs
    outside the declared ranges), it is +inf: no angle is skipped."""
    Rc, Rs, _ = radii(P)
    b, c, tan_phi = P["wheel.width"], P["soil.cohesion"], ca.tan(P["soil.phi"])
    n, modulus = reece(slip, P)
    k_eq = modulus * (Rc / b) ** n
    half = ca.sin(theta_f / 2)
    sigma_max = k_eq * ca.exp(n * ca.log(2 * half**2))  # k_eq*(1 - cos(theta_f))**n
    # in a rut: the rut's pressure at the deepest point (it rises with depth on both its
    # branches; the law there is not a bound: where the elastic layer is not thin against the
    # rut, the elastic line law(yield_depth)*d/layer rises above the law at the same depth)
    ground = rut(slip, P)
    sigma_max = ca.if_else(ground.on, ground.pressure(2 * Rc * half**2), sigma_max)
    theta_r = exit_angle(theta_f, P)
    ratio = _max_stress_ratio(slip, P)
    theta_m = ratio * theta_f
    span = ca.fabs(theta_f - theta_m) + ca.fabs(theta_m - theta_r)
    sin_f, g_max = ca.sin(theta_f), shear_peak(P)
    grouser = _grouser_density(P) * _grouser_force(1, theta_f, P, Rc) * g_max * sin_f
    arc = b * span * (Rc * sigma_max + Rs * sin_f * (c + sigma_max * tan_phi) * g_max) \
        + span * grouser
    patch = _patch_form(theta_f, slip, 0, P, False)["normal_force_static"]
    lam = P["model.exit_ratio"]
    holds = [theta_f <= FULL_BURIAL, ca.fabs(ratio) <= 1, lam >= 0, lam <= 1, n >= 0, c >= 0,
             P["soil.gamma"] >= 0, k_eq >= 0, tan_phi >= 0, P["soil.residual_ratio"] > 0,
             P["grouser.height"] >= 0, Rc > 0, Rs > 0]
    bound = ca.if_else(P["model.contact_form"] == 1, patch, arc)
    # where an assumption fails (inputs outside the model's ranges) there is no bound: +inf
    return ca.if_else(all_of(holds), BOUND_MARGIN * bound, math.inf)


def all_of(conditions: list) -> ca.SX:
    out = conditions[0]
    for condition in conditions[1:]:
        out = ca.logic_and(out, condition)
    return out


ARC, ARC_REVERSAL, PATCH = 0, 1, 2  # the cases of the contact switch (:func:`form_switch`)
FORMS = ("arc", "arc_reversal", "patch")  # their kernels' names, in case order


@lru_cache(maxsize=8)
def form_switch(nodes: tuple[int, int], ripple: bool, keep: tuple[str, ...] = CONTACT_OUTPUTS
                ) -> tuple[ca.Function, ca.Function]:
    """``(case, switch)``: every contact quantity at an entry angle (or those in ``keep``, in
    its order: the kernels then compute only what those need), evaluating only the form and
    the rule that apply.

    ``case(theta_f, slip, p)`` is PATCH when ``model.contact_form`` is 1; for the arc, ARC where
    the shear displacement keeps its sign on the arc and ARC_REVERSAL where it changes sign
    (:func:`_reverses`). ``switch(case, theta_f, slip, wheel_angle, p)`` is a CasADi
    conditional over the three SX Functions: the generated C and the virtual machine run one
    branch (expanded to SX, all three are evaluated and one is kept, exactly as before the
    switch). ARC is ARC_REVERSAL's split rule without its zero-weight sub-panel, so the two give
    the same numbers where no reversal exists; the switch saves the reversal search, the
    second sub-panel and, for the patch, the whole arc."""
    th, sl, angle, pp = (ca.SX.sym("theta_f"), ca.SX.sym("slip"), ca.SX.sym("wheel_angle"),
                         ca.SX.sym("p", len(NAMES)))
    P = Params(pp)
    tag = ("" if ripple else "_static") + ("" if keep == CONTACT_OUTPUTS else
                                            "_" + "_".join(keep))

    def kernel(name: str, out: dict) -> ca.Function:
        return ca.Function(name + tag, [th, sl, angle, pp],
                           [ca.vertcat(*(out[k] for k in keep))], {"cse": True})

    arc = kernel(FORMS[ARC], _arc_form(th, sl, angle, P, nodes, ripple, reversal=False))
    split = kernel(FORMS[ARC_REVERSAL], _arc_form(th, sl, angle, P, nodes, ripple,
                                                  reversal=True))
    patch = kernel(FORMS[PATCH], _patch_form(th, sl, angle, P, ripple))

    Rc, Rs, Rref = radii(P)
    reverses = _reverses(th, exit_angle(th, P), _Displacement(th, sl, P, Rc, Rs, Rref))
    case = ca.Function("contact_case" + tag, [th, sl, pp], [ca.if_else(
        P["model.contact_form"] == 1, PATCH, ca.if_else(reverses, ARC_REVERSAL, ARC))])
    return case, ca.Function.conditional("contact_form" + tag, [arc, split], patch)


def _at_entry_angle(theta_f, slip, wheel_angle, P: Params, nodes: tuple[int, int],
                    ripple: bool) -> dict:
    """Every contact quantity at entry angle ``theta_f`` in the form ``model.contact_form``
    selects (0 arc, 1 patch), through :func:`form_switch`' switch: only the selected form is
    evaluated, so neither form's value leaks into the other's."""
    case, switch = form_switch(nodes, ripple)
    out = switch(case(theta_f, slip, P.p), theta_f, slip, wheel_angle, P.p)
    return {k: out[i] for i, k in enumerate(CONTACT_OUTPUTS)}


YIELD_PRESSURE = ("mean_pressure", "sinkage_exponent")
"""What the imprint's relaxation toward the soil ahead needs of the contact
(:func:`plastic_update`)."""


def yield_pressure(z, slip, plastic, P: Params, nodes: tuple[int, int], smooth=None
                   ) -> tuple:
    """(mean_pressure, sinkage_exponent) of :func:`contact_at` with the plastic sinkage
    ``plastic`` (and its ``smooth``), the same numbers, from kernels that compute only those
    two (both belong to the contact at the yield sinkage: the unloading does not scale them,
    the grouser ripple and the damper do not enter them), for the co-simulation step of the
    soil's memory: the forces, torque and ripple are not evaluated."""
    theta_f = entry_angle(_yield_sinkage(z, plastic, P, smooth) - rut_surface(P), P)
    case, switch = form_switch(nodes, True, YIELD_PRESSURE)
    out = switch(case(theta_f, slip, P.p), theta_f, slip, 0, P.p)
    return out[0], out[1]


def entry_angle(z, P: Params):
    """theta_f = arccos(1 - z/R_c) in its half-angle form, accurate for tiny sinkage (1 - z/R_c
    rounds); 0 for z <= 0, with a derivative of 0 there. The square root is taken of 1, not of
    0, where z <= 0: its infinite derivative at 0, multiplied by the zero adjoint of a branch
    not taken, made every reverse-mode Jacobian column through R_c NaN (the rut maker's angle
    of model.rut_shear is 0 where the shear is not cumulative: the calibration's Jacobian by
    wheel.radius, grouser.height and model.contact_radius_factor)."""
    Rc, _, _ = radii(P)
    share = z / (2 * Rc)
    inside = share > 0
    return ca.if_else(inside, 2 * ca.asin(ca.sqrt(ca.if_else(inside, share, 1))), 0)


SCALED = ("normal_force", "drawbar_pull", "torque", "gross_thrust", "compaction_resistance",
          "normal_force_static", "bulldozing_resistance")
"""The contact outputs the elastic unloading of :func:`contact_at` scales (forces, torque)."""


def contact_at(z, z_rate, slip, wheel_angle, P: Params, nodes: tuple[int, int], ripple: bool,
             form: ca.Function | None = None, plastic=None, smooth=None) -> dict:
    """Contact quantities at sinkage z (m, to the contact circle), with damping C_f*dz/dt.
    ``form``: one of :func:`form_switch`' kernels to use in place of the switch (the lane kernels of
    :func:`lane_kernels`); by default the switch picks it.

    ``plastic``: the wheel's plastic sinkage z_p, the deepest it has pressed the soil under it
    (:func:`plastic_update`); None for the contact without it (the quasi-static solve, the
    grouser-period mean). With ``model.soil_memory`` = 1 the soil under the wheel yields at
    the yield sinkage z_y = max(z_p, z): pressed deeper than z_p it follows the
    pressure-sinkage law (plastic, the contact at z); lifted by d = z_y - z it unloads along
    the elastic line of stiffness K_u (``soil.unloading_stiffness``): every contact pressure
    falls by K_u*d, taken as a uniform share, the forces of the contact at z_y times
    max(1 - K_u*d/p_mean, 0) (p_mean the mean pressure of the contact at z_y; exact for the
    patch form's uniform pressure without cohesion, an approximation of the arc's distribution;
    d <= p_mean/K_u, a fraction of a millimetre, is small against the sinkage, so the geometry
    stays that of z_y). The damper acts while the wheel is in contact. Where z >= z_p (and
    with ``model.soil_memory`` = 0) this is the contact without it, exactly.

    ``smooth``: a width [m] for a prediction model that needs derivatives across the yield
    (the slip NMPC): z_y = :func:`soft_max` (z_p, z) over it and the unloading share's corner
    rounded (:func:`unloading_share`); None (every plant, FMU and face) is the law above."""
    yielded = _yield_sinkage(z, plastic, P, smooth)
    below = yielded - rut_surface(P)  # depth below the surface the contact begins at
    theta_f = entry_angle(below, P)
    if form is None:
        out = _at_entry_angle(theta_f, slip, wheel_angle, P, nodes, ripple)
    else:
        values = form(theta_f, slip, wheel_angle, P.p)
        out = {k: values[i] for i, k in enumerate(CONTACT_OUTPUTS)}
    if plastic is not None:
        share = unloading_share(z, yielded, out["mean_pressure"], P, smooth)
        out.update({k: share * out[k] for k in SCALED})
        below = ca.if_else(share > 0, below, 0)  # lifted off: no damper
        out["yield_sinkage"] = yielded
        out["imprint_target"] = imprint_target(z, yielded, share, out["sinkage_exponent"], P)
    damping = ca.if_else(below > 0, P["soil.damping"] * z_rate, 0)
    out["normal_force"] = ca.fmax(out["normal_force"] + damping, 0)
    return out


def _yield_sinkage(z, plastic, P: Params, smooth=None):
    """z_y: the sinkage the soil under the wheel has yielded to, max(z_p, z) with
    ``model.soil_memory`` = 1 (:func:`soft_max` over ``smooth`` [m] where given); z without
    memory (or without a plastic sinkage)."""
    if plastic is None:
        return z
    deeper = ca.fmax(plastic, z) if smooth is None else soft_max(plastic, z, smooth)
    return ca.if_else(P["model.soil_memory"] == 1, deeper, z)


def _imprint_decay(yielded, speed, P: Params, shortest: float = 1e-300):
    """|V|/l: the rate at which a wheel rolling at ``speed`` replaces the soil under it, l the
    contact length at the yield sinkage (R_c*(sin(theta_f) - sin(theta_r)), the contact
    forms' own), at least ``shortest`` [m]."""
    length = _contact_length(entry_angle(yielded - rut_surface(P), P), P)
    return ca.fabs(speed) / ca.fmax(length, shortest)


SHORTEST_IMPRINT = 1e-4
"""m: the smooth yield's shortest contact length in the imprint's decay. The smooth rate
blends both branches, so the lifted one's |V|/l is evaluated where the wheel is out of the soil
too (l = 0); floored here it stays finite (the law's own branch is not taken there)."""


RATE_WIDTH = 1e-6
"""m/s: the smooth yield's rounding of max(dz/dt, 0) in the plastic sinkage's rate."""


def imprint_target(z, yielded, share, exponent, P: Params):
    """z_t [m]: what the imprint under a rolling wheel lifted from where it yielded relaxes
    toward (``model.imprint_relaxation``). 0: the wheel's sinkage ``z`` (the surface, a rut's
    or 0, where the wheel is out of the soil: it leaves soil it has not pressed). 1: the sinkage
    at which the soil ahead of the wheel, not pressed yet, carries the force the wheel carries now,
    ``share`` (:func:`unloading_share`) of the contact's at the yield sinkage ``yielded``: a
    rigid wheel's normal force grows with its sinkage below the surface it meets, s (a rut's,
    or 0), as (z - s)**((2*n + 1)/2) (Bekker's rigid-wheel integral of p = k*z**n, Wong, Theory
    of Ground Vehicles, 4th ed., sec. 2.4.2; n the contact's ``sinkage_exponent``), so z_t =
    s + (z_y - s)*share**(2/(2*n + 1)): z_y where the wheel presses (share 1), the surface
    where it is lifted off (share 0)."""
    surface = rut_surface(P)
    power = 2 / (2 * exponent + 1)
    kept = ca.if_else(share > 0, ca.exp(power * ca.log(ca.fmax(share, 1e-300))), 0)
    fresh = surface + (yielded - surface) * kept
    # a wheel lifted out of the soil (z below its surface) leaves unpressed soil: the surface
    return ca.if_else(P["model.imprint_relaxation"] == 1, fresh, ca.fmax(z, surface))


def plastic_rate(z, z_rate, plastic, speed, P: Params, target, smooth=None):
    """d(z_p)/dt of the wheel's plastic sinkage (model exchange; :func:`plastic_update` is the
    co-simulation step): while the wheel presses the soil (z >= z_p) z_p follows the sinkage
    down, max(dz/dt, 0); lifted (z < z_p) the wheel rolls onto soil it has not pressed and the
    imprint under it relaxes, -(|V|/l)*(z_p - z_t), l the contact length, z_t (``target``,
    :func:`imprint_target`) the wheel's sinkage or the sinkage at which the soil ahead carries
    the wheel's present force (``model.imprint_relaxation``); an imprint at or above the surface
    (l = 0: nothing pressed) stays. 0 with ``model.soil_memory`` = 0.
    Where the sinkage rate input is not the exact derivative of the sinkage, z_p can drift
    below z: the outputs then yield at z (memory lost, never stiffness added). ``smooth`` (the
    smooth yield of :func:`contact_at`): the two branches blended by (1 + tanh((z -
    z_p)/smooth))/2, max(dz/dt, 0) rounded over RATE_WIDTH."""
    if smooth is not None:  # the smooth yield: the branches blended over ``smooth`` [m]
        decay = _imprint_decay(soft_max(plastic, z, smooth), speed, P, SHORTEST_IMPRINT)
        pressing = (1 + ca.tanh((z - plastic) / smooth)) / 2
        rate = (pressing * soft_max(z_rate, 0, RATE_WIDTH)
                - (1 - pressing) * decay * (plastic - target))
        return ca.if_else(P["model.soil_memory"] == 1, rate, 0)
    decay = _imprint_decay(ca.fmax(plastic, z), speed, P)
    # an imprint at or above the surface has no contact length (|V|/l infinite): nothing is
    # left to relax, the rate is 0
    lifted = ca.if_else(plastic > rut_surface(P), -decay * (plastic - target), 0)
    rate = ca.if_else(z >= plastic, ca.fmax(z_rate, 0), lifted)
    return ca.if_else(P["model.soil_memory"] == 1, rate, 0)


def plastic_update(z, plastic, speed, P: Params, h, mean_pressure, exponent):
    """The wheel's plastic sinkage z_p after a co-simulation step of ``h`` s with the sinkage
    ``z`` and carriage speed ``speed`` held: the wheel yields the soil at once to z_y = max(z_p,
    z) (the step's start), and the imprint under it is replaced by the soil ahead as the wheel
    rolls, z_p -> z_t + (z_y - z_t)*exp(-|V|*h/l), l the contact length at z_y, z_t
    (:func:`imprint_target` at the step's start, from the contact's ``mean_pressure`` and
    sinkage ``exponent`` there) the wheel's sinkage or the sinkage at which the soil ahead
    carries the wheel's present force (``model.imprint_relaxation``). The rut of earlier passes
    is the ground's (``soil.rut_depth``), not this state's. ``plastic`` unchanged with
    ``model.soil_memory`` = 0."""
    yielded = ca.fmax(plastic, z)
    target = imprint_target(z, yielded, unloading_share(z, yielded, mean_pressure, P), exponent,
                            P)
    relaxed = target + (yielded - target) * ca.exp(-_imprint_decay(yielded, speed, P) * h)
    return ca.if_else(P["model.soil_memory"] == 1, relaxed, plastic)


def _form_kernels(names: list[str], sym: list, z, z_rate, slip, angle, plastic, speed, P: Params,
                  nodes: tuple[int, int], ripple: bool) -> tuple[ca.Function, tuple]:
    """``(case, forms)`` over the symbols ``sym`` (named ``names``): the case the switch of
    :func:`form_switch` picks, and the contact of :func:`contact_at` with each form's kernel in
    place of the switch; with a ``plastic`` sinkage the outputs add MEMORY_OUTPUTS."""
    case, switch = form_switch(nodes, ripple)
    theta_f = entry_angle(_yield_sinkage(z, plastic, P) - rut_surface(P), P)
    case_fn = ca.Function("contact_case", sym, [case(theta_f, slip, P.p)], names, ["case"],
                          {"cse": True})
    rows = CONTACT_OUTPUTS + (MEMORY_OUTPUTS if plastic is not None else ())
    forms = []
    for name in FORMS:
        kernel = switch.find_function(name + ("" if ripple else "_static"))
        out = contact_at(z, z_rate, slip, angle, P, nodes, ripple, form=kernel, plastic=plastic)
        if plastic is not None:
            out["plastic_rate"] = plastic_rate(z, z_rate, plastic, speed, P,
                                               out["imprint_target"])
        forms.append(ca.Function(f"contact_{name}", sym, [ca.vertcat(*(out[k] for k in rows))],
                                 names, ["out"], {"cse": True}))
    return case_fn, tuple(forms)


@lru_cache(maxsize=4)
def lane_kernels(nodes: tuple[int, int] = DEFAULT_NODES) -> tuple[ca.Function, tuple]:
    """The contact (ripple on) as plain SX Functions of CONTACT_INPUTS, for code generators
    that evaluate many points at once (:mod:`wheelterrain.model.lanes`): ``(case, forms)``.
    ``case`` gives the switch's case (ARC, ARC_REVERSAL, PATCH) at each point; ``forms[c]`` is
    the contact with case c's kernel in place of the switch, so at every point where ``case``
    is c it is the same expression that ``functions.build().contact`` evaluates."""
    sym = [ca.SX.sym(name) for name in CONTACT_INPUTS[:-1]] + [ca.SX.sym("p", len(NAMES))]
    return _form_kernels(list(CONTACT_INPUTS), sym, *sym[:4], None, None, Params(sym[-1]), nodes,
                         True)


EXPORT_INPUTS = {
    True: (*CONTACT_INPUTS[:4], "plastic_sinkage", "carriage_speed", "p"),
    False: ("sinkage", "slip", "p"),
}
"""The inputs of :func:`export_kernels`' Functions: the dynamic contact with memory (True), the
quasi-static one (False)."""


@lru_cache(maxsize=4)
def export_kernels(memory: bool, nodes: tuple[int, int] = DEFAULT_NODES
                   ) -> tuple[ca.Function, tuple]:
    """The contact as plain SX Functions, one per form, for code that is not CasADi's (the
    Modelica library): ``(case, forms)`` as :func:`lane_kernels`, ``case`` giving the form
    (ARC, ARC_REVERSAL, PATCH) and ``forms[case]`` the contact with that form's kernel in place
    of the switch.

    ``memory=True``: the contact of ``functions.build().contact_memory`` (ripple on), inputs
    EXPORT_INPUTS[True], outputs CONTACT_OUTPUTS and MEMORY_OUTPUTS. ``memory=False``: the
    quasi-static contact of the steady state (ripple-free, no sinkage rate, no memory), inputs
    EXPORT_INPUTS[False], outputs CONTACT_OUTPUTS: its ``normal_force_static`` equal to the
    load is the steady state's equation for the sinkage."""
    names = list(EXPORT_INPUTS[memory])
    sym = [ca.SX.sym(name) for name in names[:-1]] + [ca.SX.sym("p", len(NAMES))]
    if memory:
        return _form_kernels(names, sym, *sym[:6], Params(sym[-1]), nodes, True)
    z, slip = sym[:2]
    return _form_kernels(names, sym, z, 0, slip, 0, None, None, Params(sym[-1]), nodes, False)
