"""Everything the loop's outputs compute from a run (outcome.LoopRun); nothing here writes.

Two horizons, never mixed: the DEM horizon (measured points with N <= the simulated
cycles, compared with the ensembles) and the long-term horizon (points beyond, compared
with the law the measured curves chose (loop/horizon.py) fitted to each ensemble mean and
extrapolated - an extrapolation, said so, with the error that law made on measured curves).
The frequency step (step.py) stands between them: the measured increment from N = 100 to
2000 on the whole curve beside the ensembles' over the cycles they simulated."""
from dataclasses import dataclass

import numpy as np

from ..calibration.bayes import rmse
from ..inputs import open_netcdf
from ..measured.importer import load_conditions
from ..metrics.output import display_scale
from ..scenario.modifiers import MODIFIERS
from .accumulation import fit_ensemble, predict
from .discrepancy import source_name
from .horizon import measured_curve
from .residual import covariate_tests, residual, summary
from .select import pick
from .step import shared_runs, step_rows
from .trust import detectable, discrepancy_rows, interval_notes, specimen_stray, verdict

COVARIATES = ("frequency_Hz", "confining_pressure_kPa", "deviator_max_kPa", "VCI")
# the plain model's internal signals at its last simulated cycle (mean over the cases)
SIGNALS = ("breakage_rate", "mean_coordination", "void_ratio", "volumetric_strain")


@dataclass(frozen=True)
class LongTerm:
    """One ensemble's long-term horizon at one test, by the law the measured curves chose."""
    n: np.ndarray              # measured N beyond the simulated cycles
    measured: np.ndarray       # the measured values there
    predicted: np.ndarray      # the law's extrapolation to n (NaN where it did not fit)
    fit: object                # accumulation.LawFit, or None: no law, or no convergence

    def rmse(self):
        # no point beyond the DEM horizon or no fit: nothing to compare (and no mean of nothing)
        return rmse(self.measured, self.predicted) if self.fit is not None and self.n.size else float("nan")


@dataclass(frozen=True)
class LoopStatistics:
    """Every number the loop's outputs show, computed once (loop_statistics)."""
    before: list               # per test: conditions, residual summary (plain model), SIGNALS
    after: list                # the same residual summary of the chosen effect; None: none chosen
    covariates: list           # residual.covariate_tests of bias and slope on COVARIATES + SIGNALS
    candidates: list           # per candidate: its parameters, fit, held-out RMSE, evidence, chosen
    long_term: list            # LongTerm per test, plain model
    long_term_after: list      # LongTerm per test, chosen effect; None: none chosen
    plain_rmse: float          # the plain model over every point of the DEM horizon
    step: list                 # step.step_rows: the increment over the frequency step's window
    step_shared: list          # step.shared_runs of the plain model: tests whose runs are one
    discrepancy: list = ()     # trust.discrepancy_rows: per source, beside each effect's size
    detectable: dict = None    # trust.detectable: {effect: the smallest effect the rule would choose}
    verdict: tuple = ("", "")  # trust.verdict: (class, sentence)
    stray: dict = None         # trust.specimen_stray: the measured specimens against the model's
    named: str = None          # the rule's pick were the measured curves like ours (select.pick, alike=False)

    @property
    def chosen_row(self):
        return next((c for c in self.candidates if c["chosen"]), None)

    @property
    def after_rmse(self):
        """The chosen effect's per-test RMSEs pooled, each test alike: their root mean square."""
        return rmse([r["rmse"] for r in self.after], 0.0)


def loop_statistics(run):
    """LoopStatistics of an outcome.LoopRun."""
    lp, sel, plain_curves = run.settings, run.selection, run.plain.runs["curves"]
    before = per_test_rows(run.targets, plain_curves, lp["measurement_sd"])
    for row, signals in zip(before, model_signals(run.plain.runs["cases"])):
        row.update(signals)
    after = per_test_rows(run.targets, sel.after["curves"], lp["measurement_sd"]) if sel.after is not None else None
    beyond = [points_beyond(path, lp["quantity"], lp["cycles"]) for path in run.targets.measured]
    detect = detectable(run) if run.noise is not None else {}
    stray = specimen_stray(run) if run.noise is not None else None
    named = pick(sel.evidence, len(sel.candidates), alike=False)
    return LoopStatistics(
        before=before, after=after,
        covariates=[r for resp in ("bias", "slope_ln_n") for r in covariate_tests(before, resp, COVARIATES + SIGNALS)],
        candidates=candidate_rows(sel, run.targets, run.base),
        long_term=long_term(beyond, run.cycles, plain_curves, run.long_term_law),
        long_term_after=(long_term(beyond, run.cycles, sel.after["curves"], run.long_term_law)
                         if sel.after is not None else None),
        plain_rmse=rmse(run.targets.y, run.plain.prediction),
        step=step_rows(run.targets.names, [measured_curve(p, lp["quantity"]) for p in run.targets.measured],
                       step_models(run), lp["cycles"], lp["measurement_sd"]),
        step_shared=shared_runs(run.plain.runs["cases"]),
        discrepancy=discrepancy_rows(run) if run.noise is not None else [], detectable=detect,
        verdict=verdict(sel.chosen, detect, list(sel.candidates), stray, display_scale(lp["quantity"]), named),
        stray=stray, named=named)


def step_models(run):
    """The ensembles the frequency-step table shows: the plain model, the chosen effect at
    its fitted value, and every candidate's design set in which the tests' runs are not all
    one (where f acts: a real-time effect), named by effect and parameter values."""
    sel = run.selection
    models = {"plain": run.plain.runs, **({sel.chosen: sel.after} if sel.after is not None else {})}
    for name, c in sel.candidates.items():
        for theta, st in zip(c.thetas, c.evaluate.sets):
            if shared_runs(st["cases"]) != [list(range(len(st["cases"])))]:
                models[f"{name} " + ", ".join(f"{p.name} {v:.3g}" for p, v in
                                              zip(MODIFIERS[name].parameters, theta))] = st
    return models


def describe_test(name, conditions_path):
    """A test's name, source study and declared covariates (those it gives)."""
    c = load_conditions(conditions_path)
    row = dict(test=name, source=source_name(c),
               **{k: float(c[k]) for k in COVARIATES[:3] if c.get(k) is not None})
    vci = (c.get("covariates") or {}).get("VCI")
    if vci:
        row["VCI"] = float(vci["value"])
    return row


def per_test_rows(targets, curves, measurement_sd):
    """Per test: describe_test and the residual summary in the DEM horizon of an ensemble
    (T, K, cycles)."""
    return [describe_test(name, cond) | summary(residual(n, v, ensemble, measurement_sd))
            for name, cond, (n, v), ensemble in zip(targets.names, targets.conditions, targets.points, curves)]


def model_signals(case_files):
    """[{signal: mean over the cases at the last cycle}] per test, from a model's cached
    metrics.nc (case_files: [[path per case] per test]); a failed case's last row."""
    rows = []
    for per_test in case_files:
        values = {s: [] for s in SIGNALS}
        for path in per_test:
            ds = open_netcdf(path, "metrics")
            for s in SIGNALS:
                if s in ds and ds.sizes.get("cycle", 0):
                    values[s].append(float(ds[s].values[-1]))
        rows.append({s: float(np.mean(v)) if v else float("nan") for s, v in values.items()})
    return rows


def points_beyond(path, quantity, cycles):
    """(N, values) of a measured test beyond the simulated cycles: the long-term horizon."""
    ds = open_netcdf(path, "measured")
    n, v = ds["cycle"].values, ds[quantity].values
    beyond = np.isfinite(v) & (n > cycles)
    return n[beyond], v[beyond]


def long_term(beyond, cycles, curves, law):
    """LongTerm per test of an ensemble (T, K, cycles) by `law` (horizon.LongTermLaw, or None:
    no law measured, nothing extrapolated)."""
    out = []
    for (n, v), ensemble in zip(beyond, curves):
        try:
            fit = fit_ensemble(law.name, cycles, ensemble) if law else None
        except (RuntimeError, ValueError):         # no convergence (a flat, censored ensemble)
            fit = None
        out.append(LongTerm(n, v, predict(fit, n)[0] if fit else np.full(n.size, np.nan), fit))
    return out


def candidate_rows(selection, targets, material=None):
    """Per candidate effect: its parameters, fitted mean and 90 % interval, held-out RMSE,
    the rule's evidence and whether it was chosen (loop.nc's candidates_json)."""
    rows = []
    for name, c in selection.candidates.items():
        mean, interval, ess = c.fit
        rows.append(dict(effect=name, parameters=[p.name for p in MODIFIERS[name].parameters],
                         mean=mean.tolist(), interval90=interval.tolist(), ess=ess,
                         interval_notes=interval_notes(name, mean, interval, material),
                         held_out_rmse=c.held.rmse(targets.y, targets.point_test), chosen=name == selection.chosen,
                         **selection.evidence[name]))
    return rows
