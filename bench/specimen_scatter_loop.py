"""How the scatter between biaxial specimens falls with their size over many cycles: the
permanent axial strain per specimen of one scenario's cases, read from a loop run's cache
(`ballaststudy loop ... --specimens <a set of one size>`, e.g. with `loop.effects: []`), one
folder per size. A quasi-static loop runs the tests of one p and q as one scenario (it reads
no f): its plain cases are the one folder under the run's cases/. Prints per folder and
specimen the strain at the given N (those the cases reached), the increments between them
(percentage points), and per increment the mean, the standard deviation and the sd of log10
over the specimens that had not given way. Never a test.

    python bench/specimen_scatter_loop.py LABEL=CASES_DIR [LABEL=CASES_DIR ...] [--at 1 12 100 500]

CASES_DIR holds case<k>.nc (the loop's case files, each with its metrics group).
"""
import argparse
import re
from pathlib import Path

import numpy as np

from ballaststudy.inputs import open_netcdf
from ballaststudy.scenario.results import case_curve


def cases(folder):
    """{k: (strain per cycle N = 1.. [%], failed)} of the case<k>.nc in ``folder``; a failed
    case's cycles from its failure on are NaN (not the censored value the loop fits)."""
    out = {}
    for path in sorted(Path(folder).glob("case*.nc"), key=lambda p: int(re.sub(r"\D", "", p.stem) or 0)):
        if not re.fullmatch(r"case\d+", path.stem):
            continue
        rows = open_netcdf(path, "metrics")["axial_strain"].size
        curve, failed = case_curve(path, "axial_strain", rows)
        out[int(path.stem[4:])] = (100.0 * curve, failed)
    return out


def table(label, folder, at):
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
    for a, b in windows:
        d = value[:, at.index(b)] - value[:, at.index(a)]
        d = d[np.isfinite(d)]
        log = np.log10(d[d > 0])
        print(f"  d({a}->{b}) [% points]: mean {d.mean():.3f}, sd {d.std(ddof=1):.3f}, "
              f"sd of log10 {log.std(ddof=1) if log.size > 1 else float('nan'):.2f} ({log.size} of {d.size} > 0)")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folders", nargs="+", metavar="LABEL=CASES_DIR")
    ap.add_argument("--at", type=int, nargs="+", default=[1, 12, 100, 500], metavar="N")
    a = ap.parse_args(argv)
    for run in a.folders:
        label, _, folder = run.partition("=")
        table(label, folder, sorted(a.at))


if __name__ == "__main__":
    main()
