"""What the data can tell (loop/trust.py) where the answer is known: an effect that varies
from test to test is detectable from a size of the order of the scatter, one of the
discrepancy's own shape (the same offset in every test) never is; the verdict's classes; an
interval at the edge of its range said so."""
from types import SimpleNamespace

import numpy as np
import pytest

from ballaststudy.loop.discrepancy import joint_loglik, make_discrepancy
from ballaststudy.loop.select import (STRAY_LIMIT, NoiseModel, Sampled, choose, held_out_joint, held_out_plain,
                                      residual_dof, scatter_mse)
from ballaststudy.loop.trust import detectable, interval_notes, specimen_stray, verdict

TESTS, SD = 7, 3e-4
FREQ = np.array([5.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0])


def _run(pattern):
    """A run of 7 tests, 12 points each, noise sd SD, a 'fouling' candidate whose curve moves
    by friction_loss / 0.9 x pattern(test, N) (exact surrogate) from the plain mean."""
    n = np.tile(np.geomspace(1, 200, 12), TESTS)
    point_test = np.repeat(np.arange(TESTS), 12)
    plain = 0.01 + 0.003 * np.log(n)
    samples = np.linspace(0.0, 0.9, 257)[:, None]
    mean = plain + samples / 0.9 * pattern(point_test, n)
    covs = {t: SD ** 2 * np.eye(12) for t in range(TESTS)}
    disc = make_discrepancy(plain, n, point_test, ["lab"] * TESTS)
    noise = NoiseModel(covs, covs, disc, residual_dof(3), scatter_mse(covs, point_test, disc))
    sampled = Sampled(samples, mean, np.zeros_like(mean), np.full(len(samples), 1 / len(samples)))
    y = plain + np.random.default_rng(0).normal(0.0, SD, len(n))     # measured: no effect, the noise
    return SimpleNamespace(noise=noise, targets=SimpleNamespace(point_test=point_test, y=y),
                           plain=SimpleNamespace(prediction=plain),
                           selection=SimpleNamespace(candidates={"fouling": SimpleNamespace(sampled=sampled)}))


def test_an_effect_that_varies_from_test_to_test_is_detectable_from_about_the_scatter():
    """rate-like: 0.004 x f / 60 x ln N / ln 200 at the top of the range. The rule needs a
    held-out cut beyond the scatter (rms > SD) and every test better by half a nat."""
    d = detectable(_run(lambda t, n: 0.004 * FREQ[t] / 60 * np.log(n) / np.log(200)))["fouling"]
    assert np.isfinite(d["smallest"]) and SD < d["smallest"] < 10 * SD, d
    assert d["passes"][-1] and not d["passes"][0]        # the largest effect passes, none at 0


def test_an_effect_whose_specimens_scatter_more_is_detectable_only_beyond_its_own_scatter():
    """The same rate-like effect, its own specimens scattering 2 x the plain model's (sd; its
    parameters fitted, its cut judged under that, select.candidate_covariances): the held-out
    cut must exceed 4 x the squared scatter, so the smallest detectable effect grows towards
    2 x (the gains, under the one noise model, are the same; measured 1.67 x on the grid of
    sizes)."""
    pattern = lambda t, n: 0.004 * FREQ[t] / 60 * np.log(n) / np.log(200)
    run = _run(pattern)
    alone = detectable(run)["fouling"]["smallest"]
    own = {t: 4 * c for t, c in run.noise.covs.items()}
    run.noise = NoiseModel(run.noise.covs, run.noise.plain_covs, run.noise.disc, run.noise.dof, run.noise.scatter,
                           {"fouling": own}, {"fouling": scatter_mse(own, run.targets.point_test, run.noise.disc)})
    wider = detectable(run)["fouling"]["smallest"]
    assert 1.6 * alone < wider < 2.6 * alone, (alone, wider)


def test_an_effect_of_the_discrepancys_shape_is_never_detectable():
    """The same offset in every test: the discrepancy absorbs it at any size."""
    d = detectable(_run(lambda t, n: 0.004 * np.ones_like(n)))["fouling"]
    assert np.isnan(d["smallest"]) and not any(d["passes"]), d


def test_the_verdicts_classes():
    seen, blind = dict(smallest=1e-3), dict(smallest=np.nan)
    assert verdict("rate", {}, ["rate"])[0] == "chosen"
    assert verdict(None, {"a": seen, "b": seen}, ["a", "b"])[0] == "no effect needed"
    assert verdict(None, {"a": blind}, ["a", "b"])[0] == "cannot tell"
    kind, words = verdict(None, {"a": seen, "b": blind}, ["a", "b"])
    assert kind == "partly" and "cannot tell for b" in words
    assert verdict(None, {}, [])[0] == "no candidates"
    far = dict(model="plain", ratio=2 * STRAY_LIMIT, rms=1.0, scatter=0.5 / STRAY_LIMIT)
    near = dict(model="plain", ratio=1.0, rms=1.0, scatter=1.0)
    assert verdict(None, {"a": seen}, ["a"], far)[0] == "cannot tell"
    assert verdict(None, {"a": seen}, ["a"], near)[0] == "no effect needed"
    kind, words = verdict(None, {"a": seen}, ["a"], far, named="a")
    assert kind == "cannot tell" and "a passes every other condition of the rule: named, not adopted" in words


def test_the_verdict_writes_its_amounts_in_the_reports_unit():
    """A strain of 0.039 is 3.9 % in the report's tables: the first line says the same."""
    seen = dict(smallest=0.039)
    far = dict(model="plain", ratio=2 * STRAY_LIMIT, rms=0.02, scatter=0.01 / STRAY_LIMIT)
    assert "rms effect of 3.9 %" in verdict(None, {"a": seen}, ["a"], display=(100.0, "%"))[1]
    assert "held-out rms 2 % against" in verdict(None, {"a": seen}, ["a"], far, (100.0, "%"))[1]
    assert "rms effect of 0.039" in verdict(None, {"a": seen}, ["a"])[1]


def _stray(offset_sd, seed, key="ratio"):
    """specimen_stray of 7 tests whose measured specimen is off by its own offset of sd
    ``offset_sd`` from the model's, with the noise model's noise (SD) on top."""
    run = _run(lambda t, n: np.zeros_like(n))
    rng = np.random.default_rng(seed)
    pt = run.targets.point_test
    y = run.plain.prediction + rng.normal(0.0, offset_sd, TESTS)[pt] + rng.normal(0.0, SD, len(pt))
    _measured(run, y)
    return specimen_stray(run)[key]


def _measured(run, y):
    """Give the run measured points y: the plain model's and the candidate's held-out judgement of them."""
    pt, noise, s = run.targets.point_test, run.noise, run.selection.candidates["fouling"].sampled
    run.targets.y, run.selection.chosen = y, None
    run.plain.held = held_out_plain(run.plain.prediction[None], y, pt, noise.plain_covs, noise.dof, noise.disc)
    joint = joint_loglik(y[None] - s.mean, s.sd, noise.covs, pt, noise.disc, noise.dof)
    run.selection.candidates["fouling"].held = held_out_joint(s.samples, s.mean, joint, pt, noise.disc)
    _judge(run)


def _judge(run):
    """The rule's evidence on the run's measured points, as loop.cli judges them."""
    cands = run.selection.candidates
    run.selection.evidence = choose({k: (c.held, run.plain.held) for k, c in cands.items()}, run.targets.y,
                                    {k: run.noise.scatter_of(k) for k in cands})[1]


def test_specimens_like_ours_do_not_stray_and_unlike_ones_do():
    """Measured curves drawn from the noise model itself: the ratio about 1 (20 seeds: all
    under 1.6, none beyond the limit); each test's specimen off by 10 x the scatter: beyond
    it in every seed."""
    alike = [_stray(0.0, s) for s in range(20)]
    assert max(alike) < 1.6 and 0.6 < np.median(alike) < 1.3, alike
    assert min(_stray(10 * SD, s) for s in range(20)) > STRAY_LIMIT
    assert _stray(10 * SD, 0, "within") == {}     # the candidate's scatter is the plain model's here


def test_the_stray_is_against_the_scatter_of_the_model_the_run_ends_with():
    """Specimens off by 10 x the scatter, and a candidate whose own specimens scatter 100 x the
    plain model's (sd): not chosen, the curves stray against the plain model's scatter
    whichever model predicts best (its specimens are the ones "no effect needed" speaks
    for); chosen, against its own, 100 x less."""
    run = _run(lambda t, n: np.zeros_like(n))
    rng = np.random.default_rng(0)
    pt = run.targets.point_test
    _measured(run, run.plain.prediction + rng.normal(0.0, 10 * SD, TESTS)[pt] + rng.normal(0.0, SD, len(pt)))
    own = {t: 1e4 * c for t, c in run.noise.covs.items()}
    run.noise = NoiseModel(run.noise.covs, run.noise.plain_covs, run.noise.disc, run.noise.dof, run.noise.scatter,
                           {"fouling": own}, {"fouling": scatter_mse(own, pt, run.noise.disc)})
    _judge(run)
    unchosen = specimen_stray(run)
    assert unchosen["model"] == "fouling" and unchosen["ratio"] > STRAY_LIMIT     # the best predictor
    # ... within fouling's own scatter, 100 x the plain model's, and the verdict says so
    assert unchosen["within"] == {"fouling": pytest.approx(unchosen["ratio"] / 100, rel=0.01)}
    assert "within the scatter of fouling's own specimens" in verdict(None, {}, ["fouling"], unchosen)[1]
    run.selection.chosen = "fouling"
    chosen = specimen_stray(run)
    assert chosen["model"] == "fouling" and chosen["scatter"] == pytest.approx(100 * unchosen["scatter"], rel=0.01)


@pytest.mark.parametrize("interval, edge", [([0.195, 0.1999], "high"), ([0.0, 0.03], ""), ([0.05, 0.1], "")])
def test_an_interval_at_the_edge_of_its_range_is_marked(interval, edge):
    """abrasion's wear_per_cycle is designed over [0, 0.2] (issue 75: 0.198 [0.195, 0.1999]);
    its low bound is no wear, an answer inside the range, not an edge; end restraint's low
    bound (frictionless platens) is an edge."""
    (note,) = interval_notes("abrasion", [np.mean(interval)], [interval])
    assert note["at_edge"] == edge
    assert note["width_share"] == pytest.approx((interval[1] - interval[0]) / 0.18)
    assert interval_notes("end_restraint", [0.01], [[0.0, 0.02]])[0]["at_edge"] == "low"


def test_the_no_effect_value_is_the_plain_models():
    """end restraint is off at the stones' own friction (Table 4.2's 0.7, or the calibrated
    mu); abrasion at no wear; rate has no such value (its real-time mode is a change)."""
    assert interval_notes("end_restraint", [0.58], [[0.56, 0.60]])[0]["excludes_no_effect"] is True
    assert interval_notes("end_restraint", [0.58], [[0.56, 0.60]], {"mu": 0.59})[0]["excludes_no_effect"] is False
    assert interval_notes("abrasion", [0.01], [[0.0, 0.02]])[0]["no_effect"] == 0.0
    assert interval_notes("rate", [0.45], [[0.44, 0.46]])[0]["excludes_no_effect"] is None
    # pressed on the no-effect bound: its 5 % tail cannot reach the bound, the value is held
    assert interval_notes("fouling", [1.7e-4], [[1.6e-4, 2.3e-4]])[0]["excludes_no_effect"] is False
    assert interval_notes("fouling", [0.05], [[0.04, 0.06]])[0]["excludes_no_effect"] is True


def test_a_wide_interval_excludes_nothing_and_presses_on_no_edge():
    """The prior's own 90 % interval of abrasion, [0.01, 0.19], never holds 0 (no wear) and
    ends near 0.2 by construction: it says nothing, and is read so."""
    (note,) = interval_notes("abrasion", [0.1], [[0.01, 0.19]])
    assert note["excludes_no_effect"] is False and note["at_edge"] == "" and note["width_share"] == pytest.approx(1.0)
    assert interval_notes("rate", [0.63], [[0.27, 0.699]])[0]["at_edge"] == ""


def test_the_model_that_predicts_best_is_judged():
    """Curves made with an effect of rms 14 x the noise: the plain model strays beyond the
    limit (its held-out rms, with what the shared discrepancy takes, 7.6 x the scatter), the
    candidate that makes the effect does not - chosen, or the best where none is chosen (a
    plain model missing a real effect is not 'specimens unlike ours')."""
    pattern = lambda t, n: 0.012 * FREQ[t] / 60 * np.log(n) / np.log(200)     # noqa: E731
    run = _run(pattern)
    pt = run.targets.point_test
    made = run.plain.prediction + pattern(pt, np.tile(np.geomspace(1, 200, 12), TESTS))
    _measured(run, made + np.random.default_rng(1).normal(0.0, SD, len(pt)))
    plain_ratio = float(np.sqrt(np.mean((run.targets.y - run.plain.held.predicted) ** 2))) / specimen_stray(run)["scatter"]
    assert plain_ratio > STRAY_LIMIT
    for chosen in (None, "fouling"):
        run.selection.chosen = chosen
        stray = specimen_stray(run)
        assert stray["model"] == "fouling" and stray["ratio"] < 1.6, stray
