"""A batch of independent 2D DEM cases stepped together on one GPU.

``Batch.from_simulations(sims, controls)`` copies B built ``Simulation`` s (balls, wall
segments, contact table, gravity, dt) and their controllers (``control.Control``, or None)
into one set of device arrays: the balls of all cases end to end with a case index, each
case with its own dt, gravity, domain, cell grid, walls, contact coefficients, time, step
and controllers. ``run(n)`` advances every case n steps (a few kernel launches per step,
kernels.py), or to its first event; ``to_simulations(sims)`` and ``to_controls()`` write
the state back (into the simulations and the Control objects).

Each case steps on its own budget: ``start(cases, n)`` gives halted cases n more steps,
``advance()`` steps until some case halts (its budget spent, or an event of its
controllers: the window of a servo, a reversal...) and names it. A halted case waits,
its threads idle, while the others step on; its host reacts (reads and drains its
controllers, sets new targets) and starts it again: a rig's "run k steps, measure,
decide" loop, per case, with no step of any case lost or repeated.

What the batch holds today: balls (free or with held velocities, local damping, external
loads), kinematic wall segments (constant velocity and spin), every contact law of
``ContactLaw`` (its sub-models are the CPU engine's, compiled for the GPU), flat joints
(failure, breakage log, interface removal; kernels.flat_joint), clumps (free or held),
density scaling at a fixed dt and the automatic dt (kernels.ball_springs, at every rebuild
of a case), controllers (every sensor, actuator and controller of control.py, driven
bodies included: the CPU's own functions per case, kernels.case_control). Checkpoints go
through the CPU: ``to_simulations`` then ``Simulation.save_checkpoint`` (and the rig's
``Control.to_dict``). Not yet: the energy accounts (the batch books no dissipated work).
"""
import time

import numba
import numpy as np
from numba import cuda

try:    # numba-cuda's launch machinery, for prepared launches (_Prepared); absent under
    # numba's built-in CUDA target and its simulator, where every launch is an ordinary one
    from cuda.core import LaunchConfig, launch as _core_launch
    from numba.cuda._compat import CUDA_CORE_GE_1_0
    from numba.cuda.cudadrv.driver import _to_core_stream
except ImportError:
    _core_launch = None

from .. import params as P
from ..control import EVERY, NSAMP
from . import kernels as K
from .layout import (BALL_ROWS, BOND_ROWS, CLUMP_ROWS, CONTROL_ARRAYS, SEGMENT_ROWS,
                     MAX_NEIGHBOURS, MAX_WALLS, BatchError, lists_to_cpu, pack)

# threads per block; numba's CUDA simulator runs every thread of a block as a Python
# thread, idle ones too, so its blocks are small (the tests' cases have tens of balls)
BLOCK = 16 if numba.config.ENABLE_CUDASIM else 128


def cuda_available():
    """True if numba sees a CUDA GPU (or its simulator, NUMBA_ENABLE_CUDASIM=1)."""
    try:
        return bool(cuda.is_available())
    except Exception:      # a driver that fails to load says the same thing
        return False


# the controllers' arrays a start sends, in _control_rows' order
PUSHED = ("ccfg", "cscale", "cctl", "ccpar", "ccst", "cval", "cwsum")


def _to_host(arr, lo=0, hi=None):
    """A host copy of the device array's rows lo:hi (default all). An empty range or array
    makes no device slice: numba-cuda refuses one on an empty array (a batch without
    clumps or joints, on a GPU; its simulator allows it)."""
    hi = arr.shape[0] if hi is None else hi
    if hi <= lo or arr.size == 0:
        return np.empty((max(hi - lo, 0),) + arr.shape[1:], arr.dtype)
    return (arr if (lo, hi) == (0, arr.shape[0]) else arr[lo:hi]).copy_to_host()


def _check(sim, k):
    if sim.prm[P.DT] <= 0.0:
        raise BatchError(f"case {k}: no dt (prepare the Simulation)")
    b = sim.balls
    if ((b.clump >= 0) & (b.stone >= 0) & (b.alive == 1)).any():
        raise BatchError(f"case {k}: rigid stones (clumps of stone balls): the batch has no "
                         "per-clump timestep or clump density scaling yet; run them on the cpu")


class _Prepared:
    """A kernel launch whose arguments were marshalled once: the batch never reallocates
    its device arrays, and an ordinary launch spends ~3 us of Python per argument (~100 us
    for ``forces``), more than the GPU needs for a step of a hundred cases. Built from
    numba-cuda's own steps (its _Kernel.launch), after an ordinary launch compiled it."""

    def __init__(self, disp, griddim, blockdim, args):
        kern = disp.overloads[tuple(disp.typeof_pyval(a) for a in args)]
        self.args = []
        for ty, val in zip(kern.argument_types, args):
            kern._prepare_args(ty, val, 0, [], self.args)
        self.fn = kern._codelibrary.get_cufunc().kernel
        coop = "is_cooperative" if CUDA_CORE_GE_1_0 else "cooperative_launch"
        self.config = LaunchConfig(grid=griddim, block=blockdim, shmem_size=0,
                                   **{coop: False})
        self.stream = _to_core_stream(0)

    def __call__(self):
        _core_launch(self.stream, self.config, self.fn, *self.args)


class Batch:
    """B cases on the GPU; see the module docstring."""

    def __init__(self, law, host, n_cases, grid_cells, max_cell, forces_registers=None):
        self.law = law
        self.n_cases = n_cases
        self.n_balls = host["pos"].shape[0]
        self.n_segments = host["seg"].shape[0]
        self.controlled = bool(np.any(host["ccfg"][:, EVERY] > 0))
        self.moving = int(self.controlled or np.any(host["wvel"] != 0.0)
                          or np.any(host["womega"] != 0.0))
        self.steps = 0                # launched since the last to_simulations
        self._clock_exported = np.zeros(n_cases, np.int64)   # each case's steps, and the
        self._log_exported = np.zeros(n_cases, np.int64)    # log's entries, exported
        self._remaining = np.zeros(n_cases, np.int64)   # launches a running case may need
        self._started = []            # cases started since the last advance
        self.whole_export_from = max(2, n_cases // 8)   # cases exported at once: whole arrays
        self._controls = host.pop("controls")
        self._control_dims = host["cdim"].copy()
        self._offsets = host.pop("offsets")
        self._wall_offsets = np.concatenate([host["wlo"], host["whi"][-1:]])
        self._bond_offsets = host.pop("bond_offsets")
        self._clump_offsets = host.pop("clump_offsets")
        self.n_clumps = host["cpos"].shape[0]
        host["cell_n"] = np.zeros(grid_cells, np.int32)
        host["cell_ids"] = np.full((grid_cells, max_cell), -1, np.int32)
        self.springs = bool(np.any(host["cfg"][:, K.SCALE2] > 0.0)       # density scaling
                            or np.any(host["cfg"][:, K.AUTO] > 0.0))     # or automatic dt
        self.d = d = {k: cuda.to_device(v) for k, v in host.items()}
        # the controllers' arguments of cases_step and cases_resume, built once (the device
        # arrays are never reallocated; a tuple per step is Python in the hot loop)
        self._control_args = (d["prm"], d["cpos"], d["cvel"], d["comega"], d["cforce"],
                              d["cmass"], d["cheld"], d["seg"], d["wforce"], d["wvel"],
                              *(d[k] for k in CONTROL_ARRAYS), d["cdim"])
        self.k = K.kernels(law, forces_registers)
        self.timer = None
        self.prepared = {}            # kernel name -> _Prepared (or None: ordinary launches)
        self._build_lists()           # every case: the lists before the first forces
        self._ball_springs()          # (the dt: prepare()'s, from the same lists)
        self.d["dtc"].copy_to_device(np.full(n_cases, K.NO_DT))
        self._launch("unbin", self.n_balls, self.d["alive"], self.d["case"], self.d["need"],
                      self.d["cell_n"], self.d["bcell"])

    @classmethod
    def from_simulations(cls, sims, controls=None, forces_registers=None):
        """Copy built simulations (same contact law) into one batch, each with its built
        ``Control`` (or None) from ``controls``. Every case starts halted.
        ``forces_registers``: kernels.kernels' cap (benchmarks)."""
        if not sims:
            raise BatchError("an empty batch")
        controls = [None] * len(sims) if controls is None else list(controls)
        if len(controls) != len(sims):
            raise BatchError(f"{len(controls)} controls for {len(sims)} cases")
        law = sims[0].law.layout()
        for k, s in enumerate(sims):
            if s.law.layout() != law:
                raise BatchError(f"case {k}: another contact law than case 0's")
            _check(s, k)
            s.prepare()
        return cls(law, *pack(sims, controls), forces_registers=forces_registers)

    def _launch(self, name, n, *args):
        if n <= 0:
            return
        if self.timer is not None:       # phase timing (benchmarks): device synchronised
            cuda.synchronize()
            t0 = time.perf_counter()
        fast = self.prepared.get(name)
        if fast is not None:
            try:
                fast()
            except (TypeError, ValueError, AttributeError):   # refused before launching
                self.prepared[name] = fast = None
        if fast is None:
            grid = (n + BLOCK - 1) // BLOCK
            self.k[name][grid, BLOCK](*args)
            if _core_launch is not None and name not in self.prepared:
                try:
                    self.prepared[name] = _Prepared(self.k[name], grid, BLOCK, args)
                except Exception:        # another numba-cuda: ordinary launches
                    self.prepared[name] = None
        if self.timer is not None:
            cuda.synchronize()
            self.timer[name] = self.timer.get(name, 0.0) + time.perf_counter() - t0

    def _build_lists(self):
        """Cell list and Verlet rows of the cases whose ``need`` flag is set."""
        d, nb = self.d, self.n_balls
        self._launch("bin", nb, d["pos"], d["alive"], d["case"], d["cfg"], d["grid"],
                     d["need"], d["cell_n"], d["cell_ids"], d["bcell"], d["err"])
        self._launch("build", nb, d["pos"], d["rad"], d["alive"], d["case"], d["cfg"],
                     d["grid"], d["need"], d["cell_n"], d["cell_ids"], d["nb"], d["nbn"],
                     d["nh"], d["nb2"], d["nh2"], d["seg"], d["wlo"], d["whi"], d["wl"],
                     d["wln"], d["wh"], d["wl2"], d["wh2"], d["pos0"], d["travel"],
                     d["bl"], d["bln"], d["bij"], d["bactive"], d["relist"], d["clump"],
                     d["err"])

    def _ball_springs(self):
        """Density scaling's inertial masses and the automatic dt's dt_crit of the rebuilt
        cases (if any case has either)."""
        if not self.springs:
            return
        d = self.d
        self._launch("ball_springs", self.n_balls, d["pos0"], d["rad"], d["mass"],
                     d["inertia"], d["minv"], d["iinv"], d["mat"], d["alive"], d["case"],
                     d["cfg"], d["coef"], d["nb"], d["nbn"], d["wl"], d["wln"], d["wmat"],
                     d["bl"], d["bln"], d["bij"], d["bc"], d["bactive"], d["clump"],
                     d["need"], d["dtc"])

    def start(self, cases, n_steps, sims=None):
        """Give the (halted) ``cases`` ``n_steps`` more steps each; a case's controllers, as
        its host left them (``to_controls`` read them at its halt), go to the device with
        it, and with ``sims`` (the batch's simulations, written back at the halt) its dt
        and density scaling as its host may have changed them. The next ``advance``
        resumes them."""
        cases = [int(b) for b in np.atleast_1d(cases)]
        if n_steps <= 0 or not cases:
            return self
        halt = self.d["halt"].copy_to_host()
        busy = [b for b in cases if halt[b] == K.RUNNING]
        if busy:
            raise BatchError(f"case(s) {busy} are still running")
        left = self.d["left"].copy_to_host()
        controlled = [b for b in cases if self._controls[b] is not None]
        # the controllers' arrays cross whole, once each way, for all the cases started
        # (a row at a time costs a device view and a transfer per array and case)
        rows = {k: self.d[k].copy_to_host() for k in PUSHED} if controlled else {}
        prm = self.d["prm"].copy_to_host() if sims is not None else None
        for b in cases:
            halt[b] = K.RUNNING
            left[b] = n_steps
            self._remaining[b] = n_steps
            if b in controlled:
                self._control_rows(b, rows)
            if sims is not None:
                self._push_timestep(b, sims[b], prm[b])
        for k, v in rows.items():
            self.d[k].copy_to_device(v)
        self.d["halt"].copy_to_device(halt)
        self.d["left"].copy_to_device(left)
        self._started.extend(cases)
        return self

    def advance(self, check_every=1000):
        """Step the running cases until a check (every ``check_every`` steps) finds one or
        more halted: returns {case: halt code (kernels.HALT_STEPS, HALT_EVENT)} of those
        halted since the last advance ({} if none was running). A case that halts within
        a chunk idles until it ends. A failed case raises BatchError."""
        d = self.d
        if self._started:
            self._started = []
            self._launch("cases_resume", self.n_cases, d["halt"], *self._control_args)
        halted = {}
        while not halted:
            running = self._remaining > 0
            if not running.any():
                break
            chunk = int(min(check_every, self._remaining[running].max()))
            for _ in range(chunk):
                self._step()
            self._raise_errors()
            halt = d["halt"].copy_to_host()
            self._remaining[running] -= chunk
            for b in np.flatnonzero(running):
                if halt[b] != K.RUNNING:
                    halted[int(b)] = int(halt[b])
                    self._remaining[b] = 0
        return halted

    def run(self, n_steps, check_every=1000):
        """Advance every case ``n_steps`` steps, or to its controllers' first event (as
        ``Simulation.run(n, control=...)``): ``start`` them all, ``advance`` until every
        one halted. The error flags are read every ``check_every`` steps and at the end
        (a failed case raises BatchError). With ``self.timer`` a dict, each kernel's time
        is added to it (slower)."""
        self.start(range(self.n_cases), n_steps)
        while self.advance(check_every):
            pass
        return self

    def _step(self):
        """One step of every running case: the kernels in their order (kernels.py)."""
        d = self.d
        nb = self.n_balls
        self._launch("walls_step", max(self.n_segments, self.n_cases), d["seg"], d["wvel"],
                     d["womega"], d["centre"], d["wforce"], d["wmoment"], d["wcase"],
                     d["travel"], d["cfg"], self.moving, d["need"], d["clock"], d["halt"])
        self._launch("first_half", nb, d["pos"], d["vel"], d["omega"], d["vend"], d["wend"],
                     d["force"], d["minv"], d["iinv"], d["fix"], d["alive"], d["case"],
                     d["pos0"], d["cfg"], d["travel"], d["need"], d["relist"], d["clump"],
                     d["halt"])
        self._launch("clumps_first", self.n_clumps, d["cpos"], d["cvel"], d["comega"],
                     d["ctheta"], d["cmass"], d["cinertia"], d["cheld"], d["cforce"],
                     d["cmoment"], d["ccase"], d["cfg"], d["pstart"], d["pidx"], d["offset"],
                     d["alive"], d["pos"], d["vel"], d["omega"], d["pos0"], d["travel"],
                     d["need"], d["halt"])
        self._build_lists()
        self._ball_springs()
        self._launch("forces", nb, d["pos"], d["vel"], d["omega"], d["vend"], d["wend"],
                     d["rad"], d["mass"], d["minv"], d["iinv"], d["fix"], d["damp"],
                     d["mat"], d["alive"], d["case"], d["fext"], d["force"], d["cfg"],
                     d["coef"], d["nb"], d["nbn"], d["nh"], d["seg"], d["link"], d["wvel"],
                     d["womega"], d["centre"], d["wmat"], d["wl"], d["wln"], d["wh"],
                     d["wforce"], d["wmoment"], d["need"], d["cell_n"], d["bcell"], d["bl"],
                     d["bln"], d["bij"], d["bc"], d["bsc"], d["bstate"], d["bfn"], d["bfs"],
                     d["bactive"], d["relist"], d["clock"], d["logi"], d["logf"], d["logn"],
                     d["clump"], d["err"], d["halt"])
        self._launch("clumps_second", self.n_clumps, d["cpos"], d["cvel"], d["comega"],
                     d["ctheta"], d["cmass"], d["cinertia"], d["cheld"], d["cforce"],
                     d["cmoment"], d["cdamp"], d["ccase"], d["cfg"], d["pstart"], d["pidx"],
                     d["offset"], d["alive"], d["pos"], d["force"], d["vend"], d["wend"],
                     d["err"], d["halt"])
        self._launch("cases_step", self.n_cases, d["halt"], d["left"], d["clock"], d["step0"],
                     d["cfg"], d["dtc"], *self._control_args)
        self.steps += 1

    def _raise_errors(self):
        err = self.d["err"].copy_to_host()
        bad = np.nonzero(err)[0]
        if len(bad):
            b = int(bad[0])
            text = "; ".join(t for bit, t in K.ERROR_TEXT.items() if err[b] & bit)
            raise BatchError(f"case {b} failed by step {self.steps}: {text} "
                             f"({len(bad)} case(s) failed)")

    def synchronize(self):
        cuda.synchronize()

    def case_arrays(self, b, *names):
        """Host copies of the named per-ball arrays of case b."""
        lo, hi = self._offsets[b], self._offsets[b + 1]
        return [_to_host(self.d[n], lo, hi) for n in names]

    def to_controls(self, cases=None):
        """Write the device's state of the controllers into the ``Control`` s the batch was
        made from (of ``cases``, default all): the last run's event, readings, window sums,
        controller state and samples, as ``Simulation.run`` leaves them."""
        h = {k: self.d[k].copy_to_host() for k in ("ccfg", "ccst", "cval", "cwsum", "csamp")}
        cases = range(self.n_cases) if cases is None else cases
        for b in cases:
            ctl = self._controls[b]
            if ctl is None:
                continue
            a = ctl.arrays
            a.cfg[:] = h["ccfg"][b]
            a.cst[:] = h["ccst"][b, :len(a.cst)]
            a.val[:] = h["cval"][b, :len(a.val)]
            a.wsum[:] = h["cwsum"][b, :len(a.wsum)]
            n = int(a.cfg[NSAMP])
            a.samp[:n] = h["csamp"][b, :n, :a.samp.shape[1]]
        return self

    def _control_rows(self, b, rows):
        """Case b's controllers as its host left them (parameters, state, switches, scales,
        pending velocities, the emptied sample buffer) into ``rows``, host copies of the
        device's arrays (``PUSHED``) that ``start`` then sends."""
        a = self._controls[b].arrays
        dim = self._control_dims[b]
        if (len(a.sensors), len(a.ctl)) != (dim[K.N_SENSORS], dim[K.N_CONTROLLERS]):
            raise BatchError(f"case {b}: its controllers were rebuilt since the batch was made")
        for key, v in zip(PUSHED, (a.cfg, a.scale, a.ctl, a.cpar, a.cst, a.val, a.wsum)):
            if len(v):
                rows[key][b, :len(v)] = v

    def _push_timestep(self, b, sim, prm):
        """Case b's dt, density scaling and automatic dt from its simulation, if its host
        changed them (a rig scales its masses for loading): the case rebuilt now with its
        inertial masses (the real ones back if scaling ended) and, with the automatic dt,
        its dt from that rebuild, as Simulation.prepare does before the next step."""
        p = sim.prm
        _check(sim, b)
        keys = [P.DT, P.DSCALE, P.DT_SAFETY, P.AUTO_DT]
        if np.array_equal(prm[keys], p[keys]):      # (prm: the device's row of case b)
            return
        prm = prm.copy()
        lo, hi = self._offsets[b], self._offsets[b + 1]
        if p[P.DSCALE] == 0.0 and prm[P.DSCALE] > 0.0:      # set_density_scaling(None)
            self.d["minv"][lo:hi] = np.ascontiguousarray(sim.balls.minv)
            self.d["iinv"][lo:hi] = np.ascontiguousarray(sim.balls.iinv)
        prm[keys] = p[keys]
        cfg = self.d["cfg"][b].copy_to_host()
        cfg[[K.DT, K.SAFETY, K.AUTO]] = p[P.DT], p[P.DT_SAFETY], p[P.AUTO_DT]
        cfg[K.SCALE2] = (p[P.DT] / p[P.DT_SAFETY]) ** 2 if p[P.DSCALE] > 0.0 else 0.0
        self.springs = self.springs or cfg[K.SCALE2] > 0.0 or cfg[K.AUTO] > 0.0
        need = np.zeros(self.n_cases, np.int32)     # (the other cases' builds are done)
        need[b] = 1
        self.d["need"].copy_to_device(need)
        self.d["cfg"][b, :] = cfg
        self._build_lists()
        self._ball_springs()
        dtc = self.d["dtc"].copy_to_host()
        if cfg[K.AUTO] > 0.0 and dtc[b] < K.NO_DT:
            cfg[K.DT] = prm[P.DT] = p[P.DT_SAFETY] * dtc[b]
            self.d["cfg"][b, :] = cfg
        dtc[b] = K.NO_DT
        self.d["dtc"].copy_to_device(dtc)
        self.d["prm"][b, :] = prm
        d = self.d
        self._launch("unbin", self.n_balls, d["alive"], d["case"], d["need"], d["cell_n"],
                     d["bcell"])

    def to_simulations(self, sims, cases=None):
        """Write the state back into the simulations the batch was made from (of
        ``cases``, default all): balls, walls (positions, velocities, reactions), flat
        joints (state, the breakages since the case's last export), clumps, and the
        contacts with their history as the CPU's Verlet lists. Their step and time advance
        by the steps they ran since their last export. Only each case's own rows cross
        to the host (a halted case's export costs the same whatever B: ~85 transfers),
        unless ``whole_export_from`` cases or more are exported at once: then each array
        crosses whole, once (~30 transfers for all of them)."""
        clock = self.d["clock"].copy_to_host()
        n_log = int(self.d["logn"].copy_to_host()[0])
        cases = range(self.n_cases) if cases is None else cases
        whole = self._whole() if len(cases) >= self.whole_export_from else None
        for b in cases:
            s, h = sims[b], self._case_rows(b, n_log, whole)
            s.balls.pos[:] = h["pos"]
            s.balls.vel[:] = h["vend"]
            s.balls.omega[:] = h["wend"]
            s.balls.force[:] = h["force"][:, :2]
            s.balls.moment[:] = h["force"][:, 2]
            s.balls.minv[:] = h["minv"]        # density scaling's, if on
            s.balls.iinv[:] = h["iinv"]
            for name, key in (("seg", "seg"), ("centre", "centre"), ("force", "wforce"),
                              ("moment", "wmoment"), ("vel", "wvel")):    # (controllers)
                getattr(s.walls, name)[:] = h[key]
            for name in ("pos", "vel", "omega", "theta", "force", "moment", "held"):
                getattr(s.clumps, name)[:] = h["c" + name]
            self._bonds_to_cpu(h, s, b)
            lists_to_cpu(h, s, self._offsets[b], self._wall_offsets[b])
            s.cnt[0] += clock[b] - self._clock_exported[b]
            s.prm[P.TIME] = h["prm"][P.TIME]        # summed step by step, as on the CPU
            s.prm[P.DT] = h["prm"][P.DT]            # (the automatic dt's)
            self._log_exported[b] = n_log
            self._clock_exported[b] = clock[b]
        self.steps = 0
        return self

    def _whole(self):
        """Host copies of every device array an export reads, each in one transfer."""
        keys = (*BALL_ROWS, *SEGMENT_ROWS, *CLUMP_ROWS, "prm", "nb", "wl", "nh", "wh",
                *(BOND_ROWS if self._bond_offsets[-1] > 0 else ()))
        return {k: _to_host(self.d[k]) for k in keys}

    def _case_rows(self, b, n_log, whole=None):
        """Host copies of case b's rows of the device arrays (its balls', segments',
        clumps' and flat joints' ranges, its list slots, the log since its last export),
        from the device or from ``whole`` (``_whole``'s copies)."""
        d = self.d
        lo, hi = self._offsets[b], self._offsets[b + 1]
        w0, w1 = self._wall_offsets[b], self._wall_offsets[b + 1]
        c0, c1 = self._clump_offsets[b], self._clump_offsets[b + 1]
        q0, q1 = self._bond_offsets[b], self._bond_offsets[b + 1]
        n = self.n_balls
        if whole is not None:
            h = {k: whole[k][lo:hi] for k in BALL_ROWS}
            h.update({k: whole[k][w0:w1] for k in SEGMENT_ROWS})
            h.update({k: whole[k][c0:c1] for k in CLUMP_ROWS})
            h.update({k: whole[k][0, q0:q1] for k in BOND_ROWS if q1 > q0})
            h["prm"] = whole["prm"][b]
            h.update({k: whole[k][:, lo:hi] for k in ("nb", "wl")})
            for k, slots in (("nh", MAX_NEIGHBOURS), ("wh", MAX_WALLS)):
                h[k] = whole[k].reshape(slots, n, *whole[k].shape[1:])[:, lo:hi]
        else:
            h = {k: _to_host(d[k], lo, hi) for k in BALL_ROWS}
            h.update({k: _to_host(d[k], w0, w1) for k in SEGMENT_ROWS})
            h.update({k: _to_host(d[k], c0, c1) for k in CLUMP_ROWS})
            h.update({k: d[k][0, q0:q1].copy_to_host() for k in BOND_ROWS if q1 > q0})
            h["prm"] = d["prm"][b].copy_to_host()
            for k, slots in (("nb", MAX_NEIGHBOURS), ("wl", MAX_WALLS)):     # slot-major
                h[k] = np.array([d[k][q, lo:hi].copy_to_host() for q in range(slots)])
            for k, slots in (("nh", MAX_NEIGHBOURS), ("wh", MAX_WALLS)):     # rows q n + i
                h[k] = np.array([d[k][q * n + lo:q * n + hi].copy_to_host()
                                 for q in range(slots)])
        k0 = self._log_exported[b]
        h["logi"] = d["logi"][k0:n_log].copy_to_host() if n_log > k0 else np.zeros((0, 4), np.int64)
        h["logf"] = d["logf"][k0:n_log].copy_to_host() if n_log > k0 else np.zeros((0, 3))
        return h

    def _bonds_to_cpu(self, h, sim, b):
        """Case b's flat-joint state (side 0's copy, its rows ``h``) and its breakages
        logged since its last export (in the CPU's order: step, bond, element) into
        ``sim``, before its step advances."""
        bd = sim.bonds
        q0 = self._bond_offsets[b]
        q1 = q0 + len(bd)
        if q1 == q0:
            return
        bd.theta[:], bd.moment[:] = h["bsc"][:, 0], h["bsc"][:, 1]
        bd.state[:], bd.fn[:] = h["bstate"], h["bfn"]
        bd.fs[:], bd.active[:] = h["bfs"], h["bactive"]
        li = h["logi"]
        lf = h["logf"]
        mine = (li[:, 1] >= q0) & (li[:, 1] < q1)
        li, lf = li[mine], lf[mine]
        order = np.lexsort((li[:, 2], li[:, 1], li[:, 0]))
        log, k0 = sim.log, int(sim.log.n[0])
        log.ensure(k0 + len(order))
        for k, r in enumerate(order):
            q = int(li[r, 1]) - q0
            since = int(li[r, 0]) - self._clock_exported[b]   # its step since the last export
            i = int(bd.i[q])
            row = dict(step=int(sim.cnt[0]) + since, time=sim.prm[P.TIME] + since * sim.prm[P.DT],
                       bond=q, elem=int(li[r, 2]), i=i, j=int(bd.j[q]),
                       stone=int(sim.balls.stone[i]), mode=int(li[r, 3]), x=lf[r, 0],
                       y=lf[r, 1], stress=lf[r, 2])
            for name, v in row.items():
                getattr(log, name)[k0 + k] = v
        log.n[0] = k0 + len(order)
