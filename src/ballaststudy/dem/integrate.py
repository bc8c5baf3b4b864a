"""Velocity Verlet (LAMMPS order: half kick, drift | forces | half kick), PFC local
damping, guards, critical timestep and density scaling. The per-ball halves are inline
helpers shared by the two halves of the step and the guards.

Velocity-dependent forces (dashpots, local damping) see the half-step velocity, as in
both LAMMPS's velocity Verlet and PFC's central-difference cycle.
Local damping (PFC): F_d = -alpha*|F|*sign(v) per degree of freedom, applied in the
second half kick; the stored ``force`` is the net force including it.
"""
import math

import numba
import numpy as np
from numba import njit

from . import params as P
from .jit import NO_NRT
from .neighbours import seg_closest
from .submodels import coefficient_row, contact_stiffness


@njit(cache=True, error_model="numpy", inline="always")
def moved(i, kin, fa, balls, cx, cy, wt, wx, wy, d1, d2, near_wall):
    """Verlet-list check of ball i after its drift and the force reset for the next
    forces: weight (wx, wy; zero for pebbles, whose clump carries it) + external load.
    Returns the updated (top-2 squared |dx - c|, wall flag)."""
    dx = kin[i, 0] - balls.pos0[i, 0]
    dy = kin[i, 1] - balls.pos0[i, 1]
    rx = dx - cx
    ry = dy - cy
    dd = rx * rx + ry * ry
    if dd > d2:
        if dd > d1:
            d2 = d1
            d1 = dd
        else:
            d2 = dd
    lim = balls.clear[i] - wt
    if lim <= 0.0 or dx * dx + dy * dy >= lim * lim:
        near_wall = True
    fa[i, 0] = wx + balls.fext[i, 0]
    fa[i, 1] = wy + balls.fext[i, 1]
    fa[i, 2] = 0.0
    return d1, d2, near_wall


@njit(cache=True, error_model="numpy", inline="always")
def _half_kick(i, kin, fa, balls, h):
    """v += h F/m per degree of freedom of ball i, except the velocity-held ones."""
    f = balls.fix[i]
    if not (f & 1):
        kin[i, 2] += h * fa[i, 0] * kin[i, 6]
    if not (f & 2):
        kin[i, 3] += h * fa[i, 1] * kin[i, 6]
    if not (f & 4):
        kin[i, 4] += h * fa[i, 2] * balls.iinv[i]


@njit(cache=True, error_model="numpy", inline="always")
def kick_drift(i, kin, fa, balls, h, dt):
    """First half of a step for free ball i: half kick, drift."""
    _half_kick(i, kin, fa, balls, h)
    kin[i, 0] += dt * kin[i, 2]
    kin[i, 1] += dt * kin[i, 3]


@njit(cache=True, error_model="numpy", inline="always")
def damp_kick(i, kin, fa, balls, h, dt):
    """Second half of a step for free ball i: PFC local damping of its net force (not on
    velocity-held dofs; ``fa`` keeps the damped force), half kick. Returns the work done
    by the damping [J]."""
    f = balls.fix[i]
    alpha = balls.damp[i]
    el = 0.0
    if alpha > 0.0:
        if not (f & 1):
            fx = locally_damped(fa[i, 0], kin[i, 2], alpha)
            el -= (fx - fa[i, 0]) * kin[i, 2] * dt
            fa[i, 0] = fx
        if not (f & 2):
            fy = locally_damped(fa[i, 1], kin[i, 3], alpha)
            el -= (fy - fa[i, 1]) * kin[i, 3] * dt
            fa[i, 1] = fy
        if not (f & 4):
            mz = locally_damped(fa[i, 2], kin[i, 4], alpha)
            el -= (mz - fa[i, 2]) * kin[i, 4] * dt
            fa[i, 2] = mz
    _half_kick(i, kin, fa, balls, h)
    return el


@njit(cache=True, error_model="numpy", inline="always")
def in_domain(kin, i, x0, y0, x1, y1, vmax2):
    """Guard pre-check of ball i, branch free; NaN fails every comparison."""
    x = kin[i, 0]
    y = kin[i, 1]
    v2 = kin[i, 2] * kin[i, 2] + kin[i, 3] * kin[i, 3]
    return ((x >= x0) & (x <= x1) & (y >= y0) & (y <= y1) & (v2 <= vmax2)
            & (abs(kin[i, 4]) < 1e300))


@njit(cache=True, error_model="numpy", inline="always")
def _first_ball(i, kin, fa, balls, h, dt, gx, gy, cx, cy, wt, d1, d2, near_wall, sx, sy):
    """first_half for free ball i."""
    kick_drift(i, kin, fa, balls, h, dt)
    sx += kin[i, 0] - balls.pos0[i, 0]
    sy += kin[i, 1] - balls.pos0[i, 1]
    m = balls.mass[i]
    d1, d2, near_wall = moved(i, kin, fa, balls, cx, cy, wt, m * gx, m * gy, d1, d2, near_wall)
    return d1, d2, near_wall, sx, sy


@njit(**NO_NRT)
def first_half(prm, kin, fa, balls, clumps, free, dense):
    """One pass per free ball (``free``: the live balls of no clump, ascending; ``dense``:
    most slots are, and a scan of every slot is then faster than the list: 7 % of a
    bonded box step) over its packed row ``kin`` = (x, y, vx, vy, omega, R, 1/m,
    material) and force row ``fa`` = (fx, fy, mz): half kick, drift, the displacement
    since the last neighbour build, force reset to weight + external load. Then half kick
    + drift of clumps.

    Verlet-list validity (exact, by the triangle inequality): a pair not listed had a
    gap > skin, and |dx_i - dx_j| <= |dx_i - c| + |dx_j - c| for ANY common vector c;
    c = the mean displacement of the previous step, so a bed falling as a whole does not
    force rebuilds. A ball may reach an unlisted wall segment only after moving
    clear[i] - wall travel. Returns (top-2 squared |dx - c|, wall flag, sum dx, sum dy, n)."""
    dt = prm[P.DT]
    gx = prm[P.GX]
    gy = prm[P.GY]
    cx = prm[P.SHIFT_X]
    cy = prm[P.SHIFT_Y]
    wt = prm[P.WALL_TRAVEL]
    h = 0.5 * dt
    d1 = 0.0
    d2 = 0.0
    near_wall = False
    sx = 0.0
    sy = 0.0
    if dense:
        for i in range(kin.shape[0]):
            if balls.clump[i] < 0 and balls.alive[i]:
                d1, d2, near_wall, sx, sy = _first_ball(i, kin, fa, balls, h, dt, gx, gy, cx, cy, wt,
                                                        d1, d2, near_wall, sx, sy)
    else:
        for i in free:
            d1, d2, near_wall, sx, sy = _first_ball(i, kin, fa, balls, h, dt, gx, gy, cx, cy, wt,
                                                    d1, d2, near_wall, sx, sy)
    clumps_kick_drift(clumps, h, dt)
    return d1, d2, near_wall, sx, sy, free.shape[0]


@njit(**NO_NRT)
def clumps_kick_drift(clumps, h, dt):
    """First half of a step for the clumps (held ones keep their velocity)."""
    for c in range(clumps.pos.shape[0]):
        if not clumps.held[c]:
            clumps.vel[c, 0] += h * clumps.force[c, 0] / clumps.imass[c]
            clumps.vel[c, 1] += h * clumps.force[c, 1] / clumps.imass[c]
            clumps.omega[c] += h * clumps.moment[c] / clumps.iinertia[c]
        clumps.pos[c, 0] += dt * clumps.vel[c, 0]
        clumps.pos[c, 1] += dt * clumps.vel[c, 1]
        clumps.theta[c] += dt * clumps.omega[c]


@njit(cache=True, error_model="numpy")
def reset_forces(gx, gy, mass, fext, force, moment, clump, alive):
    """Forces = weight + external load (pebbles: load only). Used before the first step."""
    for i in range(mass.shape[0]):
        if alive[i] and clump[i] < 0:
            force[i, 0] = mass[i] * gx + fext[i, 0]
            force[i, 1] = mass[i] * gy + fext[i, 1]
        elif alive[i]:
            force[i, 0] = fext[i, 0]
            force[i, 1] = fext[i, 1]
        else:
            force[i, 0] = 0.0
            force[i, 1] = 0.0
        moment[i] = 0.0


@njit(cache=True, error_model="numpy", inline="always")
def locally_damped(f, v, alpha):
    """PFC local damping: F - alpha |F| sign(v)."""
    if v > 0.0:
        return f - alpha * abs(f)
    if v < 0.0:
        return f + alpha * abs(f)
    return f


@njit(**NO_NRT)
def second_half(prm, kin, fa, balls, eacc, free, dense):
    """Local damping + half kick of every free ball (``free``, ``dense``: as first_half's);
    returns True if a ball may have tripped a guard (then ``guards`` says which)."""
    dt = prm[P.DT]
    h = 0.5 * dt
    x0 = prm[P.XMIN]
    y0 = prm[P.YMIN]
    x1 = prm[P.XMAX]
    y1 = prm[P.YMAX]
    vmax2 = prm[P.VMAX] * prm[P.VMAX]
    el = 0.0
    suspect = False
    if dense:
        for i in range(kin.shape[0]):
            if balls.alive[i] and balls.clump[i] < 0:
                el += damp_kick(i, kin, fa, balls, h, dt)
                suspect |= not in_domain(kin, i, x0, y0, x1, y1, vmax2)
    else:
        for i in free:
            el += damp_kick(i, kin, fa, balls, h, dt)
            suspect |= not in_domain(kin, i, x0, y0, x1, y1, vmax2)
    eacc[P.E_LOCAL] += el
    return suspect


@njit(**NO_NRT)
def clumps_damp_kick(clumps, h, dt):
    """Second half of a step for the clumps: local damping + half kick. Returns the
    damping work [J]."""
    cvel = clumps.vel
    comega = clumps.omega
    cforce = clumps.force
    cmoment = clumps.moment
    el = 0.0
    for c in range(cvel.shape[0]):
        if clumps.held[c]:
            continue
        alpha = clumps.damp[c]
        if alpha > 0.0:
            fx = locally_damped(cforce[c, 0], cvel[c, 0], alpha)
            fy = locally_damped(cforce[c, 1], cvel[c, 1], alpha)
            mz = locally_damped(cmoment[c], comega[c], alpha)
            el -= ((fx - cforce[c, 0]) * cvel[c, 0] + (fy - cforce[c, 1]) * cvel[c, 1]
                   + (mz - cmoment[c]) * comega[c]) * dt
            cforce[c, 0] = fx
            cforce[c, 1] = fy
            cmoment[c] = mz
        cvel[c, 0] += h * cforce[c, 0] / clumps.imass[c]
        cvel[c, 1] += h * cforce[c, 1] / clumps.imass[c]
        comega[c] += h * cmoment[c] / clumps.iinertia[c]
    return el


@njit(cache=True, error_model="numpy")
def guards(prm, kin, alive, err):
    """NaN/Inf, runaway speed, ball outside the domain -> status code (params.py); the
    offending ball id and value go to err. One cheap pass: the slow path only on failure."""
    vmax2 = prm[P.VMAX] ** 2
    x0 = prm[P.XMIN]
    x1 = prm[P.XMAX]
    y0 = prm[P.YMIN]
    y1 = prm[P.YMAX]
    bad = -1
    for i in range(kin.shape[0]):
        if alive[i] and not in_domain(kin, i, x0, y0, x1, y1, vmax2):
            bad = i
            break
    if bad < 0:
        return P.OK
    i = bad
    s = kin[i, 0] + kin[i, 1] + kin[i, 2] + kin[i, 3] + kin[i, 4]
    if not math.isfinite(s):
        err[0] = i
        err[1] = s
        return P.NAN_FOUND
    v2 = kin[i, 2] ** 2 + kin[i, 3] ** 2
    if v2 > vmax2:
        err[0] = i
        err[1] = math.sqrt(v2)
        return P.RUNAWAY
    err[0] = i
    err[1] = kin[i, 0] if (kin[i, 0] < x0 or kin[i, 0] > x1) else kin[i, 1]
    return P.LEFT_DOMAIN


@njit(cache=True, error_model="numpy")
def _within_skin(pos, rad, i, j, skin):
    """The Verlet list's test (neighbours.build_pairs) at the build positions ``pos``:
    closer than r_i + r_j + skin."""
    dx = pos[j, 0] - pos[i, 0]
    dy = pos[j, 1] - pos[i, 1]
    cut = rad[i] + rad[j] + skin
    return dx * dx + dy * dy < cut * cut


@njit(cache=True, error_model="numpy")
def _add_pair_springs(law, coef, rad, mat, t, i, j, ktr, krot):
    """A ball-ball contact's springs into k_tr and k_rot of both balls."""
    kn, ks, kr = contact_stiffness(law, coefficient_row(coef, mat[i], mat[j]), rad[i], rad[j], t)
    ktr[i] += kn + ks
    ktr[j] += kn + ks
    krot[i] += ks * rad[i] ** 2 + kr
    krot[j] += ks * rad[j] ** 2 + kr


@njit(cache=True, error_model="numpy")
def ball_springs(law, run, balls, pr, wp, wmat, bonds):
    """(k_tr, k_rot) of every ball: its springs over every pair of the Verlet lists
    (touching or about to touch: conservative until the next rebuild; the flat-jointed
    pairs the list leaves out count as if in it) and bonds; k_tr sums k_n + k_s, k_rot
    sums k_s R^2 + k_r (the law's stiffnesses). A clump's pebbles are the clump's business
    (clump_springs): what touches only pebbles is skipped, so their rows are partial."""
    prm = run.prm
    rad = balls.rad
    mat = balls.mat
    clump = balls.clump
    n = rad.shape[0]
    t = prm[P.THICK]
    ktr = np.zeros(n)
    krot = np.zeros(n)
    for p in range(pr.n[0]):
        if clump[pr.i[p]] < 0 or clump[pr.j[p]] < 0:
            _add_pair_springs(law, run.coef, rad, mat, t, pr.i[p], pr.j[p], ktr, krot)
    for q in range(wp.n[0]):
        i = wp.i[q]
        if clump[i] >= 0:
            continue
        r = rad[i]
        kn, ks, kr = contact_stiffness(law, coefficient_row(run.coef, wmat[wp.s[q]], mat[i]),
                                       0.0, r, t)
        ktr[i] += kn + ks
        krot[i] += ks * r ** 2 + kr
    skin = prm[P.SKIN]
    for b in range(bonds.i.shape[0]):
        if not bonds.active[b]:
            continue
        i = bonds.i[b]
        j = bonds.j[b]
        if clump[i] >= 0 and clump[j] >= 0:
            continue
        if _within_skin(balls.pos0, rad, i, j, skin):
            # a pair the Verlet list leaves out for its flat joint (neighbours.py): its
            # contact springs count as in the list, ready for when the joint goes
            _add_pair_springs(law, run.coef, rad, mat, t, i, j, ktr, krot)
        a = 2.0 * bonds.rbar[b] * t
        kn = bonds.kn[b] * a
        ks = bonds.ks[b] * a
        kb = bonds.kn[b] * t * (2.0 * bonds.rbar[b]) ** 3 / 12.0
        for i in (bonds.i[b], bonds.j[b]):
            ktr[i] += kn + ks
            krot[i] += kb + ks * rad[i] ** 2
    return ktr, krot


@njit(cache=True, error_model="numpy", inline="always")
def _add_clump_spring(balls, clumps, i, nx, ny, kn, ks, kr, ctr, crot):
    """One contact of pebble i (unit normal (nx, ny) out of it) into its clump's k_tr and
    k_rot. A turn of the clump about its centre of mass moves the contact point d = r_i +
    R_i n (r_i: the pebble's centre from the clump's) by d x dtheta: across the normal
    spring by cross(d, n) and along the shear spring by d . n, so k_rot gains
    k_n cross(r_i, n)^2 + k_s (r_i . n + R_i)^2 + k_r (for r_i = 0 the ball's k_s R^2 + k_r)."""
    c = balls.clump[i]
    rx = balls.pos[i, 0] - clumps.pos[c, 0]
    ry = balls.pos[i, 1] - clumps.pos[c, 1]
    cr = rx * ny - ry * nx
    dn = rx * nx + ry * ny + balls.rad[i]
    ctr[c] += kn + ks
    crot[c] += kn * cr * cr + ks * dn * dn + kr


@njit(cache=True, error_model="numpy")
def clump_springs(law, run, balls, clumps, pr, wp, walls, bonds):
    """(k_tr, k_rot) of every clump over its pebbles' pairs in the Verlet lists (touching
    or about to touch, at their geometry now: the ball rule's convention): k_tr sums k_n +
    k_s, k_rot sums each contact's stiffness against a turn about the centre of mass
    (_add_clump_spring). One pebble's springs against the whole clump's mass (the rule
    before) overestimated the clump's dt_crit. A flat joint left between two fragments
    (partly broken in the assembly: make_clumps keeps it) counts as in ball_springs, its
    bending stiffness with the rolling one."""
    prm = run.prm
    rad = balls.rad
    mat = balls.mat
    pos = balls.pos
    t = prm[P.THICK]
    nc = clumps.pos.shape[0]
    ctr = np.zeros(nc)
    crot = np.zeros(nc)
    for p in range(pr.n[0]):
        i = pr.i[p]
        j = pr.j[p]
        if balls.clump[i] < 0 and balls.clump[j] < 0:
            continue
        kn, ks, kr = contact_stiffness(law, coefficient_row(run.coef, mat[i], mat[j]),
                                       rad[i], rad[j], t)
        dx = pos[j, 0] - pos[i, 0]
        dy = pos[j, 1] - pos[i, 1]
        d = math.sqrt(dx * dx + dy * dy)
        if d == 0.0:
            continue
        if balls.clump[i] >= 0:
            _add_clump_spring(balls, clumps, i, dx / d, dy / d, kn, ks, kr, ctr, crot)
        if balls.clump[j] >= 0:
            _add_clump_spring(balls, clumps, j, -dx / d, -dy / d, kn, ks, kr, ctr, crot)
    skin = prm[P.SKIN]
    for b in range(bonds.i.shape[0]):      # a joint left between two fragments (assembly)
        i = bonds.i[b]
        j = bonds.j[b]
        if not bonds.active[b] or (balls.clump[i] < 0 and balls.clump[j] < 0):
            continue
        dx = pos[j, 0] - pos[i, 0]
        dy = pos[j, 1] - pos[i, 1]
        d = math.sqrt(dx * dx + dy * dy)
        if d == 0.0:
            continue
        a = 2.0 * bonds.rbar[b] * t
        kn = bonds.kn[b] * a
        ks = bonds.ks[b] * a
        kb = bonds.kn[b] * t * (2.0 * bonds.rbar[b]) ** 3 / 12.0
        if _within_skin(balls.pos0, rad, i, j, skin):     # as ball_springs: its contact too
            cn, cs, cr = contact_stiffness(law, coefficient_row(run.coef, mat[i], mat[j]),
                                           rad[i], rad[j], t)
            kn += cn
            ks += cs
            kb += cr
        if balls.clump[i] >= 0:
            _add_clump_spring(balls, clumps, i, dx / d, dy / d, kn, ks, kb, ctr, crot)
        if balls.clump[j] >= 0:
            _add_clump_spring(balls, clumps, j, -dx / d, -dy / d, kn, ks, kb, ctr, crot)
    seg = walls.seg
    for q in range(wp.n[0]):
        i = wp.i[q]
        if balls.clump[i] < 0:
            continue
        s = wp.s[q]
        kn, ks, kr = contact_stiffness(law, coefficient_row(run.coef, walls.mat[s], mat[i]),
                                       0.0, rad[i], t)
        cx, cy, _ = seg_closest(pos[i, 0], pos[i, 1], seg[s, 0], seg[s, 1], seg[s, 2], seg[s, 3])
        dx = cx - pos[i, 0]
        dy = cy - pos[i, 1]
        d = math.sqrt(dx * dx + dy * dy)
        if d == 0.0:
            continue
        _add_clump_spring(balls, clumps, i, dx / d, dy / d, kn, ks, kr, ctr, crot)
    return ctr, crot


@njit(cache=True, error_model="numpy")
def critical_dt(law, run, balls, clumps, pr, wp, walls, bonds):
    """dt_crit = min(sqrt(m/k_tr), sqrt(I/k_rot)) over the free balls (ball_springs) and
    the free clumps (clump_springs, about the centre of mass; held clumps move as told).
    With density scaling, inertial masses (and moments) of balls and free clumps are
    raised to k_tr*(dt/f)^2 instead (never lowered below the real ones: PFC scales both
    ways; we only add inertia); a pebble's dashpot sees its clump's inertial mass."""
    numba.literally(law)
    prm = run.prm
    n = balls.rad.shape[0]
    ktr, krot = ball_springs(law, run, balls, pr, wp, walls.mat, bonds)
    f = prm[P.DT_SAFETY]
    s2 = (prm[P.DT] / f) ** 2
    scaled = prm[P.DSCALE] > 0.0
    dtc = 1.0e30
    for i in range(n):
        if not balls.alive[i] or ktr[i] == 0.0 or balls.clump[i] >= 0:
            continue
        if scaled:
            balls.minv[i] = 1.0 / max(balls.mass[i], ktr[i] * s2)
            balls.iinv[i] = 1.0 / max(balls.inertia[i], krot[i] * s2)
        dtc = min(dtc, math.sqrt(1.0 / (balls.minv[i] * ktr[i])))
        if krot[i] > 0.0:
            dtc = min(dtc, math.sqrt(1.0 / (balls.iinv[i] * krot[i])))
    if clumps.pos.shape[0] == 0:
        return dtc
    ctr, crot = clump_springs(law, run, balls, clumps, pr, wp, walls, bonds)
    for c in range(clumps.pos.shape[0]):
        if clumps.held[c] or ctr[c] == 0.0:
            continue
        if scaled:
            clumps.imass[c] = max(clumps.mass[c], ctr[c] * s2)
            clumps.iinertia[c] = max(clumps.inertia[c], crot[c] * s2)
        dtc = min(dtc, math.sqrt(clumps.imass[c] / ctr[c]))
        dtc = min(dtc, math.sqrt(clumps.iinertia[c] / crot[c]))
    if scaled:
        for i in range(n):
            c = balls.clump[i]
            if c >= 0:
                balls.minv[i] = 1.0 / clumps.imass[c]
    return dtc
