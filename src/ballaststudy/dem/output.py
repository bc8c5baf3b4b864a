"""Compute-like measurements: pure functions of a Simulation's state (never change it).
They are bound as Simulation methods."""
import numpy as np

from .energy import energies  # noqa: F401  (re-exported as a Simulation method)
from .fragments import fragments as label_fragments


def wall_force(sim, ids=None):
    """Force exerted by the balls on each segment [N] (rows = ``ids`` or all)."""
    f = sim.walls.force
    return f.copy() if ids is None else f[ids].copy()


def wall_moment(sim, ids=None):
    m = sim.walls.moment
    return m.copy() if ids is None else m[ids].copy()


def clump_force(sim, cid):
    """(force [N], moment about the centre of mass [N m]) of clump ``cid`` from the last
    step: weight + contacts (local damping excluded for held clumps, which are not
    damped)."""
    return sim.clumps.force[cid].copy(), float(sim.clumps.moment[cid])


def local_damping_force(sim, ids=None, clumps=False):
    """The local damping force on balls ``ids`` (clumps ``ids`` if ``clumps``; all if None)
    in the last step [N], rows (fx, fy): a force from outside the system
    (integrate.locally_damped), so a balance of loads and reactions on a damped packing
    must count it. The engine keeps only the damped net force F_d = F - alpha |F| sign(v_h),
    v_h the half-step velocity the damping saw; F_d has F's sign (alpha < 1) and the last
    half kick gives v_h = v - dt/2 F_d / m, so F = F_d / (1 - alpha sign(v_h) sign(F_d))
    exactly. Zero for pebbles (their clump is damped as a whole), dead balls, held clumps
    and velocity-held dofs. alpha >= 1 is refused: a force damped to zero hides F."""
    body = sim.clumps if clumps else sim.balls
    ids = np.arange(len(body.mass)) if ids is None else np.atleast_1d(ids)
    fd = body.force[ids]
    if clumps:
        vh = body.vel[ids] - 0.5 * sim.dt * fd / body.mass[ids, None]
        damped = body.held[ids] == 0
        held = np.zeros(fd.shape, bool)
    else:
        vh = body.vel[ids] - 0.5 * sim.dt * fd * body.minv[ids, None]
        damped = (body.alive[ids] == 1) & (body.clump[ids] < 0)
        held = np.column_stack([body.fix[ids] & 1, body.fix[ids] & 2]) != 0
    alpha = np.where(held, 0.0, np.where(damped, body.damp[ids], 0.0)[:, None])
    if np.any(alpha >= 1.0):
        raise ValueError("local_damping_force: alpha >= 1 on a damped body, its force is not recoverable")
    return fd - fd / (1.0 - alpha * np.sign(vh) * np.sign(fd))


def contact_list(sim):
    """Ball-ball and ball-wall contacts with a force: dict of arrays i, j (j = -1 - segment
    for walls), force on j (for walls: on the ball) fx, fy, contact point x, y."""
    b = sim.balls
    out = []
    pr = sim.pairs
    k = np.nonzero((pr.fn[: pr.n[0]] != 0) | (pr.fs[: pr.n[0]] != 0))[0]
    i, j = pr.i[k], pr.j[k]
    d = b.pos[j] - b.pos[i]
    dist = np.hypot(*d.T)
    n = d / dist[:, None]
    t = np.column_stack([-n[:, 1], n[:, 0]])
    f = pr.fn[k, None] * n + pr.fs[k, None] * t
    delta = b.rad[i] + b.rad[j] - dist
    cp = b.pos[i] + (b.rad[i] - 0.5 * delta)[:, None] * n
    out.append((i, j, f, cp))
    wp = sim.wpairs
    k = np.nonzero((wp.fn[: wp.n[0]] != 0) | (wp.fs[: wp.n[0]] != 0))[0]
    i, s = wp.i[k], wp.s[k]
    seg = sim.walls.seg[s]
    e = seg[:, 2:] - seg[:, :2]
    u = np.clip(((b.pos[i] - seg[:, :2]) * e).sum(1) / (e * e).sum(1), 0, 1)
    cp = seg[:, :2] + u[:, None] * e
    n = b.pos[i] - cp
    n /= np.hypot(*n.T)[:, None]
    t = np.column_stack([-n[:, 1], n[:, 0]])
    f = wp.fn[k, None] * n + wp.fs[k, None] * t
    out.append((i, -1 - s, f, cp))
    cat = [np.concatenate(a) for a in zip(*out)]
    return dict(i=cat[0], j=cat[1], fx=cat[2][:, 0], fy=cat[2][:, 1], x=cat[3][:, 0],
                y=cat[3][:, 1])


def contact_state(sim):
    """Persistent per-contact state of the contact law's sub-models (e.g. slip_work,
    rolling_work [J]) for every listed ball-ball and ball-wall pair: dict of arrays i, j
    (j = -1 - segment for walls) and one array per state name (law.state_names)."""
    pr, wp, law = sim.pairs, sim.wpairs, sim.law
    n, m, h = int(pr.n[0]), int(wp.n[0]), law.history_width
    out = dict(i=np.concatenate([pr.i[:n], wp.i[:m]]),
               j=np.concatenate([pr.j[:n], -1 - wp.s[:m]]))
    for c, name in enumerate(law.state_names):
        out[name] = np.concatenate([pr.hist[:n, h + c], wp.hist[:m, h + c]])
    return out


def intact_bonds(sim):
    """(n_bonds,) bool: the bond's interface exists and has at least one intact element —
    the one meaning of an intact bond (fragments, breakage, outputs)."""
    bd = sim.bonds
    return (bd.active == 1) & bd.state.any(axis=1)


def fragments(sim, n_balls=None):
    """Fragment label of balls 0..n_balls-1 (default: all; dead balls -1), numbered by lowest
    ball id: connected components over the intact bonds among those balls."""
    b, bd = sim.balls, sim.bonds
    n = len(b) if n_balls is None else int(n_balls)
    keep = intact_bonds(sim) & (bd.i < n) & (bd.j < n)
    return label_fragments(n, bd.i[keep], bd.j[keep], np.ones(int(keep.sum()), bool),
                 ballast=b.alive[:n] == 1)[1]


def bond_list(sim):
    """Flat joints: i, j, active, per-element state (1 bonded) / normal force (tension +) /
    shear force, bending moment on j, accumulated relative rotation."""
    bd = sim.bonds
    return dict(i=bd.i.copy(), j=bd.j.copy(), active=bd.active.copy(), state=bd.state.copy(),
                fn=bd.fn.copy(), fs=bd.fs.copy(), moment=bd.moment.copy(),
                theta=bd.theta.copy())


def breakages(sim):
    """Breakage log: step, time, bond, elem, i, j, stone, mode ('tension'|'shear'),
    x, y, stress [Pa]."""
    lg = sim.log
    n = int(lg.n[0])
    d = {k: getattr(lg, k)[:n].copy() for k in
         ("step", "time", "bond", "elem", "i", "j", "stone", "x", "y", "stress")}
    d["mode"] = np.array(["tension" if m == 1 else "shear" for m in lg.mode[:n]], dtype=object)
    return d


def inertial_number(shear_rate, d, rho, p):
    """I = gamma_dot * d * sqrt(rho / p): quasi-static while I << 1e-3."""
    return shear_rate * d * np.sqrt(rho / p)


