"""The soil's laws, written once in CasADi symbols: what the soil does under a wheel, whatever
the contact's form.

- Reece's pressure-sinkage law (:func:`reece`: n = n0 + n1*|i|, Ding et al. 2011; the modulus
  with its small-wheel factor, Meirion-Griffith & Spenko 2011);
- the shear stress-displacement law (:func:`shear_function`: Janosi, or Wong's hump form of the
  paper's eq. 3) with its shear modulus on a surface of a given length
  (:func:`effective_shear_modulus`, Wiendieck 1968) and peak (:func:`shear_peak`), the
  Mohr-Coulomb strength of the shearing surface (:func:`shear_strength`, Potyondy 1961; Higa
  et al. 2019);
- the bulldozing resistance of the wedge ahead of the wheel (:func:`bulldozing`, Bekker 1960);
- the elastic-plastic soil of repetitive loading that a rut remembers (:class:`Rut`, :func:`rut`,
  :func:`rut_surface`; Wong, *Theory of Ground Vehicles*, ch. 2; the Soil Contact Model's node,
  Krenn & Hirzinger 2009).

:class:`Params` gives every law the parameter table's values by name. The contact forms
(:mod:`wheelterrain.model.contact`) integrate these laws over the wheel; nothing here knows the
wheel's geometry beyond its width and radius.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca

from wheelterrain.parameters import INDEX


class Params:
    """Attribute access to the symbolic parameter vector by table name (``P['soil.phi']``)."""

    def __init__(self, p: ca.SX) -> None:
        self.p = p

    def __getitem__(self, name: str) -> ca.SX:
        return self.p[INDEX[name]]


def shear_function(j: ca.SX, P: Params, K: ca.SX | None = None) -> ca.SX:
    """Mobilised fraction g(j) of the shear strength (odd in j), for the shear deformation
    modulus ``K`` (the contact forms pass :func:`effective_shear_modulus`; by default the
    soil's Janosi K).

    Janosi: 1 - exp(-j/K). Wong's hump form (paper eq. 3, with its last factor restored):
    K_r*(1 + (1/(K_r*(1 - 1/e)) - 1)*exp(1 - j/K))*(1 - exp(-j/K)), peak 1 at j = K, tending to K_r.
    """
    Kr, hump = P["soil.residual_ratio"], P["model.shear_model"]
    K = P["soil.shear_modulus"] if K is None else K
    E = ca.exp(-ca.fabs(j) / K)
    janosi = 1 - E
    wong = Kr * (1 + (1 / (Kr * (1 - math.exp(-1))) - 1) * math.e * E) * (1 - E)
    return ca.sign(j) * ((1 - hump) * janosi + hump * wong)


def effective_shear_modulus(length: ca.SX, P: Params) -> ca.SX:
    """K_eff = K + kappa*l: the shear deformation modulus of a shearing surface of length ``l``
    (the contact length), kappa = ``model.shear_length_ratio``. The shear stress-displacement
    curve of a soil depends on the size of the surface sheared (Wiendieck 1968); with kappa > 0
    the patch mobilisation x*l/K_eff tends to x/kappa on long contacts rather than to full
    strength, and stays x*l/K on short ones. kappa = 0 is Janosi's K exactly."""
    return P["soil.shear_modulus"] + P["model.shear_length_ratio"] * length


def shear_strength(P: Params) -> tuple[ca.SX, ca.SX]:
    """(c_eff, tan(phi_eff)): the Mohr-Coulomb strength of the wheel's shearing surface.

    A share chi of it is soil on soil at the grouser tips (strength c, tan(phi)); the rest is
    the rim on soil (adhesion rho*c, interface friction tan(rho*phi), Potyondy 1961), with
    rho = ``model.interface_ratio`` and chi = h_g/(h_g + h_e) for a grousered wheel
    (h_e = ``model.grouser_shear_height``; 0 for a smooth rim): Higa, Nagaoka & Yoshida 2019
    find nearly all of a grousered wheel's traction at its grousers. Written as the soil's
    strength minus the rim's deficit, so rho = 1 gives c and tan(phi) exactly."""
    c, phi = P["soil.cohesion"], P["soil.phi"]
    h_g, rho = P["grouser.height"], P["model.interface_ratio"]
    chi = ca.if_else(h_g > 0, h_g / (h_g + P["model.grouser_shear_height"]), 0)
    tan_phi = ca.tan(phi)
    rim = 1 - chi
    return c - rim * (1 - rho) * c, tan_phi - rim * (tan_phi - ca.tan(rho * phi))


DIAMETER_REFERENCE = 0.5  # m: below it the flat-plate law fails (Meirion-Griffith & Spenko)


def bulldozing(z: ca.SX, P: Params) -> ca.SX:
    """Bulldozing resistance [N] of the soil wedge ahead of a wheel sunk by ``z``: the share
    ``model.bulldozing`` of the Rankine passive force over the depth z on the width b,
    b*(gamma*z**2*K_p/2 + 2*c*z*sqrt(K_p)), K_p = tan(pi/4 + phi/2)**2 (Bekker 1960; Wong,
    *Theory of Ground Vehicles*, ch. 4). It grows as z**2: where slip digs the wheel in, the
    resistance follows. 0 at the default share."""
    c, gamma = P["soil.cohesion"], P["soil.gamma"]
    k_p = ca.tan(math.pi / 4 + P["soil.phi"] / 2) ** 2
    depth = ca.fmax(z, 0)
    return P["model.bulldozing"] * P["wheel.width"] * (
        0.5 * gamma * depth**2 * k_p + 2 * c * depth * ca.sqrt(k_p))


def shear_peak(P: Params) -> ca.SX:
    """The largest |g(j)| of :func:`shear_function` over all j: 1 for Janosi; for Wong's hump
    K_r*max over E in [0, 1] of (1 + C*e*E)*(1 - E), K_r*(C*e + 1)**2/(4*C*e) at
    E = (C*e - 1)/(2*C*e) when C*e > 1, else K_r at E = 0 (1.05 at K_r = 1)."""
    Kr, hump = P["soil.residual_ratio"], P["model.shear_model"]
    ce = (1 / (Kr * (1 - math.exp(-1))) - 1) * math.e
    wong = Kr * ca.if_else(ce > 1, (ce + 1) ** 2 / (4 * ca.fmax(ce, 1)), 1)
    return (1 - hump) + hump * wong


def reece(slip: ca.SX, P: Params) -> tuple[ca.SX, ca.SX]:
    """Reece's pressure-sinkage law: the exponent n = n0 + n1*max(sigma, 0) (Ding et al. 2011;
    sigma the model's slip, :mod:`wheelterrain.model.slip`) and the modulus
    (c*k_c' + gamma*b*k_phi')*(2R/D_ref)**m (p = modulus*(z/b)**n), shared by both contact
    forms. The diameter factor, m = ``model.diameter_exponent`` and D_ref =
    DIAMETER_REFERENCE, is the small-wheel correction in the form of Meirion-Griffith & Spenko
    2011 (a power of the diameter); m = 0 is the flat-plate law exactly.

    In skid (sigma < 0) the exponent is held at n0, its value at the edge of the data the law
    was fitted on: Ding et al. measured driven wheels (i = 0 to 0.6), and no source here gives
    a skid-sinkage law (this project's assumption; it had used |i|, a skid digging in as much as
    the same driving slip, without a source either)."""
    n = P["soil.n0"] + P["soil.n1"] * ca.fmax(slip, 0)
    diameter = (2 * P["wheel.radius"] / DIAMETER_REFERENCE) ** P["model.diameter_exponent"]
    modulus = (P["soil.cohesion"] * P["soil.k_c"]
               + P["soil.gamma"] * P["wheel.width"] * P["soil.k_phi"]) * diameter
    return n, modulus


@dataclass(frozen=True)
class Rut:
    """The rut a wheel meets, with ``model.soil_memory`` = 1 and ``soil.rut_depth`` > 0
    (``on``; else every field describes virgin soil and ``on`` is 0).

    The elastic-plastic soil of repetitive loading (Wong, *Theory of Ground Vehicles*, ch. 2;
    the Soil Contact Model's soil node, Krenn & Hirzinger 2009): soil that was pressed to a
    yield depth y carried the pressure p(y) of the pressure-sinkage law there; pressed again it
    answers along a stiff elastic line up to p(y) and along the law beyond. Unloaded, its
    surface sprang back by the elastic rebound p(y)/K_u (K_u = ``soil.unloading_stiffness``)
    to the rut's free surface, ``soil.rut_depth`` (what a profile of the rut measures). So a
    point at depth d below the rut's surface carries::

        p = p(surface + d)            d >= layer   (plastic: the law, from the original surface)
        p = p(surface + layer)*d/layer  d < layer  (elastic reloading)
        layer = p(surface)/K_u        the rebound, p at the surface: first order in layer/y

    ``surface`` [m], ``layer`` [m] and ``yield_depth`` = surface + layer; ``n`` and
    ``modulus`` of :func:`reece` (p(z) = modulus*(z/b)**n). The contact begins at the rut's
    surface (:func:`rut_surface`): both forms take the entry angle of the depth below it.

    A rut that keeps the pressure it carried (``soil.rut_pressure`` = p_r > 0; the Soil
    Contact Model's node keeps its yield pressure) is not read from its depth with this
    wheel's law: a rut made at another slip carried another pressure (made at i = 0.5 and read
    at i = 0, the law at its depth is 3.2 times what it carried). It reloads elastically up to
    p_r, and beyond along this wheel's law from the depth z_r at which that law carries p_r
    (continuous; the soil hardened to p_r, whatever the law that brought it there)::

        layer = p_r/K_u,  p = p_r*d/layer  (d < layer),  p = p(z_r + d - layer)  (d >= layer)

    ``peak`` is the elastic line's top (p_r, or p(yield_depth)), ``offset`` the depth on this
    wheel's law of the rut's surface (z_r - layer, or ``surface``): the plastic branch is
    p(offset + d). Where the wheel runs at its maker's slip, p_r = p(yield depth) and both
    readings agree but for the first-order rebound of the unknown one. ``soil.rut_pressure`` =
    0 is a switch (not known), not the limit of a kept pressure: there the exact Jacobians give
    the reading's derivative, 0 for that column; differentiate from a kept pressure above 0.

    Where ``on`` is 0 the fields describe a stand-in rut of depth b, so that the branch a
    switch does not take has finite derivatives (CasADi's derivative of ``if_else`` multiplies
    the branch not taken by 0, and 0*inf is NaN); every use selects by ``on``. Virgin soil,
    ``soil.rut_depth`` = 0, is a kink: the exact Jacobians report the virgin branch's
    derivative there, 0 for that column, although a rut's one-sided effect is not 0 (the
    patch form's chord begins at the rut's surface); differentiate from a rut above 0."""

    on: ca.SX
    surface: ca.SX
    layer: ca.SX
    yield_depth: ca.SX
    n: ca.SX
    modulus: ca.SX
    width: ca.SX
    kept: ca.SX  # 1 where the rut keeps the pressure it carried (soil.rut_pressure > 0)
    peak: ca.SX
    offset: ca.SX

    def law(self, depth: ca.SX) -> ca.SX:
        """The pressure-sinkage law p at ``depth`` > 0 from the original surface."""
        return self.modulus * ca.exp(self.n * ca.log(depth / self.width))

    def pressure(self, d: ca.SX) -> ca.SX:
        """The pressure at depth ``d`` >= 0 below the rut's surface (``on`` only)."""
        plastic = self.law(self.offset + ca.fmax(d, self.layer))
        elastic = self.peak * d / self.layer
        return ca.if_else(d >= self.layer, plastic, elastic)

    def plastic(self, depth: ca.SX) -> ca.SX:
        """The pressure of soil pressed plastically to ``depth`` > 0 from the original
        surface: the law there, or in a rut that keeps its pressure, the law from the depth
        that carries it (:class:`Rut`)."""
        return ca.if_else(self.kept, self.law(self.offset + (depth - self.surface)),
                          self.law(depth))

    def work_depth(self, depth: ca.SX) -> ca.SX:
        """The depth on this wheel's law of soil pressed plastically to ``depth`` from the
        original surface (the bound of the law's integral): ``depth`` itself, or in a rut
        that keeps its pressure, offset + (depth - surface)."""
        return ca.if_else(self.kept, self.offset + (depth - self.surface), depth)


def in_rut(P: Params) -> ca.SX:
    """1 where the wheel meets a rut it remembers: model.soil_memory = 1, soil.rut_depth > 0."""
    return ca.logic_and(P["model.soil_memory"] == 1, P["soil.rut_depth"] > 0)


def rut(slip: ca.SX, P: Params) -> Rut:
    """The :class:`Rut` under the wheel at the model's slip ``slip`` (sigma)."""
    n, modulus = reece(slip, P)
    b = P["wheel.width"]
    on = in_rut(P)
    surface = ca.if_else(on, P["soil.rut_depth"], b)  # the stand-in where off
    kept = ca.logic_and(on, P["soil.rut_pressure"] > 0)
    # the pressure the rut carried: kept, or read from its depth with this wheel's law
    carried = ca.if_else(kept, P["soil.rut_pressure"], modulus * ca.exp(n * ca.log(surface / b)))
    layer = carried / P["soil.unloading_stiffness"]
    yield_depth = surface + layer
    law_yield = modulus * ca.exp(n * ca.log(yield_depth / b))
    # where kept: the depth at which this wheel's law carries the rut's pressure
    equivalent = b * ca.exp(ca.log(carried / modulus) / n)
    return Rut(on, surface, layer, yield_depth, n, modulus, b, kept,
               ca.if_else(kept, carried, law_yield),
               ca.if_else(kept, equivalent - layer, surface))


def rut_surface(P: Params) -> ca.SX:
    """Depth [m] of the surface a wheel's contact begins at: the rut's (``soil.rut_depth``)
    with ``model.soil_memory`` = 1, else the original surface, 0. Sinkage is counted from the
    original surface; the contact's geometry from this one."""
    return ca.if_else(in_rut(P), P["soil.rut_depth"], 0)
