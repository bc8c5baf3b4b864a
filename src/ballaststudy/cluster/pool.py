"""The pools a stage's cases run in: processes on this machine (``LocalPool``), or the
workers of a Dask scheduler (``DaskPool``): one already running (kind dask) or one started
here whose workers dask-jobqueue submits as batch jobs (slurm, pbs, sge, lsf).

A case is a task of one worker process (one thread: the kernels hold the GIL). A worker
lost mid-case (killed, node lost, walltime) has its case rescheduled by the scheduler, and
the case resumes from its checkpoint (scenario.runner). A task that kills its worker more
often than distributed's ``allowed-failures`` comes back as KilledWorker; it is submitted
again only while its checkpoint keeps moving, so a case that can never reach its next
checkpoint stops the stage instead of cycling for ever. A case that fails for its own
reason (an exception) stops the stage as on the local pool, not retried."""
import contextlib
import os
import shlex
import sys
import uuid
from concurrent.futures import ProcessPoolExecutor, as_completed

import dask
from dask_jobqueue import LSFCluster, PBSCluster, SGECluster, SLURMCluster
from distributed import Adaptive, Client
from distributed import as_completed as as_done
from distributed.scheduler import KilledWorker
from numba.core import config as numba_config

from .guard import LIFETIME_ENV, CONFIG_ENV

CLUSTERS = {"slurm": SLURMCluster, "pbs": PBSCluster, "sge": SGECluster, "lsf": LSFCluster}
# what numba compiles for, passed on to every worker: the same target, the same bits
NUMBA_TARGET = ("NUMBA_CPU_NAME", "NUMBA_CPU_FEATURES")
# the scheduler of a jobqueue executor: how long a task of each kind is taken to last before
# one has finished (adaptive scaling asks for workers by the queued work, and distributed's
# default, 0.5 s, would ask for one), and one task a worker thread at a time (by default a
# worker holds a second one queued, which another worker, idle at a round's end, waits for)
SCHEDULER = {"distributed.scheduler.default-task-durations": {"run_case": "1h", "run_first_cycle": "10min"},
             "distributed.scheduler.worker-saturation": 1.0}
# imported by a worker as it starts, not inside its first case
WORKER_PRELOAD = ("ballaststudy.scenario.runner",)
# a worker's own periodic work, slowed: it takes the GIL from the case it runs (a case ran
# ~4 % slower in a worker than in a pool process, ~2 % with these; bench/executor_overhead.py)
WORKER_CONFIG = {"distributed.worker.profile.enabled": False, "distributed.worker.memory.monitor-interval": "10s",
                 "distributed.admin.tick.interval": "10s", "distributed.admin.system-monitor.interval": "10s"}


def dask_environment(config):
    """{environment variable: value} that set dask ``config`` keys in a new process."""
    return {"DASK_" + key.upper().replace(".", "__").replace("-", "_"): str(value) for key, value in config.items()}


class LocalPool:
    """``jobs`` processes on this machine (one: here, one call after another)."""

    def __init__(self, jobs=1):
        self.jobs = int(jobs)

    def map(self, fn, calls, done=None, progress=None):
        """fn(*call) for every call; ``done()`` after each; the first error raised."""
        if self.jobs > 1 and len(calls) > 1:
            with ProcessPoolExecutor(self.jobs) as pool:
                for future in as_completed([pool.submit(fn, *c) for c in calls]):
                    future.result()
                    if done:
                        done()
            return
        for c in calls:
            fn(*c)
            if done:
                done()


class DaskPool:
    """The workers of a Dask client's scheduler."""

    def __init__(self, client):
        self.client = client

    def map(self, fn, calls, done=None, progress=None):
        """fn(*call) for every call on the workers; ``done()`` after each; the first error
        raised (the other tasks cancelled). ``progress(call)``: a token that changes while
        the call gets on (its checkpoint's stamp); a KilledWorker task is submitted again
        while it does."""
        check_worker_targets(self.client)
        calls = list(calls)
        futures = {self._submit(fn, c): i for i, c in enumerate(calls)}
        tokens = {i: progress(c) if progress else None for i, c in enumerate(calls)}
        pending = as_done(list(futures))
        try:
            for future in pending:
                i = futures.pop(future)
                try:
                    future.result()
                except KilledWorker as lost:
                    now = progress(calls[i]) if progress else None
                    if now is None or now == tokens[i]:
                        raise RuntimeError(f"{fn.__name__}{_short(calls[i])}: its workers were lost "
                                           f"{lost.allowed_failures + 1} times without it reaching a "
                                           f"checkpoint ({lost.last_worker.address if lost.last_worker else 'worker'})"
                                           ) from lost
                    tokens[i] = now
                    again = self._submit(fn, calls[i])
                    futures[again] = i
                    pending.add(again)
                    continue
                if done:
                    done()
        finally:
            if futures:
                self.client.cancel(list(futures))

    def _submit(self, fn, call):
        return self.client.submit(fn, *call, key=f"{fn.__name__}-{uuid.uuid4().hex}", pure=False)


def _short(call):
    text = ", ".join(str(c) for c in call[1:3])
    return f"({text})"


def numba_target():
    """(cpu name, features) numba compiles for here; (None, None): the host's."""
    return numba_config.CPU_NAME, numba_config.CPU_FEATURES


def check_worker_targets(client):
    """Refuse workers that compile for another CPU target than this process (their bits
    would differ from a local run's)."""
    here = numba_target()
    for address, there in client.run(numba_target).items():
        if tuple(there) != here:
            raise RuntimeError(f"Dask worker {address} compiles for CPU {there[0] or 'host'}, this process "
                               f"for {here[0] or 'host'}: start every worker with the same NUMBA_CPU_NAME "
                               f"(and NUMBA_CPU_FEATURES) as the stage")


@contextlib.contextmanager
def case_pool(spec, jobs=1, log_dir=None):
    """The pool of an ExecutorSpec (cluster.spec): yields LocalPool(jobs) for local, a
    DaskPool for the others; a scheduler that does not answer is refused in one line
    (ConfigError) before any case runs; worker jobs are cancelled on the way out."""
    if spec.kind == "local":
        yield LocalPool(jobs)
        return
    with contextlib.ExitStack() as stack:
        if spec.kind == "dask":
            client = _connect(spec)
        else:
            stack.enter_context(dask.config.set(SCHEDULER))
            cluster = stack.enter_context(jobqueue_cluster(spec, log_dir))
            cluster.adapt(minimum_jobs=spec.minimum_jobs, maximum_jobs=spec.maximum_jobs, Adaptive=KeepBusyJobs)
            client = Client(cluster)
        stack.callback(client.close)
        yield DaskPool(client)


class KeepBusyJobs(Adaptive):
    """Adaptive scaling that retires only worker jobs none of whose workers runs a task.
    distributed's picks workers to close by count, busy or not (a round ending with one
    case left asks for one worker, and the job running it may be the one cancelled): a
    case's work since its last checkpoint would be lost each time, and its retries spent."""

    async def workers_to_close(self, target):
        names = await super().workers_to_close(target)
        processing = await self.scheduler.processing()
        info = self.cluster.scheduler_info.get("workers", {})
        job = job_of_worker(self.cluster.worker_spec)
        busy = {job.get(str(info[a]["name"]), str(info[a]["name"])) for a, keys in processing.items()
                if keys and a in info}
        return [n for n in names if job.get(str(n), str(n)) not in busy]


def job_of_worker(worker_spec):
    """{worker name: its job's name} of a SpecCluster's worker_spec (a job of several
    worker processes names them by the suffixes of its group)."""
    return {str(name) + suffix: str(name) for name, spec in worker_spec.items()
            for suffix in spec.get("group", [""])}


def _connect(spec):
    try:
        return Client(spec.scheduler_address, timeout=spec.connect_timeout_s)
    except (OSError, TimeoutError, ValueError) as err:
        raise spec.error("scheduler_address", f"{spec.scheduler_address}: no Dask scheduler answered within "
                         f"{spec.connect_timeout_s:g} s ({type(err).__name__})") from None


def worker_lifetime_s(walltime_min):
    """(lifetime, stagger) of a worker job of that walltime, in s: it retires (its cases
    rescheduled, not counted as failures) between lifetime - stagger and lifetime + stagger,
    a margin before the batch system kills it."""
    walltime = 60.0 * walltime_min
    margin = max(120.0, 0.05 * walltime)
    return walltime - margin, margin / 2


def worker_environment(spec):
    """The exports of a worker job: one numba thread, this process' CPU target, the worker's
    quieter periodic work, how long the worker lives (the checkpoint guard reads it) and the
    config's name, run in this
    process' folder (relative paths as here; PBS starts jobs in $HOME)."""
    lifetime, stagger = worker_lifetime_s(spec.walltime_min)
    env = {"NUMBA_NUM_THREADS": "1", LIFETIME_ENV: f"{lifetime - stagger:.0f}", CONFIG_ENV: spec.file,
           **{k: os.environ[k] for k in NUMBA_TARGET if k in os.environ}, **dask_environment(WORKER_CONFIG)}
    return [f"cd {shlex.quote(os.getcwd())}"] + [f"export {k}={shlex.quote(v)}" for k, v in env.items()]


@contextlib.contextmanager
def jobqueue_cluster(spec, log_dir=None):
    """dask-jobqueue's cluster of the spec's batch system: jobs of ``cores`` single-thread
    worker processes sharing ``memory_GB``, retiring before their walltime."""
    lifetime, stagger = worker_lifetime_s(spec.walltime_min)
    minutes = int(spec.walltime_min)
    options = dict(
        cores=spec.cores, processes=spec.cores, memory=f"{spec.memory_GB:g}GB",
        walltime=f"{minutes // 60:02d}:{minutes % 60:02d}:00", queue=spec.queue, account=spec.account,
        job_extra_directives=list(spec.job_directives), job_script_prologue=worker_environment(spec),
        worker_extra_args=["--lifetime", f"{lifetime:.0f}s", "--lifetime-stagger", f"{stagger:.0f}s",
                           *(a for module in WORKER_PRELOAD for a in ("--preload", module))],
        python=sys.executable, log_directory=str(log_dir) if log_dir else None)
    if spec.interface:
        options.update(interface=spec.interface, scheduler_options={"interface": spec.interface})
    if spec.kind == "lsf":
        options["walltime"] = f"{minutes // 60:02d}:{minutes % 60:02d}"
    cluster = CLUSTERS[spec.kind](**options)
    try:
        yield cluster
    finally:
        cluster.close()


def job_script(spec):
    """The worker job script the spec submits (for the README and the tests)."""
    with jobqueue_cluster(spec) as cluster:
        return cluster.job_script()

