"""Engine features beyond the spec table: energy balance with every dissipation
mechanism, held clump (plate) servo, critical timestep, density scaling, per-body damping."""
import math

import numpy as np
import pytest

from ballaststudy.dem import ContactMaterial, FlatJointMaterial, Simulation

from .generate import random_disks


def test_energy_balance_with_damping_friction_dashpots_and_breakage():
    """E_mech(0) = E_mech(t) + all dissipated energies. The dissipation is summed with
    half-step velocities (first order in dt: 1.2 % at f = 0.2, 0.3 % at f = 0.05)."""
    sim = Simulation(gravity=(0, -9.81), damping=0.2, dt_safety=0.05,
                     domain=(-0.05, -0.05, 0.15, 0.4))
    sim.set_contact_material(ContactMaterial(E=1e7, mu=0.4, beta_n=0.3, beta_s=0.2))
    sim.add_wall([(0, 0.3), (0, 0), (0.1, 0), (0.1, 0.3)])
    x, y, r, vx, vy = random_disks(60, 0, 0.1, 0.02, 0.004, 0.006, seed=2, vmax=0.5)
    sim.add_balls(x, y, r, 2650.0, stone_id=np.arange(60) // 6, vx=vx, vy=vy)
    sim.install_flat_joints(FlatJointMaterial(E=1e7, sigma_c=2e3, c=2e3, gap_factor=3.0))

    def mech(s):
        e = s.energies()
        return e["kinetic"] + e["gravity_potential"] + e["elastic_contacts"] + e["elastic_bonds"], e
    e0, _ = mech(sim)
    sim.run(120_000)
    e1, e = mech(sim)
    lost = (e["dissipated_dashpot"] + e["dissipated_friction"] + e["dissipated_damping"]
            + e["dissipated_breakage"])
    assert sim.log.n[0] > 0 and e["dissipated_friction"] > 0 and e["dissipated_damping"] > 0
    err = abs(e0 - e1 - lost) / abs(e0 - e1)
    assert err < 0.01, f"energy released {e0 - e1:.6g} J vs dissipated {lost:.6g} J ({e})"


def test_held_clump_keeps_velocity_and_reports_force():
    sim = Simulation(gravity=(0, -9.81), damping=0.7, domain=(-1, -1, 1, 1))
    sim.set_contact_material(ContactMaterial(E=1e7, mu=0.5, beta_n=0.5))
    sim.add_wall([(-0.2, 0), (0.2, 0)])
    sim.add_balls(0.0, 0.01, 0.01, 2650.0)
    plate = sim.add_clump(np.linspace(-0.04, 0.04, 9), np.full(9, 0.0251), np.full(9, 0.005),
                          2650.0, held=True)
    sim.set_clump_velocity(plate, vel=(0.0, -1e-3))
    sim.run(20_000, callback=lambda s: s.clumps.pos[plate, 1] < 0.0249, every=100)
    assert np.array_equal(sim.clumps.vel[plate], [0.0, -1e-3])
    f_plate, _ = sim.clump_force(plate)
    weight = sim.clumps.mass[plate] * 9.81
    push = f_plate[1] + weight                     # contact force of the ball on the plate
    bottom = -sim.wall_force()[0, 1]
    ball_w = sim.balls.mass[0] * 9.81
    assert push > 1.0, f"plate did not load the ball ({push} N)"
    assert abs(bottom - (push + ball_w)) <= 0.01 * bottom, f"bottom {bottom} vs plate {push} + ball {ball_w}"


def test_auto_timestep_is_f_times_critical():
    sim = Simulation(gravity=(0, 0), dt_safety=0.5, domain=(-1, -1, 1, 1))
    e = 1e8
    sim.set_contact_material(ContactMaterial(E=e, kappa=2.0))
    r = 0.01
    sim.add_balls([0.0, 2 * r], [0, 0], [r, r], 2650.0)
    sim.run(1)
    m = 2650.0 * math.pi * r * r
    kn = e * 1.0                    # 2 R t E / 2R
    k_tr, k_rot = kn + kn / 2.0, kn / 2.0 * r * r
    ref = 0.5 * min(math.sqrt(m / k_tr), math.sqrt(0.5 * m * r * r / k_rot))
    assert abs(sim.dt - ref) <= 1e-12 * ref, f"dt {sim.dt:.6e} vs f dt_crit {ref:.6e}"


def test_density_scaling_raises_inertia_and_reports_inertial_number():
    sim = Simulation(gravity=(0, 0), dt=1e-4, dt_safety=0.8, density_scaling=True,
                     domain=(-1, -1, 1, 1))
    sim.set_contact_material(ContactMaterial(E=1e8))
    sim.add_balls([0.0, 0.0199], [0, 0], [0.01, 0.01], 2650.0, vx=[0.01, -0.01])
    sim.run(200)
    assert np.all(1.0 / sim.balls.minv > sim.balls.mass), "inertial mass not raised"
    assert np.isfinite(sim.balls.pos).all()
    i_num = sim.inertial_number(shear_rate=1.0, pressure=1e5)
    assert math.isclose(i_num, 0.02 * math.sqrt(2650.0 / 1e5))


def test_density_scaling_switched_on_and_off():
    """set_density_scaling(dt): fixed dt, inertial masses raised so that it is stable, the
    weight unchanged (free fall of a lone scaled ball still at g); None: the automatic
    critical dt and the real masses again."""
    sim = Simulation(gravity=(0, 0), dt_safety=0.8, domain=(-1, -1, 1, 1))
    sim.set_contact_material(ContactMaterial(E=1e8))
    sim.add_balls([0.0, 0.0199, 0.5], [0, 0, 0.5], [0.01, 0.01, 0.01], 2650.0)
    sim.run(1)
    dt0 = sim.dt
    sim.set_density_scaling(4.0 * dt0)
    sim.run(1)
    assert sim.dt == 4.0 * dt0
    m_in = 1.0 / sim.balls.minv
    assert np.allclose(m_in[:2] / sim.balls.mass[:2], 16.0, rtol=1e-9), "x4 dt needs x16 inertia"
    assert m_in[2] == sim.balls.mass[2], "a ball without neighbours keeps its mass"
    sim.set_gravity((0.0, -9.81))
    v0 = sim.balls.vel[0, 1]
    sim.run(10)
    a = (sim.balls.vel[0, 1] - v0) / (10 * sim.dt)
    # velocity Verlet: the first half kick still used the force from before gravity was on
    assert a == pytest.approx(-9.81 / 16.0 * 9.5 / 10.0, rel=1e-9), "weight on the real mass, inertia scaled"
    sim.set_density_scaling(None)
    sim.run(1)
    assert np.array_equal(1.0 / sim.balls.minv, sim.balls.mass)
    assert sim.dt == pytest.approx(dt0, rel=1e-6)


def test_per_body_damping():
    sim = Simulation(gravity=(0, -9.81), domain=(-1, -1, 1, 1))
    sim.add_balls([0.0, 0.1], [0.0, 0.0], [0.01, 0.01], 2650.0)
    sim.set_damping(0.5, balls=[1])
    sim.run(100)
    v0, v1 = sim.balls.vel[:, 1]
    assert math.isclose(v0, -9.81 * sim.time, rel_tol=1e-9)
    assert math.isclose(v1, 0.5 * v0, rel_tol=0.02), (v0, v1)   # first half step undamped (v = 0)


def test_local_damping_force_is_alpha_times_the_weight_against_the_motion():
    """Free flight under gravity, alpha = 0.5 on three balls (one y-held) and a clump: the
    damping force is +alpha m g on a falling body and -alpha m g on a rising one (it opposes
    the motion, |F| = m g); nothing on an undamped ball or the y-held one, nothing sideways
    (F_x = 0). alpha = 1 is refused (a force damped to zero cannot be recovered)."""
    sim = Simulation(gravity=(0, -9.81), domain=(-1, -1, 1, 1))
    sim.add_balls([0.0, 0.1, 0.2, 0.3], [0.0] * 4, [0.01] * 4, 2650.0, vy=[-1.0, 1.0, -1.0, -1.0])
    lump = sim.add_clump([0.5, 0.52], [0.0, 0.0], [0.01, 0.01], 2650.0)
    sim.set_clump_velocity(lump, vel=(0.0, 1.0))
    sim.set_damping(0.5, balls=[0, 1, 3], clump_alpha=0.5, clumps=[lump])
    sim.set_ball_velocity([3], hold=2)
    sim.run(10)
    w = 9.81 * sim.balls.mass[:4]
    f = sim.local_damping_force([0, 1, 2, 3])
    assert np.allclose(f[:, 0], 0.0)
    assert f[:, 1] == pytest.approx([0.5 * w[0], -0.5 * w[1], 0.0, 0.0], rel=1e-9, abs=1e-15)
    fc = sim.local_damping_force(lump, clumps=True)
    assert fc[0] == pytest.approx([0.0, -0.5 * 9.81 * sim.clumps.mass[lump]], rel=1e-9, abs=1e-15)
    sim.set_damping(1.0, balls=[0])
    with pytest.raises(ValueError, match="alpha >= 1"):
        sim.local_damping_force([0])


def test_contact_state_slip_work_is_the_friction_dissipated_at_that_contact():
    """Persistent per-contact state: a disk sliding on a wall (no dashpots, no damping)
    dissipates all its friction at one contact; that contact's slip_work equals the
    engine's friction total, and equals the kinetic energy lost (mu m g x)."""
    from ballaststudy.dem import ContactMaterial
    r, rho, mu, v0 = 0.01, 2650.0, 0.3, 0.5
    sim = Simulation(gravity=(0.0, -9.81), domain=(-1, -1, 1, 1))
    sim.set_contact_material(ContactMaterial(E=1e8, mu=mu))
    sim.add_wall([(-0.5, 0.0), (0.5, 0.0)])
    m = rho * np.pi * r * r
    sim.add_balls(0.0, r - m * 9.81 / 2e8, r, rho, vx=v0)
    sim.run(2000)
    st = sim.contact_state()
    e = sim.energies()
    on_wall = st["j"] < 0
    assert on_wall.sum() == 1
    w = float(st["slip_work"][on_wall][0])
    assert w > 0.0
    assert abs(w - e["dissipated_friction"]) <= 1e-9 * w, (w, e["dissipated_friction"])
    lost = 0.5 * m * v0 ** 2 - e["kinetic"]
    assert abs(w - lost) <= 0.01 * lost, f"slip work {w:.6g} J vs kinetic energy lost {lost:.6g} J"
