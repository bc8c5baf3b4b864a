"""The frequency step side by side (issue 34): a quantity's increment from N = 100 to 2000,
measured beside the model's, per test.

Sun et al.'s frequency step lies in that window: the measured axial strain grows there by
several percentage points at f >= 20 Hz and by about one at f <= 10 Hz. The measured
increment is read on each test's whole curve (every point, beyond the DEM horizon too),
interpolated in ln N between the points either side (NaN where the curve does not reach
both ends). The model's is read on its simulated cycles only, never extrapolated: the
window is cut at the largest N simulated, N_b = min(2000, N_sim), and starts a factor 20
below (as 100 -> 2000 does; not below N = 1): with N_sim >= 2000 it is 100 -> 2000, with
the default 12 cycles 1 -> 12. The measured increment over that same window stands beside
it. The ensemble's interval is the 90 % prediction interval of one more specimen (the
measured one, as residual.py judges it) over the K' cases that did not give way (a case
that gave way has a censored curve, no increment of its own): mean +- the root of the two
half-widths' squares, the cases' scatter's at t(0.95, K' - 1), sd (1 + 1/K')^0.5, and
the two measured points' known sd_m's at the normal's 0.95 quantile, 2^0.5 sd_m. Why so:
drawn with the measured specimen one more of the ensemble's kind (K' = 2-8, the measured
points' sd 0.2-3.4 x the cases'), it covered 90-95 %; t(K' - 1) on the whole covered up to
100 %, and Satterthwaite's degrees of freedom 83 % at K' = 2 (two close cases make them
many). Reproduced: the measured increment over the window lies in that interval."""
import numpy as np
from scipy import stats

from ..scenario.results import at_points

STEP_CYCLES = (100.0, 2000.0)     # the window of Sun et al.'s frequency step
LEVEL = 0.9                       # the prediction interval's coverage
# how far (a factor in N) a window's end may lie beyond a measured curve's first or last
# point and still read it: N read off a log axis by digitising scatters so (Sun et al.'s
# first loading, N = 1, reads 1.00-1.02; their points in the window sit a few % off their
# nominal N), and an end read there moves by less than the curve's own scatter
DIGITISED_N = 1.05


def window(cycles):
    """(N_a, N_b): STEP_CYCLES cut at the largest N simulated (``cycles``), starting the
    same factor below N_b, at least at N = 1."""
    hi = min(STEP_CYCLES[1], float(cycles))
    return max(1.0, min(STEP_CYCLES[0], hi * STEP_CYCLES[0] / STEP_CYCLES[1])), hi


def measured_increment(n, values, lo, hi):
    """values(hi) - values(lo) on a measured curve (N sorted, finite), interpolated in ln N;
    NaN unless points lie either side of both ends, or within DIGITISED_N of one."""
    if n.size == 0 or lo * DIGITISED_N < n[0] or hi > n[-1] * DIGITISED_N:
        return float("nan")
    at = np.interp(np.log([lo, hi]), np.log(n), values)
    return float(at[1] - at[0])


def ensemble_increment(curves, failed, lo, hi, measurement_sd):
    """The increment over [lo, hi] of an ensemble (K, N_sim) whose cases gave way where
    ``failed`` (K,): {mean, interval90 [lo, hi] (NaN with fewer than two cases left), kept,
    gave_way}."""
    kept = np.asarray(curves, float)[~np.asarray(failed, bool)]
    inc = np.array([np.diff(at_points(c, np.array([lo, hi])))[0] for c in kept])
    mean, half = (float(inc.mean()) if inc.size else float("nan")), float("nan")
    if inc.size > 1:
        q = 0.5 + LEVEL / 2
        half = float(np.hypot(stats.t.ppf(q, inc.size - 1) * np.sqrt(inc.var(ddof=1) * (1 + 1 / inc.size)),
                              stats.norm.ppf(q) * np.sqrt(2) * measurement_sd))
    return dict(mean=mean, interval90=[mean - half, mean + half], kept=int(inc.size),
                gave_way=int(len(failed) - inc.size))


def reproduced(measured, model):
    """'yes' / 'no': the measured increment inside the model's interval; '-': no interval
    or no measured increment."""
    lo, hi = model["interval90"]
    if not (np.isfinite(measured) and np.isfinite(lo)):
        return "-"
    return "yes" if lo <= measured <= hi else "no"


def step_rows(names, curves_of, models, cycles, measurement_sd):
    """Per test: the measured increment over STEP_CYCLES and over the model's window, and
    each model's (``models`` {name: Evaluator set with "curves" (T, K, N_sim), "failed"
    (T, K)}) with its interval and verdict. ``curves_of`` [(N, values)] the tests' whole
    measured curves."""
    lo, hi = window(cycles)
    rows = []
    for j, (name, (n, v)) in enumerate(zip(names, curves_of)):
        at_window = measured_increment(n, v, lo, hi)
        row = dict(test=name, window=[lo, hi], measured_step=measured_increment(n, v, *STEP_CYCLES),
                   measured_window=at_window, models={})
        for model, st in models.items():
            inc = ensemble_increment(st["curves"][j], st["failed"][j], lo, hi, measurement_sd)
            row["models"][model] = inc | dict(reproduced=reproduced(at_window, inc))
        rows.append(row)
    return rows


def shared_runs(cases):
    """Groups (lists of test indices, more than one) whose model runs are one (the same case
    files, ``cases`` [[path per case] per test]: the tests differ only in what does not act
    in the model, e.g. a quasi-static run's f): their increments are one by construction."""
    groups = {}
    for j, files in enumerate(cases):
        groups.setdefault(tuple(map(str, files)), []).append(j)
    return [g for g in groups.values() if len(g) > 1]
