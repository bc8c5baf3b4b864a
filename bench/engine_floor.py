"""Where a settle2d step's time goes, and the floor under it (issue 11: the 4x LAMMPS goal).

    NUMBA_NUM_THREADS=1 python bench/engine_floor.py [--n 5000] [--at 2000 6000 12000 20000]
        [--reps 200]

Runs settle2d (bench/engine_vs_lammps.py's problem) and, at each step count of --at, times
each kernel of a step alone, --reps times inside numba (no Python call per repetition),
printing the fastest of 5 such timings in us:

  pair      the ball-ball loop (contacts.pair_forces, the engine's law)
  skeleton  the same loop's memory work with a trivial law: the same list entries, rows of
            the packed kinematics of both balls, history row read and written, forces
            stored per contact and added to both balls, the same touch test - no frame, no
            square root or division, no Coulomb limit. What the loop costs before its
            arithmetic.
  loads     the skeleton's loads alone: the list entries and both balls' rows, summed into
            one number, nothing stored. What any loop over this list costs at the least.
  walls, first, second, rebuild   the ball-wall loop, the two half steps, one neighbour
            rebuild.
All but the rebuild run with dt = 0: nothing moves and no shear history grows, so every
repetition sees the snapshot's state (with dt > 0 the same velocities, applied over and
over, would push ever more contacts to slide).

Then per snapshot: pair - skeleton, the law's cost in the real loop, and ``floor`` =
skeleton + walls + first + second: a step's cost before any contact arithmetic and before
neighbour rebuilds (the run's rebuild count is printed: amortise ``rebuild`` over it). The
4x goal's budget is LAMMPS's us/step / 4 (engine_vs_lammps.py measures LAMMPS on this
machine). Printed numbers only; never a test.
"""
import argparse
import os
import sys
import tempfile
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from numba import njit  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import engine_vs_lammps as settle2d  # noqa: E402
from ballaststudy.dem import contacts as C  # noqa: E402
from ballaststudy.dem import engine as E  # noqa: E402
from ballaststudy.dem import integrate as I  # noqa: E402
from ballaststudy.dem import params as P  # noqa: E402
from ballaststudy.dem import walls as W  # noqa: E402
from ballaststudy.dem.jit import LOOP  # noqa: E402


@njit(**LOOP, inline="always")
def both_rows(kin, pr, p):
    """List entry p's balls i, j, their distance (dx, dy), squared d2, contact reach rs
    and the trivial law's value f (every float of both rows read once)."""
    i = pr.i[p]
    j = pr.j[p]
    dx = kin[j, 0] - kin[i, 0]
    dy = kin[j, 1] - kin[i, 1]
    rs = kin[i, 5] + kin[j, 5]
    d2 = dx * dx + dy * dy
    f = (rs * rs - d2 + kin[j, 2] - kin[i, 2] + kin[j, 3] - kin[i, 3]
         + kin[i, 4] + kin[j, 4] + kin[i, 6] + kin[j, 6])
    return i, j, dx, dy, d2, rs, f


@njit(**LOOP)
def skeleton(kin, fa, pr, scale):
    """The pair loop's loads and stores around a trivial law (see the module doc)."""
    hist, p_fn, p_fs = pr.hist, pr.fn, pr.fs
    width = hist.shape[1]
    for p in range(pr.n[0]):
        i, j, dx, dy, d2, rs, f = both_rows(kin, pr, p)
        if d2 >= rs * rs:
            for c in range(width):
                hist[p, c] = 0.0
            p_fn[p] = 0.0
            p_fs[p] = 0.0
            continue
        f *= scale
        for c in range(width):
            hist[p, c] = scale * hist[p, c] + f
        p_fn[p] = f * dx
        p_fs[p] = f * dy
        fa[j, 0] += f * dx
        fa[j, 1] += f * dy
        fa[i, 0] -= f * dx
        fa[i, 1] -= f * dy
        fa[i, 2] += f
        fa[j, 2] += f


@njit(**LOOP)
def loads(kin, pr):
    """The skeleton's loads with nothing stored: the list's i, j and both balls' rows."""
    acc = 0.0
    for p in range(pr.n[0]):
        _, _, _, _, d2, rs, f = both_rows(kin, pr, p)
        acc += f if d2 < rs * rs else 0.0
    return acc


def make_kernels(law):
    """The timing loops, with the law bound as a compile-time constant (dem/bound.py)."""
    @njit
    def pair(reps, run, kin, fa, pr, act):
        for _ in range(reps):
            C.pair_forces(law, run, kin, fa, pr, act)

    @njit
    def skel(reps, kin, fa, pr):
        for _ in range(reps):
            skeleton(kin, fa, pr, 1e-30)

    @njit
    def load(reps, kin, pr):
        acc = 0.0
        for _ in range(reps):
            acc += loads(kin, pr)
        return acc

    @njit
    def walls(reps, run, kin, fa, w, wp):
        for _ in range(reps):
            W.wall_forces(law, run, kin, fa, w, wp)

    @njit
    def first(reps, prm, kin, fa, b, cl, free):
        for _ in range(reps):
            I.first_half(prm, kin, fa, b, cl, free, 2 * free.shape[0] > kin.shape[0])

    @njit
    def second(reps, prm, kin, fa, b, e, free):
        for _ in range(reps):
            I.second_half(prm, kin, fa, b, e, free, 2 * free.shape[0] > kin.shape[0])

    @njit
    def rebuild(reps, run, b, w, pr, wp, bo):
        for _ in range(reps):
            E.rebuild_lists(run, b, w, pr, wp, bo)
    return dict(pair=pair, skeleton=skel, loads=load, walls=walls, first=first, second=second,
                rebuild=rebuild)


def best_us(fn, args, reps):
    fn(1, *args)                                    # compile / warm
    times = []
    for _ in range(5):
        t0 = time.perf_counter()
        fn(reps, *args)
        times.append((time.perf_counter() - t0) / reps * 1e6)
    return min(times)


def snapshot(sim, kernels, reps):
    """Times of the kernels at the state of ``sim`` (on a copy: rebuilds reset its lists)."""
    with tempfile.TemporaryDirectory() as tmp:
        sim.save_checkpoint(os.path.join(tmp, "state.npz"))
        sim = type(sim).load_checkpoint(os.path.join(tmp, "state.npz"))
    run, b, w = sim._run_state(), sim.balls.kernel(), sim.walls.kernel()
    pr, wp, bo, cl = sim.pairs.kernel(), sim.wpairs.kernel(), sim.bonds.kernel(), sim.clumps.kernel()
    kin = np.empty((b.pos.shape[0], 8))
    C.pack_kinematics(b, kin)
    fa = np.zeros((b.pos.shape[0], 4))
    i, j = pr.i[: pr.n[0]], pr.j[: pr.n[0]]
    touching = ((kin[j, :2] - kin[i, :2]) ** 2).sum(1) < (kin[i, 5] + kin[j, 5]) ** 2
    r = dict(contacts=int(touching.sum()), pairs=int(pr.n[0]))
    still = run._replace(prm=run.prm.copy(), eacc=run.eacc.copy())
    still.prm[P.DT] = 0.0
    r["pair"] = best_us(kernels["pair"], (still, kin, fa, pr, bo.active), reps)
    r["skeleton"] = best_us(kernels["skeleton"], (kin, fa, pr), reps)
    r["loads"] = best_us(kernels["loads"], (kin, pr), reps)
    r["walls"] = best_us(kernels["walls"], (still, kin, fa, w, wp), reps)
    free = np.nonzero((b.clump < 0) & (b.alive != 0))[0]       # as engine.run_steps lists them
    r["first"] = best_us(kernels["first"], (still.prm, kin, fa, b, cl, free), reps)
    r["second"] = best_us(kernels["second"], (still.prm, kin, fa, b, still.eacc, free), reps)
    r["rebuild"] = best_us(kernels["rebuild"], (run, b, w, pr, wp, bo), max(1, reps // 10))
    return r


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=5000)
    ap.add_argument("--at", type=int, nargs="+", default=[2000, 6000, 12000, 20000])
    ap.add_argument("--reps", type=int, default=200)
    a = ap.parse_args(argv)
    settle2d.warm_up()
    sim = settle2d.build(a.n)
    sim.run(1)
    kernels = make_kernels(sim._layout)
    cols = ("pair", "skeleton", "loads", "walls", "first", "second", "rebuild")
    print(f"settle2d N={a.n}: us per call, fastest of 5 x {a.reps} (rebuild: x {max(1, a.reps // 10)})")
    print(f"{'step':>6} {'pairs':>6} {'touching':>8} " + " ".join(f"{c:>9}" for c in cols)
          + f" {'pair-skeleton':>13} {'floor':>7}")
    for step in sorted(a.at):
        sim.run(step - sim.step)
        r = snapshot(sim, kernels, a.reps)
        print(f"{step:>6} {r['pairs']:>6} {r['contacts']:>8} " + " ".join(f"{r[c]:>9.1f}" for c in cols)
              + f" {r['pair'] - r['skeleton']:>13.1f}"
              + f" {r['skeleton'] + r['walls'] + r['first'] + r['second']:>7.1f}", flush=True)
    print(f"neighbour rebuilds in the run: {sim.n_rebuilds} in {sim.step} steps (the last snapshot's "
          f"rebuild amortised: {r['rebuild'] * sim.n_rebuilds / sim.step:.1f} us/step)")


if __name__ == "__main__":
    main()
