"""Evaluation of a stone made anywhere (e.g. a laser scan) given as an STL (thesis 3.2)."""

import numpy as np
import trimesh

from ..standards.classify import sieve_group, slot_widths_m, stone_flags
from ..standards import SIZE_GROUP_BOUNDS_MM
from . import geometry


class MeshError(ValueError):
    pass


def load_closed_mesh(path):
    try:
        mesh = trimesh.load_mesh(path, force="mesh")
    except Exception as err:  # trimesh raises many types for unreadable files
        raise MeshError(f"{path}: cannot be read as a mesh: {err}") from None
    if len(mesh.faces) == 0 or not mesh.is_watertight:
        raise MeshError(f"{path}: not a closed mesh (it has open edges or no faces); "
                        "a stone must be a closed surface to have a volume")
    if not mesh.is_winding_consistent:
        raise MeshError(f"{path}: faces are not consistently oriented")
    return mesh


def evaluate_stl(path, density_kg_m3=None):
    """a, b, c (m), volume (m3), size group, flags, and mass if a density is given.

    The dimensions follow thesis 3.2 on the mesh vertices. The volume is the signed
    tetrahedra sum from the vertex mean, which is eq. 3.2 for a convex stone and stays exact
    for a closed non-convex scan.
    """
    mesh = load_closed_mesh(path)
    verts, faces = np.asarray(mesh.vertices, float), np.asarray(mesh.faces)
    a, b, c, _, _ = (x[0] for x in geometry.evaluate_dimensions(verts[None]))
    volume, _ = geometry.volume_and_centroid(verts, faces, signed=True)
    if volume < 0:       # inward-wound mesh
        volume = -volume
    k = int(sieve_group(b)[0])
    flat, nc, long = (bool(f[0]) for f in stone_flags(a, b, c))
    out = {"a_m": float(a), "b_m": float(b), "c_m": float(c), "volume_m3": float(volume),
           "sieve_group_mm": None if k < 0 else f"{SIZE_GROUP_BOUNDS_MM[k + 1]:g}/{SIZE_GROUP_BOUNDS_MM[k]:g}",
           "grid_slot_width_m": None if np.isnan(slot_widths_m(b)[0]) else float(slot_widths_m(b)[0]),
           "flat": flat, "non_cubic": nc, "long": long, "a_over_c": float(a / c)}
    if density_kg_m3 is not None:
        out["mass_kg"] = float(volume * density_kg_m3)
    return out
