"""Coverage of the loop's 90 % intervals when the measured specimen is not one of ours
(issue 34), counted over draws: test_select's planted model (a base curve per test, a
specimen's offset along the whole curve, chaos per run), K specimens of ours shared by the
plain model and every set (common random numbers, as the Evaluator runs them), and each
"measured" test a fresh specimen of its own with the effect at a planted strength drawn in
[0.2, 0.8], plus the digitiser's noise. The likelihood is the loop's (residual_covariances,
residual_dof), against the normal it used before.

The likelihood alone is counted on many draws with the exact ensemble mean (no surrogate,
so the count measures the likelihood); fit_all, surrogate and all, on fewer."""
import numpy as np
import pytest

from ballaststudy.calibration.bayes import initial_design, per_test_loglik, weighted_fit
from ballaststudy.loop.select import fit_all, residual_covariances, residual_dof

from .test_select import MEAS_SD, SETS, TESTS, _points, _specimens

GRID = np.linspace(0.0, 1.0, 1001)[:, None]


def _draw(effect, seed, k):
    """(planted theta, measured y, point_test, n, the K shared specimens' offsets, plain runs, rng)."""
    rng = np.random.default_rng(1000 + seed)
    n, point_test = _points(rng)
    theta = 0.2 + 0.6 * rng.random()
    y = _specimens(rng, n, point_test, effect, theta, 1)[0] + rng.normal(0, MEAS_SD, len(n))
    offsets = rng.normal(0, 0.002, (k, TESTS))
    plain = _specimens(rng, n, point_test, None, 0.0, k, offsets)
    return theta, y, point_test, n, offsets, plain, rng


def _exact_mean(effect, n, point_test, offsets):
    """The K specimens' ensemble mean without chaos at every GRID value (each effect is linear
    in theta)."""
    at = [_specimens(np.random.default_rng(0), n, point_test, effect, th, len(offsets), offsets, chaos=0.0).mean(axis=0)
          for th in (0.0, 1.0)]
    return at[0] + GRID * (at[1] - at[0])


def likelihood_coverage(effect, k, draws):
    """(coverage of the 90 % interval under the loop's t, under the normal)."""
    hits = np.zeros(2)
    for seed in range(draws):
        theta, y, point_test, n, offsets, plain, _ = _draw(effect, seed, k)
        covs, _ = residual_covariances(plain, point_test, MEAS_SD ** 2)
        mean = _exact_mean(effect, n, point_test, offsets)
        for j, dof in enumerate((residual_dof(k), None)):
            loglik = per_test_loglik(mean, np.zeros_like(mean), y, point_test, covs, dof).sum(axis=1)
            interval = weighted_fit(GRID, loglik - loglik.max())[2][0]
            hits[j] += interval[0] <= theta <= interval[1]
    return hits / draws


@pytest.mark.parametrize("effect", ["growth", "rate"])
def test_the_loops_intervals_cover_planted_values_on_fresh_specimens(effect):
    """K = 3, 100 draws (binomial sd of a 90 % count: 3 %). Measured 2026-11-28: t 0.92 /
    0.87 (growth / rate), normal 0.66 / 0.70; at K = 6 both ~0.95."""
    t, normal = likelihood_coverage(effect, 3, 100)
    print(f"\n{effect} coverage over 100 draws, K = 3: t {t:.2f}, normal {normal:.2f}")
    assert t >= 0.8, t
    assert t >= normal + 0.1, (t, normal)


@pytest.mark.parametrize("k", [
    pytest.param(3, marks=pytest.mark.xfail(strict=True, reason=(
        "measured 0.47 (normal 0.39): bedding, a constant shift, is told from a specimen's offset "
        "(which grows gently with ln N) only by the covariance's direction, which 3 specimens carrying "
        "chaos estimate poorly; with the true covariance 0.90"))),
    12])
def test_an_effect_shaped_like_a_specimens_offset_needs_more_specimens(k):
    """Measured 2026-11-28 (100 draws, t / normal): K = 3 0.47 / 0.39, 6 0.77 / 0.81, 12
    0.84 / 0.91, 24 0.89 / 0.94."""
    t, normal = likelihood_coverage("bedding", k, 100)
    print(f"\nbedding coverage over 100 draws, K = {k}: t {t:.2f}, normal {normal:.2f}")
    assert t >= 0.8, t


def test_the_loops_fit_covers_planted_values_on_fresh_specimens():
    """fit_all (the loop's surrogate and posterior) on rate, K = 3, over 20 draws: the
    planted value inside the 90 % interval in at least 15 (a 90 % method fails this 1 time
    in 90). Measured 2026-11-28: 0.95 (over 40 other draws t 0.875, normal 0.675; growth
    0.90, 0.65)."""
    hits = 0
    for seed in range(20):
        theta, y, point_test, n, offsets, plain, rng = _draw("rate", seed, 3)
        thetas = initial_design([0.0], [1.0], SETS, seed=seed + 1)
        runs = [_specimens(rng, n, point_test, "rate", th[0], 3, offsets) for th in thetas]
        covs, _ = residual_covariances(plain, point_test, MEAS_SD ** 2)
        interval = fit_all(thetas, runs, y, point_test, [0.0], [1.0], covs, dof=residual_dof(3))[1][0]
        hits += interval[0] <= theta <= interval[1]
    print(f"\nfit_all coverage of rate over 20 draws, K = 3: {hits / 20:.2f}")
    assert hits >= 15, hits
