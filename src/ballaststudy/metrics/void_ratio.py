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


def rigid_fit(p0, p1):
    """The least-squares rigid motion (2D Kabsch) mapping points ``p0`` onto ``p1``:
    (shapely affine matrix [a, b, d, e, xoff, yoff], largest residual distance [m])."""
    c0, c1 = p0.mean(axis=0), p1.mean(axis=0)
    a, b = p0 - c0, p1 - c1
    th = np.arctan2((a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]).sum(), (a * b).sum())
    c, s = np.cos(th), np.sin(th)
    moved = np.column_stack([c * a[:, 0] - s * a[:, 1], s * a[:, 0] + c * a[:, 1]])
    residual = float(np.sqrt(((moved - b) ** 2).sum(axis=1)).max())
    matrix = [c, -s, s, c, c1[0] - (c * c0[0] - s * c0[1]), c1[1] - (s * c0[0] + c * c0[1])]
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

    def _lookup(self, members, pos, rad, bi, bj, quad_segs):
        """(entry, rigid motion since it was built or None if just built)."""
        key = (members.tobytes(), bi.tobytes(), bj.tobytes())
        hit = self.entries.get(key)
        if hit is not None:
            matrix, residual = rigid_fit(hit[0], pos)
            if residual <= self.tolerance:
                self.hits += 1
                return hit, matrix
        self.builds += 1
        polygon = stone_solid(pos, rad, bi, bj, quad_segs)
        self.entries[key] = (pos.copy(), polygon, polygon.area)
        return self.entries[key], None

    def solid(self, members, pos, rad, bi, bj, quad_segs):
        """The fragment's solid polygon now (``stone_solid``)."""
        (_, polygon, _), matrix = self._lookup(members, pos, rad, bi, bj, quad_segs)
        return polygon if matrix is None else shapely.affinity.affine_transform(polygon, matrix)

    def area(self, members, pos, rad, bi, bj, quad_segs):
        """The fragment's solid area (a rigid motion keeps it)."""
        return self._lookup(members, pos, rad, bi, bj, quad_segs)[0][2]


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


def _fragment_area(members, pos, rad, bi, bj, region, quad_segs, cache):
    """Solid area of one fragment inside the region."""
    p, r = pos[members], rad[members]
    x0, y0, x1, y1 = region.bounds
    lo, hi = (p - r[:, None]).min(axis=0), (p + r[:, None]).max(axis=0)
    if lo[1] >= y1 or hi[1] <= y0 or lo[0] >= x1 or hi[0] <= x0:
        return 0.0
    slack = 0.25 * r.min()          # more than any contact overlap with a container wall
    if hi[1] > y1 or lo[1] < y0 - slack or lo[0] < x0 - slack or hi[0] > x1 + slack:
        solid = stone_solid(p, r, bi, bj, quad_segs) if cache is None else cache.solid(
            members, p, r, bi, bj, quad_segs)
        return shapely.intersection(solid, region).area
    if cache is None:
        return stone_solid(p, r, bi, bj, quad_segs).area
    return cache.area(members, p, r, bi, bj, quad_segs)


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
    a_solid = 0.0
    for f in range(n_fragments):
        members = order[starts[f]:starts[f + 1]]
        local[members] = np.arange(members.size)
        b = bond_order[bstarts[f]:bstarts[f + 1]]
        a_solid += _fragment_area(members, pos, rad, local[bi[b]], local[bj[b]], region,
                                  quad_segs, cache)
    i, j, lens = _overlaps(pos[ball_ids], rad[ball_ids], y_top)
    lab = labels[ball_ids]
    a_solid -= lens[lab[i] != lab[j]].sum()
    a_balls = _disk_area_below(pos[ball_ids, 1], rad[ball_ids], y_top).sum() - lens.sum()
    a_void = a_total - a_solid
    return dict(void_ratio=a_void / a_total,
                void_ratio_e=a_void / a_solid if a_solid > 0 else np.inf,
                void_ratio_balls=(a_total - a_balls) / a_total,
                area_total=a_total, area_solid=a_solid, area_void=a_void)
