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
from .jit import NO_NRT

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
def _strip(gc, th, a, b, compressed_only):
    """Integrals of g(s) and g(s)*s over [a, b] (restricted to g < 0 if asked)."""
    a, b = _loaded_part(gc, th, a, b, compressed_only)
    if b <= a:
        return 0.0, 0.0
    i0 = gc * (b - a) - th * (b * b - a * a) / 2.0
    i1 = gc * (b * b - a * a) / 2.0 - th * (b * b * b - a * a * a) / 3.0
    return i0, i1


@njit(cache=True, error_model="numpy", inline="always")
def _strip_sq(gc, th, a, b, compressed_only):
    """Integral of g(s)^2 over [a, b] (restricted to g < 0 if asked): strain energy."""
    a, b = _loaded_part(gc, th, a, b, compressed_only)
    if b <= a:
        return 0.0
    fb = gc * gc * b - gc * th * b * b + th * th * b ** 3 / 3.0
    fa = gc * gc * a - gc * th * a * a + th * th * a ** 3 / 3.0
    return fb - fa


@njit(**NO_NRT)
def bond_forces(run, kin, balls, fa, bonds, log):
    """Flat-joint forces, element failure (logged) and interface removal."""
    prm = run.prm
    eacc = run.eacc
    step = run.cnt[0]
    rad = balls.rad
    b_i, b_j, b_active, rbar, d0, gi = bonds.i, bonds.j, bonds.active, bonds.rbar, bonds.d0, bonds.gi
    kn, ks, sigc, coh, tanphi, bmu = bonds.kn, bonds.ks, bonds.sigc, bonds.coh, bonds.tanphi, bonds.mu
    theta, bmom, state, bfn, bfs = bonds.theta, bonds.moment, bonds.state, bonds.fn, bonds.fs
    dt = prm[P.DT]
    t = prm[P.THICK]
    ne = state.shape[1]
    for b in range(b_i.shape[0]):
        if not b_active[b]:
            continue
        i = b_i[b]
        j = b_j[b]
        dx = kin[j, 0] - kin[i, 0]
        dy = kin[j, 1] - kin[i, 1]
        d = math.sqrt(dx * dx + dy * dy)
        nx = dx / d
        ny = dy / d
        tx = -ny
        ty = nx
        ai = rad[i] + 0.5 * (d - rad[i] - rad[j])     # centre -> interface centre
        aj = d - ai
        w = kin[i, 4] * ai + kin[j, 4] * aj
        vt = (kin[j, 2] - kin[i, 2] - w * tx) * tx + (kin[j, 3] - kin[i, 3] - w * ty) * ty
        theta[b] += (kin[j, 4] - kin[i, 4]) * dt
        th = theta[b]
        gc = d - d0[b]
        le = 2.0 * rbar[b] / ne
        ae = le * t
        ftot_n = 0.0
        ftot_s = 0.0
        mc = 0.0
        nbonded = 0
        for e in range(ne):
            a = -rbar[b] + e * le
            se = a + 0.5 * le
            fs = bfs[b, e] - ks[b] * ae * vt * dt
            e_break = -1.0
            if state[b, e]:
                i0, i1 = _strip(gc, th, a, a + le, False)
                fn = kn[b] * t * i0
                sig = fn / ae
                tau = abs(fs) / ae
                mode = 0
                if sig >= sigc[b]:
                    mode = MODE_TENSION
                elif tau >= coh[b] - sig * tanphi[b]:
                    mode = MODE_SHEAR
                if mode > 0:
                    k = log.n[0]
                    log.step[k] = step
                    log.time[k] = prm[P.TIME]
                    log.bond[k] = b
                    log.elem[k] = e
                    log.i[k] = i
                    log.j[k] = j
                    log.stone[k] = balls.stone[i]
                    log.mode[k] = mode
                    log.x[k] = kin[i, 0] + ai * nx + se * tx
                    log.y[k] = kin[i, 1] + ai * ny + se * ty
                    log.stress[k] = sig if mode == MODE_TENSION else tau
                    log.n[0] = k + 1
                    state[b, e] = 0
                    # strain energy before the break; what survives is subtracted below
                    e_break = (0.5 * kn[b] * t * _strip_sq(gc, th, a, a + le, False)
                               + 0.5 * fs * fs / (ks[b] * ae))
                else:
                    nbonded += 1
            if not state[b, e]:
                # broken: compression-only notional surfaces with Coulomb friction
                i0, i1 = _strip(gc, th, a, a + le, True)
                fn = kn[b] * t * i0
                lim = bmu[b] * max(-fn, 0.0)
                if abs(fs) > lim:
                    if e_break < 0.0:
                        eacc[P.E_FRICTION] += lim * (abs(fs) - lim) / (ks[b] * ae)
                    fs = lim if fs > 0.0 else -lim
                if e_break >= 0.0:
                    eacc[P.E_BREAKAGE] += e_break - (
                        0.5 * kn[b] * t * _strip_sq(gc, th, a, a + le, True)
                        + 0.5 * fs * fs / (ks[b] * ae))
            bfn[b, e] = fn
            bfs[b, e] = fs
            ftot_n += fn
            ftot_s += fs
            mc += kn[b] * t * i1
        if nbonded == 0 and gc - abs(th) * rbar[b] > gi[b]:
            b_active[b] = 0       # surfaces apart beyond the installation gap: remove
            for e in range(ne):
                bfn[b, e] = 0.0
                bfs[b, e] = 0.0
            bmom[b] = 0.0
            continue
        bmom[b] = mc
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
            e_tot += 0.5 * kn[b] * thick * _strip_sq(gc, th, a, a + le, not state[b, e])
            e_tot += 0.5 * bfs[b, e] ** 2 / (ks[b] * le * thick)
    return e_tot


def find_bond_candidates(pos, rad, stone, alive, gap_factor):
    """Pairs (i<j) of live balls of one stone (stone >= 0) whose surface gap is below
    g_i = gap_factor * min(R_i, R_j) (Table 4.2: 0.4 * D_small / 2). O(N) via cells."""
    from .neighbours import build_pairs
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
        cnt = build_pairs(pos, rad, alive, np.full(n, -1, np.int32), skin,
                          lo[0], lo[1], hi[0], hi[1], oi, oj)
        if cnt >= 0:
            break
        cap = -cnt
    oi, oj = oi[:cnt].astype(np.int64), oj[:cnt].astype(np.int64)
    d = np.hypot(*(pos[oj] - pos[oi]).T)
    gap = d - rad[oi] - rad[oj]
    keep = (stone[oi] == stone[oj]) & (stone[oi] >= 0) & (gap < gap_factor * np.minimum(rad[oi], rad[oj]))
    return oi[keep], oj[keep]
