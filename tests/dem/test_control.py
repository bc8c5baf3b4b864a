"""Controllers inside the stepping loop (dem/control.py): a force servo on wall segments
reaches the analytical overlap; a held-clump servo gives the same bytes as the same control
law run from Python between engine calls; the cyclic profile reverses at its bounds and
raises its events there; the wall-force sensor balances load + weight; control state
survives a checkpoint bit for bit."""
import numpy as np
import pytest

from ballaststudy.dem import Simulation
from ballaststudy.dem.control import PEAK, TROUGH, WINDOW, Control

KN = 1.0e6                       # Hooke normal stiffness [N/m]
HOOKE = dict(kn=KN, kt=KN / 3, gamma_n=200.0, gamma_t=100.0, mu=0.5)
R = 0.01


def squeezed_ball():
    """A ball between two vertical walls 0.2 mm wider than it, no gravity."""
    sim = Simulation(gravity=(0, 0), damping=0.7, law="hooke", dt=1e-5, hooke=HOOKE,
                     domain=(-0.1, -0.1, 0.1, 0.1))
    sim.add_wall([(-R - 1e-4, -0.05), (-R - 1e-4, 0.05)])
    right = sim.add_wall([(R + 1e-4, -0.05), (R + 1e-4, 0.05)])
    sim.add_balls([0.0], [0.0], [R], 2650.0)
    return sim, right


@pytest.mark.parametrize("areal_mass", [0.0, 0.5])
def test_wall_servo_reaches_the_analytical_overlap(areal_mass):
    """Servo on the right wall to F = 100 N, or the wall a body of 0.5 kg loaded with F
    (the ball's local damping stills it): both contacts carry F, so each overlap is
    F / k_n and the walls end 2 R - 2 F / k_n apart (within 0.5 %); the window mean of
    the sensor is the target within the 1 % the last window is asked for."""
    sim, right = squeezed_ball()
    c = Control(every=10)
    f = c.wall_force(right, axis=0)
    c.servo(f, c.walls(right, axis=0), target=100.0, gain=1e-3, v_max=0.05,
            integral_steps=1000, window_steps=2000)
    c.build()
    c.set(0, areal_mass=areal_mass)
    means = []
    for _ in range(10):
        sim.run(10 ** 6, control=c)
        assert c.event == (WINDOW, 0)
        means.append(c.window_means()[f])
    gap = sim.walls.seg[right[0], 0] - sim.walls.seg[0, 0]
    assert gap == pytest.approx(2 * R - 2 * 100.0 / KN, rel=0, abs=0.005 * 2 * 100.0 / KN)
    assert means[-1] == pytest.approx(100.0, rel=0.01)
    assert sim.step == 10 * 2000


def plate_on_ball(gravity=-9.81):
    """A ball on a floor, a held one-pebble clump ("plate") just above it."""
    sim = Simulation(gravity=(0, gravity), damping=0.7, law="hooke", dt=1e-5, hooke=HOOKE,
                     domain=(-0.1, -0.1, 0.1, 0.2))
    floor = sim.add_wall([(-0.05, 0.0), (0.05, 0.0)])
    sim.add_balls([0.0], [R], [R], 2650.0)
    plate = sim.add_clump([0.0], [3 * R + 1e-3], [R], 7850.0, held=True)
    return sim, floor, plate


def test_servo_in_the_loop_equals_the_python_loop():
    """The PI law run by the kernel every 10 steps = the same law computed in Python
    between 10-step engine runs (the order of a rig that sets velocities from outside):
    identical bytes after 3000 steps."""
    target, gain, vmax, isteps, every = 50.0, 2e-4, 0.05, 500.0, 10
    a, _, pa = plate_on_ball()
    c = Control(every=every)
    c.servo(c.clump_reaction(pa, axis=1), c.held_clump(pa, axis=1), target=target,
            gain=gain, v_max=vmax, integral_steps=isteps, window_steps=10 ** 9)
    a.run(3000, control=c.build())
    b, _, pb = plate_on_ball()
    f, integral = 0.0, 0.0
    for _ in range(300):
        e = gain * (target - f) / 1.0
        integral = min(max(integral + e * float(every) / isteps, -vmax), vmax)
        v = min(max(-(e + integral), -vmax), vmax)
        b.set_clump_velocity(pb, vel=(0.0, v), omega=0.0, held=True)
        b.run(every)
        force, _ = b.clump_force(pb)
        f = float(force[1] - b.clumps.mass[pb] * b.gravity[1])
    assert f > 0.5 * target                     # it does press the ball
    assert np.array_equal(a.balls.pos, b.balls.pos)
    assert np.array_equal(a.clumps.pos, b.clumps.pos)
    assert np.array_equal(a.balls.vel, b.balls.vel)


def test_cyclic_profile_reverses_at_its_bounds():
    """Bound to bound between 20 and 80 N: events alternate peak / trough; at a peak the
    reading has just crossed 80 N (the sample before is below), at a trough it has just
    fallen to 20 N; between events the plate moves down while loading and up while
    unloading, at no more than v_max and no less than v_min."""
    sim, _, plate = plate_on_ball()
    c = Control(every=5)
    f = c.clump_reaction(plate, axis=1)
    c.cyclic(f, c.held_clump(plate, axis=1), lo=20.0, hi=80.0, v_min=0.002, v_max=0.02,
             brake=0.25, direction=-1)
    c.build()
    events, prev = [], None
    for _ in range(8):
        sim.run(10 ** 6, control=c)
        rows = c.drain()
        ev = c.event[0]
        events.append(ev)
        last, before = rows[-1, 1 + f], (rows[-2, 1 + f] if len(rows) > 1 else prev)
        if ev == PEAK:
            assert last >= 80.0 and before < 80.0
        else:
            assert ev == TROUGH and last <= 20.0 and before > 20.0
        prev = last
        c.clear_event()
        sim.run(1, control=c)             # imposes the reversed velocity
        v = sim.clumps.vel[plate, 1]
        assert (v > 0) == (ev == PEAK) and 0.002 - 1e-12 <= abs(v) <= 0.02 + 1e-12
    assert events == [PEAK, TROUGH] * 4


def test_cyclic_speed_profile():
    """v_max outside the braking band, linear to v_min at the bound approached."""
    sim, _, plate = plate_on_ball()
    c = Control(every=1)
    k = c.cyclic(c.clump_reaction(plate, axis=1), c.held_clump(plate, axis=1), lo=15.0,
                 hi=45.0, v_min=0.01, v_max=0.1, brake=0.25, direction=-1)
    c.build()
    band = 0.25 * 30.0
    assert c.velocity(k, 15.0) == pytest.approx(-0.1)
    assert c.velocity(k, 45.0 - 0.5 * band) == pytest.approx(-0.055)
    assert c.velocity(k, 45.0) == pytest.approx(-0.01)
    c.set(k, direction=1)
    assert c.velocity(k, 15.0 + 0.5 * band) == pytest.approx(0.055)
    assert c.velocity(k, 45.0) == pytest.approx(0.1)


def pressed_ball(d0):
    """A ball between two vertical walls, each pressing it by ``d0``, no gravity."""
    sim = Simulation(gravity=(0, 0), damping=0.7, law="hooke", dt=1e-5, hooke=HOOKE,
                     domain=(-0.1, -0.1, 0.1, 0.1))
    sim.add_wall([(-R + d0, -0.05), (-R + d0, 0.05)])
    right = sim.add_wall([(R - d0, -0.05), (R - d0, 0.05)])
    sim.add_balls([0.0], [0.0], [R], 2650.0)
    return sim, right


def period_error(sim, c, sensor, lo, hi, f, steps=20000):
    """Run ``steps`` (one period of f at dt 1e-5); the sensor's largest distance from the
    sinusoid lo..hi, as a fraction of hi - lo."""
    rows = []
    while sim.step < steps:
        sim.run(steps - sim.step, control=c)
        rows.append(c.drain())
        c.clear_event()
    rows = np.concatenate(rows)
    target = lo + 0.5 * (hi - lo) * (1.0 - np.cos(2.0 * np.pi * f * rows[:, 0] * sim.dt))
    return np.abs(rows[:, 1 + sensor] - target).max() / (hi - lo)


@pytest.mark.parametrize("factor, within", [(1.0, True), (0.0, False), (2.0, False)])
def test_sine_feed_forward_follows_the_target(factor, within):
    """The right wall under a SINE controller with a negligible servo gain: its feed-forward
    -C dF/dt alone makes the wall force follow 50-150 N at 5 Hz (far below the ball's
    ~250 Hz) within 2 % of the amplitude when C is the system's compliance 2 / k_n (the
    free ball shares a wall move between its two contacts); without it (C = 0) or with
    twice it the force misses by a large part of the amplitude."""
    lo, hi, f = 50.0, 150.0, 5.0
    sim, right = pressed_ball(lo / KN)
    c = Control(every=10)
    sensor = c.wall_force(right, axis=0)
    k = c.sine(sensor, c.walls(right, axis=0), lo=lo, hi=hi, frequency=f, gain=1e-12,
               v_max=1.0, integral_steps=0)
    c.build()
    c.set(k, t0=0.0, compliance=factor * 2.0 / KN)
    error = period_error(sim, c, sensor, lo, hi, f)
    assert (error < 0.02) == within, error


def test_floor_sensor_balances_load_and_weight():
    """Servo at 50 N on the plate: the floor sensor (downwards +) averages the load plus
    the ball's weight over the last window within 1 %."""
    sim, floor, plate = plate_on_ball()
    c = Control(every=10)
    f = c.clump_reaction(plate, axis=1)
    bottom = c.wall_force(floor, axis=1, scale=-1.0)
    c.servo(f, c.held_clump(plate, axis=1), target=50.0, gain=2e-4, v_max=0.05,
            integral_steps=500, window_steps=3000)
    c.build()
    for _ in range(10):
        sim.run(10 ** 6, control=c)
        means = c.window_means()
    weight = sim.balls.mass[0] * 9.81
    assert means[bottom] == pytest.approx(means[f] + weight, rel=0.01)
    assert means[f] == pytest.approx(50.0, rel=0.01)


def test_control_state_restarts_bitwise(tmp_path):
    """Engine checkpoint + control arrays saved mid-run, restored, continued: the same
    bytes as the run that never stopped."""
    def build(sim, plate):
        c = Control(every=10)
        c.servo(c.clump_reaction(plate, axis=1), c.held_clump(plate, axis=1), target=50.0,
                gain=2e-4, v_max=0.05, integral_steps=500, window_steps=700)
        return c.build()

    a, _, pa = plate_on_ball()
    ca = build(a, pa)
    b, _, pb = plate_on_ball()
    cb = build(b, pb)
    for sim, c in ((a, ca), (b, cb)):
        while sim.step < 1500:
            sim.run(1500 - sim.step, control=c)
            c.clear_event()
            c.window_means()
    b.save_checkpoint(tmp_path / "ck.npz")
    saved = cb.to_dict()
    b = Simulation.load_checkpoint(tmp_path / "ck.npz")
    cb = build(b, pb).load(saved)
    for sim, c in ((a, ca), (b, cb)):
        while sim.step < 4000:
            sim.run(4000 - sim.step, control=c)
            c.clear_event()
            c.window_means()
    assert np.array_equal(a.clumps.pos, b.clumps.pos)
    assert np.array_equal(a.balls.vel, b.balls.vel)
    assert np.array_equal(ca.arrays.cst, cb.arrays.cst)


def platen_on_fixed_ball(gamma_n=0.0, gap=0.0):
    """A ball too heavy to move (a fixed spring k_n) against the left wall; the right wall,
    ``gap`` from it, is the platen a SINE controller drives. No damping unless asked."""
    law = dict(HOOKE, gamma_n=gamma_n, gamma_t=0.0)
    sim = Simulation(gravity=(0, 0), damping=0.0, law="hooke", dt=1e-5, hooke=law,
                     domain=(-0.1, -0.1, 0.1, 0.1))
    sim.add_wall([(-R, -0.05), (-R, 0.05)])
    right = sim.add_wall([(R + gap, -0.05), (R + gap, 0.05)])
    sim.add_balls([0.0], [0.0], [R], 1.0e12)
    return sim, right


def driven(sim, right, lo, hi, frequency, mass, gain=1.0, every=1):
    c = Control(every=every, capacity=20000)
    sensor = c.wall_force(right, axis=0)
    k = c.sine(sensor, c.walls(right, axis=0), lo=lo, hi=hi, frequency=frequency, gain=gain,
               v_max=1.0, integral_steps=0, areal_mass=mass)
    c.build()
    c.set(k, t0=0.0)
    return c, sensor


@pytest.mark.parametrize("mass", [10.0, 2.5])
def test_driven_platen_oscillates_on_its_spring(mass):
    """A platen of mass M put on a spring k_n with a load F0 applied at once (undamped): the
    spring force swings to 2 F0 at t = pi sqrt(M / k_n) and back to 0 (the load's impulse
    equals the platen's momentum): peak within 1 %, its time within 2 %."""
    f0 = 100.0
    sim, right = platen_on_fixed_ball()
    c, sensor = driven(sim, right, f0, f0, 1.0e-3, mass)
    sim.run(int(1.2 * np.pi * np.sqrt(mass / KN) / sim.dt), control=c)
    rows = c.drain()
    k = int(np.argmax(rows[:, 1 + sensor]))
    assert rows[k, 1 + sensor] == pytest.approx(2 * f0, rel=0.01)
    assert rows[k, 0] * sim.dt == pytest.approx(np.pi * np.sqrt(mass / KN), rel=0.02)


@pytest.mark.parametrize("gain, within", [(1.0, True), (-1.0, False)])
def test_driven_platen_follows_the_applied_load(gain, within):
    """The platen (M = 0.05 kg, its resonance on k_n at 710 Hz), pressed at rest by 50 N,
    loaded 50-150 N at 5 Hz: over a period its reading (the spring's force) follows the
    load within 0.5 % of the range (its inertial part M a is ~1e-5 of it) and it ends at
    F / k_n of overlap; driven the wrong way (gain < 0) it leaves the ball."""
    lo, hi, f, mass = 50.0, 150.0, 5.0, 0.05
    sim, right = platen_on_fixed_ball(gap=-lo / KN)
    c, sensor = driven(sim, right, lo, hi, f, mass, gain=gain, every=10)
    error = period_error(sim, c, sensor, lo, hi, f)
    assert (error < 0.005) == within, error
    if within:
        overlap = R - sim.walls.seg[right[0], 0]
        assert overlap == pytest.approx(lo / KN, rel=0.01)


def test_only_walls_are_driven_and_old_checkpoints_load():
    """A held clump cannot be a driven body (it would write wall velocities); control
    arrays saved before the areal mass existed (8 parameter columns) load as undriven."""
    sim, _, plate = plate_on_ball()
    c = Control(every=10)
    f = c.clump_reaction(plate, axis=1)
    with pytest.raises(ValueError, match="wall segments"):
        c.sine(f, c.held_clump(plate, axis=1), lo=1.0, hi=2.0, frequency=1.0, gain=1.0,
               v_max=1.0, integral_steps=0, areal_mass=1.0)
    k = c.servo(f, c.held_clump(plate, axis=1), target=50.0, gain=2e-4, v_max=0.05,
                integral_steps=500, window_steps=700)
    c.build()
    with pytest.raises(ValueError, match="wall segments"):
        c.set(k, areal_mass=1.0)
    old = c.to_dict()
    old["control_cpar"] = old["control_cpar"][:, :8]
    restored = Control(every=10).load(old)
    assert np.array_equal(restored.arrays.cpar, c.arrays.cpar)
