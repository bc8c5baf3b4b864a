"""Many rigs' runs stepped together on one GPU (dem.gpu's batch), each run's code unchanged.

Each run (a ``CyclicRun``: its reactions, its own loops such as a consolidation, its
checkpoints) works in a thread of its own. Its engine runs, ``sim.run(n, control=...)``,
become requests: the thread waits while the driver hands every pending request to the
batch, which steps all cases at once until some case halts (its event or its steps
done); the driver writes the state back and wakes that case's thread, which reacts as it
would after a CPU run. Only one thread works at a time (the others wait on the driver),
and each reacts to its own case alone, so a case's course is the one it has alone on the
CPU: its events at the same steps, its records alike within round-off.

Between runs a rig may change its controllers (every setting goes to the device with the
case) and its dt and density scaling (likewise); anything else it changes on the host is
not seen by the batch, so a run that asks for more (a callback, another Control) is
refused with ``BatchError``.
"""
import threading
import time

from ..dem.gpu import Batch, BatchError


class _Driver:
    def __init__(self, runs, check_every, clock):
        self.runs = runs
        self.clock = clock       # seconds per phase of the drive, and its counts
        self.sims = [r.rig.sim for r in runs]
        self.check_every = int(check_every)
        self.cond = threading.Condition()
        self.pending = {}        # case -> steps asked for, waiting for the driver
        self.stepping = set()    # cases in the batch
        self.woken = set()       # cases whose run returned, until their thread resumes
        self.alive = set(range(len(runs)))
        self.errors = {}
        self.failure = None      # the batch's own error: every waiting thread raises it
        self.batch = Batch.from_simulations(self.sims, [r.control for r in runs])

    def engine_run(self, b):
        """What case b's ``sim.run`` becomes while the driver runs."""
        def run(n_steps, callback=None, every=None, control=None):
            if callback is not None or control is not self.runs[b].control:
                raise BatchError(f"case {b}: a run with a callback or another Control "
                                 "than its rig's (the batch holds its rig's only)")
            with self.cond:
                self.pending[b] = int(n_steps)
                self.cond.notify_all()
                self.cond.wait_for(lambda: b in self.woken or self.failure is not None)
                self.woken.discard(b)
                if self.failure is not None:
                    raise BatchError(f"case {b}: the batch stopped ({self.failure})")
            return self.sims[b]
        return run

    def work(self, b, job):
        try:
            job(self.runs[b])
        except BaseException as e:      # noqa: BLE001 (handed to the caller, per case)
            self.errors[b] = e
        finally:
            with self.cond:
                self.alive.discard(b)
                self.cond.notify_all()

    def _all_waiting(self):
        """No thread is working: each is finished, asking, in the batch or not yet woken."""
        return all(b not in self.alive or b in self.pending or b in self.stepping
                   for b in range(len(self.runs))) and not self.woken

    def drive(self):
        tick = _Ticks(self.clock)
        while True:
            with self.cond:
                self.cond.wait_for(self._all_waiting)
                if not self.alive:
                    return
                asked = dict(self.pending)
                self.pending.clear()
            tick("hosts")                    # the runs' own code, between their engine runs
            for n, cases in _grouped(asked).items():
                self.batch.start(cases, n, self.sims)
            self.stepping.update(asked)
            tick("start")
            halted = self.batch.advance(self.check_every)
            tick("advance")                  # the device stepping, until some case halts
            self.batch.to_simulations(self.sims, list(halted)).to_controls(list(halted))
            tick("export", len(halted))
            with self.cond:
                self.stepping.difference_update(halted)
                self.woken.update(halted)
                self.cond.notify_all()

    def fail(self, error):
        with self.cond:
            self.failure = error
            self.cond.notify_all()


class _Ticks:
    """Adds the seconds since its last call to ``clock[phase]`` (and ``n`` to
    ``clock[phase + "_n"]``); a None clock costs nothing."""

    def __init__(self, clock):
        self.clock = clock
        self.t = time.perf_counter()

    def __call__(self, phase, n=1):
        if self.clock is None:
            return
        t = time.perf_counter()
        self.clock[phase] = self.clock.get(phase, 0.0) + t - self.t
        self.clock[phase + "_n"] = self.clock.get(phase + "_n", 0) + n
        self.t = t


def _grouped(asked):
    """{steps: [cases]} of the pending requests."""
    out = {}
    for b, n in sorted(asked.items()):
        out.setdefault(n, []).append(b)
    return out


def run_batched(runs, job=lambda run: run.run(), check_every=100, clock=None, kernels=None):
    """Run ``job(run)`` (default ``run.run()``: all its cycles) for every run of ``runs``
    (``CyclicRun`` s of one contact law, their rigs' simulations built) with their
    engines stepped as one GPU batch; returns the runs. A run that raised is re-raised
    after the others finished (the first, naming its case). ``check_every``: steps
    between the host's looks for halted cases; a halted case idles until the next look
    (the biaxial rig halts every ~1600 steps in real time: 100 idles it ~3 %, for one
    small copy of B flags per look). ``clock``: a dict that gets the drive's seconds per
    phase (hosts: the runs' own code; start; advance: the device stepping; export: the
    halted cases written back) and their counts (export_n: halts), summed over calls.
    ``kernels``: a dict that gets each kernel's seconds, the device synchronised around
    every launch (slower: a benchmark's breakdown, Batch.timer)."""
    d = _Driver(runs, check_every, clock)
    d.batch.timer = kernels
    for b, sim in enumerate(d.sims):
        sim.run = d.engine_run(b)            # the instance's, over Simulation.run
    threads = [threading.Thread(target=d.work, args=(b, job), daemon=True)
               for b in range(len(runs))]
    try:
        for t in threads:
            t.start()
        d.drive()
    except BaseException as e:
        d.fail(e)
        raise
    finally:
        for t in threads:
            t.join()
        for sim in d.sims:
            del sim.run
    for b, e in sorted(d.errors.items()):
        raise BatchError(f"case {b}: {type(e).__name__}: {e}") from e
    return runs
