"""A planted study cut into the parts a run in parts would have made (study/parts.py)."""

import numpy as np
import xarray as xr


def part_of(study, keep):
    """The study a part would have made: only the (database, case) where ``keep`` (a bool
    array over database x case) ran; databases with no case of the part left out."""
    keep = xr.DataArray(np.asarray(keep), dims=("database", "case"))
    ds = study.copy(deep=True)
    for name, v in ds.data_vars.items():
        if v.dims == ("database", "case", "cycle"):
            ds[name] = v.where(keep)
    ds["cycles_run"] = xr.where(keep, ds.cycles_run, 0).astype(np.int32)
    ds["assembly_stages_at_limit"] = xr.where(keep, ds.assembly_stages_at_limit, -1).astype(np.int32)
    ds["assembly_force_ratio"] = xr.where(keep, ds.assembly_force_ratio, np.nan)
    ds["seating"] = xr.where(keep, ds.seating, np.nan)
    return ds.isel(database=np.flatnonzero(keep.values.any(axis=1)))


def split(study, first_databases, shared_database):
    """Two parts: the first databases whole plus the first half of the shared database's cases;
    the second part the rest."""
    n_db, n_case = study.sizes["database"], study.sizes["case"]
    a = np.zeros((n_db, n_case), bool)
    a[:first_databases] = True
    a[shared_database, : n_case // 2] = True
    return part_of(study, a), part_of(study, ~a)
