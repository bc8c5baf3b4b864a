"""Interrelationship Index (IRI) tables (thesis 5.7, Table 5-2): for each of the 10 pairs of
the five behaviours, the correlation across all (database, case) samples of the final values
and of the change over the cyclic phase (last minus first run cycle), Pearson and Spearman
with seeded bootstrap 95 % intervals (resampling the samples), and a verdict by
`stats.VERDICT_RULE`."""

import itertools
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from ..atomic import atomic_path
from . import scale, stats
from .optimise import FAILS, HOLDS, UNDECIDED, UNDECIDED_AT_SCALE

# thesis abbreviation -> study.nc variable
IRI_BEHAVIOURS = {"BS": "settlement", "BR": "breakage_rate", "GP": "ghost_particles", "FPA": "fpa",
                  "VR": "void_ratio"}
KINDS = {"final": stats.final_value, "change": stats.change_value}
THESIS_CSV = "iri_thesis.csv"
QUANTITIES = {"final": stats.final_value, "variability": stats.variability_value}

# Table 5-2 holds only symbols; thesis 5.7's text says what each pair does. Per pair: the
# relation it states, the per-case quantity of each behaviour its sentence speaks of (final:
# after the loading; variability: sd over the cycles, its "radically / drastically changing"),
# and its words, shortened.
THESIS_IRI = [
    ("BS", "BR", "none", "final", "final", "not shown in the simulation: breakages too rare"),
    ("BS", "GP", "positive", "final", "final", "the more ghost particles, the higher the settlement after loading"),
    ("BS", "FPA", "positive", "final", "variability",
     "a high settlement radically changes the force propagation angle; a low one keeps it stable"),
    ("BS", "VR", "negative", "final", "final", "a high settlement indicates a low void ratio"),
    ("BR", "GP", "none", "final", "final", "no relationship found (breakages too rare)"),
    ("BR", "FPA", "none", "final", "final", "no relationship found (breakages too rare)"),
    ("BR", "VR", "none", "final", "final", "no relationship found (breakages too rare)"),
    ("GP", "FPA", "positive", "variability", "variability",
     "a drastically changing number of ghost particles goes with a drastically changing angle"),
    ("GP", "VR", "negative", "final", "final", "many ghost particles, a low void ratio"),
    ("FPA", "VR", "none", "final", "final", "no direct relationship"),
]
THESIS_RULE = ("the thesis' relation against our verdict on the quantities its sentence names: holds if they "
               "are equal; does not hold if ours is another of positive / negative / none; not decidable if "
               "ours is; far below the thesis' scale every holds / does not hold becomes "
               f"\"{UNDECIDED_AT_SCALE}\"")
THESIS_COLUMNS = ["iri", "thesis", "quantity_a", "quantity_b", "n", "spearman_rho", "spearman_lo", "spearman_hi",
                  "verdict", "mark", "mark_by_rule", "thesis_words"]
COLUMNS = ["iri", "a", "b", "kind", "n", "pearson_r", "pearson_lo", "pearson_hi", "pearson_p",
           "spearman_rho", "spearman_lo", "spearman_hi", "spearman_p", "verdict"]


def case_samples(study, variable, kind):
    """Flat array over (database, case) of `kind` ('final' or 'change') of one behaviour."""
    return KINDS[kind](study[variable].values).ravel()


def iri_table(study, n_boot=2000, seed=0, min_abs_rho=stats.MIN_ABS_RHO):
    """DataFrame with one row per (pair, kind): 10 pairs x ('final', 'change')."""
    rows = []
    pairs = list(itertools.combinations(IRI_BEHAVIOURS, 2))
    for kind in KINDS:
        for k, (a, b) in enumerate(pairs):
            c = stats.correlation(case_samples(study, IRI_BEHAVIOURS[a], kind),
                                  case_samples(study, IRI_BEHAVIOURS[b], kind), n_boot=n_boot, seed=seed + k)
            rows.append({"iri": f"IRI_{a}-{b}", "a": a, "b": b, "kind": kind, **c,
                         "verdict": stats.verdict(c, min_abs=min_abs_rho)})
    return pd.DataFrame(rows)[COLUMNS]


def thesis_mark(thesis, ours):
    """THESIS_RULE's mark of our verdict against the thesis' relation (before the scale)."""
    if ours == "not decidable":
        return UNDECIDED
    return HOLDS if ours == thesis else FAILS


def thesis_table(study, n_boot=2000, seed=0, min_abs_rho=stats.MIN_ABS_RHO):
    """DataFrame, one row per pair of THESIS_IRI: our correlation of the quantities the thesis'
    sentence names, our verdict and its mark against the thesis' relation."""
    far = scale.far_below(*scale.extent(study))
    rows = []
    for k, (a, b, thesis, qa, qb, words) in enumerate(THESIS_IRI):
        x = QUANTITIES[qa](study[IRI_BEHAVIOURS[a]].values).ravel()
        y = QUANTITIES[qb](study[IRI_BEHAVIOURS[b]].values).ravel()
        c = stats.correlation(x, y, n_boot=n_boot, seed=seed + 100 + k)
        ours = stats.verdict(c, min_abs=min_abs_rho)
        by_rule = thesis_mark(thesis, ours)
        mark = UNDECIDED_AT_SCALE if far and by_rule in (HOLDS, FAILS) else by_rule
        rows.append({"iri": f"IRI_{a}-{b}", "thesis": thesis, "quantity_a": qa, "quantity_b": qb, "n": c["n"],
                     "spearman_rho": c["spearman_rho"], "spearman_lo": c["spearman_lo"],
                     "spearman_hi": c["spearman_hi"], "verdict": ours, "mark": mark, "mark_by_rule": by_rule,
                     "thesis_words": words})
    return pd.DataFrame(rows)[THESIS_COLUMNS]


def _fmt(v, digits=2):
    return "n/a" if not np.isfinite(v) else f"{v:.{digits}f}"


def scale_note(study):
    """iri.md's opening line when the study is far below the thesis' scale, else "".

    The verdicts are kept at any scale (unlike the findings of `optimise`): they state
    correlations among these samples, not a thesis claim, and n, the bootstrap interval and
    MIN_SAMPLES already carry the sample size. What would mislead is reading them as thesis
    Table 5-2 (values after 1000 cycles), which the note warns against."""
    cases, cycles = scale.extent(study)
    if not scale.far_below(cases, cycles):
        return ""
    return (f"**Far below the thesis' scale.** {scale.describe(cases, cycles)} The verdicts describe these "
            "samples only; they are not a check of thesis Table 5-2.")


def thesis_markdown(thesis, title="## Beside thesis Table 5-2"):
    """The section setting our verdicts beside thesis 5.7's relations (iri.md, the record)."""
    lines = [title, "",
             "The thesis' relation per pair from its text (5.7), our Spearman's rho of the per-case quantities "
             "its sentence names (final: at the last run cycle; variability: sd over the run cycles), our "
             f"verdict and the mark. Mark rule: {THESIS_RULE}.", "",
             "| IRI | thesis (5.7) | quantities | n | Spearman rho [95 % CI] | ours | mark |",
             "|---|---|---|---|---|---|---|"]
    for _, r in thesis.iterrows():
        mark = f"**{r.mark}**" + (f" (would be: {r.mark_by_rule})" if r.mark != r.mark_by_rule else "")
        lines.append(f"| {r.iri} | {r.thesis}: {r.thesis_words} | {r.quantity_a} / {r.quantity_b} | {r.n} | "
                     f"{_fmt(r.spearman_rho)} [{_fmt(r.spearman_lo)}, {_fmt(r.spearman_hi)}] | {r.verdict} | "
                     f"{mark} |")
    return lines + [""]


def iri_markdown(table, n_boot, seed, min_abs_rho=stats.MIN_ABS_RHO, note="", thesis=None):
    rule = stats.VERDICT_RULE.replace(str(stats.MIN_ABS_RHO), f"{min_abs_rho:g}")
    lines = ["# Interrelationship Index (IRI) of the behaviours (thesis 5.7, Table 5-2)", ""]
    if note:
        lines += [note, ""]
    lines += ["Samples: every (database, case) with both values finite. *final*: value at the last run "
              "cycle; *change*: last minus first run cycle.",
              f"Intervals: percentile bootstrap 95 %, {n_boot} resamples of the samples, seed {seed}.",
              f"Verdict rule: {rule}.", "",
              "Behaviours: BS settlement, BR breakage rate, GP ghost particles, FPA force propagation "
              "angle (mean), VR void ratio.", ""]
    for kind in KINDS:
        lines += [f"## {kind} values", "",
                  "| IRI | n | Pearson r [95 % CI] | p | Spearman rho [95 % CI] | p | verdict |",
                  "|---|---|---|---|---|---|---|"]
        for _, r in table[table.kind == kind].iterrows():
            lines.append(f"| {r.iri} | {r.n} | {_fmt(r.pearson_r)} [{_fmt(r.pearson_lo)}, {_fmt(r.pearson_hi)}] | "
                         f"{_fmt(r.pearson_p, 3)} | {_fmt(r.spearman_rho)} [{_fmt(r.spearman_lo)}, "
                         f"{_fmt(r.spearman_hi)}] | {_fmt(r.spearman_p, 3)} | {r.verdict} |")
        lines.append("")
    if thesis is not None:
        lines += thesis_markdown(thesis)
    lines += ["![IRI heatmap](iri_heatmap.png)", ""]
    return "\n".join(lines)


_MARK = {"positive": "+", "negative": "-", "none": "0", "not decidable": "?"}


def fig_heatmap(table):
    """Spearman's rho as a 5x5 matrix per kind; the verdict (+, -, 0, ?) under each number."""
    names = list(IRI_BEHAVIOURS)
    fig = Figure(figsize=(10, 4.6))
    FigureCanvasAgg(fig)
    for p, kind in enumerate(KINDS):
        ax = fig.add_subplot(1, 2, p + 1)
        m = np.full((5, 5), np.nan)
        marks = {}
        for _, r in table[table.kind == kind].iterrows():
            i, j = names.index(r.a), names.index(r.b)
            m[i, j] = m[j, i] = r.spearman_rho
            marks[(i, j)] = marks[(j, i)] = _MARK[r.verdict]
        im = ax.imshow(np.ma.masked_invalid(m), cmap="RdBu_r", vmin=-1, vmax=1)
        for (i, j), mk in marks.items():
            ax.text(j, i, f"{_fmt(m[i, j])}\n{mk}", ha="center", va="center", fontsize=8)
        ax.set_xticks(range(5), names)
        ax.set_yticks(range(5), names)
        ax.set_title(f"Spearman's rho, {kind} values")
        fig.colorbar(im, ax=ax, shrink=0.8)
    fig.suptitle("IRI: + positive, - negative, 0 none, ? not decidable")
    fig.tight_layout()
    return fig


def write_iri(study, out_dir, n_boot=2000, seed=0, min_abs_rho=stats.MIN_ABS_RHO):
    """Write iri.csv, iri_thesis.csv, iri.md and iri_heatmap.png into `out_dir` (atomically);
    return the paths."""
    out = Path(out_dir)
    table = iri_table(study, n_boot=n_boot, seed=seed, min_abs_rho=min_abs_rho)
    thesis = thesis_table(study, n_boot=n_boot, seed=seed, min_abs_rho=min_abs_rho)
    paths = [out / "iri.csv", out / THESIS_CSV, out / "iri.md", out / "iri_heatmap.png"]
    with atomic_path(paths[0]) as tmp:
        table.to_csv(tmp, index=False)
    with atomic_path(paths[1]) as tmp:
        thesis.to_csv(tmp, index=False)
    with atomic_path(paths[2]) as tmp:
        tmp.write_text(iri_markdown(table, n_boot, seed, min_abs_rho, scale_note(study), thesis))
    with atomic_path(paths[3]) as tmp:
        fig_heatmap(table).savefig(tmp, format="png", dpi=130)
    return paths
