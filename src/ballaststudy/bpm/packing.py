"""Per-stone ball sets before relaxation: which radius range a stone gets (small stones get a
scaled range), how many balls, and where they are thrown in (thesis 4.2.1, sub-step b).

Pure numpy on one stone's polygon; everything random comes from the ``rng`` passed in, so a
stone's throw-in depends only on the seed and the stone.
"""
import numpy as np

# size_policy flag values (per stone, see library.py)
POLICY_DEFAULT = 0      # the configured radius range
POLICY_SCALED = 1       # range scaled down so that the stone holds >= min_balls
POLICY_FLOOR = 2        # range scaled to the floor and still fewer than min_balls expected
POLICY_MEANINGS = "default_range scaled_range below_min_at_floor"


def mean_disk_area(r_lo, r_hi):
    """E[pi r^2] for r uniform in [r_lo, r_hi]."""
    return np.pi * (r_lo * r_lo + r_lo * r_hi + r_hi * r_hi) / 3.0


def radius_scale(area, r_lo, r_hi, solid_fraction, min_balls, floor):
    """Scale s of the radius range [s r_lo, s r_hi] for a profile of ``area``: 1 if the
    expected ball count solid_fraction*area/E[pi r^2] reaches ``min_balls``, else the s
    that makes it exactly ``min_balls`` (count ~ 1/s^2), but never below ``floor``.
    Returns (s, policy)."""
    n1 = solid_fraction * area / mean_disk_area(r_lo, r_hi)
    if n1 >= min_balls:
        return 1.0, POLICY_DEFAULT
    s = np.sqrt(n1 / min_balls)
    if s >= floor:
        return float(s), POLICY_SCALED
    return float(floor), POLICY_FLOOR


def draw_radii(area, r_lo, r_hi, solid_fraction, min_balls, rng):
    """Radii of one stone: n = max(min_balls, round(solid_fraction*area / E[pi r^2])) radii
    uniform in [r_lo, r_hi], then all multiplied by one factor so that their disk area is
    exactly solid_fraction*area (every stone starts equally dense; the factor is 1 +- a few
    percent, the relative size distribution is kept; the radii used are recorded).
    Sorted largest first (large balls placed first pack better)."""
    target = solid_fraction * area
    n = max(int(min_balls), int(round(target / mean_disk_area(r_lo, r_hi))), 2)
    r = rng.uniform(r_lo, r_hi, n)
    r *= np.sqrt(target / (np.pi * r * r).sum())
    return np.sort(r)[::-1].copy()


def edge_frame(poly):
    """Unit inward normals and offsets of a convex counter-clockwise polygon: the signed
    distance of p to edge e is n_e . p - h_e (positive inside)."""
    a = np.asarray(poly, float)
    e = np.roll(a, -1, axis=0) - a
    length = np.hypot(e[:, 0], e[:, 1])
    keep = length > 0
    a, e, length = a[keep], e[keep], length[keep]
    n = np.column_stack([-e[:, 1], e[:, 0]]) / length[:, None]      # left of edge = inside (CCW)
    h = (n * a).sum(axis=1)
    return n, h


def confining_walls(poly, margin):
    """The polygon's edges as separate wall segments, each lengthened along its own line to
    cover the polygon's whole extent in that direction plus ``margin``: a ball inside the
    convex polygon then always touches a segment's interior, never a segment end. So the
    confinement is the intersection of the edges' half-planes, with a force that is
    continuous in the ball position. (Edges linked at a corner, as ``add_wall(closed=True)``
    builds them, hand a contact over from one edge to the next when the ball's projection
    passes the corner; for a ball pressed into an inner corner the force then jumps, and in
    dense packings such a ball chatters at m/s and the force ratio never settles.)
    Returns an (n_edges, 2, 2) array of segment end points."""
    a = np.asarray(poly, float)
    b = np.roll(a, -1, axis=0)
    out = []
    for p0, p1 in zip(a, b):
        e = p1 - p0
        length = float(np.hypot(*e))
        if length == 0:
            continue
        u = e / length
        t = (a - p0) @ u
        out.append([p0 + (t.min() - margin) * u, p0 + (t.max() + margin) * u])
    return np.array(out)


def inside_distance(points, poly):
    """Signed distance of points to the boundary of a convex CCW polygon (>0 inside)."""
    n, h = edge_frame(poly)
    p = np.atleast_2d(points)
    return (p @ n.T - h[None, :]).min(axis=1)


def polygon_area_perimeter(poly):
    a = np.asarray(poly, float)
    b = np.roll(a, -1, axis=0)
    area = 0.5 * float((a[:, 0] * b[:, 1] - b[:, 0] * a[:, 1]).sum())
    return area, float(np.hypot(*(b - a).T).sum())


def throw_in(poly, r, rng, tries=16):
    """Centres for balls ``r`` (largest first) thrown into the convex polygon: each ball
    takes, of ``tries`` random candidate centres, the one with the least summed overlap
    with the balls already placed. Overlaps stay (thesis: "they can have huge overlap"),
    the relaxation removes them; the best-of-``tries`` choice only keeps the first steps
    of the relaxation from being explosive. Centres are at least min(r/2, A/(2P)) inside
    the walls (A/P <= inradius of a convex polygon, so candidates always exist), so no
    wall starts with a ball centre on its far side."""
    poly = np.asarray(poly, float)
    area, perim = polygon_area_perimeter(poly)
    lo, hi = poly.min(axis=0), poly.max(axis=0)
    n, h = edge_frame(poly)
    xy = np.empty((len(r), 2))
    for k, rk in enumerate(r):
        inset = min(0.5 * rk, 0.5 * area / perim)
        cand = np.empty((0, 2))
        while len(cand) < tries:
            p = lo + (hi - lo) * rng.random((4 * tries, 2))
            ok = (p @ n.T - h[None, :]).min(axis=1) >= inset
            cand = np.vstack([cand, p[ok]])
        cand = cand[:tries]
        if k:
            d = np.hypot(cand[:, None, 0] - xy[None, :k, 0], cand[:, None, 1] - xy[None, :k, 1])
            ov = np.clip(rk + r[None, :k] - d, 0.0, None).sum(axis=1)
            xy[k] = cand[int(np.argmin(ov))]
        else:
            xy[k] = cand[0]
    return xy
