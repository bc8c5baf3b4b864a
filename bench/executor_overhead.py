"""The cost of running a calibration round's cases on Dask instead of the local pool, with
the same cores: one round of `--sets` values of mu x the given specimens, `--cycles`
cycles, into a fresh folder (nothing cached), on `--executor local` (ProcessPoolExecutor
of --cores processes) or `--executor dask` (a distributed.LocalCluster of --cores
single-thread worker processes set up as the jobqueue executor's are: the runner imported
as they start, one task a worker at a time; started and closed inside the timing). Prints the wall
time of the round and of the cluster's start. Time the two side by side:

    farm-bench -n 3 --timeout 900 -- python bench/executor_overhead.py --executor dask SPECIMENS... \
        --vs 'python bench/executor_overhead.py --executor local SPECIMENS...'

SPECIMENS: assembled biaxial specimens, e.g. results/specimens/biaxial_small/case{0,1}.nc
(`snakemake --cores 2 results/specimens/biaxial_small/case1.nc`); --config the config
they were made with and --conditions a measured test's conditions YAML."""
import argparse
import shutil
import tempfile
import time
from pathlib import Path

import dask
import numpy as np
from distributed import Client, LocalCluster

from ballaststudy.calibration.evaluate import Evaluator
from ballaststudy.cluster.pool import SCHEDULER, WORKER_CONFIG, WORKER_PRELOAD, DaskPool, LocalPool


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("specimens", nargs="+", type=Path)
    ap.add_argument("--executor", choices=("local", "dask"), required=True)
    ap.add_argument("--config", type=Path, default=Path("config/config.yaml"))
    ap.add_argument("--conditions", type=Path, default=Path("config/measured/sun_et_al_16/p60_q230_f5.yaml"))
    ap.add_argument("--sets", type=int, default=4)
    ap.add_argument("--cycles", type=int, default=12)
    ap.add_argument("--cores", type=int, default=2)
    args = ap.parse_args()
    thetas = np.linspace(0.4, 1.0, args.sets)[:, None]
    out = Path(tempfile.mkdtemp(prefix="executor_overhead-"))
    t0 = time.perf_counter()
    try:
        if args.executor == "local":
            started = time.perf_counter()
            _round(args, thetas, out, LocalPool(args.cores))
        else:
            with dask.config.set({**SCHEDULER, **WORKER_CONFIG}), LocalCluster(
                    n_workers=args.cores, threads_per_worker=1, processes=True, dashboard_address=None,
                    preload=list(WORKER_PRELOAD)) as cluster, Client(cluster) as client:
                started = time.perf_counter()
                _round(args, thetas, out, DaskPool(client))
        done = time.perf_counter()
    finally:
        shutil.rmtree(out, ignore_errors=True)
    print(f"{args.executor}: {args.sets * len(args.specimens)} cases, round {done - started:.2f} s, "
          f"start {started - t0:.2f} s, total {done - t0:.2f} s")


def _round(args, thetas, out, pool):
    ev = Evaluator(["mu"], args.specimens, [(args.conditions, np.array([1.0, 5.0]))], args.config, args.cycles,
                   "axial_strain", out, pool=pool)
    ev(thetas)


if __name__ == "__main__":
    main()
