"""A calibration round's cases on a Dask cluster (a distributed.LocalCluster of two worker
processes): the same bits as the local pool's; a worker killed mid-case (SIGKILL of its
process, after the case wrote a checkpoint) is survived with the same bits; a scheduler
that does not answer is refused in one line before any case runs."""
import os
import signal
import socket
import threading
import time

import numpy as np
import pytest
import yaml
from distributed import Client, LocalCluster

from ballaststudy.cli import main
from ballaststudy.cluster.pool import DaskPool

from ..shipped import shipped_config
from .rounds import checkpointed_case, round_of_two, same_cases


@pytest.fixture
def cluster():
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as c:
        with Client(c) as client:
            yield client


def test_dask_gives_the_local_pools_bits(specimen, local_round, cluster, tmp_path):
    config, conditions, at, files = local_round
    at_dask, files_dask = round_of_two(specimen, config, conditions, tmp_path / "dask", DaskPool(cluster))
    assert all(np.array_equal(a, b) for a, b in zip(at, at_dask))
    same_cases(files, files_dask)


def _kill_a_worker_mid_case(client, cases, timeout_s=60):
    """SIGKILL the worker process of a case once that case has written a checkpoint:
    (the checkpoint it had, the pid killed)."""
    pids = client.run(os.getpid)
    checkpoint = checkpointed_case(cases, timeout_s)
    busy = [w for w, keys in client.processing().items() if keys]
    os.kill(pids[busy[0]], signal.SIGKILL)
    return checkpoint, pids[busy[0]]


def test_a_worker_killed_mid_case_is_survived(specimen, local_round, cluster, tmp_path):
    config, conditions, at, files = local_round
    out, result = tmp_path / "killed", {}
    worker = threading.Thread(target=lambda: result.update(
        run=round_of_two(specimen, config, conditions, out, DaskPool(cluster))))
    worker.start()
    checkpoint, pid = _kill_a_worker_mid_case(cluster, out / "cases")
    worker.join(timeout=300)
    at_dask, files_dask = result["run"]
    assert pid not in cluster.run(os.getpid).values()  # the nanny started a new one
    assert not checkpoint.exists()                      # its case finished after all
    assert all(np.array_equal(a, b) for a, b in zip(at, at_dask))
    same_cases(files, files_dask)


def test_a_scheduler_that_does_not_answer_is_refused(specimen, measured_target, tmp_path, capsys):
    """`ballaststudy calibrate --executor dask` at a port nobody listens on: one line naming
    the key, exit 2, within the connect timeout, no case run."""
    test, measured = measured_target
    config = shipped_config(tmp_path / "config.yaml", lambda cfg: cfg.update(executor=dict(connect_timeout_s=3)))
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    out, t0 = tmp_path / "cal", time.time()
    cases = yaml.safe_load(config.read_text())["calibration"]["cases"]
    assert main(["calibrate", str(measured), "--conditions", str(test), "--specimens", *[str(specimen)] * cases,
                 "--out-dir", str(out), "--config", str(config), "--quiet", "--executor", "dask",
                 "--scheduler-address", f"tcp://127.0.0.1:{port}"]) == 2
    line = capsys.readouterr().err.strip()
    assert "\n" not in line and "executor.scheduler_address" in line and "no Dask scheduler answered" in line, line
    assert time.time() - t0 < 60 and not list(out.rglob("*.nc"))
