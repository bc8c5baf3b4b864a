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


@njit(cache=True, error_model="numpy", inline="always")
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


@njit(cache=True, error_model="numpy", inline="always")
def hooke_history(delta, vn, vtx, vty, nx, ny, kn, kt, gn, gt, mu, meff, dt, hist, h):
    """LAMMPS gran/hooke/history (dampflag 1) in 2D, same operation order as
    pair_gran_hooke_history.cpp. vt = tangential relative velocity of j w.r.t. i at the
    contact (rotation included). Returns (F_n, F_t x, F_t y)."""
    fn = kn * delta - meff * gn * vn
    sx = hist[h, 0] + vtx * dt
    sy = hist[h, 1] + vty * dt
    shrmag2 = sx * sx + sy * sy       # |xi| before the projection, as in LAMMPS
    rsht = sx * nx + sy * ny          # keep xi in the tangent plane
    sx -= rsht * nx
    sy -= rsht * ny
    fsx = -(kt * sx + meff * gt * vtx)
    fsy = -(kt * sy + meff * gt * vty)
    fs2 = fsx * fsx + fsy * fsy
    fmax = mu * abs(fn)
    if fs2 > fmax * fmax:             # squares: no sqrt unless sliding
        if shrmag2 != 0.0:
            r = fmax / math.sqrt(fs2)
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


# fastmath without nnan/ninf/reassoc: same binary -> same bits (run-to-run and across a
# checkpoint restart), NaN still propagates to the guards
FAST = {"arcp", "contract", "nsz", "afn"}


@njit(cache=True, error_model="numpy")
def pack_kinematics(pos, vel, omega, rad, minv, mat, kin):
    """kin[i] = (x, y, vx, vy, omega, R, 1/m, material): one cache line per ball for the
    pair loop, whose j accesses are scattered (measured ~20 % faster than 7 arrays)."""
    for i in range(pos.shape[0]):
        kin[i, 0] = pos[i, 0]
        kin[i, 1] = pos[i, 1]
        kin[i, 2] = vel[i, 0]
        kin[i, 3] = vel[i, 1]
        kin[i, 4] = omega[i]
        kin[i, 5] = rad[i]
        kin[i, 6] = minv[i]
        kin[i, 7] = mat[i]


@njit(cache=True, error_model="numpy")
def pair_forces(prm, kin, fa, p_i, p_j, p_h, p_bond, p_fn, p_fs, npair,
                b_active, lc, eacc):
    """Add ball-ball contact forces of the Verlet list to force/moment (kin: see
    ``pack_kinematics``)."""
    if int(prm[P.LAW]) == P.LAW_HOOKE:
        _pairs_hooke(prm, kin, fa, p_i, p_j, p_h, p_bond, p_fn, p_fs, npair,
                     b_active)
    else:
        _pairs_pfc(prm, kin, fa, p_i, p_j, p_h, p_bond, p_fn, p_fs, npair,
                   b_active, lc, eacc)


@njit(cache=True, error_model="numpy", fastmath=FAST)
def _pairs_hooke(prm, kin, fa, p_i, p_j, p_h, p_bond, p_fn, p_fs, npair, b_active):
    dt = prm[P.DT]
    kn = prm[P.H_KN]
    kt = prm[P.H_KT]
    gn = prm[P.H_GN]
    gt = prm[P.H_GT]
    mu = prm[P.H_MU]
    bonds = b_active.shape[0] > 0
    for p in range(npair):
        i = p_i[p]
        j = p_j[p]
        dx = kin[j, 0] - kin[i, 0]
        dy = kin[j, 1] - kin[i, 1]
        d2 = dx * dx + dy * dy
        ri = kin[i, 5]
        rj = kin[j, 5]
        rs = ri + rj
        if d2 >= rs * rs:
            if p_fn[p] != 0.0 or p_h[p, 0] != 0.0 or p_h[p, 1] != 0.0:
                p_h[p, 0] = 0.0           # contact lost: history restarts at zero
                p_h[p, 1] = 0.0
                p_fn[p] = 0.0
                p_fs[p] = 0.0
            continue
        if bonds:
            b = p_bond[p]
            if b >= 0 and b_active[b]:
                continue                  # a flat joint replaces the contact
        d = math.sqrt(d2)
        rinv = 1.0 / d
        nx = dx * rinv
        ny = dy * rinv
        mc = 1.0 / (kin[i, 6] + kin[j, 6])
        w = kin[i, 4] * ri + kin[j, 4] * rj
        vrx = kin[j, 2] - kin[i, 2] + w * ny       # - w * t, t = (-ny, nx)
        vry = kin[j, 3] - kin[i, 3] - w * nx
        vn = vrx * nx + vry * ny
        fn, fsx, fsy = hooke_history(rs - d, vn, vrx - vn * nx, vry - vn * ny, nx, ny,
                                     kn, kt, gn, gt, mu, mc, dt, p_h, p)
        ft = fsy * nx - fsx * ny
        fx = fn * nx + fsx
        fy = fn * ny + fsy
        fa[j, 0] += fx
        fa[j, 1] += fy
        fa[i, 0] -= fx
        fa[i, 1] -= fy
        fa[j, 2] -= rj * ft
        fa[i, 2] -= ri * ft
        p_fn[p] = fn
        p_fs[p] = ft


@njit(cache=True, error_model="numpy")
def _pairs_pfc(prm, kin, fa, p_i, p_j, p_h, p_bond, p_fn, p_fs, npair, b_active,
               lc, eacc):
    dt = prm[P.DT]
    thick = prm[P.THICK]
    ed = 0.0
    ef = 0.0
    for p in range(npair):
        i = p_i[p]
        j = p_j[p]
        b = p_bond[p]
        if b >= 0 and b_active[b]:
            continue                      # a flat joint replaces the linear contact
        dx = kin[j, 0] - kin[i, 0]
        dy = kin[j, 1] - kin[i, 1]
        d2 = dx * dx + dy * dy
        ri = kin[i, 5]
        rj = kin[j, 5]
        rs = ri + rj
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
        mc = 1.0 / (kin[i, 6] + kin[j, 6])
        ai = ri - 0.5 * delta             # PFC contact point: middle of the overlap
        aj = rj - 0.5 * delta
        w = kin[i, 4] * ai + kin[j, 4] * aj
        vrx = kin[j, 2] - kin[i, 2] - w * tx
        vry = kin[j, 3] - kin[i, 3] - w * ty
        vn = vrx * nx + vry * ny
        ma = int(kin[i, 7])
        mb = int(kin[j, 7])
        kn = 2.0 * min(ri, rj) * thick * lc[ma, mb, LC_E] / rs
        ks = kn / lc[ma, mb, LC_KAPPA]
        vt = vrx * tx + vry * ty
        fn, ft, fnl, e1, e2 = pfc_linear(delta, vn, vt, kn, ks, lc[ma, mb, LC_MU],
                                         lc[ma, mb, LC_BN], lc[ma, mb, LC_BS],
                                         lc[ma, mb, LC_NOTENSION] > 0.0, mc, dt, p_h, p)
        ed += e1
        ef += e2
        fx = fn * nx + ft * tx
        fy = fn * ny + ft * ty
        fa[j, 0] += fx
        fa[j, 1] += fy
        fa[i, 0] -= fx
        fa[i, 1] -= fy
        fa[j, 2] -= aj * ft
        fa[i, 2] -= ai * ft
        p_fn[p] = fn
        p_fs[p] = ft
    eacc[P.E_DASHPOT] += ed
    eacc[P.E_FRICTION] += ef
