"""Recovery on the DEM itself (issue 13's test, re-planned for issue 34): "measured" curves
made by the model with known F_str_co and mu (not Table 4.2's) under three conditions, each
on a fresh specimen the calibration never sees (a laboratory test is a specimen of its
own), plus a digitisation noise, are calibrated back jointly with the biaxial rig on two
other specimens (tests/calibration/recovery.py). One draw of a 90 % interval misses one
time in ten, so coverage is counted over REPLICATES recoveries with fresh truth specimens
and noise (the calibration specimens, and the initial design's cases, shared): each true
value inside at least AT_LEAST of them (fewer: < 2 % if they cover 90 %), and the
friction's intervals narrower than its prior (median).

Measured 2026-11-29 (`python -m pytest -m slow -n 0 -s tests/calibration/test_recovery.py`:
66 min on 2 cores, half of it beside other work; 228
calibration scenarios of 2 cases, 21 a replicate after the first's 42): covered F_str_co 7,
mu 9 of 10; median share of the prior 73 % and 62 %. F_str_co is hardly identified: every
posterior mean lies above the truth (2.7-4.5 for 2.0), the intervals reach the prior's
upper part (4.5-5.8 of 6) and the three misses are at their lower end (2.23, 2.92, 2.78) -
at the edge of what 90 % coverage allows (7 of 10 or fewer: 7 %). Replicate 0 is the one
draw this test asserted until 2026-11-29: F_str_co [2.23, 5.63] missed 2.0 there since
2026-11-28 (it held [1.26, 5.75] on 2026-11-27; the cause of the change is not traced).

Measured 2026-12-06 at 5b63865 (after the biaxial platen's mass was corrected from 2.2x to
the documented one, which changes every biaxial curve; 31 min beside other work; 186
scenarios): FAILS, F_str_co covered 6 of 10 (at least 7), mu 10; the misses again at the
lower end (2.07-2.19 for 2.0), posterior means 2.97-4.07: the upward bias of F_str_co is
the same as before and the corrected platen tipped one more interval past the truth. Not
traced; it is the calibration's, not the platen's (the platen is now as documented)."""
import numpy as np
import pytest
from scipy.stats import binom

from .recovery import LOWER, TRUE, UPPER, covered, replicates

CONDITIONS_KPA = [(30.0, 200.0), (60.0, 200.0), (30.0, 150.0)]
REPLICATES = 10
# at least this many of REPLICATES intervals hold each true value: fewer happens with
# probability < 2 % when they cover 90 %
AT_LEAST = int(binom.ppf(0.02, REPLICATES, 0.9))


@pytest.mark.slow
def test_calibration_intervals_cover_the_truth_over_fresh_specimens(small_library, tmp_path):
    recs = replicates(small_library, tmp_path, calibration_seeds=(7, 8), conditions_kPa=CONDITIONS_KPA,
                      count=REPLICATES, first_truth_seed=9)
    hits = covered(recs)
    shares = np.array([(r.result.posterior.interval90[:, 1] - r.result.posterior.interval90[:, 0]) / (UPPER - LOWER)
                       for r in recs])
    run = len(list((tmp_path / "cal" / "cases").iterdir()))
    print(f"\nrecovery x {REPLICATES}: {run} calibration scenarios run; true {TRUE}")
    for r, rec in enumerate(recs):
        post = rec.result.posterior
        print(f"  {r}: mean {post.mean.round(3)}, 90 % {post.interval90.round(3).tolist()} "
              f"({np.round(100 * shares[r])} % of the prior), holds {hits[r].tolist()}, ESS {post.ess:.0f}")
    print(f"covered {hits.sum(axis=0).tolist()} of {REPLICATES} (at least {AT_LEAST}); "
          f"median share of the prior {np.round(100 * np.median(shares, axis=0)).tolist()} %")
    assert np.all(hits.sum(axis=0) >= AT_LEAST), hits.sum(axis=0)
    assert np.median(shares[:, 1]) < 0.9, shares[:, 1]
