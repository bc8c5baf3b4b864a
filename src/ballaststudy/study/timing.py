"""How long a study run took: the snakemake commands' ``/usr/bin/time -v`` logs, and per
step and per database from the provenance records (each job's start to finish)."""

import datetime as dt
import json
from pathlib import Path

import numpy as np
import pandas as pd

from ..inputs import input_file
from ..schema import ConfigError

# /usr/bin/time -v's lines we keep: label in the log -> our key
TIME_LINES = {"Command being timed": "command", "Elapsed (wall clock) time (h:mm:ss or m:ss)": "wall",
              "User time (seconds)": "user_s", "System time (seconds)": "system_s",
              "Maximum resident set size (kbytes)": "max_rss_kB", "Exit status": "exit_status"}


def _wall_seconds(text):
    """h:mm:ss or m:ss(.ss) -> seconds."""
    parts = [float(p) for p in text.split(":")]
    return sum(p * 60 ** k for k, p in enumerate(reversed(parts)))


def read_time_log(path):
    """The run's command, wall, CPU seconds, peak memory and exit status from a
    ``/usr/bin/time -v`` log (ConfigError naming the file if it holds none)."""
    found = {}
    text = input_file(path, "expected a /usr/bin/time -v log of the snakemake command").read_text(errors="replace")
    for line in text.splitlines():
        label, sep, value = line.strip().rpartition(": ")
        if sep and label in TIME_LINES:
            found[TIME_LINES[label]] = value.strip().strip('"')
    if "wall" not in found:
        raise ConfigError(path, None, "no 'Elapsed (wall clock) time' line: not a /usr/bin/time -v log")
    found["wall_s"] = _wall_seconds(found.pop("wall"))
    found["log"] = str(path)
    return found


def _seconds(record):
    t0, t1 = (dt.datetime.fromisoformat(record[k]) for k in ("started", "finished"))
    return (t1 - t0).total_seconds()


def _jobs(records):
    """One record per job: a step writes the same record beside each of its outputs."""
    jobs = {}
    for rec in records.values():
        if "started" in rec:
            key = (rec["step"], rec["started"], rec["finished"], json.dumps(rec.get("inputs"), sort_keys=True))
            jobs[key] = rec
    return list(jobs.values())


def stage_table(records):
    """Per step of the provenance records: jobs, core seconds (sum of each job's start to
    finish), first start, last finish and the wall span between them."""
    rows = {}
    for rec in _jobs(records):
        row = rows.setdefault(rec["step"], {"step": rec["step"], "jobs": 0, "core_s": 0.0,
                                            "first_start": rec["started"], "last_finish": rec["finished"]})
        row["jobs"] += 1
        row["core_s"] += _seconds(rec)
        row["first_start"] = min(row["first_start"], rec["started"])
        row["last_finish"] = max(row["last_finish"], rec["finished"])
    df = pd.DataFrame(list(rows.values()), columns=["step", "jobs", "core_s", "first_start", "last_finish"])
    df["span_s"] = [_seconds({"started": a, "finished": b}) for a, b in zip(df.first_start, df.last_finish)]
    return df.sort_values("first_start").reset_index(drop=True)


# steps whose jobs make one database's inputs (output <dir>/<database>.nc) or one of its cases
# (output cases/<database>/case<k>/...)
DATABASE_STEPS = {"forms generate": "forms", "bpm build": "bpm"}
CASE_STEPS = ("case assemble", "case run")


def database_of(rec):
    """The database a job worked for, from its first output's path (None for study steps)."""
    path = Path(sorted(rec.get("output", {}))[0]) if rec.get("output") else None
    if path is None:
        return None
    if rec["step"] in DATABASE_STEPS and path.parent.name == DATABASE_STEPS[rec["step"]]:
        return path.name.split(".")[0]
    parts = path.parts
    if rec["step"] in CASE_STEPS and "cases" in parts[:-2]:
        return parts[len(parts) - parts[::-1].index("cases")]      # the folder after the last "cases"
    return None


def of_databases(records, names):
    """The records of the study steps and of the jobs that worked for the named databases
    (a results folder may hold jobs of databases that a part run has not reached yet)."""
    return {path: rec for path, rec in records.items() if database_of(rec) in (None, *names)}


def database_times(records):
    """Per database: seconds of its form database and BPM library, and per case the median
    seconds of assembly and of the loading run (cases resumed from a checkpoint count from
    their resume, so the median), with the number of jobs, the core hours in all and the
    processors that ran them."""
    seconds, machines = {}, {}
    for rec in _jobs(records):
        db = database_of(rec)
        if db is not None:
            seconds.setdefault(db, {}).setdefault(rec["step"], []).append(_seconds(rec))
            machines.setdefault(db, set()).add(rec.get("machine", {}).get("processor", "not recorded"))
    rows = []
    for db, steps in sorted(seconds.items()):
        row = {"database": db}
        for step in (*DATABASE_STEPS, *CASE_STEPS):
            got = steps.get(step, [])
            key = step.replace(" ", "_")
            row[f"{key}_jobs"] = len(got)
            row[f"{key}_median_s"] = float(np.median(got)) if got else np.nan
        row["core_h"] = sum(sum(v) for v in steps.values()) / 3600
        row["processors"] = "; ".join(sorted(machines[db]))    # parts may run on machines 2x apart
        rows.append(row)
    return pd.DataFrame(rows).set_index("database") if rows else pd.DataFrame()
