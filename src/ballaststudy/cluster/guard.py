"""A case on a worker that retires before the case can reach its next checkpoint would be
rescheduled from the same checkpoint for ever. A worker job exports how long it lives; a
case running there measures its seconds a cycle and stops, in one line, as soon as its
checkpoint interval (checkpoint_every cycles) is seen to take longer than that."""
import os
import time

from ..schema import ConfigError

LIFETIME_ENV = "BALLASTSTUDY_WORKER_LIFETIME_S"
CONFIG_ENV = "BALLASTSTUDY_EXECUTOR_CONFIG"


def checkpoint_guard(label, environ=os.environ, clock=time.monotonic):
    """A run's end-of-cycle hook (run, cycle) that raises ConfigError on executor.walltime_min
    once ``checkpoint_every`` cycles at the seconds a cycle measured since the hook's first
    call exceed the worker's life; None where the worker does not say how long it lives."""
    if LIFETIME_ENV not in environ:
        return None
    life, file = float(environ[LIFETIME_ENV]), environ.get(CONFIG_ENV, "config")
    first = {}

    def hook(run, cycle):
        now = clock()
        if not first:                       # after the first cycle here (a first loading's
            first.update(t=now, cycle=cycle)    # time says nothing of a cycle's)
            return
        per_cycle = (now - first["t"]) / (cycle - first["cycle"])
        interval = per_cycle * run.checkpoint_every
        if interval > life:
            raise ConfigError(file, "executor.walltime_min",
                              f"{label}: a checkpoint interval ({run.checkpoint_every} cycles at "
                              f"{per_cycle:.3g} s) takes ~{interval:.0f} s, longer than a worker lives "
                              f"({life:.0f} s): raise walltime_min or lower the rig's checkpoint_every")
    return hook
