"""Ball-ball contacts: the contact frame of a Verlet-list entry, its force from the law
(submodels.contact_force, the one dispatch point), the loop that scatters it onto both balls.

Convention: n points from ball i to ball j, t = z x n; forces are those ON j.
"""
import math

import numba
from numba import njit

from . import params as P
from .jit import LOOP
from .submodels import WIDTH, cached_row, coefficient_row, contact_energy, contact_force, lf


@njit(cache=True, error_model="numpy")
def pack_kinematics(balls, kin):
    """kin[i] = (x, y, vx, vy, omega, R, 1/m, material): one cache line per ball for the
    pair loop, whose j accesses are scattered (measured ~20 % faster than 7 arrays)."""
    for i in range(balls.pos.shape[0]):
        kin[i, 0] = balls.pos[i, 0]
        kin[i, 1] = balls.pos[i, 1]
        kin[i, 2] = balls.vel[i, 0]
        kin[i, 3] = balls.vel[i, 1]
        kin[i, 4] = balls.omega[i]
        kin[i, 5] = balls.rad[i]
        kin[i, 6] = balls.minv[i]
        kin[i, 7] = balls.mat[i]


@njit(cache=True, error_model="numpy", inline="always")
def contact_opened(hist, fn, fs, p, width):
    """The contact of list entry p is open: its history restarts at zero (the persistent
    state columns after ``width`` are kept)."""
    for c in range(width):
        hist[p, c] = 0.0
    fn[p] = 0.0
    fs[p] = 0.0


@njit(cache=True, error_model="numpy", inline="always")
def pair_contact(law, c, thick, dt, kin, i, j, hist, p_fn, p_fs, p_lap0, p):
    """Contact of list entry p between balls i < j (coefficient row ``c`` of their
    materials): frame, force from the law on the overlap beyond ``p_lap0[p]`` (two pieces
    of one split stone: Pairs), which follows the overlap down as they part, opening.
    Returns (touching, fx, fy on j, moment on i, moment on j, dashpot, slip, rolling work)."""
    dx = kin[j, 0] - kin[i, 0]
    dy = kin[j, 1] - kin[i, 1]
    d2 = dx * dx + dy * dy
    ri = kin[i, 5]
    rj = kin[j, 5]
    lap0 = p_lap0[p]
    if lap0 > 0.0:
        lap0 = max(0.0, min(lap0, ri + rj - math.sqrt(d2)))
        p_lap0[p] = lap0
    rs = ri + rj - lap0
    if d2 >= rs * rs:
        contact_opened(hist, p_fn, p_fs, p, lf(law, WIDTH))
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    d = math.sqrt(d2)
    rinv = 1.0 / d
    nx = dx * rinv
    ny = dy * rinv
    fx, fy, mi, mj, fn, ft, e1, e2, e3 = contact_force(
        law, c, nx, ny, rs - d,
        kin[j, 2] - kin[i, 2], kin[j, 3] - kin[i, 3], kin[i, 4], kin[j, 4], ri, rj,
        kin[i, 6], kin[j, 6], thick, dt, hist, p)
    p_fn[p] = fn
    p_fs[p] = ft
    return True, fx, fy, mi, mj, e1, e2, e3


@njit(cache=True, error_model="numpy", inline="always")
def book_contact_work(eacc, dashpot, slip, rolling):
    """Add a contact loop's dissipated work to the energy accumulators [J]."""
    eacc[P.E_DASHPOT] += dashpot
    eacc[P.E_FRICTION] += slip
    eacc[P.E_ROLLING] += rolling


@njit(**LOOP)
def pair_forces(law, run, kin, fa, pr, b_active):
    """Add ball-ball contact forces of the Verlet list ``pr`` to fa = (fx, fy, mz) rows
    (kin: see ``pack_kinematics``); pairs joined by an active flat joint are skipped.
    ``law``: the packed contact law, compiled as a constant (submodels.py)."""
    numba.literally(law)
    coef = run.coef
    dt = run.prm[P.DT]
    thick = run.prm[P.THICK]
    # arrays out of their containers once (no per-pair attribute lookups)
    p_i, p_j, hist, p_bond, p_fn, p_fs, p_lap0 = pr.i, pr.j, pr.hist, pr.bond, pr.fn, pr.fs, pr.lap0
    bonds = b_active.shape[0] > 0
    c, ma, mb = coefficient_row(coef, 0, 0), -1, -1    # reloaded when the materials change
    ed = 0.0
    ef = 0.0
    er = 0.0
    for p in range(pr.n[0]):
        if bonds:
            b = p_bond[p]
            if b >= 0 and b_active[b]:
                continue     # a flat joint replaces the contact (lists from older checkpoints)
        i = p_i[p]
        j = p_j[p]
        c, ma, mb = cached_row(coef, c, ma, mb, int(kin[i, 7]), int(kin[j, 7]))
        touch, fx, fy, mi, mj, e1, e2, e3 = pair_contact(law, c, thick, dt, kin, i, j, hist,
                                                         p_fn, p_fs, p_lap0, p)
        if touch:
            fa[j, 0] += fx
            fa[j, 1] += fy
            fa[i, 0] -= fx
            fa[i, 1] -= fy
            fa[i, 2] += mi
            fa[j, 2] += mj
            ed += e1
            ef += e2
            er += e3
    book_contact_work(run.eacc, ed, ef, er)


@njit(cache=True, error_model="numpy")
def pair_elastic_energy(law, run, balls, pr, b_active):
    """Strain energy in the springs of touching ball-ball contacts [J] (flat-jointed
    pairs excluded: their energy is the bond's)."""
    numba.literally(law)
    e = 0.0
    for p in range(pr.n[0]):
        i = pr.i[p]
        j = pr.j[p]
        b = pr.bond[p]
        if b >= 0 and b_active[b]:
            continue
        ri = balls.rad[i]
        rj = balls.rad[j]
        rs = ri + rj - pr.lap0[p]
        d = math.sqrt((balls.pos[j, 0] - balls.pos[i, 0]) ** 2
                      + (balls.pos[j, 1] - balls.pos[i, 1]) ** 2)
        if d < rs:
            e += contact_energy(law, coefficient_row(run.coef, balls.mat[i], balls.mat[j]),
                                rs - d, ri, rj,
                                run.prm[P.THICK], pr.hist, p)
    return e
