"""settle2d benchmark: our numba engine vs LAMMPS on the same problem, single thread.

    NUMBA_NUM_THREADS=1 python bench/engine_vs_lammps.py [--n 5000] [--steps 20000]
        [--lammps-dir ../shared/bench/lammps] [--skip-bonded]

The problem is the one of ../shared/bench/README.md: N disks on a 40-column lattice with
hash diameters/velocities (initial_state.py), LAMMPS gran/hooke/history law with m_eff
damping (the engine's ``law="hooke"``), walls x = 0, x = 0.34 m, y = 0, dt = 0.2 sqrt(m_min/kn),
skin 0.25 d_max, velocity Verlet. The engine is timed after a JIT warm-up, over the whole
stepping loop (neighbour rebuilds included; the thermo reductions are done every 2000
steps as in LAMMPS). Prints LAMMPS's figure (run.sh), ours, a bonded variant, and LAST
``ratio=<ours/LAMMPS>``. Never a test: timings on a shared machine are noisy.
"""
import argparse
import os
import shutil
import subprocess
import sys
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_LAMMPS = os.path.normpath(os.path.join(HERE, "..", "..", "shared", "bench", "lammps"))

W, NCOL = 0.34, 40
S = W / NCOL
DMIN, DMAX, RHO, V0, KN = 0.004, 0.008, 2650.0, 0.5, 1.0e6


def initial_state(n):
    """Reimplementation of lammps/initial_state.py (same hash, lattice index order)."""
    k = np.arange(n, dtype=np.float64)
    frac = lambda a: (lambda h: h - np.floor(h))(43758.5453 * np.sin(a * (k + 1.0)))  # noqa: E731
    col, row = np.mod(k, NCOL), np.floor(k / NCOL)
    d = DMIN + (DMAX - DMIN) * frac(12.9898)
    return ((col + 0.5) * S, (row + 0.5) * S, d,
            V0 * (2.0 * frac(78.233) - 1.0), V0 * (2.0 * frac(39.3467) - 1.0))


def derived():
    mmin = RHO * np.pi * (DMIN / 2) ** 2
    mref = RHO * np.pi * ((DMIN + DMAX) / 4) ** 2
    zeta = -np.log(0.5) / np.sqrt(np.pi ** 2 + np.log(0.5) ** 2)
    gn = 2 * zeta * np.sqrt(KN / (mref / 2))
    return dict(dt=0.2 * np.sqrt(mmin / KN), kn=KN, kt=2.0 / 7.0 * KN, gamma_n=gn,
                gamma_t=gn / 2, mu=0.5, skin=0.25 * DMAX)


def build(n, bonded=False):
    from ballaststudy.dem import FlatJointMaterial, Simulation
    p = derived()
    nrow = int(np.ceil(n / NCOL))
    h = (nrow + 2) * S
    sim = Simulation(thickness=1.0, gravity=(0.0, -9.81), damping=0.0, dt=p["dt"],
                     skin=p["skin"], domain=(-0.01, -0.01, W + 0.01, 4.0 * h + 1.0),
                     law="hooke", hooke={k: p[k] for k in ("kn", "kt", "gamma_n", "gamma_t", "mu")},
                     vmax=1.0e3)
    x, y, d, vx, vy = initial_state(n)
    stone = -np.ones(n, np.int64)
    if bonded:
        # the same disks, grouped in clusters of 100: blocks of 10 x 10 lattice sites
        stone = (np.floor(y / S) // 10) * (NCOL // 10) + (np.floor(x / S) // 10)
    sim.add_balls(x, y, d / 2, RHO, stone_id=stone, vx=vx, vy=vy)
    sim.add_wall([(0.0, h * 4.0 + 1.0), (0.0, 0.0), (W, 0.0), (W, h * 4.0 + 1.0)])
    if bonded:
        # installation gap 2.5 R_min bonds every lattice neighbour of a block (gaps
        # 0.5-4.5 mm); E* = 1e6 Pa gives bond k_n A ~ the contact kn (same dt)
        sim.install_flat_joints(FlatJointMaterial(E=1.0e6, kappa=3.5, sigma_c=1e5,
                                                  c=1e5, gap_factor=2.5))
    return sim


def run_ours(n, steps, bonded=False):
    """Returns (ball-steps/s, us/step, rebuilds, mean y, max y, KE, bonds broken)."""
    warm = build(min(n, 400), bonded)
    warm.run(50, callback=lambda s: None, every=25)           # JIT compile / load cache
    sim = build(n, bonded)
    sim.run(1)                                               # setup: first neighbour build
    r0 = sim.n_rebuilds
    thermo = []

    def reduce(s):                 # LAMMPS-like thermo: cheap reductions every 2000 steps
        live = s.balls.alive == 1
        thermo.append((s.step, s.balls.pos[live, 1].max(), s.balls.pos[live, 1].mean()))
    t0 = time.perf_counter()
    sim.run(steps, callback=reduce, every=2000)
    t = time.perf_counter() - t0
    y = sim.balls.pos[:, 1]
    ke = 0.5 * (sim.balls.mass * (sim.balls.vel ** 2).sum(1)).sum()
    nb = int(sim.log.n[0])
    return n * steps / t, 1e6 * t / steps, sim.n_rebuilds - r0, y.mean(), y.max(), ke, nb


def run_lammps(lammps_dir, n, steps):
    run_sh = os.path.join(lammps_dir, "run.sh")
    out = subprocess.run([run_sh, str(n), str(steps)], capture_output=True, text=True, check=True)
    line = [ln for ln in out.stdout.splitlines() if ln.startswith("lammps_ball_steps_per_s=")][-1]
    vals = dict(kv.split("=") for kv in line.split())
    return float(vals["lammps_ball_steps_per_s"]), line, out.stderr


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=5000)
    ap.add_argument("--steps", type=int, default=20000)
    ap.add_argument("--lammps-dir", default=DEFAULT_LAMMPS)
    ap.add_argument("--skip-bonded", action="store_true")
    a = ap.parse_args(argv)
    if shutil.which(os.environ.get("LMP", "lmp")) is None:
        print("LAMMPS binary 'lmp' not found. Install it with:  apt-get install -y lammps",
              file=sys.stderr)
        return 2
    if not os.path.exists(os.path.join(a.lammps_dir, "run.sh")):
        print(f"no run.sh in {a.lammps_dir} (give --lammps-dir)", file=sys.stderr)
        return 2
    print(f"settle2d N={a.n} steps={a.steps} dt={derived()['dt']:.6e} "
          f"NUMBA_NUM_THREADS={os.environ['NUMBA_NUM_THREADS']}")
    lmp_bsps, line, err = run_lammps(a.lammps_dir, a.n, a.steps)
    print(line)
    for ln in err.splitlines():
        if ln.startswith(("us_per_step", "Neighbor list builds", "thermo")) or ln[:1].isdigit() \
                or ln.strip()[:1].isdigit():
            print("  lammps:", ln.strip())
    bsps, us, nreb, ym, yx, ke, _ = run_ours(a.n, a.steps)
    print(f"ours_ball_steps_per_s={bsps:.4e} atoms={a.n} steps={a.steps} us_per_step={us:.1f} "
          f"neighbour_rebuilds={nreb}")
    print(f"ours_final mean_y={ym:.5f} m max_y={yx:.4f} m KE_trans={ke:.4g} J "
          f"(README N=5000/20000: mean_y 0.26059 m, max_y 0.5293 m, KE 0.0999 J)")
    if not a.skip_bonded:
        bb, ub, nrb, ymb, yxb, keb, nbrk = run_ours(a.n, a.steps, bonded=True)
        print(f"ours_bonded_ball_steps_per_s={bb:.4e} us_per_step={ub:.1f} neighbour_rebuilds={nrb} "
              f"element_breakages={nbrk} (flat-jointed 10x10 clusters)")
    print(f"ratio={bsps / lmp_bsps:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
