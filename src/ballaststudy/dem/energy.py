"""Energies of the current state (compute-like, pure) and dissipated totals."""
import numpy as np

from . import params as P
from .bonds import bond_energy
from .bound import elastic_energy
from .contacts import pack_kinematics


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
    """Strain energy in the springs (normal, shear, rolling) of ball-ball and ball-wall
    contacts, as the contact law defines it [J]."""
    b = sim.balls.kernel()
    kin = np.empty((len(sim.balls), 8))
    pack_kinematics(b, kin)
    return float(elastic_energy(sim._layout)(sim._run_state(), b, kin, sim.pairs.kernel(),
                                              sim.bonds.active, sim.walls.kernel(),
                                              sim.wpairs.kernel()))


def energies(sim):
    """Dict of energies [J]: kinetic (translational, rotational), gravity potential,
    elastic in contacts and in flat joints, and the dissipated totals since the start:
    dashpot, friction (contact slip and broken-element slip), local damping, rolling
    resistance, breakage (strain energy released by broken elements); ``wall_work`` = work
    done by moving walls."""
    kt, kr = kinetic(sim)
    bd = sim.bonds
    eb = bond_energy(sim.balls.pos, bd.kernel(), sim.prm[P.THICK]) if len(bd) else 0.0
    a = sim.eacc
    return dict(kinetic_translational=kt, kinetic_rotational=kr, kinetic=kt + kr,
                gravity_potential=gravity_potential(sim), elastic_contacts=contact_elastic(sim),
                elastic_bonds=float(eb), dissipated_dashpot=float(a[P.E_DASHPOT]),
                dissipated_friction=float(a[P.E_FRICTION]),
                dissipated_damping=float(a[P.E_LOCAL]),
                dissipated_rolling=float(a[P.E_ROLLING]),
                dissipated_breakage=float(a[P.E_BREAKAGE]), wall_work=float(a[P.E_WALLS]))
