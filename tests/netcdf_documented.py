"""Check a netCDF output the tests made against docs/reference/netcdf.md (or, with
BALLASTSTUDY_NETCDF_SAMPLES=DIR set, only copy it there for docs/_ext/netcdf_reference.py to
rewrite the page from)."""
import hashlib
import importlib.util
import os
import shutil
from pathlib import Path

import xarray as xr

_SPEC = importlib.util.spec_from_file_location(
    "netcdf_reference", Path(__file__).resolve().parents[1] / "docs" / "_ext" / "netcdf_reference.py")
reference = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(reference)

REWRITE = "rewrite the page: docs/_ext/netcdf_reference.py says how"


def assert_documented(path, kind):
    """Every coordinate and variable of ``path`` carries units and a long name, and the page
    lists it under ``kind`` with the same units; the file is CF. With
    BALLASTSTUDY_NETCDF_SAMPLES set it only copies the file there: a run that gathers the
    page's samples checks nothing, so a test that checks several files of a kind (one per
    variant) gathers them all in one run, before the page has their variables."""
    samples = os.environ.get("BALLASTSTUDY_NETCDF_SAMPLES")
    if samples:
        digest = hashlib.sha1(str(Path(path).resolve()).encode()).hexdigest()[:10]
        Path(samples).mkdir(parents=True, exist_ok=True)
        shutil.copyfile(path, Path(samples) / f"{kind}__{digest}.nc")
        return
    page = reference.documented()
    assert kind in page, f"{kind} has no section in {reference.PAGE}; {REWRITE}"
    with xr.open_dataset(path, decode_times=False) as ds:
        assert ds.attrs.get("Conventions", "").startswith("CF-"), f"{path}: no CF Conventions"
        for name, v in [*ds.coords.items(), *ds.data_vars.items()]:
            assert v.attrs.get("long_name"), f"{path}: {name} has no long_name"
            numeric = v.dtype.kind in "biufc"       # a label (a database's name) has no unit
            assert "units" in v.attrs or not numeric, f"{path}: {name} has no units"
            assert name in page[kind], f"{kind}: {name} not on the page; {REWRITE}"
            assert page[kind][name] == v.attrs.get("units", ""), \
                f"{kind}: {name} in {v.attrs.get('units')!r}, the page says {page[kind][name]!r}; {REWRITE}"
