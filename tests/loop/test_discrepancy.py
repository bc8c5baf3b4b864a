"""The discrepancy's algebra (loop/discrepancy.py) against the dense densities it stands
for: the source's residuals a multivariate t (or normal) with covariance blockdiag(D_t) +
X S X^T, a held-out test's density that of the test given the others, beta's posterior the
generalised least squares with its prior."""
import numpy as np
import pytest
from scipy import stats

from ballaststudy.loop.discrepancy import (_test_logpdf, beta_posterior, held_out_variance, joint_loglik, loglik,
                                           make_discrepancy, per_test_stats, source_beta, surrogate_shape)


def _problem(seed, sources=("a", "a", "b", "a", "b")):
    rng = np.random.default_rng(seed)
    sizes = rng.integers(3, 7, len(sources))
    point_test = np.concatenate([np.full(n, t) for t, n in enumerate(sizes)])
    cycle = np.concatenate([np.sort(rng.uniform(1, 200, n)) for n in sizes])
    y = 0.01 + 0.002 * np.log(cycle) + rng.normal(0, 1e-3, len(cycle))
    covs = {}
    for t, n in enumerate(sizes):
        a = rng.normal(0, 1e-3, (n, n))
        covs[t] = a @ a.T + 1e-6 * np.eye(n)
    return y, cycle, point_test, covs, make_discrepancy(y, cycle, point_test, list(sources)), rng


def _dense(disc, covs, point_test, tests):
    """The dense covariance of the points of ``tests`` (blocks, plus X S X^T within a source)."""
    sel = np.isin(point_test, tests)
    omega = np.zeros((sel.sum(), sel.sum()))
    idx = np.flatnonzero(sel)
    for t in tests:
        at = np.searchsorted(idx, np.flatnonzero(point_test == t))
        omega[np.ix_(at, at)] += covs[t]
    src = disc.test_source[point_test[sel]]
    x = disc.basis[sel]
    for s in range(len(disc.sources)):
        m = src == s
        omega[np.ix_(m, m)] += x[m] @ np.diag(disc.prior_sd[s] ** 2) @ x[m].T
    return sel, omega


def _per_test_t(disc, covs, point_test, y, m, tests, dof, beta):
    """log prod_t t(y_t - m_t - X_t beta; D_t, dof) for betas (G, q), one source's tests."""
    out = 0.0
    for t in tests:
        sel = point_test == t
        r = y[sel][None] - m[sel][None] - beta @ disc.basis[sel].T
        out = out + stats.multivariate_t(np.zeros(sel.sum()), covs[t], df=dof).logpdf(r)
    return out


def _brute(disc, covs, point_test, y, m, tests, dof, s):
    """log of the integral over beta of the per-test t's and beta's prior, on a fine grid."""
    from ballaststudy.loop.discrepancy import per_test_stats
    st = per_test_stats((y - m)[None], np.zeros((1, len(y))), covs, point_test, disc.basis)
    mean, cov = beta_posterior(sum(st[t].xdx for t in tests), sum(st[t].xdr for t in tests), disc.prior_sd[s])
    sd = np.sqrt(np.diag(cov[0]))
    axes = [np.linspace(mu - 12 * v, mu + 12 * v, 801) for mu, v in zip(mean[0], sd)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 2)
    log_f = (_per_test_t(disc, covs, point_test, y, m, tests, dof, grid)
             + stats.multivariate_normal(np.zeros(2), np.diag(disc.prior_sd[s] ** 2)).logpdf(grid))
    cell = np.prod([a[1] - a[0] for a in axes])
    return np.log(np.sum(np.exp(log_f - log_f.max())) * cell) + log_f.max()


def _dense_source(disc, covs, point_test, y, m, tests, dof):
    total = 0.0
    for s in range(len(disc.sources)):
        in_s = [t for t in tests if disc.test_source[t] == s]
        if not in_s:
            continue
        if dof is None:
            sel, omega = _dense(disc, covs, point_test, in_s)
            total += stats.multivariate_normal(np.zeros(sel.sum()), omega).logpdf(y[sel] - m[sel])
        else:
            total += _brute(disc, covs, point_test, y, m, in_s, dof, s)
    return total


@pytest.mark.parametrize("dof", [None, 2.0, 9.0])
def test_the_joint_density_is_the_integral_over_the_discrepancy(dof):
    """Normal: the dense density of blockdiag(D_t) + X S X^T (exact). t: the per-test t's
    times beta's prior integrated on a fine grid: the nodes' error under 1e-3 where a source
    has two tests or more; a source of one test of 3-6 points (test 4 once test 2 is left
    out) has tails in beta that 9 nodes about its mode miss by ~0.02 (measured: 0.018, 0.021;
    15 nodes 0.007), far below a gain's tie of 0.5."""
    y, cycle, point_test, covs, disc, rng = _problem(1)
    mean = rng.normal(0.01, 1e-3, (2, len(y)))
    joint = joint_loglik(y[None] - mean, np.zeros_like(mean), covs, point_test, disc, dof)
    tol = 1e-7 if dof is None else 1e-3
    assert np.allclose(loglik(y[None] - mean, np.zeros_like(mean), covs, point_test, disc, dof), joint.full)
    for i, m in enumerate(mean):
        assert joint.full[i] == pytest.approx(_dense_source(disc, covs, point_test, y, m, range(5), dof), abs=tol)
        for j in (0, 2):
            rest = [t for t in range(5) if t != j]
            assert joint.without[i, j] == pytest.approx(_dense_source(disc, covs, point_test, y, m, rest, dof),
                                                        abs=tol if j == 0 else 3e-2)


def test_beta_is_the_generalised_least_squares_with_its_prior():
    y, cycle, point_test, covs, disc, _ = _problem(2, sources=("a",) * 5)
    st = per_test_stats(y[None], np.zeros((1, len(y))), covs, point_test, disc.basis)
    mean, cov = beta_posterior(sum(s.xdx for s in st), sum(s.xdr for s in st), disc.prior_sd[0])
    d = np.zeros((len(y), len(y)))
    for t, c in covs.items():
        d[np.ix_(point_test == t, point_test == t)] = c
    x = disc.basis
    precision = x.T @ np.linalg.solve(d, x) + np.diag(disc.prior_sd[0] ** -2.0)
    assert np.allclose(cov[0], np.linalg.inv(precision), rtol=1e-8)
    assert np.allclose(mean[0], np.linalg.solve(precision, x.T @ np.linalg.solve(d, y)), rtol=1e-8)
    assert disc.terms == ("offset", "slope_ln_n")


def test_a_shared_offset_is_recovered_and_a_held_out_test_predicted_with_it():
    """Tests of one source with one planted offset: beta's posterior holds it, and the
    held-out prediction of the plain model moves by it (the other tests tell it)."""
    rng = np.random.default_rng(3)
    point_test = np.repeat(np.arange(6), 8)
    cycle = np.tile(np.geomspace(1, 100, 8), 6)
    covs = {t: 1e-8 * np.eye(8) for t in range(6)}
    y = 0.004 + rng.normal(0, 1e-4, len(cycle))          # the model's mean is 0: the offset is 0.004
    disc = make_discrepancy(y, cycle, point_test, ["lab"] * 6)
    (mean, sd), = source_beta(y, covs, point_test, disc, dof=2.0)
    assert abs(mean[0] - 0.004) < 3 * sd[0] and sd[0] < 1e-4
    joint = joint_loglik(y[None], np.zeros((1, len(y))), covs, point_test, disc, 2.0)
    assert np.allclose(joint.beta_without[0, :, 0], 0.004, atol=2e-4)
    var = held_out_variance(covs, point_test, disc)
    assert np.all(var > 1e-8) and np.all(var < 1e-8 + 1e-7)     # the noise plus the offset's share left


def test_a_slope_needs_points_at_three_cycles():
    y = np.array([1.0, 2.0, 1.5, 2.5])
    disc = make_discrepancy(y, [1, 10, 1, 10], [0, 0, 1, 1], ["a", "a"])
    assert disc.terms == ("offset",) and disc.basis.shape == (4, 1)


def test_the_prior_scale_is_the_larger_of_the_measured_and_the_models_quantity():
    """A model straining 7 times what the lab measured: the discrepancy's prior lets it be
    that large (prior sd from the model's rms), not the measured rms."""
    y, n, pt = np.full(6, 0.01), np.tile([1.0, 5.0, 10.0], 2), np.repeat([0, 1], 3)
    assert make_discrepancy(y, n, pt, ["a", "a"]).prior_sd[0, 0] == pytest.approx(0.01)
    assert make_discrepancy(y, n, pt, ["a", "a"], model=np.full(6, 0.07)).prior_sd[0, 0] == pytest.approx(0.07)


def test_the_surrogates_error_runs_along_the_curve():
    """surrogate_shape: the design sets' mean curves' covariance per test, mean diagonal 1,
    of their rank (J - 1) but for a ridge; per_test_stats with it is the dense t of the test's
    covariance plus sd^2 x shape (sd one value per test and sample)."""
    rng = np.random.default_rng(6)
    point_test = np.repeat([0, 1], [5, 4])
    sets = rng.normal(0, 1e-3, (4, 9))
    shape = surrogate_shape(sets, point_test)
    for t, c in shape.items():
        assert np.mean(np.diag(c)) == pytest.approx(1.0, rel=1e-5)
        assert np.sum(np.linalg.eigvalsh(c) > 1e-3) == 3
    covs = {0: 1e-8 * np.eye(5), 1: 2e-8 * np.eye(4)}
    resid, sd = rng.normal(0, 1e-4, (2, 9)), np.repeat([[3e-4, 1e-4]], 2, axis=0)[:, point_test]
    disc = make_discrepancy(np.ones(9), np.arange(1.0, 10.0), point_test, ["a", "a"])
    stats_ = per_test_stats(resid, sd, covs, point_test, disc.basis, shape)
    for t in (0, 1):
        sel = point_test == t
        for m in range(2):
            full = covs[t] + sd[m, sel][:, None] * sd[m, sel][None] * shape[t]
            dense = stats.multivariate_t(np.zeros(sel.sum()), full, df=2.0).logpdf(resid[m, sel])
            s = stats_[t]
            assert _test_logpdf(s.quad[m], s.logdet[m], s.n, 2.0) == pytest.approx(dense, abs=1e-9)
