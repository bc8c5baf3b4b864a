"""The study's reference record (docs/thesis-scale/, issue 35): read from a run's outputs,
its numbers equal what the study and the records hold, worked out here by hand."""

import argparse
import json
import shutil

import numpy as np
import pandas as pd
import pytest
import xarray as xr
from matplotlib import image

from ballaststudy.config import ConfigError
from ballaststudy.study.cli import register
from ballaststudy.study.breakage import breakage_counts, breakage_timing
from ballaststudy.study.record import _breakage_lines
from ballaststudy.study.timing import database_times, of_databases, read_time_log, stage_table

from .parts import split

MATERIAL = {"material_parameters": {"E_Pa": 1e9, "mu": 0.7}}   # the planted case runs' parameters
TIME_LOG = """\
\tCommand being timed: "snakemake --cores 2 --configfile config/thesis.yaml"
\tUser time (seconds): 7000.50
\tSystem time (seconds): 199.50
\tElapsed (wall clock) time (h:mm:ss or m:ss): 1:02:03
\tMaximum resident set size (kbytes): 2097152
\tExit status: 0
"""


def _record(step, started, finished, params=None):
    return {"step": step, "output": {}, "params": params or {}, "params_sha256": "x", "seed": 0,
            "package": {"name": "ballaststudy", "version": "0", "git": "abc123"}, "host": "h1",
            "machine": {"processor": "CPU X", "cpus": 2, "system": "Linux"},
            "started": started, "finished": finished}


@pytest.fixture(scope="module")
def run(thesis_study, tmp_path_factory):
    """A results folder as the workflow leaves it: study.nc, the IRI and optimisation outputs,
    and planted records: two case runs of 100 s and 200 s (the first beside two outputs), one
    bpm build."""
    path, _ = thesis_study
    res = tmp_path_factory.mktemp("run") / "results"
    res.mkdir()
    shutil.copy(path, res / "study.nc")
    p = argparse.ArgumentParser()
    register(p.add_subparsers(dest="stage"))
    for action, out in (("iri", "study/iri"), ("optimise", "study/report")):
        args = p.parse_args(["study", action, str(res / "study.nc"), "--out", str(res / out), "--resamples", "200"])
        args.func(args)
    a, b = "cases/G_1-1/case0", "cases/G_2-1/case0"       # the folders the workflow gives two cases
    planted = [(f"{a}/metrics.nc", _record("case run", "2026-01-01T00:00:00+00:00", "2026-01-01T00:01:40+00:00",
                                           MATERIAL)),
               (f"{b}/metrics.nc", _record("case run", "2026-01-01T00:01:00+00:00", "2026-01-01T00:04:20+00:00",
                                           MATERIAL)),
               ("bpm/G_1-1.nc", _record("bpm build", "2025-12-31T23:00:00+00:00", "2025-12-31T23:00:30+00:00",
                                        {"bpm": {"radius_min": 2.5e-3, "radius_max": 5e-3}}))]
    planted.append((f"{a}/case.png", planted[0][1]))   # one job's record beside each of its outputs
    for rel, rec in planted:
        side = res / (rel + ".prov.json")
        side.parent.mkdir(parents=True, exist_ok=True)
        side.write_text(json.dumps(dict(rec, output={str(res / rel): "0"})))
    log = res.parent / "thesis.time"
    log.write_text(TIME_LOG)
    return p, res, log


def test_time_log_and_stages(run, tmp_path):
    _, res, log = run
    got = read_time_log(log)
    assert got["wall_s"] == 3723 and got["command"].startswith("snakemake --cores 2")
    assert float(got["user_s"]) + float(got["system_s"]) == 7200
    bad = tmp_path / "not_a_log.txt"
    bad.write_text("hello\n")
    with pytest.raises(ConfigError, match="not_a_log.txt.*Elapsed"):
        read_time_log(bad)
    from ballaststudy.provenance.store import load_records
    stages = stage_table(load_records(res)).set_index("step")
    case = stages.loc["case run"]
    assert case.jobs == 2 and case.core_s == 300 and case.span_s == 260   # 00:00:00 to 00:04:20
    assert stages.loc["bpm build", "core_s"] == 30
    assert stages.index[0] == "bpm build"       # ordered by first start
    times = database_times(load_records(res))   # per database from the output paths
    assert list(times.index) == ["G_1-1", "G_2-1"]
    assert times.loc["G_1-1", "bpm_build_median_s"] == 30 and times.loc["G_1-1", "case_run_median_s"] == 100
    assert times.loc["G_2-1", "case_run_jobs"] == 1 and times.loc["G_2-1", "case_run_median_s"] == 200
    assert times.loc["G_1-1", "core_h"] == 130 / 3600 and np.isnan(times.loc["G_2-1", "bpm_build_median_s"])
    assert times.loc["G_1-1", "processors"] == "CPU X"
    # a part run's folder may hold jobs of databases the study does not hold yet: left out
    kept = of_databases(load_records(res), ["G_1-1"])
    assert sum(r["step"] == "case run" for r in kept.values()) == 2          # beside its two outputs
    assert {r["step"] for r in kept.values()} == {"case run", "bpm build", "study iri", "study optimise"}
    assert list(database_times(kept).index) == ["G_1-1"]


def test_record_numbers_and_files(run, thesis_study, tmp_path):
    p, res, log = run
    _, study = thesis_study
    out = tmp_path / "thesis-scale"
    args = p.parse_args(["study", "record", str(res), "--out", str(out), "--time-log", str(log)])
    args.func(args)
    md = (out / "README.md").read_text()
    table = pd.read_csv(out / "per_database.csv", index_col=0, dtype={"group": str})
    # by hand: each case's value at its last cycle (here every case ran all cycles), mean and sd/sqrt(n)
    final = study["settlement"].values[:, :, -1]
    assert np.allclose(table["settlement"], final.mean(axis=1))
    assert np.allclose(table["settlement_se"], final.std(axis=1, ddof=1) / np.sqrt(final.shape[1]))
    assert (table["settlement_n"] == 4).all() and len(table) == 15
    db, row = table.index[0], table.iloc[0]
    assert f"| {db} | {row.group} | {row.percent_passing_22_4mm:.1f} | 4 | {row.settlement * 1e3:.4g} ± " in md
    # the run: its command, wall and CPU hours from the log; stages from the records
    assert "`snakemake --cores 2 --configfile config/thesis.yaml`: wall 1.03 h, CPU 2.00 h" in md
    assert "| case run | 2 | 5.0 | 4.3 |" in md and "abc123 (bpm build, case run)" in md
    assert "| G_1-1 | - | 30 | - (0) | 1.7 (1) | 0.04 | CPU X |" in md
    assert "| G_2-1 | - | - | - (0) | 3.3 (1) | 0.06 | CPU X |" in md
    assert "CPU X, 2 logical CPUs, Linux" in md and "2.5-5 mm" in md
    assert "Material parameters of the cases: {\"E_Pa\": 1000000000.0, \"mu\": 0.7}." in md
    assert "The thesis' 15 databases: 15 present\n" in md
    assert "- Extent: 15 databases, 4 cases each, up to 12 cycles (cases ran 12 cycles)." in md
    # comparisons beside the thesis, copied from the run's own outputs
    assert pd.read_csv(out / "iri_thesis.csv").equals(pd.read_csv(res / "study/iri/iri_thesis.csv"))
    assert pd.read_csv(out / "findings.csv").equals(pd.read_csv(res / "study/report/findings.csv"))
    assert "## IRI beside thesis Table 5-2" in md and "| IRI_BS-GP | positive:" in md
    assert "| 1 | " in md and "| G_1-5 |" in md          # the optimum table: group 1, thesis' pick
    assert md.count("not decidable at this scale") >= 3   # 4 cases x 12 cycles: below the thesis' scale
    # figures: every report figure, at THUMBNAIL_SCALE of its size
    for name in ("fig_5-1_settlement.png", "fig_5-6_void_ratio.png", "fig_fines_threshold.png"):
        big, small = image.imread(res / "study/report" / name), image.imread(out / name)
        assert abs(small.shape[1] / big.shape[1] - 0.45) < 0.01 and f"]({name})" in md
    assert md.startswith("# The thesis-scale study") and f"ballaststudy study record {res}" in md


def test_record_refuses_an_incomplete_run(run, tmp_path):
    p, res, _ = run
    partial = tmp_path / "partial"
    shutil.copytree(res, partial)
    (partial / "study/iri/iri_thesis.csv").unlink()
    out = tmp_path / "out"
    args = p.parse_args(["study", "record", str(partial), "--out", str(out)])
    with pytest.raises(ConfigError, match="iri_thesis.csv"):
        args.func(args)
    assert not out.exists()


def test_record_of_a_part_names_the_missing_databases(run, thesis_study, tmp_path):
    p, res, _ = run
    _, study = thesis_study
    part = tmp_path / "part"
    shutil.copytree(res, part)
    study.isel(database=slice(2, None)).to_netcdf(part / "study.nc")     # G_1-1 and G_1-2 not run yet
    for action, out in (("iri", "study/iri"), ("optimise", "study/report")):
        args = p.parse_args(["study", action, str(part / "study.nc"), "--out", str(part / out), "--resamples", "100"])
        args.func(args)
    args = p.parse_args(["study", "record", str(part), "--out", str(tmp_path / "out")])
    args.func(args)
    md = (tmp_path / "out" / "README.md").read_text()
    assert "The thesis' 15 databases: 13 present; **missing: G_1-1, G_1-2** (a part of the study)" in md
    assert "no /usr/bin/time log given" in md
    assert len(pd.read_csv(tmp_path / "out" / "per_database.csv")) == 13


def test_breakage_timing_and_counts_on_planted_counts():
    """Four cases with planted cumulative broken counts and bond totals: one breaks 3 elements in
    the static pre-loading and half its final count before cycle 1 ends, one only later, one
    never, one stops after 3 cycles."""
    nan = np.nan
    broken = np.array([[[5, 5, 6, 8, 10], [0, 2, 4, 4, 4]], [[0, 0, 0, 0, 0], [3, 3, 6, nan, nan]]])
    per_cycle = np.array([[[2, 0, 1, 2, 2], [0, 2, 2, 0, 0]], [[0, 0, 0, 0, 0], [1, 0, 3, nan, nan]]])
    bonds = np.array([[1000, 2000], [1200, 1500]])[..., None]
    tension = np.floor(broken / 2)
    dims = ("database", "case", "cycle")
    study = xr.Dataset({"breakage_rate": (dims, broken / bonds), "broken_tension": (dims, tension),
                        "broken_shear": (dims, broken - tension), "breakages_per_cycle": (dims, per_cycle)})
    t = breakage_timing(study, cycles=(1, 3, 5, 10))
    assert (t["cases_broke"], t["cases_ran"]) == (3, 4)
    # by hand: cycle 1: 5/10, 0/4, 3/6; cycle 3: 6/10, 4/4, 6/6; cycle 5: 1, 1 (the short case left out)
    assert t["share"] == {1: 0.5, 3: 1.0, 5: 1.0}
    assert list(t["elements"]) == [1000, 2000, 1500] and list(t["broken"]) == [10, 4, 6]
    total, during = breakage_counts(study)
    assert np.array_equal(total, [[10, 4], [0, 6]]) and np.array_equal(during, [[7, 4], [0, 4]])
    text = "\n".join(_breakage_lines(study))
    assert "1,000-2,000 flat-joint elements per case" in text and "0.05-0.1 % of the breakage rate" in text
    assert "fewer than 10-20 broken elements" in text and "ours broke 6 (median; 4-10)" in text
    # per database means: totals (10 + 4) / 2 = 7 and (0 + 6) / 2 = 3; during (7 + 4) / 2, (0 + 4) / 2
    assert "mean per database (Fig. 5-3): 3-7, of them during the load cycles 2-5.5 " in text


def test_record_from_parts_equals_the_whole_runs(run, thesis_study, tmp_path):
    """A run in two parts (study pack each, study merge, then iri, optimise, record) gives the
    record of the whole run: the same tables, and the records and time logs of both parts."""
    p, res, log = run
    _, study = thesis_study
    whole = tmp_path / "whole"
    args = p.parse_args(["study", "record", str(res), "--out", str(whole)])
    args.func(args)
    first, second = split(study, 8, 8)
    folders = []
    for k, (part, records) in enumerate(((first, res), (second, None))):
        folder = tmp_path / f"run{k}"
        if records is not None:
            shutil.copytree(records, folder)          # the planted records: G_1-1 and G_2-1, in the first part
        folder.mkdir(exist_ok=True)
        if records is not None:                        # a rig record per cycle, which the pack leaves out
            part = part.assign(cycle_steps=part.settlement * 0 + 7000.0)
        part.to_netcdf(folder / "study.nc")
        if records is None:                            # a case of G_3-1 in the second part
            side = folder / "cases/G_3-1/case3/metrics.nc.prov.json"
            side.parent.mkdir(parents=True)
            side.write_text(json.dumps(dict(_record("case run", "2026-01-02T00:00:00+00:00",
                                                    "2026-01-02T00:06:00+00:00", MATERIAL),
                                            machine={"processor": "CPU Y", "cpus": 2, "system": "Linux"},
                                            output={str(folder / "cases/G_3-1/case3/metrics.nc"): "0"})))
        folders.append(tmp_path / "parts" / f"part{k}")
        args = p.parse_args(["study", "pack", str(folder), "--out", str(folders[-1]),
                             *(["--time-log", str(log)] if k == 0 else [])])
        args.func(args)
    assert sorted(x.name for x in folders[0].iterdir()) == ["README.md", "records.json", "study.nc", "thesis.time"]
    with xr.open_dataset(folders[0] / "study.nc") as kept:
        assert "cycle_steps" not in kept and kept.attrs["kept_by_study_pack"].endswith(": cycle_steps")
    readme = (folders[1] / "README.md").read_text()
    assert "- Cases run per database: G_2-4 2, G_2-5 4, G_3-1 4," in readme and "records of its 1 job;" in readme
    merged = tmp_path / "merged"
    args = p.parse_args(["study", "merge", *map(str, folders), "--out", str(merged)])
    args.func(args)
    for action, out in (("iri", "study/iri"), ("optimise", "study/report")):
        args = p.parse_args(["study", action, str(merged / "study.nc"), "--out", str(merged / out),
                             "--resamples", "200"])
        args.func(args)
    out = tmp_path / "from-parts"
    args = p.parse_args(["study", "record", str(merged), "--out", str(out),
                         "--time-log", str(folders[0] / "thesis.time")])
    args.func(args)
    for name in ("per_database.csv", "iri_thesis.csv", "findings.csv"):
        assert pd.read_csv(out / name).equals(pd.read_csv(whole / name)), name
    md = (out / "README.md").read_text()
    assert f"Merged from the parts (`ballaststudy study merge`): {folders[0]}, {folders[1]}" in md
    assert "| G_1-1 | - | 30 | - (0) | 1.7 (1) | 0.04 | CPU X |" in md
    assert "| G_3-1 | - | - | - (0) | 6.0 (1) | 0.10 | CPU Y |" in md     # the second part's machine
    assert "`snakemake --cores 2 --configfile config/thesis.yaml`: wall 1.03 h" in md


def test_pack_refuses_a_time_log_record_would_refuse(run, thesis_study, tmp_path):
    """An empty time log (its /usr/bin/time killed with the run) is refused by pack as record
    refuses it, naming the file, and nothing of the part is written."""
    p, res, log = run
    folder = tmp_path / "run"
    shutil.copytree(res, folder)
    thesis_study[1].to_netcdf(folder / "study.nc")
    empty = tmp_path / "killed.time"
    empty.write_text("")
    args = p.parse_args(["study", "pack", str(folder), "--out", str(tmp_path / "part"),
                         "--time-log", str(log), "--time-log", str(empty)])
    with pytest.raises(ConfigError, match="killed.time.*Elapsed"):
        args.func(args)
    assert not (tmp_path / "part").exists()
