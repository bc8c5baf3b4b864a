"""The BPM library reader against the bpm format (synthetic libraries)."""
import json

import numpy as np
import pytest

from ballaststudy.config import ConfigError
from ballaststudy.rig.library import LibraryError, Library, load_library, synthetic_library


def test_synthetic_library_format(tmp_path):
    ds = synthetic_library(5, r0=0.006, seed=1)
    assert ds["ball_count"].sum() == ds.sizes["ball"]
    assert ds["bond_count"].sum() == ds.sizes["bond"]
    assert ds["material"].dtype == np.int8 and ds["material"].attrs["flag_meanings"] == "hard soft"
    p = tmp_path / "BPM.nc"
    ds.to_netcdf(p)
    lib = load_library(p)
    assert len(lib) == 5 and lib.database == "synthetic"
    s = lib.stone(2)
    assert len(s.x) == lib.ball_count(2) and len(s.bond_i) == lib.bond_count(2)
    # ball centres are relative to the stone's ball centroid
    assert abs(s.x.mean()) < 1e-12 and abs(s.y.mean()) < 1e-12
    # local bond indices, within the stone
    assert s.bond_i.max() < len(s.x) and s.bond_j.max() < len(s.x)


def test_materials_json_parsed():
    ds = synthetic_library(2, r0=0.006, seed=1)
    raw = json.loads(ds.attrs["materials_json"])
    raw["soft"]["flat_joint"]["sigma_c"] = 1.0e5
    raw["hard"] = {"E": 3.0e9, "density": 3000.0}          # flat keys are accepted too
    ds.attrs["materials_json"] = json.dumps(raw)
    lib = Library(ds)
    assert lib.materials[1]["fj"].sigma_c == 1.0e5
    assert lib.materials[0]["fj"].E == 3.0e9 and lib.materials[0]["density"] == 3000.0


def test_bad_library_names_file_and_variable(tmp_path):
    ds = synthetic_library(2, r0=0.006, seed=1).drop_vars("bond_i")
    p = tmp_path / "bad.nc"
    ds.to_netcdf(p)
    with pytest.raises(ConfigError, match="bad.nc.*bond_i"):
        load_library(p)
    with pytest.raises(LibraryError, match="bad.nc: bond_i: variable missing"):
        Library(ds, p)
    with pytest.raises(ConfigError, match="file not found"):
        load_library(tmp_path / "missing.nc")
