"""The loading run of any cyclic rig (kit): the engine runs with the rig's controllers
(dem.control) until one raises an event; the rig reacts (``on_window``, ``on_peak``, the
row of a finished cycle); this class keeps the samples, the per-cycle records and the
behaviours, thins the time series, checkpoints and resumes bit for bit.

A cycle runs from one trough (lower reversal) to the next; before the first trough the rig
is in its own preparatory phases (static pre-loading, consolidation...).
A subclass gives ``CHANNELS`` (sample name -> sensor of its Control), ``CYCLE_FIELDS``
(name -> (units, long name)), ``State`` (its CycleState), ``cycle_row()``,
``behaviours()`` and, for extra records, ``_extra_arrays`` / ``_load_extra``.
"""
import json
from dataclasses import asdict, dataclass, field

import numpy as np

from ..atomic import atomic_path
from ..schema import ConfigError
from ..inputs import open_checkpoint
from ..dem.control import PEAK, TROUGH, WINDOW


@dataclass
class CycleState:
    """Where a run stands (checkpointed as JSON)."""
    phase: str = "static"            # the rig's preparatory phases -> cyclic -> done
    cycle: int = 0
    cycle_start_step: int = 0
    cycle_sample0: int = 0           # first sample of the cycle
    peak_sample: int = -1            # sample of the upper reversal (-1: not yet)
    log0: int = 0                    # breakage log entries before loading began
    n_bonds0: int = 0                # breakable units when loading began (stone model's:
                                     # flat joints, or rigid stones)
    rows: list = field(default_factory=list)           # behaviours per cycle
    metrics_cfg: dict = field(default_factory=dict)
    failure: str = ""                # why the run stopped before its cycles ("" = it did not:
                                     # a specimen that failed, set by the rig)


def json_array(obj):
    """``obj`` as JSON in UTF-8 bytes (a uint8 array): a checkpoint's run state, whose
    per-cycle rows grow with the cycles (a numpy string would take 4 bytes a character)."""
    return np.frombuffer(json.dumps(obj).encode(), np.uint8)


def json_of(array):
    """The object of a ``json_array`` (or of the numpy string older checkpoints hold)."""
    return json.loads(array.tobytes().decode() if array.dtype == np.uint8 else str(array))


class CyclicRun:
    CHANNELS = {}
    CYCLE_FIELDS = {}
    CYCLING = ("cyclic",)           # phases whose samples belong to the current cycle
    State = CycleState

    def __init__(self, rig, cycles, control, checkpoint=None, checkpoint_every=1,
                 metrics=None, max_cycle_steps=None):
        self.rig = rig
        self.cycles = int(cycles)
        self.control = control
        self.checkpoint = checkpoint
        self.checkpoint_every = int(checkpoint_every)
        self.max_cycle_steps = max_cycle_steps
        self.s = self.State(log0=rig.stones.n_breakages(rig.sim), metrics_cfg=dict(metrics or {}),
                            n_bonds0=rig.stones.breakable_units(rig.sim))
        self.samples = {k: [] for k in ("step", "cycle", *self.CHANNELS)}
        self.cyc = {k: [] for k in self.CYCLE_FIELDS}
        self.hooks = []      # callables(run, cycle) at the end of each cycle (VTK...)
        # the stones as loading begins: what broken_mass_share measures breakage against
        self.stone_unit = np.asarray(rig.fragments())
        self._checkpoint_due = False

    # --------------------------------------------------------------- events
    def advance(self, max_steps=None):
        """Run the engine until a controller's event (or ``max_steps``), then react."""
        sim, c = self.rig.sim, self.control
        n = max_steps or (c.capacity - 1) * c.every
        sim.run(n, control=c)
        self._book_samples(c.drain())
        event, k = c.event
        c.clear_event()
        if event == WINDOW:
            self.on_window(k)
        elif event == PEAK:
            self.s.peak_sample = len(self.samples["step"]) - 1
            self.on_peak()
        elif event == TROUGH:
            self._trough()
        self.check_stalled()
        if self._checkpoint_due:
            self._checkpoint_due = False
            self.save_checkpoint(self.checkpoint)

    def on_window(self, controller):
        """A servo's averaging window is complete (the rig decides what follows)."""

    def on_peak(self):
        """The upper reversal of the cycle."""

    def check_stalled(self):
        s = self.s
        if (s.phase == "cyclic" and self.max_cycle_steps
                and self.rig.sim.step - s.cycle_start_step > self.max_cycle_steps):
            raise RuntimeError(f"cycle {s.cycle} did not finish within "
                               f"{self.max_cycle_steps} steps")

    def _book_samples(self, rows):
        label = self.s.cycle if self.s.phase in self.CYCLING else -1
        self.samples["step"].extend(int(v) for v in rows[:, 0])
        self.samples["cycle"].extend([label] * len(rows))
        for name, sensor in self.CHANNELS.items():
            self.samples[name].extend(rows[:, 1 + sensor].tolist())

    def _trough(self):
        if self.s.phase == "cyclic":
            self._end_cycle()
        if self.s.phase != "done":
            self.s.phase = "cyclic"
            self._start_cycle()

    def _start_cycle(self):
        s = self.s
        s.cycle_start_step = self.rig.sim.step
        s.cycle_sample0 = len(self.samples["step"])
        s.peak_sample = -1
        self.on_cycle_start()

    def on_cycle_start(self):
        """A cycle begins (the rig resets what it tracks per cycle)."""

    def _end_cycle(self):
        s = self.s
        for k, v in self.cycle_row().items():
            self.cyc[k].append(v)
        s.rows.append(self.behaviours())
        self._thin_samples(s.cycle_sample0)
        for hook in self.hooks:
            hook(self, s.cycle)
        s.cycle += 1
        if s.cycle >= self.cycles:
            s.phase = "done"
        self.on_cycle_end()
        if self.checkpoint and (s.cycle % self.checkpoint_every == 0 or s.phase == "done"):
            self._checkpoint_due = True     # saved once the next cycle has begun

    def on_cycle_end(self):
        """After a cycle's records (caches to reset at checkpoints...)."""

    def stone_units(self, n):
        """The stone each of balls 0..n-1 was when loading began (-1: none): the snapshot's
        ``stone_unit``."""
        out = np.full(n, -1, np.int64)
        out[: len(self.stone_unit)] = self.stone_unit
        return out

    def _thin_samples(self, k0, every=1):
        """Keep every ``every``-th sample of the finished cycle (and its last)."""
        if every <= 1:
            return
        n = len(self.samples["step"])
        keep = list(range(k0, n, every))
        if keep and keep[-1] != n - 1:
            keep.append(n - 1)
        for v in self.samples.values():
            v[k0:] = [v[i] for i in keep]

    def cycle_samples(self, name):
        """This cycle's samples of one channel (all of them: thinned only at its end)."""
        return np.asarray(self.samples[name][self.s.cycle_sample0:])

    # --------------------------------------------------------------- driving
    def run(self, progress=None, stop_after=None):
        """Run until ``cycles`` are done (or ``stop_after`` further cycles: an interruption
        for tests). ``progress(phase, cycle)`` is called after each event or chunk."""
        s = self.s
        c0 = s.cycle
        while s.phase != "done":
            self.advance()
            if progress is not None:
                progress(s.phase, s.cycle)
            if stop_after is not None and s.cycle - c0 >= stop_after:
                break
        return self

    # --------------------------------------------------------------- checkpoint
    def _extra_arrays(self):
        return {}

    def _load_extra(self, d):
        pass

    def save_checkpoint(self, path):
        """Engine + rig layout and parameters + run state + controllers + records: one
        npz, written atomically."""
        data = {"samp_" + k: np.asarray(v) for k, v in self.samples.items()}
        data.update({"cyc_" + k: np.asarray(v, float) for k, v in self.cyc.items()})
        data.update(self._extra_arrays())
        data["stone_unit"] = self.stone_unit
        data["engine"] = np.frombuffer(self.rig.engine_bytes(), np.uint8)
        data["state"] = json_array(asdict(self.s))
        data.update(self.control.to_dict())
        data["layout"] = np.array(json.dumps(vars(self.rig.layout)))
        data["params"] = np.array(json.dumps(self.rig.params.to_dict()))
        data["cycles"] = np.array(self.cycles)
        with atomic_path(path) as tmp:
            with open(tmp, "wb") as f:
                np.savez(f, **data)

    @classmethod
    def from_checkpoint(cls, path, rig_class, cycles=None, **kwargs):
        """The run saved in ``path`` (its metrics settings come with it)."""
        d = open_checkpoint(path)
        try:
            rig = rig_class.from_parts(d["engine"].tobytes(), json.loads(str(d["layout"])),
                                       json.loads(str(d["params"])), path)
            run = cls(rig, int(d["cycles"]) if cycles is None else cycles, checkpoint=path,
                      resumed=True, **kwargs)
            run.s = cls.State(**json_of(d["state"]))
            run.control.load(d)
            for k in run.samples:
                run.samples[k] = d["samp_" + k].tolist()
            for k in run.cyc:
                run.cyc[k] = d["cyc_" + k].tolist()
            run._load_extra(d)
            if "stone_unit" in d:     # older checkpoints: the stones at the resume
                run.stone_unit = d["stone_unit"]
        except (KeyError, TypeError, ValueError) as err:   # ValueError: JSON or engine bytes
            raise ConfigError(path, None, f"not a checkpoint of this version ({err}); "
                              "run again with --restart") from None
        if run.s.phase == "done" and not run.s.failure and run.s.cycle < run.cycles:
            run.s.phase = "cyclic"      # more cycles asked for than were run (a failed
                                        # specimen stays failed)
            run._start_cycle()
        return run
