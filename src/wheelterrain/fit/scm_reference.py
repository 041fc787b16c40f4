"""An independent multi-pass reference: the Soil Contact Model's node law on a discretised rim.

Written from the published algorithm (Krenn & Hirzinger 2009, "SCM - A soil contact model for
multi-body system simulations"; the node update of Chrono's ``SCMTerrain``), not from this
project's contact forms, so that the contact's multi-pass direction can be checked against a
second implementation of the law the rover's soil memory follows. Every soil column along the
strip is one node; a wheel rolls over it steadily, so every node sees the same history and the
march of one node through the contact, front to rear, is the whole contact:

- **elastic try**: sigma = K_u*(d - z_p), d the rim's depth below the original surface at the
  node, z_p the node's plastic sinkage; no contact where it is <= 0;
- **yield**: where the try exceeds the pressure the node has carried, sigma_y, the node
  follows the pressure-sinkage law, sigma = p(d) (Reece's form, this wheel's exponent at its
  slip), and remembers sigma_y = sigma, z_p = d - sigma/K_u;
- **shear**: the node's shear displacement accumulates while it is in contact, j += slip
  velocity * dt (the rim element's tangential slip, R*(1 - (1 - i)*cos(theta)) per radian:
  driving slips only); the next pass starts from the share ``shear_share`` of it (SCM keeps
  it all, 1: its node record is never reset; ``model.rut_shear`` is this project's share);
  tau = (c + sigma*tan(phi))*(1 - exp(-j/K));
- **forces**: on the arc, sigma along the rim's normal and tau along its tangent (the arc
  form's directions); a pass's sinkage is the one at which the vertical force carries the
  load (bracketed root).

A pass leaves each node at its plastic sinkage z_p (the rut's free surface: the elastic part
springs back) with the pressure it carried, sigma_y, and its shear displacement: the next
pass meets exactly that. Not modelled (as in this project's contact): the material
SCM's bulldozing moves to the rut's sides.

The wheel and soil are this project's parameters by table name: the contact radius
R + f_c*h_g, the width, c, phi, K, K_u and the Reece constants (``soil.n0``, ``soil.n1``,
``soil.k_c``, ``soil.k_phi``, ``soil.gamma``); grousers, ripple and the model's extensions are
not part of it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

NODES = 4000
"""Nodes over the contact's arc: from 2000 to 8000 the pull per newton moves ~1e-4, the
sinkage 2e-5 relative."""


@dataclass(frozen=True)
class Node:
    """What a pass leaves a soil node with: its plastic sinkage z_p [m] (the rut's free
    surface), the pressure it carried sigma_y [Pa], its shear displacement j [m]."""

    plastic: float = 0.0
    carried: float = 0.0
    shear: float = 0.0


def _soil(p: Mapping[str, float], slip: float) -> tuple[float, float]:
    n = p["soil.n0"] + p["soil.n1"] * max(slip, 0.0)
    modulus = (p["soil.cohesion"] * p["soil.k_c"]
               + p["soil.gamma"] * p["wheel.width"] * p["soil.k_phi"])
    return n, modulus


def _march(p: Mapping[str, float], slip: float, node: Node, shear_share: float,
           sinkage: float, nodes: int) -> tuple[float, float, float, Node]:
    """One node through the contact of a wheel sunk to ``sinkage``: (Fz, Fx, torque, the
    node after)."""
    R = p["wheel.radius"] + p["model.contact_radius_factor"] * p["grouser.height"]
    b, K_u, K = p["wheel.width"], p["soil.unloading_stiffness"], p["soil.shear_modulus"]
    c, tan_phi = p["soil.cohesion"], math.tan(p["soil.phi"])
    n, modulus = _soil(p, slip)
    top = math.acos(max(1.0 - sinkage / R, -1.0))
    edges = np.linspace(top, -top, nodes + 1)
    theta = 0.5 * (edges[:-1] + edges[1:])
    step = edges[0] - edges[1]
    depth = sinkage - R * (1.0 - np.cos(theta))
    # the node's yield depth (where its elastic line meets the pressure it carried)
    start = node.plastic + node.carried / K_u
    yielded = np.maximum.accumulate(np.maximum(depth, start))
    law = modulus * np.power(np.maximum(yielded, 0.0) / b, n)
    carried = np.where(yielded > start, law, node.carried)
    sigma = np.where(depth >= yielded, carried, carried - K_u * (yielded - depth))
    touch = sigma > 0
    sigma = np.where(touch, sigma, 0.0)
    j0 = shear_share * node.shear
    j = j0 + np.cumsum(np.where(touch, R * (1.0 - (1.0 - slip) * np.cos(theta)) * step, 0.0))
    tau = np.where(touch, (c + sigma * tan_phi) * -np.expm1(-j / K), 0.0)
    area = b * R * step
    fz = area * np.sum(sigma * np.cos(theta) + tau * np.sin(theta))
    fx = area * np.sum(tau * np.cos(theta) - sigma * np.sin(theta))
    torque = area * R * np.sum(tau)
    last = yielded[-1]
    after = Node(plastic=last - carried[-1] / K_u, carried=float(carried[-1]),
                 shear=float(j[-1]))
    return float(fz), float(fx), float(torque), after


def one_pass(p: Mapping[str, float], load: float, slip: float, node: Node = Node(),
             shear_share: float = 1.0, nodes: int = NODES) -> tuple[dict, Node]:
    """The steady pass of a wheel carrying ``load`` [N] at the driving slip ``slip`` (0 <= i
    < 1) over soil whose nodes are ``node``: its row (``sinkage`` [m] from the original
    surface, ``drawbar_pull`` [N], ``traction_coefficient``, ``torque`` [N m], ``rut_left``
    [m]) and the nodes it leaves."""
    if not 0.0 <= slip < 1.0:
        raise ValueError(f"the SCM reference takes driving slips 0 <= i < 1, not {slip}")
    R = p["wheel.radius"] + p["model.contact_radius_factor"] * p["grouser.height"]

    def excess(z: float) -> float:
        return _march(p, slip, node, shear_share, z, nodes)[0] - load

    low = node.plastic + 1e-9
    high = node.plastic + 0.95 * R
    if excess(high) < 0:
        raise ValueError(f"the SCM reference wheel cannot carry {load} N on this soil")
    sinkage = brentq(excess, low, high, xtol=1e-10, rtol=1e-12)
    fz, fx, torque, after = _march(p, slip, node, shear_share, sinkage, nodes)
    return ({"sinkage": sinkage, "drawbar_pull": fx, "traction_coefficient": fx / load,
             "torque": torque, "normal_force": fz, "rut_left": after.plastic}, after)


def passes(p: Mapping[str, float], load: float, slip: float, count: int = 5,
           shear_share: float | None = None, nodes: int = NODES) -> list[dict]:
    """``count`` passes over one strip, each meeting the nodes the one before left: one row
    per pass (:func:`one_pass`) with ``pass`` and ``sinkage_increment``. ``shear_share``:
    by default ``p["model.rut_shear"]``, the share this project's contact inherits."""
    share = p["model.rut_shear"] if shear_share is None else shear_share
    node, rows, previous = Node(), [], 0.0
    for k in range(1, count + 1):
        row, node = one_pass(p, load, slip, node, share, nodes)
        rows.append({"pass": k, **row, "sinkage_increment": row["sinkage"] - previous})
        previous = row["sinkage"]
    return rows
