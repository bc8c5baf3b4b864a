"""A study's reference record (issue 35: docs/thesis-scale/): what a run's outputs say
against the thesis' chapter 5, written by the program from the run, never by hand.

Reads the results folder (study.nc, the IRI and optimisation outputs, every provenance
record) and optionally the ``/usr/bin/time -v`` logs of the snakemake commands that made
it; writes README.md, per_database.csv, stages.csv, database_times.csv, the thesis
comparisons as CSV and the figures as small PNGs."""

import json
from pathlib import Path

import numpy as np
import pandas as pd
from PIL import Image

from ..atomic import atomic_copy, atomic_path
from ..inputs import input_dir, input_file, open_netcdf
from ..provenance.store import load_records
from . import optimise, plots, scale, stats
from .aggregate import BEHAVIOURS
from .breakage import THESIS_MAX_MEAN_BREAKAGES, breakage_counts, breakage_timing
from .iri import THESIS_CSV, thesis_markdown
from .parts import PART_RECORDS, load_part_records
from .report import extent_line, scale_banner
from .timing import database_times, of_databases, read_time_log, stage_table

# behaviour, column label, factor to the unit shown
SHOWN = [("settlement", "final settlement (mm)", 1e3), ("breakage_rate", "breakage rate (%)", 100.0),
         ("ghost_particles", "ghost particles (-)", 1.0), ("fpa", "force propagation angle (deg)", 1.0),
         ("void_ratio", "void ratio (-)", 1.0)]
THUMBNAIL_SCALE = 0.45


def _need(path, what):
    return input_file(path, f"expected {what} (run the study first: snakemake ... all)")


def per_database(study):
    """Per database: group, percent passing 22.4 mm, and for each behaviour the mean,
    standard error and n over cases of its value at each case's last run cycle."""
    df = pd.DataFrame(index=pd.Index([str(d) for d in study.database.values], name="database"))
    df["group"] = [str(g) for g in study.group.values]
    df["percent_passing_22_4mm"] = study.percent_passing_22_4mm.values
    for var, _, _ in SHOWN:
        mean, se, n = stats.case_mean_se(stats.final_value(study[var].values))
        df[var], df[f"{var}_se"], df[f"{var}_n"] = mean, se, n
    return df


def _distinct(records, get):
    """The distinct values (as text) of ``get(record)`` over the records, None left out."""
    values = (get(rec) for rec in records.values())
    return sorted({v if isinstance(v, str) else json.dumps(v, sort_keys=True) for v in values if v is not None})


def _run_lines(records, logs, study):
    steps_of = {}
    for rec in records.values():
        steps_of.setdefault(rec["package"].get("git") or "not recorded", set()).add(rec["step"])
    commits = [f"{c} ({', '.join(sorted(steps))})" for c, steps in sorted(steps_of.items())]
    hosts = _distinct(records, lambda r: r.get("host", "not recorded"))
    machines = _distinct(records, lambda r: "{processor}, {cpus} logical CPUs, {system}".format(**r["machine"])
                         if "machine" in r else "not recorded (records older than the machine field)")
    names = {str(d) for d in study.database.values}
    missing = [d for d in scale.THESIS_DATABASES if d not in names]
    lines = ["## The run", "", f"- Extent: {extent_line(study)}",
             f"- The thesis' {len(scale.THESIS_DATABASES)} databases: {len(scale.THESIS_DATABASES) - len(missing)} "
             f"present" + (f"; **missing: {', '.join(missing)}** (a part of the study)" if missing else ""),
             *([f"- Merged from the parts (`ballaststudy study merge`): {study.attrs['merged_from']}"]
               if "merged_from" in study.attrs else []),
             f"- Commit{'s' if len(commits) > 1 else ''} of the outputs (steps): {'; '.join(commits)}",
             f"- Host{'s' if len(hosts) > 1 else ''}: {', '.join(hosts)}; machine: {'; '.join(machines)}"]
    for log in logs:
        lines.append(f"- `{log.get('command', '?')}`: wall {log['wall_s'] / 3600:.2f} h, CPU "
                     f"{(float(log.get('user_s', 'nan')) + float(log.get('system_s', 'nan'))) / 3600:.2f} h, "
                     f"peak memory {float(log.get('max_rss_kB', 'nan')) / 2**20:.2f} GiB, exit status "
                     f"{log.get('exit_status', '?')} ({Path(log['log']).name})")
    if logs:
        lines.append(f"- Wall time of the commands above, in all: {sum(x['wall_s'] for x in logs) / 3600:.2f} h")
    else:
        lines.append("- Wall time: no /usr/bin/time log given (`--time-log`)")
    return lines + [""]


def _stage_lines(stages):
    lines = ["## Where the time went (provenance records)", "",
             "Per step: jobs, core minutes (each job from its record's start to its finish: a case resumed "
             "from a checkpoint counts from its resume; the package import, ~2 s a job, is outside), and the "
             "wall span from the first start to the last finish.", "",
             "| step | jobs | core min | span min | first start | last finish |", "|---|---|---|---|---|---|"]
    lines += [f"| {r.step} | {r.jobs} | {r.core_s / 60:.1f} | {r.span_s / 60:.1f} | {r.first_start} | "
              f"{r.last_finish} |" for r in stages.itertuples()]
    return lines + [f"| all | {int(stages.jobs.sum())} | {stages.core_s.sum() / 60:.1f} | | | |", ""]


def _whole(seconds):
    """Seconds as the records resolve them (whole seconds): < 1 rather than 0; - for no job."""
    return "-" if np.isnan(seconds) else "< 1" if seconds < 1 else f"{seconds:.0f}"


def _minutes(seconds):
    return "-" if np.isnan(seconds) else f"{seconds / 60:.1f}"


def _time_lines(times):
    if times.empty:
        return []
    lines = ["Per database (median per case, since a case resumed from a checkpoint counts from its resume; "
             "jobs in brackets):", "",
             "| database | forms s | bpm s | assembly s per case | loading min per case | core h | processor |",
             "|---|---|---|---|---|---|---|"]
    for db, r in times.iterrows():
        lines.append(f"| {db} | {_whole(r.forms_generate_median_s)} | {_whole(r.bpm_build_median_s)} | "
                     f"{_whole(r.case_assemble_median_s)} ({int(r.case_assemble_jobs)}) | "
                     f"{_minutes(r.case_run_median_s)} ({int(r.case_run_jobs)}) | {r.core_h:.2f} | {r.processors} |")
    return lines + [""]


def _database_lines(table):
    head = " | ".join(label for _, label, _ in SHOWN)
    lines = ["## Per database (mean ± standard error over cases, values at the last run cycle)", "",
             f"| database | group | passing 22.4 mm (%) | cases | {head} |", "|---" * (4 + len(SHOWN)) + "|"]
    for db, r in table.iterrows():
        cells = [f"{r[v] * f:.4g} ± {r[f'{v}_se'] * f:.2g}" for v, _, f in SHOWN]
        lines.append(f"| {db} | {r.group} | {r.percent_passing_22_4mm:.1f} | {int(r.settlement_n)} | "
                     + " | ".join(cells) + " |")
    return lines + [""]


def _finding_lines(findings):
    lines = ["## The thesis' chapter-5 findings", "", "| finding | thesis' claim | our mark | numbers |",
             "|---|---|---|---|"]
    lines += [f"| {f.finding} | {f.claim} | **{f.mark}** | {f.numbers} |" for f in findings.itertuples()]
    return lines + [""]


def _optimum_lines(ranking):
    lines = ["## The optimised aggregate (thesis 5.8)", "",
             f"Rule: {optimise.RECOMMEND_RULE}; ranking: `ranking.csv` of the run.", "",
             "| group | ours (rank) | thesis |", "|---|---|---|"]
    for group, rows in ranking.groupby("group", sort=True):
        ours = rows[rows.recommended]
        pick = ", ".join(f"{d} ({int(r['rank'])})" for d, r in ours.iterrows()) or "none"
        lines.append(f"| {group} | {pick} | {optimise.THESIS_OPTIMUM.get(str(group), 'none named')} |")
    return lines + [""]


def _breakage_lines(study):
    t = breakage_timing(study)
    lines = []
    if t["share"]:
        reached = ", ".join(f"{v * 100:.0f} % by the end of cycle {c}" for c, v in t["share"].items())
        lines.append(f"- When the cases broke (median over the {t['cases_broke']} cases that broke; the static "
                     f"pre-loading counts in cycle 1): {reached} of each case's final breakage rate.")
    if t["elements"].size:
        e = t["elements"]
        lines.append(f"- The unit of breakage: {e.min():,}-{e.max():,} flat-joint elements per case, so one broken "
                     f"element is {100 / e.max():.2g}-{100 / e.min():.2g} % of the breakage rate and the "
                     f"thesis' < 1 % means fewer than {e.min() / 100:.0f}-{e.max() / 100:.0f} broken elements "
                     f"per case; ours broke {int(np.median(t['broken']))} (median; "
                     f"{t['broken'].min()}-{t['broken'].max()}).")
    total, during = (np.nanmean(c, axis=1) for c in breakage_counts(study))
    lines.append(f"- Broken elements per case, mean per database (Fig. 5-3): {np.nanmin(total):.3g}-"
                 f"{np.nanmax(total):.3g}, of them during the load cycles {np.nanmin(during):.3g}-"
                 f"{np.nanmax(during):.3g} (the rest in the static pre-loading); the thesis' highest "
                 f"database mean is just above {THESIS_MAX_MEAN_BREAKAGES:g} (5.3).")
    return lines


def _model_lines(records, study):
    """Numbers that bear on where we differ from the thesis: resolution, material, breakage."""
    bpm = [r["params"].get("bpm", {}) for r in records.values() if r["step"] == "bpm build"]
    radii = sorted({(b["radius_min"] * 1e3, b["radius_max"] * 1e3) for b in bpm if "radius_min" in b})
    material = _distinct({k: r for k, r in records.items() if r["step"] == "case run"},
                         lambda r: r["params"].get("material_parameters") or "Table 4.2's")
    final_br = stats.final_value(study["breakage_rate"].values)
    ran = np.isfinite(final_br)
    broke = int((final_br[ran] > 0).sum())
    lines = ["## What bears on the differences", "",
             f"- Ball radii of the bonded stones (bpm): "
             f"{', '.join(f'{a:g}-{b:g} mm' for a, b in radii) or 'not recorded'}"
             " (the thesis does not give its PFC value).",
             f"- Material parameters of the cases: {'; '.join(material) or 'not recorded'}.",
             f"- Breakage: {broke} of {int(ran.sum())} cases broke at least one bond; final breakage rate at most "
             f"{np.nanmax(final_br) * 100 if ran.any() else float('nan'):.3g} % (the thesis: breakages too rare "
             "for trends, 5.7)."] + _breakage_lines(study)
    return lines + [""]


def _thumbnails(sources, out):
    written = []
    for src in sources:
        with Image.open(src) as im, atomic_path(out / src.name) as tmp:
            im.thumbnail((round(im.width * THUMBNAIL_SCALE), round(im.height * THUMBNAIL_SCALE)),
                         Image.Resampling.LANCZOS)
            im.save(tmp, format="PNG", optimize=True)
        written.append(out / src.name)
    return written


def _banner(study):
    text = scale_banner(study)
    return [text, ""] if text else []


def write_record(results_dir, out_dir, time_logs=(), command=None):
    """Write the record of the study in ``results_dir`` into ``out_dir``; return the paths."""
    results, out = input_dir(results_dir, "expected a results folder"), Path(out_dir)
    study = open_netcdf(_need(results / "study.nc", "study.nc"), "study", require=tuple(BEHAVIOURS))
    iri_thesis = pd.read_csv(_need(results / "study" / "iri" / THESIS_CSV, "the IRI stage's thesis table"))
    report_dir = results / "study" / "report"
    findings = pd.read_csv(_need(report_dir / "findings.csv", "the optimisation report's findings"))
    ranking = pd.read_csv(_need(report_dir / "ranking.csv", "the optimisation report's ranking"), index_col=0)
    records = load_records(results)
    if (results / PART_RECORDS).is_file():      # a results folder merged from parts (study merge)
        records.update(load_part_records(results / PART_RECORDS))
    records = of_databases(records, [str(d) for d in study.database.values])
    logs = [read_time_log(p) for p in time_logs]
    figures = [_need(report_dir / name, "a figure of the optimisation report") for name in plots.figure_names()]
    table, stages, times = per_database(study), stage_table(records), database_times(records)
    out.mkdir(parents=True, exist_ok=True)                           # everything read: now write
    written = _thumbnails(figures, out)
    for name, frame, index in (("per_database.csv", table, True), ("stages.csv", stages, False),
                               ("database_times.csv", times, True)):
        with atomic_path(out / name) as tmp:
            frame.to_csv(tmp, index=index)
        written.append(out / name)
    written += [atomic_copy(results / "study" / "iri" / THESIS_CSV, out / THESIS_CSV),
                atomic_copy(report_dir / "findings.csv", out / "findings.csv")]
    lines = ["# The thesis-scale study beside Wang 2018, chapter 5", "",
             f"Written by `{command or 'ballaststudy study record'}` from the run's outputs in `{results}`; "
             "regenerate it, do not edit it.", ""]
    lines += _banner(study) + _run_lines(records, logs, study) + _stage_lines(stages) + _time_lines(times)
    lines += _database_lines(table)
    lines += thesis_markdown(iri_thesis, "## IRI beside thesis Table 5-2") + _finding_lines(findings)
    lines += _optimum_lines(ranking) + _model_lines(records, study)
    lines += ["## Figures (Figs. 5-1 to 5-6 and the fines threshold)", "",
              f"Curves: mean over cases; bands: {plots.BAND}.", ""]
    lines += [f"![{p.stem}]({p.name})" for p in written if p.suffix == ".png"] + [""]
    with atomic_path(out / "README.md") as tmp:
        tmp.write_text("\n".join(lines))
    return [out / "README.md"] + written

