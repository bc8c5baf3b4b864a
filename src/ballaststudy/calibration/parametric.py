"""The parametric study (thesis 4.4, Figs. 4-14 and 4-15): F_str_co and mu varied one at a
time (the other at Table 4.2's), K box-test cases per value on the same K assembled
specimens (common random numbers), settlement and breakage per cycle.

Per parameter: the curves per value (mean and +-1 sd band), the final settlement and
breakage (last cycle) against the value with an ordinary least-squares slope over all
cases, its 95 % interval (t) and p-value, and the standardised regression coefficient
SRC = slope sd(value) / sd(output) over those runs - linear and one-at-a-time. The
variance-based indices come from a design of their own (``design_sets``: a Latin hypercube
over both ranges at once, K cases per set; sensitivity.py): first-order and total Sobol
indices of the final settlement and breakage.
The thesis' findings: "settlement rises as F_str-co falls" and "settlement rises as mu
falls" hold if the slope's 95 % interval lies below 0, do not hold if above, else not
decidable; far below the thesis' scale (study/scale.py) not decidable at this scale."""
import json
from collections import Counter

import numpy as np
import xarray as xr
from scipy import stats

from ..atomic import atomic_path
from ..inputs import open_netcdf
from ..metrics.output import VARIABLES, display_scale
from ..scenario.modifiers import material_parameter
from ..schema import ConfigError
from ..study import scale
from ..study.optimise import UNDECIDED_AT_SCALE, three_way
from .bayes import initial_design
from .sensitivity import sobol_indices

OUTPUTS = ("settlement", "breakage_rate")
NAMES = ("F_str_co", "mu")        # the parameters the study varies
DESIGN = "design"                 # the ``parameter`` of a run of the sensitivity design
FINDINGS = {"F_str_co": "settlement rises as F_str-co falls (thesis 4.4, Fig. 4-14)",
            "mu": "settlement rises as mu falls (thesis 4.4, Fig. 4-15)"}


def design_sets(ranges, n, seed):
    """[{name: value}] of the sensitivity design: n sets, a Latin hypercube in ``ranges``
    ({name: (low, high)}, the one-at-a-time values' span)."""
    if n == 0:
        return []
    lower, upper = (np.array([ranges[k][i] for k in NAMES], float) for i in (0, 1))
    return [dict(zip(NAMES, map(float, t))) for t in initial_design(lower, upper, n, seed)]


def varied(ds, path):
    """(parameter, {name: value}) a case's metrics.nc ran with (its material_parameters
    attribute): one name for a one-at-a-time run, every name for a design run."""
    text = ds.attrs.get("material_parameters_json", "{}")
    values = json.loads(text)
    if len(values) == 1 and set(values) <= set(NAMES):
        return next(iter(values)), values
    if set(values) == set(NAMES):
        return DESIGN, values
    raise ConfigError(path, "material_parameters_json", f"{text}: not a parametric run (one of "
                      f"{', '.join(NAMES)}, or all of them: ballaststudy parametric setting)")


def parametric_dataset(paths):
    """One dataset (run, cycle): every case's settlement and breakage with its parameter,
    value(s) and specimen."""
    rows = []
    for p in paths:
        ds = open_netcdf(p, "metrics")
        name, values = varied(ds, p)
        rows.append((name, values, int(ds.attrs.get("seed", -1)), [ds[k].values for k in OUTPUTS]))
    n = min(r[3][0].size for r in rows)
    data = {k: (("run", "cycle"), np.array([r[3][i][:n] for r in rows]),
                {"units": VARIABLES[k][0], "long_name": VARIABLES[k][1]}) for i, k in enumerate(OUTPUTS)}
    data["parameter"] = ("run", [r[0] for r in rows], {"long_name": f"parameter varied ({DESIGN}: all, "
                                                                    "the sensitivity design)"})
    data["value"] = ("run", [r[1].get(r[0], np.nan) for r in rows],
                     {"units": "1", "long_name": "its value (the other at Table 4.2's; NaN in the design)"})
    for k in NAMES:
        data[k] = ("run", [r[1].get(k, np.nan) for r in rows],
                   {"units": material_parameter(k).units, "long_name": f"{k} of the run (NaN: Table 4.2's)"})
    data["specimen"] = ("run", [r[2] for r in rows], {"units": "1", "long_name": "seed of the assembled case (the same K for every value)"})
    return xr.Dataset(data, coords={"cycle": ("cycle", np.arange(n), {"units": "1", "long_name": "load cycle"})},
                      attrs={"Conventions": "CF-1.8", "title": "parametric study (thesis 4.4)",
                             "cases": ", ".join(map(str, paths))})


def sensitivity_table(ds, seed=0):
    """Per output: Sobol indices over the design runs (each set's mean of its cases); []
    without design runs, or with fewer than 4 sets."""
    sel = ds["parameter"].values == DESIGN
    thetas = np.column_stack([ds[k].values[sel] for k in NAMES])
    sets, which = np.unique(thetas, axis=0, return_inverse=True) if sel.any() else (np.zeros((0, 2)), None)
    if len(sets) < 4:
        return []
    rows = []
    for k in OUTPUTS:
        final = ds[k].values[sel, -1]
        means = np.array([np.nanmean(final[which.ravel() == j]) for j in range(len(sets))])
        ok = np.isfinite(means)
        indices = sobol_indices(sets[ok], means[ok], sets.min(axis=0), sets.max(axis=0), NAMES, seed)
        rows += [dict(output=k, parameter=n, sets=int(ok.sum()), **v) for n, v in indices.items()]
    return rows


def cases_per_value(ds):
    """The fewest cases of any one-at-a-time (parameter, value)."""
    oat = ds["parameter"].values != DESIGN
    return min(Counter(zip(ds["parameter"].values[oat], ds["value"].values[oat])).values())


def slope_table(ds):
    """Per (parameter, output): slope of the final value over the parameter, its 95 %
    interval, p, SRC, n; and the per-value means."""
    out = []
    for name in sorted(set(ds["parameter"].values) - {DESIGN}):
        sel = ds["parameter"].values == name
        x = ds["value"].values[sel]
        for k in OUTPUTS:
            y = ds[k].values[sel, -1]
            ok = np.isfinite(y)
            row = dict(parameter=name, output=k, n=int(ok.sum()), slope=np.nan, ci_low=np.nan,
                       ci_high=np.nan, p_value=np.nan, src=np.nan)
            if ok.sum() >= 3 and np.ptp(x[ok]) > 0:
                fit = stats.linregress(x[ok], y[ok])
                t = stats.t.ppf(0.975, ok.sum() - 2)
                sd_y = np.std(y[ok], ddof=1)
                row.update(slope=fit.slope, ci_low=fit.slope - t * fit.stderr, ci_high=fit.slope + t * fit.stderr,
                           p_value=fit.pvalue, src=fit.slope * np.std(x[ok], ddof=1) / sd_y if sd_y > 0 else np.nan)
            row["means"] = {f"{v:g}": float(np.nanmean(y[x == v])) for v in np.unique(x)}
            out.append(row)
    return out


def findings(table, cases, cycles):
    """The thesis' two findings, marked from the settlement slopes."""
    marks = []
    for row in table:
        if row["output"] != "settlement" or row["parameter"] not in FINDINGS:
            continue
        mark = three_way(-row["ci_high"], -row["ci_low"])      # holds if the slope is below 0
        by_rule = mark
        if scale.far_below(cases, cycles) and mark != "not decidable":
            mark = UNDECIDED_AT_SCALE
        marks.append(dict(finding=FINDINGS[row["parameter"]], mark=mark, mark_by_rule=by_rule,
                          numbers=f"slope {row['slope']:.3g} m per unit, 95 % [{row['ci_low']:.3g}, "
                                  f"{row['ci_high']:.3g}], p = {row['p_value']:.2g}, n = {row['n']}"))
    return marks


def plot_parameter(path, ds, name):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    sel = ds["parameter"].values == name
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.6), dpi=110)
    for ax, k in zip(axes, OUTPUTS):
        scale_, unit = display_scale(k)
        for v in np.unique(ds["value"].values[sel]):
            y = scale_ * ds[k].values[sel & (ds["value"].values == v)]
            m = np.nanmean(y, axis=0)
            line, = ax.plot(ds["cycle"], m, lw=1.5, label=f"{name} = {v:g}")
            if y.shape[0] > 1:
                s = np.nanstd(y, axis=0, ddof=1)
                ax.fill_between(ds["cycle"], m - s, m + s, color=line.get_color(), alpha=0.15)
        ax.set_xlabel("load cycle")
        ax.set_ylabel(f"{k.replace('_', ' ')} [{unit}]")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    fig.suptitle(f"{material_parameter(name).long_name}: mean of the cases and +-1 sd", fontsize=8)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", bbox_inches="tight")
    plt.close(fig)


def report_markdown(path, table, marks, cases, cycles, sobol=()):
    lines = ["# Parametric study (thesis 4.4)", "",
             f"{cases} box-test cases per value (the same assembled specimens), {cycles} load cycles; "
             "one parameter varied at a time, the other at Table 4.2's.", "",
             "| parameter | output (last cycle) | slope | 95 % interval | p | SRC | n | mean per value |",
             "|---|---|---|---|---|---|---|---|"]
    for r in table:
        means = ", ".join(f"{v}: {m:.3g}" for v, m in r["means"].items())
        lines.append(f"| {r['parameter']} | {r['output']} | {r['slope']:.3g} | [{r['ci_low']:.3g}, "
                     f"{r['ci_high']:.3g}] | {r['p_value']:.2g} | {r['src']:.2f} | {r['n']} | {means} |")
    lines += ["", "SRC: standardised regression coefficient over the one-at-a-time runs (module doc).", ""]
    if sobol:
        lines += ["## Global sensitivity (Sobol indices)", "",
                  f"{sobol[0]['sets']} parameter sets of a Latin hypercube over both ranges, {cases} cases "
                  "each; a Gaussian-process surrogate of each set's mean final value, its first-order (S1) "
                  "and total (ST) Sobol indices by SALib with 95 % bootstrap intervals of the sampling "
                  "(the surrogate's own error not included: read them as a ranking).", "",
                  "| output (last cycle) | parameter | S1 | ST |", "|---|---|---|---|"]
        lines += [f"| {r['output']} | {r['parameter']} | {r['S1']:.2f} +- {r['S1_conf']:.2f} | "
                  f"{r['ST']:.2f} +- {r['ST_conf']:.2f} |" for r in sobol]
        lines.append("")
    lines += ["## The thesis' findings", ""]
    lines += [f"- {m['finding']}: **{m['mark']}** ({m['numbers']}; by the rule alone: {m['mark_by_rule']})"
              for m in marks]
    if scale.far_below(cases, cycles):
        lines += ["", scale.describe(cases, cycles)]
    with atomic_path(path) as tmp:
        tmp.write_text("\n".join(lines) + "\n")
