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

Disks are polygons with 4 * quad_segs sides (shapely), which under-estimates a disk's
area by about (2 pi / (4 q))^2 / 6 (0.16 % for q = 16).
"""
import numpy as np
import shapely


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


def void_ratio(pos, rad, labels, n_fragments, bond_i, bond_j, bond_intact,
               x_min, x_max, y_bottom, y_top, quad_segs=16):
    """Void ratio of the ballast region [x_min, x_max] x [y_bottom, y_top] (y_top = plate
    bottom) [m].

    pos (n,2) [m], rad (n,) [m]: all balls; labels (n,) fragment of each ball, -1 for
    balls that are not ballast (ignored); bonds as in ``fragments``.

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
    solids = []
    for f in range(n_fragments):
        members = order[starts[f]:starts[f + 1]]
        local[members] = np.arange(members.size)
        b = bond_order[bstarts[f]:bstarts[f + 1]]
        solids.append(stone_solid(pos[members], rad[members], local[bi[b]], local[bj[b]], quad_segs))
    solid = shapely.intersection(shapely.union_all(solids), region) if solids else shapely.Polygon()
    disks = shapely.buffer(shapely.points(pos[ball_ids]), rad[ball_ids], quad_segs=quad_segs)
    balls = shapely.intersection(shapely.union_all(disks), region) if ball_ids.size else shapely.Polygon()
    a_solid = solid.area
    a_void = a_total - a_solid
    return dict(void_ratio=a_void / a_total,
                void_ratio_e=a_void / a_solid if a_solid > 0 else np.inf,
                void_ratio_balls=(a_total - balls.area) / a_total,
                area_total=a_total, area_solid=a_solid, area_void=a_void)
