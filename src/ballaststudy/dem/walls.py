"""Ball-segment contacts and kinematic wall motion.

The wall plays body i (infinite mass, velocity of the segment at the contact point),
the ball plays body j, so the same contact law applies (submodels.contact_force).
PFC ball-facet stiffness: A = 2 R t, L = R (physics spec), effective mass m_c = m_ball
(LAMMPS: m_eff = m_i).
"""
import math

import numba
from numba import njit

from . import params as P
from .contacts import book_contact_work, contact_opened
from .jit import LOOP, NO_NRT
from .neighbours import seg_closest
from .submodels import WIDTH, cached_row, coefficient_row, contact_energy, contact_force, lf


@njit(**NO_NRT)
def move_walls(seg, wvel, womega, centre, dt):
    """Rotate each segment about its centre by omega*dt, then translate by vel*dt.
    Returns the largest endpoint displacement (for the Verlet rebuild criterion)."""
    dmax = 0.0
    for s in range(seg.shape[0]):
        c = math.cos(womega[s] * dt)
        sn = math.sin(womega[s] * dt)
        for e in range(2):
            x = seg[s, 2 * e] - centre[s, 0]
            y = seg[s, 2 * e + 1] - centre[s, 1]
            nxp = centre[s, 0] + c * x - sn * y + wvel[s, 0] * dt
            nyp = centre[s, 1] + sn * x + c * y + wvel[s, 1] * dt
            d = math.sqrt((nxp - seg[s, 2 * e]) ** 2 + (nyp - seg[s, 2 * e + 1]) ** 2)
            dmax = max(dmax, d)
            seg[s, 2 * e] = nxp
            seg[s, 2 * e + 1] = nyp
        centre[s, 0] += wvel[s, 0] * dt
        centre[s, 1] += wvel[s, 1] * dt
    return dmax


@njit(cache=True, error_model="numpy")
def _joint_elsewhere(px, py, seg, link, s, u):
    """True if a contact at an endpoint of segment s is handled by its neighbour: a start
    joint always belongs to the previous segment; an end joint only while the ball is not
    over the interior of the next segment (then that one has the contact)."""
    if u <= 0.0 and link[s, 0] >= 0:
        return True
    if u >= 1.0 and link[s, 1] >= 0:
        q = link[s, 1]
        ex = seg[q, 2] - seg[q, 0]
        ey = seg[q, 3] - seg[q, 1]
        return (px - seg[q, 0]) * ex + (py - seg[q, 1]) * ey > 0.0
    return False


@njit(cache=True, error_model="numpy", inline="always")
def wall_contact_point(kin, i, seg, link, s):
    """Closest point (cx, cy) of segment s to ball i and the squared distance; d2 = inf if
    the contact belongs to a neighbour segment (see _joint_elsewhere)."""
    cx, cy, u = seg_closest(kin[i, 0], kin[i, 1], seg[s, 0], seg[s, 1], seg[s, 2], seg[s, 3])
    if _joint_elsewhere(kin[i, 0], kin[i, 1], seg, link, s, u):
        return cx, cy, math.inf
    return cx, cy, (kin[i, 0] - cx) ** 2 + (kin[i, 1] - cy) ** 2


@njit(cache=True, error_model="numpy", inline="always")
def wall_contact(law, c, thick, dt, kin, i, walls, s, hist, w_fn, w_fs, q):
    """Contact of wall-list entry q between ball i and segment s (coefficient row ``c`` of
    their materials): the segment is body i of
    the law (zero radius, infinite mass, its velocity at the contact point), the ball body
    j. Adds the reaction to the segment's force and moment. Returns (fx, fy, moment on the
    ball, dashpot, slip, rolling work, work of the wall on the ball); zeros if open."""
    cx, cy, d2 = wall_contact_point(kin, i, walls.seg, walls.link, s)
    r = kin[i, 5]
    if d2 >= r * r or d2 == 0.0:
        contact_opened(hist, w_fn, w_fs, q, lf(law, WIDTH))
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    d = math.sqrt(d2)
    nx = (kin[i, 0] - cx) / d
    ny = (kin[i, 1] - cy) / d
    centre = walls.centre
    wx = walls.vel[s, 0] - walls.omega[s] * (cy - centre[s, 1])
    wy = walls.vel[s, 1] + walls.omega[s] * (cx - centre[s, 0])
    fx, fy, mi, mj, fn, ft, e1, e2, e3 = contact_force(
        law, c, nx, ny, r - d, kin[i, 2] - wx,
        kin[i, 3] - wy, 0.0, kin[i, 4], 0.0, r, 0.0, kin[i, 6], thick, dt, hist, q)
    walls.force[s, 0] -= fx
    walls.force[s, 1] -= fy
    walls.moment[s] -= (cx - centre[s, 0]) * fy - (cy - centre[s, 1]) * fx
    w_fn[q] = fn
    w_fs[q] = ft
    return fx, fy, mj, e1, e2, e3, (fx * wx + fy * wy) * dt


@njit(**LOOP)
def wall_forces(law, run, kin, fa, walls, wp):
    """Add ball-segment forces to the balls; record force and moment on each segment."""
    numba.literally(law)
    coef = run.coef
    dt = run.prm[P.DT]
    thick = run.prm[P.THICK]
    w_i, w_s, hist, w_fn, w_fs = wp.i, wp.s, wp.hist, wp.fn, wp.fs
    for s in range(walls.seg.shape[0]):
        walls.force[s, 0] = 0.0
        walls.force[s, 1] = 0.0
        walls.moment[s] = 0.0
    c, ma, mb = coefficient_row(coef, 0, 0), -1, -1    # reloaded when the materials change
    ed = 0.0
    ef = 0.0
    er = 0.0
    ew = 0.0
    for q in range(wp.n[0]):
        i = w_i[q]
        s = w_s[q]
        c, ma, mb = cached_row(coef, c, ma, mb, walls.mat[s], int(kin[i, 7]))
        fx, fy, mj, e1, e2, e3, e4 = wall_contact(law, c, thick, dt, kin, i, walls, s, hist,
                                                  w_fn, w_fs, q)
        fa[i, 0] += fx
        fa[i, 1] += fy
        fa[i, 2] += mj
        ed += e1
        ef += e2
        er += e3
        ew += e4
    book_contact_work(run.eacc, ed, ef, er)
    run.eacc[P.E_WALLS] += ew


@njit(cache=True, error_model="numpy")
def wall_elastic_energy(law, run, kin, walls, wp):
    """Strain energy in the springs of touching ball-segment contacts [J]."""
    numba.literally(law)
    e = 0.0
    for q in range(wp.n[0]):
        i = wp.i[q]
        s = wp.s[q]
        cx, cy, d2 = wall_contact_point(kin, i, walls.seg, walls.link, s)
        r = kin[i, 5]
        if d2 < r * r and d2 > 0.0:
            e += contact_energy(law, coefficient_row(run.coef, walls.mat[s], int(kin[i, 7])),
                                r - math.sqrt(d2), 0.0, r, run.prm[P.THICK], wp.hist, q)
    return e
