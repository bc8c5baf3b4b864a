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
from ballaststudy.loop.discrepancy import loglik, make_discrepancy
from ballaststudy.loop.select import (candidate_covariances, fit_all, independent_tests, residual_covariances,
                                      residual_dof)

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
            ll = per_test_loglik(mean, np.zeros_like(mean), y, point_test, covs, dof).sum(axis=1)
            interval = weighted_fit(GRID, ll - ll.max())[2][0]
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


def scattering_coverage(draws, scale, k=3):
    """(coverage, mean width over the prior's 90 %) of fit_all's 90 % intervals on rate, each
    (under the plain model's covariance, under the candidate's own), where the effect makes
    every specimen scatter ``scale`` x the plain model's (its offsets scaled), the lab
    specimen too."""
    hits, width = np.zeros(2), np.zeros(2)
    for seed in range(draws):
        rng = np.random.default_rng(3000 + seed)
        n, point_test = _points(rng)
        theta = 0.2 + 0.6 * rng.random()
        y = (_specimens(rng, n, point_test, "rate", theta, 1, scale * rng.normal(0, 0.002, (1, TESTS)))[0]
             + rng.normal(0, MEAS_SD, len(n)))
        offsets = rng.normal(0, 0.002, (k, TESTS))
        plain = _specimens(rng, n, point_test, None, 0.0, k, offsets)
        thetas = initial_design([0.0], [1.0], SETS, seed=seed + 1)
        runs = [_specimens(rng, n, point_test, "rate", th[0], k, scale * offsets) for th in thetas]
        noise = residual_covariances(plain, point_test, MEAS_SD ** 2)
        covs = noise[0]
        for j, fit_covs in enumerate((None, candidate_covariances(runs, point_test, MEAS_SD ** 2, noise)[0])):
            lo, hi = fit_all(thetas, runs, y, point_test, [0.0], [1.0], covs, dof=residual_dof(k),
                             fit_covs=fit_covs)[1][0]
            hits[j] += lo <= theta <= hi
            width[j] += (hi - lo) / 0.9
    return hits / draws, width / draws


def test_an_effect_that_makes_specimens_scatter_is_fitted_under_its_own_scatter():
    """Rate, K = 3, 20 draws, the effect's specimens scattering 5 x the plain model's (as
    real-time loading makes DEM specimens give way: rate's sets scatter 3-9 x the plain
    model's in strain, docs/loop/inference.md), the lab specimen too. Fitted under the
    candidate's own covariance (select.candidate_covariances) the intervals widen and hold
    the planted value in at least 15 of 20 (a 90 % method fails this 1 time in 90).
    Measured 2026-12-07 over 40 draws: coverage 0.825 under the plain model's covariance,
    0.975 under the candidate's own, 1.45 x as wide (0.043 and 0.063 of the prior): on this
    formula model the t's scale absorbs most of the plain covariance's error (0.825 is not
    significantly below 0.9); on the DEM truths the candidate's own scatter is what made the
    intervals hold (docs/loop/inference.md)."""
    (plain, own), (w_plain, w_own) = scattering_coverage(20, 5.0)
    print(f"\nrate, specimens scattering 5 x under the effect, 20 draws: coverage {plain:.2f} -> {own:.2f}, "
          f"width/prior {w_plain:.3f} -> {w_own:.3f} (plain model's covariance -> the candidate's own)")
    assert own >= 0.75 and w_own > 1.2 * w_plain, (plain, own, w_plain, w_own)


def _shared_draw(effect, seed, k, shared_sd):
    """As _draw, but the measured tests are one lab specimen under all of them (one offset
    shared by every test, of sd ``shared_sd``: a ballast unlike ours), the issue 75 case."""
    rng = np.random.default_rng(5000 + seed)
    n, point_test = _points(rng)
    theta = 0.2 + 0.6 * rng.random()
    lab = np.full((1, TESTS), rng.normal(0, shared_sd))
    y = _specimens(rng, n, point_test, effect, theta, 1, lab)[0] + rng.normal(0, MEAS_SD, len(n))
    offsets = rng.normal(0, 0.002, (k, TESTS))
    return theta, y, point_test, n, offsets, _specimens(rng, n, point_test, None, 0.0, k, offsets)


def shared_coverage(effect, draws, shared_sd, k=3):
    """(coverage, mean width over the prior's 90 %) of the 90 % intervals, tests independent
    (the likelihood before issue 75) and with the discrepancy."""
    hits, width = np.zeros(2), np.zeros(2)
    for seed in range(draws):
        theta, y, point_test, n, offsets, plain = _shared_draw(effect, seed, k, shared_sd)
        covs, _ = residual_covariances(plain, point_test, MEAS_SD ** 2)
        mean = _exact_mean(effect, n, point_test, offsets)
        for j, disc in enumerate((independent_tests(point_test), make_discrepancy(y, n, point_test, ["lab"] * TESTS))):
            ll = loglik(y[None] - mean, np.zeros_like(mean), covs, point_test, disc, residual_dof(k))
            lo, hi = weighted_fit(GRID, ll - ll.max())[2][0]
            hits[j] += lo <= theta <= hi
            width[j] += (hi - lo) / 0.9
    return hits / draws, width / draws


def test_one_lab_specimen_under_every_test_the_discrepancy_keeps_the_intervals_honest():
    """Issue 75's case on the planted formula model: one lab specimen whose offset is shared
    by the 7 tests. Measured 2026-12-06, 200 draws, coverage of rate's 90 % intervals, tests
    independent / with the discrepancy: shared sd 0 0.83 / 0.865, 0.003 (1.5 x our
    specimens') 0.58 / 0.865, 0.006 0.45 / 0.865 - the discrepancy absorbs the offset
    whatever its size, and rate, acting through f from test to test, stays identified (width
    0.04 of the prior's). Here 100 draws at 0.006 (binomial sd 0.034). An effect shaped like
    the shared offset (bedding, a constant) is then not told from it: its interval is the
    prior's (what the report calls 'cannot tell'), where before it covered a few per cent
    of the draws at a tenth of the prior's width - a precise wrong answer."""
    (before, after), (w_before, w_after) = shared_coverage("rate", 100, 0.006)
    print(f"\nrate, one shared lab specimen, 100 draws: coverage {before:.2f} -> {after:.2f}, "
          f"width/prior {w_before:.3f} -> {w_after:.3f}")
    assert after >= 0.78 and after >= before + 0.2, (before, after)
    assert w_after < 0.1                                          # rate stays identified
    (before, after), (w_before, w_after) = shared_coverage("bedding", 20, 0.006)
    print(f"bedding: coverage {before:.2f} -> {after:.2f}, width/prior {w_before:.3f} -> {w_after:.3f}")
    assert w_after > 0.8 and after >= 0.9 and before < 0.5, (before, after, w_after)
