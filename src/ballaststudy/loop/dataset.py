"""loop.nc: every curve of a loop run and every number its report quotes, self-describing
(units and long_name on each variable; the per-test, covariate, candidate and frequency-step
tables as JSON attributes)."""
import json

import numpy as np
import xarray as xr

from ..metrics.output import VARIABLES
from ..scenario.mapping import mapping_kinds
from .select import likelihood_words

CF = "CF-1.8"


def loop_dataset(run, stats):
    """The xarray Dataset of loop.nc from an outcome.LoopRun and its statistics.LoopStatistics."""
    units, long_name, _ = VARIABLES[run.settings["quantity"]]
    sel = run.selection
    data = {**_points(run.targets, units, long_name), **_plain(run.plain, units, long_name),
            **_candidates(sel.candidates, stats.candidates, units, long_name)}
    if run.plain.probe is not None:
        data["plain_probe"] = (("test", "case", "cycle"), run.plain.probe["curves"], {
            "units": units, "long_name": "plain model run again from velocities perturbed by round-off size "
                                         "(the chaos probe): simulated " + long_name})
    if sel.after is not None:
        data["after"] = (("test", "case", "cycle"), sel.after["curves"],
                         {"units": units, "long_name": "chosen effect at its fitted value: simulated " + long_name})
    return xr.Dataset(data, coords={
        "effect": ("effect", list(sel.candidates), {"long_name": "candidate effect (scenario/modifiers)"}),
        "test": ("test", [r["test"] for r in stats.before], {"long_name": "measured test"}),
        "cycle": ("cycle", run.cycles, {"units": "1", "long_name": "load cycle number N"}),
        "case": ("case", np.arange(run.cases), {"units": "1", "long_name": "specimen"})},
        attrs={"Conventions": CF, "title": "closing the loop with measured data",
               "tests_json": json.dumps(stats.before), "covariate_tests_json": json.dumps(stats.covariates),
               "candidates_json": json.dumps(stats.candidates), "chosen": sel.chosen or "none",
               "verdict_class": stats.verdict[0], "verdict": stats.verdict[1],
               "specimen_stray_json": json.dumps(stats.stray or {}), "specimen_stray_units": units,
               "discrepancy_json": json.dumps(stats.discrepancy), "discrepancy_units": units,
               "detectable_json": json.dumps(stats.detectable or {}), "detectable_units": units,
               "frequency_step_json": json.dumps(stats.step), "frequency_step_units": units,
               "material_parameters_json": json.dumps(run.base),
               "untestable_effects": ", ".join(sel.untestable) or "none",
               "likelihood": likelihood_words(run.likelihood_dof), **_long_term_attrs(run.long_term_law),
               **_mapping_attrs(run.mapping or {})})


def _mapping_attrs(records):
    """The stress mapping the tests ran under: its kind(s) and each test's record as JSON."""
    return {"stress_mapping": mapping_kinds(records), "stress_mapping_json": json.dumps(records)}


def _long_term_attrs(law):
    """The long-term law the report extrapolated with and its error on measured curves."""
    if law is None:
        return {"long_term_law": "none"}
    return {"long_term_law": law.name, "long_term_fit_cycles": law.fit_cycles,
            "long_term_stated_error": law.stated_error, "long_term_stated_error_units": "1",
            "long_term_curves": law.curves}


def _points(targets, units, long_name):
    """The measured points of the DEM horizon, one after the other."""
    return {
        "measured": ("point", targets.y, {"units": units, "long_name": "measured " + long_name}),
        "measured_cycle": ("point", targets.point_cycle, {"units": "1", "long_name": "load cycle N of the point"}),
        "point_test": ("point", targets.point_test.astype(np.int32), {"units": "1", "long_name": "test of the point"}),
    }


def _plain(plain, units, long_name):
    return {
        "plain": (("test", "case", "cycle"), plain.runs["curves"], {"units": units, "long_name": "plain model: simulated " + long_name}),
        "plain_prediction": ("point", plain.prediction, {"units": units, "long_name": "plain model: ensemble mean at the point"}),
        "plain_lpd": ("test", plain.held.lpd,
                      {"units": "1", "long_name": "plain model: log predictive density of the test's points (the noise model every model is judged under)"}),
    }


def _candidates(candidates, rows, units, long_name):
    """Each candidate at its design sets (the run at its fitted value, if chosen, is `after`);
    none where no candidate was testable."""
    if not candidates:
        return {}
    return {
        "candidate": (("effect", "set", "test", "case", "cycle"),
                      np.array([[s["curves"] for s in c.evaluate.sets[: len(c.thetas)]] for c in candidates.values()]),
                      {"units": units, "long_name": "candidate effect at a design set: simulated " + long_name}),
        "candidate_value": (("effect", "set", "parameter_index"), _padded([c.thetas for c in candidates.values()], np.nan),
                            {"units": "1", "long_name": "the effect's parameter values at the set (effect_parameter; NaN: it has fewer)"}),
        "effect_parameter": (("effect", "parameter_index"), _padded([r["parameters"] for r in rows], ""),
                             {"long_name": "the effect's parameters (empty: it has fewer)"}),
        "held_out_lpd": (("effect", "test"), np.array([c.held.lpd for c in candidates.values()]),
                         {"units": "1", "long_name": "held-out log predictive density (the test left out of the fit)"}),
        "held_out_prediction": (("effect", "point"), np.array([c.held.predicted for c in candidates.values()]),
                                {"units": units, "long_name": "held-out prediction of the point (its test left out)"}),
    }


def _padded(rows, fill):
    """Ragged last axis -> one array, short rows filled (effects have one or two parameters)."""
    rows = [np.asarray(r) for r in rows]
    width = max(r.shape[-1] for r in rows)
    out = np.full((len(rows), *rows[0].shape[:-1], width), fill, dtype=object if fill == "" else float)
    for i, r in enumerate(rows):
        out[i, ..., : r.shape[-1]] = r
    return out.astype(str) if fill == "" else out
