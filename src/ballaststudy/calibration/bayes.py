"""Bayesian calibration of model parameters against one measured curve (thesis 4.3).

The model (a DEM simulation) is run elsewhere as an ensemble of K random cases per parameter
set; this module only sees arrays: parameter sets theta (d,) in a box [lower, upper] and, per
set, the K case curves (K, P) at the P points of the measured curve y (P,).

Method
  1. initial_design: Latin hypercube in the box (optionally containing the default set).
  2. ensemble_stats: ensemble-mean curve per set and the case-to-case variance pooled over
     all sets (every set scatters the same way, so pooling gives many degrees of freedom).
  3. Surrogate: a Gaussian process of the ensemble-mean curve over the normalised box.
  4. posterior: uniform prior, Gaussian likelihood of y with the surrogate mean and variance
     noise_var + surrogate variance (independent points), by importance weights on a
     scrambled Sobol sample of the prior box.
  5. next_batch: new sets spread out (maximin) inside the posterior mass.
  6. calibrate: design -> evaluate -> (fit, posterior, next batch, evaluate) x iterations
     -> final fit and posterior.

Choice of noise_var (the caller's, calibrate() does it this way): the measured curve is
treated as one more random case of the test, while the surrogate predicts the mean of K
cases, so y - surrogate mean has variance sigma^2 (1 + 1/K) with sigma^2 the pooled case
variance:  noise_var = pooled_var * (1 + 1/K) + measurement_var  (the last term optional).
With different K per set, calibrate() uses the average of 1/K_j.
"""
import warnings
from dataclasses import dataclass

import numpy as np
from scipy.special import logsumexp
from scipy.stats import qmc
from sklearn.exceptions import ConvergenceWarning
from sklearn.gaussian_process import GaussianProcessRegressor
from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel

N_CANDIDATES = 4096   # posterior resamples next_batch chooses from


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
    """(means (J, P), pooled case-to-case variance (P,)) of J sets of case curves (K_j, P).

    Pooled variance = sum of squared deviations from each set's mean / sum of (K_j - 1);
    a set with one case has no deviation and no degree of freedom, so it adds nothing.
    """
    curves_list = [np.asarray(c, float) for c in curves_list]
    if not curves_list or any(c.ndim != 2 or c.shape[1] != curves_list[0].shape[1] for c in curves_list):
        raise ValueError("curves_list must be a non-empty list of (K, P) arrays with the same P")
    if not all(np.isfinite(c).all() for c in curves_list):
        raise ValueError("case curves must be finite (fill censored values before calibrating)")
    dof = sum(len(c) - 1 for c in curves_list)
    if dof == 0:
        raise ValueError("no parameter set has K >= 2 cases: the case-to-case variance is unknown")
    means = np.array([c.mean(axis=0) for c in curves_list])
    squares = sum(((c - m) ** 2).sum(axis=0) for c, m in zip(curves_list, means))
    return means, squares / dof


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


def posterior(surrogate, y, noise_var, lower, upper, n_samples=20000, seed=0):
    """Posterior of the parameters given the measured curve y (P,), uniform prior on the box.

    Importance weights on 2^ceil(log2(n_samples)) scrambled Sobol points: cheap, since the
    surrogate is cheap, and exact in the limit; ess tells whether the sample resolves it.
    """
    lower, upper = _box(lower, upper)
    exponent = max(int(np.ceil(np.log2(n_samples))), 0)
    samples = _from_unit(qmc.Sobol(len(lower), rng=seed).random_base2(exponent), lower, upper)
    mu, sd = surrogate.predict(samples)
    var = np.asarray(noise_var, float) + sd ** 2
    loglik = -0.5 * np.sum((np.asarray(y, float) - mu) ** 2 / var + np.log(2 * np.pi * var), axis=1)
    log_weights = loglik - logsumexp(loglik)
    weights = np.exp(log_weights)
    mean = weights @ samples
    centred = samples - mean
    cov = (weights[:, None] * centred).T @ centred
    sd_post = np.sqrt(np.diag(cov))
    interval90 = np.array([weighted_quantile(s, weights, [0.05, 0.95]) for s in samples.T])
    return Posterior(samples, log_weights, weights, mean, interval90, cov / np.outer(sd_post, sd_post),
                     float(1.0 / np.sum(weights ** 2)), samples[np.argmax(weights)])


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
    noise_var: np.ndarray     # (P,)
    surrogate: Surrogate


def _evaluate(evaluate, thetas):
    curves = [np.asarray(c, float) for c in evaluate(thetas)]
    if len(curves) != len(thetas):
        raise ValueError(f"evaluate returned {len(curves)} curve sets for {len(thetas)} parameter sets")
    return curves


def _update(thetas, curves, y, lower, upper, measurement_var, n_samples, seed):
    """(noise_var, surrogate, posterior) from all sets evaluated so far."""
    means, pooled_var = ensemble_stats(curves)
    noise_var = pooled_var * (1.0 + np.mean([1.0 / len(c) for c in curves])) + measurement_var
    surrogate = Surrogate(lower, upper, seed).fit(thetas, means)
    return noise_var, surrogate, posterior(surrogate, y, noise_var, lower, upper, n_samples, seed)


def calibrate(evaluate, y, lower, upper, n_initial, iterations, batch, seed, include=None,
              measurement_var=0.0, n_samples=20000):
    """Sequential Bayesian calibration; ``evaluate(thetas (n, d)) -> n arrays (K, P)`` is
    called once per round with the whole batch (so the caller can run it in parallel)."""
    thetas = initial_design(lower, upper, n_initial, seed, include)
    curves = _evaluate(evaluate, thetas)
    rounds = np.zeros(n_initial, dtype=int)
    for r in range(1, iterations + 1):
        _, _, post = _update(thetas, curves, y, lower, upper, measurement_var, n_samples, seed + r)
        new = next_batch(post, thetas, batch, lower, upper, seed + r)
        thetas = np.vstack([thetas, new])
        curves += _evaluate(evaluate, new)
        rounds = np.concatenate([rounds, np.full(batch, r)])
    noise_var, surrogate, post = _update(thetas, curves, y, lower, upper, measurement_var, n_samples,
                                         seed + iterations + 1)
    return CalibrationResult(thetas, rounds, curves, post, noise_var, surrogate)
