"""Contact laws (pure scalar kernels) and the ball-ball pair loop.

Two laws share the loop:
* PFC linear model with dashpots (the engine's law, physics-spec "LC"):
  k_n = A E*/L, k_s = k_n/kappa*, normal dashpot -2 beta_n sqrt(m_c k_n) v_n with the
  total normal force clamped at zero (no tension, default; PFC dashpot mode 1) or not
  (``no_tension=False``, PFC mode 0, where e = exp(-pi beta/sqrt(1-beta^2)) holds), incremental shear force with
  Coulomb limit mu*F_n^linear, shear dashpot inactive while sliding (PFC default).
* LAMMPS ``gran/hooke/history`` (benchmark law): F_n = kn d - m_eff gamma_n v_n (no clamp),
  shear displacement vector xi with kt and m_eff gamma_t damping, Coulomb on |F_n|.

Convention: n points from body i to body j, t = z x n; forces are those ON j.
"""
import math

from numba import njit

from . import params as P

# columns of the contact-material table lc[mat_a, mat_b, :]
LC_E, LC_KAPPA, LC_MU, LC_BN, LC_BS, LC_NOTENSION = 0, 1, 2, 3, 4, 5
LC_NCOL = 6


@njit(cache=True, inline="always")
def pfc_linear(delta, vn, vt, kn, ks, mu, bn, bs, notension, mc, dt, hist, h):
    """PFC linear law. Updates the shear force hist[h, 0]; returns
    (F_n, F_t, F_n linear part, dashpot work, friction work) for this step."""
    fnl = kn * delta
    fnd = -2.0 * bn * math.sqrt(mc * kn) * vn
    fn = fnl + fnd
    if notension and fn < 0.0:
        fn = 0.0      # no-tension: the dashpot may not make the contact pull
    fs = hist[h, 0] - ks * vt * dt
    lim = mu * fnl
    e_fric = 0.0
    fsd = 0.0
    if abs(fs) > lim:
        e_fric = lim * (abs(fs) - lim) / ks
        fs = lim if fs > 0.0 else -lim
    else:
        fsd = -2.0 * bs * math.sqrt(mc * ks) * vt
    hist[h, 0] = fs
    e_dash = -((fn - fnl) * vn + fsd * vt) * dt
    return fn, fs + fsd, fnl, e_dash, e_fric


@njit(cache=True, inline="always")
def hooke_history(delta, vn, vtx, vty, nx, ny, kn, kt, gn, gt, mu, meff, dt, hist, h):
    """LAMMPS gran/hooke/history (dampflag 1) in 2D, same operation order as
    pair_gran_hooke_history.cpp. vt = tangential relative velocity of j w.r.t. i at the
    contact (rotation included). Returns (F_n, F_t x, F_t y)."""
    fn = kn * delta - meff * gn * vn
    sx = hist[h, 0] + vtx * dt
    sy = hist[h, 1] + vty * dt
    shrmag = math.sqrt(sx * sx + sy * sy)
    rsht = sx * nx + sy * ny          # keep xi in the tangent plane
    sx -= rsht * nx
    sy -= rsht * ny
    fsx = -(kt * sx + meff * gt * vtx)
    fsy = -(kt * sy + meff * gt * vty)
    fs = math.sqrt(fsx * fsx + fsy * fsy)
    fmax = mu * abs(fn)
    if fs > fmax:
        if shrmag != 0.0:
            r = fmax / fs
            sx = r * (sx + meff * gt * vtx / kt) - meff * gt * vtx / kt
            sy = r * (sy + meff * gt * vty / kt) - meff * gt * vty / kt
            fsx *= r
            fsy *= r
        else:
            fsx = 0.0
            fsy = 0.0
    hist[h, 0] = sx
    hist[h, 1] = sy
    return fn, fsx, fsy


@njit(cache=True)
def pair_forces(prm, pos, vel, omega, rad, minv, mat, force, moment,
                p_i, p_j, p_h, p_bond, p_fn, p_fs, npair, b_active, lc, eacc):
    """Add ball-ball contact forces of the Verlet list to force/moment."""
    dt = prm[P.DT]
    law = int(prm[P.LAW])
    thick = prm[P.THICK]
    ed = 0.0
    ef = 0.0
    for p in range(npair):
        i = p_i[p]
        j = p_j[p]
        b = p_bond[p]
        if b >= 0 and b_active[b]:
            continue                      # a flat joint replaces the linear contact
        dx = pos[j, 0] - pos[i, 0]
        dy = pos[j, 1] - pos[i, 1]
        d2 = dx * dx + dy * dy
        rs = rad[i] + rad[j]
        if d2 >= rs * rs:
            p_h[p, 0] = 0.0               # contact lost: history restarts at zero
            p_h[p, 1] = 0.0
            p_fn[p] = 0.0
            p_fs[p] = 0.0
            continue
        d = math.sqrt(d2)
        delta = rs - d
        nx = dx / d
        ny = dy / d
        tx = -ny
        ty = nx
        mc = 1.0 / (minv[i] + minv[j])
        if law == P.LAW_HOOKE:
            ai = rad[i]
            aj = rad[j]
        else:
            ai = rad[i] - 0.5 * delta     # PFC contact point: middle of the overlap
            aj = rad[j] - 0.5 * delta
        w = omega[i] * ai + omega[j] * aj
        vrx = vel[j, 0] - vel[i, 0] - w * tx
        vry = vel[j, 1] - vel[i, 1] - w * ty
        vn = vrx * nx + vry * ny
        if law == P.LAW_HOOKE:
            fn, fsx, fsy = hooke_history(delta, vn, vrx - vn * nx, vry - vn * ny, nx, ny,
                                         prm[P.H_KN], prm[P.H_KT], prm[P.H_GN], prm[P.H_GT],
                                         prm[P.H_MU], mc, dt, p_h, p)
            ft = fsx * tx + fsy * ty
        else:
            ma = mat[i]
            mb = mat[j]
            kn = 2.0 * min(rad[i], rad[j]) * thick * lc[ma, mb, LC_E] / rs
            ks = kn / lc[ma, mb, LC_KAPPA]
            vt = vrx * tx + vry * ty
            fn, ft, fnl, e1, e2 = pfc_linear(delta, vn, vt, kn, ks, lc[ma, mb, LC_MU],
                                             lc[ma, mb, LC_BN], lc[ma, mb, LC_BS],
                                             lc[ma, mb, LC_NOTENSION] > 0.0, mc, dt, p_h, p)
            fsx = ft * tx
            fsy = ft * ty
            ed += e1
            ef += e2
        fx = fn * nx + fsx
        fy = fn * ny + fsy
        force[j, 0] += fx
        force[j, 1] += fy
        force[i, 0] -= fx
        force[i, 1] -= fy
        moment[j] -= aj * ft
        moment[i] -= ai * ft
        p_fn[p] = fn
        p_fs[p] = ft
    eacc[P.E_DASHPOT] += ed
    eacc[P.E_FRICTION] += ef
