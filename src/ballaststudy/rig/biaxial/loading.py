"""Loading the biaxial specimen: the stress sensors and controllers (kit: dem.control),
isotropic consolidation, a static deviator hold, and cycles of the deviator (cycle 0 the
bound-to-bound profile, then a sinusoid at the test's f in real time or at the f of the
quasi-static bounds) with the records of each cycle; the behaviours per cycle
from ``ballaststudy.metrics.biaxial``, failure of a specimen that cannot carry p + q_max."""
from collections import namedtuple
from dataclasses import dataclass, field

import numpy as np

from ...dem.control import Control
from ...metrics.biaxial import compute_biaxial_cycle
from ...metrics.cycle import MetricsParams
from ...metrics.strain import axial_strain, specimen_strains
from ...metrics.void_ratio import SolidCache
from ...metrics.breakage import mode_codes
from ..cyclic import CycleState, CyclicRun
from .inertial import bulk_density, profile_speed, quasi_static_frequency, travel_time
from .params import KPA
from .peak import WINDOW_STRAIN, lookback_start, new_peak
from .specimen import BiaxialRig, place_membrane

AXIAL, LEFT, RIGHT, HEIGHT, X_LEFT, X_RIGHT = range(6)        # sensors (then the segments')
# controllers: the side servos (two rigid walls, or one per membrane segment), then these
ControllerIds = namedtuple("ControllerIds", "sides top profile sine segment_sensors")
# sigma_1's records are the means over this interval, as a load cell read at 2 kHz records
# it: a sample (one step's contact forces on the platen) carries single contacts' pulses, up
# to ~5 % of p + q_max on the small specimen, that a lab load cell's bandwidth and the
# platen's mass filter out; a 60 Hz sinusoid's peak reads 0.1 % of its range low
LOAD_CELL_INTERVAL_S = 0.5e-3


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
    s_top = c.servo(AXIAL, top, gain=p.servo_gain_m_s_per_kPa,
                    **{**servo, "v_max": p.consolidation_platen_velocity_m_s})
    lo, hi = p.axial_bounds_Pa
    profile = c.cyclic(AXIAL, top, lo=lo, hi=hi, v_min=0.0, v_max=0.0, brake=0.0, direction=-1,
                       active=False)      # the strength test's constant speed (it sets it)
    sine = c.sine(AXIAL, top, lo=lo, hi=hi, frequency=p.frequency_Hz,
                  gain=p.servo_gain_m_s_per_kPa, gain_unit=KPA, v_max=p.sine_velocity_min_m_s,
                  integral_steps=p.servo_integral_steps, active=False)  # gain and v_max: from
                  # the compliance measured in cycle 0 (BiaxialRun._sine_servo) before it starts
    ids = ControllerIds(sides, s_top, profile, sine, sensors if lay.left_groups else [])
    return c.build(), ids


CYCLE_FIELDS = {
    "cycle_end_step": ("1", "engine step at the end of the cycle"),
    "cycle_steps": ("1", "engine steps in the cycle"),
    "axial_stress_max": ("Pa", "largest axial stress sigma_1 at the top platen in the cycle (2D: force / "
                         "(width t)), as a load cell records it: the running mean over 0.5 ms, LOAD_CELL_INTERVAL_S"),
    "axial_stress_min": ("Pa", "smallest axial stress sigma_1 in the cycle's unloading (after its peak: "
                         "cycle 0 starts from the consolidation's p), as axial_stress_max"),
    "confining_stress_mean": ("Pa", "mean side-wall stress sigma_3 over the cycle (2D: force / (height t))"),
    "height_at_end": ("m", "specimen height between the platens at the end of the cycle"),
    "width_at_end": ("m", "mean specimen width between the sides (area / height) at the end of the cycle"),
    "width_max_at_end": ("m", "largest width between the sides (the membrane's bulge) at the end of the cycle"),
    "elements_broken_tension": ("1", "flat-joint elements broken in tension since loading began"),
    "elements_broken_shear": ("1", "flat-joint elements broken in shear since loading began"),
    "inertia_added": ("1", "inertial mass density scaling adds to the free balls at the end of the "
                      "cycle, as a fraction of their real mass"),
    "loading_frequency": ("Hz", "frequency of the sinusoidal deviator in the cycle's unloading "
                          "(real time: the test's; quasi-static: from the inertial-number and "
                          "stress-wave bounds, rig.biaxial.inertial; NaN in cycle 0, the "
                          "bound-to-bound profile)"),
}


@dataclass
class BiaxialState(CycleState):
    phase: str = "consolidation"
    windows: int = 0
    settled_windows: int = 0          # windows in a row within the tolerance, at rest
    window_height: float = float("nan")   # specimen height and time at the last window
    window_time: float = float("nan")
    loading_start_step: int = -1      # end of consolidation
    height0: float = float("nan")     # H0, W0: at the end of consolidation
    width0: float = float("nan")
    window_means: list = field(default_factory=list)    # stress window means (axial, left, right)
    compliance: list = field(default_factory=lambda: [0.0, 0.0])   # C [m/Pa] of the last loading
                                      # and unloading branch (0: none yet)
    half_sample0: int = -1            # the sample where this half cycle began
    prev_half_sample0: int = -1       # ... and where the one before it began
    unloading_frequency: float = 0.0  # the sinusoid's, in this cycle's unloading
    peak_stress: float = 0.0          # q's largest window mean [Pa] in this loading branch and
    peak_strain: float = float("nan")  # the axial strain at the window's centre (peak.py)
    watched_samples: int = 0          # the samples check_stalled has read in this branch
    sine_servo_step: int = -1         # the engine step the sinusoid's servo was last set at


class BiaxialRun(CyclicRun):
    """Consolidation, then cycles of the deviator (quasi-static or real-time); per cycle
    the records above and the behaviours (``metrics.biaxial.compute_biaxial_cycle``)."""
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
        self._metrics_setup()
        if p.mode not in ("quasi_static", "real_time"):
            raise ValueError(f"loading mode {p.mode!r}: quasi_static or real_time")
        if p.load_control not in ("applied_force", "servo"):
            raise ValueError(f"load_control {p.load_control!r}: applied_force or servo")
        if p.loading_dt_factor > 1.0 and not resumed:   # at rest while consolidating
            rig.sim.set_density_scaling(p.loading_dt_factor * rig.sim.dt)

    def _metrics_setup(self):
        """The ``metrics:`` settings (again after a resume: the checkpoint's) and the stone
        solids reused between cycles (emptied at every checkpoint cycle, so that a resumed
        run computes what an uninterrupted one does)."""
        self.metrics_params = MetricsParams.from_config(self.s.metrics_cfg)
        self.solid_cache = SolidCache(self.metrics_params.solid_reuse_tolerance)

    def _rescale(self):
        """Stress sensors follow the specimen's current size (driven walls' mass per loaded
        area too)."""
        c, t = self.control, self.rig.sim.thickness
        w, h = self.rig.width(), self.rig.height()
        c.set_scale(AXIAL, 1.0 / (w * t))
        c.set_scale(LEFT, -1.0 / (h * t))
        c.set_scale(RIGHT, 1.0 / (h * t))
        mu = self.rig.params.platen_mass_ratio * self.specimen_mass() / (w * t)
        for k in (self.ids.sine, *self.ids.sides):
            if c.get(k, "areal_mass") > 0.0:
                c.set(k, areal_mass=mu)

    def specimen_mass(self):
        """The live balls' inertial mass [kg] (density scaling's included: driven boundaries
        scale with it, so their step stays as stable as the balls', their stiffness over
        their mass below that of the balls they touch; a rigid stone's counted once)."""
        sim = self.rig.sim
        return float(sim.inertial_masses()[sim.balls.alive == 1].sum())

    def _drive(self, controllers):
        """load_control applied_force: these controllers drive their walls as bodies of
        the areal mass of a top platen of platen_mass_ratio x the specimen's mass
        (_rescale sets it), their targets applied as loads."""
        if self.rig.params.load_control == "applied_force":
            for k in controllers:
                self.control.set(k, areal_mass=1.0)
            self._rescale()

    # --------------------------------------------------------------- events
    def advance(self, max_steps=None):
        """A membrane follows the platens (segment heights, their stress sensors) before
        every run of the engine (at least every control buffer: well below a mm of platen
        travel); before, not after, so a resumed run does what an uninterrupted one does."""
        sensors = self.ids.segment_sensors
        if sensors:
            scales = segment_scales(len(sensors), place_membrane(self.rig), self.rig.sim.thickness)
            for sensor, f in zip(sensors, scales):
                self.control.set_scale(sensor, f)
        super().advance(max_steps or self._steps_to_watch())

    def _steps_to_watch(self):
        """While loading: at most the steps in which the platen travels a quarter of
        softening_strain (check_stalled runs after each run of the engine, so a softening
        specimen is caught within 1.25 x softening_strain, a failing one within a quarter
        of it past failure_axial_strain): at its largest speed, or, driven by an applied
        load, accelerating from its speed now under its largest load with nothing below it
        (a collapse; its speed has no bound); else None (a control buffer)."""
        s, p, c = self.s, self.rig.params, self.control
        if s.phase not in ("loading", "cyclic"):
            return None
        k = self.ids.profile if c.get(self.ids.profile, "active") else self.ids.sine
        dt, travel = self.rig.sim.dt, 0.25 * p.softening_strain * self.rig.height()
        n = int(travel / (c.get(k, "v_max") * dt))
        mu = c.get(k, "areal_mass") if k == self.ids.sine else 0.0
        if mu > 0.0:
            a = c.get(k, "hi") / mu
            v0 = abs(float(self.rig.sim.walls.vel[self.rig.layout.top[0], 1]))
            n = min(n, int((np.sqrt(v0 * v0 + 2.0 * a * travel) - v0) / (a * dt)))
        return max(c.every, min(n, (c.capacity - 1) * c.every) // c.every * c.every)

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
        within = np.all(np.abs(sig - target) / target < p.consolidation_tolerance)
        s.settled_windows = s.settled_windows + 1 if within and self._at_rest() else 0
        if s.settled_windows >= p.consolidation_windows_in_a_row:
            s.windows = s.settled_windows = 0
            if s.phase == "hold":
                s.phase = "held"
                return
            s.phase = "loading"
            s.loading_start_step = self.rig.sim.step
            self._start_cycle()                 # the first loading is load cycle N = 1
            s.height0, s.width0 = self.rig.height(), self.rig.width()
            for k in self.ids.sides:        # keep p; no more windows
                c.set(k, window_steps=np.inf)
            self._drive(self.ids.sides)
            c.set(self.ids.top, active=False)
            s.half_sample0 = len(self.samples["step"]) - 1
            self._start_first_loading()
        elif s.windows >= p.consolidation_max_windows:
            raise RuntimeError(f"{s.phase} at {', '.join(f'{v / KPA:g}' for v in target)} kPa "
                               f"not reached within {s.windows} windows (last means "
                               f"{', '.join(f'{v / KPA:.2f}' for v in sig)} kPa)")

    def _start_first_loading(self):
        """The first cycle (N = 1), both modes: the bound-to-bound profile from p to p + q_max
        and back to p + q_min (each bound reached whatever the specimen's compliance, still
        unknown) at the platen speed of first_loading_inertial_number at p
        (inertial.profile_speed: the virgin loading's strain depends on its rate down to
        I ~ 2e-5), braking over the last braking_fraction of the range to braking_speed_ratio
        of it. At 20 Hz the sinusoid's first loading of the full-size specimen (a real-time
        quarter period for 2.6 % axial strain) reached 0.6 x p + q_max; its first unloading
        with the first loading's compliance (plastic: 10 x the unloading's) lifted the platen
        off the specimen."""
        p, c = self.rig.params, self.control
        lo, hi = p.axial_bounds_Pa
        v = profile_speed(self.rig, p.first_loading_inertial_number, p.confining_pressure_kPa * KPA)
        c.set(self.ids.profile, active=True, direction=-1, lo=lo, hi=hi, v_min=p.braking_speed_ratio * v,
              v_max=v, brake=p.braking_fraction)

    def _first_cycle_ended(self):
        """The sinusoid takes over at the first trough, from its trough phase; _branch_ended
        then sets its frequency (quasi-static) and feed-forward. Real time: from here on the
        test's f and (_trough, once cycle 0's records are made) the real masses but
        realtime_added_inertia_max."""
        c = self.control
        c.set(self.ids.profile, active=False)
        c.set(self.ids.sine, active=True, half_periods=0, integral=0.0, compliance=0.0,
              t0=self.rig.sim.time)
        self._drive([self.ids.sine])

    def _at_rest(self):
        """Whether the axial strain rate since the last window is below
        consolidation_strain_rate_max_1_s (the platen no longer travels: a window within
        the tolerance while it still settles is luck, not equilibrium)."""
        s, h, t = self.s, self.rig.height(), self.rig.sim.time
        rate = abs(h - s.window_height) / (h * (t - s.window_time)) if t > s.window_time else np.inf
        s.window_height, s.window_time = h, t
        return bool(rate < self.rig.params.consolidation_strain_rate_max_1_s)

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
        s.phase, s.windows, s.settled_windows = "hold", 0, 0
        while s.phase == "hold":
            self.advance()
        return np.array(s.window_means[-1])

    def on_peak(self):
        self._rescale()
        self._branch_ended()
        self.s.prev_half_sample0 = self.s.half_sample0
        self.s.half_sample0 = len(self.samples["step"]) - 1

    def _branch_ended(self):
        """What the rig learns from the half cycle just ended (from the samples): the
        platen's compliance C = -dy/dsigma_1 of a loading or an unloading branch (they
        differ: a loading one deforms plastically too; a branch whose stress moved less than
        a tenth of the range, or none, keeps the last C; the first unloading's C stands for
        the reloadings' until one is measured: the virgin loading's is plastic) and, with
        sine_feed_forward under the servo, for the next branch the sinusoid's feed-forward
        -C d(target)/dt with the C of its kind, so the servo only corrects what C does not
        foresee, and the bound the branch before missed (its extreme comes late, in this
        branch: the commanded bound moves by the miss; not cycle 0's, the profile's).
        Quasi-static: the frequency of the bounds for the larger C of the two kinds (they
        hold for the whole cycle; an unloading's C reads low while the specimen creeps down:
        with the coming branch's C the frequency rose fourfold over 15 cycles of creep on a
        small specimen, until it gave way)."""
        p, s = self.rig.params, self.s
        k0, k1 = s.half_sample0, len(self.samples["step"]) - 1
        if k0 < 0 or k1 <= k0:
            return
        y, sig = self.samples["platen_y"], np.asarray(self.samples["axial_stress"][k0:k1 + 1])
        dsig, dq = sig[-1] - sig[0], p.deviator_range_Pa
        if abs(dsig) < 0.1 * dq:
            return
        loaded = int(dsig > 0.0)            # 1: a loading branch ended, an unloading follows
        measured = -(y[k1] - y[k0]) / dsig
        if measured > 0.0:                  # (else the platen did not follow: keep the last)
            s.compliance[1 - loaded] = measured
        if s.phase == "loading" and not loaded:     # the first unloading: a reloading is not
            s.compliance[0] = s.compliance[1]       # the virgin loading (plastic: 10 x softer)
        following = s.compliance[loaded] or s.compliance[1 - loaded]
        # (an applied load misses by noise alone: adapted to, its misses at 60 Hz grew)
        if p.sine_feed_forward and p.load_control == "servo":
            if s.cycle >= 1 + loaded:       # the branch before is not one of cycle 0
                self._adapt_bound(s.prev_half_sample0, k1, not loaded)
            self.control.set(self.ids.sine, compliance=following)
        if p.mode == "quasi_static" and max(s.compliance) > 0.0:
            self._set_frequency(self._quasi_static_frequency(max(s.compliance)))
        if following > 0.0:
            self._sine_servo(following, dq)

    def _sine_servo(self, compliance, dq):
        """The sinusoid's servo for the coming branch, from its compliance C: the gain
        C / (sine_servo_time_waves t_w), so that the servo's time constant C / gain is that
        many travel times t_w = sqrt(rho_b C H) of the stress wave (a servo faster than the
        wave steers the top layer, not the specimen: 1.1 t_w lost the bounds on the small
        box_test specimen, 0.8 t_w on the full-size one; one gain for both, tuned on the
        small one at 2.2 t_w, was 3.3 t_w on the full-size one and lagged 20 %); the speed limit
        sine_velocity_min_m_s, or twice the platen's largest speed the sinusoid asks,
        pi f C dq, if that is more (at a fixed 0.05 m/s the servo saturated on the full-size
        specimen at 20 Hz); its integral starts anew (the last branch's, wound up by its lag,
        held the next unloading 9 kPa above p + q_min on the full-size specimen)."""
        p, c, k = self.rig.params, self.control, self.ids.sine
        t_w = travel_time(bulk_density(self.rig), compliance, self.rig.height())
        need = 2.0 * np.pi * c.get(k, "frequency") * compliance * dq
        c.set(k, gain=float(compliance / (p.sine_servo_time_waves * t_w)) * KPA,
              v_max=max(p.sine_velocity_min_m_s, float(need)), integral=0.0)
        self.s.sine_servo_step = self.rig.sim.step

    def continue_under(self, params):
        """The run, at the end of cycle 0, goes on under ``params``, which differ from its
        own only in what cycle 0 does not read (``params.first_cycle_inert_keys()``: the
        test's f; cycle 0 loads at the first-loading rate in either mode): what the first
        trough set from them is set anew - real time: the sinusoid's frequency and its
        servo's speed limit (quasi-static: f is inert throughout) - so the cycles run as
        in a run of its own (runner.run_cases: one cycle 0 for a test's frequencies).
        ValueError if they differ in more, or the run is elsewhere, or the servo was last
        set before the trough (a first unloading too short to measure)."""
        old, new, s = self.rig.params.to_dict(), params.to_dict(), self.s
        differ = {k for k in new if new[k] != old[k]}
        if not differ <= set(params.first_cycle_inert_keys()):
            raise ValueError(f"cycle 0 reads {sorted(differ - set(params.first_cycle_inert_keys()))}")
        if s.cycle != 1 and not (s.failure and s.cycle == 0):
            raise ValueError(f"the run is at cycle {s.cycle}, not at the end of cycle 0")
        servo_now = s.sine_servo_step == self.rig.sim.step
        if s.phase != "done" and params.mode == "real_time" and not servo_now:
            raise ValueError("the sinusoid's servo was not set at the first trough")
        self.rig.params = params
        if s.phase == "done" or params.mode != "real_time":
            return
        self.control.set(self.ids.sine, frequency=params.frequency_Hz)
        self._sine_servo(s.compliance[0] or s.compliance[1], params.deviator_range_Pa)

    def _adapt_bound(self, k0, k1, loading):
        """Move the sinusoid's commanded bound (hi after a loading branch, lo after an
        unloading) by what the branch missed its target by (as the load cell reads it over
        samples k0..k1), within a quarter of the range of the target."""
        p, c, k = self.rig.params, self.control, self.ids.sine
        dq, (lo, hi) = p.deviator_range_Pa, p.axial_bounds_Pa
        name, target = ("hi", hi) if loading else ("lo", lo)
        sig = self._load_cell(self.samples["axial_stress"][k0:k1 + 1], self.samples["step"][k0:k1 + 1])
        reached = np.max(sig) if loading else np.min(sig)
        command = c.get(k, name) + target - reached
        c.set(k, **{name: float(np.clip(command, target - 0.25 * dq, target + 0.25 * dq))})

    def _set_frequency(self, f):
        """A new frequency from this reversal on, the sinusoid's phase kept (t0 moved so that
        its half periods so far end now)."""
        c, k = self.control, self.ids.sine
        c.set(k, frequency=f, t0=self.rig.sim.time - c.get(k, "half_periods") / (2.0 * f))

    def _quasi_static_frequency(self, compliance):
        """rig.biaxial.inertial.quasi_static_frequency for this specimen and loading."""
        p, rig = self.rig.params, self.rig
        return quasi_static_frequency(rig, compliance, p.confining_pressure_kPa * KPA,
                                      p.deviator_range_Pa, p.quasi_static_inertial_number,
                                      p.quasi_static_lag)

    def check_stalled(self):
        """A stress-controlled specimen that cannot carry sigma_1 = p + q_max fails, as in the
        laboratory: its axial strain runs away. The run ends as a result, not an error, when
        the axial strain reaches failure_axial_strain, or the deviator q = sigma_1 - sigma_3
        passed a peak below the bound and the specimen went on straining by softening_strain
        (the peak strength of a strain-controlled test; q read as the strength test reads
        it, its mean over peak.WINDOW_STRAIN of axial strain), or a cycle of the sinusoid
        does not end within max_cycle_steps (not cycle 0: its profile moves the platen on
        until the bound or failure_axial_strain, however many steps that takes at its
        inertial number); ``failure`` says which, where and at what stress."""
        s, p = self.s, self.rig.params
        if s.phase not in ("loading", "cyclic"):
            return super().check_stalled()
        ea = self.strains()[0]
        if s.peak_sample < 0:
            self._watch_peak()
        steps = self.rig.sim.step - s.cycle_start_step
        if ea >= p.failure_axial_strain:
            why = f"axial strain {ea:.3f} reached failure_axial_strain {p.failure_axial_strain:g}"
        elif ea - s.peak_strain >= p.softening_strain and s.peak_sample < 0:
            why = (f"q peaked at {s.peak_stress / KPA:.1f} kPa (axial strain {s.peak_strain:.4f}) "
                   f"and fell below it over a further softening_strain {p.softening_strain:g}")
        elif s.phase == "cyclic" and steps > p.max_cycle_steps:
            why = (f"the cycle between p + q_min and p + q_max = {p.confining_pressure_kPa + p.deviator_max_kPa:g} "
                   f"kPa did not end within max_cycle_steps {p.max_cycle_steps} (axial strain {ea:.4f})")
        else:
            return
        where = "in the first loading" if s.phase == "loading" else f"in cycle {s.cycle}"
        s.failure = (f"the specimen failed {where}: {why}; sigma_1 "
                     f"{self.control.reading(AXIAL) / KPA:.1f} kPa at that moment")
        s.phase = "done"

    def _watch_peak(self):
        """The loading branch's peak of q (peak.new_peak) over the samples since the
        last check, looking back (by doubling chunks) as far as their windows reach."""
        s, S = self.s, self.samples
        start, n = max(s.half_sample0, 0), len(S["step"])
        first = max(s.watched_samples, start)
        s.watched_samples = n
        if first >= n:
            return
        bottom, y = self.rig.bottom_y(), S["platen_y"]

        def strain(k0, k1):
            return axial_strain(np.asarray(y[k0:k1]) - bottom, s.height0)

        back, e_first = 1024, strain(first, first + 1)[0]
        k0 = max(start, first - back)
        while k0 > start and strain(k0, first).min() > e_first - WINDOW_STRAIN:
            back *= 2
            k0 = max(start, first - back)
        tail = strain(k0, n)
        skip = lookback_start(tail, 0, first - k0)
        k = k0 + skip
        q = np.asarray(S["axial_stress"][k:n]) - 0.5 * (np.asarray(S["left_stress"][k:n])
                                                        + np.asarray(S["right_stress"][k:n]))
        m, at = new_peak(tail[skip:], q, first - k, origin=strain(start, start + 1)[0])
        if m > s.peak_stress:
            s.peak_stress, s.peak_strain = m, at

    def _trough(self):
        """The first trough after consolidation ends cycle 0 (N = 1 of a laboratory test: the
        first loading from p to p + q_max and the unloading to p + q_min)."""
        self._rescale()
        first = self.s.phase == "loading"
        self.s.unloading_frequency = np.nan if first else self.control.get(self.ids.sine, "frequency")
        if first:
            self._first_cycle_ended()
        self._branch_ended()
        self.s.peak_stress, self.s.peak_strain = 0.0, np.nan   # each loading branch is
        self.s.watched_samples = 0                              # watched for softening anew
        s, k0, peak = self.s, self.s.cycle_sample0, self.s.half_sample0
        if s.phase == "loading":
            s.phase = "cyclic"
        super()._trough()
        every = max(1, int(self.rig.params.timeseries_every))     # after the cycle's thinning:
        s.prev_half_sample0 = k0 + -(-(peak - k0) // every)        # the first kept at the peak or after
        s.half_sample0 = len(self.samples["step"]) - 1
        p = self.rig.params
        if first and p.mode == "real_time":
            self.rig.sim.set_density_scaling(self.rig.sim.scaled_timestep(p.realtime_added_inertia_max))

    def strains(self):
        """(axial, volumetric) strain since the end of consolidation, compression +."""
        s = self.s
        return specimen_strains(self.rig.height(), self.rig.width(), s.height0, s.width0)

    # --------------------------------------------------------------- records
    def cycle_row(self):
        rig, s = self.rig, self.s
        modes = rig.stones.breakages(rig.sim)["mode"][s.log0:]
        sig1 = self._load_cell(self.cycle_samples("axial_stress"), self.cycle_samples("step"))
        peak = s.peak_sample - s.cycle_sample0 - (len(self.cycle_samples("step")) - len(sig1)) // 2
        unloading = sig1[min(max(0, peak), len(sig1) - 1):]     # (the window centred on it)
        sig3 = 0.5 * (self.cycle_samples("left_stress") + self.cycle_samples("right_stress"))
        return dict(cycle_end_step=rig.sim.step, cycle_steps=rig.sim.step - s.cycle_start_step,
                    axial_stress_max=float(sig1.max()), axial_stress_min=float(unloading.min()),
                    confining_stress_mean=float(sig3.mean()), height_at_end=rig.height(),
                    width_at_end=rig.width(),
                    width_max_at_end=float(np.max(rig.side_x("right") - rig.side_x("left"))),
                    elements_broken_tension=int(np.sum(modes == "tension")),
                    elements_broken_shear=int(np.sum(modes == "shear")),
                    inertia_added=rig.sim.added_inertia(), loading_frequency=s.unloading_frequency)

    def _load_cell(self, sig, steps):
        """sigma_1 as a load cell records it: the running mean over LOAD_CELL_INTERVAL_S of
        the samples at ``steps``, on the control steps (a finished cycle's samples are
        thinned: interpolated between those kept)."""
        every = self.control.every
        grid = np.arange(steps[0], steps[-1] + 1, every)
        sig = np.interp(grid, steps, sig)
        n = int(round(LOAD_CELL_INTERVAL_S / (every * self.rig.sim.dt)))
        n = min(max(1, n), len(sig))
        return np.convolve(sig, np.ones(n) / n, mode="valid")

    def on_cycle_end(self):
        """The solids are rebuilt wherever a run may start from a saved state, so that it
        rounds as the run that went on: at its checkpoints and at the end of the first
        loading (scenario.runner: hook-only effects start there)."""
        if self.s.cycle % self.checkpoint_every == 0 or self.s.cycle == 1:
            self.solid_cache.clear()

    def _thin_samples(self, k0, every=None):
        super()._thin_samples(k0, max(1, int(self.rig.params.timeseries_every)))

    # --------------------------------------------------------------- behaviours
    def snapshot(self):
        """The end-of-cycle snapshot ``metrics.biaxial.compute_biaxial_cycle`` reads (the
        engine's arrays as they are: the compute only reads them)."""
        rig, s = self.rig, self.s
        sim, lay = rig.sim, rig.layout
        b = sim.balls
        stone = np.zeros(len(b), bool)
        stone[rig.stone_balls()] = True
        i, j, fn = rig.ball_contacts()
        seg = sim.walls.seg
        br = rig.stones.breakages(sim)
        link_i, link_j, link_intact = rig.stones.topology(sim)
        return dict(
            pos=b.pos, rad=b.rad, ballast=stone,
            bond_i=link_i, bond_j=link_j, bond_intact=link_intact,
            contact_i=i, contact_j=j, contact_fn=fn,
            geometry=dict(x_left=rig.side_x("left").mean(), x_right=rig.side_x("right").mean(),
                          y_bottom=float(seg[lay.bottom[0], 1]), y_top=float(seg[lay.top[0], 1])),
            height=rig.height(), width=rig.width(), height0=s.height0, width0=s.width0,
            break_step=br["step"][s.log0:],
            break_mode=mode_codes(br["mode"][s.log0:]).astype(np.int64),
            n_bonds_installed=s.n_bonds0, n_elements_per_bond=rig.stones.elements_per_unit(sim),
            cycle_start_step=s.cycle_start_step, cycle_end_step=sim.step + 1,
            stone_unit=self.stone_units(len(b)), mass=b.mass)

    def behaviours(self):
        """Strains, breakage (eqs. 4.6-4.8), fragments, mean coordination and void ratio of
        the specimen rectangle between the walls (``ballaststudy.metrics``)."""
        return compute_biaxial_cycle(self.snapshot(), self.metrics_params, self.solid_cache)

    # --------------------------------------------------------------- checkpoint
    def _load_extra(self, d):
        self._metrics_setup()

    @classmethod
    def from_checkpoint(cls, path, cycles=None, checkpoint_every=None):
        return super().from_checkpoint(path, BiaxialRig, cycles=cycles,
                                       checkpoint_every=checkpoint_every)
