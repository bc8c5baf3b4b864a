"""One measure for a branch's peak (rig.biaxial.peak): the softening check, fed the samples
chunk by chunk as a run produces them, finds the peak the strength test's curve reports;
a spike narrower than the window counts only as its window mean."""
import numpy as np
import pytest

from ballaststudy.rig.biaxial.peak import WINDOW_STRAIN, lookback_start, new_peak, window_mean


def planted_branch(n=20000, seed=0):
    """Strain rising to 4 % with a noisy rate; q: a broad hump (120 kPa at 2.5 %) and, at
    0.04 %, a spike of 300 kPa over 1e-4 of strain (an early skeleton that collapses)."""
    rng = np.random.default_rng(seed)
    ea = np.cumsum(rng.uniform(0.5, 1.5, n))
    ea *= 0.04 / ea[-1]
    q = 120e3 * (ea / 0.025) * np.exp(1.0 - ea / 0.025) + rng.normal(0.0, 5e3, n)
    q[np.abs(ea - 0.0004) < 5e-5] = 300e3
    return ea, q


def watch(ea, q, chunks):
    """The peak as check_stalled follows it: after each chunk, the new samples' windows."""
    best, at, first = -np.inf, np.nan, 0
    for end in chunks:
        k0 = lookback_start(ea[:end], 0, first) if first < end else 0
        m, c = new_peak(ea[k0:end], q[k0:end], first - k0, origin=0.0)
        if m > best:
            best, at = m, c
        first = end
    return best, at


@pytest.mark.parametrize("seed", [0, 1])
def test_the_check_finds_the_curves_peak(seed):
    ea, q = planted_branch(seed=seed)
    grid = np.arange(0.0, ea[-1] - 0.5 * WINDOW_STRAIN, 1e-5)    # the curve, finely
    curve = window_mean(ea, q, grid)
    rng = np.random.default_rng(seed + 10)
    chunks = np.unique(np.r_[np.sort(rng.integers(1, ea.size, 40)), ea.size])
    best, at = watch(ea, q, chunks)
    assert best == pytest.approx(curve.max(), rel=0.01)
    assert at == pytest.approx(grid[np.argmax(curve)], abs=2e-4)
    assert 0.02 < at < 0.03          # the hump, not the spike the window averages
    # one chunk or many: the same peak (the windows look back across chunk ends)
    assert watch(ea, q, [ea.size]) == pytest.approx((best, at), rel=1e-12)


def test_a_spike_wider_than_the_window_is_the_peak():
    ea, q = planted_branch()
    q[np.abs(ea - 0.004) < 2 * WINDOW_STRAIN] = 300e3
    best, at = watch(ea, q, np.linspace(100, ea.size, 30).astype(int))
    assert best == pytest.approx(300e3, rel=1e-9) and at == pytest.approx(0.004, abs=2 * WINDOW_STRAIN)


def test_no_window_before_the_branch_origin():
    ea, q = planted_branch()
    few = ea < 0.5 * WINDOW_STRAIN          # no window centred at 0 or beyond ends here
    m, at = new_peak(ea[few], q[few], 0, origin=0.0)
    assert m == -np.inf and np.isnan(at)
