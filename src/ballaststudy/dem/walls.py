"""Ball-segment contacts and kinematic wall motion.

The wall plays body i (infinite mass, velocity of the segment at the contact point),
the ball plays body j, so the same contact laws apply. PFC ball-facet stiffness:
A = 2 R t, L = R (physics spec), effective mass m_c = m_ball (LAMMPS: m_eff = m_i).
"""
import math

from numba import njit

from . import params as P
from .contacts import LC_BN, LC_BS, LC_E, LC_KAPPA, LC_MU, LC_NOTENSION, hooke_history, pfc_linear
from .neighbours import seg_closest


@njit(cache=True, error_model="numpy")
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


@njit(cache=True, error_model="numpy")
def wall_forces(prm, kin, rad, minv, mat, fa,
                seg, wvel, womega, centre, wmat, link, wforce, wmoment,
                w_i, w_s, w_h, w_fn, w_fs, nwp, lc, eacc):
    """Add ball-segment forces to the balls; record force and moment on each segment."""
    dt = prm[P.DT]
    law = int(prm[P.LAW])
    thick = prm[P.THICK]
    for s in range(seg.shape[0]):
        wforce[s, 0] = 0.0
        wforce[s, 1] = 0.0
        wmoment[s] = 0.0
    ed = 0.0
    ef = 0.0
    ew = 0.0
    for q in range(nwp):
        i = w_i[q]
        s = w_s[q]
        cx, cy, u = seg_closest(kin[i, 0], kin[i, 1], seg[s, 0], seg[s, 1], seg[s, 2], seg[s, 3])
        dx = kin[i, 0] - cx
        dy = kin[i, 1] - cy
        d2 = dx * dx + dy * dy
        r = rad[i]
        if d2 >= r * r or d2 == 0.0 or _joint_elsewhere(kin[i, 0], kin[i, 1], seg, link, s, u):
            w_h[q, 0] = 0.0
            w_h[q, 1] = 0.0
            w_fn[q] = 0.0
            w_fs[q] = 0.0
            continue
        d = math.sqrt(d2)
        delta = r - d
        nx = dx / d
        ny = dy / d
        tx = -ny
        ty = nx
        # wall velocity at the contact point
        wx = wvel[s, 0] - womega[s] * (cy - centre[s, 1])
        wy = wvel[s, 1] + womega[s] * (cx - centre[s, 0])
        arm = r if law == P.LAW_HOOKE else r - 0.5 * delta
        vrx = kin[i, 2] - wx - kin[i, 4] * arm * tx
        vry = kin[i, 3] - wy - kin[i, 4] * arm * ty
        vn = vrx * nx + vry * ny
        mc = 1.0 / minv[i]
        if law == P.LAW_HOOKE:
            fn, fsx, fsy = hooke_history(delta, vn, vrx - vn * nx, vry - vn * ny, nx, ny,
                                         prm[P.H_KN], prm[P.H_KT], prm[P.H_GN], prm[P.H_GT],
                                         prm[P.H_MU], mc, dt, w_h, q)
            ft = fsx * tx + fsy * ty
        else:
            ma = wmat[s]
            mb = mat[i]
            kn = 2.0 * thick * lc[ma, mb, LC_E]          # A E / L with A = 2 R t, L = R
            ks = kn / lc[ma, mb, LC_KAPPA]
            vt = vrx * tx + vry * ty
            fn, ft, fnl, e1, e2 = pfc_linear(delta, vn, vt, kn, ks, lc[ma, mb, LC_MU],
                                             lc[ma, mb, LC_BN], lc[ma, mb, LC_BS],
                                             lc[ma, mb, LC_NOTENSION] > 0.0, mc, dt, w_h, q)
            fsx = ft * tx
            fsy = ft * ty
            ed += e1
            ef += e2
        fx = fn * nx + fsx
        fy = fn * ny + fsy
        fa[i, 0] += fx
        fa[i, 1] += fy
        fa[i, 2] -= arm * ft
        wforce[s, 0] -= fx
        wforce[s, 1] -= fy
        wmoment[s] -= (cx - centre[s, 0]) * fy - (cy - centre[s, 1]) * fx
        ew += (fx * wx + fy * wy) * dt       # power of the wall on the ball
        w_fn[q] = fn
        w_fs[q] = ft
    eacc[P.E_DASHPOT] += ed
    eacc[P.E_FRICTION] += ef
    eacc[P.E_WALLS] += ew
