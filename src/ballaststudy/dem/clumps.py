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
from scipy import ndimage

from . import params as P
from .integrate import in_domain, moved
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


def buried(x, y, r, probe):
    """Which pebbles (centres x, y, radii r) of one clump no disk of radius ``probe`` can
    touch from outside the clump: a probe's centre must keep r_j + probe from every
    pebble's, and those it can reach from far away (the exterior) may touch a pebble i
    only if one is within r_i + probe of it. On a raster of side h = probe / 4, made to
    err towards "reachable": a cell is blocked only within r_j + probe - h (a feasible
    point is within h / sqrt 2 of its cell's centre), cells connect through corners, and
    a pebble is reachable from cells within r_i + probe + h. A wall, a straight line,
    reaches a pebble only through the clump's outline, so only by overlapping the
    pebbles there by about a pebble: never at contact overlaps. Returns a bool array."""
    x, y, r = (np.asarray(a, float) for a in (x, y, r))
    h = probe / 4.0
    pad = r.max() + probe + 3 * h
    x0, y0 = x.min() - pad, y.min() - pad
    nx = int(np.ceil((x.max() + pad - x0) / h)) + 1
    ny = int(np.ceil((y.max() + pad - y0) / h)) + 1
    gx, gy = x0 + h * np.arange(nx), y0 + h * np.arange(ny)
    blocked = np.zeros((nx, ny), bool)
    for xi, yi, ri in zip(x, y, r):
        reach = ri + probe - h
        a, b = _window(gx, xi, reach), _window(gy, yi, reach)
        blocked[a, b] |= ((gx[a, None] - xi) ** 2 + (gy[None, b] - yi) ** 2) < reach * reach
    labels, _ = ndimage.label(~blocked, structure=np.ones((3, 3)))
    outside = labels == labels[0, 0]           # the raster's corner is far from every pebble
    out = np.ones(len(x), bool)
    for k, (xi, yi, ri) in enumerate(zip(x, y, r)):
        reach = ri + probe + h
        a, b = _window(gx, xi, reach), _window(gy, yi, reach)
        near = ((gx[a, None] - xi) ** 2 + (gy[None, b] - yi) ** 2) <= reach * reach
        out[k] = not (near & outside[a, b]).any()
    return out


def _window(g, c, reach):
    """The slice of the grid ``g`` within ``reach`` of ``c``."""
    return slice(max(int(np.searchsorted(g, c - reach)), 0), int(np.searchsorted(g, c + reach, side="right")))


@njit(cache=True, error_model="numpy", inline="always")
def pebble_motion(cx, cy, vx, vy, w, cs, sn, ox, oy):
    """Position and velocity of the pebble at (ox, oy) in the frame of a clump at (cx, cy)
    moving at (vx, vy) with spin w, turned by (cos, sin) = (cs, sn) (the GPU batch uses it
    too)."""
    rx = cs * ox - sn * oy
    ry = sn * ox + cs * oy
    return cx + rx, cy + ry, vx - w * ry, vy + w * rx


@njit(cache=True, error_model="numpy", inline="always")
def _place(i, kin, balls, clumps, last, cs, sn):
    """Pebble i on its clump's rigid motion; the clump's rotation (cos, sin) = (cs, sn) is
    computed again only if it is not the ``last`` one's (a clump's pebbles mostly follow
    each other). Returns (its clump, cs, sn)."""
    c = balls.clump[i]
    if c != last:
        cs = math.cos(clumps.theta[c])
        sn = math.sin(clumps.theta[c])
    kin[i, 0], kin[i, 1], kin[i, 2], kin[i, 3] = pebble_motion(
        clumps.pos[c, 0], clumps.pos[c, 1], clumps.vel[c, 0], clumps.vel[c, 1], clumps.omega[c],
        cs, sn, balls.offset[i, 0], balls.offset[i, 1])
    kin[i, 4] = clumps.omega[c]
    return c, cs, sn


@njit(**NO_NRT)
def place_pebbles(prm, kin, fa, balls, clumps, pebbles, check, d1, d2, near_wall):
    """Position/velocity of the ``pebbles`` (live ball ids, ascending) from the rigid
    motion of their clump; with ``check``, in the same pass, each one's Verlet-list check
    and force reset (integrate.moved: external load only, the clump carries the weight).
    Returns (a pebble may have tripped a guard: ``integrate.guards`` says which, top-2
    squared displacements, wall flag)."""
    x0, y0, x1, y1 = prm[P.XMIN], prm[P.YMIN], prm[P.XMAX], prm[P.YMAX]
    vmax2 = prm[P.VMAX] * prm[P.VMAX]
    cx, cy, wt = prm[P.SHIFT_X], prm[P.SHIFT_Y], prm[P.WALL_TRAVEL]
    suspect = False
    last, cs, sn = -1, 1.0, 0.0
    for i in pebbles:
        last, cs, sn = _place(i, kin, balls, clumps, last, cs, sn)
        suspect |= not in_domain(kin, i, x0, y0, x1, y1, vmax2)
        if check:
            d1, d2, near_wall = moved(i, kin, fa, balls, cx, cy, wt, 0.0, 0.0, d1, d2, near_wall)
    return suspect, d1, d2, near_wall


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
