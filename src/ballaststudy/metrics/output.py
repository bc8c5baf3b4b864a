"""metrics.nc: one row per loading cycle (dimension ``cycle``), one variable per
behaviour, each with ``units`` and ``long_name``; written atomically."""
import numpy as np
import xarray as xr

from ..atomic import atomic_path

# name: (units, long_name, dtype)
VARIABLES = {
    "settlement": ("m", "settlement: downward displacement of the loading ball at the settlement force on the loading branch, relative to cycle 0 (thesis 4.5.1)", "f8"),
    "displacement_at_peak": ("m", "downward displacement of the loading ball at the cycle's peak force, relative to its position at the settlement force in cycle 0", "f8"),
    "peak_force": ("N", "peak force on the loading ball in the cycle (per thickness t)", "f8"),
    "y_at_level": ("m", "vertical position of the loading ball at the settlement force on the loading branch", "f8"),
    "breakage_rate_tension": ("1", "breakage rate in tension BR_T = FJ_T / FJ_Total (eq. 4.6), cumulative, fraction", "f8"),
    "breakage_rate_shear": ("1", "breakage rate in shear BR_S = FJ_S / FJ_Total (eq. 4.7), cumulative, fraction", "f8"),
    "breakage_rate": ("1", "breakage rate BR = BR_T + BR_S (eq. 4.8), cumulative, fraction", "f8"),
    "broken_mass_share": ("1", "share of the stones' mass no longer in the largest piece of the stone it belonged to when loading began (either stone model; a rigid stone's fines count as broken), cumulative, fraction", "f8"),
    "breakages_per_cycle": ("1", "number of flat-joint breakages during the cycle", "i8"),
    "broken_tension": ("1", "flat-joint bonds broken in tension FJ_T, cumulative", "i8"),
    "broken_shear": ("1", "flat-joint bonds broken in shear FJ_S, cumulative", "i8"),
    "fpa_left": ("degree", "force propagation angle on the left FA_left, from the horizontal at the plate's bottom middle point", "f8"),
    "fpa_right": ("degree", "force propagation angle on the right FA_right, from the horizontal at the plate's bottom middle point", "f8"),
    "fpa": ("degree", "force propagation angle FA_averaged = (FA_right + FA_left) / 2 (eq. 4.9)", "f8"),
    "x90_left": ("m", "distance left of the plate's middle collecting 90 % of the left bottom force", "f8"),
    "x90_right": ("m", "distance right of the plate's middle collecting 90 % of the right bottom force", "f8"),
    "depth": ("m", "depth from the plate's bottom middle point to the container bottom", "f8"),
    "void_ratio": ("1", "void ratio VR = A_void / A_total below the plate, stones as solid (eq. 4.10; = porosity n)", "f8"),
    "void_ratio_e": ("1", "soil-mechanics void ratio e = A_void / A_solid below the plate, stones as solid", "f8"),
    "void_ratio_balls": ("1", "A_void / A_total below the plate with the balls' disks as solid (intra-stone pores as void)", "f8"),
    "n_fragments": ("1", "number of fragments (stones and their broken pieces)", "i8"),
    "mean_coordination": ("1", "mean particle coordination number over all fragments", "f8"),
    "ghost_particles": ("1", "number of ghost particles (coordination number <= 2, container and shoulder excluded)", "i8"),
    "excluded_container": ("1", "fragments touching the container (excluded from ghost particles)", "i8"),
    "excluded_shoulder": ("1", "fragments in the shoulder area (excluded from ghost particles)", "i8"),
    # triaxial / biaxial tests (measured and simulated)
    "axial_strain": ("1", "permanent axial strain since the start of cyclic loading, compression positive", "f8"),
    "volumetric_strain": ("1", "permanent volumetric strain since the start of cyclic loading, compression positive (2D: area strain)", "f8"),
}


def display_scale(name):
    """(factor, unit) to plot a variable in: lengths in mm, fractions in %."""
    return (1e3, "mm") if VARIABLES[name][0] == "m" else (100.0, "%")


def metrics_dataset(rows, attrs=None):
    """Dataset with dimension ``cycle`` from a list of ``compute_cycle`` results (cycle k =
    rows[k]); the variables the rows give (one table for every rig). Unknown keys raise;
    a cycle that lacks one is filled with NaN / -1."""
    n = len(rows)
    given = {k for r in rows for k in r}
    unknown = sorted(given - set(VARIABLES))
    if unknown:
        raise KeyError(f"no units/long_name for {unknown}; add them to metrics.output.VARIABLES")
    data = {}
    for name, (units, long_name, dtype) in VARIABLES.items():
        if name not in given:
            continue
        fill = -1 if dtype == "i8" else np.nan
        v = np.array([r.get(name, fill) for r in rows], dtype=dtype).reshape(n)
        data[name] = xr.Variable("cycle", v, {"units": units, "long_name": long_name})
    ds = xr.Dataset(data, coords={"cycle": ("cycle", np.arange(n), {"units": "1", "long_name": "loading cycle"})})
    ds.attrs.update({"title": "box-test behaviours per loading cycle (Wang 2018, 4.5.1)"})
    ds.attrs.update(attrs or {})
    return ds


def write_metrics(path, rows_or_dataset, attrs=None):
    """Write metrics.nc atomically (temp + rename); returns the path."""
    ds = rows_or_dataset if isinstance(rows_or_dataset, xr.Dataset) else metrics_dataset(rows_or_dataset, attrs)
    bad = [name for name, v in ds.variables.items()
           if "units" not in v.attrs or "long_name" not in v.attrs]
    if bad:
        raise ValueError(f"variables lacking units or long_name: {bad}")
    with atomic_path(path) as tmp:
        ds.to_netcdf(tmp, engine="netcdf4")
    return path


def read_metrics(path):
    """metrics.nc as a loaded xarray Dataset (file closed)."""
    with xr.open_dataset(path, engine="netcdf4") as ds:
        return ds.load()
