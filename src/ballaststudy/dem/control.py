"""Controllers inside the stepping loop (what LAMMPS calls fixes): sensors, controllers,
actuators and a sample buffer, run by the stepping kernel every ``every`` steps.

After such a step the sensors are read and sampled; every active controller updates its
state from its sensor and may raise an event (a servo's averaging window is complete, the
cyclic profile reverses at a bound). Then either the controllers' velocities are imposed
on their actuators at once, or — on an event — the kernel returns to Python (status
``params.CONTROL_EVENT``) before imposing them: the rig reacts (next target, another
controller, a snapshot at the peak) and the next run imposes them first (``pending``).
So a rig enters Python at events, checkpoints and progress only, and the order of
operations is that of a Python loop "run k steps, measure, decide, set the velocity".

Sensors (reading = ``scale`` x quantity):
  CLUMP_REACTION  force of the contacts on a clump along an axis (net force minus weight)
  CLUMP_POSITION  a clump's centre along an axis
  WALL_FORCE      summed force of the balls on a set of wall segments along an axis
  WALL_POSITION   mean coordinate of a set of wall segments' end points along an axis
Actuators: HELD_CLUMP (velocity along the axis, other components and spin held at zero),
WALLS (velocity of a set of segments along the axis).
Controllers:
  SERVO   PI force servo, v = -clip(gain (target - f) + I, +-v_max); I integrates
          gain (target - f) every / integral_steps, clipped at +-v_max (no wind-up). It
          first approaches (v_max towards the target) until the reading reaches ``touch``;
          from then on it averages every sensor over windows of ``window_steps``. A positive
          gain moves the actuator towards -axis to raise the reading, a negative one
          towards +axis.
  CYCLIC  bound-to-bound profile: moves with sign ``direction`` at v_max until the reading
          is within ``brake`` x (hi - lo) of the bound it approaches, then linearly down
          to v_min at the bound; reverses at hi (event PEAK) and at lo (event TROUGH).
  SINE    real-time sinusoid: a PI servo (as SERVO) whose target follows
          lo + (hi - lo) (1 - cos(2 pi f (t - t0))) / 2 in simulated time t, from lo at t0,
          plus a feed-forward -C d(target)/dt with the actuator's compliance C [m per
          reading unit] (0: none; the rig sets it from what it measures); events at its
          half periods (PEAK at the maxima, TROUGH at the minima).
A SERVO or SINE with an ``areal_mass`` mu > 0 drives a body instead (a platen, a side
wall): its actuator, a set of wall segments, is a body of mu [mass per reading unit of
force: kg/m^2 for a stress] under the target as an applied load, its velocity integrated
every step from a = (reading - target) / mu (towards +axis for a positive gain), so the
reading (the contacts' load on it) follows the target up to the body's inertia mu a,
whatever the specimen's compliance: a stress boundary, as a force-controlled actuator's
load on a cap or a cell pressure on a membrane. Its gain's sign alone counts; its window
events as before.

All arrays live in one named container (``ControlArrays``); the ``Control`` class builds it
and saves/restores it (rigs keep it in their checkpoints).
"""
import math
from collections import namedtuple

import numpy as np
from numba import njit

from . import params as P
from .jit import NO_NRT

# cfg slots (int64)
EVERY, COUNT, PENDING, EVENT, EVENT_CONTROLLER, NSAMP, WINDOW_N = range(7)
NCFG = 7
# sensor kinds, actuator kinds, controller kinds
CLUMP_REACTION, CLUMP_POSITION, WALL_FORCE, WALL_POSITION = 0, 1, 2, 3
HELD_CLUMP, WALLS = 0, 1
SERVO, CYCLIC, SINE = 1, 2, 3
# events
NO_EVENT, WINDOW, PEAK, TROUGH, BUFFER_FULL = 0, 1, 2, 3, 4
EVENT_NAMES = {WINDOW: "window", PEAK: "peak", TROUGH: "trough", BUFFER_FULL: "buffer full"}
# controller parameters (cpar columns) and state (cst columns)
TARGET, GAIN, GAIN_UNIT, VMAX, INTEGRAL_STEPS, WINDOW_STEPS, TOUCH = range(7)
LO, HI, VMIN, BRAKE = 0, 1, 2, 4          # CYCLIC: VMAX = 3 as above
SINE_LO, SINE_HI, FREQUENCY = 5, 6, 7     # SINE: GAIN ... INTEGRAL_STEPS as SERVO
COMPLIANCE = 0                            # SINE: the feed-forward's (TARGET's slot)
AREAL_MASS = 8                            # SERVO, SINE: a driven body's (0: the PI servo)
INTEGRAL, TOUCHED, APPROACH_STEPS, WINDOW_DONE = range(4)
HALF_PERIODS, T0, NOW = 1, 2, 3           # SINE state (INTEGRAL = 0 as SERVO)
DIRECTION = 0
NPAR, NST = 9, 4
assert VMAX == 3

_STATE = {"integral": INTEGRAL, "touched": TOUCHED, "approach_steps": APPROACH_STEPS,
          "window_done": WINDOW_DONE, "direction": DIRECTION}
_SERVO_PAR = {"target": TARGET, "gain": GAIN, "gain_unit": GAIN_UNIT, "v_max": VMAX,
              "integral_steps": INTEGRAL_STEPS, "window_steps": WINDOW_STEPS, "touch": TOUCH,
              "areal_mass": AREAL_MASS}
_CYCLIC_PAR = {"lo": LO, "hi": HI, "v_min": VMIN, "v_max": VMAX, "brake": BRAKE}
_SINE_PAR = {"gain": GAIN, "gain_unit": GAIN_UNIT, "v_max": VMAX,
             "integral_steps": INTEGRAL_STEPS, "lo": SINE_LO, "hi": SINE_HI,
             "frequency": FREQUENCY, "compliance": COMPLIANCE, "areal_mass": AREAL_MASS}
_SINE_STATE = {"integral": INTEGRAL, "half_periods": HALF_PERIODS, "t0": T0, "now": NOW}

ControlArrays = namedtuple(
    "ControlArrays", "cfg sensors members scale actuators ctl cpar cst val wsum samp")


# ------------------------------------------------------------------------- kernels
@njit(**NO_NRT)
def sensor_reading(prm, clumps, walls, c, s):
    kind, a, b, ax = c.sensors[s, 0], c.sensors[s, 1], c.sensors[s, 2], c.sensors[s, 3]
    if kind == CLUMP_REACTION:
        v = clumps.force[a, ax] - clumps.mass[a] * prm[P.GX + ax]
    elif kind == CLUMP_POSITION:
        v = clumps.pos[a, ax]
    elif kind == WALL_FORCE:
        v = 0.0
        for m in range(a, b):
            v += walls.force[c.members[m], ax]
    else:
        v = 0.0
        for m in range(a, b):
            v += walls.seg[c.members[m], ax] + walls.seg[c.members[m], 2 + ax]
        v *= 0.5 / (b - a)
    return c.scale[s] * v


@njit(**NO_NRT)
def read_sensors(prm, clumps, walls, c):
    for s in range(c.sensors.shape[0]):
        c.val[s] = sensor_reading(prm, clumps, walls, c, s)


@njit(**NO_NRT)
def _servo_update(c, k):
    """Approach, then the averaging window (of every sensor: ``window``). Returns an
    event code."""
    st, par = c.cst[k], c.cpar[k]
    if st[TOUCHED] == 0.0:
        if c.val[c.ctl[k, 1]] < par[TOUCH]:
            st[APPROACH_STEPS] += c.cfg[EVERY]
            return NO_EVENT
        st[TOUCHED] = 1.0
    st[WINDOW_DONE] += c.cfg[EVERY]
    return WINDOW if st[WINDOW_DONE] >= par[WINDOW_STEPS] else NO_EVENT


@njit(**NO_NRT)
def _cyclic_update(c, k):
    st, par = c.cst[k], c.cpar[k]
    f = c.val[c.ctl[k, 1]]
    if st[DIRECTION] < 0.0:
        if f >= par[HI]:
            st[DIRECTION] = 1.0
            return PEAK
    elif f <= par[LO]:
        st[DIRECTION] = -1.0
        return TROUGH
    return NO_EVENT


@njit(**NO_NRT)
def _sine_update(c, k, time):
    """Half periods of the command since t0: PEAK at odd ones, TROUGH at even ones."""
    st, par = c.cst[k], c.cpar[k]
    st[NOW] = time
    n = math.floor(2.0 * par[FREQUENCY] * (time - st[T0]))
    if n > st[HALF_PERIODS]:
        st[HALF_PERIODS] = n
        return PEAK if n % 2 == 1 else TROUGH
    return NO_EVENT


@njit(**NO_NRT)
def sine_target(par, st):
    return sine_target_at(par, st, st[NOW])


@njit(**NO_NRT)
def sine_target_at(par, st, time):
    phase = 2.0 * math.pi * par[FREQUENCY] * (time - st[T0])
    return par[SINE_LO] + 0.5 * (par[SINE_HI] - par[SINE_LO]) * (1.0 - math.cos(phase))


@njit(**NO_NRT)
def sine_rate(par, st):
    """d(target)/dt of the sinusoid [reading unit per s]."""
    w = 2.0 * math.pi * par[FREQUENCY]
    return 0.5 * (par[SINE_HI] - par[SINE_LO]) * w * math.sin(w * (st[NOW] - st[T0]))


@njit(**NO_NRT)
def _pi_velocity(st, par, target, f, every):
    vmax = par[VMAX]
    e = par[GAIN] * (target - f) / par[GAIN_UNIT]
    if par[INTEGRAL_STEPS] > 0.0:
        st[INTEGRAL] = min(max(st[INTEGRAL] + e * every / par[INTEGRAL_STEPS], -vmax), vmax)
        e += st[INTEGRAL]
    return min(max(-e, -vmax), vmax)


@njit(**NO_NRT)
def controller_velocity(c, k):
    """The velocity controller k commands from its sensor's last reading (the servo's
    integral advances: call once per control step)."""
    st, par = c.cst[k], c.cpar[k]
    f = c.val[c.ctl[k, 1]]
    vmax = par[VMAX]
    if c.ctl[k, 0] == SERVO:
        return _pi_velocity(st, par, par[TARGET], f, float(c.cfg[EVERY]))
    if c.ctl[k, 0] == SINE:
        v = _pi_velocity(st, par, sine_target(par, st), f, float(c.cfg[EVERY]))
        return min(max(v - par[COMPLIANCE] * sine_rate(par, st), -vmax), vmax)
    bound = par[HI] if st[DIRECTION] < 0.0 else par[LO]
    frac = min(1.0, abs(bound - f) / (par[BRAKE] * (par[HI] - par[LO])))
    return st[DIRECTION] * (par[VMIN] + (vmax - par[VMIN]) * frac)


@njit(**NO_NRT)
def drives_body(c, k):
    return (c.ctl[k, 0] != CYCLIC and c.cpar[k, AREAL_MASS] > 0.0
            and c.actuators[c.ctl[k, 2], 0] == WALLS)


@njit(**NO_NRT)
def drive_bodies(prm, clumps, walls, c):
    """Every step: the velocity of each driven body (a SERVO or SINE with an areal mass)
    for the next step, from the load on it now (symplectic Euler, as the balls: stable
    while its contacts' stiffness over its mass stays below (2 / dt)^2)."""
    for k in range(c.ctl.shape[0]):
        if c.ctl[k, 3] == 0 or not drives_body(c, k):
            continue
        par = c.cpar[k]
        target = sine_target_at(par, c.cst[k], prm[P.TIME]) if c.ctl[k, 0] == SINE else par[TARGET]
        load = sensor_reading(prm, clumps, walls, c, c.ctl[k, 1])
        accel = math.copysign(1.0, par[GAIN]) * (load - target) / par[AREAL_MASS]
        act = c.actuators[c.ctl[k, 2]]
        a, b, ax = act[1], act[2], act[3]
        v = walls.vel[c.members[a], ax] + prm[P.DT] * accel
        for m in range(a, b):
            walls.vel[c.members[m], ax] = v


@njit(**NO_NRT)
def actuate(clumps, walls, c):
    """Impose every active controller's velocity on its actuator (a driven body's is its
    own: drive_bodies)."""
    c.cfg[PENDING] = 0
    for k in range(c.ctl.shape[0]):
        if c.ctl[k, 3] == 0 or drives_body(c, k):
            continue
        v = controller_velocity(c, k)
        kind, a, b, ax = (c.actuators[c.ctl[k, 2], 0], c.actuators[c.ctl[k, 2], 1],
                          c.actuators[c.ctl[k, 2], 2], c.actuators[c.ctl[k, 2], 3])
        if kind == HELD_CLUMP:
            clumps.held[a] = 1
            clumps.vel[a, ax] = v
            clumps.vel[a, 1 - ax] = 0.0
            clumps.omega[a] = 0.0
        else:
            for m in range(a, b):
                walls.vel[c.members[m], ax] = v


@njit(**NO_NRT)
def control_step(prm, step, clumps, walls, c):
    """Once every ``every`` steps, after the step: read, sample, update; impose the
    velocities unless an event asks Python first. Returns True on an event."""
    drive_bodies(prm, clumps, walls, c)
    c.cfg[COUNT] += 1
    if c.cfg[COUNT] < c.cfg[EVERY]:
        return False
    c.cfg[COUNT] = 0
    read_sensors(prm, clumps, walls, c)
    n = c.cfg[NSAMP]
    c.samp[n, 0] = step
    for s in range(c.val.shape[0]):
        c.samp[n, 1 + s] = c.val[s]
    c.cfg[NSAMP] = n + 1
    event = NO_EVENT
    windowing = False
    for k in range(c.ctl.shape[0]):
        if c.ctl[k, 3] == 0:
            continue
        kind = c.ctl[k, 0]
        if kind == SERVO:
            e = _servo_update(c, k)
        elif kind == CYCLIC:
            e = _cyclic_update(c, k)
        else:
            e = _sine_update(c, k, prm[P.TIME])
        windowing = windowing or (c.ctl[k, 0] == SERVO and c.cst[k, TOUCHED] > 0.0)
        if e != NO_EVENT and event == NO_EVENT:
            event = e
            c.cfg[EVENT_CONTROLLER] = k
    if windowing:                 # one window for all servos: every sensor's sum
        for s in range(c.val.shape[0]):
            c.wsum[s] += c.val[s]
        c.cfg[WINDOW_N] += 1
    if event == NO_EVENT and n + 1 == c.samp.shape[0]:
        event = BUFFER_FULL
    c.cfg[EVENT] = event
    if event != NO_EVENT:
        c.cfg[PENDING] = 1
        return True
    actuate(clumps, walls, c)
    return False


# ------------------------------------------------------------------------- Python side
class Control:
    """Builder and owner of a ``ControlArrays``. Add sensors, actuators and controllers
    (each call returns an index), then pass the object to ``Simulation.run(control=...)``.
    Samples are rows (step, reading of sensor 0, 1, ...) taken every ``every`` steps."""

    def __init__(self, every, capacity=4096):
        self.every = int(every)
        self.capacity = int(capacity)
        self._sensors, self._actuators, self._ctl, self._par = [], [], [], []
        self._members, self._direction = [], {}
        self.arrays = None

    def _group(self, ids):
        a = len(self._members)
        self._members.extend(int(i) for i in ids)
        return a, len(self._members)

    def clump_reaction(self, clump, axis, scale=1.0):
        self._sensors.append(((CLUMP_REACTION, int(clump), 0, int(axis)), float(scale)))
        return len(self._sensors) - 1

    def clump_position(self, clump, axis):
        self._sensors.append(((CLUMP_POSITION, int(clump), 0, int(axis)), 1.0))
        return len(self._sensors) - 1

    def wall_force(self, segments, axis, scale=1.0):
        a, b = self._group(segments)
        self._sensors.append(((WALL_FORCE, a, b, int(axis)), float(scale)))
        return len(self._sensors) - 1

    def wall_position(self, segments, axis):
        a, b = self._group(segments)
        self._sensors.append(((WALL_POSITION, a, b, int(axis)), 1.0))
        return len(self._sensors) - 1

    def set_scale(self, sensor, scale):
        """Change a sensor's factor (a stress sensor's 1 / (length t) as the length changes)."""
        self.arrays.scale[sensor] = scale

    def held_clump(self, clump, axis):
        self._actuators.append((HELD_CLUMP, int(clump), 0, int(axis)))
        return len(self._actuators) - 1

    def walls(self, segments, axis):
        a, b = self._group(segments)
        self._actuators.append((WALLS, a, b, int(axis)))
        return len(self._actuators) - 1

    def servo(self, sensor, actuator, target, gain, v_max, integral_steps, window_steps,
              touch=-np.inf, gain_unit=1.0, active=True):
        """PI servo: ``gain`` in m/s per ``gain_unit`` newtons (1e3: m/s per kN)."""
        par = np.zeros(NPAR)
        par[[TARGET, GAIN, GAIN_UNIT, VMAX, INTEGRAL_STEPS, WINDOW_STEPS, TOUCH]] = (
            target, gain, gain_unit, v_max, integral_steps, window_steps, touch)
        return self._add(SERVO, sensor, actuator, active, par)

    def cyclic(self, sensor, actuator, lo, hi, v_min, v_max, brake, direction=-1,
               active=True):
        par = np.zeros(NPAR)
        par[[LO, HI, VMIN, VMAX, BRAKE]] = lo, hi, v_min, v_max, brake
        k = self._add(CYCLIC, sensor, actuator, active, par)
        self._direction[k] = direction
        return k

    def sine(self, sensor, actuator, lo, hi, frequency, gain, v_max, integral_steps,
             gain_unit=1.0, active=True, areal_mass=0.0):
        """Real-time sinusoid from lo to hi at ``frequency`` [Hz] (t0: ``set(k, t0=...)``
        when it starts; the servo part as ``servo``; areal_mass > 0: it drives a platen of
        that mass per reading unit of force instead, the sign of ``gain`` its direction)."""
        if areal_mass > 0 and self._actuators[actuator][0] != WALLS:
            raise ValueError("only wall segments are driven as bodies")
        par = np.zeros(NPAR)
        par[[GAIN, GAIN_UNIT, VMAX, INTEGRAL_STEPS, SINE_LO, SINE_HI, FREQUENCY, AREAL_MASS]] = (
            gain, gain_unit, v_max, integral_steps, lo, hi, frequency, areal_mass)
        return self._add(SINE, sensor, actuator, active, par)

    def _add(self, kind, sensor, actuator, active, par):
        self._ctl.append((kind, sensor, actuator, 1 if active else 0))
        self._par.append(par)
        return len(self._ctl) - 1

    def build(self):
        """Allocate the arrays (first run imposes the controllers' velocities)."""
        ns = len(self._sensors)
        cst = np.zeros((len(self._ctl), NST))
        for k, d in self._direction.items():
            cst[k, DIRECTION] = d
        cfg = np.zeros(NCFG, np.int64)
        cfg[EVERY], cfg[PENDING] = self.every, 1
        self.arrays = ControlArrays(
            cfg, np.array([s for s, _ in self._sensors], np.int64).reshape(ns, 4),
            np.array(self._members, np.int64), np.array([g for _, g in self._sensors]),
            np.array(self._actuators, np.int64).reshape(-1, 4),
            np.array(self._ctl, np.int64).reshape(-1, 4),
            np.array(self._par).reshape(-1, NPAR), cst, np.zeros(ns), np.zeros(ns),
            np.zeros((self.capacity, 1 + ns)))
        return self

    @staticmethod
    def empty():
        """The container of 'no control' (every = 0)."""
        z = np.zeros((0, 4), np.int64)
        return ControlArrays(np.zeros(NCFG, np.int64), z, np.zeros(0, np.int64), np.zeros(0),
                             z, z, np.zeros((0, NPAR)), np.zeros((0, NST)), np.zeros(0),
                             np.zeros(0), np.zeros((1, 1)))

    # --------------------------------------------------------- reading and steering
    @property
    def event(self):
        """(event code, controller) of the last run's stop, NO_EVENT if none."""
        c = self.arrays.cfg
        return int(c[EVENT]), int(c[EVENT_CONTROLLER])

    def clear_event(self):
        self.arrays.cfg[EVENT] = NO_EVENT

    def drain(self):
        """Samples since the last drain, (k, 1 + n_sensors), and empty the buffer."""
        n = int(self.arrays.cfg[NSAMP])
        out = self.arrays.samp[:n].copy()
        self.arrays.cfg[NSAMP] = 0
        return out

    def reading(self, sensor):
        return float(self.arrays.val[sensor])

    def window_means(self):
        """Mean reading of every sensor over the servo window just completed; resets it."""
        a = self.arrays
        means = a.wsum / a.cfg[WINDOW_N]
        self.reset_window()
        return means

    def reset_window(self):
        """Start a new averaging window now."""
        a = self.arrays
        a.wsum[:] = 0.0
        a.cfg[WINDOW_N] = 0
        a.cst[:, WINDOW_DONE] = 0.0

    def _slot(self, k, name):
        a = self.arrays
        if a.ctl[k, 0] == SINE:
            return (a.cst, _SINE_STATE[name]) if name in _SINE_STATE else (a.cpar, _SINE_PAR[name])
        if name in _STATE:
            return a.cst, _STATE[name]
        if a.ctl[k, 0] == SERVO:
            return a.cpar, _SERVO_PAR[name]
        return a.cpar, _CYCLIC_PAR[name]

    def set(self, k, **values):
        """Change controller k's parameters (target=..., ...) or state (integral=...,
        direction=...) or switch it (active=True/False)."""
        for name, v in values.items():
            if name == "areal_mass" and v > 0 and self.arrays.actuators[self.arrays.ctl[k, 2], 0] != WALLS:
                raise ValueError(f"controller {k}: only wall segments are driven as bodies")
            if name == "active":
                self.arrays.ctl[k, 3] = 1 if v else 0
            else:
                table, col = self._slot(k, name)
                table[k, col] = v

    def get(self, k, name):
        if name == "active":
            return bool(self.arrays.ctl[k, 3])
        table, col = self._slot(k, name)
        return float(table[k, col])

    def velocity(self, k, reading):
        """What controller k would command at ``reading`` (advances a servo's integral)."""
        a = self.arrays
        s = a.ctl[k, 1]
        old = a.val[s]
        a.val[s] = reading
        try:
            return float(controller_velocity(a, k))
        finally:
            a.val[s] = old

    def to_dict(self, prefix="control_"):
        return {prefix + n: np.asarray(v) for n, v in zip(ControlArrays._fields, self.arrays)}

    def load(self, d, prefix="control_"):
        """Restore the arrays saved by ``to_dict`` (the same controllers built)."""
        a = {n: np.array(d[prefix + n]) for n in ControlArrays._fields}
        a["cpar"] = np.pad(a["cpar"], ((0, 0), (0, NPAR - a["cpar"].shape[1])))  # older: 8
        self.arrays = ControlArrays(**a)
        self.every = int(self.arrays.cfg[EVERY])
        return self
