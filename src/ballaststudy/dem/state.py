"""State of a 2D DEM model: plain dataclasses of numpy arrays (no behaviour but growth).

Kernels receive each dataclass as one named container: ``obj.kernel()`` is a namedtuple of
the same arrays (``<Class>Arrays``, fields in the dataclass's order), which numba passes as
one argument. ``Simulation`` owns these objects and the checkpoint.
Ball ids are stable: deleting a ball clears ``alive`` instead of compacting the arrays.
"""
from collections import namedtuple
from dataclasses import dataclass, field, fields

import numpy as np


def _grow(a, n_new, fill=0):
    """Return ``a`` extended along axis 0 to ``n_new`` rows, new rows = ``fill``."""
    out = np.full((n_new,) + a.shape[1:], fill, dtype=a.dtype)
    out[: a.shape[0]] = a
    return out


class _Arrays:
    """Mixin: dict round trip (checkpoint) and row growth for array dataclasses."""

    def to_dict(self, prefix):
        return {prefix + f.name: getattr(self, f.name) for f in fields(self)}

    @classmethod
    def from_dict(cls, d, prefix):
        return cls(**{f.name: np.array(d[prefix + f.name]) for f in fields(cls)})

    def kernel(self):
        """The arrays as the kernels' named container (no copies)."""
        return self.Arrays(*(getattr(self, f.name) for f in fields(self)))

    def take(self, arrays):
        """Adopt the arrays of a container a kernel returned (lists it grew)."""
        for f in fields(self):
            setattr(self, f.name, getattr(arrays, f.name))

    def append_rows(self, k, cols):
        """Grow every column by ``k`` rows (zeros) and set ``cols`` {name: value} in them.
        Returns the first new row."""
        n0 = len(self)
        for f in fields(self):
            setattr(self, f.name, _grow(getattr(self, f.name), n0 + k))
        for name, v in cols.items():
            getattr(self, name)[n0:] = v
        return n0


def _z(*shape, dtype=np.float64):
    return field(default_factory=lambda: np.zeros(shape, dtype=dtype))


@dataclass
class Balls(_Arrays):
    """Disks. ``fix`` bitmask: 1 = x velocity held, 2 = y velocity held, 4 = spin held.
    ``clump`` = clump id or -1; ``offset`` = pebble position in its clump frame;
    ``buried`` pebbles are left out of contact detection and of the per-step placement."""
    pos: np.ndarray = _z(0, 2)
    vel: np.ndarray = _z(0, 2)
    omega: np.ndarray = _z(0)
    rad: np.ndarray = _z(0)
    mass: np.ndarray = _z(0)          # gravitational mass rho*pi*R^2*t [kg]
    inertia: np.ndarray = _z(0)       # m R^2 / 2 [kg m^2]
    minv: np.ndarray = _z(0)          # 1 / inertial mass (density scaling may change it)
    iinv: np.ndarray = _z(0)          # 1 / inertial moment of inertia
    force: np.ndarray = _z(0, 2)      # net force incl. gravity and local damping [N]
    moment: np.ndarray = _z(0)        # net moment [N m]
    stone: np.ndarray = _z(0, dtype=np.int32)
    mat: np.ndarray = _z(0, dtype=np.int32)
    fix: np.ndarray = _z(0, dtype=np.int32)
    clump: np.ndarray = _z(0, dtype=np.int32)
    offset: np.ndarray = _z(0, 2)
    alive: np.ndarray = _z(0, dtype=np.uint8)
    pos0: np.ndarray = _z(0, 2)       # positions at the last neighbour build
    clear: np.ndarray = _z(0)         # gap to the nearest unlisted wall segment at that build
    fext: np.ndarray = _z(0, 2)       # external force set by the caller (a load) [N]
    damp: np.ndarray = _z(0)          # PFC local damping coefficient alpha [-]
    buried: np.ndarray = _z(0, dtype=np.uint8)   # 1: a pebble no outside body can reach
                                      # (clumps.buried): no contacts, placed only when read

    def __len__(self):
        return self.pos.shape[0]

    def append(self, **cols):
        k = len(cols["pos"])
        n0 = self.append_rows(k, cols)
        return np.arange(n0, n0 + k)


@dataclass
class Walls(_Arrays):
    """Kinematic line segments. Each moves with ``vel`` and rotates with ``omega`` about
    ``centre``; ``link`` = (previous, next) segment of the same polyline or -1, so a ball
    touching a joint is counted on one segment only."""
    seg: np.ndarray = _z(0, 4)        # x0, y0, x1, y1 [m]
    vel: np.ndarray = _z(0, 2)
    omega: np.ndarray = _z(0)
    centre: np.ndarray = _z(0, 2)
    force: np.ndarray = _z(0, 2)      # force exerted BY balls ON the segment [N]
    moment: np.ndarray = _z(0)        # moment of that force about ``centre`` [N m]
    mat: np.ndarray = _z(0, dtype=np.int32)
    link: np.ndarray = _z(0, 2, dtype=np.int32)

    def __len__(self):
        return self.seg.shape[0]

    def append(self, **cols):
        k = len(cols["seg"])
        n0 = self.append_rows(k, cols)
        return np.arange(n0, n0 + k)


@dataclass
class Clumps(_Arrays):
    """Rigid bodies of pebbles (pebbles are balls with ``Balls.clump`` = id).
    ``held`` clumps keep the velocity the caller sets (PFC plate). ``mass``/``inertia`` are
    the real ones (weight, output); ``imass``/``iinertia`` the inertial ones the kicks
    divide by, equal to them unless density scaling raised them."""
    pos: np.ndarray = _z(0, 2)
    vel: np.ndarray = _z(0, 2)
    omega: np.ndarray = _z(0)
    theta: np.ndarray = _z(0)
    mass: np.ndarray = _z(0)
    inertia: np.ndarray = _z(0)
    held: np.ndarray = _z(0, dtype=np.uint8)
    force: np.ndarray = _z(0, 2)      # net force incl. gravity [N]
    moment: np.ndarray = _z(0)        # net moment about the centre of mass [N m]
    damp: np.ndarray = _z(0)          # local damping coefficient alpha [-]
    imass: np.ndarray = _z(0)         # inertial mass [kg] (density scaling may raise it)
    iinertia: np.ndarray = _z(0)      # inertial moment of inertia [kg m^2]
    strength: np.ndarray = _z(0)      # characteristic stress at which it splits [Pa] (inf: never)
    gen: np.ndarray = _z(0, dtype=np.int32)   # splits between the assembled stone and this piece
    damage: np.ndarray = _z(0)        # fatigue damage D: it splits at strength (1 - D) [-]
    peak: np.ndarray = _z(0)          # largest characteristic stress checked since the last
                                      # damage update [Pa]

    def __len__(self):
        return self.pos.shape[0]

    @classmethod
    def from_dict(cls, d, prefix):
        """Checkpoints written before the inertial, strength and damage columns existed:
        real = inertial, unbreakable, generation 0, undamaged."""
        d = dict(d)
        for name, real in (("imass", "mass"), ("iinertia", "inertia")):
            d.setdefault(prefix + name, d[prefix + real])
        n = len(d[prefix + "mass"])
        d.setdefault(prefix + "strength", np.full(n, np.inf))
        d.setdefault(prefix + "gen", np.zeros(n, np.int32))
        d.setdefault(prefix + "damage", np.zeros(n))
        d.setdefault(prefix + "peak", np.zeros(n))
        return super().from_dict(d, prefix)

    def append(self, **cols):
        cols.setdefault("imass", cols["mass"])
        cols.setdefault("iinertia", cols["inertia"])
        cols.setdefault("strength", np.inf)
        return self.append_rows(1, cols)


@dataclass
class Pairs(_Arrays):
    """Verlet list of ball-ball pairs (i < j, grouped by ascending i). ``hist`` = the contact
    law's per-contact columns: its sub-models' history (reset when the contact opens), then
    their persistent state (law.ContactLaw.width); ``bond`` = flat-joint index of the pair or
    -1; ``fn``/``fs`` = last normal/shear force (for output and energies); ``lap0`` = the
    overlap two pebbles of one stone had when a split put them in two pieces: the contact
    acts on the overlap beyond it only, and it shrinks to the overlap as they part (0: none).
    """
    i: np.ndarray = _z(0, dtype=np.int32)
    j: np.ndarray = _z(0, dtype=np.int32)
    hist: np.ndarray = _z(0, 2)
    bond: np.ndarray = _z(0, dtype=np.int32)
    fn: np.ndarray = _z(0)
    fs: np.ndarray = _z(0)
    lap0: np.ndarray = _z(0)
    n: np.ndarray = field(default_factory=lambda: np.zeros(1, np.int64))

    @classmethod
    def empty(cls, cap, width):
        return cls(np.zeros(cap, np.int32), np.zeros(cap, np.int32), np.zeros((cap, width)),
                   np.full(cap, -1, np.int32), np.zeros(cap), np.zeros(cap), np.zeros(cap),
                   np.zeros(1, np.int64))

    @classmethod
    def from_dict(cls, d, prefix):
        """Checkpoints written before splits existed: no sibling overlaps."""
        d = dict(d)
        d.setdefault(prefix + "lap0", np.zeros(len(d[prefix + "fn"])))
        return super().from_dict(d, prefix)


@dataclass
class WallPairs(_Arrays):
    """Verlet list of ball-segment pairs (sorted by (ball, segment)), columns as Pairs."""
    i: np.ndarray = _z(0, dtype=np.int32)
    s: np.ndarray = _z(0, dtype=np.int32)
    hist: np.ndarray = _z(0, 2)
    fn: np.ndarray = _z(0)
    fs: np.ndarray = _z(0)
    n: np.ndarray = field(default_factory=lambda: np.zeros(1, np.int64))

    @classmethod
    def empty(cls, cap, width):
        return cls(np.zeros(cap, np.int32), np.zeros(cap, np.int32), np.zeros((cap, width)),
                   np.zeros(cap), np.zeros(cap), np.zeros(1, np.int64))


@dataclass
class Bonds(_Arrays):
    """Flat joints (Potyondy 2012) in 2D, sorted by (i, j). Per bond: interface half
    length ``rbar``, installation distance ``d0`` and gap ``gi``, stiffness per area
    ``kn``/``ks`` [Pa/m], strengths ``sigc``/``coh`` [Pa], ``tanphi``, residual ``mu``;
    per element (columns): ``state`` 1 = bonded, 0 = broken; ``fn`` normal force
    (tension positive) [N]; ``fs`` shear force on ball j along the tangent [N].
    ``theta`` = accumulated relative rotation omega_j - omega_i [rad]."""
    i: np.ndarray = _z(0, dtype=np.int32)
    j: np.ndarray = _z(0, dtype=np.int32)
    active: np.ndarray = _z(0, dtype=np.uint8)
    rbar: np.ndarray = _z(0)
    d0: np.ndarray = _z(0)
    gi: np.ndarray = _z(0)
    kn: np.ndarray = _z(0)
    ks: np.ndarray = _z(0)
    sigc: np.ndarray = _z(0)
    coh: np.ndarray = _z(0)
    tanphi: np.ndarray = _z(0)
    mu: np.ndarray = _z(0)
    theta: np.ndarray = _z(0)
    moment: np.ndarray = _z(0)        # bending moment on ball j about the interface centre
    state: np.ndarray = _z(0, 1, dtype=np.uint8)
    fn: np.ndarray = _z(0, 1)
    fs: np.ndarray = _z(0, 1)

    def __len__(self):
        return self.i.shape[0]


@dataclass
class BreakLog(_Arrays):
    """Every flat-joint element breakage: step, time, bond, element, balls, stone,
    mode (1 = tension, 2 = shear), position of the element centroid, stress at failure
    (sigma for tension, tau for shear) [Pa]. Capacity = number of installed elements,
    since an element breaks at most once."""
    step: np.ndarray = _z(0, dtype=np.int64)
    time: np.ndarray = _z(0)
    bond: np.ndarray = _z(0, dtype=np.int32)
    elem: np.ndarray = _z(0, dtype=np.int32)
    i: np.ndarray = _z(0, dtype=np.int32)
    j: np.ndarray = _z(0, dtype=np.int32)
    stone: np.ndarray = _z(0, dtype=np.int32)
    mode: np.ndarray = _z(0, dtype=np.int32)
    x: np.ndarray = _z(0)
    y: np.ndarray = _z(0)
    stress: np.ndarray = _z(0)
    n: np.ndarray = field(default_factory=lambda: np.zeros(1, np.int64))

    def ensure(self, cap):
        if self.step.shape[0] < cap:
            for f in fields(self):
                if f.name != "n":
                    setattr(self, f.name, _grow(getattr(self, f.name), cap))


@dataclass
class SplitLog(_Arrays):
    """Every split of a rigid stone (dem/crushing.py): step, time, the clump split
    (``parent``; it keeps the piece holding its lowest ball id) and the new one
    (``child``), the assembled stone, the parent's generation, the characteristic stress
    and the strength it reached [Pa], the parent's centre of mass [m] and the split line's
    direction, the pieces' pebbles and masses [kg], and the mass removed as fines [kg]
    (pieces below the fines size)."""
    step: np.ndarray = _z(0, dtype=np.int64)
    time: np.ndarray = _z(0)
    parent: np.ndarray = _z(0, dtype=np.int32)
    child: np.ndarray = _z(0, dtype=np.int32)
    stone: np.ndarray = _z(0, dtype=np.int32)
    gen: np.ndarray = _z(0, dtype=np.int32)
    stress: np.ndarray = _z(0)
    strength: np.ndarray = _z(0)
    x: np.ndarray = _z(0)
    y: np.ndarray = _z(0)
    ux: np.ndarray = _z(0)
    uy: np.ndarray = _z(0)
    n_parent: np.ndarray = _z(0, dtype=np.int32)
    n_child: np.ndarray = _z(0, dtype=np.int32)
    m_parent: np.ndarray = _z(0)
    m_child: np.ndarray = _z(0)
    fines: np.ndarray = _z(0)

    def __len__(self):
        return self.step.shape[0]

    def append(self, **cols):
        self.append_rows(1, cols)

    @classmethod
    def from_dict(cls, d, prefix):
        """Checkpoints written before splits existed: an empty log."""
        if prefix + "step" not in d:
            return cls()
        return super().from_dict(d, prefix)


for _cls in (Balls, Walls, Clumps, Pairs, WallPairs, Bonds, BreakLog, SplitLog):
    _cls.Arrays = namedtuple(_cls.__name__ + "Arrays", [f.name for f in fields(_cls)])
    _cls.Arrays.__module__ = __name__
    globals()[_cls.Arrays.__name__] = _cls.Arrays     # importable by name (numba cache)

# scalar run parameters (params.py), counters, error slot, energy accumulators and the
# contact law's material-pair coefficient table (the law itself, a packed int, is passed to
# the kernels beside it as a numba literal: submodels.py)
RunState = namedtuple("RunState", "prm cnt err eacc coef")
