"""Shared model of the dem tests."""
import numpy as np
import pytest

from ballaststudy.dem import ContactMaterial, FlatJointMaterial, Simulation

from .generate import random_disks

HOOKE = dict(kn=1e6, kt=2e6 / 7, gamma_n=2000.0, gamma_t=1000.0, mu=0.5)


def _small_model(seed, law="pfc", material=None):
    """Small but complete: 80 disks in 10 bonded stones, a free clump, a moving wall,
    damping. ``law``: "pfc", "hooke" or a ContactLaw (then give its ``material``)."""
    kw = dict(law="hooke", dt=2e-5, hooke=HOOKE) if law == "hooke" else dict(law=law)
    sim = Simulation(gravity=(0, -9.81), damping=0.3, domain=(-0.05, -0.05, 0.25, 0.5), **kw)
    if law != "hooke":
        sim.set_contact_material(material or ContactMaterial(E=1e7, mu=0.5, beta_n=0.2,
                                                             beta_s=0.1))
    sim.add_wall([(0, 0.3), (0, 0), (0.2, 0), (0.2, 0.3)], segments=3)
    top = sim.add_wall([(0.0, 0.28), (0.2, 0.28)])
    sim.set_wall_velocity(top, (0.0, -0.2))
    x, y, r, vx, vy = random_disks(80, 0.0, 0.2, 0.01, 0.004, 0.006, seed=seed, vmax=0.2)
    sim.add_balls(x, y, r, 2650.0, stone_id=np.arange(80) // 8, vx=vx, vy=vy)
    sim.install_flat_joints(FlatJointMaterial(E=1e7, sigma_c=2e4, c=2e4, gap_factor=3.0))
    sim.add_clump([0.09, 0.11], [0.2, 0.2], [0.008, 0.008], 2650.0)
    return sim


@pytest.fixture
def small_model():
    """The builder of the small complete model: small_model(seed, law, material)."""
    return _small_model
