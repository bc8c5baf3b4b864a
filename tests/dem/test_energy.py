"""Verification case 7: 100 disks in a box, no damping, no friction: energy conserved."""
import numpy as np

from ballaststudy.dem import ContactMaterial, Simulation


def total(sim):
    e = sim.energies()
    return e["kinetic"] + e["gravity_potential"] + e["elastic_contacts"], e


def test_case7_energy_conservation_100_disks():
    rng = np.random.default_rng(7)
    n, w = 100, 0.2
    sim = Simulation(gravity=(0.0, -9.81), damping=0.0, dt_safety=0.1,
                     domain=(-0.05, -0.05, w + 0.05, 0.5))
    sim.set_contact_material(ContactMaterial(E=1.0e7, kappa=2.5, mu=0.0))
    sim.add_wall([(0.0, 0.3), (0.0, 0.0), (w, 0.0), (w, 0.3)])
    col, row = np.arange(n) % 10, np.arange(n) // 10
    sim.add_balls(0.01 + 0.02 * col, 0.01 + 0.02 * row, rng.uniform(0.006, 0.009, n), 2650.0,
                  vx=rng.uniform(-0.5, 0.5, n), vy=rng.uniform(-0.5, 0.5, n))
    e0, _ = total(sim)
    sim.run(100_000)
    e1, parts = total(sim)
    drift = abs(e1 - e0) / abs(e0)
    assert drift < 1e-4, f"relative energy drift {drift:.3e} (E0 {e0:.6g} J, E1 {e1:.6g} J, {parts})"
    assert parts["kinetic"] > 0.01 * e0, "the disks came to rest: nothing was tested"
