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

from . import params as P
from .integrate import in_domain
from .jit import NO_NRT


def pebble_sums(m, x, y, own_inertia):
    """Mass, centre of mass and polar moment of inertia about it of pebbles of masses
    ``m`` at (x, y) with their own moments ``own_inertia`` (sums: overlaps count twice)."""
    mt = m.sum()
    cx = (m * x).sum() / mt
    cy = (m * y).sum() / mt
    inertia = (own_inertia + m * ((x - cx) ** 2 + (y - cy) ** 2)).sum()
    return mt, cx, cy, inertia


def mass_properties(x, y, r, rho, thick):
    """Pebble-sum mass, centre of mass and polar moment of inertia about it of disks of
    density rho."""
    m = rho * np.pi * r ** 2 * thick
    return pebble_sums(m, x, y, 0.5 * m * r ** 2)


@njit(cache=True, error_model="numpy", inline="always")
def pebble_motion(cx, cy, vx, vy, w, cs, sn, ox, oy):
    """Position and velocity of the pebble at (ox, oy) in the frame of a clump at (cx, cy)
    moving at (vx, vy) with spin w, turned by (cos, sin) = (cs, sn) (the GPU batch uses it
    too)."""
    rx = cs * ox - sn * oy
    ry = sn * ox + cs * oy
    return cx + rx, cy + ry, vx - w * ry, vy + w * rx


@njit(**NO_NRT)
def place_pebbles(prm, kin, balls, clumps, pebbles):
    """Position/velocity of the ``pebbles`` (their ball ids, ascending) from the rigid
    motion of their clump. Returns True if a pebble may have tripped a guard (then
    ``integrate.guards`` says which)."""
    offset = balls.offset
    cpos = clumps.pos
    cvel = clumps.vel
    comega = clumps.omega
    ctheta = clumps.theta
    x0 = prm[P.XMIN]
    y0 = prm[P.YMIN]
    x1 = prm[P.XMAX]
    y1 = prm[P.YMAX]
    vmax2 = prm[P.VMAX] * prm[P.VMAX]
    suspect = False
    last = -1                      # a clump's pebbles mostly follow each other: its
    cs = 1.0                       # rotation is computed once per run of them
    sn = 0.0
    for i in pebbles:
        c = balls.clump[i]
        if not balls.alive[i]:
            continue
        if c != last:
            cs = math.cos(ctheta[c])
            sn = math.sin(ctheta[c])
            last = c
        kin[i, 0], kin[i, 1], kin[i, 2], kin[i, 3] = pebble_motion(
            cpos[c, 0], cpos[c, 1], cvel[c, 0], cvel[c, 1], comega[c], cs, sn,
            offset[i, 0], offset[i, 1])
        kin[i, 4] = comega[c]
        if not in_domain(kin, i, x0, y0, x1, y1, vmax2):
            suspect = True
    return suspect


@njit(**NO_NRT)
def gather_clumps(gx, gy, kin, fa, balls, clumps, pebbles):
    """Clump force = weight + sum of its pebbles' forces (``pebbles``: their ball ids,
    ascending); moment about the centre of mass."""
    cpos = clumps.pos
    cmass = clumps.mass
    cforce = clumps.force
    cmoment = clumps.moment
    for c in range(cpos.shape[0]):
        cforce[c, 0] = cmass[c] * gx
        cforce[c, 1] = cmass[c] * gy
        cmoment[c] = 0.0
    for i in pebbles:
        c = balls.clump[i]
        if not balls.alive[i]:
            continue
        cforce[c, 0] += fa[i, 0]
        cforce[c, 1] += fa[i, 1]
        cmoment[c] += fa[i, 2] + (kin[i, 0] - cpos[c, 0]) * fa[i, 1] \
            - (kin[i, 1] - cpos[c, 1]) * fa[i, 0]
