"""Settlement: vertical displacement of the loading ball (thesis 4.5.1, l. 1036; 4.2.3).

Like the box test (thesis 4.1, l. 802, Fig. 4-2 b: "the position of the pressing plate by 30 kN of
every loading step"), the settlement of a cycle is read where the loading-ball force
crosses 30 kN on the loading (rising) branch, relative to that position in cycle 0,
positive downward.

Forces in 2D are per out-of-plane thickness t as in PFC2D; the rig passes the force in N
exactly as the thesis states it (15-45 kN), so the 30 kN level is compared directly.
"""
import numpy as np


def loading_branch_crossing(y, force, level):
    """Where one cycle's force first rises through ``level`` before its peak.

    y: (k,) vertical position of the loading ball [m] (up positive), samples of one cycle.
    force: (k,) compressive force on the loading ball [N] at the same samples.
    level: force level [N], e.g. 30e3.

    Returns (y_at_level, y_at_peak, peak_force): y_at_level is linearly interpolated
    between the two samples around the first upward crossing between the cycle start and
    the peak sample (the loading branch); NaN if the force does not cross ``level`` there
    (e.g. the cycle starts above it).
    """
    y = np.asarray(y, float)
    f = np.asarray(force, float)
    if y.shape != f.shape or y.ndim != 1 or y.size == 0:
        raise ValueError(f"y and force must be equal-length 1D arrays, got {y.shape} and {f.shape}")
    ipk = int(np.argmax(f))
    fl = f[: ipk + 1]
    k = np.nonzero((fl[:-1] < level) & (fl[1:] >= level))[0]
    if k.size == 0:
        y_c = np.nan
    else:
        k = k[0]
        s = (level - fl[k]) / (fl[k + 1] - fl[k])
        y_c = y[k] + s * (y[k + 1] - y[k])
    return float(y_c), float(y[ipk]), float(f[ipk])


def settlement(y_cycles, force_cycles, level=30e3):
    """Per-cycle settlement from the loading-ball series of every cycle.

    y_cycles, force_cycles: sequences (one entry per cycle) of 1D arrays [m], [N].
    Returns dict of (n_cycles,) arrays:
      settlement: y_level(cycle 0) - y_level(cycle k) [m], positive downward;
      displacement_at_peak: y_level(cycle 0) - y_at_peak(cycle k) [m], positive downward
        (same reference, so it is the settlement plus the elastic part under the peak);
      peak_force [N]; y_at_level [m] (absolute, for checking).
    """
    rows = np.array([loading_branch_crossing(y, f, level) for y, f in zip(y_cycles, force_cycles)])
    if rows.size == 0:
        e = np.zeros(0)
        return dict(settlement=e, displacement_at_peak=e, peak_force=e, y_at_level=e)
    y_ref = rows[0, 0]
    return dict(settlement=y_ref - rows[:, 0], displacement_at_peak=y_ref - rows[:, 1],
                peak_force=rows[:, 2], y_at_level=rows[:, 0])
