"""Statistics shared by the IRI tables and the optimisation: per-case summaries of a
behaviour's cycle series, bootstrap intervals of correlations, the correlation verdict rule
and the two-segment regression for the fines threshold. Pure functions of arrays."""

import numpy as np
from scipy import stats

# Verdict rule for a correlation (IRI tables and the thesis' monotone claims).
MIN_ABS_RHO = 0.3
MIN_SAMPLES = 8
VERDICT_RULE = (f"positive if the 95 % bootstrap interval of Spearman's rho lies above 0 and |rho| >= "
                f"{MIN_ABS_RHO}; negative if it lies below 0 and |rho| >= {MIN_ABS_RHO}; none otherwise; "
                f"not decidable with fewer than {MIN_SAMPLES} samples or a constant behaviour")


def _last_finite(a, reverse=False):
    """Value at the last (or first) finite entry along the last axis; NaN if none."""
    a = np.asarray(a, float)
    ok = np.isfinite(a)
    n = a.shape[-1]
    if reverse:
        idx = np.argmax(ok, axis=-1)
    else:
        idx = n - 1 - np.argmax(ok[..., ::-1], axis=-1)
    v = np.take_along_axis(a, idx[..., None], axis=-1)[..., 0]
    return np.where(ok.any(axis=-1), v, np.nan)


def final_value(series):
    """Value at each case's last run cycle (series: (..., cycle), NaN-padded)."""
    return _last_finite(series)


def first_value(series):
    return _last_finite(series, reverse=True)


def change_value(series):
    """Change over the cyclic phase: last minus first run cycle."""
    return final_value(series) - first_value(series)


def level_value(series):
    """Mean over the run cycles."""
    s = np.asarray(series, float)
    out = np.full(s.shape[:-1], np.nan)
    ok = np.isfinite(s).any(axis=-1)
    if ok.any():
        out[ok] = np.nanmean(np.where(np.isfinite(s[ok]), s[ok], np.nan), axis=-1)
    return out


def variability_value(series):
    """Standard deviation over the run cycles (lower = more stable)."""
    s = np.asarray(series, float)
    out = np.full(s.shape[:-1], np.nan)
    ok = np.isfinite(s).sum(axis=-1) >= 2
    if ok.any():
        out[ok] = np.nanstd(s[ok], axis=-1, ddof=1)
    return out


def case_mean_se(values):
    """Per row of a (database, case) array: mean over the finite cases, its standard error
    (sd with ddof 1 / sqrt(n); 0 with one case) and n."""
    n = np.isfinite(values).sum(axis=1)
    with np.errstate(all="ignore"):
        mean = np.where(n > 0, np.nansum(values, axis=1) / np.maximum(n, 1), np.nan)
        sd = np.array([np.std(r[np.isfinite(r)], ddof=1) if k >= 2 else 0.0 for r, k in zip(values, n)])
    return mean, sd / np.sqrt(np.maximum(n, 1)), n


def _row_pearson(x, y):
    """Pearson r of each row pair of (B, n) arrays."""
    xm = x - x.mean(axis=1, keepdims=True)
    ym = y - y.mean(axis=1, keepdims=True)
    den = np.sqrt((xm ** 2).sum(axis=1) * (ym ** 2).sum(axis=1))
    with np.errstate(all="ignore"):
        return np.where(den > 0, (xm * ym).sum(axis=1) / den, np.nan)


def correlation(x, y, n_boot=2000, seed=0):
    """Pearson and Spearman of paired samples with percentile bootstrap 95 % intervals
    (resampling the pairs). Non-finite pairs are dropped. Returns a dict."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    ok = np.isfinite(x) & np.isfinite(y)
    x, y = x[ok], y[ok]
    n = len(x)
    out = {"n": n}
    const = n < 3 or np.ptp(x) == 0 or np.ptp(y) == 0
    if const:
        nan = float("nan")
        out.update(pearson_r=nan, pearson_p=nan, pearson_lo=nan, pearson_hi=nan,
                   spearman_rho=nan, spearman_p=nan, spearman_lo=nan, spearman_hi=nan)
        return out
    pr = stats.pearsonr(x, y)
    sr = stats.spearmanr(x, y)
    idx = np.random.default_rng(seed).integers(0, n, size=(n_boot, n))
    xb, yb = x[idx], y[idx]
    rp = _row_pearson(xb, yb)
    rs = _row_pearson(stats.rankdata(xb, axis=1), stats.rankdata(yb, axis=1))
    # resamples with a constant variable have no correlation; they are left out
    plo, phi = np.nanpercentile(rp, [2.5, 97.5])
    slo, shi = np.nanpercentile(rs, [2.5, 97.5])
    out.update(pearson_r=float(pr[0]), pearson_p=float(pr[1]), pearson_lo=float(plo), pearson_hi=float(phi),
               spearman_rho=float(sr[0]), spearman_p=float(sr[1]), spearman_lo=float(slo), spearman_hi=float(shi))
    return out


def verdict(c, min_abs=MIN_ABS_RHO, min_n=MIN_SAMPLES):
    """'positive' / 'negative' / 'none' / 'not decidable' for a `correlation` result (VERDICT_RULE)."""
    rho, lo, hi = c["spearman_rho"], c["spearman_lo"], c["spearman_hi"]
    if c["n"] < min_n or not np.isfinite(rho):
        return "not decidable"
    if lo > 0 and abs(rho) >= min_abs:
        return "positive"
    if hi < 0 and abs(rho) >= min_abs:
        return "negative"
    return "none"


def two_segment_fit(x, y):
    """Two-segment piecewise-linear regression with a free jump: a line on x <= x0 and another
    on x > x0, each fitted by least squares, x0 chosen to minimise the total squared error
    among the gaps between adjacent distinct x that leave at least two distinct x on each side.
    Within the winning gap every x0 fits equally well; the breakpoint is its midpoint.

    x: (n,) (the same for all fits); y: (n,) or (B, n) for B fits (vectorised over B).
    Returns dict breakpoint, gap_lo, gap_hi, left (a, b), right (a, b) and `excess`: the mean
    over the points above x0 of y minus the left line extrapolated (> 0: the upper regime
    lies above the lower one's trend). Arrays over B, or floats for 1D y. None when fewer than
    4 distinct x or a non-finite value."""
    x = np.asarray(x, float)
    y = np.asarray(y, float)
    single = y.ndim == 1
    Y = np.atleast_2d(y)
    ux = np.unique(x)
    if len(ux) < 4 or not np.all(np.isfinite(x)) or not np.all(np.isfinite(Y)):
        return None
    B = Y.shape[0]
    best_sse = np.full(B, np.inf)
    out = {k: np.full(B, np.nan) for k in ("breakpoint", "gap_lo", "gap_hi", "left_a", "left_b", "right_a",
                                           "right_b", "excess", "sse")}
    for k in range(1, len(ux) - 2):
        left = x <= ux[k]
        coefs, sse = [], np.zeros(B)
        for side in (left, ~left):
            A = np.column_stack([np.ones(side.sum()), x[side]])
            coef = Y[:, side] @ np.linalg.pinv(A).T                # (B, 2)
            sse += ((coef @ A.T - Y[:, side]) ** 2).sum(axis=1)
            coefs.append(coef)
        better = sse < best_sse - 1e-18
        if better.any():
            best_sse[better] = sse[better]
            excess = (Y[:, ~left] - (coefs[0][:, :1] + coefs[0][:, 1:] * x[~left])).mean(axis=1)
            for key, val in (("breakpoint", 0.5 * (ux[k] + ux[k + 1])), ("gap_lo", ux[k]), ("gap_hi", ux[k + 1]),
                             ("left_a", coefs[0][:, 0]), ("left_b", coefs[0][:, 1]), ("right_a", coefs[1][:, 0]),
                             ("right_b", coefs[1][:, 1]), ("excess", excess), ("sse", sse)):
                out[key][better] = np.broadcast_to(val, (B,))[better]
    return {k: float(v[0]) for k, v in out.items()} if single else out


def bootstrap_database_means(values, n_boot, rng):
    """Bootstrap of per-database means by resampling cases within each database.

    values: (database, case) array, NaN for missing cases. Returns (n_boot, database); a
    database without finite cases gives NaN."""
    values = np.asarray(values, float)
    out = np.full((n_boot, values.shape[0]), np.nan)
    for i, row in enumerate(values):
        v = row[np.isfinite(row)]
        if len(v):
            out[:, i] = v[rng.integers(0, len(v), size=(n_boot, len(v)))].mean(axis=1)
    return out


def interval(samples, level=0.95):
    """Percentile interval of bootstrap samples at ``level`` (NaNs ignored)."""
    s = np.asarray(samples, float)
    s = s[np.isfinite(s)]
    if not len(s):
        return float("nan"), float("nan")
    lo, hi = np.percentile(s, [50 * (1 - level), 50 * (1 + level)])
    return float(lo), float(hi)
