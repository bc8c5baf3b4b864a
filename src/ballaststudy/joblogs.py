"""The reasons of a failed Snakemake run, from its job logs: every rule sends a job's output
to its log, so without this a bad input met inside a job shows only as "Error in rule ...";
the Snakefile's `onerror` prints these lines, the same ones the command line prints."""

from pathlib import Path

PREFIX = "ballaststudy: error: "


def error_lines(log_dir, since):
    """The `ballaststudy: error:` lines of the logs under `log_dir` written at or after `since`
    (seconds since the epoch), oldest log first."""
    logs = [p for p in Path(log_dir).rglob("*.log") if p.stat().st_mtime >= since]
    lines = []
    for log in sorted(logs, key=lambda p: p.stat().st_mtime):
        lines += [ln.strip() for ln in log.read_text(errors="replace").splitlines() if ln.startswith(PREFIX)]
    return lines
