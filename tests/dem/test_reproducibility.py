"""Cases 14-15 (bitwise checkpoint restart, seeds) and the run guards."""
import numpy as np
import pytest

from ballaststudy.dem import Simulation, SimulationError


STATE = ("pos", "vel", "omega", "force", "moment")


def snapshot(sim):
    b = sim.balls
    return [getattr(b, k).copy() for k in STATE] + [sim.walls.force.copy(), sim.clumps.pos.copy(),
                                                     sim.bonds.state.copy(), sim.log.n.copy()]


@pytest.mark.parametrize("law", ["pfc", "hooke"])
def test_case14_checkpoint_restart_is_bitwise(tmp_path, law, small_model):
    ref = small_model(1, law)
    ref.run(1500, callback=lambda s: None, every=500)
    path = tmp_path / "ck.npz"
    ref.save_checkpoint(path)
    ref.run(1500)
    again = Simulation.load_checkpoint(path)
    assert again.step == 1500
    again.run(1500)
    assert ref.step == again.step == 3000
    assert len(ref.bonds) > 10, "no bonds installed: restart of bond state not tested"
    for k, (a, b) in enumerate(zip(snapshot(ref), snapshot(again))):
        assert np.array_equal(a, b), f"state item {k} differs after restart"
    assert ref.energies() == again.energies()


def test_case15_seeds(small_model):
    a, b, c = small_model(7), small_model(7), small_model(8)
    for s in (a, b, c):
        s.run(800)
    assert all(np.array_equal(u, v) for u, v in zip(snapshot(a), snapshot(b))), "same seed differs"
    assert not np.array_equal(a.balls.pos, c.balls.pos), "different seeds gave the same state"


def test_guards_stop_with_clear_message_and_checkpoint_stays_usable(tmp_path, small_model):
    sim = small_model(3)
    sim.run(200)
    path = tmp_path / "last.npz"
    sim.save_checkpoint(path)
    sim.balls.vel[5] = (np.nan, 0.0)
    with pytest.raises(SimulationError, match=r"NaN/Inf.*step 201.*offending balls: \[.*\b5\b"):
        sim.run(100)
    sim = Simulation.load_checkpoint(path)
    sim.balls.vel[9] = (0.0, 5e3)
    with pytest.raises(SimulationError, match=r"runaway velocity.*ball 9"):
        sim.run(100)
    sim = Simulation.load_checkpoint(path)
    sim.balls.pos[12] = (0.3, 0.1)
    with pytest.raises(SimulationError, match=r"left the domain.*ball 12"):
        sim.run(100)
    ok = Simulation.load_checkpoint(path)
    ok.run(100)
    assert ok.step == 300


def test_callbacks_delete_balls_and_scale_bonds(small_model):
    sim = small_model(4)
    seen = []

    def rig(s):
        seen.append(s.step)
        if s.step == 100:
            s.delete_balls([0, 1, 2])
            s.scale_bond_strength(2.0)
            s.set_damping(0.5)
        return s.step >= 300
    sigc0 = sim.bonds.sigc.copy()
    sim.run(1000, callback=rig, every=100)
    assert seen == [100, 200, 300] and sim.step == 300
    assert np.all(sim.balls.alive[:3] == 0)
    assert np.allclose(sim.bonds.sigc, 2 * sigc0)
    gone = (sim.bonds.i < 3) | (sim.bonds.j < 3)
    assert np.all(sim.bonds.active[gone] == 0)
    c = sim.contact_list()
    assert not np.isin(c["i"], [0, 1, 2]).any() and not np.isin(c["j"], [0, 1, 2]).any()


def test_perturbed_velocities_touch_live_free_balls_only_seeded(small_model):
    """The chaos probe's perturbation (loop.select): each velocity component of a live free
    ball gets a normal draw of the given sd (sample sd within 20 % over 150 components),
    a held ball, a clump's pebble and a deleted ball keep theirs; one seed, one draw."""
    sim = small_model(1)
    sim.set_ball_velocity(3, hold=7)
    sim.delete_balls([5])
    before = sim.balls.vel.copy()
    sim.perturb_velocities(1e-3, seed=4)
    change = sim.balls.vel - before
    untouched = np.zeros(len(change), bool)
    untouched[[3, 5]] = True
    untouched |= sim.balls.clump >= 0
    assert untouched.sum() == 4 and np.all(change[untouched] == 0)
    assert np.all(change[~untouched] != 0) and abs(change[~untouched].std() / 1e-3 - 1) < 0.2
    again = small_model(1)
    again.set_ball_velocity(3, hold=7)
    again.delete_balls([5])
    again.perturb_velocities(1e-3, seed=4)
    assert np.array_equal(again.balls.vel, sim.balls.vel)
