"""Buried pebbles (clumps.buried, Simulation.bury): a pebble no body from outside its
clump can touch is found where the geometry says (a ring whose gaps are narrower than the
probe hides its centre; a ring opened wider does not), the kernel leaves buried pebbles
out of its lists and its per-step placement without changing a run by a bit (a bed of
stones landing on a floor, buried against none), and a split uncovers the pebbles on its
new faces."""
import math

import numpy as np
import pytest

from ballaststudy.dem import ContactMaterial, Simulation, clumps, crushing

R, RHO = 0.002, 2650.0


def _ring(gap, missing=0, n=12):
    """A centre pebble in a ring of ``n`` pebbles of radius R whose neighbours' surfaces
    are ``gap`` apart (``missing`` of them left out): centres (x, y), radii."""
    ring = (2 * R + gap) / (2 * math.sin(math.pi / n))   # exact: the chord is 2R + gap
    a = 2 * math.pi * np.arange(missing, n) / n
    x = np.r_[0.0, ring * np.cos(a)]
    y = np.r_[0.0, ring * np.sin(a)]
    return x, y, np.full(len(x), R)


@pytest.mark.parametrize("gap, missing, hidden", [
    (0.1 * R, 0, True),
    (0.6 * R, 0, True),      # a probe of R / 2 (R wide) passes gaps of R and more; the raster
    (1.05 * R, 0, False),    # errs towards "passes" by 2 h = R / 4: hidden below 0.75 R
    (1.5 * R, 0, False),     # (and the ring leaves room inside to reach the centre)
    (0.1 * R, 1, False),     # closed but for one pebble left out
])
def test_a_ring_hides_its_centre_from_a_probe_wider_than_its_gaps(gap, missing, hidden):
    x, y, r = _ring(gap, missing)
    hid = clumps.buried(x, y, r, probe=0.5 * R)
    assert bool(hid[0]) == hidden
    assert not hid[1:].any()                          # the ring's pebbles face outside


def _lattice_disk(radius=0.02, spacing=0.95):
    a = 2 * R * spacing
    n = int(radius / a) + 2
    pts = np.array([((c + 0.5 * (row % 2)) * a, row * a * math.sqrt(3) / 2)
                    for row in range(-n, n + 1) for c in range(-n, n + 1)])
    return pts[np.hypot(*pts.T) <= radius - R]


def _bed(bury):
    """Six lattice-disk stones dropped on a floor and onto each other (gravity, damping)."""
    sim = Simulation(gravity=(0.0, -9.81), domain=(-0.3, -0.05, 0.3, 0.6), damping=0.3)
    sim.set_contact_material(ContactMaterial(E=1e8, kappa=2.5, mu=0.5))
    sim.add_wall([(-0.3, 0.0), (0.3, 0.0)])
    p = _lattice_disk()
    groups = []
    for k in range(6):
        ids = sim.add_balls(p[:, 0] + 0.03 * (k % 3) - 0.03 + 0.004 * k, p[:, 1] + 0.03 + 0.045 * k,
                            np.full(len(p), R), RHO, stone_id=k)
        groups.append(ids)
    cl = sim.make_clumps(groups)
    n = sim.bury(cl) if bury else 0
    return sim, n


def test_buried_pebbles_change_nothing_in_a_run():
    """Lists without them and their placement only where the state is read: the same run
    bit for bit (they can touch nothing), with the lattice disks' inner pebbles buried
    (their pebbles overlap: two thirds of them; ~30 % of a BPM stone's)."""
    runs = []
    for bury in (True, False):
        sim, n = _bed(bury)
        for _ in range(4):
            sim.run(5000)
        runs.append((sim, n))
    (a, n), (b, _) = runs
    assert 0.5 * len(a.balls) < n < 0.8 * len(a.balls)
    assert a.pairs.n[0] > 3 and a.clumps.pos[:, 1].max() < 0.06     # landed, stones on stones
    assert np.array_equal(a.balls.pos, b.balls.pos) and np.array_equal(a.clumps.vel, b.clumps.vel)
    assert np.array_equal(a.clumps.pos, b.clumps.pos) and np.array_equal(a.balls.force, b.balls.force)


def test_a_split_uncovers_the_pebbles_on_its_new_faces():
    sim = Simulation(gravity=(0.0, 0.0), domain=(-0.2, -0.2, 0.2, 0.2))
    sim.set_contact_material(ContactMaterial(E=1e8, kappa=2.5, mu=0.5))
    p = _lattice_disk()
    c = sim.make_clumps([sim.add_balls(p[:, 0], p[:, 1], np.full(len(p), R), RHO, stone_id=0)])[0]
    sim.enable_crushing([c], sigma0=2e6, m=5.0, d0=0.04, seed=1, fines_diameter=0.0, every=10)
    before = sim.bury([c])
    assert before > 0
    kept, other, _ = crushing.partition(sim, c, np.array([0.0, 1.0]))
    child = crushing.split_clump(sim, c, other)
    b = sim.balls
    for piece in (kept, other):
        fresh = clumps.buried(b.pos[piece, 0], b.pos[piece, 1], b.rad[piece], 0.5 * R)
        assert np.array_equal(b.buried[piece] == 1, fresh)
    woken = (b.buried == 0) & (np.abs(b.pos[:, 0]) < 2 * R)     # along the split line x = 0
    assert woken.sum() > 4 and int(b.buried.sum()) < before and child == 1
