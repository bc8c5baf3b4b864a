"""Residuals of the model against measured tests, in the DEM horizon (N <= the simulated
cycles), and their attribution to the tests' declared covariates (issue 14).

Per test: the ensemble of K simulated curves (N = 1..N_sim, cycle k at N = k + 1) at the
measured points, interpolated in ln N (scenario.results.at_points); the residual
r = measured - ensemble mean, with a pointwise band s (1 + 1/K)^0.5 (+ the measurement sd).

The points of one curve are not independent: a specimen is stiffer or softer all along, so
a pointwise chi-square or a regression over the points would call one specimen's own curve
a misfit. The measured curve is treated as one more specimen instead: its level (mean over
the points) and its slope in ln N are compared with the K cases' levels and slopes, a
prediction t-test with K - 1 degrees of freedom, t = (measured - mean of cases) /
(sd of cases (1 + 1/K)^0.5 (+) the measurement's share). With K = 1 the scatter is
unknown; only the measurement sd remains (normal) and the summary says so.

Across tests: each summary number against each declared covariate by least squares with
one intercept per source study (the source is a grouping factor, not pooled), the slope's
t-test p, Holm-adjusted over the covariates tried. A relation is significant if its
adjusted p < ALPHA."""
from dataclasses import dataclass

import numpy as np
from scipy import stats

from ..scenario.results import at_points

ALPHA = 0.05


@dataclass(frozen=True)
class Residual:
    n: np.ndarray            # (P,) measured N within the simulated cycles
    measured: np.ndarray     # (P,)
    cases: np.ndarray        # (K, P) the simulated cases at the points
    measurement_sd: float

    @property
    def predicted(self):
        return self.cases.mean(axis=0)

    @property
    def r(self):
        return self.measured - self.predicted

    @property
    def sd(self):
        """Pointwise standard deviation of r: one more specimen and the measurement."""
        k = len(self.cases)
        scatter = self.cases.var(axis=0, ddof=1) * (1 + 1 / k) if k > 1 else 0.0
        return np.sqrt(scatter + self.measurement_sd ** 2) * np.ones(len(self.n))


def residual(n, measured, curves, measurement_sd):
    """The residual of one test: n, measured (P,) the measured points; curves (K, N_sim)
    the simulated cases (finite); points beyond N_sim are left out, never extrapolated."""
    curves = np.atleast_2d(np.asarray(curves, float))
    if not np.isfinite(curves).all():
        raise ValueError("simulated curves must be finite (fill a failed case first)")
    n, measured = np.asarray(n, float), np.asarray(measured, float)
    keep = np.isfinite(measured) & (n >= 1) & (n <= curves.shape[1])
    at = np.array([at_points(c, n[keep]) for c in curves])
    return Residual(n[keep], measured[keep], at, float(measurement_sd))


def features(ln_n, curves):
    """(level, slope in ln N) of each curve (rows) at the points: mean, least-squares slope."""
    curves = np.atleast_2d(curves)
    x = ln_n - ln_n.mean()
    return curves.mean(axis=1), curves @ x / np.sum(x ** 2)


def summary(res):
    """RMSE; bias and residual slope in ln N, each with its standard error and two-sided
    prediction-test p (module doc)."""
    p, k = len(res.n), len(res.cases)
    out = dict(points=p, cases=k, scatter_known=k > 1, rmse=float(np.sqrt(np.mean(res.r ** 2))) if p else np.nan)
    if p < 3 or np.ptp(np.log(res.n)) == 0:
        return out | dict(bias=float(res.r.mean()) if p else np.nan, bias_se=np.nan, bias_p=np.nan,
                          slope_ln_n=np.nan, slope_se=np.nan, slope_p=np.nan)
    ln_n = np.log(res.n)
    level_m, slope_m = features(ln_n, res.measured)
    level_c, slope_c = features(ln_n, res.cases)
    meas = (res.measurement_sd / np.sqrt(p), res.measurement_sd / np.sqrt(np.sum((ln_n - ln_n.mean()) ** 2)))
    for name, m, c, e in (("bias", level_m[0], level_c, meas[0]), ("slope_ln_n", slope_m[0], slope_c, meas[1])):
        scatter = c.var(ddof=1) * (1 + 1 / k) if k > 1 else 0.0
        se = float(np.sqrt(scatter + e ** 2))
        t = (m - c.mean()) / se if se > 0 else np.inf
        dist = stats.t(k - 1) if k > 1 else stats.norm
        key = "slope" if name == "slope_ln_n" else "bias"
        out.update({name: float(m - c.mean()), f"{key}_se": se, f"{key}_p": float(2 * dist.sf(abs(t)))})
    return out


def covariate_tests(rows, response, covariates, group="source"):
    """Each covariate's slope on ``response`` across the tests (rows: dicts with the
    response, the covariates where declared and the group), one intercept per group, with
    its t-test p and the Holm-adjusted p over the covariates tried. Untried (reported so):
    a covariate that varies in no group, or whose variation one test alone carries (all
    but one test share a value: that test's residual would be the whole evidence)."""
    results = []
    for cov in covariates:
        sel = [r for r in rows if np.isfinite(r.get(cov, np.nan)) and np.isfinite(r[response])]
        groups = sorted({r[group] for r in sel})
        x = np.array([r[cov] for r in sel], float)
        y = np.array([r[response] for r in sel], float)
        g = np.array([groups.index(r[group]) for r in sel])
        varies = any(np.ptp(x[g == j]) > 0 for j in range(len(groups))) if sel else False
        if varies:
            _, counts = np.unique(x, return_counts=True)
            varies = len(x) - counts.max() >= 2
        dof = len(sel) - len(groups) - 1
        row = dict(covariate=cov, response=response, tests=len(sel), groups=len(groups),
                   slope=np.nan, se=np.nan, p=np.nan, tried=bool(varies and dof > 0))
        if row["tried"]:
            design = np.column_stack([x, (g[:, None] == np.arange(len(groups))).astype(float)])
            coef, *_ = np.linalg.lstsq(design, y, rcond=None)
            s2 = np.sum((y - design @ coef) ** 2) / dof
            se = np.sqrt(s2 * np.linalg.inv(design.T @ design)[0, 0])
            row.update(slope=float(coef[0]), se=float(se),
                       p=float(2 * stats.t.sf(abs(coef[0] / se), dof)) if se > 0 else 0.0)
        results.append(row)
    tried = [r for r in results if r["tried"]]
    for r, adj in zip(tried, holm([r["p"] for r in tried])):
        r.update(p_holm=adj, significant=bool(adj < ALPHA))
    return results


def holm(p):
    """Holm's step-down adjusted p-values (family-wise error over the tests tried)."""
    p = np.asarray(p, float)
    order = np.argsort(p)
    adjusted = np.maximum.accumulate((len(p) - np.arange(len(p))) * p[order])
    out = np.empty_like(p)
    out[order] = np.minimum(adjusted, 1.0)
    return out.tolist()

