"""Bonded against rigid stones side by side on the same specimens: the behaviours of
loading runs of each model, case by case, at given cycles.

    python bench/stone_models_compare.py BONDED_DIR RIGID_DIR [--at 10 100 1000]
        [--names case0 case1 ...]

Each DIR holds ``<case>/metrics.nc`` of ``ballaststudy case run --stone-model <model>``
(box rig) on the same assembled specimens (matched by the case folder's name). Per
behaviour and cycle: each model's mean and sample sd over the cases, the paired
difference rigid - bonded (mean, its 90 % t interval) and the sd of the paired
differences against the models' own scatter. A difference whose interval excludes 0 is
one the seeds resolve; the scatter says whether it matters. Never a test."""
import argparse
from pathlib import Path

import numpy as np
import xarray as xr
from scipy import stats

BEHAVIOURS = (("settlement", 1e3, "mm"), ("broken_mass_share", 100.0, "%"), ("breakage_rate", 100.0, "%"),
              ("breakages_per_cycle", 1.0, "1"), ("void_ratio", 1.0, "1"),
              ("fpa", 1.0, "deg"), ("ghost_particles", 1.0, "1"),
              ("mean_coordination", 1.0, "1"))


def cases(folder):
    return {p.parent.name: p for p in sorted(Path(folder).glob("*/metrics.nc"))}


def value(path, name, cycle):
    with xr.open_dataset(path) as ds:
        if name not in ds or ds.sizes["cycle"] <= cycle:
            return np.nan
        if name == "breakages_per_cycle":          # a cumulative count up to the cycle
            return float(ds[name].values[: cycle + 1].sum())
        return float(ds[name].values[cycle])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("bonded")
    ap.add_argument("rigid")
    ap.add_argument("--at", type=int, nargs="+", default=[10, 100, 1000], help="cycles (1-based)")
    a = ap.parse_args(argv)
    b, r = cases(a.bonded), cases(a.rigid)
    names = sorted(set(b) & set(r), key=lambda n: (len(n), n))
    print(f"{len(names)} specimens run with both models: {' '.join(names)}")
    for name, scale, units in BEHAVIOURS:
        for n in a.at:
            x = np.array([value(b[c], name, n - 1) for c in names]) * scale
            y = np.array([value(r[c], name, n - 1) for c in names]) * scale
            ok = np.isfinite(x) & np.isfinite(y)
            if ok.sum() < 2:
                continue
            x, y = x[ok], y[ok]
            d = y - x
            half = stats.t.ppf(0.95, len(d) - 1) * d.std(ddof=1) / np.sqrt(len(d))
            label = "cumulative breakages" if name == "breakages_per_cycle" else name
            print(f"{label:>21s} N={n:<5d} [{units}] bonded {x.mean():8.3f} sd {x.std(ddof=1):7.3f} | "
                  f"rigid {y.mean():8.3f} sd {y.std(ddof=1):7.3f} | rigid-bonded {d.mean():+8.3f} "
                  f"[{d.mean() - half:+.3f}, {d.mean() + half:+.3f}] sd {d.std(ddof=1):.3f} (n={len(d)})")


if __name__ == "__main__":
    main()
