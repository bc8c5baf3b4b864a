"""On a real one-node SLURM (slurmctld, slurmd, munge: tests/cluster/one_node_slurm.sh,
skipped where its binaries are absent): dask-jobqueue submits a calibration round's workers
with sbatch, a worker job cancelled with scancel mid-case is survived, and the round gives
the local pool's bits; `snakemake --profile profiles/slurm calibrate` on a small config ends
with a local run's evaluations.nc. Every test process shares one SLURM (the script counts
its users)."""
import os
import shutil
import subprocess
import threading
import tempfile
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import yaml

from ballaststudy.cluster.pool import case_pool
from ballaststudy.cluster.spec import executor_spec

from ..biaxial_fast import FAST_LOADING
from ..shipped import ROOT
from .rounds import checkpointed_case, round_of_two, same_cases

SCRIPT = ROOT / "tests" / "cluster" / "one_node_slurm.sh"


@pytest.fixture(scope="module")
def slurm():
    """SLURM_CONF of a one-node SLURM up for this module's tests, stopped after them."""
    folder = Path(tempfile.gettempdir()) / f"ballaststudy-slurm-{os.getuid()}"
    up = subprocess.run([str(SCRIPT), "start", str(folder)], capture_output=True, text=True)
    if up.returncode == 3:
        pytest.skip(up.stderr.strip())
    assert up.returncode == 0, up.stderr
    patch = pytest.MonkeyPatch()
    patch.setenv("SLURM_CONF", up.stdout.strip())
    yield up.stdout.strip()
    patch.undo()
    subprocess.run([str(SCRIPT), "stop", str(folder)], check=True)


def _jobs():
    """{job id: state} of the dask worker jobs squeue lists."""
    out = subprocess.run(["squeue", "-h", "-n", "dask-worker", "-o", "%i %T"], capture_output=True, text=True,
                         check=True).stdout
    return dict(line.split() for line in out.splitlines())


def test_slurm_workers_run_a_round_and_survive_a_cancelled_job(slurm, specimen, local_round, tmp_path):
    config, conditions, at, files = local_round
    spec = executor_spec({"executor": dict(kind="slurm", cores=1, memory_GB=2, walltime_min=10, maximum_jobs=2)},
                         config)
    out, result, seen = tmp_path / "slurm", {}, set()
    t0 = time.time()
    with case_pool(spec, log_dir=tmp_path / "workers") as pool:
        worker = threading.Thread(target=lambda: result.update(
            run=round_of_two(specimen, config, conditions, out, pool)))
        worker.start()
        checkpoint = checkpointed_case(out / "cases")
        running = [j for j, state in _jobs().items() if state == "RUNNING"]
        seen.update(_jobs())
        subprocess.run(["scancel", running[0]], check=True)
        while worker.is_alive():
            seen.update(_jobs())
            worker.join(timeout=0.5)
    at_slurm, files_slurm = result["run"]
    print(f"round on slurm: {time.time() - t0:.1f} s, {len(seen)} worker jobs")
    assert len(seen) >= 2 and running[0] not in _jobs()
    assert not checkpoint.exists()                    # its case finished after all
    assert all(np.array_equal(a, b) for a, b in zip(at, at_slurm))
    same_cases(files, files_slurm)


def _snakemake_start(cwd, *args):
    """(the snakemake run, its log cwd/snakemake.log): a file, as a pipe left unread fills."""
    log = Path(cwd) / "snakemake.log"
    with open(log, "w") as out:
        return subprocess.Popen(["snakemake", *args], cwd=cwd, stdout=out, stderr=subprocess.STDOUT), log


def _snakemake_end(started):
    run, log = started
    assert run.wait() == 0, log.read_text()[-6000:]


def _snakemake(cwd, *args):
    _snakemake_end(_snakemake_start(cwd, *args))


def _edit(path, change):
    cfg = yaml.safe_load(path.read_text())
    change(cfg)
    path.write_text(yaml.safe_dump(cfg))


def _small_calibration(cfg, data_dir):
    """One 3 kg database, two 0.15 x 0.30 m specimens, mu alone: 3 sets x 2 cases x 6 cycles
    (the target's points at N = 1 and 5), quick first loadings (tests/biaxial_fast.py)."""
    cfg["measured"]["data_dir"] = str(data_dir)
    cfg["specimens"]["biaxial_small"]["cases"] = 2
    cfg["strength"]["cases"] = 2
    cfg["rig"]["biaxial"]["loading"].update(FAST_LOADING)
    cfg["calibration"].update(cases=2, cycles=6, parameters={"mu": {"min": 0.3, "max": 1.2}}, initial_design=2,
                              iterations=0, posterior_samples=1024)


@pytest.fixture(scope="module")
def small_workflow(tmp_path_factory, measured_data_dir):
    """A workflow folder whose calibrate target is small, everything before it run."""
    d = tmp_path_factory.mktemp("workflow")
    for part in ("workflow", "profiles"):
        shutil.copytree(ROOT / part, d / part, symlinks=False)
    shutil.copytree(ROOT / "config" / "measured", d / "config" / "measured")
    dbs = yaml.safe_load((ROOT / "config" / "databases.yaml").read_text())
    dbs["defaults"]["mass_kg"] = 3
    dbs["databases"] = {"box_test": dbs["databases"]["box_test"]}
    (d / "config" / "databases.yaml").write_text(yaml.safe_dump(dbs))
    shutil.copy(ROOT / "config" / "config.yaml", d / "config")
    _edit(d / "config" / "config.yaml", lambda cfg: _small_calibration(cfg, measured_data_dir))
    _snakemake(d, "--cores", "2", "calibrate", "--omit-from", "calibrate")
    return d


def test_snakemake_calibrate_on_slurm_ends_as_a_local_run(slurm, small_workflow, tmp_path):
    """`snakemake --profile profiles/slurm calibrate` with the executor slurm: the rule a
    1-core coordinator job, its cases in worker jobs it submits; the same evaluations.nc as
    `snakemake --cores 2 calibrate` with the local executor."""
    if os.path.realpath("/etc/slurm/slurm.conf") != os.path.realpath(slurm):
        pytest.skip("/etc/slurm/slurm.conf is another SLURM's (the plugin's steps read that path)")
    local, cluster = (shutil.copytree(small_workflow, tmp_path / name, symlinks=True) for name in ("local", "slurm"))
    local_run = _snakemake_start(local, "--cores", "2", "calibrate")   # beside the SLURM run: most of that is waiting
    _edit(cluster / "config" / "config.yaml", lambda cfg: cfg.update(executor=dict(
        kind="slurm", cores=2, memory_GB=4, walltime_min=10, maximum_jobs=2)))
    t0 = time.time()
    _snakemake(cluster, "--profile", "profiles/slurm", "--slurm-status-command", "squeue",
               "--slurm-init-seconds-before-status-checks", "5", "calibrate")
    _snakemake_end(local_run)
    out = Path("results/calibration/sun_et_al_16/p60_q230_f5")
    jobs = len(list((cluster / out / "workers").glob("*.err")))
    print(f"snakemake calibrate on slurm: {time.time() - t0:.0f} s, 1 coordinator job, {jobs} worker job(s)")
    assert jobs >= 1
    with xr.open_dataset(local / out / "evaluations.nc") as a, xr.open_dataset(cluster / out / "evaluations.nc") as b:
        assert set(a.variables) == set(b.variables) and a.attrs == b.attrs
        for name in a.variables:
            assert np.array_equal(a[name].values, b[name].values, equal_nan=a[name].dtype.kind == "f"), name
