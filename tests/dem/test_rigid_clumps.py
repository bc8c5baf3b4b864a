"""Rigid stones in the engine (physics spec "Rigid stones that split", R1/R4 for the part
built): balls made clumps in place keep mass, momentum and angular momentum and add no
kinetic energy; the same clump made either way steps bit for bit alike; a clump's critical
timestep is its mass on all its springs (translation) and its moment of inertia on each
contact's stiffness against a turn (rotation); density scaling raises a clump's inertia,
never its weight; a rigid run resumes from a checkpoint bitwise; checkpoints written
before the clumps' inertial columns still load."""
import math

import numpy as np
import pytest

from ballaststudy.dem import ContactMaterial, Simulation

from .generate import random_disks

E, KAPPA, RHO, T = 1e7, 2.5, 2650.0, 1.0


def _moving_groups(seed=3):
    """30 moving, spinning disks in three groups (the stones), gravity off."""
    sim = Simulation(gravity=(0.0, 0.0), domain=(-1, -1, 1, 1))
    sim.set_contact_material(ContactMaterial(E=E, kappa=KAPPA, mu=0.5))
    rng = np.random.default_rng(seed)
    x, y, r, vx, vy = random_disks(30, 0.0, 0.3, 0.01, 0.004, 0.008, seed=seed, vmax=0.5)
    sim.add_balls(x, y, r, RHO, stone_id=np.arange(30) // 10, vx=vx, vy=vy,
                  omega=rng.normal(0.0, 20.0, 30))
    return sim, [np.arange(k, k + 10) for k in (0, 10, 20)]


def _momenta_of_balls(sim, ids):
    b = sim.balls
    m = b.mass[ids]
    p = (m[:, None] * b.vel[ids]).sum(axis=0)
    lz = (b.inertia[ids] * b.omega[ids]
          + m * (b.pos[ids, 0] * b.vel[ids, 1] - b.pos[ids, 1] * b.vel[ids, 0])).sum()
    ke = 0.5 * (m * (b.vel[ids] ** 2).sum(axis=1) + b.inertia[ids] * b.omega[ids] ** 2).sum()
    return m.sum(), p, lz, ke


def _momenta_of_clump(sim, c):
    k = sim.clumps
    m, v, w, (cx, cy) = k.mass[c], k.vel[c], k.omega[c], k.pos[c]
    lz = k.inertia[c] * w + m * (cx * v[1] - cy * v[0])
    ke = 0.5 * (m * (v ** 2).sum() + k.inertia[c] * w ** 2)
    return m, m * v, lz, ke


def test_making_clumps_keeps_mass_and_momenta_and_adds_no_energy():
    sim, groups = _moving_groups()
    before = [_momenta_of_balls(sim, g) for g in groups]
    pos = sim.balls.pos.copy()
    ids = sim.make_clumps(groups)
    assert ids == [0, 1, 2]
    for c, (m, p, lz, ke) in zip(ids, before):
        m2, p2, lz2, ke2 = _momenta_of_clump(sim, c)
        assert m2 == m                                        # the pebbles' own masses, summed
        scale = np.abs(p).max() + 1e-300
        assert np.abs(p2 - p).max() <= 1e-12 * scale, (p, p2)
        assert abs(lz2 - lz) <= 1e-12 * abs(lz), (lz, lz2)
        assert ke2 <= ke * (1 + 1e-12) and ke2 < ke, (ke, ke2)     # rigid: the least energy
    assert np.abs(sim.balls.pos - pos).max() < 1e-15               # the stones do not move
    assert (sim.balls.clump == np.arange(30) // 10).all()


def test_made_clump_steps_like_the_same_clump_added():
    """R4: stones made clumps in place and the same clumps built by add_clump: the same
    trajectory bit for bit (1500 steps: a drop onto a wall, contacts between them)."""
    x, y, r, _, _ = random_disks(24, 0.0, 0.2, 0.05, 0.005, 0.008, seed=5, vmax=0.0)
    groups = [np.arange(k, k + 8) for k in (0, 8, 16)]
    sims = []
    for way in ("made", "added"):
        sim = Simulation(gravity=(0.0, -9.81), damping=0.2, domain=(-0.5, -0.5, 0.7, 0.7))
        sim.set_contact_material(ContactMaterial(E=E, kappa=KAPPA, mu=0.5, beta_n=0.1))
        sim.add_wall([(-0.1, 0.0), (0.3, 0.0)], segments=4)
        if way == "made":
            sim.add_balls(x, y, r, RHO, stone_id=np.arange(24) // 8)
            sim.make_clumps(groups)
        else:
            for k, g in enumerate(groups):
                sim.add_clump(x[g], y[g], r[g], RHO, stone_id=k)
        sim.run(1500)
        sims.append(sim)
    made, added = sims
    assert np.abs(made.clumps.vel).max() > 0.0
    for name in ("pos", "vel", "omega", "theta"):
        assert np.array_equal(getattr(made.clumps, name), getattr(added.clumps, name)), name
    assert np.array_equal(made.balls.pos, added.balls.pos)


def _row_on_a_wall(n, spacing, overlap=1e-5, r=0.005):
    """n pebbles of radius r in a row, pressed ``overlap`` into a flat wall, one clump."""
    sim = Simulation(gravity=(0.0, 0.0), domain=(-1, -1, 1, 1))
    sim.set_contact_material(ContactMaterial(E=E, kappa=KAPPA, mu=0.5))
    sim.add_wall([(-0.5, 0.0), (0.5, 0.0)])
    x = (np.arange(n) - 0.5 * (n - 1)) * spacing
    sim.add_clump(x, np.full(n, r - overlap), np.full(n, r), RHO)
    return sim, x, r


@pytest.mark.parametrize("n", [1, 2, 8])
def test_a_clumps_critical_timestep_is_its_mass_on_all_its_springs(n):
    """Ball-facet springs k_n = 2 t E* (A = 2 R t, L = R), k_s = k_n / kappa*. Translation:
    sqrt(M / (n (k_n + k_s))); rotation about the centre of mass: each contact's normal
    spring at arm x_k, its shear spring at arm R: sqrt(I / (k_n sum x_k^2 + n k_s R^2)).
    The rule before (one pebble's springs against the whole clump) gives sqrt(n) x the
    translational value: unstable for n = 8 under f = 0.8."""
    sim, x, r = _row_on_a_wall(n, spacing=0.006)
    sim.prepare()
    kn = 2.0 * T * E
    ks = kn / KAPPA
    m = RHO * math.pi * r ** 2 * T
    mass, inertia = n * m, n * 0.5 * m * r ** 2 + m * (x ** 2).sum()
    dt_tr = math.sqrt(mass / (n * (kn + ks)))
    dt_rot = math.sqrt(inertia / (kn * (x ** 2).sum() + n * ks * r ** 2))
    assert sim.critical_dt() == pytest.approx(min(dt_tr, dt_rot), rel=1e-12)
    lim = sim.timestep_limit()
    assert lim["body"] == "clump" and lim["clump"] == 0 and lim["pebbles"] == n
    # the vertical mode's exact stability limit 2 / omega, omega^2 = n k_n / M
    assert sim.critical_dt() < 2.0 / math.sqrt(n * kn / mass)
    assert sim.dt == pytest.approx(0.8 * sim.critical_dt(), rel=1e-12)


def test_density_scaling_raises_a_clumps_inertia_not_its_weight():
    """A clump at rest on a wall under gravity, density-scaled at 4 x its dt: its inertial
    mass rises to k_tr (dt / f)^2 while the wall carries its real weight; scaling off gives
    the real inertia back."""
    sim, x, r = _row_on_a_wall(4, spacing=0.006, overlap=1e-7)
    sim.set_gravity((0.0, -9.81))
    sim.set_damping(0.7, clump_alpha=0.7)
    sim.run(2000)
    dt0 = sim.dt
    mass, inertia = float(sim.clumps.mass[0]), float(sim.clumps.inertia[0])
    sim.set_density_scaling(4.0 * dt0)
    sim.run(20000)
    assert sim.dt == 4.0 * dt0
    assert sim.clumps.imass[0] > 10.0 * mass and sim.clumps.iinertia[0] > inertia
    assert sim.clumps.mass[0] == mass
    assert sim.added_inertia() == pytest.approx(sim.clumps.imass[0] / mass - 1.0)
    assert -sim.wall_force()[:, 1].sum() == pytest.approx(mass * 9.81, rel=1e-6)
    assert np.all(np.abs(sim.balls.minv[sim.balls.clump == 0] * sim.clumps.imass[0] - 1) < 1e-15)
    sim.set_density_scaling(None)
    assert sim.clumps.imass[0] == mass and sim.clumps.iinertia[0] == inertia
    assert sim.balls.minv[0] == 1.0 / mass


def _rigid_small_model(small_model):
    sim = small_model(1)
    sim.run(200)
    stones = sim.balls.stone
    sim.make_clumps([np.flatnonzero(stones == s) for s in np.unique(stones[stones >= 0])
                     if (sim.balls.clump[stones == s] < 0).all()])
    return sim


def test_rigid_run_resumes_from_a_checkpoint_bitwise(small_model, tmp_path):
    """Stones made clumps (small complete model: walls, a moving wall, damping): 300 steps,
    a checkpoint, 300 more, against 600 straight; and the same run twice."""
    straight = _rigid_small_model(small_model).run(600)
    again = _rigid_small_model(small_model).run(600)
    part = _rigid_small_model(small_model).run(300)
    part.save_checkpoint(tmp_path / "ck.npz")
    resumed = Simulation.load_checkpoint(tmp_path / "ck.npz").run(300)
    for other in (again, resumed):
        for name in ("pos", "vel", "omega", "theta", "imass"):
            assert np.array_equal(getattr(straight.clumps, name), getattr(other.clumps, name)), name
        assert np.array_equal(straight.balls.pos, other.balls.pos)
    assert len(straight.clumps) == 11 and np.abs(straight.clumps.vel[1:]).max() > 0.0


def test_checkpoint_without_the_inertial_columns_loads(small_model, tmp_path):
    """Assembled specimens saved before clumps had imass / iinertia: real = inertial."""
    sim = small_model(2)
    sim.run(50)
    sim.save_checkpoint(tmp_path / "new.npz")
    with np.load(tmp_path / "new.npz") as z:
        old = {k: z[k] for k in z.files if k not in ("c_imass", "c_iinertia")}
    np.savez(tmp_path / "old.npz", **old)
    back = Simulation.load_checkpoint(tmp_path / "old.npz")
    assert np.array_equal(back.clumps.imass, sim.clumps.mass)
    assert np.array_equal(back.clumps.iinertia, sim.clumps.inertia)
    a, b = sim.run(100), back.run(100)
    assert np.array_equal(a.balls.pos, b.balls.pos)


def test_perturbation_moves_rigid_stones_not_other_clumps(small_model):
    """The chaos probe's draw reaches the rigid stones (their clumps, pebbles with them);
    a clump that is no stone (stone id -1) keeps its velocity."""
    sim = _rigid_small_model(small_model)
    before = sim.clumps.vel.copy()
    sim.perturb_velocities(1e-3, seed=1)
    moved = np.any(sim.clumps.vel != before, axis=1)
    assert moved[1:].all() and not moved[0]          # clump 0: the model's own, no stone
    b, c = sim.balls, sim.clumps
    peb = b.clump == 3
    w, r = c.omega[3], b.pos[peb] - c.pos[3]
    assert np.allclose(b.vel[peb], c.vel[3] + w * np.column_stack([-r[:, 1], r[:, 0]]), atol=1e-15)


def test_inertial_masses_count_a_clump_once(small_model):
    """Per ball, the share of the inertial mass: a free ball's 1/minv, a pebble's share of
    its clump's (by mass); summed over a clump's pebbles: the clump's inertial mass, with
    density scaling raising it."""
    sim = _rigid_small_model(small_model)
    b, c = sim.balls, sim.clumps
    free = b.clump < 0
    assert np.array_equal(sim.inertial_masses()[free], 1.0 / b.minv[free])
    per_clump = np.bincount(b.clump[~free], weights=sim.inertial_masses()[~free], minlength=len(c))
    assert np.allclose(per_clump, c.imass, rtol=1e-12, atol=0.0)
    sim.set_density_scaling(4.0 * sim.dt)
    sim.run(20)
    assert (c.imass > c.mass).any()
    per_clump = np.bincount(b.clump[~free], weights=sim.inertial_masses()[~free], minlength=len(c))
    assert np.allclose(per_clump, c.imass, rtol=1e-12, atol=0.0)
