"""Cycle-count accumulation laws of the permanent axial strain eps(N) (issue 14).

A DEM run reaches N_sim ~ 10^2-10^3 load cycles while measured tests go to N = 5e5; a law fitted
to the DEM ensemble carries the model to that horizon, so its form decides the long-term answer.
Ballast hardens (shakes down) and then creeps slowly, which Sato's form

    eps = eps0 + gamma (1 - exp(-alpha (N - 1))) + beta (N - 1)

describes with a bounded hardening part and a constant creep rate. A log or a power law keeps the
rate it had inside the fitted window: fitted on 10^3-10^4 cycles it overshoots 5e5 by tens of
percent. The hardening-log law keeps Sato's hardening and lets the creep slow down as ln N
does. Which law carries a measured curve furthest is measured, not assumed (loop/horizon.py).

Strains are fractions; N is the cycle count, N = 1 the first loading.
"""
from dataclasses import dataclass

import numpy as np
from scipy.optimize import curve_fit, lsq_linear

HARDENING_GRID = 61    # log-spaced hardening rates alpha the Sato fit starts from the best of
SIGMA_FLOOR = 0.1      # fit_ensemble: standard errors floored at this fraction of their median
RELATIVE_STEP = 1e-6   # numerical Jacobian: step relative to the parameter (at least 1e-6 of it)


def sato(n, params):
    """Sato's hardening law eps0 + gamma (1 - exp(-alpha (N - 1))) + beta (N - 1).

    eps0   permanent axial strain after the first loading (N = 1)
    gamma  hardening strain still to come after N = 1 (>= 0)
    alpha  hardening rate per cycle (> 0): 63 % of gamma is reached 1/alpha cycles after N = 1
    beta   creep rate per cycle left once hardened (>= 0); beta = 0 is shakedown
    """
    eps0, gamma, alpha, beta = params
    cycles_after_first = np.asarray(n, float) - 1.0
    return eps0 - gamma * np.expm1(-alpha * cycles_after_first) + beta * cycles_after_first


def shakedown(n, params):
    """Sato's law without creep (beta = 0): eps0 + gamma (1 - exp(-alpha (N - 1))), the
    plastic-shakedown reading of a run too short to tell hardening from creep."""
    eps0, gamma, alpha = params
    return sato(n, (eps0, gamma, alpha, 0.0))


def hardening_log(n, params):
    """eps0 + gamma (1 - exp(-alpha (N - 1))) + c ln N: Sato's hardening with a creep whose
    rate falls as 1/N (c >= 0, the strain per e-fold of N once hardened), the semi-log
    growth large triaxial tests on ballast show after the first cycles."""
    eps0, gamma, alpha, c = params
    return sato(n, (eps0, gamma, alpha, 0.0)) + c * np.log(np.asarray(n, float))


def log_law(n, params):
    """a + b ln N (reference only): a is the strain at N = 1, b the strain per e-fold of N."""
    a, b = params
    return a + b * np.log(np.asarray(n, float))


def power_law(n, params):
    """a N^b (reference only): a is the strain at N = 1 (> 0), b the exponent."""
    a, b = params
    return a * np.asarray(n, float) ** b


LAWS = {"sato": sato, "shakedown": shakedown, "hardening_log": hardening_log, "log": log_law,
        "power": power_law}
PARAMETER_NAMES = {"sato": ("eps0", "gamma", "alpha", "beta"), "shakedown": ("eps0", "gamma", "alpha"),
                   "hardening_log": ("eps0", "gamma", "alpha", "c"), "log": ("a", "b"), "power": ("a", "b")}
HARDENING_LAWS = ("sato", "shakedown", "hardening_log")     # the laws with a hardening rate alpha
_FITTED_AS_LOG = {law: ("alpha",) for law in HARDENING_LAWS}   # rates spanning decades: fitted as logs


@dataclass(frozen=True)
class LawFit:
    """A law fitted to eps(N): parameters in PARAMETER_NAMES order with their covariance; rss is
    the weighted residual sum of squares (chi-square when sigma was given), dof = points - params,
    n_min..n_max the fitted cycle counts (beyond n_max the law extrapolates)."""
    name: str
    params: np.ndarray
    names: tuple
    covariance: np.ndarray
    rss: float
    dof: int
    n_min: float
    n_max: float

    @property
    def standard_errors(self):
        return np.sqrt(np.diag(self.covariance))


def _curve(n, eps):
    """(n, eps) as float arrays, checked: 1-D, same length, finite, N >= 1."""
    n, eps = np.asarray(n, float), np.asarray(eps, float)
    if n.ndim != 1 or eps.shape != n.shape:
        raise ValueError(f"cycle counts {n.shape} and permanent strains {eps.shape} must be 1-D of one length")
    if not (np.isfinite(n).all() and np.isfinite(eps).all()):
        raise ValueError("cycle counts and permanent strains must be finite (no NaN or inf)")
    if np.any(n < 1):
        raise ValueError("cycle counts must be >= 1 (N = 1 is the first loading)")
    return n, eps


def _checked(name, n, eps, sigma):
    """Validated (n, eps, sigma or None) for fitting law `name`."""
    if name not in LAWS:
        raise ValueError(f"unknown accumulation law {name!r}; known: {sorted(LAWS)}")
    n, eps = _curve(n, eps)
    n_params = len(PARAMETER_NAMES[name])
    if len(np.unique(n)) <= n_params:
        raise ValueError(f"the {name} law has {n_params} parameters and needs at least {n_params + 1} "
                         f"distinct cycle counts; got {len(np.unique(n))}")
    if name == "power" and np.any(eps <= 0):
        raise ValueError("the power law needs positive permanent strain at every cycle count")
    if sigma is None:
        return n, eps, None
    sigma = np.broadcast_to(np.asarray(sigma, float), n.shape)
    if not (np.isfinite(sigma).all() and np.all(sigma > 0)):
        raise ValueError("sigma must be finite and > 0 at every cycle count")
    return n, eps, sigma


def _hardening_rate_range(n):
    """(lowest, highest) alpha the cycle counts resolve. Slower hardening, not 63 % complete within
    the fitted span, cannot be told from creep: left free it runs off to gamma -> inf, alpha -> 0
    with gamma alpha acting as a creep rate. Faster hardening, complete (e^-10) before the first
    cycle count after N = 1, is a constant step that no point can date."""
    cycles_after_first = np.unique(n) - 1.0
    resolved = cycles_after_first[cycles_after_first > 0]
    return 1.0 / resolved[-1], 10.0 / resolved[0]


def _bounds(name, n):
    """(lower, upper) bounds of the parameters of law `name` fitted on cycle counts n."""
    if name in HARDENING_LAWS:
        slowest, fastest = _hardening_rate_range(n)
        lower, upper = np.array([-np.inf, 0.0, slowest, 0.0]), np.array([np.inf, np.inf, fastest, np.inf])
        return (lower, upper) if name != "shakedown" else (lower[:3], upper[:3])
    if name == "power":
        return np.array([0.0, -np.inf]), np.array([np.inf, np.inf])
    return np.full(2, -np.inf), np.full(2, np.inf)


def _start_sato(n, eps, weights, creep="linear"):
    """Start at the best alpha of a log grid over the resolved range: for fixed alpha the law is
    linear in (eps0, gamma, creep), solved exactly with gamma, creep >= 0, so the nonlinear fit
    begins in the right valley instead of a local minimum next to a guessed alpha. creep:
    "linear" (Sato, beta (N - 1)), "log" (hardening_log, c ln N) or None (shakedown)."""
    cycles_after_first = n - 1.0
    columns = [np.ones_like(n), None]
    span = 1.0
    if creep is not None:            # scaled to order one: bvls works on comparable columns
        creep_term = cycles_after_first if creep == "linear" else np.log(n)
        span = creep_term.max()
        columns.append(creep_term / span)

    def profile(alpha):
        columns[1] = -np.expm1(-alpha * cycles_after_first)
        design = np.column_stack(columns)
        solution = lsq_linear(design * weights[:, None], eps * weights,
                              bounds=([-np.inf] + [0.0] * (len(columns) - 1), [np.inf] * len(columns)),
                              method="bvls")
        return solution.cost, alpha, solution.x

    _, alpha, x = min((profile(alpha) for alpha in np.geomspace(*_hardening_rate_range(n), HARDENING_GRID)),
                      key=lambda candidate: candidate[0])
    start = [x[0], x[1], alpha] + ([x[2] / span] if creep else [])
    return np.array(start)


def _start_log(n, eps, weights):
    """Weighted linear least squares in ln N: the log law's exact solution."""
    design = np.column_stack([np.ones_like(n), np.log(n)])
    return np.linalg.lstsq(design * weights[:, None], eps * weights, rcond=None)[0]


def _start_power(n, eps, weights):
    """Linear least squares of ln eps on ln N (weights times eps: d ln eps = d eps / eps)."""
    design = np.column_stack([np.ones_like(n), np.log(n)])
    ln_a, b = np.linalg.lstsq(design * (weights * eps)[:, None], np.log(eps) * weights * eps, rcond=None)[0]
    return np.array([np.exp(ln_a), b])


_STARTS = {"sato": _start_sato, "shakedown": lambda n, eps, w: _start_sato(n, eps, w, creep=None),
           "hardening_log": lambda n, eps, w: _start_sato(n, eps, w, creep="log"),
           "log": _start_log, "power": _start_power}


def fit_law(name, n, eps, sigma=None):
    """Fit law `name` to the permanent axial strain eps at cycle counts n by curve_fit.

    sigma (optional, per point or scalar) is the standard deviation of eps, taken as absolute;
    a misfit larger than it (chi-square / dof > 1) inflates the covariance by that ratio, so a
    law that does not follow the data cannot claim the precision of the data. Without sigma
    the covariance is scaled by the residual variance as usual.
    """
    n, eps, sigma = _checked(name, n, eps, sigma)
    law, names = LAWS[name], PARAMETER_NAMES[name]
    weights = np.ones_like(n) if sigma is None else 1.0 / sigma
    as_log = np.array([p in _FITTED_AS_LOG.get(name, ()) for p in names])
    lower, upper = _bounds(name, n)
    start = np.clip(_STARTS[name](n, eps, weights), lower, upper)

    def fitted_law(cycles, *fitted):
        return law(cycles, _natural(np.array(fitted), as_log))

    fitted, fitted_covariance = curve_fit(
        fitted_law, n, eps, p0=_log_of(start, as_log), sigma=sigma, absolute_sigma=sigma is not None,
        bounds=(_log_of(lower, as_log), _log_of(upper, as_log)), method="trf", x_scale="jac")
    params = _natural(fitted, as_log)
    dof = len(n) - len(params)
    rss = float(np.sum(((eps - law(n, params)) * weights) ** 2))
    scale = np.where(as_log, params, 1.0)         # d p / d ln p = p
    covariance = fitted_covariance * np.outer(scale, scale)
    if sigma is not None:
        covariance = covariance * max(1.0, rss / dof)
    return LawFit(name, params, names, covariance, rss, dof, float(n.min()), float(n.max()))


def _log_of(params, as_log):
    out = np.array(params, float)
    with np.errstate(divide="ignore"):          # a zero lower bound becomes -inf, as it should
        out[as_log] = np.log(out[as_log])
    return out


def _natural(fitted, as_log):
    out = np.array(fitted, float)
    out[as_log] = np.exp(out[as_log])
    return out


def _jacobian(law, n, params):
    """d law / d params at cycle counts n by central differences, shape n.shape + (params,)."""
    columns = []
    for i, step in enumerate(RELATIVE_STEP * np.maximum(np.abs(params), 1e-6)):
        shift = np.zeros_like(params)
        shift[i] = step
        columns.append((law(n, params + shift) - law(n, params - shift)) / (2.0 * step))
    return np.stack(columns, axis=-1)


def predict(fit, n):
    """(mean, sd) of the fitted law at cycle counts n. sd is the delta-method standard deviation
    from the parameter covariance: what the fitted cycles leave open about the law, which grows
    with the distance beyond fit.n_max (not the scatter of one test about the mean)."""
    n = np.asarray(n, float)
    law = LAWS[fit.name]
    jacobian = _jacobian(law, n, fit.params)
    variance = np.einsum("...i,ij,...j->...", jacobian, fit.covariance, jacobian)
    return law(n, fit.params), np.sqrt(np.maximum(variance, 0.0))


def fit_ensemble(name, n, curves):
    """Fit law `name` to the mean of K random cases, curves (K, len(n)), weighted by the standard
    error of that mean (case-to-case sd / sqrt K). The standard errors are floored at SIGMA_FLOOR
    times their median: cases that agree exactly at some N (e.g. all zero at N = 1) would
    otherwise get infinite weight. If the cases agree everywhere, the fit is unweighted."""
    curves = np.asarray(curves, float)
    if curves.ndim != 2 or curves.shape[1] != np.size(n) or len(curves) < 2:
        raise ValueError(f"curves must be (K >= 2, {np.size(n)}) = (cases, cycle counts); got {curves.shape}")
    if not np.isfinite(curves).all():
        raise ValueError("case curves must be finite (no NaN or inf)")
    standard_error = curves.std(axis=0, ddof=1) / np.sqrt(len(curves))
    scattered = standard_error[standard_error > 0]
    sigma = np.maximum(standard_error, SIGMA_FLOOR * np.median(scattered)) if scattered.size else None
    return fit_law(name, n, curves.mean(axis=0), sigma)


def extrapolation_error(name, n, eps, n_fit_max):
    """Relative error (predicted - true) / true at the largest cycle count of a long curve when law
    `name` is fitted only on N <= n_fit_max: how far the law carries a short run."""
    n, eps = _curve(n, eps)
    fitted = n <= n_fit_max
    if fitted.all():
        raise ValueError(f"no cycle count beyond n_fit_max = {n_fit_max} to extrapolate to")
    fit = fit_law(name, n[fitted], eps[fitted])
    last = np.argmax(n)
    return float((LAWS[name](n[last], fit.params) - eps[last]) / eps[last])
