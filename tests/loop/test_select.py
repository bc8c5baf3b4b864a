"""Choosing the missing effect on planted models with known answers: "DEM" ensembles made
by formula (a base curve per test, specimen offsets along the whole curve, point noise),
three candidate effects of different shape, "measured" curves = one more specimen of the
model with one effect at a known strength. The rule must name the planted effect and cut
the held-out RMSE by half; with no effect planted it must choose none (negative control)."""
import numpy as np
import pytest

from ballaststudy.calibration.bayes import initial_design
from ballaststudy.loop.select import (choose, fit_all, held_out_candidate, held_out_plain,
                                      residual_covariances)

TESTS = 7
FREQ = np.array([5.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0])     # a declared covariate per test
K, SETS, MEAS_SD = 4, 8, 3e-4
EFFECTS = {   # theta in [0, 1]; strength per test and N
    "growth": lambda th, t, n: th * 0.006 * np.log(n),
    "bedding": lambda th, t, n: th * 0.012 * np.ones_like(n),
    "rate": lambda th, t, n: th * 0.0002 * FREQ[t] * np.log(n),
}


def _points(rng):
    """Each test's digitised points: 11-20, uneven in ln N, within N <= 200."""
    pts = [np.sort(np.exp(rng.uniform(0, np.log(200), rng.integers(11, 21)))) for _ in range(TESTS)]
    return np.concatenate(pts), np.concatenate([np.full(len(p), t) for t, p in enumerate(pts)])


def _specimens(rng, n, point_test, effect, theta, k):
    """k specimens' curves at the points under the model with ``effect`` at ``theta``."""
    out = []
    for _ in range(k):
        offset = rng.normal(0, 0.002, TESTS)
        curve = np.empty(len(n))
        for t in range(TESTS):
            sel = point_test == t
            base = 0.01 + 0.003 * (1 + 0.1 * t) * np.log(n[sel])
            extra = EFFECTS[effect](theta, t, n[sel]) if effect else 0.0
            curve[sel] = base + extra + offset[t] * (1 + 0.1 * np.log(n[sel])) + rng.normal(0, 2e-4, sel.sum())
        out.append(curve)
    return np.array(out)


def _loop(truth, seed):
    rng = np.random.default_rng(seed)
    n, point_test = _points(rng)
    measured = _specimens(rng, n, point_test, truth, 0.6, 1)[0] + rng.normal(0, MEAS_SD, len(n))
    plain_curves = _specimens(rng, n, point_test, None, 0.0, K)
    thetas = initial_design([0.0], [1.0], SETS, seed=seed + 1)
    runs = {name: [_specimens(rng, n, point_test, name, th[0], K) for th in thetas] for name in EFFECTS}
    held, fits, plains = {}, {}, {}
    for name, curves in runs.items():
        covs = residual_covariances([plain_curves] + curves, point_test, MEAS_SD ** 2)
        plains[name] = held_out_plain(plain_curves, measured, point_test, covs)
        held[name] = held_out_candidate(thetas, curves, measured, point_test, [0.0], [1.0], covs)
        fits[name] = fit_all(thetas, curves, measured, point_test, [0.0], [1.0], covs)
    chosen, evidence = choose({k: (held[k], plains[k]) for k in runs})
    plain = plains[next(iter(runs))]
    return chosen, evidence, held, plain, measured, point_test, fits


@pytest.mark.parametrize("truth", list(EFFECTS))
def test_the_planted_effect_is_named_and_halves_the_held_out_error(truth):
    chosen, evidence, held, plain, measured, point_test, fits = _loop(truth, seed=7)
    assert chosen == truth, evidence
    before, after = plain.rmse(measured, point_test), held[truth].rmse(measured, point_test)
    assert after < 0.5 * before, (before, after)
    assert np.all(np.abs(held[truth].theta_mean[:, 0] - 0.6) < 0.25)     # each fold near the truth
    mean, interval, ess = fits[truth]
    assert interval[0, 0] <= 0.6 <= interval[0, 1] and ess > 10


@pytest.mark.parametrize("seed", [3, 11])
def test_no_effect_planted_none_chosen(seed):
    chosen, evidence, *_ = _loop(None, seed)
    assert chosen is None, evidence


def test_an_effect_that_changes_nothing_is_not_chosen():
    """Its runs are the plain model's: every held-out gain is round-off, none may count."""
    rng = np.random.default_rng(2)
    n, point_test = _points(rng)
    plain_curves = _specimens(rng, n, point_test, None, 0.0, K)
    measured = _specimens(rng, n, point_test, None, 0.0, 1)[0]
    thetas = initial_design([0.0], [1.0], SETS, seed=3)
    runs = [plain_curves + 1e-15 * th[0] for th in thetas]
    covs = residual_covariances([plain_curves] + runs, point_test, MEAS_SD ** 2)
    plain = held_out_plain(plain_curves, measured, point_test, covs)
    held = held_out_candidate(thetas, runs, measured, point_test, [0.0], [1.0], covs)
    chosen, evidence = choose({"nothing": (held, plain)})
    assert chosen is None and evidence["nothing"]["wins"] == 0 and evidence["nothing"]["p"] == 1.0


def test_specimen_share_scales_only_the_specimen_part():
    """(share + 1/K) x pooled + measurement: share 1 and share 0 differ by the pooled
    covariance exactly, the measurement variance stays on the diagonal."""
    rng = np.random.default_rng(5)
    n, point_test = _points(rng)
    curves = [_specimens(rng, n, point_test, None, 0.0, K) for _ in range(3)]
    one = residual_covariances(curves, point_test, MEAS_SD ** 2)
    none = residual_covariances(curves, point_test, MEAS_SD ** 2, specimen_share=0.0)
    for t in one:
        pooled = (one[t] - none[t])
        assert np.allclose(none[t], pooled / K + MEAS_SD ** 2 * np.eye(len(pooled)), rtol=1e-12, atol=1e-18)
