"""A BPM library on disk (one netCDF per form database): building it from a forms file,
choosing the stones of a limited library, reading it back. Format: see ``ballaststudy.bpm``."""

import json

import numpy as np
import xarray as xr

from ..atomic import atomic_path
from ..schema import ConfigError
from ..forms.database import stone_profiles
from ..inputs import open_netcdf
from ..provenance import Recorder
from . import packing
from .build import build_stones
from .params import DENSITIES, MATERIAL_NAMES, materials_json

FORMS_VARIABLES = ("profile", "profile_vertex_count", "profile_area", "material", "a", "b", "c",
                   "sieve_group_lower", "sieve_group_upper", "mass")
LIBRARY_VARIABLES = ("form_index", "material", "ball_count", "bond_count", "ball_x", "ball_y",
                     "ball_radius", "bond_i", "bond_j", "bond_gap")


def open_forms(path):
    """The forms netCDF, loaded and checked; ConfigError (one line) if it is not one."""
    ds = open_netcdf(path, "forms", require=FORMS_VARIABLES)
    meanings = ds.material.attrs.get("flag_meanings", "")
    if meanings.split() != list(MATERIAL_NAMES):
        raise ConfigError(path, "material", f"flag_meanings {meanings!r}; expected 'hard soft'")
    if ds.sizes["stone"] == 0:
        raise ConfigError(path, None, "the form database has no stones")
    return ds


def select_stones(forms, max_stones, seed):
    """Indices (sorted) of the stones of a library limited to ``max_stones`` (None or >= the
    database: all). Stratified so that the library keeps the database's grading and rock
    mix: strata = (sieve group, material); each stratum gets its share of max_stones by
    stone count (largest-remainder rounding), and within a stratum
    the stones are taken by systematic sampling over the stratum sorted by mass (random
    start from ``seed``), so each stratum's mass distribution is kept too. A rig that draws
    stones uniformly from the library then sees the database's number (and so mass)
    distribution over the sieve groups."""
    n = forms.sizes["stone"]
    if max_stones is None or max_stones >= n:
        return np.arange(n)
    rng = np.random.default_rng([int(seed), 1])
    key = np.column_stack([forms.sieve_group_lower.values, forms.material.values])
    strata, label = np.unique(key, axis=0, return_inverse=True)
    label = label.ravel()
    counts = np.bincount(label, minlength=len(strata))
    quota = counts * max_stones / n
    take = np.floor(quota).astype(int)
    rest = max_stones - take.sum()
    take[np.argsort(-(quota - take), kind="stable")[:rest]] += 1
    mass = forms.mass.values
    out = []
    for s in range(len(strata)):
        if take[s] == 0:
            continue
        members = np.nonzero(label == s)[0]
        members = members[np.argsort(mass[members], kind="stable")]
        pos = ((np.arange(take[s]) + rng.random()) * len(members) / take[s]).astype(int)
        out.append(members[np.minimum(pos, len(members) - 1)])
    return np.sort(np.concatenate(out))


def _var(data, dims, units, long_name, **attrs):
    return (dims, data, {"units": units, "long_name": long_name, **attrs})


def to_dataset(forms, index, stones, params, seed, provenance_json):
    """The library as an xarray Dataset (format: module docstring of ballaststudy.bpm)."""
    t = params.thickness
    mat = np.array([s.material for s in stones], np.int8)
    ball_area = np.array([np.pi * float((s.r ** 2).sum()) for s in stones])
    rho = np.asarray(DENSITIES)[mat]
    # balls relative to their own area-weighted centroid; where that centroid is in the profile
    cen = np.array([[(s.x * s.r ** 2).sum(), (s.y * s.r ** 2).sum()] / (s.r ** 2).sum()
                    for s in stones])
    bx = np.concatenate([s.x - c[0] for s, c in zip(stones, cen)])
    by = np.concatenate([s.y - c[1] for s, c in zip(stones, cen)])
    nb = np.array([len(s.r) for s in stones], np.int32)
    nbd = np.array([len(s.bond_i) for s in stones], np.int32)
    f = forms.isel(stone=index)
    copied = lambda name: (("stone",), f[name].values, dict(f[name].attrs))  # noqa: E731
    col = lambda name: np.array([getattr(s, name) for s in stones])  # noqa: E731
    v = {
        "form_index": _var(np.asarray(index, np.int32), "stone", "1",
                           "index of the stone in the forms file"),
        "material": _var(mat, "stone", "1", "rock material",
                         flag_values=np.array([0, 1], np.int8), flag_meanings="hard soft"),
        "ball_count": _var(nb, "stone", "1", "balls per stone", sample_dimension="ball"),
        "bond_count": _var(nbd, "stone", "1", "flat joints per stone", sample_dimension="bond"),
        "profile_area": copied("profile_area"),
        "ball_area": _var(ball_area, "stone", "m2", "sum of the balls' disk areas pi r^2"),
        "mass_2d": _var(rho * ball_area * t, "stone", "kg",
                        "2D stone mass rho * sum(pi r^2) * t (PFC2D, per thickness t)"),
        "density": _var(rho, "stone", "kg m-3", "ball density (Table 4.2)"),
        "sieve_group_lower": copied("sieve_group_lower"),
        "sieve_group_upper": copied("sieve_group_upper"),
        "a": copied("a"), "b": copied("b"), "c": copied("c"),
        "min_radius_used": _var(np.array([s.r.min() for s in stones]), "stone", "m",
                                "smallest ball radius of the stone"),
        "max_radius_used": _var(np.array([s.r.max() for s in stones]), "stone", "m",
                                "largest ball radius of the stone"),
        "radius_scale": _var(col("scale"), "stone", "1",
                             "factor applied to the configured radius range for this stone"),
        "size_policy": _var(col("policy").astype(np.int8), "stone", "1",
                            "how the stone's ball size was chosen",
                            flag_values=np.array([0, 1, 2], np.int8),
                            flag_meanings=packing.POLICY_MEANINGS),
        "balls_removed": _var(col("removed_rattlers") + col("removed_outside"), "stone", "1",
                              "thrown-in balls deleted (not bonded to the stone's main cluster, "
                              "or centre outside the polygon)"),
        "force_ratio": _var(col("force_ratio"), "stone", "1",
                            "average force ratio at the end of the confined relaxation"),
        "relax_cycles": _var(col("relax_cycles").astype(np.int32), "stone", "1",
                             "confined relaxation cycles of the stone's batch"),
        "ball_centroid_x": _var(cen[:, 0], "stone", "m",
                                "balls' area centroid in the profile frame (profile centroid = 0)"),
        "ball_centroid_y": _var(cen[:, 1], "stone", "m",
                                "balls' area centroid in the profile frame (profile centroid = 0)"),
        "ball_x": _var(bx, "ball", "m", "ball centre x relative to the stone's ball centroid "
                       "(profile frame: x along the profile's a)"),
        "ball_y": _var(by, "ball", "m", "ball centre y relative to the stone's ball centroid"),
        "ball_radius": _var(np.concatenate([s.r for s in stones]), "ball", "m", "ball radius"),
        "bond_i": _var(np.concatenate([s.bond_i for s in stones]).astype(np.int32), "bond", "1",
                       "first ball of the flat joint, index local to the stone"),
        "bond_j": _var(np.concatenate([s.bond_j for s in stones]).astype(np.int32), "bond", "1",
                       "second ball of the flat joint, index local to the stone"),
        "bond_gap": _var(np.concatenate([s.bond_gap for s in stones]), "bond", "m",
                         "surface gap at the saved positions (negative = overlap); the flat "
                         "joint's bonded reference state (g_0 = 0)"),
    }
    ratio = col("force_ratio")
    attrs = {
        "title": f"bonded particle model library {forms.attrs.get('database', '')}",
        "database": forms.attrs.get("database", ""),
        "Conventions": "CF-1.8",
        "thickness_m": t,
        "radius_min_m": params.radius_min,
        "radius_max_m": params.radius_max,
        "radius_distribution": "uniform in [s*radius_min, s*radius_max], then scaled so that "
                               "sum(pi r^2) = (1 - porosity) * profile_area",
        "radius_scale_floor": params.radius_scale_floor,
        "min_balls": params.min_balls,
        "porosity": params.porosity,
        "materials_json": materials_json(params),
        "force_ratio_definition": "per stone: mean over its balls of |sum of contact, body and "
                                  "applied forces| / mean over its balls of the sum of their "
                                  "magnitudes (thesis 4.2.1); every stone below the limit",
        "force_ratio_limit": params.force_ratio_limit,
        "force_ratio_max": float(ratio.max()),
        "force_ratio_mean": float(ratio.mean()),
        "stones_not_converged": int((ratio >= params.force_ratio_limit).sum()),
        "relax_cycles_max": int(col("relax_cycles").max()),
        "relax_cycles_mean": float(col("relax_cycles").mean()),
        "bonded_cycles": params.bonded_cycles,
        "bonds_broken_in_relaxation": int(col("broken_elements").sum()),
        "max_bonded_displacement_m": float(col("max_bonded_move").max()),
        "residual_speed_max_m_s": float(col("residual_speed").max()),
        "residual_speed_note": "fastest ball when the confined relaxation stopped; velocities "
                               "are set to zero when the walls are removed",
        "damping": params.damping,
        "forms_stones": int(forms.sizes["stone"]),
        "max_stones": -1 if params.max_stones is None else int(params.max_stones),
        "stone_selection": "all" if len(index) == forms.sizes["stone"] else
                           "stratified by (sieve group, material), systematic by mass within",
        "bpm_params": json.dumps(params.as_dict(), sort_keys=True),
        "seed": int(seed),
        "provenance": provenance_json,
    }
    coords = {"stone": ("stone", np.arange(len(stones)), {"units": "1", "long_name": "stone index in the library"})}
    return xr.Dataset(v, coords=coords, attrs=attrs)


def build_library(forms_path, out_path, params, seed, config_files=(), progress=None):
    """Read a forms file, build its BPM library, write ``out_path`` (atomic) and its
    provenance record. Returns the Dataset written."""
    forms = open_forms(forms_path)
    recorder = Recorder("bpm build", inputs=[forms_path, *config_files],
                        params={"bpm": params.as_dict()}, seed=seed)
    index = select_stones(forms, params.max_stones, seed)
    profiles = stone_profiles(forms)
    try:
        stones = build_stones([profiles[i] for i in index], forms.material.values[index],
                              params, seed, ids=index, progress=progress)
    except ValueError as err:
        raise ConfigError(forms_path, "profile", str(err)) from None
    recorder.finish()
    ds = to_dataset(forms, index, stones, params, seed, recorder.json())
    with atomic_path(out_path) as tmp:
        ds.to_netcdf(tmp, engine="netcdf4")
    recorder.write_beside(out_path)
    return ds


def load_library(path):
    """The BPM library Dataset (loaded); ConfigError if missing or not a library."""
    return open_netcdf(path, "bpm", require=LIBRARY_VARIABLES)


def _offsets(counts):
    return np.concatenate([[0], np.cumsum(counts)])


def stone_balls(ds, k):
    """Stone ``k`` of a library: (x, y, r, bond_i, bond_j, material) with x, y relative to
    the stone's ball centroid (m) and bond indices local to the stone."""
    bo = _offsets(ds.ball_count.values)
    do = _offsets(ds.bond_count.values)
    b = slice(bo[k], bo[k + 1])
    d = slice(do[k], do[k + 1])
    return (ds.ball_x.values[b], ds.ball_y.values[b], ds.ball_radius.values[b],
            ds.bond_i.values[d], ds.bond_j.values[d], int(ds.material.values[k]))
