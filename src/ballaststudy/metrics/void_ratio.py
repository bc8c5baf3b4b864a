"""Void ratio (thesis 4.5.1, eq. 4.10, l. 1061-1063): VR = A_void / A_total.

Note the name: what the thesis calls the void ratio VR is void area over *total* area,
i.e. what soil mechanics calls the porosity n. We keep the thesis' name ``void_ratio`` for
it and call the soil-mechanics void ratio e = A_void / A_solid ``void_ratio_e``.

Region: the ballast below the plate level - between the container walls, from the
container bottom up to the plate's bottom (at its middle point).

Solid = the stones (fragments), not the balls: a BPM stone is a polygon filled with balls
(thesis 4.2.1), so the pores between a stone's own balls are rock, not drainage void. A
fragment's solid polygon is

    union(its disks, one trapezoid per intact bond) with all interior holes filled,

the trapezoid of bond (i, j) joining the diameters of the two disks normal to the line of
centres (c_i +- r_i n_perp, c_j +- r_j n_perp). The trapezoids bridge the installation gaps
between bonded balls (up to 0.4 R, Table 4.2) and straighten the outline between bonded
boundary balls to their common tangent; every cycle of bonds then encloses a hole that
the filling closes. Holes are filled per fragment *before* the fragments are united, so
a pore enclosed by several stones stays void. For a convex stone whose boundary balls are
bonded neighbours the result is exactly the Minkowski sum of the polygon of centres with
a disk of radius r (equal radii): A = A_centres + P_centres r + pi r^2. Filling the holes
of the union of disks alone would not work here: with installation gaps the disks of one
stone need not overlap, and the pores leak out through the gaps.

Areas (each cycle, fast): the region's sides and bottom are the container walls, which
the stones do not cross beyond contact overlaps of micrometres. A fragment inside the
region (up to such overlaps) counts with its whole solid area, a fragment crossing the
plate level (or any side by more than a quarter of its smallest ball radius) with its
solid polygon cut to the region, one outside not at all. The disks of the ball-based
porosity are cut at the plate level only. Stones touch with tiny overlaps:
the union of the solids is their sum minus the lens overlap of every pair of overlapping
balls of different fragments (pairs of overlaps overlapping each other are neglected).
The ball-based porosity uses exact disks the same way: sum of the disk areas below the
plate level minus the lens of every overlapping pair.

Disks in a fragment's solid are polygons with 4 * quad_segs sides (shapely), which
under-estimates a disk's area by about (2 pi / (4 q))^2 / 6 (0.16 % for q = 16).

``SolidCache``: a fragment's solid is reused while the same balls and bonds make the
fragment and they moved rigidly (least-squares rigid fit, largest residual below a
tolerance): a stone deforms by micrometres under load, so its area is unchanged to
~1e-4, and building the polygons is most of the cost. A stone inside the region counts
with the area kept; one crossing the plate level with the kept polygon moved by the
fitted rigid motion, then cut. The rig clears it at checkpoints,
so a resumed run computes the same numbers as one that never stopped.
"""
import numpy as np
import shapely
import shapely.affinity
from scipy.spatial import cKDTree


def _fill_holes(geom):
    """Polygon/MultiPolygon with interior rings removed."""
    parts = shapely.get_parts(geom)
    shells = [shapely.polygons(shapely.get_exterior_ring(p)) for p in parts if not p.is_empty]
    return shapely.union_all(shells) if shells else shapely.Polygon()


def stone_solid(pos, rad, bond_i, bond_j, quad_segs=16):
    """Solid polygon of one fragment (all balls given belong to it, the bonds are its intact
    bonds with ball ids indexing ``pos``)."""
    pos = np.asarray(pos, float)
    rad = np.asarray(rad, float)
    disks = shapely.buffer(shapely.points(pos), rad, quad_segs=quad_segs)
    parts = list(disks)
    bi = np.asarray(bond_i, dtype=np.int64)
    bj = np.asarray(bond_j, dtype=np.int64)
    if bi.size:
        d = pos[bj] - pos[bi]
        n = np.column_stack([-d[:, 1], d[:, 0]]) / np.hypot(d[:, 0], d[:, 1])[:, None]
        ri, rj = rad[bi, None], rad[bj, None]
        quad = np.stack([pos[bi] + ri * n, pos[bj] + rj * n, pos[bj] - rj * n, pos[bi] - ri * n], axis=1)
        parts.extend(shapely.polygons(quad))
    return _fill_holes(shapely.union_all(parts))


def rigid_fits(p0, p1, seg):
    """The least-squares rigid motion (2D Kabsch) mapping each segment of the stacked points
    ``p0`` onto the same rows of ``p1`` (``seg``: the segments' first rows, ascending, none
    empty): (shapely affine matrices [a, b, d, e, xoff, yoff] (k, 6), largest residual
    distance per segment [m])."""
    n = np.diff(np.append(seg, len(p0)))
    of = np.repeat(np.arange(len(seg)), n)
    c0 = np.add.reduceat(p0, seg) / n[:, None]
    c1 = np.add.reduceat(p1, seg) / n[:, None]
    a, b = p0 - c0[of], p1 - c1[of]
    th = np.arctan2(np.add.reduceat(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0], seg),
                    np.add.reduceat((a * b).sum(axis=1), seg))
    c, s = np.cos(th), np.sin(th)
    moved = np.column_stack([c[of] * a[:, 0] - s[of] * a[:, 1], s[of] * a[:, 0] + c[of] * a[:, 1]])
    residual = np.maximum.reduceat(np.sqrt(((moved - b) ** 2).sum(axis=1)), seg)
    matrix = np.column_stack([c, -s, s, c, c1[:, 0] - (c * c0[:, 0] - s * c0[:, 1]),
                              c1[:, 1] - (s * c0[:, 0] + c * c0[:, 1])])
    return matrix, residual


class SolidCache:
    """Solids of fragments, kept while they move rigidly (see the module text): the area
    as it is, the polygon moved with the stone (for a stone crossing the region's edge)."""

    def __init__(self, tolerance):
        self.tolerance = float(tolerance)      # [m] largest rigid-fit residual
        self.entries = {}                      # key -> (ball positions, solid polygon, area)
        self.hits = self.builds = 0

    def clear(self):
        self.entries.clear()

    def lookup(self, frags, build):
        """One (entry, rigid motion since it was built, or None if built now) per fragment of
        ``frags`` = [(key, current ball positions)]; ``build(k)`` makes the k-th one's solid.
        The rigid fits of all kept fragments in one vectorised pass (per-fragment numpy calls
        cost more than the fits)."""
        kept = [k for k, (key, _) in enumerate(frags) if key in self.entries]
        fits = {}
        if kept:
            p0 = [self.entries[frags[k][0]][0] for k in kept]
            seg = np.cumsum([0] + [len(q) for q in p0[:-1]])
            matrix, residual = rigid_fits(np.concatenate(p0),
                                          np.concatenate([frags[k][1] for k in kept]), seg)
            fits = {k: m for k, m, r in zip(kept, matrix, residual) if r <= self.tolerance}
        out = []
        for k, (key, pos) in enumerate(frags):
            if k in fits:
                self.hits += 1
                out.append((self.entries[key], list(fits[k])))
                continue
            self.builds += 1
            polygon = build(k)
            self.entries[key] = (pos.copy(), polygon, polygon.area)
            out.append((self.entries[key], None))
        return out


def _disk_area_below(y, r, y_top):
    """Area of each disk (centre height y, radius r) below the line y = y_top."""
    h = np.clip((y_top - y) / r, -1.0, 1.0)            # signed distance of the cut, in r
    return r * r * (np.pi - np.arccos(h) + h * np.sqrt(1.0 - h * h))


def _lens(d, r1, r2):
    """Area of the intersection of two disks with centre distance 0 <= d < r1 + r2."""
    d = np.maximum(d, 1e-300)
    small = d <= np.abs(r1 - r2)                        # one disk inside the other
    c1 = np.clip((d * d + r1 * r1 - r2 * r2) / (2 * d * r1), -1.0, 1.0)
    c2 = np.clip((d * d + r2 * r2 - r1 * r1) / (2 * d * r2), -1.0, 1.0)
    k = (-d + r1 + r2) * (d + r1 - r2) * (d - r1 + r2) * (d + r1 + r2)
    a = r1 * r1 * np.arccos(c1) + r2 * r2 * np.arccos(c2) - 0.5 * np.sqrt(np.maximum(k, 0.0))
    return np.where(small, np.pi * np.minimum(r1, r2) ** 2, a)


def _overlaps(pos, rad, y_top):
    """(i, j, lens area) of every pair of overlapping disks whose lens centre lies below
    y_top."""
    if len(pos) < 2:
        return np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0)
    pairs = cKDTree(pos).query_pairs(2.0 * float(rad.max()), output_type="ndarray")
    i, j = pairs[:, 0], pairs[:, 1]
    d = np.hypot(*(pos[j] - pos[i]).T)
    keep = d < rad[i] + rad[j]
    i, j, d = i[keep], j[keep], d[keep]
    below = 0.5 * (pos[i, 1] + pos[j, 1]) < y_top
    i, j, d = i[below], j[below], d[below]
    return i, j, _lens(d, rad[i], rad[j])


def _solid_area(ids, p, r, seg, bonds, region, quad_segs, cache):
    """Solid area inside the region of the fragments whose balls (ids ``ids``, positions
    ``p``, radii ``r``) are the segments ``seg`` (first rows, ascending, none empty);
    ``bonds[f]``: fragment f's intact bonds (i, j) in local ball ids."""
    x0, y0, x1, y1 = region.bounds
    lo = np.minimum.reduceat(p - r[:, None], seg)
    hi = np.maximum.reduceat(p + r[:, None], seg)
    slack = 0.25 * np.minimum.reduceat(r, seg)   # more than any contact overlap with a wall
    inside = ~((lo[:, 1] >= y1) | (hi[:, 1] <= y0) | (lo[:, 0] >= x1) | (hi[:, 0] <= x0))
    cut = (hi[:, 1] > y1) | (lo[:, 1] < y0 - slack) | (lo[:, 0] < x0 - slack) | (hi[:, 0] > x1 + slack)
    ends = np.append(seg[1:], len(p))
    frags = np.nonzero(inside)[0]

    def solid(f):
        return stone_solid(p[seg[f]:ends[f]], r[seg[f]:ends[f]], *bonds[f], quad_segs)
    if cache is None:
        found = [((None, sol, sol.area), None) for sol in map(solid, frags)]
    else:
        found = cache.lookup([((ids[seg[f]:ends[f]].tobytes(), bonds[f][0].tobytes(),
                                bonds[f][1].tobytes()), p[seg[f]:ends[f]]) for f in frags],
                             lambda k: solid(frags[k]))
    total = 0.0
    for f, ((_, polygon, area), matrix) in zip(frags, found):
        if not cut[f]:
            total += area
            continue
        if matrix is not None:
            polygon = shapely.affinity.affine_transform(polygon, matrix)
        total += shapely.intersection(polygon, region).area
    return total


def void_ratio(pos, rad, labels, n_fragments, bond_i, bond_j, bond_intact,
               x_min, x_max, y_bottom, y_top, quad_segs=16, cache=None):
    """Void ratio of the ballast region [x_min, x_max] x [y_bottom, y_top] (y_top = plate
    bottom) [m].

    pos (n,2) [m], rad (n,) [m]: all balls; labels (n,) fragment of each ball, -1 for
    balls that are not ballast (ignored); bonds as in ``fragments``; cache: a
    ``SolidCache`` or None (every solid built anew).

    Returns dict:
      void_ratio     VR = A_void / A_total with the stones as solid (eq. 4.10) [1]
      void_ratio_e   e  = A_void / A_solid with the same solid [1]
      void_ratio_balls  A_void / A_total with the disks as solid (pores inside stones
                     counted as void; the "porosity of the balls") [1]
      area_total, area_solid, area_void [m^2] (per unit thickness).
    """
    pos = np.asarray(pos, float)
    rad = np.asarray(rad, float)
    labels = np.asarray(labels)
    if y_top <= y_bottom or x_max <= x_min:
        raise ValueError(f"empty region x [{x_min}, {x_max}] y [{y_bottom}, {y_top}]")
    region = shapely.box(x_min, y_bottom, x_max, y_top)
    a_total = region.area
    bi = np.asarray(bond_i, dtype=np.int64)
    bj = np.asarray(bond_j, dtype=np.int64)
    ok = np.asarray(bond_intact, bool)
    ok = ok & (labels[bi] >= 0) & (labels[bi] == labels[bj])
    bi, bj = bi[ok], bj[ok]
    # local ids: balls sorted by fragment
    ball_ids = np.nonzero(labels >= 0)[0]
    order = ball_ids[np.argsort(labels[ball_ids], kind="stable")]
    starts = np.searchsorted(labels[order], np.arange(n_fragments + 1))
    bond_frag = labels[bi]
    bond_order = np.argsort(bond_frag, kind="stable")
    bstarts = np.searchsorted(bond_frag[bond_order], np.arange(n_fragments + 1))
    local = np.empty(labels.size, dtype=np.int64)
    local[order] = np.arange(order.size) - starts[labels[order]]
    li, lj = local[bi[bond_order]], local[bj[bond_order]]
    present = np.nonzero(np.diff(starts) > 0)[0]      # fragments with a ballast ball
    bonds = [(li[bstarts[f]:bstarts[f + 1]], lj[bstarts[f]:bstarts[f + 1]]) for f in present]
    a_solid = _solid_area(order, pos[order], rad[order], starts[present], bonds, region,
                          quad_segs, cache) if present.size else 0.0
    i, j, lens = _overlaps(pos[ball_ids], rad[ball_ids], y_top)
    lab = labels[ball_ids]
    a_solid -= lens[lab[i] != lab[j]].sum()
    a_balls = _disk_area_below(pos[ball_ids, 1], rad[ball_ids], y_top).sum() - lens.sum()
    a_void = a_total - a_solid
    return dict(void_ratio=a_void / a_total,
                void_ratio_e=a_void / a_solid if a_solid > 0 else np.inf,
                void_ratio_balls=(a_total - a_balls) / a_total,
                area_total=a_total, area_solid=a_solid, area_void=a_void)
