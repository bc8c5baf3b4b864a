"""`ballaststudy measured compare`: the measured curves and K simulated ones on one cycle
axis (measured N and simulated N = k + 1), NaN where a curve has no point; a figure."""
import numpy as np
import xarray as xr

from ballaststudy.cli import main

from tests.netcdf_documented import assert_documented
from .test_import import write_test


def fake_case(path, strains, **attrs):
    n = len(strains)
    ds = xr.Dataset({"axial_strain": ("cycle", np.asarray(strains, float), {"units": "1"}),
                     "volumetric_strain": ("cycle", -np.asarray(strains, float), {"units": "1"})},
                    coords={"cycle": np.arange(n)}, attrs={"seed": 5, **attrs})
    ds.to_netcdf(path)
    return path


def test_measured_and_simulated_on_one_axis(tmp_path):
    d = tmp_path / "m"
    d.mkdir()
    conditions = write_test(d)                        # measured at N = 1, 10, 100, 1000
    measured = tmp_path / "measured.nc"
    assert main(["measured", "import", str(conditions), "--out", str(measured), "--quiet"]) == 0
    cases = [fake_case(tmp_path / "c0.nc", [0.001, 0.002, 0.003]),
             fake_case(tmp_path / "c1.nc", [0.004, 0.005])]
    out = tmp_path / "cmp.nc"
    assert main(["measured", "compare", str(measured), *map(str, cases), "--out", str(out),
                 "--quiet"]) == 0
    with xr.open_dataset(out) as ds:
        assert ds["cycle"].values.tolist() == [1, 2, 3, 10, 100, 1000]
        np.testing.assert_array_equal(ds["simulated_axial_strain"].values[0, :3], [0.001, 0.002, 0.003])
        np.testing.assert_array_equal(ds["simulated_axial_strain"].values[1, :2], [0.004, 0.005])
        assert np.isnan(ds["simulated_axial_strain"].values[1, 2:]).all()
        np.testing.assert_array_equal(ds["measured_axial_strain"].values[[0, 3, 4]], [0.01, 0.02, 0.03])
        assert np.isnan(ds["measured_axial_strain"].values[[1, 2, 5]]).all()
        assert ds.attrs["confining_pressure_kPa"] == 30 and ds.attrs["Conventions"]
        assert ds.attrs["stress_mapping"] == "none"        # cases that name none (or nothing)
        for v in ds.data_vars.values():
            assert v.attrs["units"] and v.attrs["long_name"]
    assert out.with_suffix(".png").stat().st_size > 1000


def test_a_box_metrics_file_is_refused(tmp_path, capsys):
    d = tmp_path / "m"
    d.mkdir()
    measured = tmp_path / "measured.nc"
    main(["measured", "import", str(write_test(d)), "--out", str(measured), "--quiet"])
    box = tmp_path / "box.nc"
    xr.Dataset({"settlement": ("cycle", [0.0])}).to_netcdf(box)
    assert main(["measured", "compare", str(measured), str(box), "--out",
                 str(tmp_path / "o.nc")]) == 2
    assert "box.nc: axial_strain: not a biaxial case" in capsys.readouterr().err
    assert not (tmp_path / "o.nc").exists()


def test_a_failed_case_is_kept_with_its_reason(tmp_path):
    """A specimen that failed in the first loading (no cycle rows) is a result: its curve is
    empty, its reason is in the comparison's attributes, the others are compared as usual."""
    d = tmp_path / "m"
    d.mkdir()
    measured = tmp_path / "measured.nc"
    main(["measured", "import", str(write_test(d)), "--out", str(measured), "--quiet"])
    failed = tmp_path / "failed.nc"
    xr.Dataset(coords={"cycle": np.arange(0)},
               attrs={"failed": 1, "failure": "the specimen failed in the first loading: x"}).to_netcdf(failed)
    ok = fake_case(tmp_path / "ok.nc", [0.001, 0.002])
    out = tmp_path / "cmp.nc"
    assert main(["measured", "compare", str(measured), str(failed), str(ok), "--out", str(out), "--quiet"]) == 0
    with xr.open_dataset(out) as ds:
        assert ds.attrs["simulated_failures"] == "case 0: the specimen failed in the first loading: x"
        assert np.isnan(ds["simulated_axial_strain"].values[0]).all()
        np.testing.assert_array_equal(ds["simulated_axial_strain"].values[1, :2], [0.001, 0.002])


def test_the_stress_mapping_of_the_cases_is_named(tmp_path):
    """Cases run under a stress mapping (scenario/mapping.py): the comparison carries its
    record - the lab's q and the q the 2D specimens were loaded at - and the figure says so."""
    d = tmp_path / "m"
    d.mkdir()
    measured = tmp_path / "measured.nc"
    main(["measured", "import", str(write_test(d)), "--out", str(measured), "--quiet"])
    record = {"stress_mapping": "strength_ratio", "stress_mapping_ratio": 0.5,
              "stress_mapping_deviator_min_kPa": 5.0, "stress_mapping_deviator_max_kPa": 100.0,
              "stress_mapping_lab_deviator_max_kPa": 200.0}
    case = fake_case(tmp_path / "c0.nc", [0.001, 0.002], **record)
    out = tmp_path / "cmp.nc"
    assert main(["measured", "compare", str(measured), str(case), "--out", str(out), "--quiet"]) == 0
    with xr.open_dataset(out) as ds:
        assert {k: ds.attrs[k] for k in record} == record
    assert out.with_suffix(".png").stat().st_size > 1000


def test_documented_netcdf_measured_compare(tmp_path):
    measured = tmp_path / "measured.nc"
    assert main(["measured", "import", str(write_test(tmp_path)), "--out", str(measured), "--quiet"]) == 0
    cases = [fake_case(tmp_path / f"c{k}.nc", [0.001, 0.002]) for k in range(2)]
    out = tmp_path / "cmp.nc"
    assert main(["measured", "compare", str(measured), *map(str, cases), "--out", str(out), "--quiet"]) == 0
    assert_documented(out, "measured_compare")
