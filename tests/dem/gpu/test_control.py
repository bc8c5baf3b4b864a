"""Controllers in the GPU batch (dem/control.py run per case on the device), under numba's
CUDA simulator, against the CPU engine: cases that halt at their own events and budgets
while the others step on, reacted to by their hosts as a rig does."""
import copy

import numpy as np
import pytest

from ballaststudy.dem.control import PEAK, TROUGH, WINDOW, Control
from ballaststudy.dem.gpu import Batch, BatchError
from ballaststudy.dem.gpu.kernels import HALT_EVENT, HALT_STEPS

from .beds import RHO, assert_same_motion

STEPS = 45


def servo_wall(sim):
    """A PI servo on the right wall (its reaction along x, 1.5 x today's), windows of 20
    steps: WINDOW events."""
    right = [len(sim.walls) - 1]
    ctl = Control(every=2)
    f = ctl.wall_force(right, 0)
    ctl.servo(f, ctl.walls(right, 0), target=1.5 * max(sim.walls.force[right[0], 0], 0.05),
              gain=2e-3, v_max=0.02, integral_steps=40, window_steps=20)
    return ctl.build()


def sine_body(sim):
    """The right wall driven as a body of 0.1 kg under a sinusoidal load of 2 N above
    today's (the biaxial rig's applied loads) at 1000 Hz, a quarter period in: a PEAK after
    about 13 steps, a TROUGH 25 steps later."""
    right = [len(sim.walls) - 1]
    ctl = Control(every=1)
    f = ctl.wall_force(right, 0)
    now = float(sim.walls.force[right[0], 0])
    k = ctl.sine(f, ctl.walls(right, 0), lo=now, hi=now + 2.0, frequency=1000.0, gain=1.0,
                 v_max=0.1, integral_steps=0, areal_mass=0.1)
    ctl.build()
    ctl.set(k, t0=sim.time - 0.25e-3)     # the first reversal (a peak) after ~13 steps
    return ctl


def cyclic_plate(landed):
    """A held clump pushed into the bed between two reactions (the box test's plate):
    PEAK at hi, TROUGH at lo."""
    ctl = Control(every=1)
    r = ctl.clump_reaction(0, 1)
    w = float(landed.clumps.mass[0] * 9.81)
    ctl.cyclic(r, ctl.held_clump(0, 1), lo=1.0 * w, hi=1.2 * w, v_min=5e-4, v_max=5e-3,
               brake=0.3)
    return ctl.build()


def react(sim, ctl, log):
    """What a rig does at an event: note it with the readings, drain the samples, set the
    next target (a servo's alternates between 1.5 and 1.2 x its first)."""
    code, k = ctl.event
    row = [sim.step, code, k, ctl.reading(0)]
    if code == WINDOW:
        row += list(ctl.window_means())
        target = ctl.get(k, "target")
        ctl.set(k, target=target * (0.8 if len(log) % 2 == 0 else 1.25))
    log.append((row, ctl.drain()))
    ctl.clear_event()


def on_cpu(sim, ctl, steps):
    log = []
    end = sim.step + steps
    while sim.step < end:
        sim.run(end - sim.step, control=ctl)
        if ctl.event[0]:
            react(sim, ctl, log)
    return log


def on_gpu(sims, ctls, steps, check_every):
    """The cases in one batch, each host reacting to its own halts as on_cpu."""
    batch = Batch.from_simulations(sims, ctls)
    logs = [[] for _ in sims]
    first = [s.step for s in sims]
    batch.start(range(len(sims)), steps)
    while True:
        halted = batch.advance(check_every)
        if not halted:
            break
        batch.to_simulations(sims).to_controls(list(halted))
        for b, code in halted.items():
            if code == HALT_EVENT:
                react(sims[b], ctls[b], logs[b])
            done = sims[b].step - first[b]
            if done < steps:
                batch.start([b], steps - done)
    return logs


def cases(beds):
    landed = copy.deepcopy(beds[0])
    top = float((landed.balls.pos[:, 1] + landed.balls.rad).max())
    landed.add_clump([0.02, 0.026, 0.032], [top + 0.004] * 3, [0.003] * 3, RHO)
    landed.run(2000)
    free = copy.deepcopy(landed)         # (its clump free: the plate's is the batch's 2nd)
    landed.set_clump_velocity(0, vel=(0.0, 0.0), omega=0.0, held=True)
    sims = [copy.deepcopy(beds[1]), free, landed]
    return sims, [servo_wall(sims[0]), sine_body(sims[1]), cyclic_plate(landed)]


@pytest.mark.parametrize("check_every", [1, 10])
def test_controllers_step_like_the_cpu_engine(beds, check_every):
    """A servo wall (window events, targets changed by the host), a wall driven as a body
    under a sinusoidal load (peaks and troughs) and a cyclic plate (a held clump between
    two reactions), in one batch: each case halts at its own events (checked every step,
    or every 10: a halted case idles while the others step on), its host reacts, and
    every case ends as on the CPU: the same events at the same steps, samples, readings
    and motion within round-off."""
    sims, ctls = cases(beds)
    ref = [copy.deepcopy(s) for s in sims]
    cpu = [on_cpu(s, copy.deepcopy(c), STEPS) for s, c in zip(ref, ctls)]
    gpu = on_gpu(sims, ctls, STEPS, check_every)
    codes = [{row[1] for row, _ in log} for log in cpu]
    assert codes == [{WINDOW}, {PEAK, TROUGH}, {PEAK, TROUGH}]    # every case had events
    for c_log, g_log, c, g in zip(cpu, gpu, ref, sims):
        assert [r[:3] for r, _ in c_log] == [r[:3] for r, _ in g_log]
        for (rc, sc), (rg, sg) in zip(c_log, g_log):
            assert np.allclose(rc[3:], rg[3:], rtol=1e-9, atol=1e-12)
            assert np.array_equal(sc[:, 0], sg[:, 0])
            assert np.allclose(sc[:, 1:], sg[:, 1:], rtol=1e-9, atol=1e-12)
        assert g.step == c.step and g.time == c.time
        assert_same_motion(c, g)
        assert np.abs(c.walls.seg - g.walls.seg).max() < 1e-14
        assert np.allclose(c.walls.vel, g.walls.vel, rtol=1e-9, atol=1e-15)
        assert np.allclose(c.clumps.vel, g.clumps.vel, rtol=1e-9, atol=1e-13)
    assert ref[1].walls.vel[-1, 0] != 0.0                   # the body moved under its load
    assert ref[2].clumps.vel[0, 1] != 0.0                   # the plate moves


def test_a_halted_case_waits_while_the_others_step(beds):
    """Budgets of 4 and 12 steps, checked every 4: the first halts after its 4 and waits
    (8 more steps of the other) bit for bit as a case run 4 steps alone, then runs on."""
    a, b = copy.deepcopy(beds[0]), copy.deepcopy(beds[2])
    batch = Batch.from_simulations([a, b])
    batch.start([0], 4).start([1], 12)
    assert batch.advance(check_every=4) == {0: HALT_STEPS}
    assert batch.advance(check_every=4) == {1: HALT_STEPS}
    assert batch.advance() == {}
    batch.to_simulations([a, b])
    alone = copy.deepcopy(beds[0])
    Batch.from_simulations([alone]).run(4).to_simulations([alone])
    assert a.step == beds[0].step + 4 and b.step == beds[2].step + 12
    assert np.array_equal(a.balls.pos, alone.balls.pos)
    assert np.array_equal(a.balls.vel, alone.balls.vel)
    with pytest.raises(BatchError, match="still running"):
        batch.start([1], 3).start([1], 3)


def test_controls_that_do_not_fit_are_refused(beds):
    sim = copy.deepcopy(beds[1])
    with pytest.raises(BatchError, match="1 controls for 2 cases"):
        Batch.from_simulations([sim, sim], [servo_wall(sim)])
    with pytest.raises(BatchError, match="not built"):
        Batch.from_simulations([sim], [Control(every=1)])
    ctl = servo_wall(sim)
    batch = Batch.from_simulations([sim], [ctl])
    ctl.wall_force([0], 1)
    ctl.build()
    with pytest.raises(BatchError, match="rebuilt"):
        batch.start([0], 1)
