"""The loop's outputs from typed bundles (outcome.LoopRun, statistics.LoopStatistics), no
DEM run and no command line: the per-point order, the long-term horizon when a law cannot
be fitted, the pooled RMSE, the verdict rule, and loop.nc, chosen.yaml, report.md and
curves.png of a hand-made run with one effect chosen. The end-to-end loop is test_cli.py's."""
import dataclasses
import json
import warnings
from types import SimpleNamespace

import matplotlib
import numpy as np
import pytest

from ballaststudy.calibration.bayes import rmse
from ballaststudy.loop.cli import Candidate
from ballaststudy.loop.dataset import loop_dataset
from ballaststudy.loop.markdown import _verdict_of, report_markdown
from ballaststudy.loop.outcome import LoopRun, PlainModel, Selection, Targets
from ballaststudy.loop.plots import _panel, plot_curves
from ballaststudy.loop.report import chosen_doc
from ballaststudy.loop.discrepancy import make_discrepancy
from ballaststudy.loop.select import ALPHA, HeldOut, NoiseModel, Sampled, pick, scatter_mse
from ballaststudy.loop.trust import detectable, discrepancy_rows, specimen_stray, verdict
from ballaststudy.loop.accumulation import LawFit
from ballaststudy.loop.horizon import LongTermLaw
from ballaststudy.loop.statistics import LongTerm, LoopStatistics, candidate_rows, long_term, step_models
from ballaststudy.loop.step import shared_runs, step_rows

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402 (after the backend)

SETTINGS = dict(quantity="axial_strain", cycles=3, cases=2, effects=["end_restraint", "fouling"], design_sets=2,
                refine_rounds=0, refine_sets=2,
                specimen_share=1.0, measurement_sd=1e-4, discrepancy_terms=["offset"],
                discrepancy_prior_sd_share=1.0)
TARGETS = Targets(["conditions/a.yaml", "conditions/b.yaml"], ["a.nc", "b.nc"],
              [(np.array([1.0, 2.0, 3.0]), np.array([0.001, 0.002, 0.0025])), (np.array([1.0, 3.0]), np.array([0.001, 0.003]))])


def test_points_one_after_the_other():
    assert TARGETS.names == ["a", "b"]
    np.testing.assert_array_equal(TARGETS.point_test, [0, 0, 0, 1, 1])
    np.testing.assert_array_equal(TARGETS.point_cycle, [1, 2, 3, 1, 3])
    np.testing.assert_array_equal(TARGETS.y, [0.001, 0.002, 0.0025, 0.001, 0.003])


LAW = LongTermLaw("log", 1e3, 0.004, 12)


def test_long_term_without_a_fit_or_a_point_beyond():
    """One case cannot be fitted (no scatter to weight by): no fit, NaN extrapolations, and a
    test with no point beyond the DEM horizon has a NaN RMSE, without a warning; without a
    law nothing is extrapolated."""
    curves = np.array([[[0.001, 0.002, 0.0025]], [[0.001, 0.002, 0.003]]])       # (T, K = 1, cycles)
    beyond = [(np.array([30.0, 500.0]), np.array([0.004, 0.005])), (np.zeros(0), np.zeros(0))]
    out = long_term(beyond, np.arange(1.0, 4.0), curves, LAW)
    assert out[0].fit is None and np.isnan(out[0].predicted).all() and out[0].predicted.shape == (2,)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert np.isnan(out[1].rmse()) and np.isnan(out[0].rmse())
    assert all(lt.fit is None for lt in long_term(beyond, np.arange(1.0, 4.0), np.repeat(curves, 2, axis=1), None))


def test_long_term_extrapolates_by_the_given_law():
    """Two cases of a log curve: the law given is fitted and carried to the points beyond."""
    cycles = np.arange(1.0, 6.0)
    curves = (0.001 + 0.002 * np.log(cycles) + np.array([[-1e-5], [1e-5]]))[None]   # (T = 1, K = 2, cycles)
    beyond = [(np.array([100.0, 1e4]), 0.001 + 0.002 * np.log(np.array([100.0, 1e4])))]
    (lt,) = long_term(beyond, cycles, curves, LAW)
    assert lt.fit.name == "log" and lt.rmse() < 1e-6


def test_the_verdict_follows_the_rule():
    row = dict(chosen=False, p=ALPHA / 2 - 1e-3, gain=3.0, mse_cut=2e-8, scatter_mse=1e-8, left_mse=1.5e-8)
    assert _verdict_of(row, 2) == "passes, smaller gain"
    assert _verdict_of(row | dict(mse_cut=0.5e-8), 2) == "rejected: held-out cut within the scatter"
    assert _verdict_of(row | dict(left_mse=2.5e-8), 2) == "rejected: leaves more than it cuts"
    assert _verdict_of(row | dict(gain=-1.0), 2) == "rejected: no gain"
    assert _verdict_of(row | dict(p=ALPHA / 2), 2) == "rejected: gain not consistent across tests"
    assert _verdict_of(row | dict(chosen=True), 2) == "chosen"


def _chosen_run():
    """A run of K = 2 cases, 3 cycles, two tests, the end_restraint effect chosen."""
    rng = np.random.default_rng(0)
    runs = lambda name, shared=False: [[f"{name}{'' if shared else j}/case{k}.nc" for k in range(2)] for j in range(2)]
    plain = dict(curves=0.001 + 0.001 * rng.random((2, 2, 3)), cases=runs("plain", shared=True),
                 first_loadings=["plain"] * 2, failed=[[False, False]] * 2)
    after = dict(curves=0.001 + 0.001 * rng.random((2, 2, 3)), cases=runs("after"), first_loadings=["a0", "a1"],
                 failed=[[False, True], [False, False]])
    design = [dict(curves=rng.random((2, 2, 3)), cases=runs(f"design{i}"), first_loadings=[f"d{i}"] * 2,
                   failed=[[False, False]] * 2)
              for i in range(2)]          # (their tests differ only in what cycle 0 does not read)
    held = HeldOut(np.array([1.0, 2.0]), TARGETS.y + 1e-4, np.zeros((2, 1)))
    samples = np.linspace(0.0, 1.2, 16)[:, None]
    curves = TARGETS.y + 1e-4 * (samples - 0.3)                     # the surrogate: linear in the parameter
    sampled = Sampled(samples, curves, np.zeros_like(curves), np.full(16, 1 / 16))
    candidate = Candidate(np.array([[0.0], [1.2]]), [], held, (np.array([0.3]), np.array([[0.2, 0.4]]), 100.0),
                          sampled, SimpleNamespace(sets=design + [after]))
    evidence = dict(gain=5.0, se=1.0, z=5.0, wins=2, tests=2, p=0.01, mse_cut=4e-8, scatter_mse=1e-8,
                    left_mse=0.5e-8)
    selection = Selection({"end_restraint": candidate}, {"end_restraint": evidence}, "end_restraint", after, ["fouling"])
    plain_model = PlainModel(plain, TARGETS.y + 2e-4, HeldOut(np.array([0.5, 1.5]), TARGETS.y + 2e-4, np.zeros((2, 0))))
    covs = {t: 1e-8 * np.eye(int(np.sum(TARGETS.point_test == t))) for t in range(2)}
    disc = make_discrepancy(TARGETS.y, TARGETS.point_cycle, TARGETS.point_test, ["planted", "planted"],
                            SETTINGS["discrepancy_terms"])
    noise = NoiseModel(covs, covs, disc, 1.0, scatter_mse(covs, TARGETS.point_test, disc))
    run = LoopRun(SETTINGS, TARGETS, plain_model, selection, {}, minutes=0.5, likelihood_dof=1.0, noise=noise)
    rows = [dict(test=name, source="planted", points=3, rmse=2e-4 * (j + 1), bias=1e-4, bias_p=0.5, slope_ln_n=0.0,
                 slope_p=np.nan) for j, name in enumerate(TARGETS.names)]
    no_fit = LongTerm(np.zeros(0), np.zeros(0), np.zeros(0), None)
    step = step_rows(TARGETS.names, WHOLE, step_models(run), 3, 1e-4)
    detect = detectable(run)
    stats = LoopStatistics(rows, [r | dict(rmse=1e-4) for r in rows], [], candidate_rows(selection, TARGETS),
                           [no_fit] * 2, [no_fit] * 2, rmse(TARGETS.y, plain_model.prediction), step,
                           shared_runs(plain["cases"]), discrepancy_rows(run), detect,
                           verdict("end_restraint", detect, ["end_restraint"], specimen_stray(run)), specimen_stray(run))
    return run, stats


# the tests' whole measured curves: a reaches N = 2000, b ends within the DEM horizon
WHOLE = [(np.array([1.0, 2.0, 3.0, 100.0, 2000.0]), np.array([0.001, 0.002, 0.0025, 0.01, 0.02])),
         (np.array([1.0, 3.0]), np.array([0.001, 0.003]))]


def test_a_chosen_effect_in_every_output(tmp_path):
    run, stats = _chosen_run()
    assert run.dem_cases == 2 * 2 * (1 + 3)                     # plain + 2 design sets + the fitted run
    assert run.dem_runs == 2 * (1 + 2 * 3)              # the plain model's tests share their runs
    assert run.dem_first_loadings == 2 * (1 + 2 + 1 + 1)    # the design sets' tests their cycle 0
    assert stats.after_rmse == pytest.approx(1e-4) and stats.chosen_row["effect"] == "end_restraint"
    assert stats.candidates[0]["held_out_rmse"] == pytest.approx(1e-4)
    assert chosen_doc(stats, {}) == {"effect": "end_restraint", "verdict": "chosen",
                                     "parameters": {"platen_friction": 0.3},
                                     "interval90": {"platen_friction": [0.2, 0.4]}, "material_parameters": "table_4_2",
                                     "stress_mapping": "none"}
    ds = loop_dataset(run, stats)
    assert ds["candidate"].shape == (1, 2, 2, 2, 3) and "after" in ds and "plain_probe" not in ds
    assert list(ds["effect_parameter"].values[0]) == ["platen_friction"] and ds.attrs["chosen"] == "end_restraint"
    assert ds.attrs["untestable_effects"] == "fouling" and ds["cycle"].values.tolist() == [1.0, 2.0, 3.0]
    assert ds.attrs["stress_mapping"] == "none"
    assert ds.attrs["likelihood"] == "multivariate t with dof = 1"      # K - 1, K = 2 specimens
    text = report_markdown(run, stats)
    assert text.splitlines()[2] == "**Verdict: Effect chosen: end_restraint.**"
    assert "| planted | plain |" in text and "| planted | end_restraint |" in text
    assert ds.attrs["verdict_class"] == "chosen" and json.loads(ds.attrs["discrepancy_json"])[0]["source"] == "planted"
    assert "Stress mapping: **none**" in text
    stray = json.loads(ds.attrs["specimen_stray_json"])
    assert stray["model"] == "end_restraint" and stray["ratio"] == pytest.approx(stray["rms"] / stray["scatter"])
    assert f"the end_restraint model's held-out RMSE {100 * stray['rms']:.3g} %" in text
    assert "likelihood: multivariate t with dof = 1 (K - 1:" in text
    assert "16 DEM cases, 14 runs from 10 first loadings (" in text and "; 0.5 min in this run" in text and "**Effect chosen: end_restraint**" in text
    assert f"p < {ALPHA:g} / 1 (candidates)" in text and "| end_restraint | platen_friction 0.3 [0.2, 0.4] (0.19), excludes the no-effect 0.7 |" in text
    assert "| 0.01 | 2 | - | chosen |" in text     # held-out RMSE, cut / bar sqrt(4), detectable (2 tests: never), verdict
    assert "-> 0.01 % on the fitted tests" in text and "not testable: no target declares VCI" in text
    assert "No accumulation law given" in text and ds.attrs["long_term_law"] == "none"
    assert "N = 1 -> 3 (100 -> 2000 cut at the 3 cycles simulated" in text
    assert "The DEM horizon ends before N = 2000" in text and "runs are one for a, b (" in text
    assert "| a | - | +1 | +0.15 |" in text and "| b | - | - | +0.2 |" in text     # percent
    assert "| 0/2 | yes |" in text and "| 1/2 | - |" in text     # end_restraint's a: one case left, no interval
    # the design sets whose tests ran apart (here every one), by their values; the plain model's ran as one
    assert " end_restraint platen_friction 0 1 -> 3 [90 %] |" in text and " end_restraint platen_friction 1.2 1 -> 3" in text
    step = json.loads(ds.attrs["frequency_step_json"])
    assert step[0]["measured_step"] == pytest.approx(0.01) and step[0]["models"]["end_restraint"]["kept"] == 1
    plot_curves(tmp_path / "curves.png", run, stats)
    assert (tmp_path / "curves.png").stat().st_size > 1000


def test_the_long_term_law_in_every_output(tmp_path):
    """A law given: report.md names it with its stated error and says the run is shorter than
    its N_fit; loop.nc records it; curves.png's scale is set by what was measured and
    simulated, never by an extrapolation that runs away (the issue's 400,000 % figure)."""
    run, stats = _chosen_run()
    run = dataclasses.replace(run, long_term_law=LAW)
    beyond = [(np.array([100.0, 5e5]), np.array([0.004, 0.006]))] * 2
    stats = dataclasses.replace(stats, long_term=long_term(beyond, run.cycles, run.plain.runs["curves"], LAW),
                                long_term_after=long_term(beyond, run.cycles, run.selection.after["curves"], LAW))
    text = report_markdown(run, stats)
    assert "fitted by the **log** law" in text and "within +-0.4 % (0.9 quantile)" in text
    assert "This run fits 3 cycles, fewer than 1000" in text
    ds = loop_dataset(run, stats)
    assert ds.attrs["long_term_law"] == "log" and ds.attrs["long_term_stated_error"] == 0.004
    runaway_fit = LawFit("log", np.array([0.0, 30.0]), ("a", "b"), np.zeros((2, 2)), 0.0, 1, 1.0, 3.0)  # 30 per e-fold
    runaway = dataclasses.replace(stats, long_term=[LongTerm(*beyond[0], np.full(2, 40.0), runaway_fit)] * 2)
    plot_curves(tmp_path / "curves.png", run, runaway)
    fig, ax = plt.subplots()
    _panel(ax, 0, run, runaway)
    bottom, top = ax.get_ylim()
    plt.close(fig)
    assert -0.1 < bottom < 0.1 and 0.6 < top < 0.9            # percent: the data span 0.1-0.6 %


def _unchosen(run, stats, **evidence):
    """The chosen run with end_restraint's evidence changed so that the rule passes nothing."""
    ev = {"end_restraint": run.selection.evidence["end_restraint"] | evidence}
    run = dataclasses.replace(run, selection=Selection(run.selection.candidates, ev))
    return run, dataclasses.replace(stats, after=None, candidates=candidate_rows(run.selection, TARGETS),
                                    long_term_after=None, step=[r | dict(models={"plain": r["models"]["plain"]})
                                                                for r in stats.step])


def test_no_effect_chosen():
    run, stats = _unchosen(*_chosen_run(), p=0.25)                  # 2 tests: the least p there is
    stats = dataclasses.replace(stats, verdict=verdict(None, stats.detectable, ["end_restraint"]))
    assert stats.verdict[0] == "cannot tell"         # two tests: the signed-rank test can never pass
    assert "**Verdict: These data cannot tell" in report_markdown(run, stats)
    assert chosen_doc(stats, {"mu": 0.5}) == {"effect": "none", "verdict": "cannot tell", "parameters": {},
                                              "interval90": {},
                                              "material_parameters": {"mu": 0.5}, "stress_mapping": "none"}
    assert "after" not in loop_dataset(run, stats) and "**No effect chosen**" in report_markdown(run, stats)
    assert "end_restraint 1 -> 3" not in report_markdown(run, stats)
    text = report_markdown(run, stats).split("## DEM horizon")[1].split("\n\n")[2]   # its table
    rows = text.splitlines()[2:]
    assert len(rows) == 2 and all(line.split(" | ")[6] == "-" for line in rows), rows      # not nan


def test_a_pick_beyond_the_stray_limit_is_named_not_adopted():
    """end_restraint passes every condition but the last: what it leaves is 4.5 x the
    scatter's root. The report names it in the candidates' table and its first lines, the
    verdict is 'cannot tell', chosen.yaml and loop.nc adopt nothing."""
    run, stats = _chosen_run()
    run, stats = _unchosen(run, stats, mse_cut=4e-7, left_mse=2e-7)       # scatter_mse 1e-8
    far = dict(model="end_restraint", ratio=np.sqrt(20.0), rms=np.sqrt(2e-7), scatter=1e-4)
    named = pick(run.selection.evidence, 1, alike=False)
    stats = dataclasses.replace(stats, stray=far, named=named,
                                verdict=verdict(None, stats.detectable, ["end_restraint"], far, named=named))
    text = report_markdown(run, stats)
    assert stats.verdict[0] == "cannot tell" and "end_restraint passes every other condition" in stats.verdict[1]
    assert "named, not adopted: even with it the curves stray 4.47 x the scatter" in text
    assert "**No effect adopted**: end_restraint passes every other condition of the rule" in text
    assert chosen_doc(stats, {})["effect"] == "none" and loop_dataset(run, stats).attrs["chosen"] == "none"


def test_curves_within_a_candidates_own_scatter_are_said_so():
    """Curves straying 20 x from the plain model's scatter but 1.5 x from end_restraint's own
    (trust.specimen_stray's within): the report's stray paragraph and the verdict give that
    reading beside 'specimens unlike ours'; within the limit, neither mentions it."""
    run, stats = _chosen_run()
    run, stats = _unchosen(run, stats, mse_cut=4e-7, left_mse=2e-7)
    far = dict(model="plain", ratio=20.0, rms=2e-4, scatter=1e-5, within={"end_restraint": 1.5})
    stats = dataclasses.replace(stats, stray=far, verdict=verdict(None, stats.detectable, ["end_restraint"], far))
    text = report_markdown(run, stats)
    assert "end_restraint 1.5 - within the limit" in text
    assert "within the scatter of end_restraint's own specimens (1.5 x)" in stats.verdict[1]
    near = far | dict(ratio=1.0)
    stats = dataclasses.replace(stats, stray=near, verdict=verdict(None, stats.detectable, ["end_restraint"], near))
    assert "within the limit" not in report_markdown(run, stats) and "own specimens" not in stats.verdict[1]


def test_no_candidate_testable(tmp_path):
    """Every effect untestable (no target declares its covariate), or none given: the plain
    model alone, judged and written; no candidate variables in loop.nc."""
    run, stats = _chosen_run()
    run = dataclasses.replace(run, selection=Selection({}, {}, untestable=["fouling"]))
    stats = dataclasses.replace(stats, after=None, candidates=[], long_term_after=None,
                                step=[r | dict(models={"plain": r["models"]["plain"]}) for r in stats.step])
    ds = loop_dataset(run, stats)
    assert "candidate" not in ds and ds.attrs["chosen"] == "none" and ds.sizes["effect"] == 0
    text = report_markdown(run, stats)
    assert "**No effect chosen**" in text and "| fouling | - |" in text
    plot_curves(tmp_path / "curves.png", run, stats)
    assert chosen_doc(stats, {})["effect"] == "none"
    compared_only = dataclasses.replace(run, settings=SETTINGS | dict(effects=[]),
                                        selection=Selection({}, {}))
    text = report_markdown(compared_only, stats)
    assert "None given (`loop.effects` is empty): the plain model is compared only." in text
    assert "No effect chosen" not in text and "## The frequency step" in text


def test_a_step_the_dem_reached_reproduced_everywhere():
    """A DEM horizon of 2000 cycles: the window is the step's own (one measured column), and
    a model that reproduces every test has its intervals' width set against the spread of
    the measured increments (a 'yes' everywhere from an interval that spans them all)."""
    run, stats = _chosen_run()
    run = dataclasses.replace(run, settings=SETTINGS | dict(cycles=2000))
    plain = dict(mean=0.02, interval90=[-0.05, 0.09], kept=3, gave_way=0, reproduced="yes")
    step = [dict(test=name, window=[100.0, 2000.0], measured_step=m, measured_window=m, models={"plain": plain})
            for name, m in zip(TARGETS.names, (0.01, 0.08))]
    text = report_markdown(run, dataclasses.replace(stats, step=step))
    assert "| test | f Hz | measured 100 -> 2000 | plain 100 -> 2000 [90 %] | gave way | reproduced |" in text
    assert "| a | - | +1 | +2 [-5, 9] | 0/3 | yes |" in text
    assert "plain: reproduced on all 2 tests, with intervals 14 % wide against measured increments from 1 to 8 %" in text
    assert "The DEM horizon ends before" not in text


def test_without_a_discrepancy_the_report_says_so():
    """loop.discrepancy_terms: [] (the likelihood before issue 75): no terms, one line."""
    run, stats = _chosen_run()
    noise = run.noise
    disc = make_discrepancy(TARGETS.y, TARGETS.point_cycle, TARGETS.point_test, ["planted", "planted"], ())
    run = dataclasses.replace(run, noise=dataclasses.replace(noise, disc=disc),
                              settings=SETTINGS | dict(discrepancy_terms=[]))
    rows = discrepancy_rows(run)
    assert rows[0]["terms"] == [] and rows[0]["plain"]["mean"] == []
    text = report_markdown(run, dataclasses.replace(stats, discrepancy=rows))
    assert "None estimated (`loop.discrepancy_terms: []`)" in text
