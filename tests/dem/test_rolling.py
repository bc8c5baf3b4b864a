"""Rolling resistance: ContactLaw.pfc(rolling="epsd"), the elastic-plastic spring-dashpot
model ("type C") of Ai et al. (2011), checked against analytical results.

Ball-wall contact (the wall is body i, the ball body j): k_n = 2 t E, k_s = k_n / kappa,
rolling radius R_r = R, k_r = kr_ratio k_s R^2, limit |M_r| <= mu_r R F_n; contact point
and friction arm at a = R - delta/2 (PFC), delta = m g cos(theta) / k_n at rest.

Disk of mass m, I = m R^2 / 2, on an incline (a horizontal wall, gravity tilted by theta)
with friction large enough not to slip:
  at rest iff  a m g sin(theta) <= mu_r R m g cos(theta),  i.e. tan(theta_c) = mu_r R / a,
  rolling:     m x'' = m g sin(theta) - F_s,  I x''/a = a F_s - mu_r R F_n
           ->  x'' = g (sin(theta) - mu_r (R/a) cos(theta)) / (1 + I/(m a^2)).
On a flat wall (theta = 0) a rolling disk decelerates at mu_r g (R/a) / (1 + I/(m a^2))
(~ 2/3 mu_r g) and stops after v0^2 / (2 decel).
"""
import math

import numpy as np
import pytest

from ballaststudy.dem import ContactMaterial, Simulation
from ballaststudy.dem.law import ContactLaw

R, RHO, G, E = 0.01, 2650.0, 9.81, 1.0e8
M = RHO * math.pi * R * R                 # t = 1 m
I = 0.5 * M * R * R
KN = 2.0 * E                              # ball-facet: A E / L = 2 R t E / R


def epsd():
    return ContactLaw.pfc(rolling="epsd")


def history_column(law, kind):
    """First column of a sub-model's history in the per-contact array."""
    return law.history_column(kind)


def rolling_column(law):
    """Column of the rolling spring moment M_r (pfc_incremental: F_s is "tangential")."""
    return history_column(law, "rolling")


def arm(cos_theta):
    """Contact arm a = R - delta/2 at the static overlap delta = m g cos / k_n."""
    return R - 0.5 * M * G * cos_theta / KN


def rolling_decel(theta, mu_r):
    """Analytical acceleration down the slope of a disk rolling without slip against the
    limit rolling moment (negative: it would not roll)."""
    a = arm(math.cos(theta))
    return G * (math.sin(theta) - mu_r * (R / a) * math.cos(theta)) / (1.0 + I / (M * a * a))


def critical_angle(mu_r):
    """tan(theta_c) = mu_r R / a (a evaluated at theta_c; the fixed point converges at once)."""
    th = math.atan(mu_r)
    for _ in range(3):
        th = math.atan(mu_r * R / arm(math.cos(th)))
    return th


def disk_on_wall(gravity, material, vx=0.0, omega=0.0, **kw):
    sim = Simulation(gravity=gravity, law=epsd(), domain=(-1, -1, 1, 1), **kw)
    sim.set_contact_material(material)
    sim.add_wall([(-0.5, 0.0), (0.5, 0.0)])
    d0 = -M * gravity[1] / KN                  # static overlap: starts at rest on the wall
    sim.add_balls(0.0, R - d0, R, RHO, vx=vx, omega=omega)
    return sim


def sample(sim, t_end, n=40):
    """Run to t_end, recording (t, x, vx, omega) about ``n`` times at even intervals (few
    ``run`` calls: a call has a fixed cost)."""
    if sim.step == 0:
        sim.run(1)                      # the automatic timestep is set by the first run
    every = max(1, int(round((t_end - sim.time) / sim.dt / n)))
    rows = []
    while sim.time < t_end:
        sim.run(every)
        b = sim.balls
        rows.append((sim.time, b.pos[0, 0], b.vel[0, 0], b.omega[0]))
    return np.array(rows).T


# dashpots: beta_n damps the normal vibration the start excites; beta_s and eta_r the
# rocking. Kept moderate: the automatic timestep ignores dashpots, and with beta_s = 0.5
# AND eta_r = 0.3 at dt_safety 0.8 a resting disk keeps a period-2 oscillation whose booked
# dissipation grows without bound (beta_s = 0.8 alone does the same).
MU_R = 0.2
INCLINE = dict(E=E, kappa=2.5, mu=1.0, beta_n=0.5, beta_s=0.2, mu_r=MU_R, kr_ratio=1.0,
               eta_r=0.2)


def incline_sim(theta):
    return disk_on_wall((G * math.sin(theta), -G * math.cos(theta)), ContactMaterial(**INCLINE))


# ------------------------------------------------------------------ 1. incline
def test_incline_below_threshold_stays_at_rest():
    theta_c = critical_angle(MU_R)
    theta = 0.8 * theta_c
    sim = incline_sim(theta)
    sim.run(1)
    x_start = sim.balls.pos[0, 0]
    t, x, v, w = sample(sim, 0.6)
    settled = t > 0.1
    e_mid = sim.energies()
    t2, x2, v2, _ = sample(sim, 0.9, 20)
    e_end = sim.energies()
    a = arm(math.cos(theta))
    travel = abs(x2[-1] - x_start)
    drift = abs(x2[-1] - x[settled][0])
    vmax = max(np.abs(v[settled]).max(), np.abs(v2).max())
    # a resting disk travels only the deflection of its springs (F_s/k_s + a M_r/k_r ~ 3e-8
    # m) and a little plastic rolling while the sudden tilt overshoots; at 1.2 theta_c it
    # travels ~1 R in 0.3 s
    assert travel < 1e-4 * R, \
        f"theta = 0.8 theta_c ({math.degrees(theta):.3f} deg): travelled {travel:.3e} m " \
        f"(analytical: at rest, 0; R = {R})"
    assert drift < 1e-7 * R and vmax < 1e-8, \
        f"theta = 0.8 theta_c: after the transient it still moves: drift {drift:.3e} m, " \
        f"max |v| {vmax:.3e} m/s (analytical 0)"
    # statics: F_s = m g sin(theta) and M_r = a F_s (moment balance), signs included
    h = sim.wpairs.hist[0]
    fs = h[history_column(sim.law, "tangential")]
    fs_ref = M * G * math.sin(theta)
    mr_ref = a * fs_ref
    lim = MU_R * R * M * G * math.cos(theta)
    assert abs(fs - fs_ref) <= 1e-3 * fs_ref, \
        f"shear force measured {fs:.6g} N analytical m g sin = {fs_ref:.6g} N"
    mr = h[rolling_column(sim.law)]
    assert abs(mr - mr_ref) <= 1e-3 * mr_ref, \
        f"rolling moment measured {mr:.6g} N m analytical a m g sin = {mr_ref:.6g} N m " \
        f"(limit mu_r R F_n = {lim:.6g})"
    # at rest nothing keeps dissipating (a spurious oscillation would)
    lost = [e_end[k] - e_mid[k] for k in ("dissipated_rolling", "dissipated_dashpot",
                                          "dissipated_friction")]
    assert max(lost) < 1e-9 * M * G * R, f"dissipation while at rest: {lost} J"


def test_incline_above_threshold_rolls_against_the_limit_moment():
    theta_c = critical_angle(MU_R)
    theta = 1.2 * theta_c
    sim = incline_sim(theta)
    x0 = sim.balls.pos[0, 0]
    t, x, v, w = sample(sim, 0.3)
    fit = t > 0.05
    acc = 2.0 * np.polyfit(t[fit], x[fit], 2)[0]
    ref = rolling_decel(theta, MU_R)
    free = 2.0 / 3.0 * G * math.sin(theta)   # rolling without rolling resistance
    assert abs(acc - ref) <= 0.01 * ref, \
        f"theta = 1.2 theta_c ({math.degrees(theta):.3f} deg): a measured {acc:.6f} m/s^2 " \
        f"analytical g (sin - mu_r R/a cos)/(1 + I/(m a^2)) = {ref:.6f} m/s^2"
    assert acc < 0.5 * free, \
        f"a measured {acc:.5f} is not clearly below the no-resistance (2/3) g sin = {free:.5f}"
    a = arm(math.cos(theta))
    slip = v[-1] + w[-1] * a
    assert abs(slip) < 1e-3 * abs(v[-1]), f"slip velocity {slip:.3e} m/s (v = {v[-1]:.4f})"
    # all the rolling happens at the limit: work = mu_r R F_n x rotation
    work = sim.energies()["dissipated_rolling"]
    work_ref = MU_R * R * M * G * math.cos(theta) * (x[-1] - x0) / a
    assert abs(work - work_ref) <= 0.01 * work_ref, \
        f"rolling work measured {work:.6g} J analytical mu_r R F_n x/a = {work_ref:.6g} J"


def test_critical_angle_is_mu_r_R_over_a():
    """theta_c itself: the disk stays at 0.98 theta_c and rolls at 1.02 theta_c."""
    theta_c = critical_angle(MU_R)
    t, _, v_stay, _ = sample(incline_sim(0.98 * theta_c), 0.2, 5)
    v_ref = abs(rolling_decel(0.98 * theta_c, MU_R)) * t[-1]    # the speed scale
    assert abs(v_stay[-1]) < 1e-6 * v_ref, \
        f"0.98 theta_c: v = {v_stay[-1]:.3e} m/s at t = {t[-1]:.3f} s (analytical 0)"
    t, _, v_roll, _ = sample(incline_sim(1.02 * theta_c), 0.2, 5)
    v_ref = rolling_decel(1.02 * theta_c, MU_R) * t[-1]
    assert 0.5 * v_ref < v_roll[-1] < 2.0 * v_ref, \
        f"1.02 theta_c: v = {v_roll[-1]:.4e} m/s at t = {t[-1]:.3f} s, analytical " \
        f"{v_ref:.4e} m/s (+ the start transient)"


# ------------------------------------------------------------------ 2. flat wall
@pytest.mark.parametrize("direction", [1.0, -1.0])
def test_rolling_disk_decelerates_and_stops(direction):
    mu_r, v0 = 0.1, 0.3 * direction
    a = arm(1.0)
    mat = ContactMaterial(E=E, kappa=2.5, mu=1.0, beta_n=0.5, beta_s=0.2, mu_r=mu_r,
                          kr_ratio=1.0, eta_r=0.2)
    sim = disk_on_wall((0.0, -G), mat, vx=v0, omega=-v0 / a)
    k0 = sim.energies()["kinetic"]
    dec = mu_r * G * (R / a) / (1.0 + I / (M * a * a))
    t_stop = abs(v0) / dec
    dist = v0 * v0 / (2.0 * dec)
    t, x, v, w = sample(sim, 1.3 * t_stop, 60)
    fit = (t > 0.05 * t_stop) & (t < 0.9 * t_stop)
    slope = np.polyfit(t[fit], v[fit], 1)[0]
    assert abs(-slope * direction - dec) <= 0.01 * dec, \
        f"deceleration measured {-slope * direction:.6f} m/s^2 analytical " \
        f"mu_r g (R/a)/(1 + I/(m a^2)) = {dec:.6f} m/s^2 (2/3 mu_r g = {2 / 3 * mu_r * G:.6f})"
    assert abs(x[-1] * direction - dist) <= 0.02 * dist, \
        f"stopping distance measured {x[-1] * direction:.6f} m analytical " \
        f"v0^2/(2 decel) = {dist:.6f} m"
    rest = t > 1.1 * t_stop
    assert np.abs(v[rest]).max() < 1e-4 * abs(v0), \
        f"not at rest after t_stop: max |v| {np.abs(v[rest]).max():.3e} m/s (v0 = {v0})"
    slip = np.abs(v[fit] + w[fit] * a).max()
    assert slip < 1e-3 * abs(v0), f"slip velocity {slip:.3e} m/s while rolling"
    e = sim.energies()
    assert abs(e["dissipated_rolling"] - k0) <= 0.01 * k0, \
        f"rolling work {e['dissipated_rolling']:.6g} J vs kinetic energy lost {k0:.6g} J"


# ------------------------------------------------------------------ 3. energy balance
def total(e):
    return (e["kinetic"] + e["gravity_potential"] + e["elastic_contacts"]
            + e["dissipated_friction"] + e["dissipated_rolling"] + e["dissipated_dashpot"]
            + e["dissipated_damping"] - e["wall_work"])


# Tolerance. test_energy.py holds conservative contacts to 1e-4; with friction and rolling
# the engine books plastic work as "limit x plastic increment" (submodels.py), which is
# first order in dt when F_n (hence the limit) changes within a step. On this case the
# error (E - E0)/E_mech0 measured -1.6e-3, -1.0e-3, -6.6e-4, -3.5e-4 at dt_safety 0.2, 0.1,
# 0.05, 0.025 (seeds 2, 3 at 0.025: -5.3e-4, -4.3e-4), so 0.025 and 1e-3. The rolling work
# is ~0.06 E_mech0 = 60x the tolerance: leaving it out of the sum fails the test.
ENERGY_TOL = 1.0e-3


def test_energy_balance_with_rolling_dissipation():
    """30 disks settling in a closed box with friction and rolling resistance; no local
    damping, light dashpots (beta 0.05) so that the bed comes to rest in 0.3 s."""
    rng = np.random.default_rng(1)
    n, w = 30, 0.2
    sim = Simulation(gravity=(0.0, -G), damping=0.0, dt_safety=0.025, law=epsd(),
                     domain=(-0.05, -0.05, w + 0.05, 0.5))
    sim.set_contact_material(ContactMaterial(E=1.0e7, kappa=2.5, mu=0.5, beta_n=0.05,
                                             beta_s=0.05, mu_r=0.1, eta_r=0.0))
    sim.add_wall([(0.0, 0.3), (0.0, 0.0), (w, 0.0), (w, 0.3), (0.0, 0.3)])
    col, row = np.arange(n) % 10, np.arange(n) // 10
    r = rng.uniform(0.006, 0.009, n)
    sim.add_balls(0.01 + 0.02 * col, 0.0095 + 0.02 * row, r, RHO,
                  vx=rng.uniform(-0.2, 0.2, n), vy=rng.uniform(-0.2, 0.2, n),
                  omega=rng.uniform(-30.0, 30.0, n))
    e = sim.energies()
    e0 = total(e)
    mech0 = e["kinetic"] + e["gravity_potential"]     # potential zero at the floor y = 0
    worst, at = 0.0, None
    while sim.time < 0.3:
        sim.run(10000)
        e = sim.energies()
        err = (total(e) - e0) / mech0
        if abs(err) >= abs(worst):
            worst, at = err, dict(e, time=sim.time)
    roll = e["dissipated_rolling"] / mech0
    lost = 1.0 - (e["kinetic"] + e["gravity_potential"] + e["elastic_contacts"]) / mech0
    assert abs(worst) < ENERGY_TOL, \
        f"energy balance: worst (E - E0)/E_mech0 = {worst:.3e} (analytical 0, tolerance " \
        f"{ENERGY_TOL:g}) at {at}"
    assert roll > 20 * ENERGY_TOL and roll > 0.1 * lost, \
        f"rolling dissipation {roll:.3e} E_mech0 (of {lost:.3e} lost) is too small to test " \
        f"its accounting"
    assert e["kinetic"] < 0.01 * mech0, f"not settled: kinetic {e['kinetic']:.3e} J"


# ------------------------------------------------------------------ 4. checkpoint
def rolling_state(sim):
    b, p, q = sim.balls, sim.pairs, sim.wpairs
    return dict(pos=b.pos.copy(), vel=b.vel.copy(), omega=b.omega.copy(),
                force=b.force.copy(), moment=b.moment.copy(),
                pairs_ij=np.column_stack([p.i[:p.n[0]], p.j[:p.n[0]]]),
                pairs_hist=p.hist[:p.n[0]].copy(),
                wall_pairs_hist=q.hist[:q.n[0]].copy(), clumps=sim.clumps.pos.copy())


def rolling_contacts(sim):
    """Number of listed contacts whose rolling spring carries a moment."""
    c = rolling_column(sim.law)
    p, q = sim.pairs, sim.wpairs
    return (np.count_nonzero(p.hist[:p.n[0], c]) + np.count_nonzero(q.hist[:q.n[0], c]))


def test_checkpoint_restart_is_bitwise_with_rolling_law(tmp_path, small_model):
    k, more = 2500, 1500          # by step 2500 the bed has landed: rolling moments exist
    ref = small_model(1, epsd(), ContactMaterial(E=1e7, mu=0.5, beta_n=0.2, beta_s=0.1,
                                                 mu_r=0.15, kr_ratio=1.0, eta_r=0.1))
    ref.run(k, callback=lambda s: None, every=500)
    at_save = rolling_contacts(ref)
    assert at_save > 5, f"only {at_save} contacts carry a rolling moment at the checkpoint: " \
                        f"the restart of the rolling history would not be tested"
    path = tmp_path / "ck.npz"
    ref.save_checkpoint(path)
    ref.run(more)
    again = Simulation.load_checkpoint(path)
    assert again.step == k and again.law.names == ref.law.names
    again.run(more)
    assert ref.step == again.step == k + more
    a, b = rolling_state(ref), rolling_state(again)
    for name in a:
        same_shape = a[name].shape == b[name].shape
        assert same_shape and np.array_equal(a[name], b[name]), \
            f"{name} differs after restart (max |diff| " \
            f"{np.abs(a[name] - b[name]).max() if same_shape else 'shape'})"
    assert ref.energies() == again.energies()
    ca, cb = ref.contact_state(), again.contact_state()
    assert all(np.array_equal(ca[n], cb[n]) for n in ca), "contact_state differs after restart"
    assert ref.energies()["dissipated_rolling"] > 0.0 and rolling_contacts(ref) > 5
    assert len(ref.bonds) > 10, "no bonds installed: restart of bond state not tested"


# ------------------------------------------------------------------ mu_r = 0
def pile(law, mu_r):
    """Twelve disks of two sizes dropped into a frictional V of walls: rolling, sliding,
    collisions and lasting contacts."""
    sim = Simulation(gravity=(0.0, -G), law=law, domain=(-0.3, -0.1, 0.3, 0.5), damping=0.1)
    sim.set_contact_material(ContactMaterial(E=E, kappa=2.5, mu=0.5, beta_n=0.3, beta_s=0.1,
                                             mu_r=mu_r, kr_ratio=1.0, eta_r=0.3))
    sim.add_wall([(-0.2, 0.2), (0.0, 0.0), (0.2, 0.2)])
    k = np.arange(12)
    sim.add_balls(-0.05 + 0.03 * (k % 4), 0.15 + 0.03 * (k // 4), R * (1.0 + 0.3 * (k % 2)), RHO,
                  omega=0.5 * (k - 6))
    return sim


def test_mu_r_zero_is_the_law_without_rolling():
    """epsd at mu_r = 0 (with its stiffness and dashpot ratios set) carries no moment and
    leaves the timestep alone: the run equals the law without a rolling sub-model within
    round-off. The two laws compile to different kernels whose last bits differ (spins
    1e-14 rad/s apart after 5000 steps, positions still equal); the pile's collisions
    amplify that chaotically (1e-4 m by 10000 steps), so the check stops at 5000 steps,
    where mu_r = 0.3 has moved the pile ~1 cm (the comparison can fail)."""
    runs = {}
    for name, law, mu_r in (("none", ContactLaw.pfc(), 0.0), ("epsd0", epsd(), 0.0),
                            ("epsd", epsd(), 0.3)):
        sim = pile(law, mu_r)
        sim.run(5000)
        runs[name] = (sim.dt, sim.balls.pos.copy())
    assert runs["epsd0"][0] == runs["none"][0]
    assert np.abs(runs["epsd0"][1] - runs["none"][1]).max() < 1e-9
    assert np.abs(runs["epsd"][1] - runs["none"][1]).max() > 1e-3
