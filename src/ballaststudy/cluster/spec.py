"""Where a stage's cases run: the config's ``executor`` section (and the command line's
--executor, --scheduler-address over it), checked before any case runs."""
import shutil
from dataclasses import dataclass, field

from ..schema import ConfigError

JOBQUEUE = {"slurm": "sbatch", "pbs": "qsub", "sge": "qsub", "lsf": "bsub"}    # kind: submit command
KINDS = ("local", "dask", *JOBQUEUE)


@dataclass(frozen=True)
class ExecutorSpec:
    kind: str = "local"
    scheduler_address: str = None
    connect_timeout_s: float = 30.0
    cores: int = None
    memory_GB: float = None
    walltime_min: float = None
    minimum_jobs: int = 0
    maximum_jobs: int = 4
    queue: str = None
    account: str = None
    job_directives: tuple = field(default_factory=tuple)
    interface: str = None
    file: str = "config"        # where it was read, for the one-line messages

    @property
    def jobqueue(self):
        return self.kind in JOBQUEUE

    def error(self, key, message):
        return ConfigError(self.file, f"executor.{key}", message)


def executor_spec(cfg, file, kind=None, scheduler_address=None, submit=True):
    """The checked spec of ``cfg``'s executor section, ``kind`` and ``scheduler_address``
    (the command line's, None: the config's) over it; ConfigError in one line for a kind
    that is not known, a dask executor without an address, a jobqueue one without cores,
    memory or walltime, or (``submit``: where the stage runs) whose submit command this
    machine lacks."""
    sec = dict(cfg.get("executor") or {})
    sec.update({k: v for k, v in (("kind", kind), ("scheduler_address", scheduler_address)) if v is not None})
    sec["job_directives"] = tuple(sec.get("job_directives") or ())
    spec = ExecutorSpec(**sec, file=str(file))
    if spec.kind not in KINDS:
        raise spec.error("kind", f"{spec.kind!r}; allowed: {', '.join(KINDS)}")
    if spec.kind == "dask" and not spec.scheduler_address:
        raise spec.error("scheduler_address", "missing: the dask executor needs the address of a running "
                         "scheduler (tcp://host:port), or --scheduler-address")
    if spec.jobqueue:
        for key in ("cores", "memory_GB", "walltime_min"):
            if getattr(spec, key) is None:
                raise spec.error(key, f"missing: a {spec.kind} executor needs cores, memory_GB and walltime_min")
        if spec.minimum_jobs > spec.maximum_jobs:
            raise spec.error("minimum_jobs", f"{spec.minimum_jobs} must be at most executor.maximum_jobs "
                             f"({spec.maximum_jobs})")
        if submit and shutil.which(JOBQUEUE[spec.kind]) is None:
            raise spec.error("kind", f"{spec.kind}: its submit command {JOBQUEUE[spec.kind]} is not on "
                             f"this machine's PATH (run the stage on the cluster's login node)")
    return spec
