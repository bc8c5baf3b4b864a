"""Aggregation of the per-case metrics into one self-describing dataset, `results/study.nc`
(design.md "study"; thesis ch. 5: 15 databases x 10 cases x 1000 cycles).

Layout: dims (database, case, cycle); one variable per behaviour (`BEHAVIOURS`), padded with
NaN where a case ran fewer cycles or a (database, case) has no metrics file; `cycles_run`
says how many cycles each case has. Database-level coordinates come from the form database
(generated values, `forms.validate.validation_row`): group, percent passing at every grading
sieve, SD (eq. 3.3), percent passing 22.4 mm (Table 5-1), SI, FI, LI and the mean size
(mass-weighted mean of the middle dimension b, i.e. of the sieve-relevant size).
"""

import json
import math
import re
from pathlib import Path

import numpy as np
import xarray as xr

from ..atomic import atomic_path
from ..schema import ConfigError
from ..forms.validate import validation_row
from ..inputs import open_netcdf
from ..rig.deposition import EQUILIBRIUM_FORCE_RATIO
from ..metrics.output import VARIABLES
from ..provenance import Recorder
from ..standards import GRADING_SIEVES_MM

# name -> (canonical units, long name). Same names as in the rig's metrics.nc.
# the behaviours of study.nc: units and long names are metrics.nc's (one table per variable)
BEHAVIOURS = {name: VARIABLES[name][:2] for name in (
    "settlement", "breakage_rate_tension", "breakage_rate_shear", "breakage_rate", "fpa_left",
    "fpa_right", "fpa", "void_ratio", "ghost_particles", "mean_coordination",
    "broken_tension", "broken_shear", "breakages_per_cycle")}    # the counts: Fig. 5-3

# accepted input units -> factor to the canonical unit
_UNIT_FACTORS = {
    "m": {"m": 1.0, "metre": 1.0, "meter": 1.0, "mm": 1e-3},
    "1": {"1": 1.0, "": 1.0, "-": 1.0, "%": 0.01, "percent": 0.01, "count": 1.0},
    "degree": {"degree": 1.0, "degrees": 1.0, "deg": 1.0, "rad": 180.0 / math.pi, "radian": 180.0 / math.pi},
}

MEAN_SIZE_DEFINITION = "mass-weighted mean of the middle stone dimension b: sum(m_i b_i) / sum(m_i)"
_NAME = re.compile(r"G_(\d+)-(\d+)$")


def database_order_key(name):
    """G_<group>-<index> by group then index; other names (e.g. box_test) after, by name."""
    m = _NAME.match(str(name))
    return (0, int(m[1]), int(m[2]), "") if m else (1, 0, 0, str(name))


def database_group(name, forms_ds=None):
    """Group of a database: the forms file's `group` attribute if present, else <g> of
    G_<g>-<i>, else the name itself (a group of its own, like box_test)."""
    if forms_ds is not None and "group" in forms_ds.attrs:
        return str(forms_ds.attrs["group"])
    m = _NAME.match(str(name))
    return m[1] if m else str(name)


def _factor(path, name, units):
    canon = BEHAVIOURS[name][0]
    table = _UNIT_FACTORS[canon]
    key = str(units).strip()
    if key not in table:
        raise ConfigError(path, f"{name}.units",
                          f"{units!r} not understood; allowed: {', '.join(repr(u) for u in table)}")
    return table[key]


def _case_series(path, ds):
    """{name: (values in canonical units, attrs)} and the cycle labels of one metrics.nc."""
    if "cycle" not in ds.dims:
        raise ConfigError(path, "cycle", f"no dimension 'cycle' (dims: {', '.join(map(str, ds.dims)) or 'none'})")
    cycles = ds["cycle"].values if "cycle" in ds.coords else np.arange(ds.sizes["cycle"])
    if len(np.unique(cycles)) != len(cycles):
        raise ConfigError(path, "cycle", "cycle labels repeat")
    out, extra = {}, {}
    for name in BEHAVIOURS:
        if name not in ds.data_vars:
            raise ConfigError(path, name, f"variable missing; required: {', '.join(BEHAVIOURS)}")
        v = ds[name]
        if v.dims != ("cycle",):
            raise ConfigError(path, name, f"dims {v.dims}, expected ('cycle',)")
        f = _factor(path, name, v.attrs.get("units", BEHAVIOURS[name][0]))
        out[name] = v.values.astype(float) * f
    for name, v in ds.data_vars.items():
        # carried along unchanged when self-describing and per cycle
        if name not in BEHAVIOURS and v.dims == ("cycle",) and "units" in v.attrs and "long_name" in v.attrs \
                and v.dtype.kind in "fiub":
            extra[name] = (v.values.astype(float), {"units": v.attrs["units"], "long_name": v.attrs["long_name"]})
    return np.asarray(cycles), out, extra


def _stone_model(metrics):
    """The one stone model of the cases (a metrics file without the attribute is from
    before the switch: bonded); ConfigError naming the first case of another."""
    models = {key: ds.attrs.get("stone_model", "bonded") for key, (_, ds) in metrics.items()}
    first = next(iter(models.values()))
    for key, m in models.items():
        if m != first:
            raise ConfigError(metrics[key][0], "stone_model", f"{m!r}, but other cases ran {first!r}; "
                              "allowed: one stone model in a study")
    return first


def _stages_at_limit(ds):
    """How many of the case's assembly stages stopped at their step limit (the rig layout
    its metrics file carries); -1 where the file does not record it."""
    layout = json.loads(ds.attrs.get("rig_layout_json", "{}"))
    return len(layout["stages_at_limit"]) if "stages_at_limit" in layout else -1


def _seating(ds):
    """The loading ball's descent from the start of the static pre-loading (its first
    sample) to the settlement force in cycle 0: what the settlement, counted from cycle 0,
    leaves out; NaN where the file lacks either."""
    if "sample_y" not in ds or "y_at_level" not in ds or not ds.sizes.get("sample") or not ds.sizes.get("cycle"):
        return np.nan
    return float(ds["sample_y"].values[0] - ds["y_at_level"].values[0])


def _force_ratio_at_start(ds):
    """The stones' force ratio when the case's loading began (its rig layout); NaN where the
    file does not record it."""
    layout = json.loads(ds.attrs.get("rig_layout_json", "{}"))
    return float(layout.get("stage_end", {}).get("relax", {}).get("force_ratio", np.nan))


def database_coordinates(forms_ds):
    """Database-level numbers from a form database (generated values, via validation_row)."""
    row = validation_row(forms_ds)
    b, mass = forms_ds.b.values.astype(float), forms_ds.mass.values.astype(float)
    return {
        "percent_passing": np.array([row[f"passing_{s:g}mm_pct"] for s in GRADING_SIEVES_MM]),
        "size_diversity": row["size_diversity"],
        "percent_passing_22_4mm": row["passing_22.4mm_pct"],
        "shape_index": row["si_pct"],
        "flakiness_index": row["fi_pct"],
        "particle_length_index": row["li_pct"],
        "mean_size": float(np.sum(mass * b) / np.sum(mass)),
    }


_COORD_ATTRS = {
    "group": ("1", "database group (thesis Table 3-1: 1 mean size, 2 size distribution, 3 shape)"),
    "percent_passing": ("percent", "generated percent passing by mass at each grading sieve"),
    "size_diversity": ("percent", "size diversity SD = sum_i |f(i) - 50| of the generated grading (eq. 3.3)"),
    "percent_passing_22_4mm": ("percent", "generated percent passing 22.4 mm by mass (Table 5-1)"),
    "shape_index": ("percent", "generated shape index SI (non-cubic stones, a/c > 3, by mass)"),
    "flakiness_index": ("percent", "generated flakiness index FI (flat stones by mass)"),
    "particle_length_index": ("percent", "generated particle length index LI (stones a >= 100 mm by mass)"),
    "mean_size": ("m", "mean stone size: " + MEAN_SIZE_DEFINITION),
}


def case_label_key(v):
    """Sort key of a case label: integer labels in order, then the others by name."""
    return (0, v, "") if isinstance(v, (int, np.integer)) else (1, 0, str(v))


def build_study(metrics, forms, groups=None):
    """The study Dataset from loaded inputs.

    metrics: {(database, case): (path, Dataset)}; forms: {database: (path, Dataset)};
    groups: optional {database: group} overriding `database_group`.
    """
    if not metrics:
        raise ConfigError("study aggregate", None, "no metrics files given")
    dbs = sorted({db for db, _ in metrics}, key=database_order_key)
    missing = [db for db in dbs if db not in forms]
    if missing:
        raise ConfigError("study aggregate", "forms", f"no form database for {', '.join(missing)}")
    cases = sorted({c for _, c in metrics}, key=case_label_key)
    if not all(isinstance(c, (int, np.integer)) for c in cases):
        cases = [str(c) for c in cases]
    series = {key: _case_series(path, ds) for key, (path, ds) in metrics.items()}
    model = _stone_model(metrics)
    cycles = np.unique(np.concatenate([s[0] for s in series.values()]))
    extra_names = sorted(set.intersection(*(set(s[2]) for s in series.values())))
    shape = (len(dbs), len(cases), len(cycles))
    arrays = {n: np.full(shape, np.nan) for n in list(BEHAVIOURS) + extra_names}
    run = np.zeros(shape[:2], dtype=np.int32)
    at_limit = np.full(shape[:2], -1, dtype=np.int32)
    force_ratio = np.full(shape[:2], np.nan)
    seating = np.full(shape[:2], np.nan)
    for (db, case), (cyc, vals, extra) in series.items():
        i, j = dbs.index(db), cases.index(case if not isinstance(cases[0], str) else str(case))
        at_limit[i, j] = _stages_at_limit(metrics[(db, case)][1])
        force_ratio[i, j] = _force_ratio_at_start(metrics[(db, case)][1])
        seating[i, j] = _seating(metrics[(db, case)][1])
        k = np.searchsorted(cycles, cyc)
        for n in BEHAVIOURS:
            arrays[n][i, j, k] = vals[n]
        for n in extra_names:
            arrays[n][i, j, k] = extra[n][0]
        run[i, j] = len(cyc)
    dims = ("database", "case", "cycle")
    data = {n: (dims, arrays[n], {"units": BEHAVIOURS[n][0], "long_name": BEHAVIOURS[n][1]}) for n in BEHAVIOURS}
    first_extra = next(iter(series.values()))[2]
    for n in extra_names:
        data[n] = (dims, arrays[n], dict(first_extra[n][1]))
    data["cycles_run"] = (("database", "case"), run,
                          {"units": "1", "long_name": "loading cycles in the case's metrics file (0: no file)"})
    data["assembly_stages_at_limit"] = (("database", "case"), at_limit, {
        "units": "1", "long_name": "assembly stages of the case that stopped at their step limit, not "
                                   "at their criterion (its assembled.nc names them; -1: not recorded)"})
    data["assembly_force_ratio"] = (("database", "case"), force_ratio, {
        "units": "1", "long_name": "the stones' force ratio when loading began: mean |unbalanced force| / mean "
                                   "sum of force magnitudes, PFC's equilibrium measure (thesis 4.2.1: at rest below "
                                   f"{EQUILIBRIUM_FORCE_RATIO:g}; NaN: not recorded)"})
    data["seating"] = (("database", "case"), seating, {
        "units": "m", "long_name": "downward displacement of the loading ball from the start of the static "
                                   "pre-loading to the settlement force in cycle 0: the seating the settlement leaves "
                                   "out (thesis 4.5.1 reads the pressing ball's displacement; NaN: not recorded)"})
    dbc = {db: database_coordinates(forms[db][1]) for db in dbs}
    coords = {
        "database": ("database", np.array(dbs, dtype=object), {"long_name": "form database (Table 3-1)"}),
        "case": ("case", np.array(cases, dtype=object if isinstance(cases[0], str) else np.int64),
                 {"long_name": "simulation case (random selection and packing of stones)",
                  **({} if isinstance(cases[0], str) else {"units": "1"})}),
        "cycle": ("cycle", cycles, {"units": "1", "long_name": "loading cycle"}),
        "sieve": ("sieve", np.array(GRADING_SIEVES_MM) * 1e-3, {"units": "m", "long_name": "square-mesh sieve size"}),
        "group": ("database", np.array([str((groups or {}).get(db, database_group(db, forms[db][1]))) for db in dbs],
                                       dtype=object), {"long_name": _COORD_ATTRS["group"][1]}),
    }
    for name, (units, long_name) in _COORD_ATTRS.items():
        if name == "group":
            continue
        dim = ("database", "sieve") if name == "percent_passing" else "database"
        coords[name] = (dim, np.array([dbc[db][name] for db in dbs], dtype=float),
                        {"units": units, "long_name": long_name})
    attrs = {
        "title": "ballast form distribution study: behaviour per database, case and loading cycle",
        "Conventions": "CF-1.8",
        "mean_size_definition": MEAN_SIZE_DEFINITION,
        "database_coordinates_source": "generated values of the form database (forms.validate.validation_row)",
        "padding": "NaN where a case ran fewer cycles or has no metrics file; see cycles_run",
        "stone_model": model,
    }
    return xr.Dataset(data, coords=coords, attrs=attrs)


def aggregate(metrics_paths, forms_paths, out, groups=None):
    """Write `out` (e.g. results/study.nc) from {(database, case): metrics.nc} and
    {database: forms.nc}; returns the path. Provenance (inputs with sha256) goes into the
    global attribute `provenance` and beside the file as `<out>.prov.json`."""
    metrics_paths = {k: Path(p) for k, p in metrics_paths.items()}
    forms_paths = {k: Path(p) for k, p in forms_paths.items()}
    metrics = {k: (p, open_netcdf(p, "metrics")) for k, p in metrics_paths.items()}
    used = {db for db, _ in metrics_paths}
    forms = {db: (p, open_netcdf(p, "forms")) for db, p in forms_paths.items() if db in used}
    inputs = sorted(map(str, metrics_paths.values())) + sorted(str(p) for p, _ in forms.values())
    recorder = Recorder("study aggregate", inputs=inputs,
                        params={"metrics": {f"{db}/{c}": str(p) for (db, c), p in sorted(
                                    metrics_paths.items(), key=lambda kv: (str(kv[0][0]), str(kv[0][1])))},
                                "forms": {db: str(p) for db, (p, _) in sorted(forms.items())},
                                "groups": groups or {}})
    ds = build_study(metrics, forms, groups)
    recorder.finish()
    ds.attrs["provenance"] = recorder.json()
    out = Path(out)
    with atomic_path(out) as tmp:
        ds.to_netcdf(tmp, engine="netcdf4", encoding=netcdf_encoding(ds))
    recorder.write_beside(out)
    return out


def netcdf_encoding(ds):
    """Lossless compression of the per-cycle variables: a thesis-scale study.nc (16 x 10 x
    1001 values a behaviour) is kept in the repository in parts (study/parts.py)."""
    return {n: {"zlib": True, "complevel": 4, "shuffle": True}
            for n, v in ds.data_vars.items() if v.dtype.kind == "f"}


def identify_metrics(path):
    """(database, case) of a metrics.nc: its global attributes `database` and `case` if
    present, else the path .../<database>/<case>/metrics.nc (case 'case_03' or '3' -> 3)."""
    path = Path(path)
    ds = open_netcdf(path, "metrics")
    db = ds.attrs.get("database", path.parent.parent.name if path.parent.parent.name else None)
    case = ds.attrs.get("case", path.parent.name)
    if not db or case in (None, ""):
        raise ConfigError(path, None, "cannot tell database and case: no attributes 'database'/'case' "
                                      "and the path is not .../<database>/<case>/metrics.nc")
    m = re.fullmatch(r"(?:case[_-]?)?(\d+)", str(case))
    return str(db), int(m[1]) if m else str(case)
