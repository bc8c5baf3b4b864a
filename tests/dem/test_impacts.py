"""Verification cases 1-3 (physics spec): normal and oblique impacts, PFC linear law."""
import math

import numpy as np

from ballaststudy.dem import ContactMaterial, Simulation

R, RHO, E = 0.01, 2650.0, 1.0e8
M = RHO * math.pi * R ** 2          # t = 1 m


def damped_reference(beta, w0):
    """(e, t_c) of the linear spring-dashpot: unclamped (spec formula) and no-tension
    (contact force ends when k d + c d' = 0, closed form of the damped oscillator)."""
    wd = w0 * math.sqrt(1 - beta ** 2)
    e_free = math.exp(-math.pi * beta / math.sqrt(1 - beta ** 2))
    tc_free = math.pi / wd
    # force zero: tan(wd t) = -2 beta sqrt(1-beta^2) / (1 - 2 beta^2)
    ts = (math.pi + math.atan(-2 * beta * math.sqrt(1 - beta ** 2) / (1 - 2 * beta ** 2))) / wd
    v = math.exp(-beta * w0 * ts) * (math.cos(wd * ts) - beta * w0 / wd * math.sin(wd * ts))
    return e_free, tc_free, abs(v), ts


def collide(beta, no_tension, wall):
    """Head-on impact at 1 m/s; returns (restitution, force duration, t_c analytical...)."""
    mc = M if wall else M / 2
    kn = 2 * E if wall else E       # A E / L: ball-facet 2Rt E / R, ball-ball 2Rt E / 2R
    w0 = math.sqrt(kn / mc)
    e_free, tc_free, e_nt, tc_nt = damped_reference(beta, w0)
    dt = min(tc_free, tc_nt) / 400
    sim = Simulation(gravity=(0, 0), dt=dt, domain=(-1, -1, 1, 1))
    sim.set_contact_material(ContactMaterial(E=E, kappa=2.5, mu=0.5, beta_n=beta,
                                             no_tension=no_tension))
    if wall:
        sim.add_wall([(-0.5, 0.0), (0.5, 0.0)])
        sim.add_balls(0.0, R + 0.002, R, RHO, vy=-1.0)
    else:
        sim.add_balls([-R - 0.002, R + 0.002], [0, 0], [R, R], RHO, vx=[1.0, -1.0])
    touching = []

    def probe(s):
        f = s.wall_force() if wall else s.pairs.fn[: s.pairs.n[0]]
        touching.append(bool(np.any(f != 0)))
    sim.run(int(3 * tc_free / dt) + int(0.004 / dt), callback=probe, every=1)
    v = sim.balls.vel
    e = v[0, 1] / 1.0 if wall else (v[1, 0] - v[0, 0]) / 2.0
    duration = sum(touching) * dt
    return e, duration, (e_nt, tc_nt) if no_tension else (e_free, tc_free)


def check(e, duration, ref, tol=0.01):
    e_ref, tc_ref = ref
    assert abs(e - e_ref) <= tol * e_ref, f"restitution measured {e:.5f} analytical {e_ref:.5f}"
    assert abs(duration - tc_ref) <= tol * tc_ref, \
        f"contact duration measured {duration:.6e} analytical {tc_ref:.6e}"


def test_case1_two_disks_head_on_spec_formula():
    """Case 1 with the dashpot allowed to pull (PFC dashpot mode 0): e, t_c of the spec."""
    check(*collide(0.2, no_tension=False, wall=False))


def test_case1_two_disks_head_on_no_tension():
    """Case 1 with the default no-tension clamp: e, t_c of the clamped oscillator."""
    check(*collide(0.2, no_tension=True, wall=False))


def test_case2_disk_wall_normal_impact():
    check(*collide(0.3, no_tension=False, wall=True))
    check(*collide(0.3, no_tension=True, wall=True))


def test_case3_oblique_wall_impact_sliding():
    """e = 1 (no dashpot), v_t > 6 mu v_n: dv_t = -2 mu v_n, domega = -4 mu v_n / R."""
    mu, vn, vt = 0.1, 1.0, 1.0
    sim = Simulation(gravity=(0, 0), dt=2e-7, domain=(-1, -1, 1, 1))
    sim.set_contact_material(ContactMaterial(E=1.0e9, kappa=2.5, mu=mu))
    sim.add_wall([(-0.5, 0.0), (0.5, 0.0)])
    sim.add_balls(0.0, R + 0.0005, R, RHO, vx=vt, vy=-vn)
    sim.run(3000)
    assert np.all(sim.wall_force() == 0), "still in contact"
    dvt = sim.balls.vel[0, 0] - vt
    dw = sim.balls.omega[0]
    for name, got, ref in (("dv_t", dvt, -2 * mu * vn), ("domega", dw, -4 * mu * vn / R),
                           ("v_n after", sim.balls.vel[0, 1], vn)):
        assert abs(got - ref) <= 0.02 * abs(ref), f"{name} measured {got:.6g} analytical {ref:.6g}"


def test_hooke_law_restitution_matches_lammps_setup():
    """The benchmark law (LAMMPS gran/hooke/history, m_eff damping, no clamp): gamma_n
    chosen for e = 0.5 between two 6 mm disks -> measured e = 0.5, t_c = pi / omega_d."""
    rho, r, kn = 2650.0, 0.003, 1.0e6
    meff = rho * math.pi * r * r / 2
    zeta = -math.log(0.5) / math.sqrt(math.pi ** 2 + math.log(0.5) ** 2)
    gn = 2 * zeta * math.sqrt(kn / meff)
    tc = math.pi / (math.sqrt(kn / meff) * math.sqrt(1 - zeta ** 2))
    dt = tc / 400
    sim = Simulation(gravity=(0, 0), dt=dt, domain=(-1, -1, 1, 1), law="hooke",
                     hooke=dict(kn=kn, kt=2 * kn / 7, gamma_n=gn, gamma_t=gn / 2, mu=0.5))
    sim.add_balls([-r - 1e-4, r + 1e-4], [0, 0], [r, r], rho, vx=[0.5, -0.5])
    touching = []
    sim.run(int(2 * tc / dt), callback=lambda s: touching.append(s.pairs.fn[0] != 0), every=1)
    e = (sim.balls.vel[1, 0] - sim.balls.vel[0, 0]) / 1.0
    dur = sum(touching) * dt
    assert abs(e - 0.5) <= 0.005, f"hooke restitution measured {e:.5f} expected 0.5"
    assert abs(dur - tc) <= 0.01 * tc, f"hooke contact duration {dur:.4e} expected {tc:.4e}"
