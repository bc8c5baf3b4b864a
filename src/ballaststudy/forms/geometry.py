"""Geometry of one ballast form: generation (3.1), evaluation (3.2), volume (eq. 3.2), 2D profile.

All lengths in metres. Batched kernels take point sets of shape (batch, n, 3).
"""

import numpy as np
from scipy.spatial import ConvexHull
from shapely.geometry import Polygon


def _cross(u, v):
    """Row-wise cross product of (..., 3) arrays; np.cross costs more than the maths for tiny arrays."""
    return np.stack([u[..., 1] * v[..., 2] - u[..., 2] * v[..., 1],
                     u[..., 2] * v[..., 0] - u[..., 0] * v[..., 2],
                     u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]], axis=-1)


def ellipsoid_surface_points(rng, semi_axes, n):
    """n random points on the surface of ellipsoids with the given semi-axes, shape (batch, n, 3).

    Directions are uniform on the unit sphere and then stretched by the semi-axes, so the
    points crowd towards the ends of a long ellipsoid as they would on a sphere mapped onto it.
    Axes are aligned with x, y, z: evaluation is orientation-free, so no rotation is needed.
    """
    semi_axes = np.atleast_2d(semi_axes)
    d = rng.standard_normal((semi_axes.shape[0], n, 3))
    d /= np.linalg.norm(d, axis=2, keepdims=True)
    return d * semi_axes[:, None, :]


def _max_pair(points):
    """Largest pairwise distance and the unit vector along it, for each point set (batch, n, k)."""
    diff = points[:, :, None, :] - points[:, None, :, :]
    d2 = np.einsum("bijk,bijk->bij", diff, diff)
    flat = d2.reshape(d2.shape[0], -1).argmax(axis=1)
    i, j = np.unravel_index(flat, d2.shape[1:])
    vec = diff[np.arange(points.shape[0]), i, j]
    length = np.linalg.norm(vec, axis=1)
    return length, vec / length[:, None]


def evaluate_dimensions(points):
    """Thesis 3.2: a, b, c and the directions of a and b, for point sets (batch, n, 3).

    a = largest vertex distance; vertices projected along a onto the plane normal to it,
    b = largest projected distance; projected again along b onto the line normal to a and b,
    c = largest distance on that line. Projections never lengthen a distance, so a >= b >= c.
    """
    points = np.asarray(points, dtype=float)
    a, dir_a = _max_pair(points)
    on_plane = points - np.einsum("bnk,bk->bn", points, dir_a)[:, :, None] * dir_a[:, None, :]
    b, dir_b = _max_pair(on_plane)
    # the exact projection leaves a round-off component along a; remove it
    dir_b -= np.einsum("bk,bk->b", dir_b, dir_a)[:, None] * dir_a
    dir_b /= np.linalg.norm(dir_b, axis=1, keepdims=True)
    on_line = np.einsum("bnk,bk->bn", points, _cross(dir_a, dir_b))
    c = on_line.max(axis=1) - on_line.min(axis=1)
    return a, b, c, dir_a, dir_b


def convex_hull(points):
    """Convex polyhedron through the points: (vertices, faces) with outward-oriented triangles.

    Only hull vertices are kept (points on an ellipsoid surface all are), faces index them.
    """
    hull = ConvexHull(points)
    vertices, faces = points, hull.simplices.copy()
    if len(hull.vertices) < len(points):
        used = np.sort(hull.vertices)
        remap = np.full(len(points), -1)
        remap[used] = np.arange(used.size)
        vertices, faces = points[used], remap[faces]
    v0, v1, v2 = (vertices[faces[:, k]] for k in range(3))
    outward = np.einsum("fk,fk->f", _cross(v1 - v0, v2 - v0), hull.equations[:, :3]) < 0
    faces[outward] = faces[outward][:, ::-1]
    return vertices, faces


def volume_and_centroid(vertices, faces, signed=False):
    """Volume by tetrahedra from an interior point (eq. 3.2) and the solid's centroid.

    The interior point is the vertex mean, inside any convex polyhedron; each face with it
    spans one tetrahedron of volume |(v1-p) x (v2-p) . (v3-p)| / 6. With signed=True the
    tetrahedra keep their sign, which is exact for any closed, consistently wound mesh
    (convex or not); the result is negative for an inward-wound one.
    """
    p = vertices.mean(axis=0)
    v1, v2, v3 = (vertices[faces[:, k]] - p for k in range(3))
    tet = np.einsum("fk,fk->f", _cross(v1, v2), v3) / 6.0
    if not signed:
        tet = np.abs(tet)
    volume = tet.sum()
    centroid = p + (tet[:, None] * (v1 + v2 + v3) / 4.0).sum(axis=0) / volume
    return float(volume), centroid


def section_profile(vertices, faces, origin, dir_a, dir_b):
    """Convex polygon cut from the polyhedron by the plane through origin spanned by dir_a, dir_b.

    Returns (n, 2) counter-clockwise vertices in the plane's (a, b) coordinates relative to
    origin: the stone's 2D profile for the 2D DEM (thesis 4.2.1).
    """
    normal = _cross(dir_a, dir_b)
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    # consistently wound faces run each edge once in each direction: keep one of the two
    edges = edges[edges[:, 0] < edges[:, 1]]
    s = (vertices - origin) @ normal
    s0, s1 = s[edges[:, 0]], s[edges[:, 1]]
    cross = s0 * s1 < 0
    t = s0[cross] / (s0[cross] - s1[cross])
    p0, p1 = vertices[edges[cross, 0]], vertices[edges[cross, 1]]
    pts = np.concatenate([p0 + t[:, None] * (p1 - p0), vertices[s == 0]]) - origin
    xy = np.column_stack([pts @ dir_a, pts @ dir_b])
    hull = ConvexHull(xy)   # 2D hulls come counter-clockwise
    return xy[hull.vertices]


def profile_dimensions(xy):
    """Area (eq. 4.1, via shapely) and the profile's own a, b (largest extent and the extent
    normal to it), in m^2 and m."""
    length, direction = _max_pair(xy[None, :, :])
    a, dir_a = length[0], direction[0]
    normal = np.array([-dir_a[1], dir_a[0]])
    across = xy @ normal
    return Polygon(xy).area, float(a), float(across.max() - across.min())
