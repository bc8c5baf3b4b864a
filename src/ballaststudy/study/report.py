"""Optimisation report (thesis 5.8) as Markdown with its tables (CSV) and figures (PNG)."""

import json
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from ..atomic import atomic_path
from ..rig.deposition import EQUILIBRIUM_FORCE_RATIO
from . import optimise, plots, scale


def fig_fines_threshold(ctx):
    """Final settlement (mean over cases, bar = se) vs percent passing 22.4 mm with the
    two-segment fit (free jump) and the breakpoint's bootstrap interval (shaded)."""
    s = ctx["summary"]
    fig = Figure(figsize=(6.2, 4.2))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    for g, rows in s.groupby("group", sort=False):
        ax.errorbar(rows.percent_passing_22_4mm, rows.settlement_final * 1e3, yerr=rows.settlement_final_se * 1e3,
                    fmt="o", ms=5, capsize=2, label=f"group {g}")
    ft = ctx["fines"]
    if ft is not None:
        f = ft["fit"]
        for lo_x, hi_x, a, b, label in (
                (ft["x"].min(), f["gap_lo"], f["left_a"], f["left_b"],
                 f"two-segment fit, breakpoint {f['breakpoint']:.3g} %"),
                (f["gap_hi"], ft["x"].max(), f["right_a"], f["right_b"], None)):
            xs = np.linspace(lo_x, hi_x, 100)
            ax.plot(xs, 1e3 * (a + b * xs), "k-", lw=1, label=label)
        lo, hi = ft["breakpoint_ci"]
        if np.isfinite(lo) and hi > lo:
            ax.axvspan(lo, hi, color="0.5", alpha=0.2, label="breakpoint 95 % interval")
        elif np.isfinite(lo):
            ax.axvline(lo, color="0.4", ls="--", lw=1, label="breakpoint 95 % interval (one point)")
    ax.axvspan(*optimise.THRESHOLD_RANGE, color="tab:red", alpha=0.15, label="thesis: 16-17.5 %")
    ax.set(xlabel="percent passing 22.4 mm (%)", ylabel="final settlement (mm)",
           title="Settlement regime vs fines (thesis 5.2)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def _cell(v):
    if isinstance(v, (float, np.floating)):
        return "n/a" if not np.isfinite(v) else f"{v:.4g}"
    return str(v)


def _md_table(df, columns):
    lines = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    for name, row in df.iterrows():
        lines.append("| " + " | ".join(_cell(name if c == "database" else row[c]) for c in columns) + " |")
    return lines


def scale_banner(study):
    """The report's opening paragraph when the study is far below the thesis' scale, else ""."""
    cases, cycles = scale.extent(study)
    if not scale.far_below(cases, cycles):
        return ""
    return (f"**Far below the thesis' scale.** {scale.describe(cases, cycles)} The thesis' findings are about "
            f"the behaviour after {scale.THESIS_CYCLES} cycles averaged over {scale.THESIS_CASES} cases, so this "
            f"run can neither confirm nor refute them: every finding whose rule gives holds or does not hold is "
            f"marked \"{optimise.UNDECIDED_AT_SCALE}\" (what the rule gives is in brackets and in `mark_by_rule` "
            f"of findings.csv/json). The ranking, Pareto set and figures describe this run only. Rule: "
            f"{scale.SCALE_RULE}.")


def _mark_cell(f):
    if f["mark"] == f["mark_by_rule"]:
        return f"**{f['mark']}**"
    return f"**{f['mark']}** (would be: {f['mark_by_rule']})"


def report_markdown(ctx, findings, pareto, recommend, figures, study_path=None, extent="", banner=""):
    ranking = ctx["ranking"]
    cols = ["rank", "database", "group", "tier_path", "settlement_final", "breakage_rate_final", "ghost_level",
            "ghost_variability", "fpa_level", "fpa_variability", "void_ratio_level", "void_ratio_variability"]
    lines = ["# The optimised ballast aggregate (thesis 5.8)", ""]
    if banner:
        lines += [banner, ""]
    if study_path:
        lines += [f"Data: `{study_path}`; bootstrap {ctx['n_boot']} resamples, seed {ctx['seed']}.", ""]
    if extent:
        lines += [extent, ""]
    lines += ["## Ranking", "", f"Rule: {optimise.RANKING_RULE}.", "",
              "Units: settlement m, breakage rate 1 (fraction), ghost particles count, FPA deg, void ratio 1. "
              "`tier_path`: tier (1 = best) at each criterion in order.", ""]
    lines += _md_table(ranking, cols) + [""]
    lines += ["## Pareto set", "", f"Rule: {optimise.PARETO_RULE}.", "",
              ", ".join(pareto) if pareto else "(empty)", "",
              "## Recommended databases", "", f"Rule: {optimise.RECOMMEND_RULE}.", ""]
    lines += [f"- group {g}: **{d}** (rank {int(ranking.loc[d, 'rank'])}"
              f"{', in the Pareto set' if d in pareto else ', not in the Pareto set'})" for g, d in recommend.items()]
    lines += ["", "## The thesis' findings against our numbers", "",
              "| finding | claim | mark | numbers |", "|---|---|---|---|"]
    lines += [f"| {f['finding']} | {f['claim']} | {_mark_cell(f)} | {f['numbers']} |" for f in findings]
    lines += ["", "Rules:", ""] + [f"- `{f['finding']}`: {f['rule']}." for f in findings]
    lines += ["", "## Figures", "", f"Curves: mean over cases; bands: {plots.BAND}.", ""]
    lines += [f"![{p.stem}]({p.name})" for p in figures] + [""]
    return "\n".join(lines)


def _span(lo, hi):
    return f"{int(lo)}" if lo == hi else f"{int(lo)}-{int(hi)}"


def extent_line(study):
    """One sentence: databases, cases, cycles run, and assemblies stopped at a step limit."""
    run = scale.cycles_run(study)
    cases = (run > 0).sum(axis=1)
    text = (f"{study.sizes['database']} databases, {_span(cases.min(), cases.max())} cases each, "
            f"up to {study.sizes['cycle']} cycles")
    if (run > 0).any():
        text += f" (cases ran {_span(run[run > 0].min(), run.max())} cycles)"
    text += "."
    if "assembly_stages_at_limit" in study:
        limits = study["assembly_stages_at_limit"].values
        if (limits >= 0).any():
            text += (f" {int((limits > 0).sum())} of {int((limits >= 0).sum())} cases were assembled "
                     "with a stage stopped at its step limit, not at its criterion (study.nc: "
                     "assembly_stages_at_limit; each case's assembled.nc names the stages).")
    if "assembly_force_ratio" in study and np.isfinite(study["assembly_force_ratio"].values).any():
        ratio = study["assembly_force_ratio"].values
        ratio = ratio[np.isfinite(ratio)]
        text += (f" The stones' force ratio when loading began: median {np.median(ratio):.2g}, largest "
                 f"{ratio.max():.2g}; {int((ratio >= EQUILIBRIUM_FORCE_RATIO).sum())} of {ratio.size} cases at or above "
                 f"the thesis' equilibrium limit {EQUILIBRIUM_FORCE_RATIO:g} (4.2.1; study.nc: assembly_force_ratio).")
    return text


def write_report(study, out_dir, n_boot=2000, seed=0, study_path=None):
    """Write report.md, ranking.csv, findings.csv/json, Figs. 5-1 ... 5-6 and the fines-threshold
    figure into `out_dir` (atomically); return the written paths."""
    out = Path(out_dir)
    ctx = optimise.context(study, n_boot, seed)
    findings = optimise.check_findings(study, n_boot, seed, ctx=ctx)
    pareto = optimise.pareto_set(ctx["summary"])
    recommend = optimise.recommended(ctx["ranking"])
    figures = plots.write_figures(study, out)
    fig = out / plots.FINES_THRESHOLD
    with atomic_path(fig) as tmp:
        fig_fines_threshold(ctx).savefig(tmp, format="png", dpi=plots.DPI)
    figures.append(fig)
    ranking = ctx["ranking"].copy()
    ranking["pareto"] = [d in pareto for d in ranking.index]
    ranking["recommended"] = [recommend.get(ranking.loc[d, "group"]) == d for d in ranking.index]
    written = []
    for name, write in (
            ("ranking.csv", lambda p: ranking.to_csv(p)),
            ("findings.csv", lambda p: pd.DataFrame(findings).to_csv(p, index=False)),
            ("findings.json", lambda p: p.write_text(json.dumps(findings, indent=1))),
            ("report.md", lambda p: p.write_text(report_markdown(ctx, findings, pareto, recommend, figures,
                                                                 study_path, extent_line(study),
                                                                 scale_banner(study))))):
        with atomic_path(out / name) as tmp:
            write(tmp)
        written.append(out / name)
    return written + figures
