"""Benchmark of the form generator: every database of the config, generated and written
(netCDF + STL archive) as the workflow does it, on `--workers` processes.

    python bench/forms_benchmark.py [--config config/config.yaml] [--workers 2]

Prints one line per database (seconds, stones) and, last, the total wall time.
"""

import argparse
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor

from ballaststudy.config import database_seed, form_params, load_config, load_databases, select_databases
from ballaststudy.forms.pipeline import generate_database


def _one(job):
    name, definition, seed, params, out = job
    t0 = time.perf_counter()
    nc = generate_database(name, definition, seed, params, out)
    import xarray as xr
    with xr.open_dataset(nc) as ds:
        n = ds.sizes["stone"]
    return name, time.perf_counter() - t0, n


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--config", default="config/config.yaml")
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    cfg = load_config(args.config)
    params = form_params(cfg)
    dbs = load_databases(cfg["databases_file"], params)
    names = select_databases(cfg, dbs, args.config)
    with tempfile.TemporaryDirectory() as out:
        jobs = [(n, dbs[n], database_seed(cfg["seed"], n, dbs[n]), params, out) for n in names]
        t0 = time.perf_counter()
        with ProcessPoolExecutor(args.workers) as pool:
            for name, seconds, stones in pool.map(_one, jobs):
                print(f"database={name:9s} seconds={seconds:6.2f} stones={stones}")
        total = time.perf_counter() - t0
    print(f"databases={len(names)} workers={args.workers} total_wall_seconds={total:.1f}")


if __name__ == "__main__":
    main()
