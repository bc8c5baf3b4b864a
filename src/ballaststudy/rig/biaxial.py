"""The cyclic biaxial test: the 2D analogue of the cyclic triaxial test on which the public
measured ballast data are taken (a 300 x 600 mm cylinder under a confining pressure p and
a cyclic deviator stress q). Built on the kit: deposition.py places and drops the stones,
dem.control runs the servos inside the engine's loop, cyclic.py keeps the records.

The specimen is a rectangle of bonded stones between a bottom platen, a top platen and two
frictionless sides: rigid side walls (``membrane_segments`` 1), or a flexible membrane, a
chain of ``membrane_segments`` segments per side, each under its own stress servo, so the
specimen bulges as a real one does (the segments' heights follow the platens: each spans
1/n of the specimen height). Stages:
1. deposition in a tall box of the specimen's width; balls above the specimen height cut;
2. isotropic consolidation: three stress servos (left, right, top) hold p until the
   window means of all three are within ``consolidation_tolerance`` of p;
3. cyclic loading: the side servos keep p; the top platen drives the axial stress
   sigma_1 = p + q between p + q_min and p + q_max — quasi-static: the bound-to-bound
   profile at the configured platen speeds, with density scaling (loading_dt_factor);
   real-time: true masses, a stress servo following a sinusoid at the test's frequency f
   in simulated time (a cycle lasts 1/f). Cycle 0 is the first loading from p to p + q_max
   and the unloading to p + q_min: load cycle N = 1 of a laboratory test.
2D stresses are forces per boundary length per thickness t (sigma = F / (L t)); strains are
compression positive from the end of consolidation: axial 1 - H/H0, volumetric (area)
1 - W H / (W0 H0), H and W between the walls' faces.
"""
from collections import namedtuple
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from ..dem.control import Control
from .base import Rig
from .cyclic import CycleState, CyclicRun
from .deposition import (DepositionParams, choose_stones, deposition_conditions, drop,
                         new_simulation, place_stones, ramp_gravity, remove_debris,
                         shelf_centres)

KPA = 1.0e3
PLATEN, MEMBRANE = 2, 3      # wall materials: platens with Table 4.2's friction, side walls without


@dataclass
class BiaxialParams(DepositionParams):
    RIG: ClassVar[str] = "biaxial"
    # specimen (assembly)
    width_m: float = 0.30              # 2D slice of the 300 mm x 600 mm triaxial cylinder
    height_m: float = 0.60
    membrane_friction: float = 0.0     # side walls stand for the membrane: frictionless
    membrane_segments: int = 1         # 1: rigid side walls; n > 1: a membrane of n segments a side
    relax_steps: int = 5000
    # loading
    confining_pressure_kPa: float = 30.0
    deviator_min_kPa: float = 15.0
    deviator_max_kPa: float = 230.0
    servo_gain_m_s_per_kPa: float = 2.0e-4
    servo_velocity_m_s: float = 0.01
    servo_integral_steps: int = 5000
    consolidation_window_steps: int = 5000
    consolidation_tolerance: float = 0.02
    consolidation_max_windows: int = 200
    mode: str = "quasi_static"         # or "real_time": true masses, sinusoidal q at f
    frequency_Hz: float = 20.0
    realtime_gain_m_s_per_kPa: float = 5.0e-4   # the platen's servo in real-time mode
    realtime_velocity_m_s: float = 0.05
    platen_v_max_m_s: float = 0.005
    platen_v_min_m_s: float = 0.0005
    braking_fraction: float = 0.25
    failure_axial_strain: float = 0.15   # a stress-controlled specimen beyond this has failed
    softening_strain: float = 0.02       # ... or once sigma_1 fell past its peak over this strain
    cycles: int = 100
    control_every: int = 10
    loading_dt_factor: float = 2.0
    checkpoint_every: int = 50
    timeseries_every: int = 10
    vtk_cycles: list = field(default_factory=lambda: [0, -1])
    max_cycle_steps: int = 5000000

    def take_conditions(self, c):
        """A measured test's loading conditions (``measured.importer.load_conditions``):
        p, the q bounds, f."""
        self.confining_pressure_kPa = c["confining_pressure_kPa"]
        self.deviator_max_kPa = c["deviator_max_kPa"]
        if c.get("deviator_min_kPa") is not None:
            self.deviator_min_kPa = c["deviator_min_kPa"]
        if c.get("frequency_Hz") is not None:
            self.frequency_Hz = c["frequency_Hz"]
        if not self.deviator_min_kPa < self.deviator_max_kPa:
            raise ValueError(f"deviator {self.deviator_min_kPa:g}-{self.deviator_max_kPa:g} kPa: "
                             "the minimum must be below the maximum")


@dataclass
class BiaxialLayout:
    bottom: list = field(default_factory=list)    # wall segment ids
    top: list = field(default_factory=list)
    left: list = field(default_factory=list)      # every segment of a side
    right: list = field(default_factory=list)
    left_groups: list = field(default_factory=list)   # membrane: segment ids per servo, bottom up
    right_groups: list = field(default_factory=list)
    stone_library_index: list = field(default_factory=list)
    stone_material: list = field(default_factory=list)
    n_stone_balls: int = 0
    bonds_library: int = 0
    bonds_installed: int = 0
    seed: int = 0
    database: str = ""
    library: str = ""
    stage_steps: dict = field(default_factory=dict)


class BiaxialRig(Rig):
    Layout = BiaxialLayout
    Params = BiaxialParams
    title = "cyclic biaxial case: assembled specimen"
    kind = "biaxial"

    def wall_groups(self):
        lay = self.layout
        return {"bottom": lay.bottom, "top": lay.top, "left": lay.left, "right": lay.right}

    def _x(self, ids):
        return float(self.sim.walls.seg[ids[0], 0])

    def side_groups(self, side):
        """Segment ids per side servo, bottom up: one group (the rigid wall) or n."""
        lay = self.layout
        groups = lay.left_groups if side == "left" else lay.right_groups
        return groups or [lay.left if side == "left" else lay.right]

    def side_x(self, side):
        """x of each servo group of a side, bottom up."""
        return np.array([self._x(g) for g in self.side_groups(side)])

    def width(self):
        """Mean width between the sides (area / height: the membrane's segments span equal
        heights), as the area correction of a triaxial test."""
        return float(np.mean(self.side_x("right") - self.side_x("left")))

    def height(self):
        seg = self.sim.walls.seg
        return float(seg[self.layout.top[0], 1] - seg[self.layout.bottom[0], 1])

    def stresses(self):
        """(sigma_axial at the top platen, sigma_left, sigma_right) [Pa], compression +."""
        f = self.sim.wall_force()
        t, lay = self.sim.thickness, self.layout
        w, h = self.width(), self.height()
        return (float(f[lay.top, 1].sum()) / (w * t), float(-f[lay.left, 0].sum()) / (h * t),
                float(f[lay.right, 0].sum()) / (h * t))


# ----------------------------------------------------------------------------- assembly
def build_specimen(lib, params, seed):
    """Stones on shelves in a tall box of the specimen's width (bottom platen at y = 0,
    side walls reaching well above the shelves); bonds installed."""
    p = params
    rng = np.random.default_rng(seed)
    picks = choose_stones(lib, p.fill_area_ratio * p.width_m * p.height_m, rng)
    stones = [lib.stone(k) for k in picks]
    w2 = 0.5 * p.width_m
    centres, top = shelf_centres(stones, -w2, w2, p.placement_gap_factor, rng)
    h_tall = top + p.height_m
    margin = max(p.width_m, 0.1)
    sim = new_simulation(lib, p, (-w2 - margin, -margin, w2 + margin, h_tall + margin),
                         p.contact_damping_ratio)
    lay = BiaxialLayout(seed=int(seed), database=lib.database, library=lib.path,
                        stone_library_index=[int(k) for k in picks],
                        stone_material=[int(s.material) for s in stones])
    wide = 0.6 * p.width_m       # platens reach past the side walls as these move in
    lay.bottom = sim.add_wall([(-w2 - wide, 0.0), (w2 + wide, 0.0)], material_id=PLATEN).tolist()
    n = p.membrane_segments
    ys = [h_tall] + ([] if n == 1 else list(np.linspace(p.height_m, 0.0, n + 1))) + [-0.05 * p.height_m]
    lay.left = sim.add_wall([(-w2, y) for y in ys], material_id=MEMBRANE).tolist()
    lay.right = sim.add_wall([(w2, y) for y in ys[::-1]], material_id=MEMBRANE).tolist()
    if n > 1:
        lay.left_groups = membrane_groups(lay.left[::-1])
        lay.right_groups = membrane_groups(lay.right)
    lay.bonds_library = place_stones(sim, lib, stones, centres, rng)
    lay.n_stone_balls = len(sim.balls)
    lay.bonds_installed = int(sim.install_flat_joints({m: lib.materials[m]["fj"]
                                                      for m in (0, 1)}))
    return BiaxialRig(sim, lay, p)


def membrane_groups(chain):
    """Servo groups of a membrane chain given bottom up (extension below, n segments,
    extension above): the membrane segment first, the extensions with the end segments."""
    groups = [[k] for k in chain[1:-1]]
    groups[0].append(chain[0])
    groups[-1].append(chain[-1])
    return groups


def place_membrane(rig):
    """Each side's n membrane segments span 1/n of the specimen height between the platens
    (their x kept; the extensions beyond the platens follow). Returns the segment length."""
    lay, seg = rig.layout, rig.sim.walls.seg
    bottom, top = float(seg[lay.bottom[0], 1]), float(seg[lay.top[0], 1])
    n = len(lay.left_groups)
    y = np.linspace(bottom, top, n + 1)
    for side in ("left", "right"):
        down = side == "left"              # the left chain runs top down, the right bottom up
        for k, group in enumerate(rig.side_groups(side)):
            lo, hi = y[k], y[k + 1]
            rig.sim.set_segment_y(group[0], *((hi, lo) if down else (lo, hi)))
            if len(group) > 1:             # an extension, joined at the chain's end node
                joint = lo if k == 0 else hi
                starts_there = (k == 0) == down
                rig.sim.set_segment_y(group[1], *((joint, None) if starts_there else (None, joint)))
    return (top - bottom) / n


def wall_friction(rig, mu):
    """Platens: ``mu`` (Table 4.2's); side walls: the membrane's."""
    sim = rig.sim
    for m in (0, 1):
        sim.set_contact_coefficient("mu", mu, m, PLATEN)
        sim.set_contact_coefficient("mu", rig.params.membrane_friction, m, MEMBRANE)


def assemble_biaxial(lib, params, seed, progress=None):
    """Deposition, the cut at the specimen height, the top platen on the highest stone,
    relaxation at normal gravity. Returns the BiaxialRig (not yet consolidated)."""
    rig = build_specimen(lib, params, seed)
    p, sim, lay, st = params, rig.sim, rig.layout, rig.layout.stage_steps
    mu = lib.materials[0]["lc"].mu
    n_stones = len(lay.stone_library_index)
    st["drop"] = (deposition_conditions(rig, p, mu, on=True)
                  + drop(rig, p, n_stones, progress))
    st["gravity"] = ramp_gravity(rig, p.drop_gravity_m_s2, p.gravity_m_s2, p.gravity_ramp_steps,
                                 progress)
    b = sim.balls
    ids = rig.stone_balls()
    sim.delete_balls(ids[b.pos[ids, 1] + b.rad[ids] > p.height_m])
    remove_debris(rig, p.min_fragment_balls)
    deposition_conditions(rig, p, mu, on=False)
    wall_friction(rig, mu)
    sim.scale_bond_strength(1.0 / p.drop_bond_factor)
    ids = rig.stone_balls()
    top = float((b.pos[ids, 1] + b.rad[ids]).max())
    w2, wide = 0.5 * p.width_m, 0.6 * p.width_m
    lay.top = sim.add_wall([(w2 + wide, top), (-w2 - wide, top)], material_id=PLATEN).tolist()
    if lay.left_groups:
        place_membrane(rig)
    sim.set_damping(p.damping)
    sim.run(p.relax_steps)
    st["relax"] = p.relax_steps
    if progress is not None:
        progress(p.relax_steps)
    return rig


# ----------------------------------------------------------------------------- loading
AXIAL, LEFT, RIGHT, HEIGHT, X_LEFT, X_RIGHT = range(6)        # sensors (then the segments')
# controllers: the side servos (two rigid walls, or one per membrane segment), then these
ControllerIds = namedtuple("ControllerIds", "sides top profile sine segment_sensors")


def segment_scales(n_groups, seg_len, t):
    """Stress per summed x force of each membrane segment, left ones first (compression +:
    the balls push the left wall towards -x): -+1 / (L t)."""
    return [(-1.0 if k < n_groups // 2 else 1.0) / (seg_len * t) for k in range(n_groups)]


def biaxial_control(rig):
    """Stress sensors of the moving walls (each side as a whole, and each membrane segment),
    their positions, and the controllers: the side servos (on while cycling), the top
    platen's consolidation servo, the profile and the sinusoid. Returns (Control, ids)."""
    p, lay, t = rig.params, rig.layout, rig.sim.thickness
    w, h = rig.width(), rig.height()
    groups = rig.side_groups("left") + rig.side_groups("right")
    c = Control(every=p.control_every)
    c.wall_force(lay.top, axis=1, scale=1.0 / (w * t))
    c.wall_force(lay.left, axis=0, scale=-1.0 / (h * t))
    c.wall_force(lay.right, axis=0, scale=1.0 / (h * t))
    c.wall_position(lay.top, axis=1)
    c.wall_position([g[0] for g in rig.side_groups("left")], axis=0)
    c.wall_position([g[0] for g in rig.side_groups("right")], axis=0)
    servo = dict(target=p.confining_pressure_kPa * KPA, gain_unit=KPA,
                 v_max=p.servo_velocity_m_s, integral_steps=p.servo_integral_steps,
                 window_steps=p.consolidation_window_steps)
    if lay.left_groups:           # a servo per membrane segment, on its own stress
        scales = segment_scales(len(groups), h / len(lay.left_groups), t)
        sensors = [c.wall_force(g, axis=0, scale=f) for g, f in zip(groups, scales)]
    else:
        sensors = [LEFT, RIGHT]
    sides = [c.servo(sensor, c.walls(g, 0), gain=(-1.0 if k < len(groups) // 2 else 1.0)
                     * p.servo_gain_m_s_per_kPa, **servo)       # left: +x raises its stress
             for k, (sensor, g) in enumerate(zip(sensors, groups))]
    top = c.walls(lay.top, 1)
    s_top = c.servo(AXIAL, top, gain=p.servo_gain_m_s_per_kPa, **servo)
    sig3 = p.confining_pressure_kPa * KPA
    lo, hi = sig3 + p.deviator_min_kPa * KPA, sig3 + p.deviator_max_kPa * KPA
    profile = c.cyclic(AXIAL, top, lo=lo, hi=hi, v_min=p.platen_v_min_m_s,
                       v_max=p.platen_v_max_m_s, brake=p.braking_fraction, direction=-1,
                       active=False)
    sine = c.sine(AXIAL, top, lo=lo, hi=hi, frequency=p.frequency_Hz,
                  gain=p.realtime_gain_m_s_per_kPa, gain_unit=KPA, v_max=p.realtime_velocity_m_s,
                  integral_steps=p.servo_integral_steps, active=False)
    ids = ControllerIds(sides, s_top, profile, sine, sensors if lay.left_groups else [])
    return c.build(), ids


CYCLE_FIELDS = {
    "cycle_end_step": ("1", "engine step at the end of the cycle"),
    "cycle_steps": ("1", "engine steps in the cycle"),
    "axial_stress_max": ("Pa", "largest axial stress sigma_1 at the top platen in the cycle (2D: force / (width t))"),
    "axial_stress_min": ("Pa", "smallest axial stress sigma_1 in the cycle"),
    "confining_stress_mean": ("Pa", "mean side-wall stress sigma_3 over the cycle (2D: force / (height t))"),
    "height_at_end": ("m", "specimen height between the platens at the end of the cycle"),
    "width_at_end": ("m", "mean specimen width between the sides (area / height) at the end of the cycle"),
    "width_max_at_end": ("m", "largest width between the sides (the membrane's bulge) at the end of the cycle"),
    "elements_broken_tension": ("1", "flat-joint elements broken in tension since loading began"),
    "elements_broken_shear": ("1", "flat-joint elements broken in shear since loading began"),
}


@dataclass
class BiaxialState(CycleState):
    phase: str = "consolidation"
    windows: int = 0
    loading_start_step: int = -1      # end of consolidation
    height0: float = float("nan")     # H0, W0: at the end of consolidation
    width0: float = float("nan")
    window_means: list = field(default_factory=list)    # stress window means (axial, left, right)
    failure: str = ""                 # why the specimen failed ("" = it did not)
    peak_stress: float = 0.0          # sigma_1's largest recent mean in this loading, its strain
    peak_strain: float = 0.0


class BiaxialRun(CyclicRun):
    """Consolidation, then cycles of the deviator (quasi-static or real-time); per cycle
    the records above and the behaviours (strains, breakage)."""
    CHANNELS = {"axial_stress": AXIAL, "left_stress": LEFT, "right_stress": RIGHT,
                "platen_y": HEIGHT, "left_x": X_LEFT, "right_x": X_RIGHT}
    CYCLE_FIELDS = CYCLE_FIELDS
    CYCLING = ("loading", "cyclic")     # the first loading is cycle 0
    State = BiaxialState

    def __init__(self, rig, cycles, checkpoint=None, checkpoint_every=None, metrics=None,
                 resumed=False):
        p = rig.params
        control, self.ids = biaxial_control(rig)
        super().__init__(rig, cycles, control, checkpoint,
                         checkpoint_every or p.checkpoint_every, metrics, p.max_cycle_steps)
        if p.mode not in ("quasi_static", "real_time"):
            raise ValueError(f"loading mode {p.mode!r}: quasi_static or real_time")
        if p.mode == "quasi_static" and p.loading_dt_factor > 1.0 and not resumed:
            rig.sim.set_density_scaling(p.loading_dt_factor * rig.sim.dt)

    def _rescale(self):
        """Stress sensors follow the specimen's current size."""
        c, t = self.control, self.rig.sim.thickness
        w, h = self.rig.width(), self.rig.height()
        c.set_scale(AXIAL, 1.0 / (w * t))
        c.set_scale(LEFT, -1.0 / (h * t))
        c.set_scale(RIGHT, 1.0 / (h * t))

    def advance(self, max_steps=None):
        """A membrane follows the platens (segment heights, their stress sensors) before
        every run of the engine (at least every control buffer: well below a mm of platen
        travel); before, not after, so a resumed run does what an uninterrupted one does."""
        sensors = self.ids.segment_sensors
        if sensors:
            scales = segment_scales(len(sensors), place_membrane(self.rig), self.rig.sim.thickness)
            for sensor, f in zip(sensors, scales):
                self.control.set_scale(sensor, f)
        super().advance(max_steps)

    def on_window(self, controller):
        p, s, c = self.rig.params, self.s, self.control
        means = c.window_means()
        self._rescale()
        if s.phase not in ("consolidation", "hold"):
            return
        s.windows += 1
        sig = means[[AXIAL, LEFT, RIGHT]]
        s.window_means.append([float(v) for v in sig])
        p3 = p.confining_pressure_kPa * KPA
        target = np.array([c.get(self.ids.top, "target"), p3, p3])
        if np.all(np.abs(sig - target) / target < p.consolidation_tolerance):
            s.windows = 0
            if s.phase == "hold":
                s.phase = "held"
                return
            s.phase = "loading"
            s.loading_start_step = self.rig.sim.step
            self._start_cycle()                 # the first loading is load cycle N = 1
            s.height0, s.width0 = self.rig.height(), self.rig.width()
            for k in self.ids.sides:        # keep p; no more windows
                c.set(k, window_steps=np.inf)
            c.set(self.ids.top, active=False)
            if p.mode == "real_time":       # the sinusoid starts at p + q_min now
                c.set(self.ids.sine, active=True, t0=self.rig.sim.time, half_periods=0,
                      integral=0.0)
            else:
                c.set(self.ids.profile, active=True, direction=-1)
        elif s.windows >= p.consolidation_max_windows:
            raise RuntimeError(f"{s.phase} at {', '.join(f'{v / KPA:g}' for v in target)} kPa "
                               f"not reached within {s.windows} windows (last means "
                               f"{', '.join(f'{v / KPA:.2f}' for v in sig)} kPa)")

    def hold(self, q_kPa):
        """A static deviator stage (after consolidation, instead of cycling): the top servo
        holds p + q, the side ones p, until the window means of all three are within the
        tolerance. Returns those means (axial, left, right) [Pa]."""
        p, s, c = self.rig.params, self.s, self.control
        while s.phase == "consolidation":
            self.advance()
        c.set(self.ids.profile, active=False)
        c.set(self.ids.sine, active=False)
        c.set(self.ids.top, active=True, integral=0.0,
              target=(p.confining_pressure_kPa + q_kPa) * KPA)
        for k in (*self.ids.sides, self.ids.top):
            c.set(k, window_steps=p.consolidation_window_steps)
        c.reset_window()
        s.phase, s.windows = "hold", 0
        while s.phase == "hold":
            self.advance()
        return np.array(s.window_means[-1])

    def on_peak(self):
        self._rescale()

    def check_stalled(self):
        """A stress-controlled specimen that cannot carry sigma_1 = p + q_max fails, as in the
        laboratory: its axial strain runs away. The run ends as a result, not an error, when
        the axial strain reaches failure_axial_strain, or sigma_1 (mean of the last 50
        samples) passed a peak below the bound and the specimen went on straining by
        softening_strain (the peak strength of a strain-controlled test), or a loading to
        p + q_max does not end within max_cycle_steps; ``failure`` says which, where and at
        what stress."""
        s, p = self.s, self.rig.params
        if s.phase not in ("loading", "cyclic"):
            return super().check_stalled()
        ea, sig1 = self.strains()[0], float(np.mean(self.samples["axial_stress"][-50:]))
        if sig1 > s.peak_stress:
            s.peak_stress, s.peak_strain = sig1, ea
        steps = self.rig.sim.step - (s.loading_start_step if s.phase == "loading" else s.cycle_start_step)
        if ea >= p.failure_axial_strain:
            why = f"axial strain {ea:.3f} reached failure_axial_strain {p.failure_axial_strain:g}"
        elif ea - s.peak_strain >= p.softening_strain and s.peak_sample < 0:
            why = (f"sigma_1 peaked at {s.peak_stress / KPA:.1f} kPa (axial strain {s.peak_strain:.4f}) "
                   f"and fell below it over a further softening_strain {p.softening_strain:g}")
        elif steps > p.max_cycle_steps:
            why = (f"sigma_1 did not reach p + q_max = {p.confining_pressure_kPa + p.deviator_max_kPa:g} "
                   f"kPa within max_cycle_steps {p.max_cycle_steps} (axial strain {ea:.4f})")
        else:
            return
        where = "in the first loading" if s.phase == "loading" else f"in cycle {s.cycle}"
        s.failure = (f"the specimen failed {where}: {why}; sigma_1 "
                     f"{self.control.reading(AXIAL) / KPA:.1f} kPa at that moment")
        s.phase = "done"

    def _trough(self):
        """The first trough after consolidation ends cycle 0 (N = 1 of a laboratory test: the
        first loading from p to p + q_max and the unloading to p + q_min)."""
        self._rescale()
        self.s.peak_stress = 0.0        # each loading branch is watched for softening anew
        if self.s.phase == "loading":
            self.s.phase = "cyclic"
        super()._trough()

    def strains(self):
        """(axial, volumetric) strain since the end of consolidation, compression +."""
        s = self.s
        h, w = self.rig.height(), self.rig.width()
        return 1.0 - h / s.height0, 1.0 - (w * h) / (s.width0 * s.height0)

    def cycle_row(self):
        rig, s = self.rig, self.s
        modes = rig.sim.breakages()["mode"][s.log0:]
        sig1 = self.cycle_samples("axial_stress")
        sig3 = 0.5 * (self.cycle_samples("left_stress") + self.cycle_samples("right_stress"))
        return dict(cycle_end_step=rig.sim.step, cycle_steps=rig.sim.step - s.cycle_start_step,
                    axial_stress_max=float(sig1.max()), axial_stress_min=float(sig1.min()),
                    confining_stress_mean=float(sig3.mean()), height_at_end=rig.height(),
                    width_at_end=rig.width(),
                    width_max_at_end=float(np.max(rig.side_x("right") - rig.side_x("left"))),
                    elements_broken_tension=int(np.sum(modes == "tension")),
                    elements_broken_shear=int(np.sum(modes == "shear")))

    def behaviours(self):
        """Strains, breakage (eqs. 4.6-4.8), fragments, mean coordination and void ratio of
        the specimen rectangle between the walls (ballaststudy.metrics' functions)."""
        from ..metrics.breakage import breakage_rate
        rig, s = self.rig, self.s
        br = rig.sim.breakages()
        mode = np.where(br["mode"][s.log0:] == "tension", 1, 2)
        rates = breakage_rate(mode, br["step"][s.log0:], s.n_bonds0,
                              [s.cycle_start_step, rig.sim.step + 1],
                              int(rig.sim.bonds.state.shape[1]))
        ea, ev = self.strains()
        out = {k: v[0].item() for k, v in rates.items()}
        out.update(axial_strain=float(ea), volumetric_strain=float(ev), **self.packing())
        return out

    def packing(self):
        """Fragments, mean coordination number (ball-ball contacts carrying force) and
        void ratios of the specimen rectangle, stones as solid and balls as solid."""
        from ..metrics import MetricsParams
        from ..metrics.coordination import coordination_numbers
        from ..metrics.fragments import fragments
        from ..metrics.void_ratio import SolidCache, void_ratio
        if not hasattr(self, "_solids"):
            self._params = MetricsParams.from_config(self.s.metrics_cfg)
            self._solids = SolidCache(self._params.solid_reuse_tolerance)
        rig, mp = self.rig, self._params
        b, bd = rig.sim.balls, rig.sim.bonds
        stone = np.zeros(len(b), bool)
        stone[rig.stone_balls()] = True
        intact = rig.sim.intact_bonds()
        nf, labels = fragments(len(b), bd.i, bd.j, intact, stone)
        cn = coordination_numbers(labels, nf, *rig.ball_contacts(),
                                  mp.contact_force_threshold, False)
        seg, lay = rig.sim.walls.seg, rig.layout
        vr = void_ratio(b.pos, b.rad, labels, nf, bd.i, bd.j, intact,
                        rig.side_x("left").mean(), rig.side_x("right").mean(),
                        float(seg[lay.bottom[0], 1]), float(seg[lay.top[0], 1]),
                        mp.disk_quad_segs, self._solids)
        return dict(n_fragments=int(nf), mean_coordination=float(cn.mean()) if nf else np.nan,
                    void_ratio=vr["void_ratio"], void_ratio_e=vr["void_ratio_e"],
                    void_ratio_balls=vr["void_ratio_balls"])

    def on_cycle_end(self):
        if self.s.cycle % self.checkpoint_every == 0 and hasattr(self, "_solids"):
            self._solids.clear()     # a resumed run computes what an uninterrupted one does

    def _thin_samples(self, k0, every=None):
        super()._thin_samples(k0, max(1, int(self.rig.params.timeseries_every)))

    @classmethod
    def from_checkpoint(cls, path, cycles=None, checkpoint_every=None):
        return super().from_checkpoint(path, BiaxialRig, cycles=cycles,
                                       checkpoint_every=checkpoint_every)


CHANNEL_UNITS = {
    "axial_stress": ("Pa", "axial stress sigma_1 at the top platen (2D: force / (width t))"),
    "left_stress": ("Pa", "stress on the left side wall (2D: force / (height t))"),
    "right_stress": ("Pa", "stress on the right side wall (2D: force / (height t))"),
    "platen_y": ("m", "top platen height"),
    "left_x": ("m", "left side wall x"),
    "right_x": ("m", "right side wall x"),
}


def write_biaxial_outputs(run, out, figures=True, attrs=None):
    """metrics.nc of a biaxial run (+ the specimen figure beside it)."""
    from pathlib import Path

    from ..metrics.output import write_metrics
    from .output import write_figures
    from .records import cyclic_dataset
    s = run.s
    ds = cyclic_dataset(run, CHANNEL_UNITS, "cyclic biaxial case: per-cycle records and "
                        "behaviours", {"confining_pressure_Pa": run.rig.params.confining_pressure_kPa * KPA,
                                       "height_at_consolidation_m": s.height0,
                                       "width_at_consolidation_m": s.width0,
                                       "stress_convention": "2D stresses: force per boundary "
                                       "length per thickness t; compression positive",
                                       "failed": int(bool(s.failure)), "failure": s.failure,
                                       **(attrs or {})})
    write_metrics(Path(out), ds)
    if figures:
        write_figures(run, ds, out, "biaxial specimen ")
    return ds
