"""The loop's outputs: loop.nc (every curve), report.md, chosen.yaml, curves.png.

Two horizons, never mixed: the DEM horizon (measured points with N <= the simulated
cycles, compared with the ensembles) and the long-term horizon (points beyond, compared
with Sato's law fitted to each ensemble mean and extrapolated - an extrapolation, said so)."""
import json
from pathlib import Path

import numpy as np
import xarray as xr
import yaml

from ..atomic import atomic_path
from ..metrics.output import VARIABLES, display_scale
from .accumulation import fit_ensemble, predict
from .effects import EFFECTS
from .residual import covariate_tests, residual, summary

CF = "CF-1.8"
COVARIATES = ("frequency_Hz", "confining_pressure_kPa", "deviator_max_kPa", "VCI")
# the plain model's internal signals at its last simulated cycle (mean over the cases)
SIGNALS = ("breakage_rate", "mean_coordination", "void_ratio", "volumetric_strain")
LONG_TERM_LAWS = ("sato", "shakedown")


def model_signals(out, key, tests, cases):
    """[{signal: mean over the cases at the last cycle}] per test, from the plain model's
    cached metrics.nc (cases/<key>/test<j>/case<k>.nc); a failed case's last row."""
    from ..inputs import open_netcdf
    rows = []
    for j in range(tests):
        values = {s: [] for s in SIGNALS}
        for k in range(cases):
            ds = open_netcdf(Path(out) / "cases" / key / f"test{j}" / f"case{k}.nc", "metrics")
            for s in SIGNALS:
                if s in ds and ds.sizes.get("cycle", 0):
                    values[s].append(float(ds[s].values[-1]))
        rows.append({s: float(np.mean(v)) if v else float("nan") for s, v in values.items()})
    return rows


def _rmse(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.sqrt(np.mean((a - b) ** 2))) if a.size else float("nan")


def per_test_rows(args, lp, curves, measured):
    """Per test: name, conditions, covariates, source, the residual summary in the DEM
    horizon of an ensemble (T, K, cycles)."""
    from ..measured.importer import load_conditions
    rows = []
    for j, (cond, (n, v)) in enumerate(zip(args.conditions, measured)):
        c = load_conditions(cond)
        row = dict(test=Path(cond).with_suffix("").name, source=c["source"].split(",")[0],
                   **{k: float(c[k]) for k in COVARIATES[:3] if c.get(k) is not None})
        vci = (c.get("covariates") or {}).get("VCI")
        if vci:
            row["VCI"] = float(vci["value"])
        row.update(summary(residual(n, v, curves[j], lp["measurement_sd"])))
        rows.append(row)
    return rows


def long_term(args, lp, curves):
    """Per test: (N beyond the simulated cycles, measured there, {law: its extrapolation
    there}, {law: the fit or None}) for Sato's law (hardening + creep) and the shakedown law
    (no creep): a run too short to tell hardening from creep is read both ways."""
    from ..inputs import open_netcdf
    out = []
    cycles = np.arange(1, lp["cycles"] + 1, dtype=float)
    for j, path in enumerate(args.measured):
        ds = open_netcdf(path, "measured")
        n, v = ds["cycle"].values, ds[lp["quantity"]].values
        beyond = np.isfinite(v) & (n > lp["cycles"])
        preds, fits = {}, {}
        for law in LONG_TERM_LAWS:
            try:
                fits[law] = fit_ensemble(law, cycles, curves[j])
                preds[law] = predict(fits[law], n[beyond])[0]
            except (RuntimeError, ValueError):     # no convergence (a flat, censored ensemble)
                fits[law], preds[law] = None, np.full(beyond.sum(), np.nan)
        out.append((n[beyond], v[beyond], preds, fits))
    return out


def candidate_rows(candidates, evidence, y, point_test, chosen):
    rows = []
    for name, c in candidates.items():
        held, (mean, interval, ess) = c.held, c.fit
        eff = EFFECTS[name]
        rows.append(dict(effect=name, parameters=[p.name for p in eff.parameters],
                         mean=mean.tolist(), interval90=interval.tolist(), ess=ess,
                         held_out_rmse=held.rmse(y, point_test), chosen=name == chosen,
                         **evidence[name]))
    return rows


def _padded(rows, fill):
    """Ragged last axis -> one array, short rows filled (effects have one or two parameters)."""
    rows = [np.asarray(r) for r in rows]
    width = max(r.shape[-1] for r in rows)
    out = np.full((len(rows), *rows[0].shape[:-1], width), fill, dtype=object if fill == "" else float)
    for i, r in enumerate(rows):
        out[i, ..., : r.shape[-1]] = r
    return out.astype(str) if fill == "" else out


def loop_dataset(lp, measured, plain_set, candidates, after, rows_before, y, point_test, plain_mean, plain_held,
                 probe_set=None):
    units, long_name, _ = VARIABLES[lp["quantity"]]
    names = list(candidates)
    data = {
        "measured": ("point", y, {"units": units, "long_name": "measured " + long_name}),
        "measured_cycle": ("point", np.concatenate([n for n, _ in measured]), {"units": "1", "long_name": "load cycle N of the point"}),
        "point_test": ("point", point_test.astype(np.int32), {"units": "1", "long_name": "test of the point"}),
        "plain": (("test", "case", "cycle"), plain_set["curves"], {"units": units, "long_name": "plain model: simulated " + long_name}),
        "plain_prediction": ("point", plain_mean, {"units": units, "long_name": "plain model: ensemble mean at the point"}),
        "plain_lpd": ("test", plain_held.lpd,
                      {"units": "1", "long_name": "plain model: log predictive density of the test's points (the noise model every model is judged under)"}),
        "candidate": (("effect", "set", "test", "case", "cycle"),
                      np.array([[s["curves"] for s in c.evaluate.sets[: len(c.thetas)]] for c in candidates.values()]),
                      {"units": units, "long_name": "candidate effect at a design set: simulated " + long_name}),
        "candidate_value": (("effect", "set", "parameter_index"), _padded([c.thetas for c in candidates.values()], np.nan),
                            {"units": "1", "long_name": "the effect's parameter values at the set (effect_parameter; NaN: it has fewer)"}),
        "effect_parameter": (("effect", "parameter_index"),
                             _padded([[p.name for p in EFFECTS[k].parameters] for k in names], ""),
                             {"long_name": "the effect's parameters (empty: it has fewer)"}),
        "held_out_lpd": (("effect", "test"), np.array([c.held.lpd for c in candidates.values()]),
                         {"units": "1", "long_name": "held-out log predictive density (the test left out of the fit)"}),
        "held_out_prediction": (("effect", "point"), np.array([c.held.predicted for c in candidates.values()]),
                                {"units": units, "long_name": "held-out prediction of the point (its test left out)"}),
    }
    if probe_set is not None:
        data["plain_probe"] = (("test", "case", "cycle"), probe_set["curves"], {"units": units, "long_name": "plain model run again from velocities perturbed by round-off size (the chaos probe): simulated " + long_name})
    if after is not None:
        data["after"] = (("test", "case", "cycle"), after["curves"], {"units": units, "long_name": "chosen effect at its fitted value: simulated " + long_name})
    return xr.Dataset(data, coords={
        "effect": ("effect", names), "test": ("test", [r["test"] for r in rows_before]),
        "cycle": ("cycle", np.arange(1, lp["cycles"] + 1, dtype=float), {"units": "1", "long_name": "load cycle number N"}),
        "case": ("case", np.arange(plain_set["curves"].shape[1]), {"units": "1", "long_name": "specimen"})},
        attrs={"Conventions": CF, "title": "closing the loop with measured data (issue 14)"})


def write_outputs(out, args, lp, measured, plain_set, plain_mean, candidates, evidence, chosen, after,
                  base, untestable, minutes, plain_held, probe_set=None):
    y = np.concatenate([v for _, v in measured])
    point_test = np.concatenate([np.full(n.size, j) for j, (n, _) in enumerate(measured)])
    before = per_test_rows(args, lp, plain_set["curves"], measured)
    for row, sig in zip(before, model_signals(out, plain_set["key"], len(before), len(args.specimens))):
        row.update(sig)
    after_rows = per_test_rows(args, lp, after["curves"], measured) if after is not None else None
    cov = [r for resp in ("bias", "slope_ln_n") for r in covariate_tests(before, resp, COVARIATES + SIGNALS)]
    cands = candidate_rows(candidates, evidence, y, point_test, chosen)
    horizon = dict(before=long_term(args, lp, plain_set["curves"]),
                   after=long_term(args, lp, after["curves"]) if after is not None else None)
    files = [out / "report.md", out / "loop.nc", out / "chosen.yaml", out / "curves.png"]
    ds = loop_dataset(lp, measured, plain_set, candidates, after, before, y, point_test, plain_mean, plain_held,
                      probe_set)
    ds.attrs.update(tests_json=json.dumps(before), covariate_tests_json=json.dumps(cov), candidates_json=json.dumps(cands),
                    chosen=chosen or "none", material_parameters_json=json.dumps(base),
                    untestable_effects=", ".join(untestable) or "none")
    with atomic_path(files[1]) as tmp:
        ds.to_netcdf(tmp)
    dem_cases = len(args.specimens) * len(args.measured) * (1 + (probe_set is not None) + sum(len(c.evaluate.sets) for c in candidates.values()))
    with atomic_path(files[2]) as tmp:
        tmp.write_text(yaml.safe_dump(_chosen_doc(chosen, cands, base), sort_keys=False))
    plot_curves(files[3], lp, measured, plain_set, after, horizon, [r["test"] for r in before])
    text = report_markdown(lp, before, after_rows, cov, cands, chosen, horizon, plain_mean, y, point_test,
                           dem_cases, minutes, untestable)
    with atomic_path(files[0]) as tmp:
        tmp.write_text(text)
    return files


def _chosen_doc(chosen, cands, base):
    row = next((c for c in cands if c["chosen"]), None)
    return {"effect": chosen or "none",
            "parameters": dict(zip(row["parameters"], row["mean"])) if row else {},
            "interval90": dict(zip(row["parameters"], row["interval90"])) if row else {},
            "material_parameters": base or "table_4_2"}


def _noise_words(lp):
    if lp["specimen_share"] == 0:
        return ("the measured curves are taken as runs of the model's own specimens, so the scatter is "
                "chaos / K: the plain ensemble run again from velocities perturbed by round-off size "
                "(the chaos probe), plus the measurement's.")
    return (f"the measured specimen scatters like {lp['specimen_share']:g} x one of the plain model's, "
            "plus 1/K of that for the ensemble mean, plus the measurement's.")


def _fmt_p(p):
    return "-" if not np.isfinite(p) else f"{p:.2g}"


def report_markdown(lp, before, after, cov, cands, chosen, horizon, plain_mean, y, point_test, dem_cases, minutes,
                    untestable=()):
    scale, unit = display_scale(lp["quantity"])
    q = lp["quantity"].replace("_", " ")
    refined = (f" + {lp['refine_rounds']} x {lp['refine_sets']} refined around the held-out posteriors"
               if lp["refine_rounds"] else "")
    lines = ["# Closing the loop with measured data", "",
             f"{len(before)} tests, {lp['cases']} specimens per model and test, {lp['cycles']} simulated cycles "
             f"(the DEM horizon); {len(cands)} candidate effects at {lp['design_sets']} parameter sets each"
             f"{refined}; "
             f"{dem_cases} DEM cases ({minutes:.1f} min in this run; cases found in the cache are not rerun). "
             f"Quantity: {q} [{unit}].", "",
             "## DEM horizon: measured vs the plain model, per test", "",
             "Residual = measured - ensemble mean at the measured points (N <= the simulated cycles). "
             "Bias and slope (per unit ln N) are judged as one more specimen of the ensemble (p: two-sided "
             "prediction test; K - 1 degrees of freedom).", "",
             "| test | p kPa | f Hz | VCI % | points | RMSE before | RMSE after (fitted) | bias (p) | slope ln N (p) |",
             "|---|---|---|---|---|---|---|---|---|"]
    for j, r in enumerate(before):
        a = after[j]["rmse"] * scale if after else float("nan")
        lines.append(f"| {r['test']} | {r.get('confining_pressure_kPa', float('nan')):g} | {r.get('frequency_Hz', float('nan')):g} | "
                     f"{r.get('VCI', 0):g} | {r['points']} | {scale * r['rmse']:.3g} | {a:.3g} | "
                     f"{scale * r['bias']:.3g} ({_fmt_p(r['bias_p'])}) | {scale * r['slope_ln_n']:.3g} ({_fmt_p(r['slope_p'])}) |")
    lines += ["", "## What the residual relates to (across tests)", "",
              "Least squares of each test's bias and slope on each declared covariate and on each of the "
              "plain model's internal signals at its last cycle (" + ", ".join(SIGNALS) + "; mean of the "
              "cases), one intercept per source study (a grouping factor), t-test p, Holm-adjusted over "
              "everything tried for that response.", "",
              "| response | covariate | tests | slope | p | p (Holm) | significant |", "|---|---|---|---|---|---|---|"]
    for r in cov:
        if r["tried"]:
            lines.append(f"| {r['response']} | {r['covariate']} | {r['tests']} | {r['slope']:.3g} | "
                         f"{_fmt_p(r['p'])} | {_fmt_p(r['p_holm'])} | {'yes' if r['significant'] else 'no'} |")
        else:
            lines.append(f"| {r['response']} | {r['covariate']} | {r['tests']} | - | - | - | not tried (no variation within a source, one test alone carries it, or too few tests) |")
    lines += ["", "## Candidate effects, judged on held-out tests", "",
              "Each test left out once: the effect's parameter fitted on the others, the left-out test's "
              "points predicted. Gain = sum over tests of held-out log predictive density minus the plain "
              "model's, every model under one noise model: " + _noise_words(lp) + " Rule: one-sided Wilcoxon signed-rank test of the per-test gains, p < 0.05 / "
              f"{len(cands)} (candidates); the largest gain among the passing is chosen.", "",
              "| effect | parameter: fitted mean [90 %] | gain | SE | tests better | p | held-out RMSE | verdict |",
              "|---|---|---|---|---|---|---|---|"]
    plain_rmse = _rmse(y, plain_mean)
    for c in cands:
        par = ", ".join(f"{n} {m:.3g} [{lo:.3g}, {hi:.3g}]" for n, m, (lo, hi) in zip(c["parameters"], c["mean"], c["interval90"]))
        verdict = "chosen" if c["chosen"] else ("rejected: gain not consistent across tests" if c["p"] >= 0.05 / len(cands)
                                                 else "passes, smaller gain" if c["gain"] > 0 else "rejected: no gain")
        lines.append(f"| {c['effect']} | {par} | {c['gain']:.3g} | {c['se']:.3g} | {c['wins']}/{c['tests']} | "
                     f"{_fmt_p(c['p'])} | {scale * c['held_out_rmse']:.3g} | {verdict} |")
    lines += [f"| {e} | - | - | - | - | - | - | not testable: no target declares {EFFECTS[e].covariate} "
              "(its runs would be the plain model's), not run |" for e in untestable]
    lines += ["", f"Plain model RMSE over all points: {scale * plain_rmse:.3g} {unit} (nothing fitted: fitted = held out).", ""]
    if chosen:
        row = next(c for c in cands if c["chosen"])
        after_rmse = np.sqrt(np.mean([r["rmse"] ** 2 for r in after]))
        lines += [f"**Effect chosen: {chosen}** ({EFFECTS[chosen].mechanism}). RMSE in the DEM horizon: "
                  f"{scale * plain_rmse:.3g} -> {scale * after_rmse:.3g} {unit} on the fitted tests (the effect "
                  f"run at its fitted value), {scale * plain_rmse:.3g} -> {scale * row['held_out_rmse']:.3g} {unit} "
                  "held out (each test predicted from the others, by the surrogate).", ""]
    else:
        lines += ["**No effect chosen**: none beats the plain model on held-out tests consistently enough; "
                  "the model is left unchanged.", ""]
    lines += _long_term_lines(horizon, scale, unit, [r["test"] for r in before], lp["cycles"])
    return "\n".join(lines) + "\n"


def _long_term_lines(horizon, scale, unit, names, cycles):
    lines = ["## Long-term horizon (extrapolated, reported apart)", "",
             "Each ensemble mean over the simulated cycles fitted by Sato's law eps0 + gamma (1 - exp(-alpha "
             "(N - 1))) + beta (N - 1) and by the shakedown law (beta = 0), extrapolated to the measured points "
             "beyond them. A run too short to tell hardening from creep is read both ways: creep carried over "
             "decades of N (Sato) against none (shakedown). Read it as what the DEM horizon implies, not as a "
             "prediction the DEM made.", "",
             "| test | points beyond | decades extrapolated | RMSE Sato before / after | RMSE shakedown before / after "
             "| Sato gamma, alpha, beta (plain) |", "|---|---|---|---|---|---|"]
    for j, (n, v, pred, fits) in enumerate(horizon["before"]):
        after = horizon["after"][j][2] if horizon["after"] else None
        cells = [f"{scale * _rmse(v, pred[law]):.3g} / " + (f"{scale * _rmse(v, after[law]):.3g}" if after else "-")
                 for law in LONG_TERM_LAWS]
        fit = fits["sato"]
        law = "no fit (did not converge)" if fit is None else ", ".join(f"{x:.3g}" for x in fit.params[1:])
        decades = f"{np.log10(n.max() / cycles):.1f}" if n.size else "-"
        lines.append(f"| {names[j]} | {n.size} | {decades} | {cells[0]} | {cells[1]} | {law} |")
    return lines + [""]


def plot_curves(path, lp, measured, plain_set, after, horizon, names):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    scale, unit = display_scale(lp["quantity"])
    cols = min(4, len(names))
    rows = -(-len(names) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4 * cols, 3.2 * rows), dpi=100, squeeze=False)
    cycles = np.arange(1, lp["cycles"] + 1)
    far = np.geomspace(lp["cycles"], 5e5, 60)
    for j, ax in enumerate(axes.flat):
        if j >= len(names):
            ax.axis("off")
            continue
        for label, ens, lt, colour in (("plain", plain_set, horizon["before"], "0.4"),
                                        ("chosen effect", after, horizon["after"], "C0")):
            if ens is None:
                continue
            c = scale * ens["curves"][j]
            ax.plot(cycles, c.mean(axis=0), color=colour, lw=2, label=label)
            ax.fill_between(cycles, c.min(axis=0), c.max(axis=0), color=colour, alpha=0.2)
            for law, style in zip(LONG_TERM_LAWS, ("--", ":")):
                if lt[j][3][law] is not None:
                    ax.plot(far, scale * predict(lt[j][3][law], far)[0], color=colour, ls=style, lw=1)
        n, v = measured[j]
        ax.plot(n, scale * v, "ko", ms=3, label="measured (DEM horizon)")
        ax.plot(horizon["before"][j][0], scale * horizon["before"][j][1], "o", mfc="none", mec="k", ms=3,
                label="measured (long-term)")
        ax.set_xscale("log")
        ax.set_title(names[j], fontsize=8)
        ax.set_xlabel("N")
        ax.set_ylabel(f"{lp['quantity'].replace('_', ' ')} [{unit}]")
        ax.grid(alpha=0.3)
    axes.flat[0].legend(fontsize=6)
    fig.suptitle("measured vs model: DEM horizon (solid, band = min-max of the cases), extrapolated by "
                 "Sato (dashed) and shakedown (dotted)", fontsize=8)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", bbox_inches="tight")
    plt.close(fig)
