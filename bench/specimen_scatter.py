"""How the scatter between biaxial specimens falls with their size: K specimens (seeds) of
each size under one cyclic test, their axial strain per cycle side by side.

    NUMBA_NUM_THREADS=1 python bench/specimen_scatter.py [--sizes 0.15x0.30 0.30x0.60]
        [--seeds 1 2 3 4] [--p 60] [--deviator-min 15] [--deviator-max 230]
        [--frequency 20] [--cycles 10] [--first-loading-inertial-number 1.35e-4]
        [--library BPM.nc] [--config config/config.yaml]

Each (size, seed) is assembled from box_test's library at the config's resolution
(bench/case_benchmark.py builds and caches it), consolidated to p, loaded first (cycle 0,
at --first-loading-inertial-number: default the tests' fast rate, ten times the config's),
then cycled in real time at --frequency between p + q_min and p + q_max. Prints per run
its stones and balls, seconds, failure and axial strain after each cycle; then per size
the mean and standard deviation over the seeds of the strain after cycle 0 and after the
last cycle, of the strain gained after cycle 0 (the permanent strain of the cycles: what
the loop compares), their coefficient of variation, and how many specimens failed. A
failed specimen's curve ends at its failure and leaves the statistics of the cycles it
did not reach. Never a test.

Measured 2026-11-28 (box_test library at the config's resolution, p 60 kPa, 20 Hz, 10
cycles after cycle 0, seeds 1-4; sizes 0.15 x 0.30 / 0.225 x 0.45 / 0.30 x 0.60 m:
~37 / 83 / 142 stones, 358 / 840 / 1439 balls; the sd of log10 computed from the printed
per-seed strains):
  - q 15-230 kPa (Sun et al.'s, unmapped): one specimen of four failed in its first loading
    at every size; the survivors' strain gained in cycles 1-10 cv 0.72 / 1.05 / 0.36, sd of
    log10 0.51 / 0.60 / 0.18.
  - q 15-80 kPa: none failed; the strain after cycle 0 cv 1.74 / 1.28 / 1.58 (sd of log10
    0.75 / 0.47 / 0.92: at full size 1.6e-4 to 1.9e-2), the strain gained in cycles 1-10
    cv 1.94 / 1.14 / 1.36 (sd of log10 1.79 / 0.63 / 0.58).
The first loading's scatter does not fall with size up to the full specimen: it is set by
single events (one specimen in four strains tens of times more than the others). The
cycles' accumulation scatters less from the middle size on, still a factor ~4 (10^0.58)
between specimens at full size. With a cv near 1.4 a K-specimen ensemble mean carries a
relative standard error of ~1.4 / sqrt(K): ~0.6 at K = 6, 0.1 at K = 200.
"""
import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

os.environ.setdefault("NUMBA_NUM_THREADS", "1")
HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))


def size(text):
    w, h = (float(v) for v in text.lower().split("x"))
    return w, h


def one(lib, a, width, height, seed):
    """(stones, balls, seconds, failure, axial strain after each cycle) of one specimen."""
    from ballaststudy.config import load_config
    from ballaststudy.rig.biaxial import BiaxialRun, assemble_biaxial
    from ballaststudy.rig.kinds import params_from_config
    params = params_from_config("biaxial", load_config(a.config).get("rig", {}))
    params.width_m, params.height_m = width, height
    t = time.perf_counter()
    rig = assemble_biaxial(lib, params, seed=seed)
    p = rig.params
    p.mode, p.frequency_Hz = "real_time", a.frequency
    p.confining_pressure_kPa = a.p
    p.deviator_min_kPa, p.deviator_max_kPa = a.deviator_min, a.deviator_max
    p.first_loading_inertial_number = a.first_loading_inertial_number
    run = BiaxialRun(rig, cycles=1 + a.cycles).run()
    alive = rig.sim.balls.alive.astype(bool)
    stones = len(np.unique(rig.sim.balls.stone[alive]))
    strain = [r.get("axial_strain", np.nan) for r in run.s.rows]
    return stones, int(alive.sum()), time.perf_counter() - t, run.s.failure, strain


def statistics(label, runs, cycles):
    """Per size: mean, sd and cv over the seeds (NaN where a run ended before)."""
    curves = np.full((len(runs), 1 + cycles), np.nan)
    for k, (*_, strain) in enumerate(runs):
        curves[k, :len(strain)] = strain[:1 + cycles]
    first, last = curves[:, 0], curves[:, -1]
    gained = last - first
    failed = sum(1 for r in runs if r[3])

    def msd(v):
        v = v[np.isfinite(v)]
        if v.size < 2:
            return f"n={v.size}"
        m, s = v.mean(), v.std(ddof=1)
        # strains spread over decades (one specimen's event): the spread of log10 says it
        log = f", sd of log10 {np.log10(v).std(ddof=1):.2f}" if np.all(v > 0) else ""
        return f"{m:.4g} +- {s:.2g} (cv {s / abs(m):.2f}{log}, n={v.size})" if m else f"{m:.3g}"
    stones = np.mean([r[0] for r in runs])
    print(f"{label}: {stones:.0f} stones, {np.mean([r[1] for r in runs]):.0f} balls a "
          f"specimen; failed {failed} of {len(runs)}; axial strain after cycle 0 {msd(first)}; "
          f"after cycle {cycles} {msd(last)}; gained in cycles 1-{cycles} {msd(gained)}",
          flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=size, nargs="+", default=[(0.15, 0.30), (0.30, 0.60)],
                    help="WIDTHxHEIGHT [m]")
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3, 4])
    ap.add_argument("--p", type=float, default=60.0, metavar="KPA")
    ap.add_argument("--deviator-min", type=float, default=15.0, metavar="KPA")
    ap.add_argument("--deviator-max", type=float, default=230.0, metavar="KPA")
    ap.add_argument("--frequency", type=float, default=20.0)
    ap.add_argument("--cycles", type=int, default=10)
    ap.add_argument("--first-loading-inertial-number", type=float, default=1.35e-4)
    ap.add_argument("--library", help="a BPM.nc (default: box_test's, built once)")
    ap.add_argument("--config", default="config/config.yaml")
    a = ap.parse_args(argv)
    from case_benchmark import box_test_library

    from ballaststudy.rig.library import load_library
    lib = load_library(a.library or box_test_library(a.config))
    print(f"p {a.p:g} kPa, q {a.deviator_min:g}-{a.deviator_max:g} kPa, {a.frequency:g} Hz "
          f"real time, {a.cycles} cycles after cycle 0 (I = {a.first_loading_inertial_number:g})",
          flush=True)
    tempfile.tempdir = tempfile.mkdtemp()
    table = {}
    for w, h in a.sizes:
        runs = []
        for seed in a.seeds:
            r = one(lib, a, w, h, seed)
            runs.append(r)
            print(f"{w:g} x {h:g} m seed {seed}: {r[0]} stones, {r[1]} balls, {r[2]:.0f} s, "
                  f"{r[3] or 'no failure'}; axial strain per cycle "
                  + " ".join(f"{v:.4g}" for v in r[4]), flush=True)
        table[(w, h)] = runs
    for (w, h), runs in table.items():
        statistics(f"{w:g} x {h:g} m", runs, a.cycles)
    return 0


if __name__ == "__main__":
    sys.exit(main())
