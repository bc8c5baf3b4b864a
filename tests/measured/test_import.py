"""`ballaststudy measured import`: curves sorted by N, converted to SI and compression
positive, put on one cycle axis (NaN where a curve has no point), conditions and sign
conventions kept as attributes; every bad input one line naming file (and line or key),
exit 2, nothing written. Synthetic files only (planted values); the shipped tests are
imported as a whole when their data folder is present."""
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import yaml

from ballaststudy.cli import main
from ballaststudy.measured import measured_dataset

from tests.netcdf_documented import assert_documented

ROOT = Path(__file__).resolve().parents[2]


def write_test(d, axial="1, 0.01\n100, 0.03\n10, 0.02\n", vol="1, 0.5\n1000, -0.2\n",
               **conditions):
    (d / "ax.dat").write_text(axial)
    (d / "vol.csv").write_text(vol)
    cfg = dict(source="planted", rig="triaxial", confining_pressure_kPa=30,
               deviator_max_kPa=230, frequency_Hz=5,
               covariates={"VCI": {"value": 50, "units": "%"}},
               curves=[dict(file="ax.dat", quantity="axial_strain", units="1",
                            sign="compression_positive"),
                       dict(file="vol.csv", quantity="volumetric_strain", units="%",
                            sign="dilation_positive", sign_confirmed=False)])
    cfg.update(conditions)
    path = d / "test.yaml"
    path.write_text(yaml.safe_dump(cfg))
    return path


def test_curves_sorted_converted_on_one_axis(tmp_path):
    ds = measured_dataset(write_test(tmp_path))
    assert ds["cycle"].values.tolist() == [1, 10, 100, 1000]
    np.testing.assert_array_equal(ds["axial_strain"].values[:3], [0.01, 0.02, 0.03])
    assert np.isnan(ds["axial_strain"].values[3])
    # percent -> fraction, dilation positive -> compression positive
    np.testing.assert_allclose(ds["volumetric_strain"].values[[0, 3]], [-0.005, 0.002])
    assert np.isnan(ds["volumetric_strain"].values[1:3]).all()
    assert ds["volumetric_strain"].attrs["sign_confirmed"] == 0
    for v in ds.variables.values():
        assert v.attrs["units"] and v.attrs["long_name"]
    assert ds.attrs["Conventions"].startswith("CF")
    assert ds.attrs["confining_pressure_kPa"] == 30 and ds.attrs["covariate_VCI"] == 50
    assert ds.attrs["covariate_VCI_units"] == "%"


def test_repeated_point_is_accepted(tmp_path):
    ds = measured_dataset(write_test(tmp_path, axial="1, 0.01\n5, 0.02\n5, 0.02\n"))
    assert np.count_nonzero(np.isfinite(ds["axial_strain"].values)) == 2


@pytest.mark.parametrize("axial, where, what", [
    ("1, 0.01\n2, x\n", "ax.dat:2", "expected two numbers"),
    ("1, 0.01\n-3, 0.02\n", "ax.dat:2", "negative cycle"),
    ("1, 0.01\n2, 1.5\n", "ax.dat:2", "> 1"),
    ("1, 0.01\n5, 0.02\n2, 0.0\n5, 0.03\n", "ax.dat:2", "not a function of N: line 4"),
    ("", "ax.dat", "no data lines"),
])
def test_bad_curve_names_file_and_line(tmp_path, capsys, axial, where, what):
    path = write_test(tmp_path, axial=axial)
    out = tmp_path / "out.nc"
    assert main(["measured", "import", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and where in err[0] and what in err[0], err
    assert not out.exists()


@pytest.mark.parametrize("change, key", [
    (lambda c: c["curves"][0].pop("units"), "curves[0]"),
    (lambda c: c.update(rig="shear_box"), "rig"),
    (lambda c: c.pop("confining_pressure_kPa"), "confining_pressure_kPa"),
    (lambda c: c["curves"][0].update(units="mm"), "curves[0].units"),
    (lambda c: c["curves"][1].update(quantity="axial_strain"), "curves[1].quantity"),
    (lambda c: c["curves"][0].update(file="missing.dat"), "curves[0].file"),
])
def test_bad_conditions_name_file_and_key(tmp_path, capsys, change, key):
    path = write_test(tmp_path)
    cfg = yaml.safe_load(path.read_text())
    change(cfg)
    path.write_text(yaml.safe_dump(cfg))
    out = tmp_path / "out.nc"
    assert main(["measured", "import", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert f"test.yaml: {key}" in err and "\n" not in err, err
    assert not out.exists()


def test_data_dir_lookup_and_cli(tmp_path):
    data = tmp_path / "data"
    data.mkdir()
    path = write_test(data)
    conditions = tmp_path / "conditions"
    conditions.mkdir()
    moved = conditions / "test.yaml"
    moved.write_text(path.read_text())       # the YAML elsewhere, the curves in data/
    out = tmp_path / "out.nc"
    assert main(["measured", "import", str(moved), "--data-dir", str(data), "--out", str(out),
                 "--quiet"]) == 0
    with xr.open_dataset(out) as ds:
        assert ds.sizes["cycle"] == 4
    assert out.with_name("out.nc.prov.json").is_file()


def test_every_shipped_test_imports(measured_data_dir):
    """Each YAML of config/measured imports with both strains on a sorted cycle axis (no
    values are checked: the data are not ours to restate)."""
    tests = sorted((ROOT / "config" / "measured").rglob("*.yaml"))
    assert len(tests) == len(list(measured_data_dir.rglob("axial*")))
    for path in tests:
        ds = measured_dataset(path, measured_data_dir)
        assert set(ds.data_vars) == {"axial_strain", "volumetric_strain"}, path
        assert np.all(np.diff(ds["cycle"].values) > 0), path
        assert np.isfinite(ds["axial_strain"].values).sum() >= 3, path


def test_documented_netcdf_measured(tmp_path):
    out = tmp_path / "test.nc"
    assert main(["measured", "import", str(write_test(tmp_path)), "--out", str(out), "--quiet"]) == 0
    assert_documented(out, "measured")
