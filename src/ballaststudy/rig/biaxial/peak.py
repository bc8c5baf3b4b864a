"""A loading branch's stress read one way everywhere: as its mean over WINDOW_STRAIN of
axial strain. The strength test's curve (q_peak, phi_peak) and the softening check that
ends a test past its peak (BiaxialRun.check_stalled) both read it, so the peak that stops
a test is the peak it reports. A mean over a number of samples is not one measure: 50
samples were ~1e-4 of strain at I = 1e-3 but ~1e-6 at 1.5e-5, where a specimen's early
spike (sigma_1 159 kPa at 0.04 % strain, then ~15 kPa at 0.25 %) stopped the test 2 %
later while the curve's window means, on which phi_peak was read, averaged it away.

Samples are ordered by the running maximum of the axial strain (a platen that only
advances moves it monotonically; a servo's small reversals keep the order)."""
import numpy as np

WINDOW_STRAIN = 0.002


def window_mean(order, x, at, window=WINDOW_STRAIN):
    """Mean of x over the samples whose ``order`` (non-decreasing strain) lies in
    [at - window / 2, at + window / 2], for each ``at`` (at least one sample each)."""
    c = np.concatenate([[0.0], np.cumsum(x)])
    lo = np.searchsorted(order, at - 0.5 * window)
    hi = np.maximum(np.searchsorted(order, at + 0.5 * window, side="right"), lo + 1)
    return (c[hi] - c[lo]) / (hi - lo)


def lookback_start(strain, start, first, window=WINDOW_STRAIN):
    """The earliest sample, from ``start`` on, that a window ending at sample ``first``
    holds: going back from first while the strain stays above strain[first] - window
    (a branch's strain rises, so the samples a window holds are contiguous)."""
    below = np.flatnonzero(np.asarray(strain[start:first]) <= strain[first] - window)
    return start + int(below[-1]) + 1 if below.size else start


def new_peak(strain, x, first, origin, window=WINDOW_STRAIN):
    """(largest window mean, strain at its centre) among the windows that end at the
    samples ``first`` onwards of ``strain``/``x`` (the samples a window before them holds
    included) and are centred at origin or beyond (the curve of strength_curve begins at
    the branch's strain, origin); (-inf, nan) if none is."""
    order = np.maximum.accumulate(np.asarray(strain, float))
    at = order[first:] - 0.5 * window
    at = at[at >= origin]
    if at.size == 0:
        return -np.inf, np.nan
    m = window_mean(order, np.asarray(x, float), at, window)
    k = int(np.argmax(m))
    return float(m[k]), float(at[k])
