"""Bayesian calibration of model parameters against measured curves (thesis 4.3).

The model (a DEM simulation) is run elsewhere as an ensemble of K random cases per parameter
set; this module only sees arrays: parameter sets theta (d,) in a box [lower, upper] and, per
set, the K case curves (K, P) at the P points of the measured curves y (P,); point_test (P,)
says which measured test each point belongs to (one test if None).

Method
  1. initial_design: Latin hypercube in the box (optionally containing the default set).
  2. ensemble_stats: ensemble-mean curve per set and the case-to-case covariance pooled over
     all sets (every set scatters the same way).
  3. Surrogate: a Gaussian process of the ensemble-mean curve over the normalised box.
  4. posterior: uniform prior; per test, the likelihood of its points around the surrogate
     mean with the residual covariance (below) plus the surrogate's variance on the
     diagonal, by importance weights on a scrambled Sobol sample of the prior box.
  5. next_batch: new sets spread out (maximin) inside the posterior mass.
  6. calibrate: design -> evaluate -> (fit, posterior, next batch, evaluate) x iterations
     -> final fit and posterior.

Residual covariance (calibrate()'s choice): a laboratory specimen is never one of ours, so
the measured curve is treated as one more random specimen of the test, while the surrogate
predicts the mean of K: y - surrogate mean has covariance C (1 + 1/K), C the case-to-case
covariance (plus the measurement's variance on the diagonal). The points of a curve are
correlated - a specimen is softer or stiffer all along - and independent points count one
specimen's offset once per point: on planted curves whose specimens differ by such an
offset, the 90 % intervals from independent points held the truth in 67 % of draws
(tests/calibration/test_coverage.py). Between tests the residuals are independent (a lab
test is a specimen of its own), so the covariance is per test. C is shrunk towards its
diagonal (SHRINK) so that it stays positive definite with few cases.

Few specimens: every set runs the same K specimens (common random numbers), so however
many sets are pooled, C's specimen part rests on K - 1 degrees of freedom; with K = 3 an
estimate a third of the truth is common, and a normal likelihood trusts it. calibrate()
therefore uses the multivariate t with K - 1 degrees of freedom and scale C (1 + 1/K), the
predictive of one more specimen when the covariance's scale is known only from K - 1
(it tends to the normal as K grows); with independent cases per set (no shared
specimens) the normal is used.
"""
import warnings
from dataclasses import dataclass

import numpy as np
from scipy.special import gammaln, logsumexp
from scipy.stats import qmc
from sklearn.exceptions import ConvergenceWarning
from sklearn.gaussian_process import GaussianProcessRegressor
from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel

N_CANDIDATES = 4096   # posterior resamples next_batch chooses from
SHRINK = 0.1          # weight of the diagonal in a shrunk case covariance


def _box(lower, upper):
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    if lower.ndim != 1 or lower.shape != upper.shape or not np.all(upper > lower):
        raise ValueError("lower and upper must be (d,) arrays with upper > lower")
    return lower, upper


def _to_unit(thetas, lower, upper):
    return (np.atleast_2d(np.asarray(thetas, float)) - lower) / (upper - lower)


def _from_unit(u, lower, upper):
    return lower + u * (upper - lower)


def rmse(a, b):
    """Root-mean-square difference of two arrays."""
    return float(np.sqrt(np.mean((np.asarray(a, float) - np.asarray(b, float)) ** 2)))


def initial_design(lower, upper, n, seed, include=None):
    """(n, d) scrambled Latin hypercube in the box; ``include`` (d,) replaces the first point."""
    lower, upper = _box(lower, upper)
    design = _from_unit(qmc.LatinHypercube(len(lower), rng=seed).random(n), lower, upper)
    if include is not None:
        design[0] = include
    return design


def ensemble_stats(curves_list):
    """(means (J, P), pooled case-to-case covariance (P, P)) of J sets of case curves (K_j, P).

    Pooled covariance = sum of the outer products of the deviations from each set's mean /
    sum of (K_j - 1); a set with one case has no deviation and no degree of freedom, so it
    adds nothing.
    """
    curves_list = [np.asarray(c, float) for c in curves_list]
    if not curves_list or any(c.ndim != 2 or c.shape[1] != curves_list[0].shape[1] for c in curves_list):
        raise ValueError("curves_list must be a non-empty list of (K, P) arrays with the same P")
    if not all(np.isfinite(c).all() for c in curves_list):
        raise ValueError("case curves must be finite (fill censored values before calibrating)")
    dof = sum(len(c) - 1 for c in curves_list)
    if dof == 0:
        raise ValueError("no parameter set has K >= 2 cases: the case-to-case covariance is unknown")
    means = np.array([c.mean(axis=0) for c in curves_list])
    deviations = np.concatenate([c - m for c, m in zip(curves_list, means)])
    return means, deviations.T @ deviations / dof


def shrunk(cov):
    """cov with the weight SHRINK moved onto its diagonal (positive definite with few cases)."""
    return (1 - SHRINK) * cov + SHRINK * np.diag(np.diag(cov))


def noise_covariances(case_cov, point_test, scale, measurement_var=0.0):
    """{test: scale x shrunk case covariance of its points + measurement_var x I}."""
    point_test = np.asarray(point_test)
    return {t: scale * shrunk(case_cov[np.ix_(point_test == t, point_test == t)])
            + measurement_var * np.eye(int(np.sum(point_test == t))) for t in np.unique(point_test)}


def residual_logpdf(r, cov, dof=None):
    """log density of residuals r (M, P) with covariance cov (M, P, P) or (P, P): normal, or
    with ``dof`` the multivariate t with dof degrees of freedom and scale matrix cov."""
    chol = np.linalg.cholesky(cov)
    z = np.linalg.solve(chol, r[..., None])[..., 0]
    logdet = 2 * np.log(np.diagonal(chol, axis1=-2, axis2=-1)).sum(axis=-1)
    p, quad = r.shape[-1], np.sum(z ** 2, axis=-1)
    if dof is None:
        return -0.5 * (quad + logdet + p * np.log(2 * np.pi))
    return (gammaln((dof + p) / 2) - gammaln(dof / 2) - 0.5 * p * np.log(dof * np.pi) - 0.5 * logdet
            - 0.5 * (dof + p) * np.log1p(quad / dof))


def per_test_loglik(mean, sd, y, point_test, covs, dof=None):
    """(M, T) log-likelihood of each test's points for M surrogate predictions (mean, sd)
    (M, P): the test's residual covariance plus the surrogate's variance on its diagonal."""
    out = []
    for t, cov in covs.items():
        sel = np.asarray(point_test) == t
        full = cov[None] + np.eye(sel.sum())[None] * (sd[:, sel] ** 2)[:, :, None]
        out.append(residual_logpdf(np.asarray(y, float)[sel][None] - mean[:, sel], full, dof))
    return np.array(out).T


class Surrogate:
    """Gaussian process of the ensemble-mean curve (P points) over the normalised box.

    The P outputs fall into groups (default: one), one GP per group with shared kernel
    hyperparameters: the points of a curve depend smoothly on the same parameters and J is
    small, so sharing keeps the fit stable. Each output is centred; a group's outputs are
    scaled by one standard deviation (the group's pooled one), so that one kernel amplitude
    suits all of them and an output that hardly varies stays small beside one that does.

    Groups are what the loop needs (one per measured test): an effect may act in some tests
    only (fouling through VCI, wear where the network breaks). Fitted with one shared kernel,
    the many outputs it leaves unchanged - their set-to-set scatter standardised up to the
    size of a signal - made the GP call every output's variation white noise, its mean flat
    in theta (found with bench/loop_undeclared.py: posteriors equal to the prior, the
    planted effects not found).
    """

    def __init__(self, lower, upper, seed=0):
        self.lower, self.upper = _box(lower, upper)
        self.seed = seed

    def fit(self, thetas, means, groups=None):
        """thetas (J, d), means (J, P); groups (P,) labels of the outputs (None: one group,
        each output scaled by its own standard deviation, as one curve's points are)."""
        means = np.asarray(means, float)
        self.groups = np.zeros(means.shape[1], int) if groups is None else np.asarray(groups)
        self.y_mean = means.mean(axis=0)
        self.y_std = np.maximum(means.std(axis=0), 1e-12)
        if groups is not None:
            for g in np.unique(self.groups):
                sel = self.groups == g
                self.y_std[sel] = max(np.sqrt(np.mean(means[:, sel].var(axis=0))), 1e-12)
        u = _to_unit(thetas, self.lower, self.upper)
        self.gps = {g: self._fit_one(u, ((means - self.y_mean) / self.y_std)[:, self.groups == g])
                    for g in np.unique(self.groups)}
        return self

    def _fit_one(self, u, z):
        d = len(self.lower)
        kernel = (ConstantKernel(1.0, (1e-3, 1e3)) * RBF(length_scale=[0.3] * d, length_scale_bounds=(0.02, 10.0))
                  + WhiteKernel(1e-2, (1e-8, 1.0)))
        gp = GaussianProcessRegressor(kernel, n_restarts_optimizer=5, random_state=self.seed)
        with warnings.catch_warnings():     # a hyperparameter at its bound: expected with few sets
            warnings.simplefilter("ignore", ConvergenceWarning)
            return gp.fit(u, z)

    def predict(self, thetas):
        """(mean (M, P), std (M, P)) of the ensemble-mean curve, in the units of the curves.

        The fitted white noise is the scatter of the training means (case noise / K), which
        noise_var already carries; it is removed, so std is the surrogate's own uncertainty.
        """
        u = _to_unit(thetas, self.lower, self.upper)
        mean, sd = np.empty((len(u), self.groups.size)), np.empty((len(u), self.groups.size))
        for g, gp in self.gps.items():
            sel = self.groups == g
            m, std = gp.predict(u, return_std=True)
            mean[:, sel] = m.reshape(len(u), -1)
            var = np.maximum(np.asarray(std).reshape(len(u), -1) ** 2 - gp.kernel_.k2.noise_level, 0.0)
            sd[:, sel] = np.broadcast_to(np.sqrt(var), (len(u), sel.sum()))
        return self.y_mean + mean * self.y_std, sd * self.y_std


@dataclass(frozen=True)
class Posterior:
    """Importance-weighted sample of the posterior and its summaries."""
    samples: np.ndarray       # (M, d) uniform prior draws, parameter units
    log_weights: np.ndarray   # (M,) normalised: weights = exp(log_weights)
    weights: np.ndarray       # (M,) sum to 1
    mean: np.ndarray          # (d,)
    interval90: np.ndarray    # (d, 2) weighted 5 % and 95 % quantiles
    correlation: np.ndarray   # (d, d)
    ess: float                # effective sample size 1 / sum(w^2)
    map: np.ndarray           # (d,) sample with the highest weight
    test_loglik: np.ndarray   # (M, T) log-likelihood of each test's points


def weighted_quantile(values, weights, q):
    """Quantiles q of a weighted sample.

    Each value sits at the middle of its step of the cumulative weight (equal weights give
    numpy's 'hazen' method); zero weights are dropped, so a point mass returns that point.
    """
    values, weights = np.asarray(values, float), np.asarray(weights, float)
    keep = weights > 0
    order = np.argsort(values[keep])
    v, w = values[keep][order], weights[keep][order]
    return np.interp(q, (np.cumsum(w) - 0.5 * w) / w.sum(), v)


def weighted_fit(samples, log_weights):
    """(weights, mean (d,), 90 % interval (d, 2), effective sample size) of prior samples
    (M, d) weighted by exp(log_weights) (any offset)."""
    weights = np.exp(log_weights - logsumexp(log_weights))
    interval90 = np.array([weighted_quantile(s, weights, [0.05, 0.95]) for s in samples.T])
    return weights, weights @ samples, interval90, float(1.0 / np.sum(weights ** 2))


def prior_samples(lower, upper, n_samples, seed):
    """(M, d) scrambled Sobol points in the box, M = 2^ceil(log2(n_samples))."""
    exponent = max(int(np.ceil(np.log2(n_samples))), 0)
    return _from_unit(qmc.Sobol(len(lower), rng=seed).random_base2(exponent), lower, upper)


def posterior(surrogate, y, noise, lower, upper, n_samples=20000, seed=0, point_test=None, dof=None):
    """Posterior of the parameters given the measured points y (P,), uniform prior on the box.

    noise: the residual's variances (P,) (independent points) or {test: covariance of its
    points} (noise_covariances); dof: None (normal) or the multivariate t's degrees of
    freedom. Importance weights on 2^ceil(log2(n_samples)) scrambled Sobol points: cheap,
    since the surrogate is cheap, and exact in the limit; ess tells whether the sample
    resolves it.
    """
    lower, upper = _box(lower, upper)
    y = np.asarray(y, float)
    point_test = np.zeros(y.size, int) if point_test is None else np.asarray(point_test)
    if not isinstance(noise, dict):
        noise = {t: np.diag(np.broadcast_to(np.asarray(noise, float), y.shape)[point_test == t])
                 for t in np.unique(point_test)}
    samples = prior_samples(lower, upper, n_samples, seed)
    mu, sd = surrogate.predict(samples)
    test_loglik = per_test_loglik(mu, sd, y, point_test, noise, dof)
    loglik = test_loglik.sum(axis=1)
    log_weights = loglik - logsumexp(loglik)
    weights, mean, interval90, ess = weighted_fit(samples, log_weights)
    centred = samples - mean
    cov = (weights[:, None] * centred).T @ centred
    sd_post = np.sqrt(np.diag(cov))
    return Posterior(samples, log_weights, weights, mean, interval90, cov / np.outer(sd_post, sd_post), ess,
                     samples[np.argmax(weights)], test_loglik)


@dataclass(frozen=True)
class HeldOut:
    """Leave-one-condition-out result of one model over T tests."""
    lpd: np.ndarray          # (T,) held-out log predictive density per test
    predicted: np.ndarray    # (P,) each point's held-out prediction (its test left out)
    theta_mean: np.ndarray   # (T, d) posterior mean of each fold (empty for the plain model)

    def rmse(self, y, point_test, tests=None):
        sel = np.isin(point_test, np.unique(point_test) if tests is None else tests)
        return rmse(np.asarray(y)[sel], self.predicted[sel])


def held_out(samples, mean, loglik, y, point_test):
    """HeldOut from prior samples (M, d), the model's mean at them (M, P) and the
    log-likelihood per test (M, T): for each test, the posterior from the other tests, the
    log predictive density of the test under it and its weighted mean prediction."""
    tests = np.unique(point_test)
    lpd, predicted, theta_mean = np.empty(len(tests)), np.empty(len(y)), np.empty((len(tests), samples.shape[1]))
    for j, t in enumerate(tests):
        log_w = loglik[:, np.arange(len(tests)) != j].sum(axis=1)
        log_w -= logsumexp(log_w)
        lpd[j] = logsumexp(log_w + loglik[:, j])
        w = np.exp(log_w)
        sel = point_test == t
        predicted[sel] = w @ mean[:, sel]
        theta_mean[j] = w @ samples
    return HeldOut(lpd, predicted, theta_mean)


def next_batch(posterior, evaluated_thetas, n, lower, upper, seed):
    """(n, d) new parameter sets: spread out (maximin distance in the normalised box, to the
    evaluated sets and to each other) among draws from the posterior, so the surrogate is
    refined where the posterior mass is without clustering the runs."""
    lower, upper = _box(lower, upper)
    rng = np.random.default_rng(seed)
    drawn = rng.choice(len(posterior.weights), size=N_CANDIDATES, p=posterior.weights)
    candidates = _to_unit(posterior.samples[drawn], lower, upper)
    evaluated = _to_unit(evaluated_thetas, lower, upper)
    nearest = np.linalg.norm(candidates[:, None, :] - evaluated[None, :, :], axis=2).min(axis=1)
    picked = []
    for _ in range(n):
        best = candidates[np.argmax(nearest)]
        picked.append(best)
        nearest = np.minimum(nearest, np.linalg.norm(candidates - best, axis=1))
    return _from_unit(np.array(picked).reshape(n, len(lower)), lower, upper)


@dataclass
class CalibrationResult:
    """Everything calibrate() evaluated and the final posterior."""
    thetas: np.ndarray        # (J, d) every evaluated set, in evaluation order
    rounds: np.ndarray        # (J,) 0 = initial design, 1.. = sequential rounds
    curves: list              # J arrays (K_j, P)
    posterior: Posterior      # from the surrogate fitted on all J sets
    noise: dict               # {test: (P_t, P_t) residual covariance}
    dof: float | None         # the likelihood's t degrees of freedom (None: normal)
    surrogate: Surrogate

    def held_out(self, y, point_test):
        """HeldOut of the final surrogate: each test predicted from the others' posterior."""
        mean = self.surrogate.predict(self.posterior.samples)[0]
        return held_out(self.posterior.samples, mean, self.posterior.test_loglik, np.asarray(y, float),
                        np.asarray(point_test))


def _evaluate(evaluate, thetas):
    curves = [np.asarray(c, float) for c in evaluate(thetas)]
    if len(curves) != len(thetas):
        raise ValueError(f"evaluate returned {len(curves)} curve sets for {len(thetas)} parameter sets")
    return curves


def _update(thetas, curves, y, point_test, lower, upper, measurement_var, shared_cases, n_samples, seed):
    """(noise, dof, surrogate, posterior) from all sets evaluated so far (module doc)."""
    means, case_cov = ensemble_stats(curves)
    scale = 1.0 + np.mean([1.0 / len(c) for c in curves])
    noise = noise_covariances(case_cov, point_test, scale, measurement_var)
    dof = min(len(c) for c in curves) - 1.0 if shared_cases else None
    surrogate = Surrogate(lower, upper, seed).fit(thetas, means)
    return noise, dof, surrogate, posterior(surrogate, y, noise, lower, upper, n_samples, seed, point_test, dof)


def calibrate(evaluate, y, lower, upper, n_initial, iterations, batch, seed, include=None,
              measurement_var=0.0, n_samples=20000, point_test=None, shared_cases=True):
    """Sequential Bayesian calibration; ``evaluate(thetas (n, d)) -> n arrays (K, P)`` is
    called once per round with the whole batch (so the caller can run it in parallel).
    point_test (P,): the measured test of each point (None: one test); shared_cases: every
    set runs the same K specimens (the t likelihood of the module doc) or independent cases
    (normal)."""
    y = np.asarray(y, float)
    point_test = np.zeros(y.size, int) if point_test is None else np.asarray(point_test)
    args = (y, point_test, lower, upper, measurement_var, shared_cases, n_samples)
    thetas = initial_design(lower, upper, n_initial, seed, include)
    curves = _evaluate(evaluate, thetas)
    rounds = np.zeros(n_initial, dtype=int)
    for r in range(1, iterations + 1):
        post = _update(thetas, curves, *args, seed + r)[-1]
        new = next_batch(post, thetas, batch, lower, upper, seed + r)
        thetas = np.vstack([thetas, new])
        curves += _evaluate(evaluate, new)
        rounds = np.concatenate([rounds, np.full(batch, r)])
    noise, dof, surrogate, post = _update(thetas, curves, *args, seed + iterations + 1)
    return CalibrationResult(thetas, rounds, curves, post, noise, dof, surrogate)
