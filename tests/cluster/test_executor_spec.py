"""The executor setting: each bad one refused in one line naming file and key; the worker
job a jobqueue spec submits (its resources, environment, lifetime); the guard that stops a
case whose checkpoint interval outlives its worker; temporary names that cannot collide
across hosts."""
import os
import shutil

import pytest

from ballaststudy.atomic import atomic_path, temporary_name
from ballaststudy.cli import main
from ballaststudy.cluster.guard import CONFIG_ENV, LIFETIME_ENV, checkpoint_guard
from ballaststudy.cluster.pool import job_of_worker, job_script, worker_lifetime_s
from ballaststudy.cluster.spec import ExecutorSpec, executor_spec
from ballaststudy.config import ConfigError

from ..shipped import shipped_config

SLURM = dict(kind="slurm", cores=4, memory_GB=8, walltime_min=120)


def _refused(executor, key, words, **flags):
    with pytest.raises(ConfigError) as err:
        executor_spec({"executor": executor}, "c.yaml", **flags)
    line = str(err.value)
    assert "\n" not in line and line.startswith(f"c.yaml: executor.{key}: ") and words in line, line


def test_local_is_the_default():
    assert executor_spec({}, "c.yaml") == ExecutorSpec(file="c.yaml")


def test_bad_settings_are_one_line():
    _refused({"kind": "condor"}, "kind", "allowed: local, dask, slurm, pbs, sge, lsf")
    _refused({}, "kind", "allowed: local", kind="mpi")
    _refused({"kind": "dask"}, "scheduler_address", "missing")
    for key in ("cores", "memory_GB", "walltime_min"):
        _refused({k: v for k, v in SLURM.items() if k != key}, key, "needs cores, memory_GB and walltime_min")
    _refused(dict(SLURM, minimum_jobs=5, maximum_jobs=2), "minimum_jobs", "at most executor.maximum_jobs (2)")


def test_the_command_line_overrides_the_config():
    spec = executor_spec({"executor": {"kind": "local"}}, "c.yaml", kind="dask", scheduler_address="tcp://h:1")
    assert (spec.kind, spec.scheduler_address) == ("dask", "tcp://h:1")


def test_a_batch_system_this_machine_lacks_is_refused(monkeypatch):
    monkeypatch.setenv("PATH", "/nonexistent")
    _refused(SLURM, "kind", "sbatch is not on this machine's PATH")


@pytest.mark.skipif(shutil.which("sbatch") is None, reason="no sbatch here (apt-get install slurm-wlm)")
def test_the_worker_job_asks_for_what_the_spec_says(monkeypatch):
    monkeypatch.setenv("NUMBA_CPU_NAME", "generic")
    spec = executor_spec({"executor": dict(SLURM, queue="short", account="rail", job_directives=["--exclusive"])},
                         "c.yaml")
    script = job_script(spec)
    for line in ("#SBATCH -n 1", "#SBATCH --cpus-per-task=4", "#SBATCH -t 02:00:00", "#SBATCH -p short",
                 "#SBATCH -A rail", "#SBATCH --exclusive", "export NUMBA_CPU_NAME=generic",
                 "export NUMBA_NUM_THREADS=1", "export DASK_DISTRIBUTED__WORKER__PROFILE__ENABLED=False",
                 "export DASK_DISTRIBUTED__WORKER__MEMORY__MONITOR_INTERVAL=10s", f"export {LIFETIME_ENV}=6660", f"export {CONFIG_ENV}=c.yaml",
                 f"cd {os.getcwd()}"):
        assert line in script, (line, script)
    assert "--preload ballaststudy.scenario.runner" in script
    assert "--nthreads 1" in script and "--nworkers 4" in script and "--lifetime 6840s --lifetime-stagger 180s" in script


def test_a_worker_retires_before_its_walltime():
    for walltime_min in (10, 120, 2880):
        lifetime, stagger = worker_lifetime_s(walltime_min)
        assert 0 < stagger < lifetime and lifetime + stagger <= 60 * walltime_min - 60
    assert worker_lifetime_s(120) == (6840.0, 180.0)     # 5 % of 2 h is its margin


class _Run:
    checkpoint_every = 50


def test_the_guard_stops_a_case_whose_checkpoint_interval_outlives_its_worker():
    """At 10 s a cycle, 50 cycles take 500 s: stopped under a 400 s life, let go under 600 s;
    the first cycle here (a first loading: slow) is not counted."""
    for life, stops in ((400, True), (600, False)):
        times = iter([100.0, 110.0, 120.0, 130.0])      # the first cycle ends at 100 s
        hook = checkpoint_guard("case 0 of k", {LIFETIME_ENV: str(life), CONFIG_ENV: "c.yaml"}, lambda: next(times))
        hook(_Run(), 0)
        if stops:
            with pytest.raises(ConfigError, match=r"c.yaml: executor.walltime_min: case 0 of k: a checkpoint "
                               r"interval \(50 cycles at 10 s\) takes ~500 s, longer than a worker lives \(400 s\)"):
                hook(_Run(), 1)
        else:
            for cycle in (1, 2, 3):
                hook(_Run(), cycle)
    assert checkpoint_guard("case", {}) is None         # not on a worker that says nothing


def test_temporary_names_differ_across_writers_of_one_pid(tmp_path):
    names = {temporary_name(tmp_path / "a.nc") for _ in range(100)}
    assert len(names) == 100 and all(n.parent == tmp_path and n.name.startswith(".a.nc.tmp.") for n in names)
    with atomic_path(tmp_path / "b.txt") as tmp:
        tmp.write_text("x")
    assert [p.name for p in tmp_path.iterdir()] == ["b.txt"]


def test_a_job_of_several_workers_is_one_group():
    """Adaptive scaling closes jobs: each worker process of a job maps to the job's name."""
    spec = {"SLURMCluster-0": {"group": ["-0", "-1"]}, "SLURMCluster-1": {"group": ["-0", "-1"]}, "solo": {}}
    assert job_of_worker(spec) == {"SLURMCluster-0-0": "SLURMCluster-0", "SLURMCluster-0-1": "SLURMCluster-0",
                                   "SLURMCluster-1-0": "SLURMCluster-1", "SLURMCluster-1-1": "SLURMCluster-1",
                                   "solo": "solo"}


def test_config_check_refuses_a_bad_executor(tmp_path, capsys):
    """`ballaststudy config check` reads the executor as the Snakefile does (its batch system
    is looked for only where the stage runs)."""
    config = shipped_config(tmp_path / "c.yaml", lambda cfg: cfg.update(executor={"kind": "pbs", "cores": 2}))
    assert main(["config", "check", "--config", str(config)]) == 2
    line = capsys.readouterr().err.strip()
    assert "\n" not in line and f"{config}: executor.memory_GB: missing" in line, line
    config = shipped_config(tmp_path / "c.yaml", lambda cfg: cfg.update(
        executor={"kind": "pbs", "cores": 2, "memory_GB": 4, "walltime_min": 60}))
    assert main(["config", "check", "--config", str(config)]) == 0
