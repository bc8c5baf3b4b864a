"""The thesis' scale (Wang 2018 ch. 5) and whether a study runs far below it.

Thesis: 10 simulation cases per form database (5.1; 4.3: "10 cases in this study") and 1000
load cycles per case (4.2.3: "only 1,000 loading steps are performed in the simulation";
5.3: "the 1000 loading cycles").

Far below = fewer than half the thesis' cases in some database, or fewer than 10 % of its
load cycles in some run case. Why these limits:
- cycles: the thesis' findings are about the behaviour accumulated over 1000 cycles, and
  settlement grows fastest in the first cycles (thesis 4.1, Fig. 4-2); a run an order of
  magnitude shorter is still dominated by that shakedown of the packing, and its "over the
  cycles" spreads (FPA, ghost particles) are sds of a few numbers.
- cases: the findings' intervals resample cases within each database, and n cases give
  only C(2n-1, n) distinct resamples of a mean: 3 at n = 2, 35 at n = 4, 126 at n = 5, so
  below 5 a 95 % interval rests on a handful of values.
The smallest database and the shortest case set the scale, since every finding compares
databases."""

import numpy as np

THESIS_DATABASES = [f"G_{g}-{i}" for g in (1, 2, 3) for i in range(1, 6)]   # Table 3-1: 3 groups x 5
THESIS_CASES = 10
THESIS_CYCLES = 1000
MIN_CASES = THESIS_CASES // 2
MIN_CYCLES = THESIS_CYCLES // 10
SCALE_RULE = (f"far below the thesis' scale: fewer than {MIN_CASES} cases (half of the thesis' {THESIS_CASES}) "
              f"in some database, or fewer than {MIN_CYCLES} load cycles (10 % of the thesis' {THESIS_CYCLES}) "
              "in some case that ran")


def cycles_run(study):
    """(database, case) array of the load cycles each case ran (0: no case): `cycles_run`
    of study.nc, else the count of finite settlement values."""
    if "cycles_run" in study:
        return np.asarray(study["cycles_run"].values, int)
    return np.isfinite(study["settlement"].values).sum(axis=-1)


def extent(study):
    """(cases, cycles): the fewest cases of a database and the fewest cycles of a run case."""
    run = cycles_run(study)
    ran = run[run > 0]
    return int((run > 0).sum(axis=1).min()), int(ran.min()) if ran.size else 0


def far_below(cases, cycles):
    """True if a study of `cases` per database and `cycles` per case is far below the thesis' scale."""
    return cases < MIN_CASES or cycles < MIN_CYCLES


def describe(cases, cycles):
    """One sentence with our numbers against the thesis'."""
    return (f"This study ran {cases} case{'s' if cases != 1 else ''} per database and {cycles} load "
            f"cycle{'s' if cycles != 1 else ''} per case (fewest over databases and cases); the thesis ran "
            f"{THESIS_CASES} cases per database and {THESIS_CYCLES} load cycles (Wang 2018, 4.2.3 and 5.1).")
