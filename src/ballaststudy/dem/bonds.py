"""Flat-joint bonds in 2D (Potyondy 2012; thesis 2.2.2.4 and Table 4.2).

The interface is a segment of length 2*Rbar normal to the line of centres, centred
midway in the gap between the two surfaces, split into N equal elements. Along the
interface (coordinate s on t = z x n) the gap is g(s) = g_c - theta*s, with
g_c = d - d0 the opening at the centre since installation and theta the relative
rotation of ball j w.r.t. ball i. Per unit length the interface pulls/pushes with
k_n*t*g(s) (tension positive), so an element's normal force and moment follow from the
integrals of g and g*s over the element (over its compressed part only once broken).
That single integral gives F_n^e = k_n A_e g(s_e) and M = sum(F_n^e s_e) - k_n I theta
as in the physics spec, and the exact compression-only response of broken elements.
"""
import math

import numpy as np
from numba import njit

from . import params as P
from .jit import LOOP, NO_NRT
from .neighbours import build_pairs

MODE_TENSION = 1
MODE_SHEAR = 2


@njit(cache=True, error_model="numpy", inline="always")
def _loaded_part(gc, th, a, b, compressed_only):
    """The part of [a, b] that carries load: all of it, or where g(s) = gc - th*s < 0 if
    ``compressed_only``. Returns (a, b); empty when b <= a."""
    if compressed_only:
        if th == 0.0:
            if gc >= 0.0:
                return a, a
        else:
            root = gc / th
            if th > 0.0:
                a = max(a, root)
            else:
                b = min(b, root)
    return a, b


@njit(cache=True, error_model="numpy", inline="always")
def strip_integrals(gc, th, a, b, compressed_only):
    """Integrals of g(s) and g(s)*s over [a, b] (restricted to g < 0 if asked)."""
    a, b = _loaded_part(gc, th, a, b, compressed_only)
    if b <= a:
        return 0.0, 0.0
    i0 = gc * (b - a) - th * (b * b - a * a) / 2.0
    i1 = gc * (b * b - a * a) / 2.0 - th * (b * b * b - a * a * a) / 3.0
    return i0, i1


@njit(cache=True, error_model="numpy", inline="always")
def strip_energy(gc, th, a, b, compressed_only):
    """Integral of g(s)^2 over [a, b] (restricted to g < 0 if asked): strain energy."""
    a, b = _loaded_part(gc, th, a, b, compressed_only)
    if b <= a:
        return 0.0
    fb = gc * gc * b - gc * th * b * b + th * th * b ** 3 / 3.0
    fa = gc * gc * a - gc * th * a * a + th * th * a ** 3 / 3.0
    return fb - fa


# Per-bond scratch rows of the three passes of ``bond_forces`` (run_steps owns the
# array: ``bond_scratch``): the contact frame from the geometry pass, the element totals
# from the element pass.
G_D, G_NX, G_NY, G_VT, G_AI, T_FN, T_FS, T_MC = range(8)
SCRATCH_COLUMNS = 8


@njit(cache=True)
def bond_scratch(n_bonds):
    """Scratch of ``bond_forces``: per-bond rows, and a list of bonds for the full pass."""
    return np.empty((n_bonds, SCRATCH_COLUMNS)), np.empty(n_bonds, np.int32)


@njit(**LOOP)
def bond_forces(run, kin, balls, fa, bonds, log, scratch):
    """Flat-joint forces, element failure (logged) and interface removal, in three passes
    over the active bonds (geometry, elements, forces onto the balls): the rows ``g`` of
    ``scratch`` (``bond_scratch``) carry each bond's frame and totals between them.

    Why so (measured on the thesis-resolution box case, 1619 bonds): the fused loop was
    bound by the divider (a square root and six divisions per bond); one reciprocal per
    bond, the failure tests multiplied through by the element area instead of dividing
    (sigma >= sigma_c as F_n >= sigma_c A_e), and the split passes cut it from 31 to
    24 us per step. Each pass runs over the bond index itself: an indirect list of the
    active bonds was slower (every bond array then needs its own index arithmetic)."""
    g, full = scratch
    _bond_geometry(run.prm[P.DT], kin, balls.rad, bonds, g)
    n_full = _bond_elements(run, bonds, g, full)
    if n_full > 0:
        _bond_elements_in_full(run, kin, balls, bonds, log, g, full, n_full)
    _bond_scatter(bonds, g, fa)


@njit(cache=True, error_model="numpy", inline="always")
def joint_frame(xi, yi, vxi, vyi, wi, ri, xj, yj, vxj, vyj, wj, rj):
    """The frame of a joint between balls i and j: centre distance d, normal (nx, ny)
    from i to j, distance ai from the centre of i to the interface centre (midway in the
    gap) and the tangential velocity of j relative to i there (the GPU batch uses it too)."""
    dx = xj - xi
    dy = yj - yi
    d = math.sqrt(dx * dx + dy * dy)
    rinv = 1.0 / d
    nx = dx * rinv
    ny = dy * rinv
    tx = -ny
    ty = nx
    ai = ri + 0.5 * (d - ri - rj)     # centre -> interface centre
    aj = d - ai
    w = wi * ai + wj * aj
    return d, nx, ny, ai, (vxj - vxi - w * tx) * tx + (vyj - vyi - w * ty) * ty


@njit(**LOOP)
def _bond_geometry(dt, kin, rad, bonds, g):
    """The contact frame of every active bond:
    centre distance d, normal n (i -> j), tangential velocity of j relative to i at the
    interface centre, distance ai from the centre of i to it; advances theta."""
    b_i, b_j, b_active, theta = bonds.i, bonds.j, bonds.active, bonds.theta
    for b in range(b_i.shape[0]):
        if not b_active[b]:
            continue
        i = b_i[b]
        j = b_j[b]
        d, nx, ny, ai, vt = joint_frame(
            kin[i, 0], kin[i, 1], kin[i, 2], kin[i, 3], kin[i, 4], rad[i],
            kin[j, 0], kin[j, 1], kin[j, 2], kin[j, 3], kin[j, 4], rad[j])
        g[b, G_VT] = vt
        theta[b] += (kin[j, 4] - kin[i, 4]) * dt
        g[b, G_D] = d
        g[b, G_NX] = nx
        g[b, G_NY] = ny
        g[b, G_AI] = ai


@njit(**LOOP)
def _bond_elements(run, bonds, g, full):
    """Element forces of the active bonds whose elements are all intact and stay so (the
    lean path): their totals (F_n, F_s, moment) go to g[:, T_FN:]. The others (a broken
    element, a failure in this step) are listed in ``full`` (returns their count) for
    ``_bond_elements_in_full`` (failure, logging, interface removal),
    which takes them in bond order (so the log and the energy sums keep their order).
    Calls (to the rare paths) in the lean loop made it ~1.6x slower."""
    b_active, rbar, d0 = bonds.active, bonds.rbar, bonds.d0
    kn, ks, sigc, coh, tanphi = bonds.kn, bonds.ks, bonds.sigc, bonds.coh, bonds.tanphi
    theta, bmom, state, bfn, bfs = bonds.theta, bonds.moment, bonds.state, bonds.fn, bonds.fs
    dt = run.prm[P.DT]
    t = run.prm[P.THICK]
    ne = state.shape[1]
    inv_ne = 1.0 / ne
    n_full = 0
    for b in range(b_active.shape[0]):
        if not b_active[b]:
            continue
        th = theta[b]
        gc = g[b, G_D] - d0[b]
        le = 2.0 * rbar[b] * inv_ne
        ae = le * t
        knt = kn[b] * t
        dfs = ks[b] * ae * g[b, G_VT] * dt
        ftot_n = 0.0
        ftot_s = 0.0
        mc = 0.0
        handed_over = False
        for e in range(ne):
            a = -rbar[b] + e * le
            fs = bfs[b, e] - dfs
            i0, i1 = strip_integrals(gc, th, a, a + le, False)
            fn = knt * i0
            # broken, or sigma >= sigma_c (tension), or tau >= c - sigma tan(phi) (shear)
            handed_over |= ((state[b, e] == 0) | (fn >= sigc[b] * ae)
                            | (abs(fs) >= coh[b] * ae - fn * tanphi[b]))
            bfn[b, e] = fn
            bfs[b, e] = fs           # the full pass starts from this F_s too
            ftot_n += fn
            ftot_s += fs
            mc += knt * i1
        if handed_over:
            full[n_full] = b
            n_full += 1
            continue
        bmom[b] = mc
        g[b, T_FN] = ftot_n
        g[b, T_FS] = ftot_s
        g[b, T_MC] = mc
    return n_full


@njit(**LOOP)
def _bond_elements_in_full(run, kin, balls, bonds, log, g, full, n_full):
    """The ``n_full`` bonds the lean pass listed in ``full``: element by element with
    failure, the broken elements' response and interface removal."""
    b_active, rbar, d0, gi = bonds.active, bonds.rbar, bonds.d0, bonds.gi
    kn, ks, sigc, coh, tanphi, bmu = bonds.kn, bonds.ks, bonds.sigc, bonds.coh, bonds.tanphi, bonds.mu
    theta, bmom, state, bfn, bfs = bonds.theta, bonds.moment, bonds.state, bonds.fn, bonds.fs
    t = run.prm[P.THICK]
    ne = state.shape[1]
    inv_ne = 1.0 / ne
    for k in range(n_full):
        b = full[k]
        th = theta[b]
        gc = g[b, G_D] - d0[b]
        le = 2.0 * rbar[b] * inv_ne
        ae = le * t
        knt = kn[b] * t
        ftot_n = 0.0
        ftot_s = 0.0
        mc = 0.0
        nbonded = 0
        for e in range(ne):
            a = -rbar[b] + e * le
            fs = bfs[b, e]           # advanced by the lean pass
            if state[b, e]:
                i0, i1 = strip_integrals(gc, th, a, a + le, False)
                fn = knt * i0
                if fn >= sigc[b] * ae or abs(fs) >= coh[b] * ae - fn * tanphi[b]:
                    fn, fs, i1 = _element_breaks(run, kin, balls, bonds, log, g, b, e, gc, th,
                                                 a, le, fn, fs)
                else:
                    nbonded += 1
            else:
                fn, fs, i1 = broken_element(run.eacc, gc, th, a, le, fs, knt, ks[b] * ae,
                                             bmu[b], -1.0)
            bfn[b, e] = fn
            bfs[b, e] = fs
            ftot_n += fn
            ftot_s += fs
            mc += knt * i1
        if nbonded == 0 and gc - abs(th) * rbar[b] > gi[b]:
            b_active[b] = 0       # surfaces apart beyond the installation gap: remove
            run.cnt[2] = 1        # rebuild next step: the pair enters the contact list
            for e in range(ne):
                bfn[b, e] = 0.0
                bfs[b, e] = 0.0
            bmom[b] = 0.0
            continue
        bmom[b] = mc
        g[b, T_FN] = ftot_n
        g[b, T_FS] = ftot_s
        g[b, T_MC] = mc


@njit(**LOOP)
def broken_element(eacc, gc, th, a, le, fs, knt, ksa, mu, e_break):
    """A broken element (compression-only notional surfaces with Coulomb friction) over
    [a, a + le]: (F_n, F_s, integral of g s). ksa = k_s A_e. e_break >= 0: it broke in this
    step with that strain energy; what survives is subtracted (breakage work), else the
    friction work of sliding is booked."""
    i0, i1 = strip_integrals(gc, th, a, a + le, True)
    fn = knt * i0
    lim = mu * max(-fn, 0.0)
    if abs(fs) > lim:
        if e_break < 0.0:
            eacc[P.E_FRICTION] += lim * (abs(fs) - lim) / ksa
        fs = lim if fs > 0.0 else -lim
    if e_break >= 0.0:
        eacc[P.E_BREAKAGE] += e_break - (0.5 * knt * strip_energy(gc, th, a, a + le, True)
                                         + 0.5 * fs * fs / ksa)
    return fn, fs, i1


@njit(**LOOP)
def _element_breaks(run, kin, balls, bonds, log, g, b, e, gc, th, a, le, fn, fs):
    """Element e of bond b fails at (F_n, F_s): logged (mode, stress, place), state 0;
    returns its broken response (see broken_element)."""
    t = run.prm[P.THICK]
    ae = le * t
    knt = bonds.kn[b] * t
    ksa = bonds.ks[b] * ae
    mode = MODE_TENSION if fn >= bonds.sigc[b] * ae else MODE_SHEAR
    i = bonds.i[b]
    se = a + 0.5 * le
    _log_break(log, run.cnt[0], run.prm[P.TIME], b, e, i, bonds.j[b], balls.stone[i], mode,
               kin[i, 0] + g[b, G_AI] * g[b, G_NX] + se * -g[b, G_NY],
               kin[i, 1] + g[b, G_AI] * g[b, G_NY] + se * g[b, G_NX],
               (fn if mode == MODE_TENSION else abs(fs)) / ae)
    bonds.state[b, e] = 0
    # strain energy before the break; what survives is subtracted in broken_element
    e_break = 0.5 * knt * strip_energy(gc, th, a, a + le, False) + 0.5 * fs * fs / ksa
    return broken_element(run.eacc, gc, th, a, le, fs, knt, ksa, bonds.mu[b], e_break)


@njit(**NO_NRT)
def _log_break(log, step, time, b, e, i, j, stone, mode, x, y, stress):
    """One element failure into the breakage log (at the element centre x, y)."""
    k = log.n[0]
    log.step[k] = step
    log.time[k] = time
    log.bond[k] = b
    log.elem[k] = e
    log.i[k] = i
    log.j[k] = j
    log.stone[k] = stone
    log.mode[k] = mode
    log.x[k] = x
    log.y[k] = y
    log.stress[k] = stress
    log.n[0] = k + 1


@njit(**LOOP)
def _bond_scatter(bonds, g, fa):
    """The active bonds' forces and moments onto their balls, in bond order."""
    b_i, b_j, b_active = bonds.i, bonds.j, bonds.active
    for b in range(b_i.shape[0]):
        if not b_active[b]:
            continue
        i = b_i[b]
        j = b_j[b]
        nx = g[b, G_NX]
        ny = g[b, G_NY]
        tx = -ny
        ty = nx
        ftot_n = g[b, T_FN]
        ftot_s = g[b, T_FS]
        mc = g[b, T_MC]
        ai = g[b, G_AI]
        aj = g[b, G_D] - ai
        fx = -ftot_n * nx + ftot_s * tx          # force on j (tension pulls j to i)
        fy = -ftot_n * ny + ftot_s * ty
        fa[j, 0] += fx
        fa[j, 1] += fy
        fa[i, 0] -= fx
        fa[i, 1] -= fy
        fa[j, 2] += mc - aj * ftot_s
        fa[i, 2] += -mc - ai * ftot_s


@njit(cache=True, error_model="numpy")
def bond_energy(pos, bonds, thick):
    """Elastic energy stored in flat joints: int 0.5 k_n t g(s)^2 ds over loaded parts
    plus 0.5 F_s^2 / (k_s A_e) per element."""
    b_i, b_j, b_active, rbar, d0 = bonds.i, bonds.j, bonds.active, bonds.rbar, bonds.d0
    kn, ks, theta, state, bfs = bonds.kn, bonds.ks, bonds.theta, bonds.state, bonds.fs
    e_tot = 0.0
    ne = state.shape[1]
    for b in range(b_i.shape[0]):
        if not b_active[b]:
            continue
        i = b_i[b]
        j = b_j[b]
        d = math.sqrt((pos[j, 0] - pos[i, 0]) ** 2 + (pos[j, 1] - pos[i, 1]) ** 2)
        gc = d - d0[b]
        th = theta[b]
        le = 2.0 * rbar[b] / ne
        for e in range(ne):
            a = -rbar[b] + e * le
            e_tot += 0.5 * kn[b] * thick * strip_energy(gc, th, a, a + le, not state[b, e])
            e_tot += 0.5 * bfs[b, e] ** 2 / (ks[b] * le * thick)
    return e_tot


def find_bond_candidates(pos, rad, stone, alive, gap_factor):
    """Pairs (i<j) of live balls of one stone (stone >= 0) whose surface gap is below
    g_i = gap_factor * min(R_i, R_j) (Table 4.2: 0.4 * D_small / 2). O(N) via cells."""
    n = len(rad)
    if n < 2:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    skin = gap_factor * float(rad.max())
    lo = pos.min(axis=0) - 1.0
    hi = pos.max(axis=0) + 1.0
    cap = 8 * n + 16
    while True:
        oi = np.zeros(cap, np.int32)
        oj = np.zeros(cap, np.int32)
        cnt = build_pairs(pos, rad, alive, np.zeros(n, np.uint8), np.full(n, -1, np.int32), skin,
                          lo[0], lo[1], hi[0], hi[1], oi, oj)
        if cnt >= 0:
            break
        cap = -cnt
    oi, oj = oi[:cnt].astype(np.int64), oj[:cnt].astype(np.int64)
    d = np.hypot(*(pos[oj] - pos[oi]).T)
    gap = d - rad[oi] - rad[oj]
    keep = (stone[oi] == stone[oj]) & (stone[oi] >= 0) & (gap < gap_factor * np.minimum(rad[oi], rad[oj]))
    return oi[keep], oj[keep]
