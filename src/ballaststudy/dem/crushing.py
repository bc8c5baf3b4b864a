"""Rigid stones that split: the second family of breakage models of the thesis' ch. 2
(a stone that meets a failure criterion is replaced by smaller pieces), on clumps of
pebbles. The choices, argued in docs/stone-models/splitting-plan.md:

- Criterion, one of two stresses of a stone (CRITERIA), each calibrated on the crushing
  test (rig/crushing.py): ``largest_contact_force``, sigma_c = F_max / (d t), F_max the
  largest total force one neighbouring body (a stone, a ball, a wall segment) exerts on it,
  d = sqrt(4 A / pi) its equivalent diameter, A the pebble-sum area (the measure the
  pebble-sum mass uses; overlaps count twice, calibrated away by the crushing test) - de
  Bono and McDowell (2016): of the major principal, mean and largest-contact-force
  criteria only the last gave normal compression lines; summing the pebble contacts per
  neighbour makes F_max the force between two stones, not between two pebbles. It is blind
  to confinement: in a bed it splits ~7x more mass than bonded stones lose
  (docs/stone-models/README.md). ``deviator``, sigma_1 - sigma_3 of the stone's average
  stress (1/(A t)) sum f (x) r (symmetrised; the 2D octahedral shear up to a factor): a
  stone's other contacts lower it, as they keep a crack from opening in a bonded stone.
- Strength: Weibull with a weakest-link size effect, survival exp(-(A/A0)(sigma/sigma0)^m),
  so a stone of diameter d has characteristic strength sigma0 (d/d0)^(-2/m) (2D; 3D
  is -3/m, geoLAMMPS fix crushing); (sigma0, m) per stone material (Table 4.2's soft
  joints make stones ~20x weaker than the hard ones: one law cannot hold both). Each
  piece draws its own from a counter-based stream keyed on (seed, its lowest ball id,
  generation): no dependence on the order stones break.
- Split: a line through the centre of mass along the most compressive principal direction
  of the stone's average stress (1/A) sum f (x) r (a Brazilian disk splits along its
  loading axis), pebbles partitioned by side; turned 90 deg if one side is empty.
- The pieces start with the parent's rigid motion at their own centres (momentum and
  angular momentum kept, kinetic energy split exactly); sibling pebbles that overlap keep
  that overlap as Pairs.lap0 (no energy injected); pieces below CRUSH_FINES in equivalent
  diameter are fines: their pebbles are removed, their mass logged, their clump held at
  rest.
- Decided in the kernel (engine.run_steps) at steps that are multiples of CRUSH_EVERY, so
  a run splits at the same steps however it is chunked or resumed; the split itself is
  done here, between two steps.
"""
import math

import numpy as np
from numba import njit

from . import params as P
from .clumps import pebble_sums
from .materials import HARD, SOFT
from .neighbours import seg_closest

_MASK64 = (1 << 64) - 1
CRITERIA = ("largest_contact_force", "deviator")     # CRUSH_CRITERION 0, 1


@njit(cache=True, error_model="numpy")
def stone_loads(thick, kin, clump_of, alive, pr, wp, seg, cpos):
    """Per clump c: F_max[c] (the largest resultant of the contacts with one other body),
    S[c] = sum f (x) (x_contact - x_c) as (xx, xy, yx, yy) [N m], and the pebble-sum area
    A[c] [m^2]. Forces are the last step's (Pairs.fn/fs); ``kin`` rows as engine.run_steps'."""
    n = kin.shape[0]
    nc = cpos.shape[0]
    nbody = nc + n + seg.shape[0]
    area = np.zeros(nc)
    for i in range(n):
        if alive[i] and clump_of[i] >= 0:
            area[clump_of[i]] += math.pi * kin[i, 5] * kin[i, 5]
    cap = 2 * pr.n[0] + wp.n[0]
    key = np.empty(cap, np.int64)
    fx = np.empty(cap)
    fy = np.empty(cap)
    s = np.zeros((nc, 4))
    m = 0
    for p in range(pr.n[0]):
        if pr.fn[p] == 0.0 and pr.fs[p] == 0.0:
            continue
        i = pr.i[p]
        j = pr.j[p]
        a = clump_of[i] if clump_of[i] >= 0 else nc + i
        b = clump_of[j] if clump_of[j] >= 0 else nc + j
        if a == b or (a >= nc and b >= nc):
            continue
        dx = kin[j, 0] - kin[i, 0]
        dy = kin[j, 1] - kin[i, 1]
        d = math.sqrt(dx * dx + dy * dy)
        nx = dx / d
        ny = dy / d
        gx = pr.fn[p] * nx - pr.fs[p] * ny       # force on j
        gy = pr.fn[p] * ny + pr.fs[p] * nx
        reach = kin[i, 5] - 0.5 * (kin[i, 5] + kin[j, 5] - d)
        px = kin[i, 0] + reach * nx
        py = kin[i, 1] + reach * ny
        if a < nc:
            m = _entry(a, b, nbody, -gx, -gy, px, py, cpos, key, fx, fy, s, m)
        if b < nc:
            m = _entry(b, a, nbody, gx, gy, px, py, cpos, key, fx, fy, s, m)
    for q in range(wp.n[0]):
        i = wp.i[q]
        a = clump_of[i]
        if a < 0 or (wp.fn[q] == 0.0 and wp.fs[q] == 0.0):
            continue
        sg = wp.s[q]
        px, py, _ = seg_closest(kin[i, 0], kin[i, 1], seg[sg, 0], seg[sg, 1], seg[sg, 2], seg[sg, 3])
        dx = kin[i, 0] - px
        dy = kin[i, 1] - py
        d = math.sqrt(dx * dx + dy * dy)
        nx = dx / d
        ny = dy / d
        m = _entry(a, nc + n + sg, nbody, wp.fn[q] * nx - wp.fs[q] * ny,
                   wp.fn[q] * ny + wp.fs[q] * nx, px, py, cpos, key, fx, fy, s, m)
    fmax = np.zeros(nc)
    order = np.argsort(key[:m])
    k = 0
    while k < m:
        kk = key[order[k]]
        sx = 0.0
        sy = 0.0
        while k < m and key[order[k]] == kk:
            sx += fx[order[k]]
            sy += fy[order[k]]
            k += 1
        c = kk // nbody
        fmax[c] = max(fmax[c], math.sqrt(sx * sx + sy * sy))
    return fmax, s, area


@njit(cache=True, error_model="numpy", inline="always")
def _entry(a, b, nbody, gx, gy, px, py, cpos, key, fx, fy, s, m):
    """Contact force (gx, gy) at (px, py) on clump a from body b: into the per-neighbour
    sums and a's stress sum."""
    key[m] = a * nbody + b
    fx[m] = gx
    fy[m] = gy
    rx = px - cpos[a, 0]
    ry = py - cpos[a, 1]
    s[a, 0] += gx * rx
    s[a, 1] += gx * ry
    s[a, 2] += gy * rx
    s[a, 3] += gy * ry
    return m + 1


@njit(cache=True, error_model="numpy")
def characteristic_stress(thick, fmax, s, area, criterion):
    """The stress each clump's strength is compared with [Pa] (0 where A = 0): criterion 0,
    F_max / (d t), d = sqrt(4 A / pi); 1, the deviator sigma_1 - sigma_3 of the average
    stress S / (A t), S symmetrised."""
    out = np.zeros(fmax.shape[0])
    for c in range(fmax.shape[0]):
        if area[c] <= 0.0:
            continue
        if criterion == 1:
            out[c] = math.hypot(s[c, 0] - s[c, 3], s[c, 1] + s[c, 2]) / (area[c] * thick)
        else:
            out[c] = fmax[c] / (math.sqrt(4.0 * area[c] / math.pi) * thick)
    return out


@njit(cache=True, error_model="numpy")
def overloaded(prm, kin, balls, clumps, pr, wp, seg):
    """True if a free clump's criterion's stress reached its strength, lowered by its
    damage (engine.run_steps asks at steps that are multiples of CRUSH_EVERY); each
    clump's ``peak`` keeps the largest stress so checked (what damage accumulates from)."""
    fmax, s, area = stone_loads(prm[P.THICK], kin, balls.clump, balls.alive, pr, wp, seg, clumps.pos)
    sig = characteristic_stress(prm[P.THICK], fmax, s, area, int(prm[P.CRUSH_CRITERION]))
    hit = False
    for c in range(sig.shape[0]):
        if not clumps.held[c]:
            clumps.peak[c] = max(clumps.peak[c], sig[c])
            hit |= sig[c] >= clumps.strength[c] * (1.0 - clumps.damage[c])
    return hit


# ---------------------------------------------------------------- strength (Python)
def _splitmix64(x):
    """One step of splitmix64 (Steele, Lea and Flood 2014) on a Python int."""
    x = (x + 0x9E3779B97F4A7C15) & _MASK64
    z = x
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & _MASK64
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & _MASK64
    return z ^ (z >> 31)


def stream_uniform(seed, piece, generation):
    """A uniform number in (0, 1) that depends on (seed, piece, generation) only: a
    counter-based stream (splitmix64 of the three, chained)."""
    z = _splitmix64(int(seed) & _MASK64)
    z = _splitmix64(z ^ (int(piece) & _MASK64))
    z = _splitmix64(z ^ (int(generation) & _MASK64))
    return ((z >> 11) + 0.5) / float(1 << 53)


def weibull_strength(u, d, sigma0, m, d0):
    """The strength of a stone of equivalent diameter ``d`` whose survival probability is
    ``u``: sigma0 (d/d0)^(-2/m) (-ln u)^(1/m) [Pa] (inverse of the survival law)."""
    return sigma0 * (d / d0) ** (-2.0 / m) * (-np.log(u)) ** (1.0 / m)


def equivalent_diameter(area):
    return np.sqrt(4.0 * np.asarray(area) / np.pi)


# the parameter slots of each stone material's law (sigma0, m)
_LAW = {HARD: (P.CRUSH_SIGMA0, P.CRUSH_M), SOFT: (P.CRUSH_SIGMA0_SOFT, P.CRUSH_M_SOFT)}


def draw_strength(prm, pebbles, rad, generation, material):
    """The strength of the piece made of balls ``pebbles`` (radii ``rad``) of stone
    ``material`` at ``generation``, from its own stream (keyed on its lowest ball id)."""
    u = stream_uniform(prm[P.CRUSH_SEED], int(np.min(pebbles)), generation)
    d = float(equivalent_diameter(np.pi * (np.asarray(rad) ** 2).sum()))
    s0, m = _LAW[int(material)]
    return float(weibull_strength(u, d, prm[s0], prm[m], prm[P.CRUSH_D0]))


def _per_material(value, name):
    """(hard, soft) from one number (both) or a pair."""
    pair = tuple(float(v) for v in np.broadcast_to(np.asarray(value, float), (2,)))
    if not all(v > 0 and math.isfinite(v) for v in pair):
        raise ValueError(f"crushing: {name} must be > 0 (one number, or one per stone material: hard, soft)")
    return pair


def enable(sim, clumps, sigma0, m, d0, seed, fines_diameter, every, criterion=CRITERIA[0]):
    """Make ``clumps`` breakable: Weibull (sigma0 [Pa] at diameter d0 [m], modulus m; each
    one number or a (hard, soft) pair, by stone material) of the ``criterion``'s stress
    (one of CRITERIA), strengths drawn for generation 0, fines below ``fines_diameter``
    [m], checked every ``every`` steps."""
    sigma0, m = _per_material(sigma0, "sigma0"), _per_material(m, "m")
    if not (d0 > 0 and fines_diameter >= 0 and int(every) >= 1 and 0 <= int(seed) < 2 ** 53):
        raise ValueError("crushing: need d0 > 0, fines_diameter >= 0, every >= 1 "
                         "and 0 <= seed < 2^53 (kept exactly in the float parameters)")
    if criterion not in CRITERIA:
        raise ValueError(f"crushing: criterion {criterion!r} is not one of {', '.join(CRITERIA)}")
    p = sim.prm
    p[P.CRUSH_CRITERION] = CRITERIA.index(criterion)
    for material, (s0, mm) in _LAW.items():
        p[s0], p[mm] = sigma0[material], m[material]
    p[P.CRUSH_EVERY], p[P.CRUSH_D0], p[P.CRUSH_SEED], p[P.CRUSH_FINES] = int(every), d0, int(seed), fines_diameter
    b = sim.balls
    for c in clumps:
        peb = np.flatnonzero((b.clump == c) & (b.alive == 1))
        sim.clumps.strength[c] = draw_strength(p, peb, b.rad[peb], sim.clumps.gen[c], b.mat[peb[0]])


def settings(sim):
    """The splitting law a Simulation runs ({criterion, sigma0_Pa, weibull_modulus (each
    [hard, soft]), d0_m, seed, fines_diameter_m, every_steps}; None when its stones do not
    split)."""
    p = sim.prm
    if not p[P.CRUSH_EVERY]:
        return None
    return dict(criterion=CRITERIA[int(p[P.CRUSH_CRITERION])],
                sigma0_Pa=[float(p[s0]) for s0, _ in _LAW.values()],
                weibull_modulus=[float(p[m]) for _, m in _LAW.values()],
                d0_m=float(p[P.CRUSH_D0]), seed=int(p[P.CRUSH_SEED]),
                fines_diameter_m=float(p[P.CRUSH_FINES]), every_steps=int(p[P.CRUSH_EVERY]))


# ---------------------------------------------------------------- damage (Python)
def accumulate_damage(sim, exponent, endurance):
    """One loading cycle's fatigue damage (Miner's linear sum over a Basquin S-N curve):
    a stone whose largest characteristic stress in the cycle (``Clumps.peak``, kept by the
    kernel's checks) reached the ratio r = peak / strength above ``endurance`` gains
    1 / N_f(r) = r^exponent (N_f(1) = 1: a load at the strength breaks it at once, as the
    static criterion does); it splits once its load reaches strength (1 - D). The peaks
    start again from 0. Returns the damage gained per clump."""
    cl = sim.clumps
    with np.errstate(invalid="ignore", divide="ignore"):
        r = np.where(np.isfinite(cl.strength) & (cl.held == 0), cl.peak / cl.strength, 0.0)
    gain = np.where(r > endurance, r ** exponent, 0.0)
    cl.damage[:] = np.minimum(cl.damage + gain, 1.0)
    cl.peak[:] = 0.0
    return gain


# ---------------------------------------------------------------- the split (Python)
def loads(sim):
    """stone_loads at the current state: (F_max, S, A) per clump."""
    b = sim.balls
    kin = np.column_stack([b.pos, b.vel, b.omega, b.rad, b.minv, b.mat])
    return stone_loads(sim.prm[P.THICK], kin, b.clump, b.alive, sim.pairs.kernel(),
                       sim.wpairs.kernel(), sim.walls.seg, sim.clumps.pos)


def split_line(s):
    """Unit direction of the most compressive principal stress of the stress sum ``s``
    (xx, xy, yx, yy), symmetrised."""
    t = np.array([[s[0], 0.5 * (s[1] + s[2])], [0.5 * (s[1] + s[2]), s[3]]])
    w, v = np.linalg.eigh(t)
    return v[:, 0]                      # eigh sorts ascending: the most negative first


def partition(sim, c, u):
    """The pebbles of clump ``c`` on either side of the line through its centre along
    ``u``: (kept: the side holding its lowest ball id, other, the line's direction). The
    line turns 90 deg when a side is empty; (all, empty, u) when no line splits it."""
    b = sim.balls
    peb = np.flatnonzero((b.clump == c) & (b.alive == 1))
    r = b.pos[peb] - sim.clumps.pos[c]
    for direction in (u, np.array([-u[1], u[0]])):
        left = r[:, 1] * direction[0] - r[:, 0] * direction[1] >= 0.0
        if left.any() and not left.all():
            keep = left == left[0]
            return peb[keep], peb[~keep], direction
    return peb, peb[:0], u


def split_overloaded(sim):
    """Split every free clump whose criterion's stress reached its strength (called by
    Simulation.run when the kernel says STONES_OVERLOADED). Returns how many split."""
    fmax, s, area = loads(sim)
    sig = characteristic_stress(sim.prm[P.THICK], fmax, s, area, int(sim.prm[P.CRUSH_CRITERION]))
    cl = sim.clumps
    hit = np.flatnonzero((cl.held == 0) & (sig >= cl.strength * (1.0 - cl.damage)))
    pairs = []
    for c in hit:
        u = split_line(s[c])
        kept, other, u = partition(sim, c, u)
        if len(other) == 0:
            cl.strength[c] = np.inf         # one pebble, or none: nothing to split
            continue
        strength, gen, centre = float(cl.strength[c]), int(cl.gen[c]), cl.pos[c].copy()
        child = split_clump(sim, c, other)
        pairs.append((kept, other))
        _log(sim, c, child, gen, sig[c], strength, centre, u, kept, other)
    if pairs:
        sim._rebuild()
        for kept, other in pairs:
            sibling_overlaps(sim, kept, other)
    return len(pairs)


def split_clump(sim, c, other):
    """Clump ``c`` loses the pebbles ``other`` to a new clump: both pieces take c's rigid
    motion at their own centre of mass (v_f = v + w x (x_f - x_c), w_f = w), which keeps
    mass, momentum and angular momentum and splits the kinetic energy exactly (parallel
    axes). Both draw a strength for the next generation and start undamaged (the crack
    that damaged the parent is the split). Returns the new clump's id."""
    b, cl = sim.balls, sim.clumps
    gen = int(cl.gen[c]) + 1
    kept = np.setdiff1d(np.flatnonzero((b.clump == c) & (b.alive == 1)), other)
    v, w, x = cl.vel[c].copy(), float(cl.omega[c]), cl.pos[c].copy()
    pieces = []
    for peb in (kept, other):
        m, cx, cy, inertia = pebble_sums(b.mass[peb], b.pos[peb, 0], b.pos[peb, 1], b.inertia[peb])
        # inertial = real: the rebuild after the split applies density scaling, if on
        pieces.append(dict(pos=(cx, cy), vel=(v[0] - w * (cy - x[1]), v[1] + w * (cx - x[0])),
                           omega=w, theta=0.0, mass=m, inertia=inertia, imass=m, iinertia=inertia,
                           gen=gen, strength=draw_strength(sim.prm, peb, b.rad[peb], gen, b.mat[peb[0]]),
                           damage=0.0, peak=0.0))
    for name, value in pieces[0].items():      # the parent's row: the piece with its lowest ball
        getattr(cl, name)[c] = value
    child = cl.append(held=0, damp=cl.damp[c], **pieces[1])
    for cid, peb, piece in ((c, kept, pieces[0]), (child, other, pieces[1])):
        b.clump[peb] = cid
        b.offset[peb] = b.pos[peb] - piece["pos"]
        b.minv[peb] = 1.0 / piece["mass"]
        sim._follow_clumps(peb)
        if equivalent_diameter(np.pi * (b.rad[peb] ** 2).sum()) < sim.prm[P.CRUSH_FINES]:
            _to_fines(sim, cid, peb)
    sim.bury([c, child])        # the new faces' pebbles can be touched now
    return child


def _to_fines(sim, c, peb):
    """A piece below the fines size leaves the model: its pebbles removed, its clump held
    at rest (its mass stays in the clump arrays and in the split log)."""
    sim.delete_balls(peb)
    cl = sim.clumps
    cl.held[c] = 1
    cl.vel[c] = 0.0
    cl.omega[c] = 0.0
    cl.strength[c] = np.inf


def sibling_overlaps(sim, kept, other):
    """Listed pairs of one pebble from each piece that overlap get that overlap as
    Pairs.lap0, so the split starts no spring between them."""
    pr, b = sim.pairs, sim.balls
    n = int(pr.n[0])
    i, j = pr.i[:n], pr.j[:n]
    a, o = np.isin(i, kept), np.isin(j, other)
    cross = (a & o) | (np.isin(i, other) & np.isin(j, kept))
    k = np.flatnonzero(cross)
    lap = b.rad[i[k]] + b.rad[j[k]] - np.hypot(*(b.pos[j[k]] - b.pos[i[k]]).T)
    pr.lap0[k] = np.maximum(lap, 0.0)


def _log(sim, parent, child, gen, stress, strength, centre, u, kept, other):
    b, cl = sim.balls, sim.clumps
    alive = b.alive == 1
    gone = 0.0
    for cid in (parent, child):
        if cl.held[cid] and not alive[b.clump == cid].any():
            gone += cl.mass[cid]
    sim.splits.append(step=sim.step, time=sim.time, parent=parent, child=child,
                      stone=int(b.stone[kept[0]]), gen=gen, stress=stress,
                      strength=strength, x=centre[0], y=centre[1], ux=u[0], uy=u[1], n_parent=len(kept), n_child=len(other),
                      m_parent=float(b.mass[kept].sum()), m_child=float(b.mass[other].sum()),
                      fines=gone)
