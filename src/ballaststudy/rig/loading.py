"""Loading the assembled box (thesis 4.2.3): static pre-loading 10/20/30 kN, then cyclic
loading between 15 and 45 kN, with a record of every cycle and checkpoints.

The loading ball is a held clump whose vertical velocity the rig sets every
``control_every`` steps (a "fix" between engine runs), from the force the plate exerts
on it (``BoxRig.loading_force``):

* static: servo v = -gain (F_target - F), |v| <= servo_velocity; every
  ``static_window_steps`` the mean of the sampled force over the window is compared with
  the target; relative error < static_tolerance -> next target.
* cyclic: the ball moves down until F >= F_max, then up until F <= F_min (velocity
  reversed at each bound); it moves at v_max until the force is within
  ``cyclic_braking_fraction`` of the load range of the bound it approaches, then its
  speed falls linearly to v_min at that bound, so it does not strike the stones. A cycle
  runs from one reversal at F_min to the next; before the first one the ball unloads
  from 30 kN.

2D forces are per thickness t (PFC2D): the thesis applies 10-45 kN to its 2D model
directly, and so does this rig (a 30 kN load on a t = 1 m slice).
"""
import json
import os
import tempfile

import numpy as np

from ..atomic import atomic_path
from .box import BoxRig

KN = 1.0e3

# per-cycle scalar records: name -> (units, long name)
CYCLE_FIELDS = {
    "cycle_end_step": ("1", "engine step at the end of the cycle"),
    "cycle_steps": ("1", "engine steps in the cycle"),
    "force_max": ("N", "largest loading-ball force in the cycle"),
    "force_min": ("N", "smallest loading-ball force in the cycle"),
    "y_at_settlement_force": ("m", "loading-ball height where the force crosses the "
                              "settlement force on the loading branch"),
    "y_at_peak": ("m", "loading-ball height at the upper reversal (peak load)"),
    "y_at_end": ("m", "loading-ball height at the end of the cycle"),
    "plate_x_at_peak": ("m", "plate centre x at peak load"),
    "plate_y_at_peak": ("m", "plate centre y at peak load"),
    "plate_angle_at_peak": ("rad", "plate rotation at peak load"),
    "plate_x": ("m", "plate centre x at the end of the cycle"),
    "plate_y": ("m", "plate centre y at the end of the cycle"),
    "plate_angle": ("rad", "plate rotation at the end of the cycle"),
    "elements_broken_tension": ("1", "flat-joint elements broken in tension since loading began"),
    "elements_broken_shear": ("1", "flat-joint elements broken in shear since loading began"),
    "contacts": ("1", "contacts carrying force at peak load"),
}


class LoadingRun:
    """The loading state machine of one case. ``advance()`` = one control step."""

    def __init__(self, rig, cycles, checkpoint=None, checkpoint_every=None, metrics=None,
                 resumed=False):
        """``metrics``: the config's ``metrics:`` section (dict) for the behaviours computed
        at the end of every cycle by ``ballaststudy.metrics`` (None = its defaults).
        ``resumed``: the engine comes from a checkpoint, its loading timestep already set."""
        p = rig.params
        self.rig = rig
        self.cycles = int(cycles)
        self.checkpoint = checkpoint
        self.checkpoint_every = int(checkpoint_every or p.checkpoint_every)
        self.s = dict(phase="static", touched=False, target=0, win_sum=0.0, win_n=0, win_steps=0,
                      windows=0, direction=-1, cycle=0, f_prev=0.0, y_prev=0.0,
                      cyc_start=0, fmax=-1e300, fmin=1e300, y30=float("nan"),
                      peak=None, log0=rig.sim.n_breakages, step0=rig.sim.step,
                      static_end_step=-1, y_ref=float("nan"), static_mean=[],
                      static_walls=[], win_bottom=0.0, win_side=0.0, cyc_sample0=0,
                      metrics_cfg=dict(metrics or {}), rows=[],
                      n_bonds0=int((rig.sim.bonds.active == 1).sum()))
        self.samples = {k: [] for k in ("step", "cycle", "force", "y")}
        self.cyc = {k: [] for k in CYCLE_FIELDS}
        self.bottom = []     # (cycle, segment) at peak
        self.side = []       # (cycle, 2, 2) at peak
        self.snap_cycles, self.snap_pos, self.snap_frag = [], [], []
        self.snap_contacts = []
        self.hooks = []      # callables(run, cycle) at the end of each cycle (VTK...)
        self._metrics_setup()
        self._ckpt_due = False
        if p.loading_dt_factor > 1.0 and not resumed:
            rig.sim.set_density_scaling(p.loading_dt_factor * rig.sim.dt)

    def _metrics_setup(self):
        from ..metrics import MetricsParams
        from ..metrics.void_ratio import SolidCache
        self.metrics_params = MetricsParams.from_config(self.s["metrics_cfg"])
        # stone solids reused between cycles; emptied at every checkpoint cycle so that a
        # resumed run computes what an uninterrupted one does
        self.solid_cache = SolidCache(self.metrics_params.solid_reuse_tolerance)

    # --------------------------------------------------------------- control law
    def _velocity(self, f):
        p, s = self.rig.params, self.s
        if s["phase"] == "static":
            # PI servo: the integral removes the offset a proportional servo keeps while
            # the aggregate creeps (clamped: no wind-up beyond the speed limit)
            target = p.static_loads_kN[s["target"]] * KN
            e = p.servo_gain_m_s_per_kN * (target - f) / KN
            if p.servo_integral_steps > 0:
                vmax = p.servo_velocity_m_s
                s["servo_int"] = float(np.clip(
                    s.get("servo_int", 0.0) + e * p.control_every / p.servo_integral_steps,
                    -vmax, vmax))
                e += s["servo_int"]
            return float(np.clip(-e, -p.servo_velocity_m_s, p.servo_velocity_m_s))
        lo, hi = p.cyclic_min_kN * KN, p.cyclic_max_kN * KN
        bound = hi if s["direction"] < 0 else lo
        frac = min(1.0, abs(bound - f) / (p.cyclic_braking_fraction * (hi - lo)))
        v = p.cyclic_v_min_m_s + (p.cyclic_v_max_m_s - p.cyclic_v_min_m_s) * frac
        return float(s["direction"] * v)

    def advance(self):
        """Set the ball's velocity, run ``control_every`` steps, measure, update."""
        rig, p, s = self.rig, self.rig.params, self.s
        sim, lb = rig.sim, rig.layout.loading
        sim.set_clump_velocity(lb, vel=(0.0, self._velocity(s["f_prev"])), omega=0.0,
                               held=True)
        sim.run(p.control_every)
        f, y = rig.loading_force(), rig.loading_y()
        self.samples["step"].append(sim.step)
        self.samples["cycle"].append(s["cycle"] if s["phase"] == "cyclic" else -1)
        self.samples["force"].append(f)
        self.samples["y"].append(y)
        getattr(self, "_" + s["phase"])(f, y)
        s["f_prev"], s["y_prev"] = f, y
        if self._ckpt_due:
            self._ckpt_due = False
            self.save_checkpoint(self.checkpoint)

    def _static(self, f, y):
        p, s = self.rig.params, self.s
        if not s["touched"]:
            # approach: the ball travels down at the servo's top speed until it presses the
            # plate (5 % of the first load); the 10,000-step windows count from that contact,
            # so a plate still settling under its own weight does not use them up
            if f < 0.05 * p.static_loads_kN[0] * KN:
                s["approach_steps"] = s.get("approach_steps", 0) + p.control_every
                if s["approach_steps"] > p.static_max_windows * p.static_window_steps:
                    raise RuntimeError(f"the loading ball did not reach the plate within "
                                       f"{s['approach_steps']} steps")
                return
            s["touched"] = True
        s["win_sum"] += f
        s["win_bottom"] += float(self.rig.bottom_forces().sum())
        s["win_side"] += float(-self.rig.side_forces()[:, 1].sum())
        s["win_n"] += 1
        s["win_steps"] += p.control_every
        if s["win_steps"] < p.static_window_steps:
            return
        target = p.static_loads_kN[s["target"]] * KN
        mean = s["win_sum"] / s["win_n"]
        walls = (s["win_bottom"] / s["win_n"], s["win_side"] / s["win_n"])
        s["win_sum"], s["win_n"], s["win_steps"] = 0.0, 0, 0
        s["win_bottom"], s["win_side"] = 0.0, 0.0
        s["windows"] += 1
        if abs(mean - target) / target < p.static_tolerance:
            s["static_mean"].append(mean)
            s["static_walls"].append(walls)     # mean bottom, side-wall vertical force
            s["target"] += 1
            s["servo_int"] = 0.0
            s["windows"] = 0
            if s["target"] == len(p.static_loads_kN):
                s["phase"] = "unload"
                s["direction"] = 1
                s["static_end_step"] = self.rig.sim.step
                s["y_ref"] = y
        elif s["windows"] >= p.static_max_windows:
            raise RuntimeError(f"static load {target / KN:g} kN not reached within "
                               f"{p.static_max_windows} windows (last mean {mean / KN:.3f} kN)")

    def _unload(self, f, y):
        if f <= self.rig.params.cyclic_min_kN * KN:
            self.s["phase"] = "cyclic"
            self._start_cycle()

    def _start_cycle(self):
        s = self.s
        s["direction"] = -1
        s["cyc_start"] = self.rig.sim.step
        s["cyc_sample0"] = len(self.samples["step"])
        s["fmax"], s["fmin"], s["y30"], s["peak"] = -1e300, 1e300, float("nan"), None

    def _cyclic(self, f, y):
        p, s, rig = self.rig.params, self.s, self.rig
        s["fmax"], s["fmin"] = max(s["fmax"], f), min(s["fmin"], f)
        fs = p.settlement_force_kN * KN
        if s["direction"] < 0:
            if s["f_prev"] < fs <= f and np.isnan(s["y30"]):
                w = (fs - s["f_prev"]) / (f - s["f_prev"])
                s["y30"] = s["y_prev"] + w * (y - s["y_prev"])
            if f >= p.cyclic_max_kN * KN:
                s["direction"] = 1
                self._peak(y)
        elif f <= p.cyclic_min_kN * KN:
            self._end_cycle(y)
            if s["phase"] == "cyclic":
                self._start_cycle()
        if rig.sim.step - s["cyc_start"] > p.max_cycle_steps:
            raise RuntimeError(f"cycle {s['cycle']} did not finish within "
                               f"{p.max_cycle_steps} steps (force {f / KN:.2f} kN)")

    def _peak(self, y):
        rig, s = self.rig, self.s
        px, py, pa = rig.plate_state()
        s["peak"] = dict(y=y, px=px, py=py, pa=pa)
        self.bottom.append(rig.bottom_forces())
        self.side.append(rig.side_forces())
        c = s["cycle"]
        snap = rig.params.snapshot_every
        contacts = rig.sim.contact_list()
        s["peak"]["contacts"] = len(contacts["i"])
        if snap > 0 and (c % snap == 0 or c == self.cycles - 1):
            b = rig.sim.balls
            self.snap_cycles.append(c)
            self.snap_pos.append(b.pos[: rig.layout.n_stone_balls].astype(np.float32))
            self.snap_frag.append(rig.fragments())
            keep = contacts["i"] >= 0
            self.snap_contacts.append(
                {k: contacts[k][keep] for k in ("i", "j", "fx", "fy", "x", "y")})

    def _end_cycle(self, y):
        rig, s = self.rig, self.s
        px, py, pa = rig.plate_state()
        pk = s["peak"] or dict(y=np.nan, px=np.nan, py=np.nan, pa=np.nan, contacts=0)
        modes = rig.sim.log.mode[s["log0"]: rig.sim.n_breakages]
        row = dict(cycle_end_step=rig.sim.step, cycle_steps=rig.sim.step - s["cyc_start"],
                   force_max=s["fmax"], force_min=s["fmin"], y_at_settlement_force=s["y30"],
                   y_at_peak=pk["y"], y_at_end=y, plate_x_at_peak=pk["px"],
                   plate_y_at_peak=pk["py"], plate_angle_at_peak=pk["pa"], plate_x=px,
                   plate_y=py, plate_angle=pa, elements_broken_tension=int((modes == 1).sum()),
                   elements_broken_shear=int((modes == 2).sum()), contacts=pk["contacts"])
        for k, v in row.items():
            self.cyc[k].append(v)
        s["rows"].append(self.behaviours())
        self._thin_samples(s["cyc_sample0"])
        c = s["cycle"]
        for hook in self.hooks:
            hook(self, c)
        s["cycle"] += 1
        if s["cycle"] >= self.cycles:
            s["phase"] = "done"
        if s["cycle"] % self.checkpoint_every == 0:
            self.solid_cache.clear()
        if self.checkpoint and (s["cycle"] % self.checkpoint_every == 0
                                or s["phase"] == "done"):
            self._ckpt_due = True      # saved once this control step is complete

    def _thin_samples(self, k0):
        """Keep every ``timeseries_every``-th sample of the finished cycle (and its last),
        so a 1000-cycle run stays a few tens of MB; the behaviours saw them all."""
        k = max(1, int(self.rig.params.timeseries_every))
        if k == 1:
            return
        n = len(self.samples["step"])
        keep = list(range(k0, n, k))
        if keep and keep[-1] != n - 1:
            keep.append(n - 1)
        for name, v in self.samples.items():
            v[k0:] = [v[i] for i in keep]

    # --------------------------------------------------------------- behaviours
    def snapshot(self):
        """The end-of-cycle snapshot ``ballaststudy.metrics.compute_cycle`` reads
        (bottom forces from the cycle's peak load, where the force propagates)."""
        rig, s, lay = self.rig, self.s, self.rig.layout
        sim = rig.sim
        b, bd = sim.balls, sim.bonds
        n = len(b)
        ballast = np.zeros(n, bool)
        ballast[: lay.n_stone_balls] = b.alive[: lay.n_stone_balls] == 1
        cl = sim.contact_list()
        ball = cl["j"] >= 0
        i, j = cl["i"][ball], cl["j"][ball]
        d = b.pos[j] - b.pos[i]
        nrm = d / np.hypot(*d.T)[:, None]
        fn = np.abs(cl["fx"][ball] * nrm[:, 0] + cl["fy"][ball] * nrm[:, 1])
        container = set(lay.bottom) | set(lay.left) | set(lay.right)
        wall = ~ball
        touch = np.zeros(n, bool)
        seg = -1 - cl["j"][wall]
        touch[cl["i"][wall][np.isin(seg, list(container))]] = True
        bottom_seg = sim.walls.seg[lay.bottom]
        px, py, _ = rig.plate_state()
        p = rig.params
        k0 = s["cyc_sample0"]
        br = sim.log
        nlog = int(br.n[0])
        return dict(
            pos=b.pos.copy(), rad=b.rad.copy(), ballast=ballast,
            bond_i=bd.i, bond_j=bd.j,
            bond_intact=sim.intact_bonds(),
            contact_i=i, contact_j=j, contact_fn=fn, ball_touches_container=touch,
            geometry=dict(container_x_min=float(sim.walls.seg[lay.left_low, 0]),
                          container_x_max=float(sim.walls.seg[lay.right_low, 0]),
                          container_y_bottom=float(bottom_seg[:, 1].mean()),
                          plate_x_mid=px, plate_bottom_y=py - 0.5 * p.plate_thickness_m,
                          plate_half_width=0.5 * p.plate_width_m),
            bottom_force=np.asarray(self.bottom[-1]) if self.bottom else rig.bottom_forces(),
            bottom_x_centre=0.5 * (bottom_seg[:, 0] + bottom_seg[:, 2]),
            bottom_width=np.abs(bottom_seg[:, 2] - bottom_seg[:, 0]),
            load_y=np.asarray(self.samples["y"][k0:]),
            load_force=np.asarray(self.samples["force"][k0:]),
            break_step=br.step[s["log0"]:nlog].copy(), break_mode=br.mode[s["log0"]:nlog].copy(),
            n_bonds_installed=int(s["n_bonds0"]), n_elements_per_bond=int(bd.state.shape[1]),
            cycle_start_step=int(s["cyc_start"]), cycle_end_step=int(sim.step) + 1)

    def behaviours(self):
        """This cycle's behaviours from ``ballaststudy.metrics`` (JSON-safe dict)."""
        from ..metrics import compute_cycle
        rows = self.s["rows"]
        ref = rows[0].get("y_at_level") if rows else None
        out = compute_cycle(self.snapshot(), self.metrics_params, y_reference=ref,
                            solid_cache=self.solid_cache)
        return {k: (float(v) if isinstance(v, (float, np.floating)) else int(v))
                for k, v in out.items()}

    # --------------------------------------------------------------- driving
    def run(self, progress=None, stop_after=None):
        """Run until ``cycles`` are done (or ``stop_after`` further cycles: an interruption
        for tests). ``progress(phase, cycle)`` is called after each control step."""
        s = self.s
        c0 = s["cycle"]
        while s["phase"] != "done":
            self.advance()
            if progress is not None:
                progress(s["phase"], s["cycle"])
            if stop_after is not None and s["cycle"] - c0 >= stop_after:
                break
        return self

    # --------------------------------------------------------------- checkpoint
    def _arrays(self):
        d = {"samp_" + k: np.asarray(v) for k, v in self.samples.items()}
        d.update({"cyc_" + k: np.asarray(v, float) for k, v in self.cyc.items()})
        nseg = len(self.rig.layout.bottom)
        d["bottom"] = np.asarray(self.bottom, float).reshape(-1, nseg)
        d["side"] = np.asarray(self.side, float).reshape(-1, 2, 2)
        d["snap_cycles"] = np.asarray(self.snap_cycles, np.int64)
        n = self.rig.layout.n_stone_balls
        d["snap_pos"] = np.asarray(self.snap_pos, np.float32).reshape(-1, n, 2)
        d["snap_frag"] = np.asarray(self.snap_frag, np.int32).reshape(-1, n)
        cnt = [len(c["i"]) for c in self.snap_contacts]
        d["snap_contact_count"] = np.asarray(cnt, np.int64)
        for k in ("i", "j", "fx", "fy", "x", "y"):
            parts = [c[k] for c in self.snap_contacts]
            d["snap_contact_" + k] = np.concatenate(parts) if parts else np.zeros(0)
        return d

    def save_checkpoint(self, path):
        """Engine checkpoint + rig layout + loading state + records, one npz, atomic."""
        data = self._arrays()
        data["engine"] = np.frombuffer(self.rig.engine_bytes(), np.uint8)
        data["state"] = np.array(json.dumps(self.s))
        data["layout"] = np.array(json.dumps(vars(self.rig.layout)))
        data["params"] = np.array(json.dumps(self.rig.params.to_dict()))
        data["cycles"] = np.array(self.cycles)
        with atomic_path(path) as tmp:
            with open(tmp, "wb") as f:
                np.savez(f, **data)

    @classmethod
    def from_checkpoint(cls, path, cycles=None, checkpoint_every=None):
        """The run saved in ``path`` (its metrics settings come with it)."""
        from .box import RigLayout
        from .params import RigParams
        with np.load(path, allow_pickle=False) as z:
            d = {k: z[k] for k in z.files}
        sim = BoxRig.sim_from_bytes(d["engine"].tobytes(), path)
        rig = BoxRig(sim, RigLayout(**json.loads(str(d["layout"]))),
                     RigParams(**json.loads(str(d["params"]))))
        run = cls(rig, int(d["cycles"]) if cycles is None else cycles, checkpoint=path,
                  checkpoint_every=checkpoint_every, resumed=True)
        run.s = json.loads(str(d["state"]))
        run._metrics_setup()
        if run.s["phase"] == "done" and run.s["cycle"] < run.cycles:
            run.s["phase"] = "cyclic"      # more cycles asked for than were run
            run._start_cycle()
        for k in run.samples:
            run.samples[k] = d["samp_" + k].tolist()
        for k in run.cyc:
            run.cyc[k] = d["cyc_" + k].tolist()
        run.bottom = list(d["bottom"])
        run.side = list(d["side"])
        run.snap_cycles = d["snap_cycles"].tolist()
        run.snap_pos = list(d["snap_pos"])
        run.snap_frag = list(d["snap_frag"])
        off = np.r_[0, np.cumsum(d["snap_contact_count"])]
        run.snap_contacts = [{k: d["snap_contact_" + k][a:b] for k in ("i", "j", "fx", "fy", "x", "y")}
                             for a, b in zip(off[:-1], off[1:])]
        return run
