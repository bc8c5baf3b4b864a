"""Rigid stones that split (dem/crushing.py; physics spec R1-R3 and issue 74's checks):
a split keeps mass exactly, momentum and angular momentum to round-off and adds no kinetic
energy; the pieces partition the pebbles on either side of a line through the centre of
mass; sibling pebbles that overlap do not push apart (a split at rest stays at rest, and
without the rule it would not); strengths follow the configured Weibull law (KS) with the
2D size effect; a disk between platens splits when its characteristic stress reaches its
strength, along the loading axis, under either criterion; the deviator criterion sees
confinement (a pebble pressed from two sides against four, exactly); a piece below the fines size leaves with its mass logged;
a run that splits is the same however it is chunked, and resumes from a checkpoint
bitwise."""
import math

import numpy as np
import pytest
from scipy import stats

from ballaststudy.dem import ContactMaterial, Simulation, crushing

R_PEBBLE, RHO = 0.002, 2650.0


def _disk(radius=0.02, spacing=0.95):
    """Pebble centres of a disk stone on a hexagonal lattice whose neighbours overlap
    (spacing < 1 diameter), as a BPM stone's balls do."""
    a = 2 * R_PEBBLE * spacing
    n = int(radius / a) + 2
    pts = [((col + 0.5 * (row % 2)) * a, row * a * math.sqrt(3) / 2)
           for row in range(-n, n + 1) for col in range(-n, n + 1)]
    pts = np.array([p for p in pts if p[0] ** 2 + p[1] ** 2 <= (radius - R_PEBBLE) ** 2])
    return pts


def _stone(vel=(0.0, 0.0), omega=0.0, gravity=(0.0, 0.0), damping=0.0):
    sim = Simulation(gravity=gravity, domain=(-0.2, -0.2, 0.2, 0.2), damping=damping)
    sim.set_contact_material(ContactMaterial(E=1e8, kappa=2.5, mu=0.5))
    p = _disk()
    ids = sim.add_balls(p[:, 0], p[:, 1], np.full(len(p), R_PEBBLE), RHO, stone_id=0)
    c = sim.make_clumps([ids])[0]
    sim.set_clump_velocity(c, vel=vel, omega=omega)
    sim._follow_clumps(ids)
    return sim, c


def _bodies(sim):
    """Mass, momentum, angular momentum about the origin and kinetic energy of the free
    clumps (real masses)."""
    k = sim.clumps
    free = np.flatnonzero(k.held == 0)
    m, v, w, x = k.mass[free], k.vel[free], k.omega[free], k.pos[free]
    lz = (k.inertia[free] * w + m * (x[:, 0] * v[:, 1] - x[:, 1] * v[:, 0])).sum()
    ke = 0.5 * (m * (v ** 2).sum(axis=1) + k.inertia[free] * w ** 2).sum()
    return m.sum(), (m[:, None] * v).sum(axis=0), lz, ke


def _enable(sim, clumps, sigma0=2e6, fines=0.0, every=10, criterion="largest_contact_force"):
    sim.enable_crushing(clumps, sigma0=sigma0, m=5.0, d0=0.04, seed=11, fines_diameter=fines,
                        every=every, criterion=criterion)


def test_a_split_keeps_mass_momenta_and_adds_no_kinetic_energy():
    sim, c = _stone(vel=(0.3, -0.2), omega=7.0)
    _enable(sim, [c])
    m0, p0, l0, e0 = _bodies(sim)
    kept, other, _ = crushing.partition(sim, c, np.array([0.6, 0.8]))
    child = crushing.split_clump(sim, c, other)
    m1, p1, l1, e1 = _bodies(sim)
    assert child == 1 and len(sim.clumps) == 2
    assert m1 == pytest.approx(m0, rel=1e-15)
    assert np.abs(p1 - p0).max() <= 1e-12 * np.abs(p0).max()
    assert abs(l1 - l0) <= 1e-12 * abs(l0)
    assert e1 <= e0 * (1 + 1e-12) and e1 == pytest.approx(e0, rel=1e-12)


def test_the_pieces_partition_the_pebbles_along_a_line_through_the_centre():
    sim, c = _stone()
    b = sim.balls
    peb = np.flatnonzero(b.clump == c)
    centre = sim.clumps.pos[c].copy()
    u = np.array([math.cos(0.3), math.sin(0.3)])
    kept, other, used = crushing.partition(sim, c, u)
    assert np.array_equal(np.sort(np.concatenate([kept, other])), peb)
    assert len(kept) and len(other) and kept.min() == peb.min()
    side = lambda ids: np.sign(used[0] * (b.pos[ids, 1] - centre[1]) - used[1] * (b.pos[ids, 0] - centre[0]))   # noqa: E731
    assert np.array_equal(used, u)
    assert abs(side(kept).sum()) == len(kept) and abs(side(other).sum()) == len(other)
    assert side(kept)[0] == -side(other)[0]
    # a line that leaves every pebble on one side turns 90 deg
    one = crushing.partition(sim, c, np.array([1.0, 0.0]))
    assert len(one[0]) and len(one[1])


@pytest.mark.parametrize("siblings", [True, False])
def test_a_split_at_rest_injects_no_energy(siblings):
    """The stone's pebbles overlap: with the sibling rule the pieces stay at rest; without
    it (lap0 cleared) the overlaps push them apart - the check can fail."""
    sim, c = _stone()
    _enable(sim, [c])
    kept, other, _ = crushing.partition(sim, c, np.array([0.0, 1.0]))
    crushing.split_clump(sim, c, other)
    sim._rebuild()
    crushing.sibling_overlaps(sim, kept, other)
    assert (sim.pairs.lap0[: sim.pairs.n[0]] > 0).sum() > 5      # they do overlap
    if not siblings:
        sim.pairs.lap0[:] = 0.0
    sim.run(500)
    ke = sim.energies()["kinetic"]
    if siblings:
        assert ke == 0.0
    else:
        assert ke > 1e-6


def test_strengths_follow_the_weibull_law_with_its_size_effect():
    sigma0, m, d0 = 3e6, 4.0, 0.04
    u = np.array([crushing.stream_uniform(5, piece, 0) for piece in range(2000)])
    for d in (0.02, 0.04, 0.08):
        s = crushing.weibull_strength(u, d, sigma0, m, d0)
        scale = sigma0 * (d / d0) ** (-2.0 / m)
        assert stats.kstest(s, stats.weibull_min(m, scale=scale).cdf).pvalue > 0.01
        assert stats.kstest(s, stats.weibull_min(m * 1.3, scale=scale).cdf).pvalue < 1e-4
    small, large = (np.median(crushing.weibull_strength(u, d, sigma0, m, d0)) for d in (0.02, 0.08))
    assert small / large == pytest.approx(4.0 ** (2.0 / m), rel=1e-12)     # larger is weaker


def test_the_streams_depend_on_seed_piece_and_generation_only():
    a = crushing.stream_uniform(1, 17, 2)
    assert a == crushing.stream_uniform(1, 17, 2)
    others = {crushing.stream_uniform(*k) for k in [(2, 17, 2), (1, 18, 2), (1, 17, 3)]}
    assert a not in others and len(others) == 3


def _between_platens(sigma0=2e6, fines=0.0, every=10, criterion="largest_contact_force"):
    sim, c = _stone(damping=0.7)
    top = sim.add_wall([(-0.05, 0.0201), (0.05, 0.0201)])
    bottom = sim.add_wall([(0.05, -0.0201), (-0.05, -0.0201)])
    sim.set_wall_velocity(top, vel=(0.0, -0.01))
    sim.set_wall_velocity(bottom, vel=(0.0, 0.01))
    _enable(sim, [c], sigma0=sigma0, fines=fines, every=every, criterion=criterion)
    return sim, c


def _stress(sim, c):
    fmax, s, area = crushing.loads(sim)
    criterion = crushing.CRITERIA.index(sim.crushing_settings()["criterion"])
    return crushing.characteristic_stress(1.0, fmax, s, area, criterion)[c]


def _closed_until_split(sim, c):
    """Close the platens 10 steps at a time until the disk splits: the largest stress at
    the checks before (the kernel's ``peak`` equal to it throughout)."""
    checked = 0.0
    while not len(sim.splits) and sim.step < 40000:
        sim.run(10)
        if not len(sim.splits):
            checked = max(checked, _stress(sim, c))
            assert sim.clumps.peak[c] == checked
    return checked


@pytest.mark.parametrize("criterion", crushing.CRITERIA)
@pytest.mark.parametrize("damage", [0.0, 0.6])
def test_a_disk_between_platens_splits_at_its_strength_along_the_loading_axis(damage, criterion):
    """Undamaged, at its strength; with damage D at strength (1 - D), well below it; not
    before (checked every 10 steps: none missed) and with no overshoot; along the loading
    axis; the pieces start undamaged. Either criterion."""
    sim, c = _between_platens(criterion=criterion)
    sim.clumps.damage[c] = damage
    strength = sim.clumps.strength[c]
    limit = strength * (1.0 - damage)
    checked = _closed_until_split(sim, c)
    log = sim.split_log()
    assert checked < limit and len(log["step"]) == 1 and log["step"][0] % 10 == 0
    assert log["strength"][0] == strength and log["stress"][0] >= limit
    assert log["stress"][0] - limit < limit - checked + 0.05 * limit   # no overshoot
    angle = math.degrees(math.acos(abs(log["uy"][0])))
    assert angle < 5.0, angle
    assert log["n_parent"][0] + log["n_child"][0] == len(_disk())
    assert sim.clumps.gen.tolist() == [1, 1] and sim.clumps.damage.tolist() == [0.0, 0.0]


def _pebble_between_walls(sides):
    """One pebble of radius 2 mm made a clump, pressed 10 um by two platens (``sides``:
    and by two side walls alike), walls at rest: the forces after one step."""
    sim = Simulation(gravity=(0.0, 0.0), domain=(-0.2, -0.2, 0.2, 0.2))
    sim.set_contact_material(ContactMaterial(E=1e8, kappa=2.5, mu=0.5))
    c = sim.make_clumps([sim.add_balls(0.0, 0.0, R_PEBBLE, RHO)])[0]
    h = R_PEBBLE - 1e-5
    walls = [sim.add_wall([(-0.01, h), (0.01, h)]), sim.add_wall([(0.01, -h), (-0.01, -h)])]
    if sides:
        walls += [sim.add_wall([(h, 0.01), (h, -0.01)]), sim.add_wall([(-h, -0.01), (-h, 0.01)])]
    sim.run(1)
    return sim, c, h, float(np.hypot(*sim.wall_force(walls[0]).sum(axis=0)))


def test_the_deviator_sees_confinement_and_the_largest_force_does_not():
    """A pebble pressed by two platens with force F at contact points +-h: S_yy = -2 F h, so
    the deviator is 2 F h / (A t) and F_max / (d t) = F / (d t); confined alike on its
    sides the deviator is 0 (to round-off) and the largest force the same."""
    area, d = math.pi * R_PEBBLE ** 2, 2 * R_PEBBLE
    for sides in (False, True):
        sim, c, h, f = _pebble_between_walls(sides)
        assert f > 0
        fmax, s, a = crushing.loads(sim)
        assert a[c] == pytest.approx(area, rel=1e-14)
        largest, deviator = (crushing.characteristic_stress(1.0, fmax, s, a, k)[c] for k in (0, 1))
        assert largest == pytest.approx(f / d, rel=1e-12)
        if sides:
            assert deviator <= 1e-12 * largest
        else:
            assert deviator == pytest.approx(2 * f * h / area, rel=1e-12)


def test_pieces_below_the_fines_size_leave_with_their_mass_logged():
    sim, c = _between_platens(fines=0.03)    # each half of the 37 mm (pebble-sum) disk is < 30 mm
    sim.add_balls(0.15, 0.15, R_PEBBLE, RHO)     # a bystander: the model is not left empty
    m0 = sim.clumps.mass[c]
    while not len(sim.splits) and sim.step < 40000:
        sim.run(100)
    log = sim.split_log()
    assert len(log["step"]) == 1
    assert (sim.balls.alive[:-1] == 0).all()
    assert log["fines"][0] == pytest.approx(m0, rel=1e-14)
    assert log["m_parent"][0] + log["m_child"][0] == pytest.approx(m0, rel=1e-14)
    assert sim.clumps.held.tolist() == [1, 1] and (sim.clumps.vel == 0).all()


def _run_chunked(chunks, total=30000, path=None):
    sim, c = _between_platens(sigma0=1.5e6, every=7)
    done = 0
    for k in chunks:
        if path is not None and done == total // 2:
            sim.save_checkpoint(path)
            sim = Simulation.load_checkpoint(path)
        sim.run(k)
        done += k
    return sim


def test_a_run_that_splits_is_the_same_however_chunked_and_resumed(tmp_path):
    whole = _run_chunked([30000])
    assert len(whole.splits) > 10          # the disk and its pieces split again and again
    chunked = _run_chunked([1234] * 24 + [384])
    resumed = _run_chunked([15000, 15000], path=tmp_path / "c.npz")
    for other in (chunked, resumed):
        assert np.array_equal(other.balls.pos, whole.balls.pos)
        assert np.array_equal(other.clumps.vel, whole.clumps.vel)
        for k, v in whole.split_log().items():
            assert np.array_equal(other.split_log()[k], v), k


def test_fatigue_damage_is_miners_sum_over_the_cycles_peaks():
    """accumulate_damage: a cycle whose peak stress is r x strength adds r^b above the
    endurance ratio, nothing below it; the sum is capped at 1; the peaks start again."""
    sim, c = _stone()
    _enable(sim, [c])
    s = sim.clumps.strength[c]
    b, endurance, total = 3.0, 0.4, 0.0
    for r in (0.5, 0.3, 0.8, 0.4, 0.6):
        sim.clumps.peak[c] = r * s
        gain = sim.accumulate_damage(b, endurance)
        total += r ** b if r > endurance else 0.0
        assert gain[c] == pytest.approx(r ** b if r > endurance else 0.0, rel=1e-12)
        assert sim.clumps.damage[c] == pytest.approx(total, rel=1e-12) and sim.clumps.peak[c] == 0.0
    sim.clumps.peak[c] = 0.99 * s
    sim.accumulate_damage(1.0, 0.0)
    assert sim.clumps.damage[c] == 1.0


def test_each_stone_material_draws_from_its_own_law(tmp_path):
    """(sigma0, m) per stone material: a hard and a soft disk draw exactly the strength of
    their own law from their streams; a checkpoint written before the soft law existed
    (32 parameters) loads with the one law it ran for both."""
    sim = Simulation(gravity=(0.0, 0.0), domain=(-0.2, -0.2, 0.2, 0.2))
    sim.set_contact_material(ContactMaterial(E=1e8, kappa=2.5, mu=0.5))
    p = _disk()
    clumps = []
    for shift, material in ((-0.05, 0), (0.05, 1)):
        ids = sim.add_balls(p[:, 0] + shift, p[:, 1], np.full(len(p), R_PEBBLE), RHO, stone_id=material,
                            material_id=material)
        clumps.append(sim.make_clumps([ids])[0])
        sim._follow_clumps(ids)
    sim.enable_crushing(clumps, sigma0=[3e6, 2e5], m=[6.0, 2.0], d0=0.04, seed=9, fines_diameter=0.0, every=10)
    b = sim.balls
    for c, (s0, m) in zip(clumps, ((3e6, 6.0), (2e5, 2.0))):
        peb = np.flatnonzero(b.clump == c)
        d = 2.0 * np.sqrt((b.rad[peb] ** 2).sum())
        assert sim.clumps.strength[c] == crushing.weibull_strength(
            crushing.stream_uniform(9, peb.min(), 0), d, s0, m, 0.04)
    assert sim.crushing_settings()["sigma0_Pa"] == [3e6, 2e5]
    path = tmp_path / "old.npz"
    sim.save_checkpoint(path)
    with np.load(path) as z:
        old = {k: z[k] for k in z.files}
    old["s_prm"] = old["s_prm"][:32]
    np.savez(path, **old)
    assert Simulation.load_checkpoint(path).crushing_settings()["weibull_modulus"] == [6.0, 6.0]
