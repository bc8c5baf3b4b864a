"""Contact-law sub-models (numba kernels) and the one point where the law is dispatched.

A contact law is a composition of four sub-models, one of each kind — normal, damping,
tangential, rolling — as LAMMPS ``pair granular`` composes its ``GranSubMod`` classes.
Each sub-model reads its coefficients from its block of columns of the material-pair table
``coef[mat_a, mat_b, :]``, and may own a block of the per-contact history (reset to zero
when the contact opens) and of the persistent per-contact state (kept while the pair stays
in the Verlet list, carried over rebuilds and checkpointed). ``law`` (an int built by
``law.ContactLaw.layout``) holds each kind's code and the first column of its blocks.

Both contact loops (ball-ball, ball-wall) call ``contact_force`` with the contact frame and
the raw kinematics; a wall plays body i with zero radius and infinite mass (minv = 0).
Convention: n points from body i to body j, t = z x n; forces are those ON j; a moment is
about the body's own centre.
"""
import math

from numba import njit

# ``law`` is one integer: 4-bit fields, field k at bits 4k..4k+3 (law.ContactLaw.layout packs
# it). Kernels receive it as a numba literal (``numba.literally``): every field is then a
# compile-time constant, each law gets its own machine code and the sub-model branches
# vanish from the contact loops. Fields: the code of each kind, the first coefficient column
# of damping/tangential/rolling (normal starts at 0), the first history and state column of
# tangential/rolling (normal and damping own none), the history width.
NORMAL, DAMPING, TANGENTIAL, ROLLING = 0, 1, 2, 3
C_DAMPING, C_TANGENTIAL, C_ROLLING = 4, 5, 6
H_TANGENTIAL, H_ROLLING, S_TANGENTIAL, S_ROLLING, WIDTH = 7, 8, 9, 10, 11
N_FIELDS = 12
C_NORMAL = 0
# coefficient rows are fixed-width tuples (the table is padded): a tuple indexed by the
# law's compile-time offsets is kept in registers, and a contact loop reloads it only when
# the material pair changes
NCOEF = 12


@njit(cache=True, error_model="numpy", inline="always")
def coefficient_row(coef, ma, mb):
    """The coefficients of material pair (ma, mb) as a tuple of NCOEF floats."""
    return (coef[ma, mb, 0], coef[ma, mb, 1], coef[ma, mb, 2], coef[ma, mb, 3],
            coef[ma, mb, 4], coef[ma, mb, 5], coef[ma, mb, 6], coef[ma, mb, 7],
            coef[ma, mb, 8], coef[ma, mb, 9], coef[ma, mb, 10], coef[ma, mb, 11])


@njit(cache=True, error_model="numpy", inline="always")
def cached_row(coef, c, ma, mb, a, b):
    """(row, ma, mb): the coefficient row ``c`` of materials (ma, mb), reloaded if the
    contact at hand is between materials (a, b) instead. Start with ma = mb = -1."""
    if a != ma or b != mb:
        return coefficient_row(coef, a, b), a, b
    return c, ma, mb


@njit(cache=True, error_model="numpy", inline="always")
def lf(law, field):
    """Field ``field`` of the packed law."""
    return (law >> (4 * field)) & 15


# sub-model codes, per kind (registered with names in law.py)
NORMAL_LINEAR_PFC, NORMAL_HOOKE = 0, 1
DAMPING_PFC_DASHPOT, DAMPING_MASS_VISCOUS = 0, 1
TANGENTIAL_PFC_INCREMENTAL, TANGENTIAL_LAMMPS_HISTORY = 0, 1
ROLLING_NONE, ROLLING_EPSD = 0, 1

JIT = dict(cache=True, error_model="numpy", inline="always")


# ---------------------------------------------------------------- normal
@njit(**JIT)
def normal_stiffness(law, c, ri, rj, thick):
    """k_n [N/m]. linear_pfc: A E*/L with A = 2 min(R) t, L = R1 + R2 (ball-facet, ri = 0:
    A = 2 R t, L = R). hooke: the table's kn."""
    kn = c[C_NORMAL]
    if lf(law, NORMAL) == NORMAL_LINEAR_PFC:
        rmin = min(ri, rj) if ri > 0.0 else rj
        kn = 2.0 * rmin * thick * kn / (ri + rj)
    return kn


@njit(**JIT)
def contact_arm_shift(law, delta):
    """Distance from a body's surface to the contact point: PFC puts it in the middle of
    the overlap; LAMMPS gran/hooke/history at the surface (arm = R)."""
    return 0.0 if lf(law, NORMAL) == NORMAL_HOOKE else 0.5 * delta


# ---------------------------------------------------------------- damping
@njit(**JIT)
def damped_normal_force(law, c, fnl, vn, kn, mc):
    """Total normal force from the spring part ``fnl``. pfc_dashpot: -2 beta_n sqrt(m_c k_n)
    v_n, the total clamped at zero if no_tension (PFC dashpot mode 1). mass_viscous
    (LAMMPS dampflag 1): -m_eff gamma_n v_n, no clamp."""
    o = lf(law, C_DAMPING)
    if lf(law, DAMPING) == DAMPING_MASS_VISCOUS:
        fn = fnl - mc * c[o] * vn
    else:
        fn = fnl - 2.0 * c[o] * math.sqrt(mc * kn) * vn
        if c[o + 1] > 0.0 and fn < 0.0:
            fn = 0.0      # no-tension: the dashpot may not make the contact pull
    return fn


# ---------------------------------------------------------------- tangential
@njit(**JIT)
def tangential_stiffness(law, c, kn):
    """k_s [N/m]: pfc_incremental k_n / kappa*; lammps_history the table's kt."""
    ks = c[lf(law, C_TANGENTIAL)]
    if lf(law, TANGENTIAL) == TANGENTIAL_PFC_INCREMENTAL:
        ks = kn / ks
    return ks


@njit(**JIT)
def tangential_force(law, c, fnl, fn, vt, nx, ny, ks, mc, dt, hist, p):
    """Shear force along t; updates the history. Returns (F_t, dashpot work, slip work).

    pfc_incremental (kappa, mu, beta_s; history: F_s): F_s <- F_s - k_s v_t dt, Coulomb
    limit mu F_n^linear, shear dashpot -2 beta_s sqrt(m_c k_s) v_t only while sticking.
    lammps_history (kt, gamma_t, mu; history: shear displacement vector xi, as
    pair_gran_hooke_history.cpp): xi += v_t dt projected on the tangent plane,
    F_t = -(kt xi + m_eff gamma_t v_t), |F_t| <= mu |F_n| with xi rescaled when sliding."""
    o = lf(law, C_TANGENTIAL)
    h = lf(law, H_TANGENTIAL)
    if lf(law, TANGENTIAL) == TANGENTIAL_LAMMPS_HISTORY:
        gt = mc * c[o + 1]
        tx = -ny
        ty = nx
        vtx = vt * tx
        vty = vt * ty
        sx = hist[p, h] + vtx * dt
        sy = hist[p, h + 1] + vty * dt
        shrmag2 = sx * sx + sy * sy       # |xi| before the projection, as in LAMMPS
        rsht = sx * nx + sy * ny          # keep xi in the tangent plane
        sx -= rsht * nx
        sy -= rsht * ny
        fsx = -(ks * sx + gt * vtx)
        fsy = -(ks * sy + gt * vty)
        fs2 = fsx * fsx + fsy * fsy
        fmax = c[o + 2] * abs(fn)
        e_slip = 0.0
        if fs2 > fmax * fmax:             # squares: no sqrt unless sliding
            e0 = sx * sx + sy * sy
            if shrmag2 != 0.0:
                r = fmax / math.sqrt(fs2)
                sx = r * (sx + gt * vtx / ks) - gt * vtx / ks
                sy = r * (sy + gt * vty / ks) - gt * vty / ks
                fsx *= r
                fsy *= r
            else:
                fsx = 0.0
                fsy = 0.0
            e_slip = 0.5 * ks * (e0 - sx * sx - sy * sy)
        hist[p, h] = sx
        hist[p, h + 1] = sy
        ft = fsx * tx + fsy * ty
        e_dash = -(ft + ks * (sx * tx + sy * ty)) * vt * dt
    else:
        fs = hist[p, h] - ks * vt * dt
        lim = c[o + 1] * fnl
        e_slip = 0.0
        e_dash = 0.0
        ft = fs
        if abs(fs) > lim:
            e_slip = lim * (abs(fs) - lim) / ks
            fs = lim if fs > 0.0 else -lim
            ft = fs
        else:
            fsd = -2.0 * c[o + 2] * math.sqrt(mc * ks) * vt
            ft = fs + fsd
            e_dash = -fsd * vt * dt
        hist[p, h] = fs
    return ft, e_dash, e_slip


@njit(**JIT)
def tangential_energy(law, hist, p, ks):
    """Elastic energy of the shear spring [J]."""
    h = lf(law, H_TANGENTIAL)
    if lf(law, TANGENTIAL) == TANGENTIAL_LAMMPS_HISTORY:
        e = 0.5 * ks * (hist[p, h] ** 2 + hist[p, h + 1] ** 2)
    else:
        e = 0.5 * hist[p, h] ** 2 / ks
    return e


# ---------------------------------------------------------------- rolling
@njit(**JIT)
def rolling_radius(ri, rj):
    """R_r = R1 R2 / (R1 + R2); against a wall (ri = 0) the ball's R."""
    return rj if ri == 0.0 else ri * rj / (ri + rj)


@njit(**JIT)
def rolling_stiffness(law, c, ks, ri, rj):
    """k_r [N m/rad]: epsd k_r = kr_ratio k_s R_r^2 (kr_ratio = 1: PFC's rrlinear);
    0 without rolling resistance, and at mu_r = 0: a spring whose limit moment is 0 is
    always fully plastic (it carries no moment, stores nothing, and must not shorten the
    critical timestep), so mu_r = 0 is the law without rolling resistance, bit for bit."""
    kr = 0.0
    if lf(law, ROLLING) == ROLLING_EPSD:
        o = lf(law, C_ROLLING)
        if c[o] > 0.0:
            rr = rolling_radius(ri, rj)
            kr = c[o + 1] * ks * rr * rr
    return kr


@njit(**JIT)
def rolling_moment(law, c, fn, kr, wrel, minv_i, minv_j, ri, rj, dt, hist, p):
    """Rolling-resistance moment on j (on i: the opposite) and the work it dissipated
    (k_r from rolling_stiffness).

    epsd — elastic-plastic spring-dashpot, "type C" of Ai et al. (2011), Powder Technol.
    206 (mu_r, kr_ratio, eta_r; history: the spring moment M_r; state: rolling_work [J]):
    M_r <- M_r - k_r (w_j - w_i) dt, |M_r| <= mu_r R_r F_n (plastic rolling beyond; F_n the
    normal spring force, as the Coulomb limit of pfc_incremental and PFC's rrlinear); while
    elastic a dashpot -eta_r 2 sqrt(I_r k_r) (w_j - w_i), none when fully mobilised
    (their f = 0); 1/I_r = sum over the bodies of 1/(I + m R^2) = 1/(1.5 m R^2) for disks."""
    m = 0.0
    md = 0.0
    work = 0.0
    if lf(law, ROLLING) == ROLLING_EPSD:
        o = lf(law, C_ROLLING)
        h = lf(law, H_ROLLING)
        m = hist[p, h] - kr * wrel * dt
        lim = c[o] * rolling_radius(ri, rj) * max(fn, 0.0)
        if abs(m) > lim:
            # limit moment x plastic rotation (none at mu_r = 0: lim and k_r are 0)
            work = lim * (abs(m) - lim) / kr if kr > 0.0 else 0.0
            m = lim if m > 0.0 else -lim
        elif c[o + 2] > 0.0:
            ir_inv = minv_j / (1.5 * rj * rj)
            if ri > 0.0:
                ir_inv += minv_i / (1.5 * ri * ri)
            md = -2.0 * c[o + 2] * math.sqrt(kr / ir_inv) * wrel
            work = -md * wrel * dt
        hist[p, h] = m
        hist[p, lf(law, WIDTH) + lf(law, S_ROLLING)] += work
    return m + md, work


@njit(**JIT)
def rolling_energy(law, kr, hist, p):
    """Elastic energy of the rolling spring of stiffness k_r [J]."""
    return 0.5 * hist[p, lf(law, H_ROLLING)] ** 2 / kr if kr > 0.0 else 0.0


# ---------------------------------------------------------------- the dispatch point
@njit(**JIT)
def contact_stiffness(law, c, ri, rj, thick):
    """(k_n, k_s, k_r) of a contact (ri = 0: a wall): the critical timestep's input."""
    kn = normal_stiffness(law, c, ri, rj, thick)
    ks = tangential_stiffness(law, c, kn)
    return kn, ks, rolling_stiffness(law, c, ks, ri, rj)


@njit(**JIT)
def contact_force(law, c, nx, ny, delta, dvx, dvy, wi, wj, ri, rj, minv_i, minv_j,
                  thick, dt, hist, p):
    """Force of one touching contact (delta > 0). dv = v_j - v_i of the centres (a wall:
    its velocity at the contact point), w = spins, ri = 0 and minv_i = 0 for a wall.
    Updates the history and the persistent state (slip and rolling work at this contact).
    Returns (fx, fy on j, moment on i, moment on j, F_n, F_t, dashpot work, slip work,
    rolling work) of this step."""
    tx = -ny
    ty = nx
    shift = contact_arm_shift(law, delta)
    ai = ri - shift if ri > 0.0 else 0.0
    aj = rj - shift
    w = wi * ai + wj * aj
    vrx = dvx - w * tx                    # relative velocity of j at the contact point
    vry = dvy - w * ty
    vn = vrx * nx + vry * ny
    vt = vrx * tx + vry * ty
    mc = 1.0 / (minv_i + minv_j)
    kn, ks, kr = contact_stiffness(law, c, ri, rj, thick)
    fnl = kn * delta
    fn = damped_normal_force(law, c, fnl, vn, kn, mc)
    ft, e_dash, e_slip = tangential_force(law, c, fnl, fn, vt, nx, ny, ks, mc, dt, hist, p)
    mr, e_roll = rolling_moment(law, c, fnl, kr, wj - wi, minv_i, minv_j, ri, rj, dt, hist, p)
    e_dash -= (fn - fnl) * vn * dt
    hist[p, lf(law, WIDTH) + lf(law, S_TANGENTIAL)] += e_slip   # unconditional: a branch was slower
    return (fn * nx + ft * tx, fn * ny + ft * ty, -ai * ft - mr, -aj * ft + mr, fn, ft,
            e_dash, e_slip, e_roll)


@njit(**JIT)
def contact_energy(law, c, delta, ri, rj, thick, hist, p):
    """Elastic energy stored in a touching contact: normal, shear and rolling springs [J]."""
    kn, ks, kr = contact_stiffness(law, c, ri, rj, thick)
    return (0.5 * kn * delta * delta + tangential_energy(law, hist, p, ks)
            + rolling_energy(law, kr, hist, p))
