"""What sets the critical timestep (Simulation.timestep_limit): two disks in contact,
radii 5 and 10 mm, one linear contact each (k_n = 2 min(R) t E / (R1 + R2), k_s = k_n /
kappa): the small one limits, by translation (sqrt(m / (k_n + k_s)) < sqrt(I / (k_s
R^2)) = sqrt(m / (2 k_s))), at the engine's dt_crit; its percentiles span the two balls."""
import math

import numpy as np
import pytest

from ballaststudy.dem import ContactMaterial, Simulation

E, KAPPA, RHO, T = 1.0e8, 2.5, 2650.0, 1.0


def test_small_disk_limits_by_translation():
    sim = Simulation(gravity=(0.0, 0.0), domain=(-1, -1, 1, 1), thickness=T)
    sim.set_contact_material(ContactMaterial(E=E, kappa=KAPPA, mu=0.5))
    r1, r2 = 0.005, 0.010
    sim.add_balls([0.0, r1 + r2 - 1e-5], [0.0, 0.0], [r1, r2], RHO)
    sim.run(1)
    lim = sim.timestep_limit()
    kn = 2.0 * r1 * T * E / (r1 + r2)
    ks = kn / KAPPA
    m1, m2 = RHO * math.pi * r1 ** 2 * T, RHO * math.pi * r2 ** 2 * T
    assert lim["ball"] == 0 and lim["springs"] == "translation" and lim["bonds"] == 0
    assert lim["radius"] == r1 and lim["mass"] == pytest.approx(m1, rel=1e-12)
    assert lim["dt_crit"] == pytest.approx(math.sqrt(m1 / (kn + ks)), rel=1e-9)
    assert lim["dt_crit"] == pytest.approx(sim.critical_dt(), rel=1e-12)
    assert lim["percentiles"][0] < lim["percentiles"][2] <= math.sqrt(m2 / (kn + ks)) * (1 + 1e-9)
    assert np.all(np.diff(lim["percentiles"]) >= 0)


def test_scaled_timestep_adds_the_allowed_inertia_to_the_small_disk_only():
    """Density scaling at scaled_timestep(a) raises the small disk's inertial mass to
    k (dt / f)^2 = m1 + a (m1 + m2) (its translation limits, as above; the large disk's
    own dt_crit is still above dt / f), no more: the engine's scaled masses, read back
    after a rebuild, add exactly a of the total; a = 0 gives the automatic dt."""
    sim = Simulation(gravity=(0.0, 0.0), domain=(-1, -1, 1, 1), thickness=T)
    sim.set_contact_material(ContactMaterial(E=E, kappa=KAPPA, mu=0.5))
    r1, r2 = 0.005, 0.010
    sim.add_balls([0.0, r1 + r2 - 1e-5], [0.0, 0.0], [r1, r2], RHO)
    sim.run(1)
    k = 2.0 * r1 * T * E / (r1 + r2) * (1.0 + 1.0 / KAPPA)
    m1, m2 = RHO * math.pi * r1 ** 2 * T, RHO * math.pi * r2 ** 2 * T
    f = 0.8
    assert sim.scaled_timestep(0.0) == pytest.approx(f * math.sqrt(m1 / k), rel=1e-9)
    a = 0.2
    dt = sim.scaled_timestep(a)
    assert dt == pytest.approx(f * math.sqrt((m1 + a * (m1 + m2)) / k), rel=1e-9)
    assert dt / f < math.sqrt(m2 / k)
    sim.set_density_scaling(dt)
    sim.run(1)
    inertial = 1.0 / sim.balls.minv
    assert inertial[1] == pytest.approx(m2, rel=1e-12)
    assert (inertial.sum() - m1 - m2) / (m1 + m2) == pytest.approx(a, rel=1e-6)
