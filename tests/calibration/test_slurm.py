"""On a real one-node SLURM (slurmctld, slurmd, munge: tests/cluster/one_node_slurm.sh,
skipped where its binaries are absent): dask-jobqueue submits a calibration round's workers
with sbatch, a worker job cancelled with scancel mid-case is survived, and the round gives
the local pool's bits."""
import subprocess
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from ballaststudy.cluster.pool import case_pool
from ballaststudy.cluster.spec import executor_spec

from .rounds import checkpointed_case, round_of_two, same_cases

SCRIPT = Path(__file__).resolve().parents[1] / "cluster" / "one_node_slurm.sh"


@pytest.fixture(scope="module")
def slurm(tmp_path_factory):
    """SLURM_CONF of a one-node SLURM up for this module's tests, stopped after them."""
    folder = tmp_path_factory.mktemp("slurm")
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
