"""Building bonded-particle stones (thesis 4.2.1, Fig. 4-7 sub-steps a-d), many at a time.

Stones are built side by side in one ``ballaststudy.dem.Simulation`` per batch: each stone
inside its own closed polygon wall, stones a few ball diameters apart so that no ball of
one stone can reach a ball or wall of another (balls of different stones never bond: the
engine bonds only balls of one ``stone_id``). One batch = one numba run for hundreds of
stones instead of one per stone.

a. walls along the 2D profile polygon (each edge a separate segment lengthened beyond the
   corners, see ``packing.confining_walls``);
b. balls thrown in (``packing.throw_in``) with overlaps;
c. relaxation with the linear contact model, no gravity, local damping, until the average
   force ratio of EVERY stone of the batch is below the limit (8e-3). The force ratio of a
   stone is the thesis' (PFC's) "ratio-average": the mean over its balls of the unbalanced
   force |sum of contact + body + applied forces| divided by the mean over its balls of the
   summed magnitudes of those forces (contact forces of balls and walls; body and applied
   forces are zero here: no gravity, no loads). Local damping is not part of either sum;
d. walls removed, balls at rest, flat joints installed between balls of one stone whose gap is below
   g_i = 0.4 * R_small (Table 4.2), relaxed ``bonded_cycles`` (1000) cycles.

After d, balls that ended up in no bonded cluster with the rest of their stone (rattlers
that would fall off at the first touch) and balls whose centre left the polygon are
deleted before the bonded relaxation; the counts are recorded per stone.
"""
from dataclasses import dataclass

import numpy as np

from ..dem import ContactMaterial, Simulation
from . import packing
from .params import DENSITIES, contact_material, flat_joint_materials


@dataclass
class Stone:
    """One stone before and after building (positions in its profile frame, m)."""
    index: int                       # position in the input list
    poly: np.ndarray
    material: int
    area: float
    scale: float = 1.0
    policy: int = packing.POLICY_DEFAULT
    x: np.ndarray = None
    y: np.ndarray = None
    r: np.ndarray = None
    bond_i: np.ndarray = None
    bond_j: np.ndarray = None
    bond_gap: np.ndarray = None
    thrown: int = 0                  # balls thrown in
    removed_rattlers: int = 0
    removed_outside: int = 0
    force_ratio: float = np.nan      # at the end of the confined relaxation
    relax_cycles: int = 0            # confined cycles of its batch
    broken_elements: int = 0         # flat-joint elements broken in the bonded relaxation
    max_bonded_move: float = 0.0     # largest ball displacement in the bonded relaxation [m]
    residual_speed: float = 0.0      # fastest ball at the end of the confined relaxation [m/s]


def prepare(stone, params, rng):
    """Radius range (scaled for small stones), radii and thrown-in centres of one stone."""
    solid = 1.0 - params.porosity
    s, pol = packing.radius_scale(stone.area, params.radius_min, params.radius_max, solid,
                                  params.min_balls, params.radius_scale_floor)
    stone.scale, stone.policy = s, pol
    n_min = params.min_balls if pol != packing.POLICY_FLOOR else 2
    r = packing.draw_radii(stone.area, s * params.radius_min, s * params.radius_max, solid,
                           n_min, rng)
    xy = packing.throw_in(stone.poly, r, rng, params.throw_tries)
    stone.x, stone.y, stone.r = xy[:, 0], xy[:, 1], r
    stone.thrown = len(r)
    return stone


def batches(stones, max_balls):
    """Stones grouped for one simulation each: sorted by radius scale (the timestep follows
    the smallest ball, so small-ball stones are kept together), at most ``max_balls``."""
    order = sorted(stones, key=lambda s: (-s.scale, s.index))
    out, cur, n = [], [], 0
    for s in order:
        if cur and n + len(s.r) > max_balls:
            out.append(cur)
            cur, n = [], 0
        cur.append(s)
        n += len(s.r)
    if cur:
        out.append(cur)
    return out


def layout(stones, walls):
    """Offsets placing the stones on a square grid, cells = largest bounding box of a stone's
    walls + a gap of 4 largest ball diameters (no contact across stones, even after
    expansion)."""
    lo = [w.reshape(-1, 2).min(axis=0) for w in walls]
    hi = [w.reshape(-1, 2).max(axis=0) for w in walls]
    ext = np.max([h - lo_ for lo_, h in zip(lo, hi)], axis=0)
    rmax = max(float(s.r.max()) for s in stones)
    cell = ext + 8.0 * rmax
    ncol = int(np.ceil(np.sqrt(len(stones))))
    return [np.array([(k % ncol) * cell[0], (k // ncol) * cell[1]]) - 0.5 * (lo[k] + hi[k])
            for k in range(len(stones))]


def force_ratio(sim, ball_stone, n_stones):
    """Per stone: mean |unbalanced force| / mean (sum of contact-force magnitudes) over its
    balls (thesis 4.2.1; body and applied forces are zero while building). 0 for a stone
    with no loaded contact (nothing to balance)."""
    n = len(ball_stone)
    c = sim.contact_list()
    i, j, fx, fy = c["i"], c["j"], c["fx"], c["fy"]
    mag = np.hypot(fx, fy)
    ball = j >= 0                      # j < 0: wall contact, force given on ball i
    fsum = np.zeros((n, 2))
    msum = np.zeros(n)
    # ball-ball: +f on j, -f on i; ball-wall: +f on i
    np.add.at(fsum[:, 0], j[ball], fx[ball])
    np.add.at(fsum[:, 1], j[ball], fy[ball])
    sign = np.where(ball, -1.0, 1.0)
    np.add.at(fsum[:, 0], i, sign * fx)
    np.add.at(fsum[:, 1], i, sign * fy)
    np.add.at(msum, j[ball], mag[ball])
    np.add.at(msum, i, mag)
    unbal = np.bincount(ball_stone, np.hypot(fsum[:, 0], fsum[:, 1]), n_stones)
    total = np.bincount(ball_stone, msum, n_stones)
    # means over the same balls: the counts cancel
    return np.divide(unbal, total, out=np.zeros(n_stones), where=total > 0)


def _confined(batch, params):
    """Sub-steps a-c for a batch. Returns positions and velocities (batch frame), radii,
    per-ball stone number in the batch, materials, stone offsets."""
    rmax = max(float(s.r.max()) for s in batch)
    walls = [packing.confining_walls(s.poly, 2.0 * rmax) for s in batch]
    off = layout(batch, walls)
    x = np.concatenate([s.x + o[0] for s, o in zip(batch, off)])
    y = np.concatenate([s.y + o[1] for s, o in zip(batch, off)])
    r = np.concatenate([s.r for s in batch])
    k_of = np.repeat(np.arange(len(batch)), [len(s.r) for s in batch]).astype(np.int32)
    mat = np.repeat([s.material for s in batch], [len(s.r) for s in batch]).astype(np.int32)
    lc = contact_material()
    sim = Simulation(thickness=params.thickness, gravity=(0.0, 0.0), damping=params.damping,
                     vmax=1.0e6)
    sim.set_contact_material(ContactMaterial(E=lc.E, kappa=lc.kappa, mu=params.packing_friction))
    sim.add_balls(x, y, r, density=np.asarray(DENSITIES)[mat], stone_id=k_of, material_id=mat)
    for w, o in zip(walls, off):
        for seg in w:
            sim.add_wall(seg + o)
    cycles = 0
    while True:
        sim.run(params.check_every)
        cycles += params.check_every
        ratio = force_ratio(sim, k_of, len(batch))
        below = ratio < params.force_ratio_limit
        if below.all() or cycles >= params.max_relax_cycles:
            break
    for k, s in enumerate(batch):
        s.force_ratio = float(ratio[k])
        s.relax_cycles = cycles
    b = sim.balls           # no public getter for ball state (see report): read-only use
    return b.pos.copy(), b.vel.copy(), r, k_of, mat, off


def _bonded(batch, params, pos, vel, r, k_of, mat, off):
    """Sub-step d for a batch: a new wall-free simulation (the engine cannot delete walls)
    from the confined positions (at rest), flat joints installed, rattlers and escaped balls
    deleted, ``bonded_cycles`` cycles."""
    sim = Simulation(thickness=params.thickness, gravity=(0.0, 0.0), damping=params.damping,
                     vmax=1.0e6)
    sim.set_contact_material(contact_material())
    # velocities are not carried over: at the force-ratio stop the forces balance, but a
    # loose ball of a frictionless packing may still fly at m/s (no force, so local damping
    # does not slow it) and would break fresh bonds at the first step
    sim.add_balls(pos[:, 0], pos[:, 1], r, density=np.asarray(DENSITIES)[mat], stone_id=k_of,
                  material_id=mat)
    sim.install_flat_joints(flat_joint_materials())
    n = len(r)
    # escaped: centre outside its own polygon (cannot happen unless a ball tunnelled a wall)
    outside = np.zeros(n, bool)
    start = 0
    for s, o in zip(batch, off):
        m = len(s.r)
        outside[start:start + m] = packing.inside_distance(pos[start:start + m] - o, s.poly) < 0
        start += m
    # keep per stone its largest fragment (ties: the one with the lowest ball id)
    comp = sim.fragments()
    keep = np.zeros(n, bool)
    for k in range(len(batch)):
        idx = np.nonzero((k_of == k) & ~outside)[0]
        if len(idx):
            labels, counts = np.unique(comp[idx], return_counts=True)
            keep[idx[comp[idx] == labels[np.argmax(counts)]]] = True
    drop = np.nonzero(~keep)[0]
    if len(drop):
        sim.delete_balls(drop)
    pos_before = sim.balls.pos.copy()
    sim.run(params.bonded_cycles)
    b = sim.balls
    bl = sim.bond_list()
    # the library keeps only bonds with every element intact: the rig installs them anew,
    # so a partly broken one would come back healed (with N_r = 1 the same as intact_bonds)
    intact = (bl["active"] == 1) & bl["state"].all(axis=1)
    bi, bj = bl["i"][intact], bl["j"][intact]
    brk = sim.breakages()
    speed = np.hypot(vel[:, 0], vel[:, 1])
    for k, (s, o) in enumerate(zip(batch, off)):
        s.residual_speed = float(speed[k_of == k].max())
        ids = np.nonzero((k_of == k) & keep)[0]
        s.removed_outside = int(((k_of == k) & outside).sum())
        s.removed_rattlers = int(((k_of == k) & ~outside & ~keep).sum())
        local = np.full(n, -1)
        local[ids] = np.arange(len(ids))
        sel = (k_of[bi] == k)
        s.bond_i, s.bond_j = local[bi[sel]].astype(np.int32), local[bj[sel]].astype(np.int32)
        p = b.pos[ids] - o
        s.x, s.y, s.r = p[:, 0], p[:, 1], r[ids]
        d = np.hypot(*(p[s.bond_j] - p[s.bond_i]).T)
        s.bond_gap = d - s.r[s.bond_i] - s.r[s.bond_j]
        s.broken_elements = int(np.isin(brk["i"], ids).sum())
        moved = np.hypot(*(b.pos[ids] - pos_before[ids]).T)
        s.max_bonded_move = float(moved.max()) if len(ids) else 0.0


def build_stones(polys, materials, params, seed, ids=None, progress=None):
    """Build one BPM per polygon. ``polys``: convex CCW polygons (m, profile frame),
    ``materials``: 0 hard / 1 soft, ``ids``: the stones' numbers (default 0, 1, ...; the
    forms-file index), so that a stone's throw-in uses its own generator
    ``default_rng([seed, id])`` whichever other stones are built. ``progress(n)`` is called
    after each batch of n stones. Returns a list of ``Stone`` in input order."""
    stones = []
    ids = range(len(polys)) if ids is None else ids
    for k, (poly, m, sid) in enumerate(zip(polys, materials, ids)):
        poly = np.asarray(poly, float)
        area, _ = packing.polygon_area_perimeter(poly)
        if not area > 0:
            raise ValueError(f"stone {k}: profile polygon is not counter-clockwise with area > 0")
        st = Stone(index=k, poly=poly, material=int(m), area=area)
        stones.append(prepare(st, params, np.random.default_rng([int(seed), int(sid)])))
    groups = batches(stones, params.batch_balls)
    for batch in groups:
        state = _confined(batch, params)
        _bonded(batch, params, *state)
        if progress is not None:
            progress(len(batch))
    return stones
