"""The cost per step of compiling the kernels for a portable CPU target: steps of an
assembled specimen's engine (from its stored checkpoint: gravity on the settled pile, every
contact and flat joint live) timed after a warm-up, under whatever NUMBA_CPU_NAME this
process has. Time the portable target against the host's side by side:

    farm-bench -n 5 --vs 'sh -c "exec python bench/cpu_target.py ASSEMBLED >>/tmp/host.log"' -- \
        sh -c 'NUMBA_CPU_NAME=generic exec python bench/cpu_target.py ASSEMBLED >>/tmp/generic.log'

ASSEMBLED: e.g. results/cases/box_test/case1/assembled.nc (box) or a biaxial specimen.
Prints ``cpu_target=<name> us_per_step=<x>`` (the best of --reps timings of --steps steps);
numba caches each target's code apart, so the first run of a target compiles it."""
import argparse
import os
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

from numba.core import config  # noqa: E402

from ballaststudy.inputs import open_netcdf  # noqa: E402
from ballaststudy.rig.kinds import kind_of, rig_classes  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("assembled")
    ap.add_argument("--steps", type=int, default=2000)
    ap.add_argument("--reps", type=int, default=3)
    args = ap.parse_args()
    ds = open_netcdf(args.assembled, "assembled")
    sim = rig_classes(kind_of(ds))[0].from_dataset(ds, "engine_checkpoint").sim
    sim.run(200)                                     # compiled or loaded, caches warm
    best = float("inf")
    for _ in range(args.reps):
        t0 = time.perf_counter()
        sim.run(args.steps)
        best = min(best, time.perf_counter() - t0)
    print(f"cpu_target={config.CPU_NAME or 'host'} balls={len(sim.balls)} us_per_step={1e6 * best / args.steps:.2f}")


if __name__ == "__main__":
    main()
