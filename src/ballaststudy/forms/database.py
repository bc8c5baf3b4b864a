"""A form database on disk: one netCDF per database (per-stone data, ragged 3D polyhedra and
2D profiles as CF contiguous ragged arrays) and a zip of one STL per stone."""

import io
import json
import zipfile

import numpy as np
import trimesh
import xarray as xr

from ..standards import GRADING_SIEVES_MM
from . import geometry


def _ragged(arrays, dtype):
    counts = np.array([len(x) for x in arrays], dtype=np.int32)
    return counts, np.concatenate(arrays).astype(dtype)


def stone_profile(stone):
    """2D profile: section through the centroid in the plane of a and b (thesis 4.2.1)."""
    xy = geometry.section_profile(stone.vertices, stone.faces, stone.centroid, stone.dir_a, stone.dir_b)
    return xy, geometry.profile_dimensions(xy)


def _var(data, dims, units, long_name, **attrs):
    return (dims, data, {"units": units, "long_name": long_name, **attrs})


def to_dataset(objective, stones, seed, params, provenance_json):
    """xarray Dataset of one generated database (lengths in m, masses in kg)."""
    profiles = [stone_profile(s) for s in stones]
    vcount, verts = _ragged([s.vertices - s.centroid for s in stones], np.float64)
    fcount, faces = _ragged([s.faces for s in stones], np.int32)
    pcount, pxy = _ragged([p[0] for p in profiles], np.float64)
    col = lambda name: np.array([getattr(s, name) for s in stones])  # noqa: E731
    mats = objective.materials
    flag = {"flag_values": np.array([0, 1], np.int8), "flag_meanings": "no yes"}
    v = {
        "a": _var(col("a"), "stone", "m", "largest dimension a (largest vertex distance)"),
        "b": _var(col("b"), "stone", "m", "middle dimension b (largest distance normal to a)"),
        "c": _var(col("c"), "stone", "m", "smallest dimension c (extent normal to a and b)"),
        "volume": _var(col("volume"), "stone", "m3", "volume of the polyhedron (eq. 3.2)"),
        "mass": _var(col("mass"), "stone", "kg", "mass of the stone"),
        "material": _var(col("material").astype(np.int8), "stone", "1", "rock material",
                         flag_values=np.arange(len(mats), dtype=np.int8),
                         flag_meanings=" ".join(m.name for m in mats)),
        "density": _var(np.array([mats[s.material].density_kg_m3 for s in stones]), "stone",
                        "kg m-3", "raw density of the stone's material"),
        "sieve_group_lower": _var(np.array([_group(objective, s).lower for s in stones]), "stone", "m",
                                  "lower sieve d of the stone's size group d <= b < D (eq. 3.1)"),
        "sieve_group_upper": _var(np.array([_group(objective, s).upper for s in stones]), "stone", "m",
                                  "upper sieve D of the stone's size group"),
        "is_flat": _var(col("flat").astype(np.int8), "stone", "1", "flat: c below the grid-sieve slot width", **flag),
        "is_non_cubic": _var(col("non_cubic").astype(np.int8), "stone", "1", "non-cubic: a/c > 3", **flag),
        "is_long": _var(col("long").astype(np.int8), "stone", "1", "long: a >= 100 mm", **flag),
        "direction_a": _var(np.array([s.dir_a for s in stones]), ("stone", "xyz"), "1", "unit vector along a"),
        "direction_b": _var(np.array([s.dir_b for s in stones]), ("stone", "xyz"), "1", "unit vector along b"),
        "vertex_count": _var(vcount, "stone", "1", "polyhedron vertices per stone", sample_dimension="vertex"),
        "vertices": _var(verts, ("vertex", "xyz"), "m", "polyhedron vertices relative to the stone's centroid"),
        "face_count": _var(fcount, "stone", "1", "triangular faces per stone", sample_dimension="face"),
        "faces": _var(faces, ("face", "corner"), "1", "face corners, indices into the stone's own vertices"),
        "profile_vertex_count": _var(pcount, "stone", "1", "2D profile vertices per stone",
                                     sample_dimension="profile_vertex"),
        "profile": _var(pxy, ("profile_vertex", "xy"), "m",
                        "2D profile polygon (counter-clockwise) in the (a, b) plane through the centroid"),
        "profile_area": _var(np.array([p[1][0] for p in profiles]), "stone", "m2", "area of the 2D profile (eq. 4.1)"),
        "profile_a": _var(np.array([p[1][1] for p in profiles]), "stone", "m", "largest dimension of the 2D profile"),
        "profile_b": _var(np.array([p[1][2] for p in profiles]), "stone", "m", "profile extent normal to its a"),
        "objective_percent_passing": _var(np.array(objective.percent_passing), "sieve", "percent",
                                          "objective percent passing by mass"),
    }
    coords = {"stone": _var(np.arange(len(stones)), "stone", "1", "stone index in the database"),
              "xyz": ("xyz", ["x", "y", "z"], {"long_name": "vertex coordinate"}),
              "xy": ("xy", ["a", "b"], {"long_name": "profile coordinate: along the stone's a and b"}),
              "sieve": _var(np.array(GRADING_SIEVES_MM) * 1e-3, "sieve", "m", "square-mesh sieve size")}
    attrs = {
        "title": f"ballast form database {objective.name}",
        "database": objective.name,
        "objective_total_mass_kg": objective.total_mass,
        "objective_shape_index_pct": objective.shape_index,
        "objective_particle_length_index_pct": objective.particle_length_index,
        "objective_flakiness_index_pct": -1.0 if objective.flakiness_index is None else objective.flakiness_index,
        "objective_flakiness_index_note": "-1 means not applicable (no FI target)",
        "materials": json.dumps([m.__dict__ for m in mats]),
        "seed": int(seed),
        "form_params": json.dumps(params.__dict__),
        "Conventions": "CF-1.8",
        "provenance": provenance_json,
    }
    return xr.Dataset(v, coords=coords, attrs=attrs)


def _group(objective, stone):
    return next(g for g in objective.groups if g.index == stone.group)


def write_netcdf(ds, path):
    ds.to_netcdf(path, engine="netcdf4")


def stone_meshes(ds):
    """One trimesh per stone, in the database's order."""
    voff = np.concatenate([[0], np.cumsum(ds.vertex_count.values)])
    foff = np.concatenate([[0], np.cumsum(ds.face_count.values)])
    verts, faces = ds.vertices.values, ds.faces.values
    return [trimesh.Trimesh(verts[voff[i]:voff[i + 1]], faces[foff[i]:foff[i + 1]], process=False)
            for i in range(ds.sizes["stone"])]


def stone_profiles(ds):
    """List of (n, 2) profile polygons (m)."""
    off = np.concatenate([[0], np.cumsum(ds.profile_vertex_count.values)])
    xy = ds.profile.values
    return [xy[off[i]:off[i + 1]] for i in range(ds.sizes["stone"])]


def write_stl_archive(ds, path):
    """A zip with one binary STL per stone (stone_00000.stl, ...), for use in other DEM codes."""
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for i, mesh in enumerate(stone_meshes(ds)):
            buf = io.BytesIO()
            mesh.export(buf, file_type="stl")
            zf.writestr(f"stone_{i:05d}.stl", buf.getvalue())
