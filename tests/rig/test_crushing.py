"""Single-stone crushing (rig/crushing.py; issue 74's check "single-stone crushing: the
survival probability against characteristic stress matches the configured Weibull modulus
within its 90 % interval over >= 50 stones"), and the Weibull fit it rests on, tested where
the answer is known: planted (sigma0, m) recovered with intervals that cover at their
level, censoring handled, and a sample that is not Weibull (all alike) not fitted as a
wide one."""
import numpy as np
import pytest

from ballaststudy.dem import crushing
from ballaststudy.rig.crushing import crush, weibull_fit
from ballaststudy.rig.library import Library, synthetic_library

SIGMA0, M, D0 = 3e6, 4.0, 0.04


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


def test_rigid_stones_crushed_between_platens_follow_their_weibull(library):
    """60 stones of the synthetic library, each split at its own drawn strength: the
    crushing test (platen force, first split) recovers the configured law."""
    out = [crush(library, k, "rigid", seed=3, splitting=dict(sigma0=SIGMA0, m=M, d0=D0))
           for k in range(len(library))]
    assert all(c.failed for c in out)
    fit = weibull_fit([c.stress for c in out], [c.diameter for c in out],
                      [c.failed for c in out], D0)
    assert fit["m_low"] <= M <= fit["m_high"], fit
    assert fit["sigma0"] == pytest.approx(SIGMA0, rel=0.15), fit
