"""An independent plain-Python implementation of the classical Wong-Reece rigid wheel.

Written from the textbook equations (Wong & Reece 1967; Wong, *Theory of Ground Vehicles*), with
scipy's adaptive quadrature (QUADPACK) and Brent's root finder; it shares no code with the package.
Classical means: theta_r = 0, theta_m = (a0 + a1*i)*theta_f, Reece pressure-sinkage with a constant
exponent n, Janosi shear 1 - exp(-j/K), every radius the rim radius, no ripple, no damping.

``kinematics="soil"`` swaps the shear displacement for the soil element's (the slip accumulated
over a ground-fixed soil element while the wheel passes it, as the Soil Contact Model counts it):
j(theta) = R*int_theta^theta_f (1/(1 - i) - cos(t))*cos(t) dt, integrated here numerically
(Gauss-Legendre) rather than in the closed form the package uses.

For braking (i < 0) the slip that enters the law is the skid s = (omega*R - V)/V = i/(1 - i)
(down to -1, a locked wheel): theta_m = (a0 + a1*s)*theta_f, and the wheel element's shear
displacement is counted per distance travelled, j = R*((1 + s)*(theta_f - theta) - (sin(theta_f)
- sin(theta))) (the time of a rim element in contact taken as R*dtheta/V instead of
dtheta/omega, finite at omega = 0). The shear displacement changes sign along the arc; the
reference then uses the same odd extension of Janosi's law as the package (tau = sign(j)*(1 -
exp(-|j|/K))*tau_max), and splits the quadrature at the sign change, found with brentq.
"""

from __future__ import annotations

import itertools
import math
import warnings
from dataclasses import dataclass

import numpy as np
from scipy.integrate import IntegrationWarning, quad
from scipy.optimize import brentq

_GL_NODES, _GL_WEIGHTS = np.polynomial.legendre.leggauss(30)


@dataclass(frozen=True)
class Classical:
    R: float      # wheel radius [m]
    b: float      # width [m]
    c: float      # cohesion [Pa]
    phi: float    # friction angle [rad]
    kc: float     # Reece k_c' [-]
    kphi: float   # Reece k_phi' [-]
    n: float      # sinkage exponent [-]
    gamma: float  # weight density [N/m3]
    K: float      # Janosi shear modulus [m]
    a0: float = 0.4
    a1: float = 0.15
    kinematics: str = "wheel"  # or "soil"

    def _parts(self, z: float, i: float):
        tf = math.acos(1.0 - z / self.R)
        skid = i / (1.0 - i) if i < 0 else None  # braking: the skid s, -1 locked
        tm = (self.a0 + self.a1 * (i if skid is None else skid)) * tf
        keq = (self.c * self.kc + self.gamma * self.b * self.kphi) * (self.R / self.b) ** self.n

        def sigma(t: float) -> float:
            if t >= tm:
                return keq * max(math.cos(t) - math.cos(tf), 0.0) ** self.n
            te = tf - t / tm * (tf - tm)
            return keq * max(math.cos(te) - math.cos(tf), 0.0) ** self.n

        def j(t: float) -> float:
            if self.kinematics == "soil":  # smooth integrand: 30-node Gauss-Legendre is exact
                u = t + (tf - t) * (_GL_NODES + 1.0) / 2.0
                rate = (1.0 / (1.0 - i) - np.cos(u)) * np.cos(u)
                return self.R * (tf - t) / 2.0 * float(_GL_WEIGHTS @ rate)
            if skid is not None:
                return self.R * ((1.0 + skid) * (tf - t) - (math.sin(tf) - math.sin(t)))
            return self.R * ((tf - t) - (1.0 - i) * (math.sin(tf) - math.sin(t)))

        def tau(t: float) -> float:
            jj = j(t)
            return (self.c + sigma(t) * math.tan(self.phi)) * math.copysign(
                1.0 - math.exp(-abs(jj) / self.K), jj)

        breaks = [tm]
        if i < 0:  # j changes sign once inside (0, tf) for a braked wheel
            lo, hi = 1e-14 * tf, tf * (1 - 1e-14)
            if j(lo) * j(hi) < 0:
                breaks.append(brentq(j, lo, hi, xtol=1e-16, rtol=1e-15))
        # Integrand magnitude: the largest possible stress times the arc length.
        magnitude = (keq + self.c) * (1.0 + math.tan(self.phi)) * max(tf, 1e-300)
        return tf, sigma, tau, sorted(breaks), magnitude

    def _integrate(self, f, tf: float, breaks, magnitude: float) -> float:
        """Adaptive quadrature panel by panel. QUADPACK may warn about roundoff on the
        (theta_f - theta)**n end-point singularity; instead of trusting the warning or silencing
        it blindly, we require its error estimate to be 1e-8 of the value, or 1e-10 of the
        integrand's magnitude where the value cancels (far below the 1e-6 comparisons)."""
        edges = [0.0, *breaks, tf]
        total, error = 0.0, 0.0
        for a, b in itertools.pairwise(edges):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", IntegrationWarning)
                value, err = quad(f, a, b, epsabs=1e-13 * magnitude, epsrel=1e-10, limit=500)
            total, error = total + value, error + err
        assert error <= max(1e-8 * abs(total), 1e-10 * magnitude), (total, error, magnitude)
        return total

    def forces(self, z: float, i: float) -> dict[str, float]:
        """Normal force, drawbar pull [N], resistive torque [N.m] at sinkage z, traction slip i."""
        tf, sigma, tau, br, eps = self._parts(z, i)
        Fz = self.R * self.b * self._integrate(
            lambda t: sigma(t) * math.cos(t) + tau(t) * math.sin(t), tf, br, eps)
        DP = self.R * self.b * self._integrate(
            lambda t: tau(t) * math.cos(t) - sigma(t) * math.sin(t), tf, br, eps)
        T = self.R**2 * self.b * self._integrate(tau, tf, br, eps)
        return {"normal_force": Fz, "drawbar_pull": DP, "torque": T}

    def lateral(self, z: float, i: float, beta: float, K_y: float,
                side: bool = True) -> dict[str, float]:
        """Side force [N] and its moment about the vertical through the centre [N.m] of a
        driven wheel (0 <= i < 1) at slip angle ``beta`` [rad], from Ishigami, Miwa, Nagatani
        & Yoshida 2007: the lateral shear displacement j_y = R*(1 - i)*(theta_f - theta)*
        tan(beta), the lateral stress (c + sigma*tan(phi))*(1 - exp(-|j_y|/K_y)) against it,
        and (``side``) the side face's bulldozing after Hegedus, R_b(h)*(R - h*cos(theta)),
        h = R*(cos(theta) - cos(theta_f)), R_b = D1*(c*h + D2*gamma*h**2/2), D1 = cot(X) +
        tan(X + phi), D2 = cot(X) + cot(X)**2*tan(phi), X = pi/4 - phi/2, each element taken
        as mobilised as the lateral shear at its angle (this project's reading)."""
        tf, sigma, _, br, eps = self._parts(z, i)
        sign = -math.copysign(1.0, beta) if beta != 0 else 0.0
        x = math.pi / 4 - self.phi / 2
        d1 = 1 / math.tan(x) + math.tan(x + self.phi)
        d2 = 1 / math.tan(x) + math.tan(self.phi) / math.tan(x) ** 2

        def mobilised(t: float) -> float:
            jy = self.R * (1.0 - i) * (tf - t) * abs(math.tan(beta))
            return 1.0 - math.exp(-jy / K_y)

        def shear(t: float) -> float:
            return self.R * self.b * (self.c + sigma(t) * math.tan(self.phi)) * mobilised(t)

        def bulldozing(t: float) -> float:
            if not side:
                return 0.0
            h = self.R * (math.cos(t) - math.cos(tf))
            rb = d1 * (self.c * h + d2 * self.gamma * h**2 / 2)
            return rb * (self.R - h * math.cos(t)) * mobilised(t)

        force = self._integrate(lambda t: shear(t) + bulldozing(t), tf, br, eps)
        moment = self._integrate(lambda t: (shear(t) + bulldozing(t)) * self.R * math.sin(t),
                                 tf, br, eps)
        return {"lateral_force": sign * force, "aligning_moment": sign * moment}

    def turning(self, z: float, i: float, beta: float, turn: float, K_y: float,
                side: bool = True) -> dict[str, float]:
        """:meth:`lateral` with a turn slip ``turn`` = r/V [rad/m] (r the wheel's yaw rate,
        counter-clockwise from above), a driven wheel (0 <= i < 1), the wheel element's
        kinematics, written from the brush model of turn slip (Pacejka, *Tire and Vehicle
        Dynamics*, ch. 3) on Ishigami et al.'s side force: an element at x = R*sin(t) ahead of
        the axle slides sideways at V*(tan(beta) + turn*x), so in the time it has been in
        contact, (tf - t)/omega, j_y = R*(1 - i)*(tan(beta)*(tf - t) + turn*R*(cos(t) -
        cos(tf))); the lateral stress -(c + sigma*tan(phi))*sign(j_y)*(1 - exp(-|j_y|/K_y)).
        The moment about the vertical adds the longitudinal shear across the width b: a tread
        element at y (to the left) has slipped j + turn*y*R*(1 - i)*(tf - t) longitudinally,
        so M_width = -R*int (c + sigma*tan(phi))*cos(t)*int_{-b/2}^{b/2} y*g(j + ...) dy dt,
        both integrals by adaptive quadrature split at every sign change of the
        displacement. The overturning moment M_x: each element's lateral force times its
        depth below the centre, R*cos(t) on the rim, and for the side face the depth of the
        resultant of Hegedus's pressure, R*cos(tf) + h*(c/2 + D2*gamma*h/3)/(c +
        D2*gamma*h/2). Returns lateral_force, aligning_moment, turning_moment (the sum) and
        overturning_moment."""
        tf, sigma, _tau, br, eps = self._parts(z, i)
        x = math.pi / 4 - self.phi / 2
        d1 = 1 / math.tan(x) + math.tan(x + self.phi)
        d2 = 1 / math.tan(x) + math.tan(self.phi) / math.tan(x) ** 2
        v = self.R * (1.0 - i)

        def jy(t: float) -> float:
            return v * (math.tan(beta) * (tf - t) + turn * self.R * (math.cos(t) - math.cos(tf)))

        def g(j: float, K: float) -> float:
            return math.copysign(1.0 - math.exp(-abs(j) / K), j)

        def parts(t: float) -> tuple[float, float, float]:  # rim, side face, side's depth
            h = self.R * (math.cos(t) - math.cos(tf))
            rb = d1 * (self.c * h + d2 * self.gamma * h**2 / 2) if side else 0.0
            strip = self.R * self.b * (self.c + sigma(t) * math.tan(self.phi))
            mobilised = g(jy(t), K_y)
            below = self.c + d2 * self.gamma * h / 2
            depth = h * (self.c / 2 + d2 * self.gamma * h / 3) / below if below > 0 else 0.0
            return (-strip * mobilised, -rb * (self.R - h * math.cos(t)) * mobilised,
                    self.R * math.cos(tf) + depth)

        def lateral(t: float) -> float:  # the side force per radian, against the displacement
            rim, face, _ = parts(t)
            return rim + face

        def overturning(t: float) -> float:
            rim, face, depth = parts(t)
            return rim * self.R * math.cos(t) + face * depth

        breaks = list(br)
        lo, hi = 1e-14 * tf, tf * (1 - 1e-14)
        if jy(lo) * jy(hi) < 0:
            breaks = sorted([*breaks, brentq(jy, lo, hi, xtol=1e-16, rtol=1e-15)])
        force = self._integrate(lateral, tf, breaks, eps)
        aligning = self._integrate(lambda t: lateral(t) * self.R * math.sin(t), tf, breaks, eps)

        def j_long(t: float) -> float:  # the classical wheel element's j (driving)
            return self.R * ((tf - t) - (1.0 - i) * (math.sin(tf) - math.sin(t)))

        def across(t: float) -> float:  # int y*g(j + turn*D*y) dy over the width
            j0, spread = j_long(t), turn * v * (tf - t)
            half = self.b / 2
            points = [] if spread == 0 else [-j0 / spread]
            points = [p for p in points if -half < p < half]
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", IntegrationWarning)
                value, _ = quad(lambda y: y * g(j0 + spread * y, self.K), -half, half,
                                points=points or None, epsabs=1e-15, epsrel=1e-11, limit=200)
            return value

        width = self._integrate(lambda t: -self.R * (self.c + sigma(t) * math.tan(self.phi))
                                * math.cos(t) * across(t), tf, br, eps * self.b**2)
        over = self._integrate(overturning, tf, breaks, eps * self.R)
        return {"lateral_force": force, "aligning_moment": aligning,
                "turning_moment": aligning + width, "overturning_moment": over}

    def sinkage(self, load: float, i: float) -> float:
        """Sinkage [m] at which the normal force equals ``load`` (Brent, z in (0, R])."""
        return brentq(lambda z: self.forces(z, i)["normal_force"] - load, 1e-12, self.R,
                      xtol=1e-15, rtol=1e-14)
