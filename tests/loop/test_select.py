"""Choosing the missing effect on planted models with known answers: "DEM" ensembles made
by formula (a base curve per test, specimen offsets along the whole curve, point noise),
three candidate effects of different shape, "measured" curves = one more specimen of the
model with one effect at a known strength (a lab test: specimen_share 1), or the ensemble
mean of the model's own specimens under it (model-made data, common random numbers:
specimen_share 0, the noise the chaos a probe measures). The rule must name the planted
effect and cut the held-out RMSE by half; with no effect planted it must choose none
(negative control)."""
import numpy as np
import pytest

from ballaststudy.calibration.bayes import initial_design
from ballaststudy.calibration.bayes import SHRINK, HeldOut
from ballaststudy.loop.select import (ALPHA, STRAY_LIMIT, candidate_covariances, chaos_covariance, choose,
                                      held_out_candidate, held_out_plain, judge_candidate, pick, residual_covariances,
                                      residual_dof, scatter_mse, stray)

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


def _specimens(rng, n, point_test, effect, theta, k, offsets=None, chaos=2e-4):
    """k specimens' curves at the points under the model with ``effect`` at ``theta``;
    ``offsets`` (k, TESTS) fixed specimens (common random numbers), else new ones; each run
    adds its own point scatter of sd ``chaos``."""
    offsets = rng.normal(0, 0.002, (k, TESTS)) if offsets is None else offsets
    out = []
    for offset in offsets:
        curve = np.empty(len(n))
        for t in range(TESTS):
            sel = point_test == t
            base = 0.01 + 0.003 * (1 + 0.1 * t) * np.log(n[sel])
            extra = EFFECTS[effect](theta, t, n[sel]) if effect else 0.0
            curve[sel] = base + extra + offset[t] * (1 + 0.1 * np.log(n[sel])) + rng.normal(0, chaos, sel.sum())
        out.append(curve)
    return np.array(out)


def _judged(thetas, runs, plain_curves, measured, point_test, noise, dof, share=1.0):
    """The loop's judgement (loop.cli._judge) of every candidate against the plain model."""
    covs, plain_covs = noise
    own = {k: candidate_covariances(c, point_test, MEAS_SD ** 2, noise, share) for k, c in runs.items()}
    judged = {k: judge_candidate(thetas, c, measured, point_test, [0.0], [1.0], covs, dof=dof, fit_covs=own[k][0])
              for k, c in runs.items()}
    held, fits = ({k: j[i] for k, j in judged.items()} for i in (0, 1))
    plain = held_out_plain(plain_curves, measured, point_test, plain_covs, dof)
    chosen, evidence = choose({k: (held[k], plain) for k in runs}, measured,
                              {k: scatter_mse(own[k][1]) for k in runs})
    return chosen, evidence, held, plain, fits


def _loop(truth, seed):
    """A lab test: the measured curve one more specimen of the model with ``truth``."""
    rng = np.random.default_rng(seed)
    n, point_test = _points(rng)
    measured = _specimens(rng, n, point_test, truth, 0.6, 1)[0] + rng.normal(0, MEAS_SD, len(n))
    plain_curves = _specimens(rng, n, point_test, None, 0.0, K)
    thetas = initial_design([0.0], [1.0], SETS, seed=seed + 1)
    runs = {name: [_specimens(rng, n, point_test, name, th[0], K) for th in thetas] for name in EFFECTS}
    noise = residual_covariances(plain_curves, point_test, MEAS_SD ** 2)
    return (*_judged(thetas, runs, plain_curves, measured, point_test, noise, residual_dof(K)), measured, point_test)


def _loop_own_specimens(truth, seed, chaos=2e-4, meas_sd=2e-5, offset_sd=0.02):
    """Model-made data: the measured curve the mean of the model's own K specimens with
    ``truth`` (a run of its own: its own chaos draw) and every set on the same specimens.
    With no effect the truth is the plain runs themselves, as in the DEM (same specimens,
    same parameters: the same bytes)."""
    rng = np.random.default_rng(seed)
    n, point_test = _points(rng)
    offsets = rng.normal(0, offset_sd, (K, TESTS))
    run = lambda effect, theta: _specimens(rng, n, point_test, effect, theta, K, offsets, chaos)
    plain_curves, probe = run(None, 0.0), run(None, 0.0)
    truth_runs = run(truth, 0.6) if truth else plain_curves
    measured = truth_runs.mean(axis=0) + rng.normal(0, meas_sd, len(n))
    thetas = np.linspace(0.0, 1.0, SETS)[:, None]
    runs = {name: [run(name, th[0]) for th in thetas] for name in EFFECTS}
    noise = residual_covariances(plain_curves, point_test, meas_sd ** 2, specimen_share=0.0, probe=probe)
    dof = residual_dof(K, specimen_share=0.0)
    return (*_judged(thetas, runs, plain_curves, measured, point_test, noise, dof, 0.0), measured, point_test)


@pytest.mark.parametrize("truth", list(EFFECTS))
def test_the_planted_effect_is_named_and_halves_the_held_out_error(truth):
    chosen, evidence, held, plain, fits, measured, point_test = _loop(truth, seed=7)
    assert chosen == truth, evidence
    before, after = plain.rmse(measured, point_test), held[truth].rmse(measured, point_test)
    assert after < 0.5 * before, (before, after)
    assert np.all(np.abs(held[truth].theta_mean[:, 0] - 0.6) < 0.25)     # each fold near the truth
    mean, interval, ess = fits[truth]
    assert interval[0, 0] <= 0.6 <= interval[0, 1] and ess > 10


RICH = 6     # smooth components of a specimen's deviation


def _rich_specimens(rng, n, point_test, effect, theta, k, sd=0.001, chaos=2e-4):
    """k specimens whose deviation from the model's mean is a smooth function of ln N with
    RICH components, the same under every test (a softer or stiffer specimen, in a shape of
    its own): K = 3 of them span 2 of those directions, a fresh one leaves their span."""
    coeffs = rng.normal(0, sd, (k, RICH))
    x = np.log(n) / np.log(200)
    shape = coeffs @ np.stack([np.cos(np.pi * j * x) for j in range(RICH)])
    out = np.empty((k, len(n)))
    for t in range(TESTS):
        sel = point_test == t
        base = 0.01 + 0.003 * (1 + 0.1 * t) * np.log(n[sel])
        extra = EFFECTS[effect](theta, t, n[sel]) if effect else 0.0
        out[:, sel] = base + extra + shape[:, sel] + rng.normal(0, chaos, (k, sel.sum()))
    return out


def _loop_fresh(truth, seed):
    """A lab test on a fresh specimen whose deviation the K = 3 specimens' covariance cannot
    represent (rank 2 of 6), the same specimen under every test (as the DEM scenarios'
    fresh truths): the likelihood is overconfident there."""
    rng = np.random.default_rng(seed)
    n, point_test = _points(rng)
    measured = _rich_specimens(rng, n, point_test, truth, 0.6, 1)[0] + rng.normal(0, MEAS_SD, len(n))
    plain_curves = _rich_specimens(rng, n, point_test, None, 0.0, 3)
    thetas = initial_design([0.0], [1.0], SETS, seed=seed + 1)
    runs = {name: [_rich_specimens(rng, n, point_test, name, th[0], 3) for th in thetas] for name in EFFECTS}
    noise = residual_covariances(plain_curves, point_test, MEAS_SD ** 2)
    return (*_judged(thetas, runs, plain_curves, measured, point_test, noise, residual_dof(3)), measured, point_test)


def test_a_fresh_specimen_outside_the_ensembles_span_chooses_nothing():
    """The negative control where the measured specimen is not one of ours (issue 34). On
    seeds 1-6 the likelihood alone would choose an effect on 3 (seeds 2, 3, 5: 6-7 of 7 tests
    better, 34-157 nats, held-out RMSE cut by 5-61 %; measured 2026-11-28 under the t with
    K - 1 degrees of freedom; under the normal it chose on 5, hundreds of nats); the held-out
    cut never stands beyond the scatter, so nothing is chosen. Planted at 0.6 (seed 7) each
    effect still is."""
    likelihood_alone = 0
    for seed in range(1, 7):
        chosen, evidence, *_ = _loop_fresh(None, seed)
        assert chosen is None, (seed, evidence)
        likelihood_alone += any(e["gain"] > 0 and e["p"] < ALPHA / len(evidence) for e in evidence.values())
    assert likelihood_alone >= 3                     # the condition is what holds the control
    for truth in EFFECTS:
        chosen, evidence, held, plain, fits, measured, point_test = _loop_fresh(truth, 7)
        assert chosen == truth, evidence
        assert held[truth].rmse(measured, point_test) < 0.5 * plain.rmse(measured, point_test)


@pytest.mark.parametrize("seed", [3, 11])
def test_no_effect_planted_none_chosen(seed):
    chosen, evidence, *_ = _loop(None, seed)
    assert chosen is None, evidence


@pytest.mark.parametrize("truth", list(EFFECTS))
def test_on_the_models_own_specimens_the_planted_effect_is_named(truth):
    """Specimen offsets (sd 0.02) a hundred times the chaos: judged by the case-to-case
    scatter (specimen_share 1) bedding and rate are not chosen (2/7 and 5/7 tests better,
    measured); by the chaos the probe measures each planted effect is, its parameter
    within +-0.01 of the truth."""
    chosen, evidence, held, plain, fits, measured, point_test = _loop_own_specimens(truth, seed=5)
    assert chosen == truth, evidence
    assert held[truth].rmse(measured, point_test) < 0.5 * plain.rmse(measured, point_test)
    mean, interval, _ = fits[truth]
    assert interval[0, 0] <= 0.6 <= interval[0, 1] and interval[0, 1] - interval[0, 0] < 0.02


@pytest.mark.parametrize("seed", [3, 11])
def test_on_the_models_own_specimens_none_planted_none_chosen(seed):
    chosen, evidence, *_ = _loop_own_specimens(None, seed)
    assert chosen is None, evidence


def test_an_effect_that_changes_nothing_is_not_chosen():
    """Its runs are the plain model's: every held-out gain is round-off, none may count."""
    rng = np.random.default_rng(2)
    n, point_test = _points(rng)
    plain_curves = _specimens(rng, n, point_test, None, 0.0, K)
    measured = _specimens(rng, n, point_test, None, 0.0, 1)[0]
    thetas = initial_design([0.0], [1.0], SETS, seed=3)
    runs = [plain_curves + 1e-15 * th[0] for th in thetas]
    covs, _ = residual_covariances(plain_curves, point_test, MEAS_SD ** 2)
    plain = held_out_plain(plain_curves, measured, point_test, covs, residual_dof(K))
    held = held_out_candidate(thetas, runs, measured, point_test, [0.0], [1.0], covs, dof=residual_dof(K))
    chosen, evidence = choose({"nothing": (held, plain)}, measured, {"nothing": scatter_mse(covs)})
    assert chosen is None and evidence["nothing"]["wins"] == 0 and evidence["nothing"]["p"] == 1.0


def test_specimen_share_scales_only_the_specimen_part():
    """(share + 1/K) x the plain ensemble's case covariance + measurement: shares 1 and 0.5
    differ by half that covariance, the measurement variance stays on the diagonal."""
    rng = np.random.default_rng(5)
    n, point_test = _points(rng)
    plain = _specimens(rng, n, point_test, None, 0.0, K)
    one, one_plain = residual_covariances(plain, point_test, MEAS_SD ** 2)
    half, _ = residual_covariances(plain, point_test, MEAS_SD ** 2, specimen_share=0.5)
    for t in one:
        case = 2 * (one[t] - half[t])
        assert np.allclose(one[t], (1 + 1 / K) * case + MEAS_SD ** 2 * np.eye(len(case)), rtol=1e-12, atol=1e-18)
        assert np.all(np.diag(case) > 1e-7)       # offsets (sd 0.002), not only the chaos (4e-8)
        assert np.array_equal(one_plain[t], one[t])      # the K specimens' offset: in every set


def test_the_chaos_probe_measures_the_chaos_not_the_specimens():
    """Runs and probe of the same specimens (offsets sd 0.002, chaos sd 2e-4 per point):
    the diagonal of the chaos covariance is the chaos variance (within sampling error,
    K = 400: +-15 % would catch a factor sqrt(2) or 2), the offsets do not enter; with
    specimen_share 0 the residual covariance is chaos / K + measurement, about the plain
    mean one chaos / K more (its own draw). One probe: half the covariance of the difference
    (shrunk); three probes: the chaos variance again, within a narrower sampling error."""
    rng = np.random.default_rng(9)
    n, point_test = _points(rng)
    k, chaos = 400, 2e-4
    offsets = rng.normal(0, 0.002, (k, TESTS))
    runs, probe = (_specimens(rng, n, point_test, None, 0.0, k, offsets, chaos) for _ in range(2))
    covs, plain_covs = residual_covariances(runs, point_test, MEAS_SD ** 2, specimen_share=0.0, probe=probe)
    for t in range(TESTS):
        cov = chaos_covariance(runs, probe, point_test, t)
        assert np.allclose(np.diag(cov), chaos ** 2, rtol=0.15)
        assert np.allclose(covs[t], cov / k + MEAS_SD ** 2 * np.eye(len(cov)), rtol=1e-12, atol=1e-20)
        assert np.allclose(plain_covs[t], covs[t] + cov / k, rtol=1e-12, atol=1e-20)
    probes = np.array([_specimens(rng, n, point_test, None, 0.0, k, offsets, chaos) for _ in range(3)])
    for t in range(TESTS):
        d = (runs - probe)[:, point_test == t]
        half = d.T @ d / (2 * k)
        assert np.allclose(chaos_covariance(runs, probe, point_test, t),
                           (1 - SHRINK) * half + SHRINK * np.diag(np.diag(half)), rtol=1e-10, atol=0)
        assert np.allclose(np.diag(chaos_covariance(runs, probes, point_test, t)), chaos ** 2, rtol=0.1)
    with pytest.raises(ValueError, match="probe"):
        residual_covariances(runs, point_test, MEAS_SD ** 2, specimen_share=0.0)


def test_the_t_rests_on_the_degrees_of_freedom_of_its_covariance():
    """K - 1 for the case-to-case covariance of K specimens (a lab specimen, any share), K x M
    for the chaos of M probes of K specimens (the model's own specimens)."""
    assert residual_dof(3) == 2 and residual_dof(6, specimen_share=0.5) == 5
    assert residual_dof(3, specimen_share=0.0) == 3 and residual_dof(4, specimen_share=0.0, probes=3) == 12


def test_a_candidate_must_explain_more_than_it_leaves():
    """Measured curves straying beyond the scatter (within STRAY_LIMIT): a candidate better
    on every held-out test, its cut 7 x the scatter, is not chosen while it leaves more
    squared error than it cuts; the same gains with less left are chosen (the threshold is
    the larger of the two, not their sum: a cut of 1.2 x what is left passes)."""
    y = np.zeros(8)
    plain = HeldOut(np.zeros(8), np.full(8, 1.0), np.zeros((8, 0)))
    scatter = 0.065

    def judged(left_rms):
        held = HeldOut(np.full(8, 3.0), np.full(8, left_rms), np.zeros((8, 1)))
        return choose({"soft": (held, plain)}, y, {"soft": scatter})

    chosen, ev = judged(np.sqrt(0.55))            # cut 0.45 < left 0.55
    assert chosen is None and ev["soft"]["mse_cut"] > 6 * scatter and ev["soft"]["p"] < ALPHA
    assert np.isclose(ev["soft"]["left_mse"], 0.55) and np.isclose(ev["soft"]["mse_cut"], 0.45)
    chosen, ev = judged(np.sqrt(1 / 2.2))         # cut 1.2 / 2.2 > left 1 / 2.2
    assert chosen == "soft", ev
    assert stray(ev["soft"]) < STRAY_LIMIT


def test_a_pick_that_leaves_the_curves_beyond_the_stray_limit_is_named_not_adopted():
    """The same gains and a cut 9 x what is left: chosen where what is left is 2.8 x the
    scatter's root, not where it is 3.2 x (the limit is on the rms, not the squared error:
    sqrt(8) and sqrt(10) fall either side of 3, where 8 and 10 would not); the rule's
    other conditions still name it (pick, alike=False)."""
    y = np.zeros(8)
    plain = HeldOut(np.zeros(8), np.full(8, 1.0), np.zeros((8, 0)))
    held = HeldOut(np.full(8, 3.0), np.full(8, np.sqrt(0.1)), np.zeros((8, 1)))
    chosen, ev = choose({"soft": (held, plain)}, y, {"soft": 0.1 / 8})
    assert chosen == "soft" and np.isclose(stray(ev["soft"]), np.sqrt(8))
    chosen, ev = choose({"soft": (held, plain)}, y, {"soft": 0.1 / 10})
    assert chosen is None and np.isclose(stray(ev["soft"]), np.sqrt(10)) and STRAY_LIMIT == 3
    assert pick(ev, 1, alike=False) == "soft" and pick(ev, 1) is None
