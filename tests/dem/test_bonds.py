"""Verification cases 8-10: flat joints in tension, in shear (with/without compression),
and a bonded chain cantilever vs the discrete beam formula."""
import math

import numpy as np
import pytest

from ballaststudy.dem import FlatJointMaterial, Simulation

R, RHO = 0.01, 2950.0


def pair(fj, n_elements=1, gap=0.0):
    """Two balls of one stone, ball 0 held, ball 1 velocity-controlled (all dofs)."""
    sim = Simulation(gravity=(0, 0), n_elements=n_elements, domain=(-1, -1, 1, 1))
    sim.add_balls([0.0, 2 * R + gap], [0.0, 0.0], [R, R], RHO, stone_id=0)
    assert sim.install_flat_joints(fj) == 1
    sim.set_ball_velocity([0, 1], vel=(0.0, 0.0), omega=0.0, hold=7)
    return sim


def pull_until_break(sim, vel, per=1):
    """Move ball 1 at ``vel``; return (gap history, bond normal-force history)."""
    rec = []

    def probe(s):
        rec.append((s.balls.pos[1, 0] - 2 * R, s.bonds.fn[0].sum(), s.bonds.fs[0].sum(),
                    int(s.log.n[0])))
        return s.log.n[0] > 0
    sim.set_ball_velocity(1, vel=vel)
    sim.run(200_000, callback=probe, every=per)
    return np.array(rec)


def test_case8_tension_slope_and_strength():
    fj = FlatJointMaterial()                    # Table 4.2 hard rock
    for ne in (1, 3):
        sim = pair(fj, n_elements=ne)
        rec = pull_until_break(sim, (2e-3, 0.0))
        area = 2 * R * 1.0
        kn_a = fj.E / (2 * R) * area            # k_n A with k_n = E*/L, L = R1 + R2
        pre = rec[rec[:, 3] == 0]
        slope = np.polyfit(pre[:, 0], pre[:, 1], 1)[0]
        assert abs(slope - kn_a) <= 0.01 * kn_a, f"N={ne}: slope measured {slope:.5e} analytical k_n A {kn_a:.5e}"
        f_break = pre[-1, 1] + (rec[-1, 0] - pre[-1, 0]) * kn_a   # force at the breaking step
        ref = fj.sigma_c * area
        assert abs(f_break - ref) <= 0.01 * ref, f"N={ne}: breaks at {f_break:.5e} N, analytical sigma_c A {ref:.5e} N"
        log = sim.breakages()
        assert len(log["mode"]) == ne and set(log["mode"]) == {"tension"}, f"modes {log['mode']}"
        assert np.all(log["stress"] >= fj.sigma_c) and np.all(log["stress"] <= 1.01 * fj.sigma_c)
        assert np.all(log["i"] == 0) and np.all(log["j"] == 1) and np.all(log["stone"] == 0)
        # broken, still closed: no tension any more, interface removed once apart > g_i
        sim.run(2000)
        assert sim.bonds.fn[0].sum() == 0.0


def shear_until_break(fj, compress):
    sim = pair(fj)
    area = 2 * R
    if compress:       # push ball 1 in to a compressive stress, then hold the distance
        sim.set_ball_velocity(1, vel=(-1e-3, 0.0))
        target = 0.5 * fj.c / (fj.E / (2 * R))
        sim.run(10_000, callback=lambda s: s.balls.pos[1, 0] - 2 * R <= -target, every=1)
    rec = pull_until_break(sim, (0.0, 5e-3))
    sig = sim.bonds.fn[0, 0] / area              # normal stress at failure (tension +)
    log = sim.breakages()
    return rec, sig, log, area


def test_case9_shear_strength_with_and_without_compression():
    for phi, compress in ((0.0, False), (30.0, True), (0.0, True)):
        fj = FlatJointMaterial(phi_deg=phi)
        rec, sig, log, area = shear_until_break(fj, compress)
        tau_c = fj.c - sig * math.tan(math.radians(phi))
        assert list(log["mode"]) == ["shear"], f"phi={phi}: modes {log['mode']}"
        tau = log["stress"][0]
        assert abs(tau - tau_c) <= 0.01 * tau_c, \
            f"phi={phi} compress={compress}: tau at failure {tau:.5e} Pa, analytical c - sigma tan(phi) {tau_c:.5e} Pa (sigma {sig:.4e})"
        if compress and phi > 0:
            assert tau > 1.05 * fj.c, "compression did not raise the shear strength"
        f_s = abs(rec[-2, 2])                    # shear force one step before failure
        assert abs(f_s - tau_c * area) <= 0.01 * tau_c * area, f"F_s {f_s:.5e} vs {(tau_c * area):.5e}"


def test_case10_cantilever_chain():
    """n+1 equal disks, first held, small tip load F: delta = F sum s_j^2 / k_theta +
    n F / (k_s A), k_theta = k_n t (2 Rbar)^3 / 12."""
    n, F = 4, 1.0
    fj = FlatJointMaterial(E=1.0e8, kappa=2.5)
    sim = Simulation(gravity=(0, 0), damping=0.7, domain=(-1, -1, 1, 1))
    x = 2 * R * np.arange(n + 1)
    sim.add_balls(x, np.zeros(n + 1), np.full(n + 1, R), RHO, stone_id=0)
    assert sim.install_flat_joints(fj) == n
    sim.set_ball_velocity(0, vel=(0, 0), omega=0.0, hold=7)
    sim.apply_force(n, (0.0, -F))
    kn = fj.E / (2 * R)
    area = 2 * R
    k_theta = kn * 1.0 * (2 * R) ** 3 / 12
    s = 2 * R * n - (2 * np.arange(1, n + 1) - 1) * R
    ref = F * (s ** 2).sum() / k_theta + n * F / (kn / fj.kappa * area)
    sim.run(200_000, callback=lambda s: np.abs(s.balls.vel).max() < 1e-9 * ref / s.dt, every=2000)
    delta = -sim.balls.pos[n, 1]
    assert abs(delta - ref) <= 0.02 * ref, f"tip deflection measured {delta:.5e} m analytical {ref:.5e} m"


def test_fragments_follow_intact_bonds_and_deleted_balls():
    """One meaning of an intact bond (active, >= 1 intact element) and of a fragment."""
    sim = Simulation(gravity=(0.0, 0.0), domain=(-1, -1, 1, 1))
    sim.add_balls([0.0, 0.02, 0.1, 0.12], [0.0] * 4, 0.01, 2650.0, stone_id=[0, 0, 1, 1])
    assert sim.install_flat_joints(FlatJointMaterial()) == 2
    assert sim.intact_bonds().tolist() == [True, True]
    assert sim.fragments().tolist() == [0, 0, 1, 1]
    sim.bonds.state[0, :] = 0                     # every element of the first bond broken
    assert sim.intact_bonds().tolist() == [False, True]
    assert sim.fragments().tolist() == [0, 1, 2, 2]
    sim.delete_balls([3])                         # its bond goes with it
    assert sim.intact_bonds().tolist() == [False, False]
    assert sim.fragments().tolist() == [0, 1, 2, -1]
    assert sim.fragments(2).tolist() == [0, 1]


def test_a_flat_jointed_pair_reports_no_contact_force():
    """Two balls pressed on each other, then bonded as they are (the joint at rest): the
    contact list has no ball-ball contact any more. The contact loop skips a bonded pair,
    so its list entry kept the force from before the bond and reported it."""
    fj = FlatJointMaterial(E=1e8, kappa=2.0, sigma_c=1e9, c=1e9, gap_factor=0.4)
    sim = Simulation(gravity=(0, 0), domain=(-1, -1, 1, 1))
    sim.add_balls([0.0, 2 * R - 1e-4], [0.0, 0.0], [R, R], RHO, stone_id=0)
    sim.set_ball_velocity([0, 1], vel=(0.0, 0.0), omega=0.0, hold=7)
    sim.run(5)
    assert (sim.contact_list()["j"] >= 0).sum() == 1          # pressed: a contact force
    assert sim.install_flat_joints(fj) == 1
    sim.run(5)
    assert (sim.contact_list()["j"] >= 0).sum() == 0
    assert sim.bonds.active[0] == 1 and sim.bonds.fn[0].sum() == 0.0


def _listed(sim):
    n = sim.pairs.n[0]
    return list(zip(sim.pairs.i[:n].tolist(), sim.pairs.j[:n].tolist()))


def test_a_removed_joint_becomes_a_contact_at_the_next_step():
    """The Verlet list leaves flat-jointed pairs out (the joint replaces the contact); the
    step after the interface is removed the pair is listed again, and pressed back together
    it carries the same contact force as a pair that was never bonded (same overlap)."""
    fj = FlatJointMaterial(E=1e8, sigma_c=1e5, c=1e9, gap_factor=0.1)
    sim = pair(fj)
    sim.run(2)
    assert _listed(sim) == []
    sim.set_ball_velocity(1, vel=(0.05, 0.0))
    sim.run(200_000, callback=lambda s: s.bonds.active[0] == 0, every=1)
    assert sim.bonds.active[0] == 0 and sim.n_breakages == 1
    sim.run(1)
    assert _listed(sim) == [(0, 1)]
    sim.set_ball_velocity(1, vel=(-0.05, 0.0))
    sim.run(200_000, callback=lambda s: s.balls.pos[1, 0] < 2 * R - 1e-5, every=1)
    fresh = Simulation(gravity=(0, 0), domain=(-1, -1, 1, 1))
    fresh.add_balls(sim.balls.pos[:, 0].copy(), [0.0, 0.0], [R, R], RHO, stone_id=0)
    fresh.set_ball_velocity([0, 1], vel=(0.0, 0.0), omega=0.0, hold=7)
    fresh.run(1)
    cl = sim.contact_list()
    assert (cl["j"] >= 0).sum() == 1 and cl["fx"][0] > 0          # j pushed away from i
    assert abs(sim.pairs.fn[0] - fresh.pairs.fn[0]) <= 1e-9 * fresh.pairs.fn[0]


def test_critical_timestep_counts_the_contact_springs_of_a_flat_jointed_pair():
    """Density scaling raises each inertial mass to k_tr (dt/f)^2, so 1/(minv (dt/f)^2)
    reads k_tr back: for a bonded pair it is the contact's (as in an unbonded twin: the
    list leaves the bonded pair out, the timestep must not) plus the joint's (k_n + k_s) A."""
    fj = FlatJointMaterial(E=1e8, kappa=2.0, sigma_c=1e9, c=1e9)
    dt = 1e-3
    k_tr = []
    for bonded in (False, True):
        sim = Simulation(gravity=(0, 0), domain=(-1, -1, 1, 1), dt=dt, dt_safety=0.8,
                         density_scaling=True)
        sim.add_balls([0.0, 2 * R - 1e-6], [0.0, 0.0], [R, R], RHO, stone_id=0)
        if bonded:
            assert sim.install_flat_joints(fj) == 1
        sim.run(1)
        s2 = (dt / 0.8) ** 2
        k_tr.append(1.0 / (sim.balls.minv[0] * s2))
    bd = sim.bonds
    joint = (bd.kn[0] + bd.ks[0]) * 2 * bd.rbar[0] * sim.thickness
    assert k_tr[1] == pytest.approx(k_tr[0] + joint, rel=1e-9)
    assert k_tr[0] > 0.1 * joint          # the contact's share is not negligible here


def _three_bonded_pairs():
    """Stones 0, 1, 2 of two balls each (bonds 0, 1, 2); stone 2 pulled until it breaks."""
    sim = Simulation(gravity=(0, 0), domain=(-1, -1, 1, 1))
    x = [0.0, 2 * R, 0.1, 0.1 + 2 * R, 0.2, 0.2 + 2 * R]
    sim.add_balls(x, [0.0] * 6, [R] * 6, RHO, stone_id=[0, 0, 1, 1, 2, 2])
    assert sim.install_flat_joints(FlatJointMaterial(sigma_c=1e5)) == 3
    sim.set_ball_velocity([2, 3, 4, 5], vel=(0.0, 0.0), omega=0.0, hold=7)
    sim.set_ball_velocity(5, vel=(2e-3, 0.0))
    sim.run(200_000, callback=lambda s: s.log.n[0] > 0, every=1)
    assert sim.breakages()["bond"].tolist() == [2]
    return sim


def test_dropping_deleted_balls_bonds_changes_nothing_but_the_indices():
    """The bonds of deleted balls taken out of the arrays: the others keep their order and
    values, the breakage log points at the same bond under its new index (-1 once it is
    taken out too), and the run goes on bit for bit as with the bonds left in."""
    kept, dropped = _three_bonded_pairs(), _three_bonded_pairs()
    for sim in (kept, dropped):
        sim.delete_balls([0])
        sim.set_ball_velocity(1, vel=(1e-3, 1e-3))
    before = {k: v.copy() for k, v in dropped.bond_list().items()}
    assert dropped.drop_deleted_bonds() == 1
    after = dropped.bond_list()
    for k in before:
        np.testing.assert_array_equal(after[k], before[k][1:])
    log = dropped.breakages()
    assert log["bond"].tolist() == [1] and dropped.bonds.i[1] == log["i"][0] == 4
    for sim in (kept, dropped):
        sim.run(500)
    np.testing.assert_array_equal(kept.balls.pos, dropped.balls.pos)
    np.testing.assert_array_equal(kept.bonds.fn[1:], dropped.bonds.fn)
    dropped.delete_balls([5])
    assert dropped.drop_deleted_bonds() == 1 and dropped.breakages()["bond"].tolist() == [-1]
    assert dropped.drop_deleted_bonds() == 0


def test_dropping_bonds_renumbers_the_verlet_lists_bond_ids():
    """A listed pair keeps pointing at its own bond (a removed joint's pair is in the list
    as a contact, its bond id after the dropped one): the energies read it before any
    rebuild."""
    sim = _three_bonded_pairs()
    sim.bonds.active[2] = 0            # stone 2's joint removed: its pair becomes a contact
    sim._touch()
    sim.run(1)
    pr, bd = sim.pairs, sim.bonds
    assert pr.bond[: pr.n[0]].tolist() == [2]
    sim.delete_balls([0])
    energy = sim.energies()
    assert sim.drop_deleted_bonds() == 1
    assert pr.bond[: pr.n[0]].tolist() == [1] and (bd.i[1], bd.j[1]) == (pr.i[0], pr.j[0]) == (4, 5)
    assert sim.energies() == energy


@pytest.mark.parametrize("n_elements", [1, 3])
def test_a_joint_pushes_its_balls_before_and_after_its_elements_break(n_elements):
    """The joint's force reaches both balls, equal and opposite along the line of centres,
    on the lean path (all elements intact) and on the full one (elements broken, the
    interface still pressed): F on ball 1 = -sum F_n (tension positive) along +x."""
    fj = FlatJointMaterial()
    sim = pair(fj, n_elements=n_elements)
    sim.set_ball_velocity(1, vel=(-1e-4, 0.0))        # press: intact, compressed
    sim.run(50)
    fn = sim.bonds.fn[0].sum()
    assert fn < 0.0 and (sim.bonds.state[0] == 1).all()
    assert sim.balls.force[1, 0] == pytest.approx(-fn, rel=1e-12)
    assert sim.balls.force[0, 0] == pytest.approx(fn, rel=1e-12)
    pull_until_break(sim, (2e-3, 0.0))                # every element breaks in tension
    sim.set_ball_velocity(1, vel=(0.0, 0.0))
    sim.run(2000)
    assert (sim.bonds.state[0] == 0).all() and sim.bonds.active[0] == 1
    sim.set_ball_velocity(1, vel=(-2e-3, 0.0))        # pressed back together: compression only
    sim.run(4000, callback=lambda s: s.bonds.fn[0].sum() < -1.0, every=1)
    fn = sim.bonds.fn[0].sum()
    assert fn < -1.0
    assert sim.balls.force[1, 0] == pytest.approx(-fn, rel=1e-12)
    assert sim.balls.force[0, 0] == pytest.approx(fn, rel=1e-12)
    assert abs(sim.balls.force[1, 1]) <= 1e-9 * abs(fn)
