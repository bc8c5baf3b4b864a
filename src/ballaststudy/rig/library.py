"""Reading a BPM library (``BPM.nc``, written by ``ballaststudy.bpm``) and a small synthetic
stand-in with the same format for tests and the benchmark.

Format (dims ``stone``, ``ball``, ``bond``; CF ragged counts ``ball_count``/``bond_count``):
per stone ``material`` (int8, flag_meanings "hard soft"), ``profile_area``, ``mass_2d`` ...;
per ball ``ball_x``, ``ball_y`` (relative to the stone's ball centroid), ``ball_radius``;
per bond ``bond_i``, ``bond_j`` (local ball indices), ``bond_gap``; attrs ``database``,
``thickness_m``, ``materials_json``.
"""
import json
from dataclasses import dataclass

import numpy as np
import xarray as xr
from scipy.spatial import ConvexHull

from ..schema import ConfigError
from ..dem import DENSITY_HARD, DENSITY_SOFT, ContactMaterial, FlatJointMaterial
from ..dem.materials import HARD, MATERIAL_NAMES, SOFT
from ..inputs import open_netcdf



class LibraryError(ConfigError):
    """A BPM library that cannot be used: `file: variable: what` (one line, exit code 2)."""


@dataclass
class Stone:
    """One BPM stone: ball centres relative to the ball centroid, radii, local bonds."""
    x: np.ndarray
    y: np.ndarray
    r: np.ndarray
    bond_i: np.ndarray
    bond_j: np.ndarray
    material: int

    @property
    def extent(self):
        """Radius of the disk about the centroid that holds every ball [m]."""
        return float(np.max(np.hypot(self.x, self.y) + self.r))

    @property
    def area(self):
        return float(np.sum(np.pi * self.r ** 2))


class Library:
    """A loaded BPM library: stones by index, materials, densities."""

    def __init__(self, ds, path="BPM.nc"):
        self.path = str(path)
        need = ("ball_count", "bond_count", "material", "ball_x", "ball_y", "ball_radius",
                "bond_i", "bond_j")
        for v in need:
            if v not in ds.variables:
                raise LibraryError(path, v, "variable missing (BPM library format)")
        self.database = str(ds.attrs.get("database", "unknown"))
        self.thickness = float(ds.attrs.get("thickness_m", 1.0))
        nb = np.asarray(ds["ball_count"].values, np.int64)
        nf = np.asarray(ds["bond_count"].values, np.int64)
        self._b0 = np.r_[0, np.cumsum(nb)]
        self._f0 = np.r_[0, np.cumsum(nf)]
        if self._b0[-1] != ds.sizes.get("ball", 0) or self._f0[-1] != ds.sizes.get("bond", 0):
            raise LibraryError(path, "ball_count", "ball_count/bond_count do not add up to the ball/bond dims")
        self.material = np.asarray(ds["material"].values, np.int64)
        self.bx = np.asarray(ds["ball_x"].values, float)
        self.by = np.asarray(ds["ball_y"].values, float)
        self.br = np.asarray(ds["ball_radius"].values, float)
        self.fi = np.asarray(ds["bond_i"].values, np.int64)
        self.fj = np.asarray(ds["bond_j"].values, np.int64)
        self.materials = parse_materials(ds.attrs.get("materials_json"), path)
        self.attrs = dict(ds.attrs)

    def __len__(self):
        return len(self.material)

    def stone(self, k):
        b = slice(self._b0[k], self._b0[k + 1])
        f = slice(self._f0[k], self._f0[k + 1])
        return Stone(self.bx[b], self.by[b], self.br[b], self.fi[f], self.fj[f],
                     int(self.material[k]))

    def ball_count(self, k):
        return int(self._b0[k + 1] - self._b0[k])

    def bond_count(self, k):
        return int(self._f0[k + 1] - self._f0[k])


def parse_materials(text, path="BPM.nc"):
    """``materials_json`` -> {0: dict(fj=FlatJointMaterial, lc=ContactMaterial, density)}
    for hard (0) and soft (1). Accepts keys either flat or under ``flat_joint``/``contact``;
    anything missing takes the Table 4.2 default of that rock."""
    try:
        raw = json.loads(text) if text else {}
    except json.JSONDecodeError as err:
        raise LibraryError(path, "materials_json", f"attribute is not JSON: {err}") from None
    out = {}
    for mid, name in enumerate(MATERIAL_NAMES):
        d = raw.get(name, {}) or {}
        fj = FlatJointMaterial.hard() if mid == HARD else FlatJointMaterial.soft()
        fjd = dict(d.get("flat_joint", d))
        fields = {k: float(fjd[k]) for k in ("E", "kappa", "sigma_c", "c", "phi_deg", "mu",
                                               "lam", "gap_factor") if k in fjd}
        fj = FlatJointMaterial(**{**fj.__dict__, **fields})
        lcd = dict(d.get("contact", {}))
        lc = ContactMaterial(**{k: float(lcd[k]) for k in ("E", "kappa", "mu") if k in lcd})
        rho = float(d.get("density", d.get("density_kg_m3",
                                            DENSITY_HARD if mid == HARD else DENSITY_SOFT)))
        out[mid] = dict(fj=fj, lc=lc, density=rho)
    return out


def load_library(path):
    """Load ``BPM.nc`` (the bpm package's format); ConfigError (one line) if it is not one."""
    return Library(open_netcdf(path, "bpm"), path)


# --------------------------------------------------------------------- synthetic stand-in
def _polygon(rng, size, aspect):
    """Random convex polygon (8-11 vertices on a jittered ellipse), size = longest axis."""
    n = int(rng.integers(8, 12))
    ang = np.sort(rng.uniform(0, 2 * np.pi, n))
    a, b = 0.5 * size, 0.5 * size / aspect
    rad = rng.uniform(0.85, 1.0, n)
    pts = np.column_stack([a * rad * np.cos(ang), b * rad * np.sin(ang)])
    return pts[ConvexHull(pts).vertices]


def _inside(pts, poly, margin):
    """Points at least ``margin`` inside the convex counter-clockwise polygon."""
    ok = np.ones(len(pts), bool)
    for p, q in zip(poly, np.roll(poly, -1, axis=0)):
        e = q - p
        nrm = np.array([e[1], -e[0]]) / np.hypot(*e)    # outward for CCW
        ok &= ((pts - p) @ nrm) <= -margin
    return ok


def synthetic_stone(rng, size, r0, material):
    """A stone: hexagonal lattice (spacing 2 r0) inside a random polygon, radii
    U(0.85, 1) r0 so every lattice neighbour is within the installation gap 0.4 r_small."""
    poly = _polygon(rng, size, rng.uniform(1.2, 2.0))
    span = poly.max()
    dx, dy = 2 * r0, np.sqrt(3) * r0
    gx, gy = np.meshgrid(np.arange(-span, span + dx, dx), np.arange(-span, span + dy, dy))
    gx = gx + (np.round(gy / dy) % 2) * r0
    pts = np.column_stack([gx.ravel(), gy.ravel()])
    pts = pts[_inside(pts, poly, 0.5 * r0)]
    if len(pts) < 3:
        pts = np.array([[-r0, 0.0], [r0, 0.0], [0.0, np.sqrt(3) * r0]])
    r = r0 * rng.uniform(0.85, 1.0, len(pts))
    pts = pts - pts.mean(axis=0)
    d = np.hypot(*(pts[:, None, :] - pts[None, :, :]).transpose(2, 0, 1))
    i, j = np.nonzero(np.triu(d < 2.01 * r0, 1))
    gap = d[i, j] - r[i] - r[j]
    area = 0.5 * abs(np.dot(poly[:, 0], np.roll(poly[:, 1], 1)) - np.dot(poly[:, 1], np.roll(poly[:, 0], 1)))
    return pts[:, 0], pts[:, 1], r, i, j, gap, area, material


def synthetic_library(n_stones=40, size=(0.03, 0.06), r0=0.004, soft_fraction=0.3, seed=0,
                      database="synthetic", thickness=1.0):
    """A BPM library in the bpm engineer's format with random polygon stones (for tests,
    the benchmark and until ``ballaststudy.bpm`` exists)."""
    rng = np.random.default_rng(seed)
    stones = [synthetic_stone(rng, rng.uniform(*size), r0,
                              SOFT if rng.random() < soft_fraction else HARD)
              for _ in range(n_stones)]
    cat = lambda k, dt: np.concatenate([s[k] for s in stones]).astype(dt)  # noqa: E731
    mats = {"hard": {"flat_joint": vars(FlatJointMaterial.hard()), "density": DENSITY_HARD},
            "soft": {"flat_joint": vars(FlatJointMaterial.soft()), "density": DENSITY_SOFT}}
    rho = np.array([DENSITY_HARD, DENSITY_SOFT])
    mat = np.array([s[7] for s in stones], np.int8)
    ball_area = np.array([np.sum(np.pi * s[2] ** 2) for s in stones])
    ds = xr.Dataset(
        {"form_index": ("stone", np.arange(n_stones, dtype=np.int32)),
         "material": ("stone", mat, {"flag_values": np.array([0, 1], np.int8),
                                     "flag_meanings": "hard soft"}),
         "ball_count": ("stone", np.array([len(s[0]) for s in stones], np.int32),
                        {"sample_dimension": "ball"}),
         "bond_count": ("stone", np.array([len(s[3]) for s in stones], np.int32),
                        {"sample_dimension": "bond"}),
         "profile_area": ("stone", np.array([s[6] for s in stones]), {"units": "m2"}),
         "ball_area": ("stone", ball_area, {"units": "m2"}),
         "mass_2d": ("stone", ball_area * rho[mat] * thickness, {"units": "kg"}),
         "ball_x": ("ball", cat(0, float), {"units": "m"}),
         "ball_y": ("ball", cat(1, float), {"units": "m"}),
         "ball_radius": ("ball", cat(2, float), {"units": "m"}),
         "bond_i": ("bond", cat(3, np.int32)),
         "bond_j": ("bond", cat(4, np.int32)),
         "bond_gap": ("bond", cat(5, float), {"units": "m"})},
        attrs={"database": database, "thickness_m": thickness,
               "materials_json": json.dumps(mats), "synthetic": 1})
    return ds
