"""Settled beds of disks for the GPU batch's tests, and their comparison with the CPU's."""
import numpy as np

from ballaststudy.dem import ContactLaw, ContactMaterial, Simulation

W, RHO = 0.06, 2650.0


# PFC linear law with rolling resistance (every sub-model has history and state)
ROLLING = ContactMaterial(E=1e7, kappa=2.5, mu=0.5, beta_n=0.3, beta_s=0.1, mu_r=0.3,
                          kr_ratio=1.0, eta_r=0.2)


def bed(n, seed, skin=2e-5, wall_speed=0.0, rolling=False, n_elements=1, thickness=1.0):
    """n disks of 4-8 mm settled by the CPU engine in a box of width W (hooke law of
    settle2d, or the PFC law with rolling resistance); a small skin so that the lists are
    rebuilt within a few steps. With ``wall_speed`` the right wall then moves inwards.
    ``thickness`` [m]: the PFC law's and the flat joints' stiffnesses scale with it (the
    hooke law's kn does not), so a batch that dropped it would not agree."""
    rng = np.random.default_rng(seed)
    cols = int(W / 0.0085)
    k = np.arange(n)
    x = (k % cols + 0.5) * 0.0085
    y = (k // cols + 0.5) * 0.0085
    r = rng.uniform(0.002, 0.004, n)
    kw = (dict(law=ContactLaw.pfc(rolling="epsd"), dt=1e-5) if rolling else
          dict(law="hooke", dt=2e-5,
               hooke=dict(kn=1e6, kt=2e6 / 7, gamma_n=800.0, gamma_t=400.0, mu=0.5)))
    sim = Simulation(gravity=(0.0, -9.81), skin=skin, damping=0.1, n_elements=n_elements,
                     thickness=thickness,
                     domain=(-0.01, -0.01, W + 0.01, 0.3), **kw)
    if rolling:
        sim.set_contact_material(ROLLING)
    sim.add_balls(x, y, r, RHO, vx=rng.uniform(-0.3, 0.3, n), vy=rng.uniform(-0.3, 0.3, n))
    sim.add_wall([(0.0, 0.25), (0.0, 0.0), (W, 0.0)], segments=2)
    right = sim.add_wall([(W, 0.0), (W, 0.25)])
    sim.run(16000 if rolling else 8000)
    sim.set_wall_velocity(right, (-wall_speed, 0.0))
    return sim


def assert_same_motion(c, g):
    """Balls (and clumps) of a case as on the CPU within round-off."""
    assert np.abs(c.balls.pos - g.balls.pos).max() < 1e-13
    assert np.abs(c.balls.vel - g.balls.vel).max() < 1e-10
    assert np.abs(c.balls.omega - g.balls.omega).max() < 1e-7
    if len(c.clumps):
        assert np.abs(c.clumps.pos - g.clumps.pos).max() < 1e-13
        assert np.abs(c.clumps.theta - g.clumps.theta).max() < 1e-12
