"""Single-stone crushing (rig/crushing.py; issue 74's check "single-stone crushing: the
survival probability against characteristic stress matches the configured Weibull modulus
within its 90 % interval over >= 50 stones"), and the Weibull fit it rests on, tested where
the answer is known: planted (sigma0, m) recovered with intervals that cover at their
level, censoring handled, and a sample that is not Weibull (all alike) not fitted as a
wide one."""
import numpy as np
import pytest
from scipy.stats import binom

from ballaststudy.dem import crushing
from ballaststudy.rig.crushing import crush, weibull_fit
from ballaststudy.rig.library import Library, synthetic_library

SIGMA0, M, D0 = 3e6, 4.0, 0.04
REPLICATES = 10
AT_LEAST = int(binom.ppf(0.02, REPLICATES, 0.9))


def _planted(rng, n, censor_at=None):
    d = rng.uniform(0.02, 0.06, n)
    s = crushing.weibull_strength(rng.random(n), d, SIGMA0, M, D0)
    failed = np.ones(n, bool)
    if censor_at is not None:
        failed = s < censor_at
        s = np.minimum(s, censor_at)
    return s, d, failed


def test_the_fit_recovers_a_planted_weibull_and_its_interval_covers():
    rng = np.random.default_rng(0)
    fits = [weibull_fit(*_planted(rng, 60), D0) for _ in range(100)]
    cover = np.mean([f["m_low"] <= M <= f["m_high"] for f in fits])
    assert 0.8 <= cover <= 0.97, cover           # 90 % nominal; 100 replicates: +-0.05 is 2 sd
    assert np.median([f["m"] for f in fits]) == pytest.approx(M, rel=0.1)
    assert np.median([f["sigma0"] for f in fits]) == pytest.approx(SIGMA0, rel=0.05)


def test_censored_stones_count_as_survivors():
    rng = np.random.default_rng(1)
    s, d, failed = _planted(rng, 400, censor_at=SIGMA0)
    assert 0.2 < failed.mean() < 0.8
    fit = weibull_fit(s, d, failed, D0)
    assert fit["m_low"] <= M <= fit["m_high"] and fit["sigma0"] == pytest.approx(SIGMA0, rel=0.1)
    naive = weibull_fit(s, d, np.ones_like(failed), D0)    # censored taken as failures
    assert not naive["m_low"] <= M <= naive["m_high"]


def test_strengths_all_alike_are_not_fitted_as_a_wide_weibull():
    fit = weibull_fit(np.full(50, 2e6) * (1 + 1e-3 * np.arange(50)), np.full(50, D0),
                      np.ones(50, bool), D0)
    assert fit["m_low"] > 50


@pytest.fixture(scope="module")
def library():
    return Library(synthetic_library(n_stones=60, seed=4))


def _series(library, seed):
    out = [crush(library, k, "rigid", seed=seed, splitting=dict(sigma0=SIGMA0, m=M, d0=D0))
           for k in range(len(library))]
    assert sum(c.failed for c in out) >= 0.9 * len(out)    # the rest censored (kept in the fit)
    return out, weibull_fit([c.stress for c in out], [c.diameter for c in out],
                            [c.failed for c in out], D0)


def test_the_platens_measure_each_rigid_stones_drawn_strength(library):
    """60 stones crushed rigid: each split is measured at or above the strength it drew,
    by at most what the force gains between two stress checks (10 steps here: up to 11 %
    on the stiffest contacts; the platen force at the split against the criterion's
    largest neighbour's), and the series' fit lands near
    the configured law (its coverage: the slow test below)."""
    out, fit = _series(library, 1)
    ratios = [c.stress / c.drawn for c in out if c.failed]
    assert 0.99 < min(ratios) and max(ratios) < 1.15, (min(ratios), max(ratios))
    assert fit["sigma0"] == pytest.approx(SIGMA0, rel=0.2) and fit["m"] == pytest.approx(M, rel=0.3), fit


@pytest.mark.slow
def test_rigid_stones_crushed_between_platens_follow_their_weibull(library):
    """REPLICATES series of 60 stones (seeds 1..10, the first ten, none screened; ~4 min):
    each series' 90 % interval of m holds the configured m in at least AT_LEAST of them
    (fewer: < 2 % if they cover 90 %). A series that misses is a draw, not the rig, when
    its drawn strengths' own fit misses too (as one did with an earlier set of seeds:
    m 5.1 [4.3, 5.9] for 4)."""
    hits = 0
    for seed in range(1, REPLICATES + 1):
        _, fit = _series(library, seed)
        hits += fit["m_low"] <= M <= fit["m_high"]
    assert hits >= AT_LEAST, hits
