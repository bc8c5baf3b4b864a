"""Calibration recovery on the DEM at a chosen design (issue 34: what pins the magnitudes).

The slow test tests/calibration/test_recovery.py at other scales (tests/calibration/
recovery.py): "measured" curves made by the model with known F_str_co and mu on fresh
specimens, one per test condition, plus a digitisation noise, calibrated back jointly on K
other specimens. Prints the 90 % intervals, their share of the prior, whether they hold the
truth, the RMSE before/after and the DEM cases run.

    NUMBA_NUM_THREADS=1 python bench/calibration_recovery.py --specimens 2 --conditions 30:200
    NUMBA_NUM_THREADS=1 python bench/calibration_recovery.py --specimens 4 \
        --conditions 30:200 60:200 30:150

Each condition is p:q_max in kPa (q_min 10 kPa, 5 Hz quasi-static). Calibration specimens
have seeds 1..K, the truths 101, 102, ... With ``--replicates R`` the recovery is made R
times with fresh truth specimens and noise (tests.calibration.recovery.replicates: the
calibration specimens and the initial design's cases shared) and the coverage of the 90 %
intervals is counted over them.
"""
import argparse
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from ballaststudy.calibration.bayes import rmse  # noqa: E402
from ballaststudy.rig.library import synthetic_library  # noqa: E402
from tests.calibration.recovery import LOWER, TRUE, UPPER, covered, replicates  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--specimens", type=int, default=2, help="K, the calibration's specimens")
    ap.add_argument("--conditions", nargs="+", default=["30:200"], help="p:q_max [kPa] per test")
    ap.add_argument("--cycles", type=int, default=5)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--seed", type=int, default=11)
    ap.add_argument("--replicates", type=int, default=1, help="recoveries with fresh truths and noise")
    ap.add_argument("--work-dir", type=Path, help="keep the specimens and cases here (default: a temporary folder)")
    args = ap.parse_args(argv)
    conditions = [tuple(float(v) for v in c.split(":")) for c in args.conditions]
    t0 = time.time()
    with tempfile.TemporaryDirectory() as tmp:
        folder = args.work_dir or Path(tmp)
        folder.mkdir(parents=True, exist_ok=True)
        library = folder / "BPM.nc"
        synthetic_library(24, size=(0.035, 0.065), r0=0.008, seed=3, database="tiny").to_netcdf(library)
        recs = replicates(library, folder, range(1, args.specimens + 1), conditions, args.replicates,
                          cycles=args.cycles, jobs=args.jobs, seed=args.seed)
        run = len(list((folder / "cal" / "cases").iterdir()))
    print(f"design: K = {args.specimens}, conditions {args.conditions}, {args.cycles} cycles; "
          f"{args.replicates} recoveries, {run} calibration scenarios of K cases run in "
          f"{(time.time() - t0) / 60:.1f} min")
    for r, rec in enumerate(recs):
        post = rec.result.posterior
        for k, name in enumerate(TRUE):
            lo, hi = post.interval90[k]
            print(f"  {r}: {name}: true {TRUE[name]}, mean {post.mean[k]:.3f}, 90 % [{lo:.3f}, {hi:.3f}] "
                  f"({100 * (hi - lo) / (UPPER[k] - LOWER[k]):.0f} % of the prior), "
                  f"{'holds' if lo <= TRUE[name] <= hi else 'MISSES'} the truth")
        print(f"  {r}: RMSE Table 4.2 {rmse(rec.result.curves[0].mean(axis=0), rec.y):.4g} -> posterior mean "
              f"{rmse(rec.after.mean(axis=0), rec.y):.4g}; ESS {post.ess:.0f}; t dof {rec.result.dof}")
    print(f"covered: {dict(zip(TRUE, covered(recs).sum(axis=0).tolist()))} of {args.replicates}")


if __name__ == "__main__":
    main()
