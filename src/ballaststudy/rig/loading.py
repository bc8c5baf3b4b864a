"""Loading the assembled box (thesis 4.2.3): static pre-loading 10/20/30 kN, then cyclic
loading between 15 and 45 kN, with a record of every cycle and checkpoints.

The loading ball is a held clump whose vertical velocity controllers inside the engine's
stepping loop set every ``control_every`` steps (``dem.control``, like LAMMPS fixes), from
the force the plate exerts on it; Python sees the run at the controllers' events only
(a static window complete, the peak, the trough), at checkpoints and for progress:

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
from dataclasses import dataclass, field

import numpy as np

from ..dem.control import Control
from ..metrics import MetricsParams, compute_cycle
from ..metrics.void_ratio import SolidCache
from ..metrics.breakage import mode_codes
from .box import BoxRig
from .cyclic import CycleState, CyclicRun

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


@dataclass
class LoadingState(CycleState):
    """The box run's state beyond a cycle's: the static target and what the records keep
    of the static phase and of the cycle's peak."""
    target: int = 0                  # index of the static load being held
    windows: int = 0                 # averaging windows spent on it
    peak: dict | None = None         # loading-ball and plate state at the peak
    static_end_step: int = -1
    y_ref: float = float("nan")      # loading-ball height at the end of static loading
    static_mean: list = field(default_factory=list)    # window mean force per static load
    static_walls: list = field(default_factory=list)   # (bottom, side-wall vertical) means


# control sensors (samples are rows: step, then these readings)
FORCE, Y, BOTTOM, SIDE = range(4)
SERVO, PROFILE = 0, 1       # the controllers' indices in loading_control


def loading_control(rig):
    """Sensors, actuator and the two controllers of the box loading (kit: dem.control):
    the PI servo of the static loads, then the cyclic bound-to-bound profile."""
    p, lay = rig.params, rig.layout
    c = Control(every=p.control_every)
    f = c.clump_reaction(lay.loading, axis=1)
    c.clump_position(lay.loading, axis=1)
    c.wall_force(lay.bottom, axis=1, scale=-1.0)             # downwards +
    c.wall_force(list(lay.left) + list(lay.right), axis=1, scale=-1.0)
    ball = c.held_clump(lay.loading, axis=1)
    # approach at the top speed until the ball presses the plate (5 % of the first load):
    # the windows count from that contact, so a plate still settling under its own
    # weight does not use them up
    c.servo(f, ball, target=p.static_loads_kN[0] * KN, gain=p.servo_gain_m_s_per_kN,
            gain_unit=KN, v_max=p.servo_velocity_m_s, integral_steps=p.servo_integral_steps,
            window_steps=p.static_window_steps, touch=0.05 * p.static_loads_kN[0] * KN)
    c.cyclic(f, ball, lo=p.cyclic_min_kN * KN, hi=p.cyclic_max_kN * KN,
             v_min=p.cyclic_v_min_m_s, v_max=p.cyclic_v_max_m_s,
             brake=p.cyclic_braking_fraction, direction=1, active=False)
    return c.build()


class LoadingRun(CyclicRun):
    """The box loading: static loads held by the servo, then cycles of the profile; the
    records of each cycle (CYCLE_FIELDS, bottom and side forces and snapshots at the peak)
    and its behaviours (ballaststudy.metrics)."""
    CHANNELS = {"force": FORCE, "y": Y}
    CYCLE_FIELDS = CYCLE_FIELDS
    State = LoadingState

    def __init__(self, rig, cycles, checkpoint=None, checkpoint_every=None, metrics=None,
                 resumed=False):
        """``metrics``: the config's ``metrics:`` section (dict) for the behaviours computed
        at the end of every cycle by ``ballaststudy.metrics`` (None = its defaults).
        ``resumed``: the engine comes from a checkpoint, its loading timestep already set."""
        p = rig.params
        super().__init__(rig, cycles, loading_control(rig), checkpoint,
                         checkpoint_every or p.checkpoint_every, metrics, p.max_cycle_steps)
        self.bottom = []     # (cycle, segment) at peak
        self.side = []       # (cycle, 2, 2) at peak
        self.snap_cycles, self.snap_pos, self.snap_frag = [], [], []
        self.snap_contacts = []
        self._metrics_setup()
        if p.loading_dt_factor > 1.0 and not resumed:
            rig.sim.set_density_scaling(p.loading_dt_factor * rig.sim.dt)

    def _metrics_setup(self):
        self.metrics_params = MetricsParams.from_config(self.s.metrics_cfg)
        # stone solids reused between cycles; emptied at every checkpoint cycle so that a
        # resumed run computes what an uninterrupted one does
        self.solid_cache = SolidCache(self.metrics_params.solid_reuse_tolerance)

    # --------------------------------------------------------------- events
    def check_stalled(self):
        p, s, c = self.rig.params, self.s, self.control
        approach = c.get(SERVO, "approach_steps")
        if s.phase == "static" and approach > p.static_max_windows * p.static_window_steps:
            raise RuntimeError(f"the loading ball did not reach the plate within "
                               f"{approach:.0f} steps")
        super().check_stalled()

    def on_window(self, controller):
        """A static window is complete: next load if its mean is within tolerance."""
        p, s, c = self.rig.params, self.s, self.control
        means = c.window_means()
        target = p.static_loads_kN[s.target] * KN
        s.windows += 1
        if abs(means[FORCE] - target) / target < p.static_tolerance:
            s.static_mean.append(float(means[FORCE]))
            s.static_walls.append((float(means[BOTTOM]), float(means[SIDE])))
            s.target += 1
            s.windows = 0
            c.set(SERVO, integral=0.0)
            if s.target < len(p.static_loads_kN):
                c.set(SERVO, target=p.static_loads_kN[s.target] * KN)
            else:                      # unload towards the cyclic minimum
                c.set(SERVO, active=False)
                c.set(PROFILE, active=True, direction=1)
                s.phase = "unload"
                s.static_end_step = self.rig.sim.step
                s.y_ref = c.reading(Y)
        elif s.windows >= p.static_max_windows:
            raise RuntimeError(f"static load {target / KN:g} kN not reached within "
                               f"{p.static_max_windows} windows (last mean "
                               f"{means[FORCE] / KN:.3f} kN)")

    def on_cycle_start(self):
        self.s.peak = None

    def on_peak(self):
        rig, s = self.rig, self.s
        px, py, pa = rig.plate_state()
        contacts = rig.sim.contact_list()
        s.peak = dict(y=self.control.reading(Y), px=px, py=py, pa=pa,
                      contacts=len(contacts["i"]))
        self.bottom.append(rig.bottom_forces())
        self.side.append(rig.side_forces())
        c = s.cycle
        snap = rig.params.snapshot_every
        if snap > 0 and (c % snap == 0 or c == self.cycles - 1):
            b = rig.sim.balls
            self.snap_cycles.append(c)
            self.snap_pos.append(b.pos[: rig.layout.n_stone_balls].astype(np.float32))
            self.snap_frag.append(rig.fragments())
            keep = contacts["i"] >= 0
            self.snap_contacts.append(
                {k: contacts[k][keep] for k in ("i", "j", "fx", "fy", "x", "y")})

    def _settlement_height(self):
        """Loading-ball height where the force first crosses the settlement force on the
        loading branch (linear between the samples around it; nan if it does not)."""
        fs = self.rig.params.settlement_force_kN * KN
        k0, kp = self.s.cycle_sample0, self.s.peak_sample
        f, y = self.samples["force"], self.samples["y"]
        for k in range(max(k0, 1), kp + 1):
            if f[k - 1] < fs <= f[k]:
                w = (fs - f[k - 1]) / (f[k] - f[k - 1])
                return y[k - 1] + w * (y[k] - y[k - 1])
        return float("nan")

    def cycle_row(self):
        rig, s = self.rig, self.s
        px, py, pa = rig.plate_state()
        pk = s.peak or dict(y=np.nan, px=np.nan, py=np.nan, pa=np.nan, contacts=0)
        modes = rig.stones.breakages(rig.sim)["mode"][s.log0:]
        force = self.samples["force"][s.cycle_sample0:]
        return dict(cycle_end_step=rig.sim.step, cycle_steps=rig.sim.step - s.cycle_start_step,
                    force_max=max(force), force_min=min(force),
                    y_at_settlement_force=self._settlement_height(),
                    y_at_peak=pk["y"], y_at_end=self.control.reading(Y),
                    plate_x_at_peak=pk["px"], plate_y_at_peak=pk["py"],
                    plate_angle_at_peak=pk["pa"], plate_x=px, plate_y=py, plate_angle=pa,
                    elements_broken_tension=int(np.sum(modes == "tension")),
                    elements_broken_shear=int(np.sum(modes == "shear")),
                    contacts=pk["contacts"])

    def _thin_samples(self, k0, every=None):
        """Keep every ``timeseries_every``-th sample of the finished cycle (and its last),
        so a 1000-cycle run stays a few tens of MB; the behaviours saw them all."""
        super()._thin_samples(k0, max(1, int(self.rig.params.timeseries_every)))

    def on_cycle_end(self):
        if self.s.cycle % self.checkpoint_every == 0:
            self.solid_cache.clear()

    # --------------------------------------------------------------- behaviours
    def snapshot(self):
        """The end-of-cycle snapshot ``ballaststudy.metrics.compute_cycle`` reads
        (bottom forces from the cycle's peak load, where the force propagates)."""
        rig, s, lay = self.rig, self.s, self.rig.layout
        sim = rig.sim
        b = sim.balls
        n = len(b)
        ballast = np.zeros(n, bool)
        ballast[: lay.n_stone_balls] = b.alive[: lay.n_stone_balls] == 1
        i, j, fn = rig.ball_contacts()
        cl = sim.contact_list()
        container = set(lay.bottom) | set(lay.left) | set(lay.right)
        wall = cl["j"] < 0
        touch = np.zeros(n, bool)
        seg = -1 - cl["j"][wall]
        touch[cl["i"][wall][np.isin(seg, list(container))]] = True
        bottom_seg = sim.walls.seg[lay.bottom]
        px, py, _ = rig.plate_state()
        p = rig.params
        k0 = s.cycle_sample0
        br = rig.stones.breakages(sim)
        link_i, link_j, link_intact = rig.stones.topology(sim)
        return dict(
            pos=b.pos.copy(), rad=b.rad.copy(), ballast=ballast,
            bond_i=link_i, bond_j=link_j, bond_intact=link_intact,
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
            break_step=br["step"][s.log0:],
            break_mode=mode_codes(br["mode"][s.log0:]).astype(np.int32),
            n_bonds_installed=int(s.n_bonds0), n_elements_per_bond=rig.stones.elements_per_unit(sim),
            cycle_start_step=int(s.cycle_start_step), cycle_end_step=int(sim.step) + 1,
            stone_unit=self.stone_units(n), mass=b.mass.copy())

    def behaviours(self):
        """This cycle's behaviours from ``ballaststudy.metrics`` (JSON-safe dict)."""
        rows = self.s.rows
        ref = rows[0].get("y_at_level") if rows else None
        out = compute_cycle(self.snapshot(), self.metrics_params, y_reference=ref,
                            solid_cache=self.solid_cache)
        return {k: (float(v) if isinstance(v, (float, np.floating)) else int(v))
                for k, v in out.items()}

    # --------------------------------------------------------------- checkpoint
    def _extra_arrays(self):
        d = {}
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

    def _load_extra(self, d):
        self._metrics_setup()
        self.bottom = list(d["bottom"])
        self.side = list(d["side"])
        self.snap_cycles = d["snap_cycles"].tolist()
        self.snap_pos = list(d["snap_pos"])
        self.snap_frag = list(d["snap_frag"])
        off = np.r_[0, np.cumsum(d["snap_contact_count"])]
        self.snap_contacts = [{k: d["snap_contact_" + k][a:b]
                               for k in ("i", "j", "fx", "fy", "x", "y")}
                              for a, b in zip(off[:-1], off[1:])]

    @classmethod
    def from_checkpoint(cls, path, cycles=None, checkpoint_every=None):
        """The run saved in ``path`` (its metrics settings come with it)."""
        return super().from_checkpoint(path, BoxRig, cycles=cycles,
                                       checkpoint_every=checkpoint_every)
