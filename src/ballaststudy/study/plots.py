"""Figures like thesis Figs. 5-1 ... 5-6: one figure per behaviour, one panel per database
group, one curve per database = mean over its cases at each cycle, with a shaded band from
the minimum to the maximum over the cases (cases that did not run a cycle are left out)."""

import warnings
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from ..atomic import atomic_path
from .breakage import THESIS_MAX_MEAN_BREAKAGES, breakage_counts

DPI = 130
BAND = "min-max over cases"
# file, variable, label, factor to the plotted unit
FIGURES = [
    ("fig_5-1_settlement.png", "settlement", "settlement (mm)", 1e3),
    ("fig_5-2_breakage_rate.png", "breakage_rate", "breakage rate (%)", 100.0),
    ("fig_5-4_ghost_particles.png", "ghost_particles", "ghost particles (-)", 1.0),
    ("fig_5-5_force_propagation_angle.png", "fpa", "force propagation angle (deg)", 1.0),
    ("fig_5-6_void_ratio.png", "void_ratio", "void ratio (%)", 100.0),
]


def _save(fig, path):
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=DPI)
    return Path(path)


def _groups(study):
    groups = list(dict.fromkeys(study.group.values.tolist()))
    return [(g, [str(d) for d, gg in zip(study.database.values, study.group.values) if gg == g]) for g in groups]


def _case_stats(values):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return np.nanmean(values, axis=0), np.nanmin(values, axis=0), np.nanmax(values, axis=0)


def fig_behaviour(study, variable, label, factor):
    groups = _groups(study)
    fig = Figure(figsize=(4.6 * len(groups), 3.8))
    FigureCanvasAgg(fig)
    cycles = study.cycle.values
    for p, (group, dbs) in enumerate(groups):
        ax = fig.add_subplot(1, len(groups), p + 1)
        for db in dbs:
            mean, lo, hi = _case_stats(study[variable].sel(database=db).values * factor)
            line, = ax.plot(cycles, mean, lw=1.3, label=db)
            ax.fill_between(cycles, lo, hi, color=line.get_color(), alpha=0.18, lw=0)
        ax.set(xlabel="loading cycle", ylabel=label, title=f"database group {group}")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(f"{label}: mean over cases, band {BAND}", fontsize=10)
    fig.tight_layout()
    return fig


def fig_breakages(study):
    """Like Fig. 5-3: the number of breakages (broken flat-joint elements) per database after
    the load cycles, mean over cases, stacked into those broken before the first cycle (static
    pre-loading) and during the cycles; error bar min-max of the total over cases; the
    thesis' highest database mean as a dashed line."""
    total, during = breakage_counts(study)
    mean, lo, hi = _case_stats(total.T)
    mean_during = _case_stats(during.T)[0]
    fig = Figure(figsize=(max(5.0, 0.6 * len(mean) + 2), 3.8))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    x = np.arange(len(mean))
    ax.bar(x, mean - mean_during, color="#c6dbef", label="before the cycles (static pre-loading)")
    ax.bar(x, mean_during, bottom=mean - mean_during, color="#3182bd", label="during the load cycles")
    ax.errorbar(x, mean, yerr=[mean - lo, hi - mean], fmt="none", color="k", lw=1)
    ax.axhline(THESIS_MAX_MEAN_BREAKAGES, color="C3", ls="--", lw=1,
               label=f"thesis: highest database mean, just above {THESIS_MAX_MEAN_BREAKAGES:g}")
    ax.set_xticks(x, [str(d) for d in study.database.values], rotation=45, ha="right")
    ax.set(ylabel="broken flat-joint elements per case", title=f"number of breakages: mean, bar {BAND}")
    ax.grid(axis="y", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


BREAKAGES = "fig_5-3_breakages.png"
FINES_THRESHOLD = "fig_fines_threshold.png"


def figure_names():
    """File names of every figure the optimisation report writes (for the workflow)."""
    names = [f[0] for f in FIGURES]
    names.insert(2, BREAKAGES)
    return names + [FINES_THRESHOLD]


def write_figures(study, out_dir):
    """Write Figs. 5-1 ... 5-6 into `out_dir` (atomically); return the paths."""
    out = Path(out_dir)
    paths = [_save(fig_behaviour(study, v, label, f), out / name) for name, v, label, f in FIGURES]
    paths.insert(2, _save(fig_breakages(study), out / BREAKAGES))
    return paths
