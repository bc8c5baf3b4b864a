"""report.md: the loop's findings in words and tables, one section per question (how far
the plain model is off per test, what that relates to, which effect helps on held-out
tests, what the long-term horizon implies); numbers from statistics.LoopStatistics."""
import numpy as np

from ..calibration.bayes import rmse
from ..metrics.output import display_scale
from ..scenario.mapping import mapping_markdown
from ..scenario.modifiers import MODIFIERS
from .select import ALPHA, STRAY_LIMIT, bar_mse, likelihood_words, stray
from .horizon import STATED_QUANTILE
from .statistics import SIGNALS
from .step import LEVEL, STEP_CYCLES


def report_markdown(run, stats):
    """report.md's text from an outcome.LoopRun and its statistics.LoopStatistics."""
    scale, unit = display_scale(run.settings["quantity"])
    lines = (_opening(run, stats, unit) + _dem_horizon(stats, scale) + _covariates(stats)
             + _candidates(run, stats, scale, unit) + _verdict(run, stats, scale, unit)
             + _discrepancy(run, stats, scale, unit)
             + _step(run, stats, scale, unit) + _long_term(run, stats, scale, unit))
    return "\n".join(lines) + "\n"


def _fmt_p(p):
    return "-" if not np.isfinite(p) else f"{p:.2g}"


def _opening(run, stats, unit):
    lp = run.settings
    q = lp["quantity"].replace("_", " ")
    refined = (f" + {lp['refine_rounds']} x {lp['refine_sets']} refined around the held-out posteriors"
               if lp["refine_rounds"] else "")
    effects = (f"{len(stats.candidates)} candidate effects at {lp['design_sets']} parameter sets each{refined}"
               if stats.candidates else "no candidate effect run")
    head = [f"**Verdict: {stats.verdict[1]}**", ""] if stats.verdict[1] else []
    return ["# Closing the loop with measured data", "", *head,
            f"{len(stats.before)} tests, {lp['cases']} specimens per model and test, {lp['cycles']} simulated cycles "
            f"(the DEM horizon); {effects}; "
            f"{run.dem_cases} DEM cases, {run.dem_runs} runs from {run.dem_first_loadings} first loadings (a case "
            "that differs from another only in what does not act, a quasi-static test's f, is the other's run; "
            "one that differs only in what the first loading does not read, a real-time test's f, or in "
            "effects that act from its end, abrasion, goes on from the other's first loading; "
            f"{run.minutes:.1f} min in this run; cases found in the cache are not rerun). "
            f"Quantity: {q} [{unit}].", "", mapping_markdown(run.mapping or {})]


def _dem_horizon(stats, scale):
    lines = ["## DEM horizon: measured vs the plain model, per test", "",
             "Residual = measured - ensemble mean at the measured points (N <= the simulated cycles). "
             "Bias and slope (per unit ln N) are judged as one more specimen of the ensemble (p: two-sided "
             "prediction test; K - 1 degrees of freedom).", "",
             "| test | p kPa | f Hz | VCI % | points | RMSE before | RMSE after (chosen effect, fitted; - none) | bias (p) "
             "| slope ln N (p) |",
             "|---|---|---|---|---|---|---|---|---|"]
    for j, r in enumerate(stats.before):
        after = f"{stats.after[j]['rmse'] * scale:.3g}" if stats.after else "-"     # "-": no effect chosen
        lines.append(f"| {r['test']} | {r.get('confining_pressure_kPa', float('nan')):g} | {r.get('frequency_Hz', float('nan')):g} | "
                     f"{r.get('VCI', 0):g} | {r['points']} | {scale * r['rmse']:.3g} | {after} | "
                     f"{scale * r['bias']:.3g} ({_fmt_p(r['bias_p'])}) | {scale * r['slope_ln_n']:.3g} ({_fmt_p(r['slope_p'])}) |")
    return lines


def _covariates(stats):
    lines = ["", "## What the residual relates to (across tests)", "",
             "Least squares of each test's bias and slope on each declared covariate and on each of the "
             "plain model's internal signals at its last cycle (" + ", ".join(SIGNALS) + "; mean of the "
             "cases), one intercept per source study (a grouping factor), t-test p, Holm-adjusted over "
             "everything tried for that response.", "",
             "| response | covariate | tests | slope | p | p (Holm) | significant |", "|---|---|---|---|---|---|---|"]
    for r in stats.covariates:
        if r["tried"]:
            lines.append(f"| {r['response']} | {r['covariate']} | {r['tests']} | {r['slope']:.3g} | "
                         f"{_fmt_p(r['p'])} | {_fmt_p(r['p_holm'])} | {'yes' if r['significant'] else 'no'} |")
        else:
            lines.append(f"| {r['response']} | {r['covariate']} | {r['tests']} | - | - | - | not tried (no variation within a source, one test alone carries it, or too few tests) |")
    return lines


def _noise_words(run):
    lp, dof = run.settings, likelihood_words(run.likelihood_dof)
    if lp["specimen_share"] == 0:
        return ("the measured curves are taken as runs of the model's own specimens, so the scatter is "
                "chaos / K: the plain ensemble run again from velocities perturbed by round-off size "
                f"(the chaos probe), plus the measurement's; likelihood: {dof} (K x 1 probe).")
    return (f"the measured specimen scatters like {lp['specimen_share']:g} x one of the plain model's, "
            f"plus 1/K of that for the ensemble mean, plus the measurement's; likelihood: {dof} (K - 1: "
            "the case-to-case covariance rests on the K specimens every set runs). A candidate's parameter is "
            "fitted, and what it leaves is measured, under its own sets' case-to-case covariance in place of the "
            "plain model's (an effect changes how specimens scatter).")


def _verdict_of(c, candidates):
    """A candidate's verdict under select.choose's rule (the Bonferroni level over the candidates)."""
    if c["chosen"]:
        return "chosen"
    if c["p"] >= ALPHA / candidates:
        return "rejected: gain not consistent across tests"
    if c["gain"] <= 0:
        return "rejected: no gain"
    if c["mse_cut"] <= c["scatter_mse"]:
        return "rejected: held-out cut within the scatter"
    if c["mse_cut"] <= bar_mse(c):
        return "rejected: leaves more than it cuts"
    if stray(c) > STRAY_LIMIT:
        return f"named, not adopted: even with it the curves stray {stray(c):.3g} x the scatter"
    return "passes, smaller gain"


def _cut_words(c):
    """sqrt(cut) / sqrt(bar) (select.bar_mse): above 1 the cut stands beyond the scatter and
    beyond what the effect leaves; a negative cut (the effect predicts worse) keeps its sign."""
    bar = bar_mse(c)
    ratio = c["mse_cut"] / bar if bar > 0 else np.inf
    return f"{np.sign(ratio) * np.sqrt(abs(ratio)):.2g}"


def _candidates(run, stats, scale, unit):
    cands = stats.candidates
    if not run.settings["effects"]:
        return ["", "## Candidate effects, judged on held-out tests", "",
                "None given (`loop.effects` is empty): the plain model is compared only.", "",
                f"Plain model RMSE over all points: {scale * stats.plain_rmse:.3g} {unit}.", ""]
    lines = ["", "## Candidate effects, judged on held-out tests", "",
             "Each test left out once: the effect's parameter fitted on the others, the left-out test's "
             "points predicted. Gain = sum over tests of held-out log predictive density minus the plain "
             "model's, every model under one noise model: " + _noise_words(run)
             + f" Rule: one-sided Wilcoxon signed-rank test of the per-test gains, p < {ALPHA:g} / "
             f"{len(cands)} (candidates), and a held-out cut beyond the scatter: the plain model's held-out "
             "mean squared error minus the effect's exceeds the squared residual a correct model expects under "
             "the effect's own scatter and what the effect itself leaves (its own held-out mean squared error: "
             "where the "
             "measured curves stray beyond our specimens' scatter, the effect must explain more than it leaves; "
             "shown as the cut's root over the larger's), and what the effect leaves within "
             f"{STRAY_LIMIT:g} x the scatter's root (beyond, the measured curves are unlike our specimens, the "
             "likelihood the gains come from does not hold, and the rule's pick is named, not adopted); the largest "
             "gain among the passing is chosen.", "",
             "Interval: the 90 % posterior interval, its width over the prior's 90 % (1: the data said "
             "nothing), marked where it runs into an edge of the design range (the data ask for more than the "
             "range allows: no estimate) and where it excludes the effect's no-effect value (the plain model's); an "
             "interval half the prior's width or wider is read as neither. Detectable: the smallest rms effect the rule chooses on this design's "
             "expected data (loop/trust.py; - none in the range).", "",
             "| effect | parameter: fitted mean [90 %] (width / prior's) | gain | SE | tests better | p | held-out RMSE "
             "| cut / bar | detectable from | verdict |", "|---|---|---|---|---|---|---|---|---|---|"]
    detect = stats.detectable or {}
    for c in cands:
        par = ", ".join(_interval_words(n, m, iv, note) for n, m, iv, note in
                        zip(c["parameters"], c["mean"], c["interval90"], c.get("interval_notes") or [{}] * 9))
        smallest = detect.get(c["effect"], {}).get("smallest", np.nan)
        lines.append(f"| {c['effect']} | {par} | {c['gain']:.3g} | {c['se']:.3g} | {c['wins']}/{c['tests']} | "
                     f"{_fmt_p(c['p'])} | {scale * c['held_out_rmse']:.3g} | {_cut_words(c)} | "
                     f"{'-' if not np.isfinite(smallest) else f'{scale * smallest:.3g}'} | "
                     f"{_verdict_of(c, len(cands))} |")
    lines += [f"| {e} | - | - | - | - | - | - | - | not testable: no target declares {MODIFIERS[e].covariate} "
              "(its runs would be the plain model's), not run |" for e in run.selection.untestable]
    held = rmse(run.targets.y, run.plain.held.predicted)
    return lines + ["", f"Plain model RMSE over all points: {scale * stats.plain_rmse:.3g} {unit}; held out (each test "
                    f"with the discrepancy the other tests of its source estimate, as the candidates' held-out RMSE): "
                    f"{scale * held:.3g} {unit}.", ""] + _stray(stats, scale, unit)


def _stray(stats, scale, unit):
    """How far the measured curves stray from the model's specimens (trust.specimen_stray)."""
    s = stats.stray
    if not s:
        return []
    return [f"The measured curves against the model's own specimens: the {s['model']} model's held-out RMSE "
            f"{scale * s['rms']:.3g} {unit} over the root of the scatter the model's specimens leave (the "
            "chosen effect's own; where none is chosen, the plain model's) "
            f"({scale * s['scatter']:.3g} {unit}): **{s['ratio']:.3g}** (about 1 where the measured specimens are "
            f"like the model's; beyond {STRAY_LIMIT:g} they are not, or an effect no candidate makes is there, and the "
            "intervals, which rest on specimens like ours, are no evidence)." + _within(s), ""]


def _within(s):
    within = s.get("within") or {}
    if s["ratio"] <= STRAY_LIMIT or not within:
        return ""
    return (" Against each candidate's own specimens' scatter (held-out RMSE over its root): "
            + ", ".join(f"{n} {r:.2g}" for n, r in within.items()) + " - within the limit: the curves scatter as "
            "that effect's specimens do.")


def _interval_words(name, mean, interval, note):
    lo, hi = interval
    text = f"{name} {mean:.3g} [{lo:.3g}, {hi:.3g}]"
    if note:
        text += f" ({note['width_share']:.2f})"
        if note["at_edge"]:
            text += f" **at the {note['at_edge']} edge of its range**"
        if note.get("excludes_no_effect"):
            text += f", excludes the no-effect {note['no_effect']:.3g}"
    return text


def _discrepancy(run, stats, scale, unit):
    """The discrepancy per source beside each effect's size."""
    if not stats.discrepancy:
        return []
    terms = stats.discrepancy[0]["terms"]
    if not terms:
        return ["## The discrepancy", "", "None estimated (`loop.discrepancy_terms: []`): every test is judged on "
                "its own, and what all tests of a source share counts once per test.", ""]
    lines = ["## The discrepancy: what the measured tests of one source share and the model lacks", "",
             "Per source, " + " and ".join(t.replace("_", " ") for t in terms) + " shared by all its tests, "
             "estimated with each model's parameters (loop/discrepancy.py; prior sd "
             f"{run.settings['discrepancy_prior_sd_share']:g} x the source's measured rms). Size: its rms over the "
             "source's points; effect: the rms of the candidate's fitted curve minus the plain model's. An effect "
             "smaller than the discrepancy beside it explains less than what the source shares.", "",
             "| source | model | " + " | ".join(f"{t} (sd)" for t in terms) + " | discrepancy size | effect size |",
             "|---|---|" + "---|" * len(terms) + "---|---|"]
    for row in stats.discrepancy:
        models = {"plain": row["plain"], **row["candidates"]}
        for name, e in models.items():
            cells = " | ".join(f"{scale * m:.3g} ({scale * sd:.2g})" for m, sd in zip(e["mean"], e["sd"]))
            effect = f"{scale * e['effect_size']:.3g}" if "effect_size" in e else "-"
            lines.append(f"| {row['source']} | {name} | {cells} | {scale * e['size']:.3g} | {effect} |")
    return lines + ["", f"In {unit} (slope: per unit ln N).", ""]


def _verdict(run, stats, scale, unit):
    chosen = run.selection.chosen
    if not run.settings["effects"]:
        return []
    if not chosen:
        if stats.named:
            return [f"**No effect adopted**: {stats.named} passes every other condition of the rule, but even with "
                    "it the "
                    "measured curves stray beyond the scatter of the model's specimens (above); the model is left "
                    "unchanged.", ""]
        return ["**No effect chosen**: none beats the plain model on held-out tests consistently enough; "
                "the model is left unchanged.", ""]
    plain = f"{scale * stats.plain_rmse:.3g}"
    return [f"**Effect chosen: {chosen}** ({MODIFIERS[chosen].mechanism}). RMSE in the DEM horizon: "
            f"{plain} -> {scale * stats.after_rmse:.3g} {unit} on the fitted tests (the effect "
            f"run at its fitted value), {plain} -> {scale * stats.chosen_row['held_out_rmse']:.3g} {unit} "
            "held out (each test predicted from the others, by the surrogate).", ""]


def _step(run, stats, scale, unit):
    """The frequency step side by side: measured over STEP_CYCLES and over the model's
    window, each model's increment there with its interval and verdict."""
    a, b = STEP_CYCLES
    return ([f"## The frequency step: the increment from N = {a:g} to {b:g}, per test", "",
             _step_words(run, stats, scale, unit)]
            + _step_table(stats, scale) + ["", f"Increments in {unit}.", ""])


def _step_words(run, stats, scale, unit):
    (lo, hi), (a, b) = stats.step[0]["window"], STEP_CYCLES
    text = (f"Measured: the increment of {run.settings['quantity'].replace('_', ' ')} from N = {a:g} to {b:g} on "
            "the whole measured curve, interpolated in ln N (- where the curve does not reach both). Models: the "
            "plain model, the chosen effect at its fitted value, and each candidate's design set whose tests ran "
            "apart (f acts in it: a real-time effect); each ensemble's increment over the window its simulated "
            f"cycles reach, N = {lo:g} -> {hi:g} ({a:g} -> {b:g} cut at the {run.settings['cycles']} cycles "
            f"simulated, starting {b / a:g} times below, at least at N = 1; never extrapolated), with the "
            f"{LEVEL * 100:g} % prediction interval of one more specimen over the cases that did not give way, "
            "beside the measured increment over the same window. Reproduced: the measured increment inside the "
            "interval.")
    if hi < b:
        text += (f" The DEM horizon ends before N = {b:g}: this run can neither reproduce nor refute the step "
                 "itself; the window's columns compare what it reached.")
    text += "".join(_spans_all(m, stats.step, scale, unit) for m in stats.step[0]["models"])
    names = run.targets.names
    return text + "".join(f" The plain model's runs are one for {', '.join(names[j] for j in g)} (the tests "
                          "differ only in what does not act in it, a quasi-static run's f): its increments there "
                          "are one by construction." for g in stats.step_shared)


def _spans_all(model, rows, scale, unit):
    """Where a model reproduces every test: how wide its intervals are against the spread of
    the measured increments, so that a 'yes' everywhere is read for what it is."""
    incs = [r["models"][model] for r in rows]
    if len(rows) < 2 or any(i["reproduced"] != "yes" for i in incs):
        return ""
    measured = [r["measured_window"] for r in rows]
    widths = [i["interval90"][1] - i["interval90"][0] for i in incs]
    lo, hi = f"{scale * min(widths):.3g}", f"{scale * max(widths):.3g}"
    return (f" {model}: reproduced on all {len(rows)} tests, with intervals {lo if lo == hi else f'{lo}-{hi}'} "
            f"{unit} wide against measured increments from {scale * min(measured):.3g} to "
            f"{scale * max(measured):.3g} {unit} across the tests.")


def _step_table(stats, scale):
    (lo, hi), (a, b) = stats.step[0]["window"], STEP_CYCLES
    models, reached = list(stats.step[0]["models"]), (lo, hi) == (a, b)
    head = f"| test | f Hz | measured {a:g} -> {b:g} |" + ("" if reached else f" measured {lo:g} -> {hi:g} |") + "".join(
        f" {m} {lo:g} -> {hi:g} [{LEVEL * 100:g} %] | gave way | reproduced |" for m in models)
    lines = ["", head, "|---|---|---|" + ("" if reached else "---|") + "---|---|---|" * len(models)]
    for r, before in zip(stats.step, stats.before):
        f = before.get("frequency_Hz")
        row = (f"| {r['test']} | {'-' if f is None else f'{f:g}'} | {_signed(scale * r['measured_step'])} |"
               + ("" if reached else f" {_signed(scale * r['measured_window'])} |"))
        for m in models:
            inc = r["models"][m]
            ilo, ihi = (scale * x for x in inc["interval90"])
            band = f" [{ilo:.3g}, {ihi:.3g}]" if np.isfinite(ilo) else ""
            row += (f" {_signed(scale * inc['mean'])}{band} | {inc['gave_way']}/{inc['gave_way'] + inc['kept']} | "
                    f"{inc['reproduced']} |")
        lines.append(row)
    return lines


def _signed(x):
    return "-" if not np.isfinite(x) else f"{x:+.3g}"


def _long_term(run, stats, scale, unit):
    law, cycles = run.long_term_law, run.settings["cycles"]
    lines = ["## Long-term horizon (extrapolated, reported apart)", ""]
    if law is None:
        return lines + ["No accumulation law given (`ballaststudy horizon` chooses one on measured curves): "
                        "nothing extrapolated beyond the DEM horizon.", ""]
    lines += [f"Each ensemble mean over the simulated cycles fitted by the **{law.name}** law, the law that carried "
              f"{law.curves} measured curves best from N <= {law.fit_cycles:g} to their last points (horizon.md), "
              "and extrapolated to the measured points beyond the DEM horizon. On those curves its error at the "
              f"last point was within +-{scale * law.stated_error:.3g} {unit} ({STATED_QUANTILE:g} quantile): "
              "the uncertainty stated with every extrapolation here."]
    if cycles < law.fit_cycles:
        lines[-1] += (f" This run fits {cycles} cycles, fewer than {law.fit_cycles:g}: from so short a run the "
                      "error can only be larger, by an amount no measured curve can tell. Read the table as what the "
                      "DEM horizon implies, not as a prediction the DEM made.")
    lines += ["", "| test | points beyond | decades extrapolated | RMSE before / after | law's parameters (plain) |",
              "|---|---|---|---|---|"]
    for j, lt in enumerate(stats.long_term):
        after = stats.long_term_after[j] if stats.long_term_after else None
        cell = f"{scale * lt.rmse():.3g} / " + (f"{scale * after.rmse():.3g}" if after else "-")
        params = ("no fit (did not converge)" if lt.fit is None else
                  ", ".join(f"{k} {x:.3g}" for k, x in zip(lt.fit.names, lt.fit.params)))
        decades = f"{np.log10(lt.n.max() / cycles):.1f}" if lt.n.size else "-"
        lines.append(f"| {run.targets.names[j]} | {lt.n.size} | {decades} | {cell} | {params} |")
    return lines + [""]
