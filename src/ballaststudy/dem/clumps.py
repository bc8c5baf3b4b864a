"""Clumps: rigid bodies of pebbles. Pebbles are balls whose ``clump`` id is >= 0; they
get contact forces like balls, and the clump integrates the sum.

Mass properties (choice where the spec allows either): by default from the pebble SUMS
(mass = sum rho*pi*R^2*t, centre = mass-weighted centroid, inertia = sum of pebble
inertia + parallel axis), overlaps counted twice — PFC's clump default for pebbles given
without a template. ``Simulation.add_clump`` accepts explicit mass/inertia overrides.
"""
import math

import numpy as np
from numba import njit

from .jit import NO_NRT


def mass_properties(x, y, r, rho, thick):
    """Pebble-sum mass, centre of mass and polar moment of inertia about it."""
    m = rho * np.pi * r ** 2 * thick
    mt = m.sum()
    cx = (m * x).sum() / mt
    cy = (m * y).sum() / mt
    inertia = (0.5 * m * r ** 2 + m * ((x - cx) ** 2 + (y - cy) ** 2)).sum()
    return mt, cx, cy, inertia


@njit(**NO_NRT)
def place_pebbles(kin, balls, clumps):
    """Pebble position/velocity from the rigid motion of their clump."""
    offset = balls.offset
    cpos = clumps.pos
    cvel = clumps.vel
    comega = clumps.omega
    ctheta = clumps.theta
    for i in range(kin.shape[0]):
        c = balls.clump[i]
        if c < 0 or not balls.alive[i]:
            continue
        cs = math.cos(ctheta[c])
        sn = math.sin(ctheta[c])
        ox = cs * offset[i, 0] - sn * offset[i, 1]
        oy = sn * offset[i, 0] + cs * offset[i, 1]
        kin[i, 0] = cpos[c, 0] + ox
        kin[i, 1] = cpos[c, 1] + oy
        kin[i, 2] = cvel[c, 0] - comega[c] * oy
        kin[i, 3] = cvel[c, 1] + comega[c] * ox
        kin[i, 4] = comega[c]


@njit(**NO_NRT)
def gather_clumps(gx, gy, kin, fa, balls, clumps):
    """Clump force = weight + sum of pebble forces; moment about the centre of mass."""
    cpos = clumps.pos
    cmass = clumps.mass
    cforce = clumps.force
    cmoment = clumps.moment
    for c in range(cpos.shape[0]):
        cforce[c, 0] = cmass[c] * gx
        cforce[c, 1] = cmass[c] * gy
        cmoment[c] = 0.0
    for i in range(kin.shape[0]):
        c = balls.clump[i]
        if c < 0 or not balls.alive[i]:
            continue
        cforce[c, 0] += fa[i, 0]
        cforce[c, 1] += fa[i, 1]
        cmoment[c] += fa[i, 2] + (kin[i, 0] - cpos[c, 0]) * fa[i, 1] \
            - (kin[i, 1] - cpos[c, 1]) * fa[i, 0]
