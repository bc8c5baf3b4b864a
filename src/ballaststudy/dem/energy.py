"""Energies of the current state (compute-like, pure) and dissipated totals."""
import numpy as np

from . import params as P
from .bonds import bond_energy
from .contacts import LC_E, LC_KAPPA


def kinetic(sim):
    """(translational, rotational) kinetic energy of free balls and clumps [J]."""
    b, c = sim.balls, sim.clumps
    free = (b.alive == 1) & (b.clump < 0)
    kt = 0.5 * (b.mass[free] * (b.vel[free] ** 2).sum(1)).sum()
    kr = 0.5 * (b.inertia[free] * b.omega[free] ** 2).sum()
    kt += 0.5 * (c.mass * (c.vel ** 2).sum(1)).sum()
    kr += 0.5 * (c.inertia * c.omega ** 2).sum()
    return float(kt), float(kr)


def gravity_potential(sim):
    """-sum m g.x over free balls and clumps (zero at the origin) [J]."""
    b, c, p = sim.balls, sim.clumps, sim.prm
    g = np.array([p[P.GX], p[P.GY]])
    free = (b.alive == 1) & (b.clump < 0)
    return float(-(b.mass[free] * (b.pos[free] @ g)).sum() - (c.mass * (c.pos @ g)).sum())


def contact_elastic(sim):
    """Strain energy in the linear springs of ball-ball and ball-wall contacts [J]."""
    b, p = sim.balls, sim.prm
    hooke = int(p[P.LAW]) == P.LAW_HOOKE
    t = p[P.THICK]
    pr = sim.pairs
    n = pr.n[0]
    i, j, h = pr.i[:n], pr.j[:n], pr.hist[:n]
    bonded = (pr.bond[:n] >= 0)
    if len(sim.bonds):
        bonded &= sim.bonds.active[np.maximum(pr.bond[:n], 0)] == 1
    dist = np.hypot(*(b.pos[j] - b.pos[i]).T)
    delta = np.where(bonded, 0.0, np.maximum(b.rad[i] + b.rad[j] - dist, 0.0))
    if hooke:
        e = 0.5 * p[P.H_KN] * delta ** 2 + 0.5 * p[P.H_KT] * (h ** 2).sum(1) * (delta > 0)
    else:
        kn = 2 * np.minimum(b.rad[i], b.rad[j]) * t * sim.lc[b.mat[i], b.mat[j], LC_E] / (b.rad[i] + b.rad[j])
        ks = kn / sim.lc[b.mat[i], b.mat[j], LC_KAPPA]
        e = 0.5 * kn * delta ** 2 + 0.5 * h[:, 0] ** 2 / ks * (delta > 0)
    wp = sim.wpairs
    m = wp.n[0]
    i, s, h = wp.i[:m], wp.s[:m], wp.hist[:m]
    seg = sim.walls.seg[s]
    ev = seg[:, 2:] - seg[:, :2]
    u = np.clip(((b.pos[i] - seg[:, :2]) * ev).sum(1) / (ev * ev).sum(1), 0, 1)
    dist = np.hypot(*(b.pos[i] - seg[:, :2] - u[:, None] * ev).T)
    delta = np.maximum(b.rad[i] - dist, 0.0) * (wp.fn[:m] != 0)
    if hooke:
        ew = 0.5 * p[P.H_KN] * delta ** 2 + 0.5 * p[P.H_KT] * (h ** 2).sum(1) * (delta > 0)
    else:
        kn = 2 * t * sim.lc[sim.walls.mat[s], b.mat[i], LC_E]
        ks = kn / sim.lc[sim.walls.mat[s], b.mat[i], LC_KAPPA]
        ew = 0.5 * kn * delta ** 2 + 0.5 * h[:, 0] ** 2 / ks * (delta > 0)
    return float(e.sum() + ew.sum())


def energies(sim):
    """Dict of energies [J]: kinetic (translational, rotational), gravity potential,
    elastic in contacts and in flat joints, and the dissipated totals since the start:
    dashpot, friction (contact slip and broken-element slip), local damping, breakage
    (strain energy released by broken elements); ``wall_work`` = work done by moving walls."""
    kt, kr = kinetic(sim)
    bd = sim.bonds
    eb = bond_energy(sim.balls.pos, bd.i, bd.j, bd.active, bd.rbar, bd.d0, bd.kn, bd.ks,
                     bd.theta, bd.state, bd.fs, sim.prm[P.THICK]) if len(bd) else 0.0
    a = sim.eacc
    return dict(kinetic_translational=kt, kinetic_rotational=kr, kinetic=kt + kr,
                gravity_potential=gravity_potential(sim), elastic_contacts=contact_elastic(sim),
                elastic_bonds=float(eb), dissipated_dashpot=float(a[P.E_DASHPOT]),
                dissipated_friction=float(a[P.E_FRICTION]),
                dissipated_damping=float(a[P.E_LOCAL]),
                dissipated_breakage=float(a[P.E_BREAKAGE]), wall_work=float(a[P.E_WALLS]))
