"""How the scatter between biaxial specimens falls with their size over many cycles: the
permanent axial strain per specimen of one scenario's cases, read from a loop run's cache
(`ballaststudy loop ... --specimens <a set of one size>`, e.g. with `loop.effects: []`), one
folder per size. A quasi-static loop runs the tests of one p and q as one scenario (it reads
no f): its plain cases are the one folder under the run's cases/. Prints per folder and
specimen the strain at the given N (those the cases reached), the increments between them
(percentage points), and per increment the mean, the standard deviation and the sd of log10
over the specimens that had not given way, with the sd's 90 % interval (chi-square); then
each further folder's variance against the first one's (F test, one-sided: smaller than the
first's). Never a test.

    python bench/specimen_scatter_loop.py LABEL=CASES_DIR [LABEL=CASES_DIR ...] [--at 1 12 100 500]

CASES_DIR holds case<k>.nc (the loop's case files, each with its metrics group).

Measured 2026-11-30 (the plain model, quasi-static, under Sun et al.'s p = 60 kPa, q 230 kPa
tests, config.yaml's settings, stress_mapping none; fresh box_test specimens the loop never
saw: small = 0.15 x 0.30 m, cases 10-15 of biaxial_small, 47-58 stones, 527-570 balls, run to
N = 2000; medium = 0.225 x 0.45 m, cases 10-13, 103-118 stones, 1176-1214 balls, assembled
by `ballaststudy case assemble ... --width-m 0.225 --height-m 0.45`, run to N = 500: 63.5 M
steps, 15.9 M a specimen, ~13.5k steps/s on one core, half the small size's). Increments in
percentage points, mean / sd over the specimens (none gave way), by
`python bench/specimen_scatter_loop.py small=<session 66's run>/cases/d7c35d54a892
medium=<this run>/cases/67f09b74e457 --at 1 12 25 100 500` (the 25 -> 500 row from --at 25 500):
  - d(1->12):    small 0.41 / 0.28 (6), medium 0.50 / 0.19 (4)
  - d(100->500): small 2.65 / 3.43,     medium 2.87 / 2.39 (sd of log10 0.92 / 0.33)
  - d(25->500):  small 3.83 / 4.75,     medium 3.60 / 2.83
The sd falls by 0.70 and 0.60 from the small to the medium size (1 / sqrt of the area ratio
2.25: 0.67), but with 6 and 4 specimens the fall is not resolved (F test of the variances p
0.29 and 0.21; the medium sd's 90 % interval for d(100->500) is [1.5, 7.0]). At both sizes
single specimens still jump: +8.8 points in 100->500 (small case13), +6.3 (medium case12).
Over shorter windows the fall is larger: d(12->25) sd 0.95 -> 0.11 (F p 0.002), d(25->100)
2.69 -> 0.56 (p 0.013); of the six windows printed, Holm keeps the first only (0.014, then 0.067),
and small's d(25->100) sd is one specimen's +6.7-point jump (case10).
Sun's measured increment over 25->500 runs from 1.1 (f = 5 Hz) to 8.4 (60 Hz), a step of 7.3
points: 1.5 small-specimen sds, 2.6 medium ones.
"""
import argparse
import re
from pathlib import Path

import numpy as np
from scipy import stats

from ballaststudy.inputs import open_netcdf


def cases(folder):
    """{k: (strain per cycle N = 1.. [%], failed)} of the case<k>.nc in ``folder``: the rows
    as run, so a failed case's curve ends at its failure (not censored as the loop fits it)."""
    paths = [p for p in Path(folder).glob("case*.nc") if re.fullmatch(r"case\d+", p.stem)]
    out = {}
    for path in sorted(paths, key=lambda p: int(p.stem[4:])):
        metrics = open_netcdf(path, "metrics")
        out[int(path.stem[4:])] = (100.0 * metrics["axial_strain"].values, bool(metrics.attrs.get("failed")))
    return out


def sd_interval(d, level=0.90):
    """The (lo, hi) interval of the sd of the population ``d`` was drawn from (chi-square)."""
    dof, tail = d.size - 1, (1.0 - level) / 2.0
    return tuple(d.std(ddof=1) * np.sqrt(dof / stats.chi2.ppf(q, dof)) for q in (1.0 - tail, tail))


def table(label, folder, at):
    """Print the folder's table; returns {(a, b): the increments of the specimens left}."""
    runs = cases(folder)
    if not runs:
        raise SystemExit(f"{folder}: no case<k>.nc")
    reached = max(c.size for c, _ in runs.values())
    at = [n for n in at if n <= reached]
    value = np.array([[c[n - 1] if n <= c.size else np.nan for n in at] for c, _ in runs.values()])
    windows = list(dict.fromkeys(list(zip(at[:-1], at[1:])) + [(at[0], at[-1])]))
    failed = [k for k, (_, f) in runs.items() if f]
    print(f"\n{label} ({folder}): {len(runs)} specimens, N reached {reached}; gave way: {failed or 'none'}")
    print("case " + " ".join(f"{f'eps({n})':>9}" for n in at) + " |"
          + " ".join(f"{f'd({a}->{b})':>11}" for a, b in windows))
    for k, v in zip(runs, value):
        print(f"{k:4d} " + " ".join(f"{x:9.3f}" for x in v) + " |"
              + " ".join(f"{v[at.index(b)] - v[at.index(a)]:11.3f}" for a, b in windows))
    out = {}
    for a, b in windows:
        d = value[:, at.index(b)] - value[:, at.index(a)]
        out[a, b] = d = d[np.isfinite(d)]
        log = np.log10(d[d > 0])
        lo, hi = sd_interval(d)
        print(f"  d({a}->{b}) [% points]: mean {d.mean():.3f}, sd {d.std(ddof=1):.3f} (90 % [{lo:.2f}, {hi:.2f}]), "
              f"sd of log10 {log.std(ddof=1) if log.size > 1 else float('nan'):.2f} ({log.size} of {d.size} > 0)")
    return out


def compare(first, other, label, first_label):
    """Each window both reached: the other's sd over the first's, F test p (other smaller)."""
    for w in sorted(first.keys() & other.keys()):
        x, y = first[w], other[w]
        f = y.var(ddof=1) / x.var(ddof=1)
        print(f"  d({w[0]}->{w[1]}): sd {label} / {first_label} {np.sqrt(f):.2f}, "
              f"F test p {stats.f.cdf(f, y.size - 1, x.size - 1):.2g}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folders", nargs="+", metavar="LABEL=CASES_DIR")
    ap.add_argument("--at", type=int, nargs="+", default=[1, 12, 100, 500], metavar="N")
    a = ap.parse_args(argv)
    runs = [(label, table(label, folder, sorted(a.at)))
            for label, _, folder in (r.partition("=") for r in a.folders)]
    for label, increments in runs[1:]:
        print(f"\n{label} against {runs[0][0]}:")
        compare(runs[0][1], increments, label, runs[0][0])


if __name__ == "__main__":
    main()
