"""The Snakemake workflow on a tiny study: runs, reruns only what a config edit touches,
does nothing when nothing changed, and the SLURM profile passes a dry run. The fast tests
run the forms stage for real and the rest of the chain as a dry run; the slow test runs the
whole chain on one database, one case, two cycles."""

import contextlib
import re
import shutil
import subprocess
from pathlib import Path

import pytest
import xarray as xr
import yaml

ROOT = Path(__file__).resolve().parents[2]


def _snakemake(cwd, *args):
    out = subprocess.run(["snakemake", "--cores", "2", *args], cwd=cwd, capture_output=True, text=True)
    assert out.returncode == 0, out.stdout + out.stderr
    return out.stdout + out.stderr


def _jobs(log):
    """{rule: count} from the dry-run job table."""
    return {m[1]: int(m[2]) for m in re.finditer(r"^(\w+)\s+(\d+)$", log, re.M) if m[1] != "total"}


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    d = tmp_path_factory.mktemp("study")
    shutil.copytree(ROOT / "workflow", d / "workflow", symlinks=False)
    shutil.copytree(ROOT / "profiles", d / "profiles")
    (d / "config").mkdir()
    dbs = yaml.safe_load((ROOT / "config" / "databases.yaml").read_text())
    dbs["defaults"]["mass_kg"] = 3
    dbs["databases"] = {k: dbs["databases"][k] for k in ("G_1-5", "box_test")}
    (d / "config" / "databases.yaml").write_text(yaml.safe_dump(dbs))
    cfg = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    cfg["study"]["cases_per_database"] = 1
    cfg["rig"]["box"]["loading"]["cycles"] = 2
    (d / "config" / "config.yaml").write_text(yaml.safe_dump(cfg))
    _snakemake(d, "forms_report")
    return d


def _unrecorded(results):
    """Files under `results` that no provenance record lists as an output (logs excepted;
    report.html is Snakemake's own)."""
    from ballaststudy.provenance.store import load_records
    recorded = {str((results.parent / p).resolve()) for p in load_records(results)}   # paths relative to the run folder
    return [p for p in results.rglob("*") if p.is_file() and not p.name.endswith(".prov.json")
            and "logs" not in p.relative_to(results).parts and str(p.resolve()) not in recorded]


def test_first_run_makes_every_output(study):
    for name in ("G_1-5", "box_test"):
        assert (study / "results" / "forms" / f"{name}.nc").is_file()
        assert (study / "results" / "forms" / f"{name}.stl.zip").is_file()
    assert (study / "results" / "forms" / "report" / "validation.csv").is_file()
    assert not _unrecorded(study / "results")     # STL archives and report figures too


def test_rerun_with_nothing_changed_does_nothing(study):
    assert "Nothing to be done" in _snakemake(study, "-n", "forms_report")


def test_whole_chain_is_planned(study):
    jobs = _jobs(_snakemake(study, "-n"))
    assert jobs == {"bpm_build": 2, "case_assemble": 2, "case_run": 2, "study_aggregate": 1,
                    "study_iri": 1, "study_optimise": 1, "all": 1}, jobs


def test_parametric_study_is_planned(study):
    """`snakemake parametric`: 5 F_str_co and 4 mu values and the design sets, parametric.cases
    runs each on the study's assembled cases, one report; not part of `all`."""
    cfg = yaml.safe_load((study / "config" / "config.yaml").read_text())
    par = cfg["parametric"]
    jobs = _jobs(_snakemake(study, "-n", "parametric"))
    n_values = len(par["F_str_co"]) + len(par["mu"]) + par["design_sets"]
    assert par["design_sets"] >= 4
    assert jobs == {"parametric_setting": n_values, "parametric_run": n_values * par["cases"],
                    "case_assemble": par["cases"], "bpm_build": 1, "parametric": 1}, jobs


def test_a_stress_mapping_plans_its_sets_strength_envelope_first(study):
    """stress_mapping strength_ratio: measured_sim and calibrate read the strength envelope of
    their own specimen set (strength_case at every p of the measured tests, then
    strength_envelope) and pass it on; none plans neither. The lab envelope is planted."""
    tests = study / "config" / "measured_planted"
    tests.mkdir(exist_ok=True)
    (tests / "ax.dat").write_text("1, 0.01\n2, 0.02\n5, 0.03\n")
    for p in (30, 45, 60):
        (tests / f"p{p}.yaml").write_text(yaml.safe_dump(dict(
            source="planted", rig="triaxial", confining_pressure_kPa=p, deviator_max_kPa=230,
            frequency_Hz=5, curves=[dict(file="ax.dat", quantity="axial_strain", units="1",
                                         sign="compression_positive")])))

    def planted(cfg, kind):
        cfg["measured"]["tests_dir"] = "config/measured_planted"
        cfg["calibration"]["targets"] = ["p30"]
        cfg["loop"]["targets"] = ["p30", "p45", "p60"]
        cfg["stress_mapping"] = {"kind": kind, "lab_envelope": {
            "citation": "planted", "confining_pressure_kPa": [10.0, 100.0], "peak_deviator_kPa": [300.0, 900.0]}}

    with _edited(study / "config" / "config.yaml", lambda cfg: planted(cfg, "strength_ratio")):
        log = _snakemake(study, "-n", "-p", "measured_sim", "calibrate", "loop")
    jobs = _jobs(log)
    cases = yaml.safe_load((study / "config" / "config.yaml").read_text())["strength"]["cases"]
    assert jobs["strength_case"] == 3 * cases and jobs["strength_envelope"] == 1, jobs
    envelope = "--strength-envelope results/strength/biaxial_small/envelope.nc"
    assert log.count(envelope) == 3 + 1 + 1, log       # measured_sim_run per test, calibrate, loop
    with _edited(study / "config" / "config.yaml", lambda cfg: planted(cfg, "none")):
        log = _snakemake(study, "-n", "-p", "measured_sim", "calibrate", "loop")
    assert "strength_case" not in _jobs(log) and "--strength-envelope" not in log
    shutil.rmtree(tests)


def _loading(cfg):
    return cfg["rig"]["box"]["loading"]


@contextlib.contextmanager
def _edited(path, change):
    """The YAML file at `path` with `change(data)` applied, restored afterwards."""
    original = path.read_text()
    data = yaml.safe_load(original)
    change(data)
    path.write_text(yaml.safe_dump(data))
    try:
        yield
    finally:
        path.write_text(original)


def test_jobs_read_the_config_several_files_and_overrides_make(study):
    """A level's overlay on a study's config (--configfile A B) and --config KEY=VALUE reach
    the jobs, which read one file: the config Snakemake made of them, written into
    results_dir when the jobs start (a dry run writes nothing)."""
    import json

    from ballaststudy.config import database_seed, form_params, load_databases
    (study / "overlay.yaml").write_text("results_dir: overlaid\nforms: {n_vertices: 24}\n")
    target = "overlaid/forms/G_1-5.nc"
    _snakemake(study, "-n", target, "--configfile", "config/config.yaml", "overlay.yaml")
    assert not (study / "overlaid").exists()
    _snakemake(study, target, "--configfile", "config/config.yaml", "overlay.yaml")
    jobs = yaml.safe_load((study / "overlaid" / "config.yaml").read_text())
    assert jobs["forms"]["n_vertices"] == 24 and jobs["study"]["cases_per_database"] == 1
    with xr.open_dataset(study / target) as ds:
        assert json.loads(ds.attrs["form_params"])["n_vertices"] == 24
    _snakemake(study, "seeded/forms/G_1-5.nc", "--config", "seed=11", "results_dir=seeded")
    cfg = yaml.safe_load((study / "config" / "config.yaml").read_text())
    definition = load_databases(study / "config" / "databases.yaml", form_params(cfg))["G_1-5"]
    with xr.open_dataset(study / "seeded" / "forms" / "G_1-5.nc") as ds:
        assert int(ds.attrs["seed"]) == database_seed(11, "G_1-5", definition)


def test_editing_one_database_reruns_only_it(study):
    with _edited(study / "config" / "databases.yaml",
                 lambda d: d["databases"]["box_test"].update(shape_index=20)):
        jobs = _jobs(_snakemake(study, "-n", "forms_report"))
    assert jobs.get("forms_generate") == 1, jobs
    assert jobs.get("forms_report") == 1, jobs


def test_the_loadings_control_interval_reassembles_box_cases(study):
    """rig.box.loading.control_every also sets the plate's moves as it is lowered onto the
    stones in the assembly: a change reassembles the cases."""
    assembled = "results/cases/box_test/case0/assembled.nc"
    _snakemake(study, assembled)
    assert _jobs(_snakemake(study, "-n", assembled)) == {}
    with _edited(study / "config" / "config.yaml", lambda c: _loading(c).update(control_every=20)):
        jobs = _jobs(_snakemake(study, "-n", assembled))
    assert jobs.get("case_assemble") == 1, jobs


def test_editing_form_settings_reruns_every_database(study):
    with _edited(study / "config" / "config.yaml", lambda c: c["forms"].update(n_vertices=24)):
        jobs = _jobs(_snakemake(study, "-n", "forms_report"))
    assert jobs.get("forms_generate") == 2, jobs


@pytest.mark.parametrize("file, change, key", [
    ("databases.yaml", lambda d: d["databases"]["G_1-5"].update(mass_kg=-1), "databases.G_1-5.mass_kg"),
    ("config.yaml", lambda c: _loading(c).update(cycles=-5), "rig.box.loading.cycles"),
    ("config.yaml", lambda c: c.update(databases=["G_9-9"]), "databases"),
    ("config.yaml", lambda c: _loading(c).update(cyclic_min_kN=50.0),
     "rig.box.loading.cyclic_min_kN"),
    ("config.yaml", lambda c: c["rig"]["box"]["assembly"].update(cycles=5),
     "rig.box.assembly.cycles"),
    # the examples: NaN / Inf blamed on the right file and key
    ("config.yaml", lambda c: c["bpm"].update(porosity=float("nan")), "bpm.porosity"),
    ("config.yaml", lambda c: c["forms"].update(ab_ratio_max=float("nan")), "forms.ab_ratio_max"),
    ("config.yaml", lambda c: _loading(c).update(static_loads_kN=[10.0, float("inf")]),
     "rig.box.loading.static_loads_kN[1]"),
    ("databases.yaml", lambda d: d["defaults"].update(mass_kg=float("inf")), "defaults.mass_kg"),
    ("config.yaml", lambda c: _loading(c).update(cycels=5), "rig.box.loading.cycels: unknown key; did you mean 'cycles'"),
    ("config.yaml", lambda c: _loading(c).update(cycles="ten"), "rig.box.loading.cycles: 'ten' is not allowed; "
     "allowed: an integer >= 1"),
    ("config.yaml", lambda c: c.clear(), "seed: missing"),
    ("config.yaml", lambda c: c.update(executor={"kind": "condor"}), "executor.kind: 'condor' is not allowed"),
    ("config.yaml", lambda c: c.update(executor={"kind": "dask"}), "executor.scheduler_address: missing"),
    ("config.yaml", lambda c: c.update(executor={"kind": "slurm", "cores": 4, "walltime_min": 60}),
     "executor.memory_GB: missing"),
])
def test_bad_config_is_rejected_before_any_job(study, file, change, key):
    """One line naming file and key, exit 2, no traceback (Snakemake shows our message)."""
    with _edited(study / "config" / file, change):
        out = subprocess.run(["snakemake", "--cores", "1", "-n"], cwd=study, capture_output=True, text=True)
    lines = out.stderr.strip().splitlines()
    assert out.returncode == 2, out.stdout + out.stderr
    assert len(lines) == 1 and lines[0].startswith("ballaststudy: error: "), out.stderr
    assert f"{file}: {key}" in lines[0], out.stderr


@pytest.mark.parametrize("content", [b"seed: [1,\n", b"\x00\xff\xfe binary"])
def test_unreadable_config_file_is_one_line(study, content):
    path = study / "config" / "config.yaml"
    saved = path.read_bytes()
    try:
        path.write_bytes(content)
        out = subprocess.run(["snakemake", "--cores", "1", "-n"], cwd=study, capture_output=True, text=True)
    finally:
        path.write_bytes(saved)
    assert out.returncode == 2 and out.stderr.strip().count("\n") == 0, out.stderr
    assert out.stderr.startswith("ballaststudy: error: config/config.yaml: not ")


@pytest.fixture
def bare_workflow(tmp_path):
    """The Snakefile, its rules and the shipped config, nothing built: for dry runs that
    must stop before any job."""
    for folder in ("workflow", "config"):
        shutil.copytree(ROOT / folder, tmp_path / folder)
    return tmp_path


# (file, the start of its first line of the key, a second copy, dotted path, how given)
TWICE = [("config/config.yaml", "seed: ", "seed: 1", "seed", []),
         ("config/databases.yaml", "  mass_kg: ", "  mass_kg: 5", "defaults.mass_kg", []),
         ("config/config.yaml", "      cycles: ", "      cycles: 4", "rig.box.loading.cycles",
          ["--configfile", "config/config.yaml"])]


@pytest.mark.parametrize("file, start, copy, key, args", TWICE, ids=["seed", "databases-nested", "configfile-nested"])
def test_a_key_given_twice_is_one_line(bare_workflow, file, start, copy, key, args):
    """PyYAML keeps the last copy of a key silently; the workflow refuses the file before
    any job, whether the Snakefile reads it first or Snakemake (--configfile) did."""
    path = bare_workflow / file
    lines = path.read_text().splitlines(keepends=True)
    at = next(i for i, line in enumerate(lines) if line.startswith(start))
    lines.insert(at + 1, copy + "\n")
    path.write_text("".join(lines))
    out = subprocess.run(["snakemake", "--cores", "1", "-n", *args], cwd=bare_workflow,
                         capture_output=True, text=True)
    shown = path if args else file                  # Snakemake passes --configfile on absolute
    assert out.returncode == 2, out.stdout + out.stderr
    assert out.stderr.strip().splitlines() == [
        f"ballaststudy: error: {shown}: {key}: key given twice (lines {at + 1} and {at + 2}); keep one"], out.stderr


def test_a_failing_job_shows_our_line(study):
    """Bad input met inside a job (a damaged forms file): Snakemake prints the job's log
    (the Snakefile's onerror), so the one line reaches the terminal, with no traceback."""
    forms = study / "results" / "forms" / "G_1-5.nc"
    saved = study / "saved.nc"
    shutil.copy2(forms, saved)
    try:
        forms.write_bytes(b"not a netCDF file at all")
        shutil.copystat(saved, forms)       # same mtime: Snakemake does not remake it
        # the BPM job forced: another test of this module may have built it already
        out = subprocess.run(["snakemake", "--cores", "1", "results/bpm/G_1-5.nc", "--forcerun", "bpm_build"],
                             cwd=study, capture_output=True, text=True)
    finally:
        shutil.copy2(saved, forms)
    log = out.stdout + out.stderr
    assert out.returncode != 0
    assert "ballaststudy: error: results/forms/G_1-5.nc: not a netCDF file" in log, log
    assert "Traceback" not in log, log


def test_slurm_profile_dry_run(study):
    log = _snakemake(study, "-n", "--profile", "profiles/slurm", "--forceall")
    assert _jobs(log).get("forms_generate") == 2, log


@pytest.mark.slow
def test_whole_chain_runs_and_reruns_only_what_changed(tmp_path):
    d = tmp_path
    shutil.copytree(ROOT / "workflow", d / "workflow", symlinks=False)
    (d / "config").mkdir()
    dbs = yaml.safe_load((ROOT / "config" / "databases.yaml").read_text())
    dbs["databases"] = {"box_test": dbs["databases"]["box_test"]}
    (d / "config" / "databases.yaml").write_text(yaml.safe_dump(dbs))
    cfg = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    cfg["study"]["cases_per_database"] = 2     # two real case records for study merge to compare
    cfg["rig"]["box"]["loading"]["cycles"] = 2
    (d / "config" / "config.yaml").write_text(yaml.safe_dump(cfg))
    _snakemake(d)
    for out in ("results/study.nc", "results/study/iri/iri.csv", "results/study/iri/iri_thesis.csv",
                "results/study/report/report.md"):
        assert (d / out).is_file(), out
    assert not _unrecorded(d / "results")
    assert "Nothing to be done" in _snakemake(d, "-n")
    # the run's reference record from its outputs and records (docs/thesis-scale/'s command)
    rec = subprocess.run(["ballaststudy", "study", "record", "results", "--out", "record"], cwd=d,
                         capture_output=True, text=True)
    assert rec.returncode == 0, rec.stderr
    md = (d / "record" / "README.md").read_text()
    for step, jobs in (("forms generate", 1), ("bpm build", 1), ("case assemble", 2), ("case run", 2),
                       ("study aggregate", 1)):
        assert f"| {step} | {jobs} |" in md, step
    assert "0 present; **missing: G_1-1" in md and "logical CPUs" in md and "| box_test | " in md
    # the same run kept as a part (study pack) and merged back: the record's tables are the run's
    for args in (["pack", "results", "--out", "part"], ["merge", "part", "--out", "merged"],
                 ["iri", "merged/study.nc", "--out", "merged/study/iri"],
                 ["optimise", "merged/study.nc", "--out", "merged/study/report"],
                 ["record", "merged", "--out", "record_merged"]):
        run = subprocess.run(["ballaststudy", "study", *args], cwd=d, capture_output=True, text=True)
        assert run.returncode == 0, (args, run.stderr)
    for name in ("per_database.csv", "database_times.csv", "iri_thesis.csv", "findings.csv"):
        assert (d / "record_merged" / name).read_text() == (d / "record" / name).read_text(), name
    with _edited(d / "config" / "config.yaml", lambda c: _loading(c).update(cyclic_max_kN=40.0)):
        jobs = _jobs(_snakemake(d, "-n"))
    assert "case_assemble" not in jobs and jobs.get("case_run") == 2, jobs
    assert jobs.get("study_aggregate") == 1, jobs
    with _edited(d / "config" / "config.yaml", lambda c: c["rig"]["box"]["assembly"].update(plate_width_m=0.28)):
        jobs = _jobs(_snakemake(d, "-n"))
    assert jobs.get("case_assemble") == 2 and jobs.get("case_run") == 2 and "bpm_build" not in jobs, jobs
