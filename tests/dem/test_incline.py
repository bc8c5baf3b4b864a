"""Verification cases 4-6: disk rolling / slipping on an incline, clump block sliding iff
tan(theta) > mu. The incline is a horizontal wall with gravity tilted by theta."""
import math

import numpy as np

from ballaststudy.dem import ContactMaterial, Simulation

R, RHO, G = 0.01, 2650.0, 9.81


def tilted(theta):
    return (G * math.sin(theta), -G * math.cos(theta))


def disk_acceleration(theta, mu, t_end=0.08):
    sim = Simulation(gravity=tilted(theta), dt=None, domain=(-1, -1, 1, 1))
    sim.set_contact_material(ContactMaterial(E=1.0e8, kappa=2.5, mu=mu, beta_n=0.5, beta_s=0.5))
    sim.add_wall([(-0.5, 0.0), (0.5, 0.0)])
    m = RHO * math.pi * R * R
    d0 = m * G * math.cos(theta) / (2.0e8)       # static overlap: starts at rest on the wall
    sim.add_balls(0.0, R - d0, R, RHO)
    sim.run(int(t_end / 2e-5), callback=None)
    samples = []
    n = 40
    for _ in range(n):
        sim.run(max(1, int(0.002 / sim.dt)))
        samples.append((sim.time, sim.balls.pos[0, 0]))
    t, x = np.array(samples).T
    a = 2 * np.polyfit(t, x, 2)[0]
    return a, sim


def test_case4_rolling_without_slip():
    theta, mu = math.radians(20), 0.5          # mu >= tan(theta)/3 = 0.121
    a, sim = disk_acceleration(theta, mu)
    ref = 2.0 / 3.0 * G * math.sin(theta)
    assert abs(a - ref) <= 0.01 * ref, f"a measured {a:.5f} analytical (2/3) g sin = {ref:.5f}"
    slip = sim.balls.vel[0, 0] + sim.balls.omega[0] * R
    assert abs(slip) < 1e-3 * abs(sim.balls.vel[0, 0]), f"slip velocity {slip:.3e}"


def test_case5_slipping():
    theta, mu = math.radians(20), 0.08         # mu < tan(theta)/3
    a, _ = disk_acceleration(theta, mu)
    ref = G * (math.sin(theta) - mu * math.cos(theta))
    assert abs(a - ref) <= 0.01 * ref, f"a measured {a:.5f} analytical g(sin - mu cos) = {ref:.5f}"


def block_speed(theta, mu):
    """Two-pebble clump resting on the wall; speed along the slope after 0.1 s."""
    sim = Simulation(gravity=tilted(theta), dt=None, domain=(-1, -1, 1, 1), damping=0.0)
    sim.set_contact_material(ContactMaterial(E=1.0e8, kappa=2.5, mu=mu, beta_n=0.5, beta_s=0.5))
    sim.add_wall([(-0.5, 0.0), (0.5, 0.0)])
    m = RHO * math.pi * R * R
    d0 = m * G * math.cos(theta) / 2.0e8
    cid = sim.add_clump([-R, R], [R - d0, R - d0], [R, R], RHO)
    sim.run(5000)
    return sim.clumps.vel[cid, 0], sim.time, sim


def test_case6_clump_block_slides_iff_tan_theta_above_mu():
    mu = 0.5
    v_stick, t, _ = block_speed(math.atan(0.9 * mu), mu)
    theta = math.atan(1.1 * mu)
    v_slide, t, _ = block_speed(theta, mu)
    v_ref = G * (math.sin(theta) - mu * math.cos(theta)) * t
    assert abs(v_stick) < 1e-3 * v_ref, f"tan = 0.9 mu: block moves, v = {v_stick:.3e} m/s"
    assert abs(v_slide - v_ref) < 0.05 * v_ref, \
        f"tan = 1.1 mu: v measured {v_slide:.5f} analytical {v_ref:.5f}"
