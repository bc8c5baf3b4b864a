"""Coverage of the calibration's 90 % intervals when the measured specimen is not one of ours
(issue 34): a planted model whose specimens differ by an offset that runs along the whole
curve (a specimen softer or stiffer all along, as DEM specimens are), K specimens shared by
every parameter set (common random numbers, as the Evaluator runs them), small chaos per
run, and a "measured" curve from a fresh specimen. Counted over many draws, the intervals
must hold the planted values about 90 % of the time; the independent-points likelihood the
calibration used before, given the same runs, does not (the failure this guards against).

The likelihood alone is tested on many draws with the exact model mean (no surrogate, so
the count measures the likelihood); the whole calibrate() with its surrogate on fewer.
"""
import numpy as np

from scipy.stats import multivariate_normal, multivariate_t

from ballaststudy.calibration.bayes import (calibrate, ensemble_stats, noise_covariances, posterior,
                                            residual_logpdf, shrunk)

N = np.array([1.0, 2.0, 5.0, 10.0, 20.0, 50.0])
LOWER, UPPER = np.array([0.5, 0.0]), np.array([3.0, 2.0])
SHAPE = 0.5 + 0.5 * np.log1p(N) / np.log1p(N[-1])   # a specimen's offset grows with N
OFFSET_SD, CHAOS_SD = 0.004, 0.0005                   # between specimens, between runs
K, SETS = 3, 12


def planted_curve(theta):
    """Compaction a and creep rate b (test_bayes' planted model)."""
    a, b = theta[0], theta[1]
    return 0.02 * a * (1.0 - np.exp(-N / 3.0)) + 0.001 * b * N + 0.002 * a * b


class ShiftedExact:
    """The exact ensemble-mean curve of the K shared specimens: truth + their mean offset."""
    def __init__(self, offset):
        self.offset = offset

    def predict(self, thetas):
        return (np.array([planted_curve(t) for t in thetas]) + self.offset,
                np.zeros((len(thetas), len(N))))


def draw(seed):
    """(theta_true, measured y, specimen offsets (K, P), rng) for one planted draw."""
    rng = np.random.default_rng(seed)
    theta = LOWER + (0.2 + 0.6 * rng.random(2)) * (UPPER - LOWER)
    offsets = rng.normal(0.0, OFFSET_SD, K)[:, None] * SHAPE
    y = planted_curve(theta) + rng.normal(0.0, OFFSET_SD) * SHAPE + rng.normal(0.0, CHAOS_SD, N.size)
    return theta, y, offsets, rng


def covered(post, theta):
    return (post.interval90[:, 0] <= theta) & (theta <= post.interval90[:, 1])


def likelihood_coverage(draws):
    """(coverage per parameter of the calibration's likelihood, of independent points)."""
    hits, independent = np.zeros(2), np.zeros(2)
    for seed in range(draws):
        theta, y, offsets, rng = draw(seed)
        runs = [offsets + rng.normal(0.0, CHAOS_SD, offsets.shape) for _ in range(SETS)]
        case_cov = ensemble_stats(runs)[1]
        model = ShiftedExact(offsets.mean(axis=0))
        noise = noise_covariances(case_cov, np.zeros(N.size, int), 1.0 + 1.0 / K)
        hits += covered(posterior(model, y, noise, LOWER, UPPER, 4096, seed, dof=K - 1), theta)
        diagonal = np.diag(case_cov) * (1.0 + 1.0 / K)
        independent += covered(posterior(model, y, diagonal, LOWER, UPPER, 4096, seed), theta)
    return hits / draws, independent / draws


def test_intervals_cover_planted_values_on_fresh_specimens():
    """200 draws (binomial sd of a 90 % count: 2 %). Measured 2026-11-27: t likelihood
    0.885 / 0.995 (a / b), independent points 0.67 / 1.00. b, the slope, over-covers under
    both (the shrunk covariance keeps part of the offset's variance as independent noise);
    a, which a specimen's offset mimics, is where independent points fail."""
    hits, independent = likelihood_coverage(200)
    print(f"\ncoverage a, b: t likelihood {hits}, independent points {independent}")
    assert np.all(hits >= 0.84), hits
    assert hits[0] <= 0.97, hits
    assert independent[0] <= 0.75, independent


def test_shrunk_keeps_the_diagonal_and_damps_the_rest():
    cov = np.array([[4.0, 2.0], [2.0, 9.0]])
    np.testing.assert_allclose(shrunk(cov), [[4.0, 1.8], [1.8, 9.0]])


def test_covariances_are_per_test_and_scaled():
    case_cov = np.arange(16.0).reshape(4, 4) + 20 * np.eye(4)
    covs = noise_covariances(case_cov, np.array([0, 0, 1, 1]), 2.0, measurement_var=0.5)
    assert list(covs) == [0, 1]
    np.testing.assert_allclose(covs[1], 2.0 * shrunk(case_cov[2:, 2:]) + 0.5 * np.eye(2))
    np.testing.assert_allclose(covs[0], 2.0 * shrunk(case_cov[:2, :2]) + 0.5 * np.eye(2))


def test_calibrate_covers_planted_values_on_fresh_specimens():
    """The whole calibrate() (surrogate, sequential design) over 20 draws: the planted values
    inside the 90 % intervals in at least 15 of 20 per parameter (a 90 % method fails this
    1 time in 100). Measured 2026-11-27: 0.85 / 1.00, ~20 s."""
    hits = np.zeros(2)
    for seed in range(20):
        theta, y, offsets, rng = draw(seed)

        def evaluate(thetas):
            return [planted_curve(t) + offsets + rng.normal(0.0, CHAOS_SD, offsets.shape) for t in thetas]
        res = calibrate(evaluate, y, LOWER, UPPER, n_initial=8, iterations=2, batch=4, seed=seed,
                        n_samples=4096)
        hits += covered(res.posterior, theta)
    print(f"\ncalibrate() coverage a, b over 20 draws: {hits / 20}")
    assert np.all(hits >= 15), hits


T_TESTS = 4
STRESS = np.repeat([0.6, 0.8, 1.0, 1.2], N.size)      # four tests at rising stress


def joint_coverage(k, draws):
    """Coverage of one parameter (a strain-growth factor theta in [0, 1]) fitted jointly to
    four tests, each measured on a lab specimen of its own, against K specimens of ours that
    run under every test (so the K specimens' mean offset is common to all four)."""
    point_test = np.repeat(np.arange(T_TESTS), N.size)
    shape = np.tile(SHAPE, T_TESTS)
    base = np.tile(0.01 * np.log1p(N), T_TESTS) * STRESS

    class Shifted:
        def __init__(self, offset):
            self.offset = offset

        def predict(self, thetas):
            return base * (1 + 0.8 * thetas) + self.offset, np.zeros((len(thetas), base.size))
    hits = 0
    for seed in range(draws):
        rng = np.random.default_rng(seed)
        theta = 0.15 + 0.7 * rng.random()
        offsets = rng.normal(0.0, OFFSET_SD, (k, 1)) * shape
        plain = base + offsets + rng.normal(0.0, CHAOS_SD, offsets.shape)
        y = (base * (1 + 0.8 * theta) + rng.normal(0.0, OFFSET_SD, T_TESTS)[point_test] * shape
             + rng.normal(0.0, CHAOS_SD, base.size))
        noise = noise_covariances(ensemble_stats([plain])[1], point_test, 1.0 + 1.0 / k)
        post = posterior(Shifted(offsets.mean(axis=0)), y, noise, [0.0], [1.0], 2048, seed, point_test, k - 1)
        hits += covered(post, np.array([theta]))[0]
    return hits / draws


def test_joint_tests_need_more_specimens():
    """Several tests against the same K specimens: their mean offset is common to every
    test, and its covariance rests on K - 1 degrees of freedom for all of them together, so
    per-test blocks over-trust a small K more than one test does. Measured 2026-11-27 (300
    draws): 0.78 at K = 3 (one test: 0.885, above), 0.93 at K = 6. A joint t over all tests
    with the cross-test 1/K term (explored on other draws, not in the code) gained ~0.06 at
    K = 3: K itself, not the form of the likelihood, is what is short."""
    few, enough = joint_coverage(3, 300), joint_coverage(6, 300)
    print(f"\njoint coverage over 4 tests: K = 3 {few:.3f}, K = 6 {enough:.3f}")
    assert enough >= 0.85, enough
    assert few < enough - 0.05, (few, enough)


def test_residual_logpdf_is_the_normal_and_the_multivariate_t():
    """Against scipy: the normal, and the t with dof degrees of freedom and scale matrix cov
    (a factor 2 or pi in the t's normalisation, or dof in place of dof + P, would show)."""
    rng = np.random.default_rng(2)
    a = rng.normal(size=(4, 4))
    cov = a @ a.T + 0.5 * np.eye(4)
    r = rng.normal(size=(5, 4)) * 2.0
    np.testing.assert_allclose(residual_logpdf(r, cov), multivariate_normal(np.zeros(4), cov).logpdf(r), rtol=1e-10)
    for dof in (1.0, 2.0, 7.5):
        np.testing.assert_allclose(residual_logpdf(r, cov, dof), multivariate_t(np.zeros(4), cov, df=dof).logpdf(r),
                                   rtol=1e-10)
