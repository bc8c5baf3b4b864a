"""Evaluation of a stone made anywhere (e.g. a laser scan) given as an STL (thesis 3.2).

The file's coordinates are read in the unit the user names (mm by default: laser scans and
EN 933 work in mm), scaled to metres for the classification and reported back in that unit,
the unit in every key: `a_mm`, `b_mm`, `c_mm`, `volume_mm3`, `grid_slot_width_mm` and
`"units": "mm"` (or `a_m` ... `volume_m3` for m). `sieve_group_mm` is always the EN 933 label
in mm, `mass_kg` always kg (density in kg/m3).
"""

import math
import struct
from pathlib import Path

import numpy as np
import trimesh

from ..schema import ConfigError
from ..standards.classify import sieve_group, slot_widths_m, stone_flags
from ..standards import SIZE_GROUP_BOUNDS_MM
from . import geometry

UNITS_TO_M = {"mm": 1e-3, "m": 1.0}
PLAUSIBLE_A_M = (1e-3, 1.0)       # a grain of sand to a boulder; outside it the unit is suspect
_PROBE_BYTES = 1 << 16            # enough of an ASCII STL to hold 'solid', 'facet' and 'vertex'


class MeshError(ValueError):
    pass


def _read_head(path):
    """(size, first bytes) of a regular file, or MeshError saying what `path` is instead."""
    path = Path(path)
    if not path.exists():
        raise MeshError(f"{path}: file not found")
    if not path.is_file():
        what = "a directory" if path.is_dir() else "not a regular file"
        raise MeshError(f"{path}: not an STL file ({what})")
    try:
        with open(path, "rb") as f:
            return path.stat().st_size, f.read(_PROBE_BYTES)
    except OSError as err:
        raise MeshError(f"{path}: cannot be read: {err.strerror}") from None


def check_stl_file(path):
    """'binary' or 'ascii' from the name and content; MeshError if `path` is no STL file.

    trimesh reads random bytes, text or a truncated file as a mesh without faces, which
    would be reported as "not a closed mesh"; the format is therefore checked first.
    """
    suffix = Path(path).suffix
    size, head = _read_head(path)
    if suffix.lower() != ".stl":
        raise MeshError(f"{path}: not an STL file (the name ends in '{suffix}', expected .stl)")
    if size == 0:
        raise MeshError(f"{path}: not an STL file (the file is empty)")
    # binary STL: 80-byte header, uint32 facet count, 50 bytes per facet
    if size >= 84 and size == 84 + 50 * struct.unpack("<I", head[80:84])[0]:
        return "binary"
    text = head.lstrip().lower()
    if text.startswith(b"solid") and b"facet" in text and b"vertex" in text:
        return "ascii"
    raise MeshError(f"{path}: not an STL file (neither a binary STL, {size} bytes where the header's "
                    "facet count gives 84 + 50 per facet, nor an ASCII STL, 'solid' with 'facet' and 'vertex')")


def load_closed_mesh(path):
    kind = check_stl_file(path)
    try:
        # unprocessed: processing would drop NaN vertices and report the hole they leave;
        # the loader's normals of such facets would print numpy warnings before our error
        with np.errstate(invalid="ignore"):
            mesh = trimesh.load_mesh(path, process=False)
    except Exception as err:  # trimesh raises many types for malformed files
        raise MeshError(f"{path}: {kind} STL that cannot be parsed: {' '.join(str(err).split())}") from None
    _check_finite(path, mesh)
    mesh.process()      # merges the per-facet vertices of an STL so edges can be matched
    if len(mesh.faces) == 0 or not mesh.is_watertight:
        raise MeshError(f"{path}: not a closed mesh (it has open edges or no faces); "
                        "a stone must be a closed surface to have a volume")
    if not mesh.is_winding_consistent:
        raise MeshError(f"{path}: faces are not consistently oriented")
    return mesh


def _check_finite(path, mesh):
    finite = np.isfinite(np.asarray(mesh.vertices, float)).all(axis=1)
    bad = int((~finite[np.asarray(mesh.faces)].all(axis=1)).sum())
    if bad:
        raise MeshError(f"{path}: {bad} of {len(mesh.faces)} facets have NaN or infinite vertex "
                        "coordinates; all must be finite numbers")


def check_units(units):
    if units not in UNITS_TO_M:
        raise ConfigError("command line", "--units", f"must be one of {', '.join(UNITS_TO_M)}, got {units!r}")
    return UNITS_TO_M[units]


def check_density(density_kg_m3):
    """The density as a float (None stays None); text is accepted so the CLI reports it too."""
    if density_kg_m3 is None:
        return None
    try:
        value = float(density_kg_m3)
    except (TypeError, ValueError):
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise ConfigError("command line", "--density",
                          f"must be a finite number > 0 (kg/m3, e.g. 2650), got {density_kg_m3!r}")
    return value


def _measure_m(mesh, scale):
    """a, b, c (m) and volume (m3) of the mesh whose coordinates are `scale` metres each."""
    verts, faces = np.asarray(mesh.vertices, float) * scale, np.asarray(mesh.faces)
    a, b, c, _, _ = (x[0] for x in geometry.evaluate_dimensions(verts[None]))
    volume, _ = geometry.volume_and_centroid(verts, faces, signed=True)
    return a, b, c, abs(volume)     # negative for an inward-wound mesh


def evaluate_stl(path, density_kg_m3=None, units="mm"):
    """a, b, c, volume and grid slot width in `units`, size group, flags, and mass if a
    density (kg/m3) is given.

    The dimensions follow thesis 3.2 on the mesh vertices. The volume is the signed
    tetrahedra sum from the vertex mean, which is eq. 3.2 for a convex stone and stays exact
    for a closed non-convex scan.
    """
    scale = check_units(units)
    density = check_density(density_kg_m3)
    a, b, c, volume = _measure_m(load_closed_mesh(path), scale)
    k = int(sieve_group(b)[0])
    slot = slot_widths_m(b)[0]
    flat, nc, long = (bool(f[0]) for f in stone_flags(a, b, c))
    out = {"units": units, f"a_{units}": float(a / scale), f"b_{units}": float(b / scale),
           f"c_{units}": float(c / scale), f"volume_{units}3": float(volume / scale**3),
           "sieve_group_mm": None if k < 0 else f"{SIZE_GROUP_BOUNDS_MM[k + 1]:g}/{SIZE_GROUP_BOUNDS_MM[k]:g}",
           f"grid_slot_width_{units}": None if np.isnan(slot) else float(slot / scale),
           "flat": flat, "non_cubic": nc, "long": long, "a_over_c": float(a / c)}
    if density is not None:
        out["mass_kg"] = float(volume * density)
    return out


def units_warning(path, result):
    """A line for stderr when a lies outside 1 mm to 1 m: the file is likely in other units."""
    units = result["units"]
    a = result[f"a_{units}"]
    if PLAUSIBLE_A_M[0] <= a * UNITS_TO_M[units] <= PLAUSIBLE_A_M[1]:
        return None
    return (f"{path}: a = {a:.4g} {units} is outside 1 mm to 1 m; is --units right "
            f"(the file's coordinates are read as {units})?")
