"""A measured cyclic test in: its conditions YAML (schema: schemas/measured.schema.yaml) and
its curve files -> one netCDF with dimension ``cycle`` (the measured N, the union of the
curves' points; NaN where a curve has none) and the rigs' variable names
(``axial_strain``, ``volumetric_strain``: compression positive, fractions; ``settlement``:
m), with the conditions, the source and the sign conventions as attributes.
"""
import json
from pathlib import Path

import numpy as np
import xarray as xr

from ..atomic import atomic_path
from ..schema import ConfigError, load_yaml, validate
from ..metrics.output import VARIABLES
from .curves import read_curve

CONDITIONS = ("confining_pressure_kPa", "deviator_min_kPa", "deviator_max_kPa", "load_min_kN",
              "load_max_kN", "frequency_Hz")
NEEDS = {"triaxial": ("confining_pressure_kPa", "deviator_max_kPa"),
         "biaxial": ("confining_pressure_kPa", "deviator_max_kPa"),
         "box": ("load_max_kN",)}


def load_conditions(path):
    """The validated conditions of one test, with the keys its rig needs."""
    cfg = validate(load_yaml(path), "measured", path)
    for key in NEEDS[cfg["rig"]]:
        if cfg.get(key) is None:
            raise ConfigError(path, key, f"required for a {cfg['rig']} test")
    for low, high in (("deviator_min_kPa", "deviator_max_kPa"), ("load_min_kN", "load_max_kN")):
        if cfg.get(low) is not None and cfg.get(high) is not None and not cfg[low] < cfg[high]:
            raise ConfigError(path, low, f"{cfg[low]:g}; allowed: below {high} ({cfg[high]:g})")
    seen = set()
    for k, c in enumerate(cfg["curves"]):
        strain = c["quantity"] != "settlement"
        if strain != (c["units"] in ("1", "%")):
            raise ConfigError(path, f"curves[{k}].units", f"{c['units']!r} is not a unit of "
                              f"{c['quantity']} (strains: '1' or '%'; settlement: 'm' or 'mm')")
        if c["quantity"] in seen:
            raise ConfigError(path, f"curves[{k}].quantity", f"{c['quantity']} given twice")
        seen.add(c["quantity"])
    return cfg


def measured_test_name(path):
    """A measured test's name from its netCDF or conditions YAML: its folder and stem
    (sun_et_al_16/p30_q230_f10)."""
    path = Path(path)
    return f"{path.parent.name}/{path.stem}"


def curve_path(conditions_file, name, data_dir=None):
    """A curve file beside the YAML, else in ``data_dir``."""
    here = Path(conditions_file).parent / name
    if here.is_file() or data_dir is None:
        return here
    return Path(data_dir) / name


def curve_files(conditions_file, data_dir=None):
    cfg = load_conditions(conditions_file)
    return [curve_path(conditions_file, c["file"], data_dir) for c in cfg["curves"]]


def measured_dataset(conditions_file, data_dir=None):
    cfg = load_conditions(conditions_file)
    curves = {}
    for k, c in enumerate(cfg["curves"]):
        path = curve_path(conditions_file, c["file"], data_dir)
        if not path.is_file():
            raise ConfigError(conditions_file, f"curves[{k}].file",
                              f"{c['file']} not found beside it"
                              + (f" nor in {data_dir}" if data_dir else ""))
        curves[c["quantity"]] = (path, c, *read_curve(path, c["quantity"], c["units"], c["sign"]))
    cycle = np.unique(np.concatenate([n for _, _, n, _ in curves.values()]))
    data = {}
    for name, (path, c, n, v) in curves.items():
        full = np.full(cycle.size, np.nan)
        full[np.searchsorted(cycle, n)] = v
        units, long_name, _ = VARIABLES[name]
        data[name] = ("cycle", full, {
            "units": units, "long_name": long_name, "source_file": path.name,
            "source_units": c["units"], "source_sign": c["sign"],
            "sign_confirmed": int(c.get("sign_confirmed", True)),
            "comment": "measured (digitised) points only; NaN where this curve has none"})
    attrs = {"Conventions": "CF-1.8",
             "title": f"measured cyclic {cfg['rig']} test", "source": cfg["source"],
             "rig": cfg["rig"], "conditions_file": str(conditions_file),
             "conditions_assumed": int(cfg.get("conditions_assumed", False)),
             "sign_convention": "strains compression positive (fractions); settlement "
                                "downwards positive",
             "specimen_json": json.dumps(cfg.get("specimen", {})),
             "covariates_json": json.dumps(cfg.get("covariates", {}))}
    if cfg.get("note"):
        attrs["note"] = cfg["note"]
    for key in CONDITIONS:
        if cfg.get(key) is not None:
            attrs[key] = float(cfg[key])
    for name, cov in (cfg.get("covariates") or {}).items():
        attrs[f"covariate_{name}"] = float(cov["value"])
        attrs[f"covariate_{name}_units"] = cov["units"]
    return xr.Dataset(data, coords={"cycle": ("cycle", cycle, {
        "units": "1", "long_name": "load cycle number N as measured (digitised, not integer)"})},
        attrs=attrs)


def write_test(ds, out):
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(out) as tmp:
        ds.to_netcdf(tmp)


def import_test(conditions_file, out, data_dir=None):
    """Write the test's netCDF atomically; returns the dataset."""
    ds = measured_dataset(conditions_file, data_dir)
    write_test(ds, out)
    return ds
