"""The batched GPU engine (dem/gpu) under numba's CUDA simulator, against the CPU engine
and against analytical results (physics spec cases 1-2)."""
import copy
import dataclasses
import math

import numpy as np
import pytest

from ballaststudy.dem import ContactMaterial, FlatJointMaterial, Simulation
from ballaststudy.dem.gpu import Batch, BatchError

from .beds import RHO, assert_same_motion, bed

def rows(sim):
    """The CPU lists' history by pair: {(i, j): row} (lists built at other times hold
    other pairs; the touching ones are in both)."""
    pr = sim.pairs
    return {(int(i), int(j)): pr.hist[p] for p, (i, j) in enumerate(zip(pr.i[:pr.n[0]],
                                                                        pr.j[:pr.n[0]]))}


def on_both(cases, steps):
    """(cpu, gpu): copies of ``cases`` advanced ``steps`` steps by each engine."""
    cpu = [copy.deepcopy(s) for s in cases]
    for s in cpu:
        s.run(steps)
    return cpu, batch_run(cases, steps)


def batch_run(sims, steps):
    sims = [copy.deepcopy(s) for s in sims]
    Batch.from_simulations(sims).run(steps).to_simulations(sims)
    return sims


def test_batch_steps_like_the_cpu_engine(beds):
    """Three settled beds (one with a moving wall), 12 steps with a skin that forces
    rebuilds: positions, velocities, spins and wall reactions as on the CPU within
    round-off, and the contacts' shear history carried over the rebuilds."""
    cpu, gpu = on_both(beds, 12)
    for c, g in zip(cpu, gpu):
        assert_same_motion(c, g)
        assert np.allclose(c.walls.force, g.walls.force, rtol=1e-9, atol=1e-9)
        assert np.abs(c.walls.seg - g.walls.seg).max() < 1e-15
        g.run(1)        # the exported lists: the CPU's rebuild carries their history
        c.run(1)
        hc, hg = rows(c), rows(g)
        shear = [k for k, v in hc.items() if np.any(v[:2] != 0.0)]
        assert len(shear) > 30
        for k in shear:
            assert np.allclose(hc[k], hg[k], rtol=1e-6, atol=1e-15)


def test_rolling_resistance_steps_like_the_cpu_engine():
    """The PFC law with rolling resistance (history: shear force, rolling moment; state:
    slip and rolling work): 8 steps of a bed 0.5 m thick as on the CPU within round-off."""
    beds = [bed(60, 4, rolling=True, thickness=0.5)]
    cpu, gpu = on_both(beds, 8)
    col = beds[0].law.history_column("rolling")
    for c, g in zip(cpu, gpu):
        assert_same_motion(c, g)
        g.run(1)
        c.run(1)
        hc, hg = rows(c), rows(g)
        rolled = [k for k, v in hc.items() if v[col] != 0.0]
        assert len(rolled) > 30
        for k in rolled:
            assert np.allclose(hc[k], hg[k], rtol=1e-6, atol=1e-15)


def jointed_bed():
    """Stones of four disks joined by flat joints (3 elements), a bed 0.5 m thick."""
    b = bed(55, 2, n_elements=3, thickness=0.5)
    b.balls.stone[:] = np.arange(len(b.balls)) // 4
    assert b.install_flat_joints(FlatJointMaterial(E=1e7, sigma_c=2e5, c=2e5,
                                                   gap_factor=1.5)) > 15
    return b


def test_density_scaling_steps_like_the_cpu_engine(beds):
    """Density scaling at a fixed dt 10 x the beds' (integrate.critical_dt: inertial
    masses raised at every rebuild so that dt is stable; a bed of flat-jointed stones
    too): the batch raises the masses the CPU does, within round-off, and steps like it.
    Most balls' masses are at least doubled (and a tenth of their moments), so a batch that
    kept the real masses, or left out the walls' or the joints' springs, would fail here."""
    cases = [copy.deepcopy(s) for s in beds[:2]] + [jointed_bed()]
    for s in cases:
        s.set_density_scaling(10.0 * s.dt)
    cpu, gpu = on_both(cases, 12)
    for c, g in zip(cpu, gpu):
        assert np.mean(c.balls.minv < 0.5 / c.balls.mass) > 0.5
        assert np.mean(c.balls.iinv < 0.5 / c.balls.inertia) > 0.1
        assert np.allclose(g.balls.minv, c.balls.minv, rtol=1e-12, atol=0.0)
        assert np.allclose(g.balls.iinv, c.balls.iinv, rtol=1e-12, atol=0.0)
        assert_same_motion(c, g)


def test_resume_from_a_checkpoint_equals_the_run_through(beds, tmp_path):
    """A case written back (to_simulations), checkpointed, loaded and batched again goes
    on bit for bit as the batch that ran straight through."""
    through = batch_run(beds[2:], 10)[0]
    half = batch_run(beds[2:], 5)[0]
    half.save_checkpoint(tmp_path / "case.npz")
    resumed = batch_run([Simulation.load_checkpoint(tmp_path / "case.npz")], 5)[0]
    assert np.array_equal(resumed.balls.pos, through.balls.pos)
    assert np.array_equal(resumed.balls.vel, through.balls.vel)
    assert np.array_equal(resumed.walls.seg, through.walls.seg)


def test_a_batch_equals_its_cases_one_by_one(beds):
    together = batch_run(beds, 8)
    for s, t in zip(beds, together):
        alone = batch_run([s], 8)[0]
        assert np.array_equal(alone.balls.pos, t.balls.pos)
        assert np.array_equal(alone.balls.vel, t.balls.vel)


def collision(wall, beta=0.3, E=1.0e8, R=0.01):
    """A 1 m/s head-on impact (physics spec cases 1-2, PFC linear law, dashpot allowed to
    pull) set up 10 um from contact; returns the simulation and (e, t_c) analytical."""
    m = RHO * math.pi * R ** 2
    mc, kn = (m, 2 * E) if wall else (m / 2, E)
    w0 = math.sqrt(kn / mc)
    e = math.exp(-math.pi * beta / math.sqrt(1 - beta ** 2))
    tc = math.pi / (w0 * math.sqrt(1 - beta ** 2))
    sim = Simulation(gravity=(0, 0), dt=tc / 200, domain=(-1, -1, 1, 1))
    sim.set_contact_material(ContactMaterial(E=E, kappa=2.5, mu=0.5, beta_n=beta,
                                             no_tension=False))
    if wall:
        sim.add_wall([(-0.5, 0.0), (0.5, 0.0)])
        sim.add_balls(0.0, R + 1e-5, R, RHO, vy=-1.0)
    else:
        sim.add_balls([-R - 5e-6, R + 5e-6], [0, 0], [R, R], RHO, vx=[1.0, -1.0])
    return sim, e, tc


def test_impacts_restitution():
    """Cases 1-2 of the physics spec in one batch: the restitution of a disk on a wall
    and of two disks within 1 % of the spring-dashpot's exp(-pi beta / sqrt(1 - beta^2))."""
    (sw, e_w, tc_w), (sp, e_p, tc_p) = collision(True), collision(False)
    steps = int(1.25 * max(tc_w / sw.dt, tc_p / sp.dt))   # contact from ~0.05 t_c to ~1.05 t_c
    batch_run_in_place = Batch.from_simulations([sw, sp])
    batch_run_in_place.run(steps).to_simulations([sw, sp])
    e_wall = sw.balls.vel[0, 1] / 1.0
    e_pair = (sp.balls.vel[1, 0] - sp.balls.vel[0, 0]) / 2.0
    assert abs(e_wall - e_w) < 0.01 * e_w, (e_wall, e_w)
    assert abs(e_pair - e_p) < 0.01 * e_p, (e_pair, e_p)
    assert abs(sp.balls.vel.sum(0)).max() < 1e-12      # momentum of the pair conserved


def test_flat_jointed_stones_step_like_the_cpu_engine():
    """Stones of four disks joined by flat joints (3 elements) in a settled bed 0.5 m
    thick: 12 steps as on the CPU within round-off, joint state included."""
    (c,), (g,) = on_both([jointed_bed()], 12)
    assert_same_motion(c, g)
    for name in ("fn", "fs", "theta", "moment"):
        ref = getattr(c.bonds, name)
        assert np.allclose(getattr(g.bonds, name), ref, rtol=1e-7,
                           atol=1e-9 * np.abs(ref).max()), name


def test_a_flat_jointed_pair_breaks_in_tension_as_on_the_cpu():
    """Physics spec case 8 in the batch: a pair pulled apart at 20 mm/s; its 2 elements
    fail in tension at sigma_c (within one step's increment, 2 %), at the CPU's step and
    place, and apart beyond the installation gap (10 um here) the joint is removed; the
    same when the batch is written back before the break (the log is exported once, at
    the CPU's step)."""
    R, fj = 0.01, FlatJointMaterial(gap_factor=1e-3)
    sim = Simulation(gravity=(0, 0), n_elements=2, dt=1.5e-5, domain=(-1, -1, 1, 1))
    sim.add_balls([0.0, 2 * R], [0.0, 0.0], [R, R], 2950.0, stone_id=0)
    assert sim.install_flat_joints(fj) == 1
    sim.set_ball_velocity([0, 1], vel=(0.0, 0.0), omega=0.0, hold=7)
    sim.set_ball_velocity(1, vel=(2e-2, 0.0))
    cpu = copy.deepcopy(sim)
    cpu.run(150)
    gpu = batch_run([sim], 150)[0]
    log, ref = gpu.breakages(), cpu.breakages()
    assert list(log["mode"]) == ["tension", "tension"]
    assert np.all(log["stress"] >= fj.sigma_c) and np.all(log["stress"] <= 1.02 * fj.sigma_c)
    assert np.array_equal(log["step"], ref["step"]) and np.array_equal(log["elem"], ref["elem"])
    assert np.allclose(log["stress"], ref["stress"], rtol=1e-9)
    assert np.allclose(log["x"], ref["x"], atol=1e-12) and np.allclose(log["y"], ref["y"], atol=1e-12)
    assert gpu.bonds.active[0] == 0 and cpu.bonds.active[0] == 0
    halves = copy.deepcopy(sim)
    batch = Batch.from_simulations([halves])
    for steps in (40, 110):          # the joint breaks at step 51: in the second part
        batch.run(steps).to_simulations([halves])
    split = halves.breakages()
    for key in ("step", "elem", "mode", "stress"):
        assert np.array_equal(split[key], log[key]), key
    assert np.allclose(split["time"], log["time"], rtol=1e-12, atol=0.0)


def test_the_complete_small_model_and_clumps_step_like_the_cpu_engine(small_model, beds):
    """tests/dem's complete small model (flat-jointed stones, a clump, a moving wall,
    damping), a clump of three pebbles landed on a bed, and the same clump held and
    pushed into the bed like the box test's plate: 12 steps as on the CPU within
    round-off, clumps and pebbles included."""
    model = small_model(1, "hooke")
    model.run(300)
    landed = copy.deepcopy(beds[0])
    top = float((landed.balls.pos[:, 1] + landed.balls.rad).max())
    landed.add_clump([0.02, 0.026, 0.032], [top + 0.004] * 3, [0.003] * 3, RHO)
    landed.run(2000)
    pebbles = landed.balls.clump >= 0
    assert np.abs(landed.balls.force[pebbles]).max() > 0.0      # the pebbles touch the bed
    pushed = copy.deepcopy(landed)
    pushed.set_clump_velocity(0, vel=(0.0, -0.02), omega=0.0, held=True)
    cpu, gpu = on_both([model, landed, pushed], 12)
    for c, g in zip(cpu, gpu):
        assert_same_motion(c, g)
        assert np.allclose(c.clumps.force, g.clumps.force, rtol=1e-8, atol=1e-12)
        assert np.allclose(c.clumps.moment, g.clumps.moment, rtol=1e-6, atol=1e-12)
    assert np.allclose(gpu[0].bonds.fn, cpu[0].bonds.fn, rtol=1e-7,
                       atol=1e-9 * np.abs(cpu[0].bonds.fn).max())
    assert np.array_equal(gpu[2].clumps.vel[0], (0.0, -0.02))
    weight = landed.clumps.mass[0] * 9.81        # the bed pushes back on the plate: the
    assert cpu[2].clumps.force[0, 1] + weight > 2 * weight     # net force holds the weight


def test_the_automatic_dt_steps_like_the_cpu_engine(beds):
    """The automatic dt (safety x dt_crit after every rebuild, from the next step on):
    two beds on their real masses, one with a wall moving in (its contacts stiffen the
    list), 40 steps: the same dt at every step as on the CPU (within round-off: the springs
    are summed in another order) and the same motion; the dt did change."""
    cases = [copy.deepcopy(s) for s in (beds[0], beds[2])]
    for s in cases:
        s.set_density_scaling(None)          # back to the automatic dt
    cpu = [copy.deepcopy(s) for s in cases]
    gpu = [copy.deepcopy(s) for s in cases]
    batch = Batch.from_simulations(gpu)
    changed = 0
    for _ in range(40):
        for c in cpu:
            c.run(1)
        batch.run(1).to_simulations(gpu)
        for c, g in zip(cpu, gpu):
            assert g.dt == pytest.approx(c.dt, rel=1e-12)
            assert g.time == pytest.approx(c.time, rel=1e-12)
        changed += cpu[1].dt != cases[1].dt
    assert changed > 0
    for c, g in zip(cpu, gpu):
        assert_same_motion(c, g)


def test_what_the_batch_does_not_hold_is_refused(beds):
    with pytest.raises(BatchError, match="case 1: another contact law"):
        Batch.from_simulations([beds[0], bed(20, 5, rolling=True)])


def test_a_failed_case_is_named(beds):
    s = copy.deepcopy(beds[1])
    s.balls.vel[3] = (2e3, 0.0)          # beyond vmax: the guard trips
    with pytest.raises(BatchError, match="case 1 failed by step 1: NaN, runaway"):
        Batch.from_simulations([beds[0], s]).run(1)


def test_an_export_of_whole_arrays_equals_the_export_case_by_case(small_model, beds):
    """to_simulations reads each case's rows from the device, or (many cases halted at
    once) every array whole, once: both give the same state bit for bit (flat joints,
    clumps, walls, contacts and their history, step and time)."""
    model = small_model(1, "hooke")
    model.run(300)
    sims = [model, copy.deepcopy(beds[0]), copy.deepcopy(beds[2])]
    batch = Batch.from_simulations([copy.deepcopy(s) for s in sims]).run(12)
    cursors = batch._clock_exported.copy(), batch._log_exported.copy()
    out = []
    for whole_from in (len(sims) + 1, 1):       # case by case, then whole arrays
        batch._clock_exported[:], batch._log_exported[:] = (c.copy() for c in cursors)
        batch.whole_export_from = whole_from
        copies = [copy.deepcopy(s) for s in sims]
        batch.to_simulations(copies, [0, 1, 2])
        out.append(copies)
    for a, b in zip(*out):
        assert np.array_equal(a.cnt, b.cnt) and np.array_equal(a.prm, b.prm)
        for part in ("balls", "walls", "clumps", "bonds", "pairs", "wpairs", "log"):
            for f in dataclasses.fields(getattr(a, part)):
                x, y = getattr(getattr(a, part), f.name), getattr(getattr(b, part), f.name)
                assert np.array_equal(x, y), f"{part}.{f.name}"
    assert out[0][0].cnt[0] == sims[0].cnt[0] + 12


def test_rigid_stones_are_refused_in_one_line(small_model):
    """Stones made clumps (the rigid stone model): the batch has neither the per-clump
    timestep nor clump density scaling, so it refuses them instead of stepping them by
    another rule than the CPU's; a clump that is no stone (the plate) is stepped."""
    sim = small_model(1, "hooke")
    sim.make_clumps([np.flatnonzero(sim.balls.stone == 0)])
    with pytest.raises(BatchError, match="case 0: rigid stones .* run them on the cpu"):
        Batch.from_simulations([sim])
