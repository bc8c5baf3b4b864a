"""Recovery on the DEM itself (issue 13's test, re-planned for issue 34): "measured" curves
made by the model with known F_str_co and mu (not Table 4.2's) under three conditions, each
on a fresh specimen the calibration never sees (a laboratory test is a specimen of its
own), plus a digitisation noise, are calibrated back jointly with the biaxial rig on two
other specimens (tests/calibration/recovery.py): the true values lie inside the 90 %
intervals, and the friction's interval is narrower than its prior.

Measured 2026-11-27 (likelihood of calibration.bayes): 78 DEM cases, mu 90 % [0.70, 1.19]
(62 % of the prior; true 0.9), F_str_co [1.26, 5.75] (90 %; true 2.0); 11 min on 2 cores
shared with a calibration run (~5 min alone).

Other designs (bench/calibration_recovery.py; calibration specimens seeds 1..K, truths
101..; one draw each):

| K | conditions | consolidation windows | mu, F_str_co: 90 % interval / prior |
|---|---|---|---|
| 2 | 1 | 1000 steps (the other tests') | 89 %, 88 % |
| 2 | 3 | 1000 steps | 74 %, 82 % |
| 2 | 1 | 5000 (the config's, as here) | 59 %, 85 % |
| 2 | 3 | 5000 | 58 %, 79 % |
| 4 | 1 | 5000 | 83 %, 84 % |
| 4 | 3 | 5000 | 71 %, 82 % |

The truth was inside every interval. Widths from one draw scatter from 58 to 89 % for mu
with no order in K or conditions, so this test asserts only "narrower than the prior" (90 %)
for mu: what the design shows is that F_str_co, acting only through the few bonds that
break, is not identified at this scale (79-90 % everywhere), and that the lab specimen's
own offset stays in the residual however many specimens of ours run (covariance
C (1 + 1/K)). Until 2026-11-27 the test asserted mu < 65 % on one curve with 1000-step
windows: it passed (56 %) under a likelihood that counted a specimen's offset once per
point, and failed on main since (86 %; 89 % under the new likelihood)."""
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
