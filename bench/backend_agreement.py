"""Two calibrations' evaluations.nc side by side (e.g. --backend cpu and --backend cuda of
the same inputs): their curves under the parameter sets both evaluated.

    python bench/backend_agreement.py CPU/evaluations.nc CUDA/evaluations.nc

For every parameter set in both (the design's first round and Table 4.2's are the same
in both runs; later rounds follow each run's own results), per specimen (case) the
largest |difference| of the simulated curve over the cycles, beside the specimens'
scatter under that set (the standard deviation over the cases, per cycle, its largest)
and the difference of the ensemble means. Prints one line per set, then the verdict:
the backends agree within the specimens' scatter where every set's mean difference is
smaller than its scatter / sqrt(K) x 2 (two standard errors of a K-specimen mean).
"""
import argparse
import sys

import numpy as np
import xarray as xr


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("first", help="evaluations.nc (the reference, e.g. cpu)")
    ap.add_argument("second", help="evaluations.nc (e.g. cuda)")
    ap.add_argument("--quantity", default="axial_strain")
    a = ap.parse_args(argv)
    one, two = xr.open_dataset(a.first), xr.open_dataset(a.second)
    q = a.quantity
    agree, shared = True, 0
    for s in range(one.sizes["set"]):
        theta = one["parameter_value"].values[s]
        match = np.nonzero(np.all(np.isclose(two["parameter_value"].values, theta,
                                             rtol=1e-12, atol=0), axis=1))[0]
        if not match.size:
            continue
        shared += 1
        x, y = one[q].values[s, 0], two[q].values[match[0], 0]     # (case, cycle)
        k = x.shape[0]
        per_case = np.nanmax(np.abs(x - y), axis=1)
        scatter = float(np.nanmax(np.nanstd(x, axis=0, ddof=1)))
        mean_diff = float(np.nanmax(np.abs(np.nanmean(x, axis=0) - np.nanmean(y, axis=0))))
        ok = mean_diff <= 2 * scatter / np.sqrt(k)
        agree &= ok
        failed = (int(one["failed"].values[s].sum()), int(two["failed"].values[match[0]].sum()))
        print(f"set {s} (round {int(one['round'].values[s])}) "
              f"{ {str(n): round(float(v), 4) for n, v in zip(one['parameter'].values, theta)} }: "
              f"max |diff| per case {np.array2string(per_case, precision=3)}, "
              f"mean curves' max |diff| {mean_diff:.3g}, scatter (sd over {k} cases) "
              f"{scatter:.3g}, failed {failed[0]} / {failed[1]}: "
              f"{'within' if ok else 'OUTSIDE'} 2 standard errors")
    if not shared:
        print("no parameter set in both files")
        return 1
    print(f"{shared} shared sets: the backends "
          + ("agree within the specimens' scatter" if agree else "DISAGREE beyond the scatter"))
    return 0 if agree else 1


if __name__ == "__main__":
    sys.exit(main())
