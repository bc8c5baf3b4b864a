"""Calibration by a GP surrogate and Bayesian posterior: parameters of a planted model are
recovered, an ignored parameter stays at its prior, and the building blocks give known answers."""
from dataclasses import replace

import numpy as np
import pytest

from ballaststudy.calibration.bayes import (calibrate, ensemble_stats, initial_design, next_batch, posterior,
                                            rmse, Surrogate, weighted_quantile)

N = np.array([1.0, 2.0, 5.0, 10.0, 20.0, 50.0])
SD = 0.002        # case-to-case scatter of the planted model
K = 3             # cases per parameter set
LOWER_AB, UPPER_AB = np.array([0.5, 0.0]), np.array([3.0, 2.0])


def planted_curve(theta):
    """Settlement-like: compaction a, creep rate b, an interaction; any further parameter is
    ignored. The two shapes differ enough that the exact posterior's 90 % intervals are about
    12 % of the prior width (for 0.01 a ln N + 0.005 b + 0.001 a b sqrt N, b's is ~50 %: the
    shapes are nearly collinear on these N)."""
    a, b = theta[0], theta[1]
    return 0.02 * a * (1.0 - np.exp(-N / 3.0)) + 0.001 * b * N + 0.002 * a * b


def planted_model(seed):
    """evaluate() for calibrate: K noisy cases per parameter set, and a count of its calls."""
    rng = np.random.default_rng(seed)
    calls = []

    def evaluate(thetas):
        calls.append(len(thetas))
        return [planted_curve(t) + rng.normal(0.0, SD, (K, len(N))) for t in thetas]
    return evaluate, calls


class ExactModel:
    """The planted model as a 'surrogate' without uncertainty: its posterior is the target."""
    def predict(self, thetas):
        return np.array([planted_curve(t) for t in thetas]), np.zeros((len(thetas), len(N)))


def run_recovery(theta_true, lower, upper, seed):
    """(calibrate result, exact-model posterior) for one measured draw."""
    measured = planted_curve(theta_true) + np.random.default_rng(seed + 1000).normal(0.0, SD, len(N))
    evaluate, calls = planted_model(seed)
    # the planted cases are independent draws per set (no shared specimens): the normal likelihood
    result = calibrate(evaluate, measured, lower, upper, n_initial=8, iterations=2, batch=4, seed=seed,
                       shared_cases=False)
    assert calls == [8, 4, 4]
    assert result.thetas.shape == (16, len(lower)) and len(result.curves) == 16
    np.testing.assert_array_equal(result.rounds, [0] * 8 + [1] * 4 + [2] * 4)
    exact = posterior(ExactModel(), measured, np.full(len(N), SD ** 2 * (1 + 1 / K)), lower, upper)
    return result, exact


def assert_recovered(post, exact, theta_true, lower, upper, dims):
    width = upper - lower
    for i in dims:
        lo, hi = post.interval90[i]
        assert lo <= theta_true[i] <= hi, (i, post.interval90[i], theta_true[i])
        assert hi - lo < 0.5 * width[i]
        assert abs(post.mean[i] - theta_true[i]) < 0.15 * width[i]
        # the surrogate's posterior is the exact one: mean within one exact sd, width within 30 %
        exact_width = exact.interval90[i, 1] - exact.interval90[i, 0]
        assert abs(post.mean[i] - exact.mean[i]) < exact_width / 3.29
        assert 0.7 < (hi - lo) / exact_width < 1.3


# The measured noise draws of seeds 0 and 3 put theta_true outside the *exact* posterior's
# 90 % interval (as 10-20 % of draws must); they test luck, not the method, so are not used.
@pytest.mark.parametrize("theta_true, seed", [((1.7, 1.2), 1), ((1.0, 0.5), 2), ((2.5, 1.6), 4)])
def test_calibrate_recovers_planted_parameters(theta_true, seed):
    theta_true = np.array(theta_true)
    result, exact = run_recovery(theta_true, LOWER_AB, UPPER_AB, seed)
    assert_recovered(result.posterior, exact, theta_true, LOWER_AB, UPPER_AB, dims=[0, 1])
    means, pooled = ensemble_stats(result.curves)
    assert np.all((np.diag(pooled) > SD ** 2 / 2) & (np.diag(pooled) < SD ** 2 * 2))
    # shrinking keeps the diagonal: the residual variance is the pooled case variance x (1 + 1/K)
    np.testing.assert_allclose(np.diag(result.noise[0]), np.diag(pooled) * (1 + 1 / K))
    assert list(result.noise) == [0] and result.dof is None
    # the surrogate reproduces the ensemble means it was fitted on to about their scatter
    assert rmse(result.surrogate.predict(result.thetas)[0], means) < SD


def test_ignored_parameter_stays_at_prior():
    lower, upper = np.append(LOWER_AB, 0.0), np.append(UPPER_AB, 1.0)
    theta_true = np.array([1.7, 1.2, 0.3])
    result, exact = run_recovery(theta_true, lower, upper, seed=5)
    post = result.posterior
    assert_recovered(post, exact, theta_true, lower, upper, dims=[0, 1])
    lo, hi = post.interval90[2]
    assert hi - lo >= 0.7
    assert abs(post.mean[2] - 0.5) < 0.15


def test_posterior_of_exact_surrogate_is_the_analytic_gaussian():
    """A linear 'surrogate' with no uncertainty: the posterior is Gaussian with known moments."""
    class Linear:
        def predict(self, thetas):
            return thetas @ np.array([[1.0, 1.0], [0.0, 2.0]]), np.zeros((len(thetas), 2))
    noise_var = np.array([0.01, 0.04])
    post = posterior(Linear(), np.array([0.5, 0.5]), noise_var, [-1.0, -1.0], [2.0, 2.0], n_samples=2 ** 16)
    # y1 = t1 + N(0, 0.01), y2 = t1 + 2 t2 + N(0, 0.04): precision = J^T diag(1/v) J
    jac = np.array([[1.0, 0.0], [1.0, 2.0]])
    cov = np.linalg.inv(jac.T @ np.diag(1 / noise_var) @ jac)
    np.testing.assert_allclose(post.mean, [0.5, 0.0], atol=0.01)
    sd = np.sqrt(np.diag(cov))
    np.testing.assert_allclose(post.interval90, np.column_stack([[0.5, 0.0] - 1.645 * sd, [0.5, 0.0] + 1.645 * sd]),
                               atol=0.02)
    np.testing.assert_allclose(post.correlation[0, 1], cov[0, 1] / sd.prod(), atol=0.03)
    np.testing.assert_allclose(post.weights.sum(), 1.0)
    np.testing.assert_allclose(np.exp(post.log_weights), post.weights)
    assert 100 < post.ess < len(post.weights)
    np.testing.assert_allclose(post.map, [0.5, 0.0], atol=0.05)


def test_surrogate_units_and_uncertainty():
    thetas = initial_design([0.0], [1.0], 10, seed=0)
    means = np.column_stack([1000 + 50 * np.sin(3 * thetas[:, 0]), 1e-3 * thetas[:, 0] ** 2])
    sur = Surrogate([0.0], [1.0]).fit(thetas, means)
    mu, std = sur.predict(np.array([[0.25], [0.75]]))
    assert mu.shape == std.shape == (2, 2)
    exact = np.column_stack([1000 + 50 * np.sin([0.75, 2.25]), 1e-3 * np.array([0.25, 0.75]) ** 2])
    np.testing.assert_allclose(mu[:, 0], exact[:, 0], rtol=0.0, atol=0.5)
    np.testing.assert_allclose(mu[:, 1], exact[:, 1], rtol=0.0, atol=2e-5)
    assert np.all(std[:, 0] < 0.5) and np.all(std[:, 1] < 2e-5)
    # noisy means (sd 0.1, 40 sets): std is the uncertainty of the mean curve, well below the
    # noise, and matches the actual error of the fitted mean
    x = np.linspace(0.0, 1.0, 40)[:, None]
    noisy = np.sin(3 * x) + np.random.default_rng(1).normal(0.0, 0.1, x.shape)
    mu, std = Surrogate([0.0], [1.0]).fit(x, noisy).predict(np.linspace(0.1, 0.9, 9)[:, None])
    assert np.all(std < 0.06)
    assert rmse(mu, np.sin(3 * np.linspace(0.1, 0.9, 9))[:, None]) < 2 * np.sqrt(np.mean(std ** 2))


def test_grouped_surrogate_follows_the_one_test_an_effect_acts_in():
    """Outputs in groups (the loop's tests): an effect that moves one test's points (a step
    of 3 noise sd across theta) and leaves seven tests at set-to-set noise. One GP per group
    follows the signal within its noise; the noise-only groups stay flat around their mean,
    their scatter not taken for a trend."""
    rng = np.random.default_rng(4)
    thetas = initial_design([0.0], [1.0], 5, seed=2)
    groups = np.repeat(np.arange(8), 4)
    signal = 0.01 * np.tanh(4 * (thetas[:, 0] - 0.5))[:, None] * np.ones(4)
    means = rng.normal(1e-3, 3e-4, (5, 32))
    means[:, :4] += signal
    sur = Surrogate([0.0], [1.0]).fit(thetas, means, groups=groups)
    at = np.array([[0.1], [0.9]])
    mu, std = sur.predict(at)
    truth = 1e-3 + 0.01 * np.tanh(4 * (at[:, 0] - 0.5))
    np.testing.assert_allclose(mu[:, :4], np.repeat(truth[:, None], 4, axis=1), atol=1.5e-3)
    rest = mu[:, 4:]
    assert np.all(np.abs(rest[1] - rest[0]) < 6e-4)        # flat: < 2 noise sd between the ends
    assert std.shape == (2, 32) and np.all(np.isfinite(std))


def test_ensemble_stats_hand_computed():
    set1 = np.array([[1.0, 10.0], [3.0, 14.0]])             # SS = [2, 8], K - 1 = 1
    set2 = np.array([[0.0, 0.0], [3.0, 3.0], [6.0, 0.0]])   # SS = [18, 6], K - 1 = 2
    single = np.array([[100.0, 100.0]])                      # one case: no information on scatter
    means, pooled = ensemble_stats([set1, single, set2])
    np.testing.assert_allclose(means, [[2.0, 12.0], [100.0, 100.0], [3.0, 1.0]])
    # cross products: set1 (-1)(-2) + (1)(2) = 4, set2 (-3)(-1) + 0 + (3)(-1) = 0
    np.testing.assert_allclose(pooled, [[20.0 / 3.0, 4.0 / 3.0], [4.0 / 3.0, 14.0 / 3.0]])
    with pytest.raises(ValueError, match="K >= 2"):
        ensemble_stats([single, single])
    with pytest.raises(ValueError, match="finite"):
        ensemble_stats([np.array([[1.0, np.nan], [2.0, 3.0]])])


def test_weighted_quantile():
    x = np.random.default_rng(0).normal(size=501)
    q = np.array([0.0, 0.05, 0.3, 0.5, 0.95, 1.0])
    equal = weighted_quantile(x, np.ones_like(x), q)
    np.testing.assert_allclose(equal, np.quantile(x, q, method="hazen"))
    assert np.max(np.abs(equal - np.quantile(x, q))) <= np.max(np.diff(np.sort(x)))
    mass = np.zeros_like(x)
    mass[17] = 3.0
    np.testing.assert_array_equal(weighted_quantile(x, mass, q), x[17])
    # weight 3 on one of two points: its value holds the middle of the mass
    np.testing.assert_allclose(weighted_quantile([0.0, 1.0], [1.0, 3.0], [0.125, 0.5, 0.625]), [0.0, 0.75, 1.0])


def test_initial_design():
    lower, upper, n = np.array([0.5, 0.0, -2.0]), np.array([3.0, 2.0, 2.0]), 7
    design = initial_design(lower, upper, n, seed=5)
    assert design.shape == (n, 3)
    assert np.all((design >= lower) & (design <= upper))
    np.testing.assert_array_equal(design, initial_design(lower, upper, n, seed=5))
    assert not np.array_equal(design, initial_design(lower, upper, n, seed=6))
    strata = np.floor((design - lower) / (upper - lower) * n).astype(int)
    for column in strata.T:
        np.testing.assert_array_equal(np.sort(column), np.arange(n))
    default = np.array([1.0, 1.0, 0.0])
    with_default = initial_design(lower, upper, n, seed=5, include=default)
    np.testing.assert_array_equal(with_default[0], default)
    np.testing.assert_array_equal(with_default[1:], design[1:])


def test_next_batch():
    lower, upper = LOWER_AB, UPPER_AB
    thetas = initial_design(lower, upper, 8, seed=0)
    means = np.array([planted_curve(t) for t in thetas])
    sur = Surrogate(lower, upper).fit(thetas, means)
    post = posterior(sur, planted_curve([1.7, 1.2]), np.full(len(N), SD ** 2), lower, upper, n_samples=4096)
    batch = next_batch(post, thetas, 5, lower, upper, seed=1)
    assert batch.shape == (5, 2)
    assert np.all((batch >= lower) & (batch <= upper))
    unit = np.vstack([thetas, batch]) / (upper - lower)
    distances = np.linalg.norm(unit[:, None] - unit[None], axis=2)[8:]
    assert np.all(np.sort(distances, axis=1)[:, 1] > 1e-6)   # [:, 0] is the point itself
    np.testing.assert_array_equal(batch, next_batch(post, thetas, 5, lower, upper, seed=1))
    # all posterior mass in a disk (normalised radius 0.15) whose centre is already evaluated:
    # the batch stays in the disk and away from the centre and from each other
    centre = np.array([1.7, 1.2])
    in_disk = np.linalg.norm((post.samples - centre) / (upper - lower), axis=1) < 0.15
    disk = replace(post, weights=in_disk / in_disk.sum())
    batch = next_batch(disk, np.vstack([thetas, centre]), 4, lower, upper, seed=2)
    unit = (batch - centre) / (upper - lower)
    assert np.all(np.linalg.norm(unit, axis=1) < 0.15)
    assert np.all(np.linalg.norm(unit, axis=1) > 0.08)
    assert np.min(distances_between(unit)) > 0.08
    # mass on three points: one already evaluated, one far from all evaluated sets, one near
    evaluated = np.array([[1.0, 1.0], [2.0, 1.0]])
    three = np.array([[1.0, 1.0], [1.5, 0.0], [2.0, 1.2]])
    three_point = replace(post, samples=three, weights=np.full(3, 1 / 3))
    for seed in range(5):
        np.testing.assert_array_equal(next_batch(three_point, evaluated, 2, lower, upper, seed), three[[1, 2]])


def distances_between(points):
    d = np.linalg.norm(points[:, None] - points[None], axis=2)
    return d[np.triu_indices(len(points), 1)]


def test_two_tests_each_predicted_from_the_other():
    """Two measured tests of the same parameters (the second at 1.5x the first's stress:
    its curve 1.5x as large): per-test blocks in the likelihood, and leave one condition out
    predicts each test from the other's posterior within a few case sd, each fold's
    parameters near the planted ones."""
    rng = np.random.default_rng(8)
    theta_true = np.array([1.7, 1.2])

    def two(theta):
        return np.concatenate([planted_curve(theta), 1.5 * planted_curve(theta)])
    point_test = np.repeat([0, 1], len(N))
    y = two(theta_true) + rng.normal(0.0, SD, 2 * len(N))
    result = calibrate(lambda thetas: [two(t) + rng.normal(0.0, SD, (K, 2 * len(N))) for t in thetas], y,
                       LOWER_AB, UPPER_AB, n_initial=8, iterations=2, batch=4, seed=3,
                       point_test=point_test, shared_cases=False)
    assert sorted(result.noise) == [0, 1] and all(c.shape == (len(N), len(N)) for c in result.noise.values())
    assert result.posterior.test_loglik.shape == (len(result.posterior.samples), 2)
    held = result.held_out(y, point_test)
    for t in (0, 1):
        assert held.rmse(y, point_test, [t]) < 3 * SD
        assert np.all(np.abs(held.theta_mean[t] - theta_true) < 0.15 * (UPPER_AB - LOWER_AB)), held.theta_mean
