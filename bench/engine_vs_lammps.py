"""settle2d benchmark: our numba engine vs LAMMPS on the same problem, single thread.

    NUMBA_NUM_THREADS=1 python bench/engine_vs_lammps.py [--n 5000] [--steps 20000]
        [--pairs 5] [--sizes 5000:20000,20000:40000,100000:4000] [--skip-scaling]
        [--skip-bonded] [--lammps-dir ../shared/bench/lammps]

The problem is the one of ../shared/bench/README.md: N disks on a 40-column lattice with
hash diameters/velocities (initial_state.py), LAMMPS gran/hooke/history law with m_eff
damping (the engine's ``law="hooke"``), walls x = 0, x = 0.34 m, y = 0, dt = 0.2 sqrt(m_min/kn),
skin 0.25 d_max, velocity Verlet. Everything runs on one thread (NUMBA_NUM_THREADS=1 and
OMP_NUM_THREADS=1 are set here unless already set; LAMMPS runs through run.sh, 1 process).

Three parts, in this order:

1. Headline (N = --n, steps = --steps): --pairs ALTERNATING pairs (LAMMPS run, then ours,
   LAMMPS, ours, ...) so that the machine's slow drifts hit both alike. One line per pair
   ``pair k: lammps_ball_steps_per_s=... ours_ball_steps_per_s=... ratio=...``, then the
   medians of both, the median of the per-pair ratios and ``goal_4x=met|NOT met``
   (goal: median ratio >= 4).
2. Scaling (--sizes N:STEPS,...; --skip-scaling skips it): one LAMMPS run and one of ours
   per size; a table of ball-steps/s, us/step, neighbour rebuilds and ratio, and for each
   size the final mean y / max y of ours beside LAMMPS's (its last thermo line) and the
   README's reference values when the README has them.
3. Bonded variant (ours only, same N and steps as the headline; --skip-bonded skips it):
   the same disks glued into flat-jointed 10 x 10 lattice clusters;
   ``ours_bonded_ball_steps_per_s=...`` and ``goal_bonded_2.5e7=met|NOT met``.

The last line printed is ``ratio=<median headline ratio>``.

What is timed. LAMMPS: its "Loop time" (run.sh): the timestep loop with forces, walls,
integration, neighbour rebuilds and thermo output every 2000 steps; setup excluded.
Ours: JIT compilation is warmed up once on a small system before any timing (and once more
for the bonded code path); each run builds the system and does one untimed step (setup:
first neighbour build and forces), then wall-clock (time.perf_counter) over ``sim.run(steps)``
as a whole: forces, walls, integration, every neighbour rebuild, and LAMMPS-like thermo
reductions (KE, max y, mean y over live balls) every 2000 steps. Ball-steps/s = N*steps/s.

A script that prints numbers, never a test: timings on a shared machine are noisy.
"""
import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_LAMMPS = os.path.normpath(os.path.join(HERE, "..", "..", "shared", "bench", "lammps"))

W, NCOL = 0.34, 40
S = W / NCOL
DMIN, DMAX, RHO, V0, KN = 0.004, 0.008, 2650.0, 0.5, 1.0e6
THERMO_EVERY = 2000
GOAL_RATIO = 4.0
GOAL_BONDED = 2.5e7
# settling check of ../shared/bench/README.md: (N, steps) -> (final mean y, final max y) [m]
README_REF = {(1250, 200000): (0.06724, 0.1372), (5000, 20000): (0.26059, 0.5293),
              (5000, 40000): (0.26076, 0.5297), (20000, 40000): (1.00106, 2.3755)}


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
    h = (nrow + 2) * S                 # LAMMPS box height; the column fills [0, nrow*S]
    # Domain (ball centres must stay inside) and side walls scale with the column: top at
    # 4 h + 1 m (N = 5000: 5.3 m; N = 100000: 2500 rows, h = 21.3 m, top 86 m), far above
    # anything a disk can reach from the lattice (the bed only falls).
    top = 4.0 * h + 1.0
    sim = Simulation(thickness=1.0, gravity=(0.0, -9.81), damping=0.0, dt=p["dt"],
                     skin=p["skin"], domain=(-0.01, -0.01, W + 0.01, top),
                     law="hooke", hooke={k: p[k] for k in ("kn", "kt", "gamma_n", "gamma_t", "mu")},
                     vmax=1.0e3)
    x, y, d, vx, vy = initial_state(n)
    assert y.max() + DMAX < top
    stone = -np.ones(n, np.int64)
    if bonded:
        # the same disks, grouped in clusters of 100: blocks of 10 x 10 lattice sites
        stone = (np.floor(y / S) // 10) * (NCOL // 10) + (np.floor(x / S) // 10)
    sim.add_balls(x, y, d / 2, RHO, stone_id=stone, vx=vx, vy=vy)
    sim.add_wall([(0.0, top), (0.0, 0.0), (W, 0.0), (W, top)])
    if bonded:
        # installation gap 2.5 R_min bonds every lattice neighbour of a block (gaps
        # 0.5-4.5 mm); E* = 1e6 Pa gives bond k_n A ~ the contact kn (same dt)
        sim.install_flat_joints(FlatJointMaterial(E=1.0e6, kappa=3.5, sigma_c=1e5,
                                                  c=1e5, gap_factor=2.5))
    return sim


_warmed = set()


def warm_up(bonded=False):
    """JIT compile / load the numba cache once per code path, on a small system, with
    enough steps for neighbour rebuilds and callbacks to happen."""
    if bonded in _warmed:
        return
    t0 = time.perf_counter()
    warm = build(400, bonded)
    warm.run(600, callback=lambda s: None, every=200)
    _warmed.add(bonded)
    print(f"# JIT warm-up{' (bonded)' if bonded else ''}: {time.perf_counter() - t0:.1f} s "
          f"(not timed)", flush=True)


def run_ours(n, steps, bonded=False):
    """One timed run of our engine; returns a dict (bsps, us, rebuilds, mean_y, max_y,
    ke, breakages, loop_s)."""
    warm_up(bonded)
    sim = build(n, bonded)
    sim.run(1)                                               # setup: first neighbour build
    r0 = sim.n_rebuilds
    thermo = []

    def reduce(s):                 # LAMMPS-like thermo: cheap reductions every 2000 steps
        b = s.balls
        live = b.alive == 1
        y = b.pos[live, 1]
        ke = 0.5 * (b.mass[live] * (b.vel[live] ** 2).sum(1)).sum()
        thermo.append((s.step, ke, y.max(), y.mean()))

    t0 = time.perf_counter()
    sim.run(steps, callback=reduce, every=THERMO_EVERY)
    t = time.perf_counter() - t0
    live = sim.balls.alive == 1
    y = sim.balls.pos[live, 1]
    ke = 0.5 * (sim.balls.mass[live] * (sim.balls.vel[live] ** 2).sum(1)).sum()
    return dict(bsps=n * steps / t, us=1e6 * t / steps, loop_s=t,
                rebuilds=sim.n_rebuilds - r0, mean_y=float(y.mean()), max_y=float(y.max()),
                ke=float(ke), breakages=len(sim.breakages()["step"]))


class LammpsError(RuntimeError):
    pass


def run_lammps(lammps_dir, n, steps):
    """One run.sh run; returns a dict (bsps, us, loop_s, rebuilds, mean_y, max_y, line)."""
    run_sh = os.path.join(lammps_dir, "run.sh")
    env = dict(os.environ, OMP_NUM_THREADS="1")
    with tempfile.TemporaryDirectory(prefix="settle2d_lmp_") as tmp:
        env.setdefault("LOGDIR", tmp)          # logs kept only if the caller sets LOGDIR
        out = subprocess.run([run_sh, str(n), str(steps)], capture_output=True, text=True,
                             env=env)
    if out.returncode != 0:
        raise LammpsError(f"{run_sh} {n} {steps} failed (exit {out.returncode}):\n"
                          f"{out.stdout[-2000:]}{out.stderr[-2000:]}")
    lines = [ln for ln in out.stdout.splitlines() if ln.startswith("lammps_ball_steps_per_s=")]
    if not lines:
        raise LammpsError(f"{run_sh}: no lammps_ball_steps_per_s line in:\n{out.stdout}")
    vals = dict(kv.split("=", 1) for kv in lines[-1].split())
    loop_s = float(vals["loop_s"])
    r = dict(bsps=float(vals["lammps_ball_steps_per_s"]), loop_s=loop_s,
             us=1e6 * loop_s / int(vals["steps"]), line=lines[-1],
             rebuilds=None, mean_y=float("nan"), max_y=float("nan"))
    err = out.stderr.splitlines()
    for i, ln in enumerate(err):
        if ln.startswith("Neighbor list builds"):
            try:
                r["rebuilds"] = int(ln.split("=")[1].split()[0])
            except (IndexError, ValueError):
                pass
        if ln.startswith("thermo (") and i + 2 < len(err):
            f = err[i + 2].split()             # last thermo: step atoms KE KErot ymax ymean
            if len(f) >= 6:
                r["max_y"], r["mean_y"] = float(f[4]), float(f[5])
    return r


def parse_sizes(text):
    sizes = []
    for item in text.split(","):
        item = item.strip()
        if not item:
            continue
        try:
            n, s = item.split(":")
            sizes.append((int(n), int(s)))
        except ValueError:
            raise argparse.ArgumentTypeError(f"bad size {item!r}: expected N:STEPS")
    return sizes


def headline(a):
    print(f"== headline: settle2d N={a.n} steps={a.steps}, {a.pairs} alternating pairs "
          f"(LAMMPS, ours), single thread", flush=True)
    lmp, ours, ratios = [], [], []
    last = None
    for k in range(1, a.pairs + 1):
        rl = run_lammps(a.lammps_dir, a.n, a.steps)
        ro = run_ours(a.n, a.steps)
        lmp.append(rl["bsps"])
        ours.append(ro["bsps"])
        ratios.append(ro["bsps"] / rl["bsps"])
        print(f"pair {k}: lammps_ball_steps_per_s={rl['bsps']:.4e} "
              f"ours_ball_steps_per_s={ro['bsps']:.4e} ratio={ratios[-1]:.3f}", flush=True)
        last = (rl, ro)
    rl, ro = last
    print(f"ours_us_per_step={ro['us']:.1f} ours_neighbour_rebuilds={ro['rebuilds']} "
          f"lammps_us_per_step={rl['us']:.1f} lammps_neighbour_rebuilds={rl['rebuilds']} "
          f"(last pair)")
    print(f"ours_final mean_y={ro['mean_y']:.5f} m max_y={ro['max_y']:.4f} m "
          f"KE_trans={ro['ke']:.4g} J{reference_text(a.n, a.steps, rl)}")
    med_l, med_o, med_r = (statistics.median(v) for v in (lmp, ours, ratios))
    print(f"median_lammps_ball_steps_per_s={med_l:.4e} median_ours_ball_steps_per_s={med_o:.4e} "
          f"median_ratio={med_r:.3f} (ratio min {min(ratios):.3f} max {max(ratios):.3f}, "
          f"{a.pairs} pairs)")
    print(f"goal_4x={'met' if med_r >= GOAL_RATIO else 'NOT met'} "
          f"(median ratio {med_r:.3f} {'>=' if med_r >= GOAL_RATIO else '<'} {GOAL_RATIO:g})",
          flush=True)
    return med_r


def reference_text(n, steps, rl):
    txt = f" | LAMMPS this run: mean_y={rl['mean_y']:.5f} max_y={rl['max_y']:.4f}"
    ref = README_REF.get((n, steps))
    if ref:
        txt += f" | README: mean_y={ref[0]:.5f} max_y={ref[1]:.4f}"
    return txt


def scaling(a):
    print("== scaling: one LAMMPS run and one of ours per size, single thread", flush=True)
    rows = []
    for n, steps in a.sizes:
        rl = run_lammps(a.lammps_dir, n, steps)
        ro = run_ours(n, steps)
        rows.append((n, steps, rl, ro))
        print(f"# done N={n} steps={steps}: lammps {rl['loop_s']:.1f} s, ours {ro['loop_s']:.1f} s",
              flush=True)
    hdr = (f"{'N':>7} {'steps':>7} {'lmp_bsps':>11} {'lmp_us/step':>11} {'lmp_rebuilds':>12} "
           f"{'ours_bsps':>11} {'ours_us/step':>12} {'ours_rebuilds':>13} {'ratio':>6}")
    print(hdr)
    for n, steps, rl, ro in rows:
        lr = "-" if rl["rebuilds"] is None else str(rl["rebuilds"])
        print(f"{n:>7} {steps:>7} {rl['bsps']:>11.3e} {rl['us']:>11.1f} {lr:>12} "
              f"{ro['bsps']:>11.3e} {ro['us']:>12.1f} {ro['rebuilds']:>13} "
              f"{ro['bsps'] / rl['bsps']:>6.2f}")
    for n, steps, rl, ro in rows:
        print(f"final N={n} steps={steps}: ours mean_y={ro['mean_y']:.5f} max_y={ro['max_y']:.4f}"
              f"{reference_text(n, steps, rl)}")
    sys.stdout.flush()


def bonded(a):
    print(f"== bonded: ours only, N={a.n} steps={a.steps}, flat-jointed 10x10 clusters",
          flush=True)
    rb = run_ours(a.n, a.steps, bonded=True)
    print(f"ours_bonded_ball_steps_per_s={rb['bsps']:.4e} us_per_step={rb['us']:.1f} "
          f"neighbour_rebuilds={rb['rebuilds']} bond_breakages={rb['breakages']} "
          f"mean_y={rb['mean_y']:.5f} max_y={rb['max_y']:.4f}")
    ok = rb["bsps"] >= GOAL_BONDED
    print(f"goal_bonded_2.5e7={'met' if ok else 'NOT met'} "
          f"({rb['bsps']:.3e} {'>=' if ok else '<'} {GOAL_BONDED:.1e} ball-steps/s)", flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                 formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    ap.add_argument("--n", type=int, default=5000, help="N of the headline and bonded runs")
    ap.add_argument("--steps", type=int, default=20000,
                    help="steps of the headline and bonded runs")
    ap.add_argument("--pairs", type=int, default=5,
                    help="alternating (LAMMPS, ours) pairs of the headline")
    ap.add_argument("--sizes", type=parse_sizes, default="5000:20000,20000:40000,100000:4000",
                    help="scaling table sizes, N:STEPS,N:STEPS,...")
    ap.add_argument("--skip-scaling", action="store_true")
    ap.add_argument("--skip-bonded", action="store_true")
    ap.add_argument("--lammps-dir", default=DEFAULT_LAMMPS,
                    help="directory of run.sh / in.settle2d")
    a = ap.parse_args(argv)
    if a.pairs < 1 or a.n < 1 or a.steps < 1:
        ap.error("--pairs, --n and --steps must be >= 1")
    lmp = os.environ.get("LMP", "lmp")
    if shutil.which(lmp) is None:
        print(f"LAMMPS binary {lmp!r} not found. Install it with:  apt-get install -y lammps",
              file=sys.stderr)
        return 2
    if not os.path.exists(os.path.join(a.lammps_dir, "run.sh")):
        print(f"no run.sh in {a.lammps_dir} (give --lammps-dir)", file=sys.stderr)
        return 2
    print(f"settle2d dt={derived()['dt']:.6e} NUMBA_NUM_THREADS={os.environ['NUMBA_NUM_THREADS']} "
          f"OMP_NUM_THREADS={os.environ['OMP_NUM_THREADS']} lmp={shutil.which(lmp)}", flush=True)
    try:
        med_r = headline(a)
        if not a.skip_scaling:
            scaling(a)
    except LammpsError as e:
        print(f"LAMMPS run failed: {e}", file=sys.stderr)
        return 1
    if not a.skip_bonded:
        bonded(a)
    print(f"ratio={med_r:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
