"""Verification cases 11-13: settled packing carries its weight, clump plate on two
supports (moment balance), segmented bottom wall sums to the one-piece wall."""
import numpy as np

from ballaststudy.dem import ContactMaterial, Simulation

from .generate import random_disks

G = 9.81


def test_case11_settled_packing_bottom_force_equals_weight():
    w = 0.06
    sim = Simulation(gravity=(0, -G), damping=0.7, domain=(-0.05, -0.05, w + 0.05, 0.5))
    sim.set_contact_material(ContactMaterial(E=1e7, mu=0.5, beta_n=0.2))
    sim.set_contact_material(ContactMaterial(E=1e7, mu=0.0), 1, 0)    # frictionless sides
    sim.add_wall([(0, 0), (w, 0)])
    left = sim.add_wall([(0, 0.3), (0, 0)], material_id=1)
    right = sim.add_wall([(w, 0), (w, 0.3)], material_id=1)
    x, y, r, _, _ = random_disks(40, 0, w, 0.0, 0.004, 0.006, seed=11)
    sim.add_balls(x, y, r, 2650.0)
    sim.run(150_000, callback=lambda s: s.energies()["kinetic"] < 1e-20, every=2000)
    assert sim.energies()["kinetic"] < 1e-20, "packing did not settle"
    weight = (sim.balls.mass * G).sum()
    fy = sim.wall_force()[0, 1]
    side_fy = sim.wall_force(np.r_[left, right])[:, 1].sum()
    assert abs(side_fy) < 1e-9 * weight, f"frictionless side walls carry {side_fy} N"
    assert abs(-fy - weight) <= 0.005 * weight, \
        f"bottom wall force {-fy:.6f} N vs weight {weight:.6f} N"


def test_case12_clump_plate_on_two_supports():
    """Free plate (clump of 21 touching pebbles) on two short wall supports under its
    weight and an off-centre load F: reactions from the moment balance."""
    r, nr, F = 0.01, 21, 50.0
    sim = Simulation(gravity=(0, -G), damping=0.7, domain=(-1, -1, 1, 1))
    sim.set_contact_material(ContactMaterial(E=1e8, mu=0.5, beta_n=0.3))
    xs = 2 * r * (np.arange(nr) - nr // 2)
    xa, xb = xs[3], xs[-5]                       # support under pebbles 3 and 16
    sa = sim.add_wall([(xa - 0.3 * r, 0.0), (xa + 0.3 * r, 0.0)])
    sb = sim.add_wall([(xb - 0.3 * r, 0.0), (xb + 0.3 * r, 0.0)])
    cid = sim.add_clump(xs, np.full(nr, r), np.full(nr, r), 2650.0)
    first = int(np.nonzero(sim.balls.clump == cid)[0][0])
    k_load = 12
    sim.apply_force(first + k_load, (0.0, -F))
    sim.run(40_000, callback=lambda s: abs(s.clumps.vel[cid]).max() < 1e-10, every=1000)
    wgt = sim.clumps.mass[cid] * G
    xg, xf = sim.clumps.pos[cid, 0], sim.balls.pos[first + k_load, 0]
    rb = (wgt * (xg - xa) + F * (xf - xa)) / (xb - xa)
    ra = wgt + F - rb
    got_a = -sim.wall_force(sa)[:, 1].sum()
    got_b = -sim.wall_force(sb)[:, 1].sum()
    for name, got, ref in (("R_a", got_a, ra), ("R_b", got_b, rb)):
        assert abs(got - ref) <= 0.01 * ref, f"{name} measured {got:.5f} N, moment balance {ref:.5f} N"


def test_case13_segmented_bottom_wall_sums_to_whole():
    """A row of disks pressed onto the bottom (some straddling or exactly on a joint):
    the 8 segment forces sum to the force on the one-segment wall."""
    rng = np.random.default_rng(13)
    # x = 0.024 straddles the joint at 0.025, x = 0.1 sits exactly on a joint
    x = np.array([0.008, 0.024, 0.040, 0.056, 0.072, 0.086, 0.1, 0.116, 0.132, 0.148,
                  0.164, 0.180])
    r = rng.uniform(0.006, 0.0068, len(x))                 # gaps >= 0.4 mm

    def model(segments):
        sim = Simulation(gravity=(0, -1000.0), damping=0.0, dt=2e-6,
                         domain=(-0.05, -0.05, 0.25, 0.3))
        sim.set_contact_material(ContactMaterial(E=1e8, mu=0.5, beta_n=0.1))
        ids = sim.add_wall([(0.0, 0.0), (0.2, 0.0)], segments=segments)
        sim.add_balls(x, r - 2e-6, r, 2650.0, vx=rng_v)
        sim.run(300)
        return sim, ids
    rng_v = np.random.default_rng(5).uniform(-0.1, 0.1, len(x))
    one, a = model(1)
    seg, b = model(8)
    whole = one.wall_force(a)[0]
    parts = seg.wall_force(b)
    total = parts.sum(axis=0)
    assert np.count_nonzero(parts[:, 1]) >= 6, f"too few loaded segments: {parts[:, 1]}"
    rel = np.abs(total - whole).max() / np.abs(whole).max()
    assert rel <= 1e-12, f"sum of 8 segments {total} vs one segment {whole} (rel {rel:.2e})"
    # and the resultant equals the sum of the ball-wall contact forces (on the balls)
    c = seg.contact_list()
    w = c["j"] < 0
    on_balls = np.array([c["fx"][w].sum(), c["fy"][w].sum()])
    assert np.allclose(-on_balls, total, rtol=1e-12, atol=0)
