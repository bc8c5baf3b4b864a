"""Why the thesis' headline does or does not reproduce, by experiment: a screening
of the settings where our set-up departs from the thesis' text, one level per study part
(config/differences/<level>.yaml), read on the two contrasts that carry the fines jump.

Per level: S(G_1-1) - S(G_1-2) and S(G_2-5) - S(G_2-4), S the final settlement's mean over
cases, with 90 % bootstrap intervals (cases resampled within databases, as the study's
findings do); each pair under the study's jump rule (optimise.py: S(fine) - JUMP_FACTOR x
S(neighbour) above 0 with 90 % confidence: the jump holds); box_test's S; the breakage
rate; the assembly's state (cases with a stage at its guard, the stones' force ratio when
loading began); the part's core-hours from its provenance records. The confirmation: the
levels that open a contrast run on the four databases at the thesis' length (10 cases x 1000
cycles, config/differences/confirm_<level>.yaml), read the same way at their last cycle,
their settlement curves beside the ends of Fig. 5-1's fine gradings."""
from pathlib import Path

import numpy as np
import pandas as pd
import xarray as xr
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from ..atomic import atomic_path
from ..config import ConfigError
from ..inputs import input_file
from . import stats
from .optimise import JUMP_FACTOR, three_way
from .parts import PART_RECORDS, PART_STUDY, load_part_records
from .timing import stage_table

CONTRASTS = (("G_1-1", "G_1-2"), ("G_2-5", "G_2-4"))   # (fine grading, its neighbour): thesis 5.2
REFERENCE = "box_test"
LEVEL = 0.90
REFERENCE_LEVEL = "ours"
# Fig. 5-1's settlement at 1000 cycles of the two fine gradings, as issue 73 reads it off the
# figure ("far above the rest of their groups", thesis 5.2); the text gives no numbers
THESIS_FIG_5_1_END_M = {"G_1-1": 0.030, "G_2-5": 0.006}
THESIS_CYCLES = 1000


def _final(study, name):
    """(database, case) final values of a behaviour."""
    return stats.final_value(study[name].values)


def settlements(study):
    """{what: (database, case) final settlement}: from cycle 0 (the study's) and from the
    start of the static pre-loading (the seating added: the pressing ball's displacement,
    thesis 4.5.1)."""
    out = {"from cycle 0": _final(study, "settlement")}
    if "seating" in study and np.isfinite(study.seating.values).any():
        out["with the seating"] = out["from cycle 0"] + study.seating.values
    return out


def contrast_rows(study, settlement, n_boot=2000, seed=0):
    """Per contrast of the (database, case) final ``settlement``: S of both databases, the
    difference with its 90 % interval, the jump statistic's interval and the rule's mark
    (not decidable where a database is missing or has fewer than 2 cases)."""
    dbs = [str(d) for d in study.database.values]
    boot = stats.bootstrap_database_means(settlement, n_boot, np.random.default_rng(seed))
    rows = []
    for fine, neighbour in CONTRASTS:
        row = {"contrast": f"S({fine}) - S({neighbour})"}
        if fine not in dbs or neighbour not in dbs:
            rows.append({**row, "mark": "not decidable"})
            continue
        i, j = dbs.index(fine), dbs.index(neighbour)
        n = np.isfinite(settlement[[i, j]]).sum(axis=1)
        s_fine, s_neighbour = np.nanmean(settlement[i]), np.nanmean(settlement[j])
        lo, hi = stats.interval(boot[:, i] - boot[:, j], LEVEL)
        jlo, jhi = stats.interval(boot[:, i] - JUMP_FACTOR * boot[:, j], LEVEL)
        rows.append({**row, "S_fine_m": s_fine, "S_neighbour_m": s_neighbour, "difference_m": s_fine - s_neighbour,
                     "difference_lo_m": lo, "difference_hi_m": hi, "jump_lo_m": jlo, "jump_hi_m": jhi,
                     "mark": three_way(jlo, jhi) if n.min() >= 2 else "not decidable"})
    return rows


def state_row(study):
    """The level's breakage, assembly state and extent."""
    ran = study.cycles_run.values > 0
    breakage = _final(study, "breakage_rate")[ran]
    dbs = [str(d) for d in study.database.values]
    ref = np.nanmean(_final(study, "settlement")[dbs.index(REFERENCE)]) if REFERENCE in dbs else np.nan
    at_limit = study.assembly_stages_at_limit.values[ran]
    ratio = study.assembly_force_ratio.values[ran] if "assembly_force_ratio" in study else np.full(ran.sum(), np.nan)
    return {"cases": int(ran.sum()), "cycles": int(study.cycles_run.values[ran].min()) if ran.any() else 0,
            "S_box_test_m": ref, "breakage_rate_pct": 100 * float(np.nanmean(breakage)),
            "cases_at_guard": int((at_limit > 0).sum()),
            "force_ratio_median": float(np.nanmedian(ratio)) if np.isfinite(ratio).any() else float("nan"),
            "force_ratio_max": float(np.nanmax(ratio)) if np.isfinite(ratio).any() else float("nan")}


def core_hours(records):
    """Core-hours of the part's jobs (each job from its start to its finish)."""
    table = stage_table(records)
    return float(table.core_s.sum() / 3600) if len(table) else float("nan")


def read_level(part_dir):
    """(study Dataset, records) of one level's part folder (study pack)."""
    part = Path(part_dir)
    with xr.open_dataset(input_file(part / PART_STUDY, "expected a part's study.nc (ballaststudy study pack)")) as ds:
        study = ds.load()
    for name in ("settlement", "breakage_rate", "cycles_run", "assembly_stages_at_limit"):
        if name not in study:
            raise ConfigError(part / PART_STUDY, name, "missing; expected a study part (ballaststudy study pack)")
    return study, load_part_records(part / PART_RECORDS)


def cut_at(study, cycle):
    """The study as if its cases had stopped after ``cycle`` (a longer run read at the
    screening's length, e.g. the thesis-scale study at 300 cycles)."""
    cut = study.sel(cycle=study.cycle <= cycle)
    cut["cycles_run"] = np.minimum(study.cycles_run, cycle + 1).astype(study.cycles_run.dtype)
    return cut


def screening_table(levels, n_boot=2000, seed=0, at_cycle=None):
    """One row per (level, settlement, contrast) from {level: part folder}; each case read
    at its last cycle, or at ``at_cycle`` where it ran longer."""
    rows = []
    for level, part in levels.items():
        study, records = read_level(part)
        if at_cycle is not None:
            study = cut_at(study, at_cycle)
        state = {**state_row(study), "core_hours": core_hours(records)}
        for what, settlement in settlements(study).items():
            for c in contrast_rows(study, settlement, n_boot, seed):
                rows.append({"level": level, "settlement": what, **c, **state})
    return pd.DataFrame(rows)


def _mm(v):
    return "" if not np.isfinite(v) else f"{1e3 * v:.2f}"


HEADER = ("| level | settlement | contrast | S fine (mm) | S neighbour (mm) | difference (mm) [90 %] | jump | "
          "box_test S (mm) | breakage (%) | cases at a guard | force ratio at loading (median / max) | "
          "cases x cycles | core-h |")


def _table_lines(table):
    lines = [HEADER, "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in table.itertuples():
        diff = (f"{_mm(r.difference_m)} [{_mm(r.difference_lo_m)}, {_mm(r.difference_hi_m)}]"
                if "difference_m" in table and np.isfinite(r.difference_m) else "")
        lines.append(f"| {r.level} | {r.settlement} | {r.contrast} | {_mm(getattr(r, 'S_fine_m', np.nan))} | "
                     f"{_mm(getattr(r, 'S_neighbour_m', np.nan))} | {diff} | {r.mark} | {_mm(r.S_box_test_m)} | "
                     f"{r.breakage_rate_pct:.2f} | {r.cases_at_guard} | {r.force_ratio_median:.2g} / "
                     f"{r.force_ratio_max:.2g} | {r.cases} x {r.cycles} | {r.core_hours:.2f} |")
    return lines


def _verdicts(table, among):
    lines = []
    for (contrast, what), rows in table.groupby(["contrast", "settlement"], sort=False):
        held = rows.level[rows.mark == "holds"].tolist()
        lines.append(f"- {contrast}, settlement {what}: the jump " + (
            f"holds under {', '.join(held)}." if held else f"holds under none of the {among}."))
    return lines


def markdown(table, command, confirmation=None):
    """differences.md: the screening table, the confirmation's where given, and a verdict
    per headline finding."""
    lines = ["# The thesis' headline under the settings its text allows", "",
             f"Written by `{command}` from the levels' study parts; regenerate it, do not edit it.", "",
             f"Contrast: S(fine) - S(neighbour), S the final settlement's mean over cases, {LEVEL:.0%} "
             "bootstrap interval (cases resampled within databases). Jump rule (the study's finding): "
             f"S(fine) - {JUMP_FACTOR:g} x S(neighbour) above 0 with {LEVEL:.0%} confidence.", "",
             "Settlement from cycle 0 is the study's; with the seating it counts from the start of the static "
             "pre-loading, as the pressing ball's displacement (thesis 4.5.1) would.", "",
             *_table_lines(table), "", "## Verdicts", "", *_verdicts(table, "levels screened")]
    spent = table.drop_duplicates("level").core_hours.sum()
    if confirmation is not None and len(confirmation):
        ends = ", ".join(f"{db} {_mm(v)} mm" for db, v in THESIS_FIG_5_1_END_M.items())
        lines += ["", "## Confirmation at the thesis' length", "",
                  "The levels confirmed, each on the contrasts' databases at its own cases and cycles, read at "
                  f"their last cycle. Fig. 5-1's fine gradings end at about {ends} (read off the figure).", "",
                  *_table_lines(confirmation), "", *_verdicts(confirmation, "levels confirmed"), "",
                  "![settlement curves](differences_confirmation.png)"]
        spent += confirmation.drop_duplicates("level").core_hours.sum()
    lines += ["", f"Core-hours in all: {spent:.1f}.", "", "![contrasts](differences.png)", ""]
    return "\n".join(lines)


def figure(table, path):
    """Per contrast, each level's difference (settlement from cycle 0) with its interval."""
    contrasts = list(dict.fromkeys(table.contrast))
    fig = Figure(figsize=(5 * len(contrasts), 0.5 * table.level.nunique() + 1.5))
    FigureCanvasAgg(fig)
    for k, c in enumerate(contrasts):
        ax = fig.add_subplot(1, len(contrasts), k + 1)
        rows = table[(table.contrast == c) & (table.settlement == "from cycle 0")].reset_index(drop=True)
        y = np.arange(len(rows))
        d = 1e3 * rows.get("difference_m", pd.Series(np.nan, index=rows.index))
        lo = 1e3 * rows.get("difference_lo_m", pd.Series(np.nan, index=rows.index))
        hi = 1e3 * rows.get("difference_hi_m", pd.Series(np.nan, index=rows.index))
        ax.errorbar(d, y, xerr=[d - lo, hi - d], fmt="o", capsize=3)
        ax.axvline(0.0, color="0.6", lw=0.8)
        ax.set_yticks(y, rows.level)
        ax.set_xlabel(f"{c} (mm), {LEVEL:.0%} interval")
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    return path


def curves_figure(confirm, path):
    """Per confirmation level, each contrast database's mean settlement over the cycles with
    its cases' range, and the ends of Fig. 5-1's fine gradings."""
    fig = Figure(figsize=(5 * len(confirm), 3.8))
    FigureCanvasAgg(fig)
    for k, (level, part) in enumerate(confirm.items()):
        study, _ = read_level(part)
        ax = fig.add_subplot(1, len(confirm), k + 1, sharey=fig.axes[0] if k else None)
        dbs = [str(d) for d in study.database.values]
        for j, db in enumerate(d for pair in CONTRASTS for d in pair if d in dbs):
            curves = 1e3 * study.settlement.values[dbs.index(db)]
            ran = np.isfinite(curves).any(axis=1)
            n = study.cycle.values + 1
            ax.plot(n, np.nanmean(curves[ran], axis=0), color=f"C{j}", label=db)
            ax.fill_between(n, np.nanmin(curves[ran], axis=0), np.nanmax(curves[ran], axis=0), color=f"C{j}",
                            alpha=0.2, lw=0)
            if db in THESIS_FIG_5_1_END_M:
                ax.plot([THESIS_CYCLES], [1e3 * THESIS_FIG_5_1_END_M[db]], marker="*", ms=11, color=f"C{j}", ls="none")
        ax.set_title(f"{level} (stars: Fig. 5-1's ends)", fontsize=9)
        ax.set_xlabel("load cycle")
        ax.set_ylabel("settlement (mm)")
        ax.legend(fontsize=8)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    return path


def write_differences(levels, out_dir, command, n_boot=2000, seed=0, at_cycle=None, confirm=None):
    """differences.csv, differences.md and differences.png in ``out_dir`` from the screening's
    {level: part}; with ``confirm`` ({level: part} at the thesis' length) also
    differences_confirmation.csv and .png. Returns the paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    table = screening_table(levels, n_boot, seed, at_cycle)
    confirmation = screening_table(confirm, n_boot, seed) if confirm else None
    paths = [_csv(table, out / "differences.csv")]
    if confirm:
        paths += [_csv(confirmation, out / "differences_confirmation.csv"),
                  curves_figure(confirm, out / "differences_confirmation.png")]
    with atomic_path(out / "differences.md") as tmp:
        tmp.write_text(markdown(table, command, confirmation))
    return paths + [out / "differences.md", figure(table, out / "differences.png")]


def _csv(table, path):
    with atomic_path(path) as tmp:
        table.to_csv(tmp, index=False)
    return path
