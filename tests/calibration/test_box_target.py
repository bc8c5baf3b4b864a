"""A box test as calibration target: the box rig under the test's load bounds, settlement
compared. Two small box specimens (the rig tests' coarse stones and short stages), a
"measured" curve made by `case run --conditions --parameters` on one of them."""
import json

import numpy as np
import pytest
import xarray as xr
import yaml

from ballaststudy.cli import main
from ballaststudy.config import ConfigError
from ballaststudy.rig.params import RigParams
from ..biaxial_fast import FAST_LOADING
from ..netcdf_documented import assert_documented
from ..shipped import shipped_config

ASSEMBLY = dict(drop_max_steps=200000, tamping_steps=8000, relax_steps=2000, fill_area_ratio=0.7)
LOADING = dict(static_window_steps=1000, static_max_windows=200, servo_velocity_m_s=0.1,
               checkpoint_every=1, snapshot_every=1)
CYCLES = 4
PLANTED_MU = 0.9


def _box_conditions(path, load_min_kN=10.0, load_max_kN=40.0):
    path.write_text(yaml.safe_dump(dict(
        source="planted", rig="box", load_min_kN=load_min_kN, load_max_kN=load_max_kN,
        curves=[dict(file="s.dat", quantity="settlement", units="m", sign="compression_positive")])))
    return path


def test_box_takes_the_test_loads():
    """Load bounds as given; preloads and settlement force scaled to the cycle's mean load,
    so the thesis' loads (15-45 kN) leave 4.2.3's protocol (10, 20, 30 kN; 30 kN) as it is."""
    p = RigParams()
    p.take_conditions({"load_min_kN": 15.0, "load_max_kN": 45.0})
    assert p.static_loads_kN == [10.0, 20.0, 30.0] and p.settlement_force_kN == 30.0
    p.take_conditions({"load_min_kN": 10.0, "load_max_kN": 40.0})
    assert (p.cyclic_min_kN, p.cyclic_max_kN, p.settlement_force_kN) == (10.0, 40.0, 25.0)
    assert np.allclose(p.static_loads_kN, [25 / 3, 50 / 3, 25.0])
    with pytest.raises(ValueError, match="minimum must be below the maximum"):
        RigParams().take_conditions({"load_max_kN": 12.0})          # the config's 15 kN min


def test_reversed_load_bounds_are_refused(tmp_path):
    from ballaststudy.measured.importer import load_conditions
    path = _box_conditions(tmp_path / "box.yaml", load_min_kN=50.0, load_max_kN=40.0)
    with pytest.raises(ConfigError, match="load_min_kN: 50; allowed: below load_max_kN"):
        load_conditions(path)


@pytest.fixture(scope="module")
def box_target(tmp_path_factory, small_library):
    """(folder, config, conditions, measured.nc, [specimens], planted metrics.nc)."""
    from ballaststudy.measured.importer import import_test
    d = tmp_path_factory.mktemp("box_target")
    def change(cfg):
        cfg["rig"]["box"]["assembly"].update(ASSEMBLY)
        cfg["rig"]["box"]["loading"].update(LOADING)
        cfg["calibration"].update(quantity="settlement", cases=2, cycles=CYCLES, initial_design=3,
                                  iterations=0, parameters={"mu": {"min": 0.4, "max": 1.2}},
                                  measurement_sd=1e-6)
    config = shipped_config(d / "config.yaml", change)
    specimens = [d / f"s{k}.nc" for k in range(2)]
    for k, s in enumerate(specimens):
        assert main(["case", "assemble", str(small_library), "--case", str(k), "--rig", "box",
                     "--config", str(config), "--out", str(s), "--quiet"]) == 0
    conditions = _box_conditions(d / "box.yaml")
    (d / "planted.yaml").write_text(yaml.safe_dump({"parameters": {"mu": PLANTED_MU}}))
    planted = d / "planted" / "metrics.nc"
    assert main(["case", "run", str(specimens[0]), "--cycles", str(CYCLES), "--conditions", str(conditions),
                 "--parameters", str(d / "planted.yaml"), "--config", str(config), "--out", str(planted),
                 "--no-vtk", "--no-figures", "--quiet"]) == 0
    with xr.open_dataset(planted) as ds:
        curve = ds["settlement"].values
    (d / "s.dat").write_text("".join(f"{k + 1}, {float(v)!r}\n" for k, v in enumerate(curve)))
    measured = d / "measured.nc"
    import_test(conditions, measured)
    return d, config, conditions, measured, specimens, planted


def test_calibration_runs_the_model_case_run_runs(box_target):
    """The Evaluator's case at the planted mu is `case run --conditions --parameters`'s,
    to the last bit; the test's peak load is what the cycles reach (the conditions act)."""
    from ballaststudy.calibration.evaluate import Evaluator
    d, config, conditions, measured, specimens, planted = box_target
    evaluate = Evaluator(["mu"], specimens, [(conditions, np.arange(1.0, CYCLES + 1))], config,
                         CYCLES, "settlement", d / "eval")
    at = evaluate(np.array([[PLANTED_MU]]))[0]
    with xr.open_dataset(planted) as ds:
        planted_curve, peak = ds["settlement"].values, ds["peak_force"].values
        assert json.loads(ds.attrs["rig_params_json"])["cyclic_max_kN"] == 40.0
    assert evaluate.kind == "box"
    assert np.array_equal(evaluate.sets[0]["curves"][0, 0], planted_curve)
    assert np.array_equal(at[0], planted_curve)             # N = 1..CYCLES: the cycles themselves
    assert not np.array_equal(evaluate.sets[0]["curves"][0, 1], planted_curve)   # the other specimen
    assert np.allclose(peak, 40e3, rtol=0.01), peak
    assert planted_curve[-1] > 0                            # it settles


@pytest.fixture(scope="module")
def box_calibration(box_target, tmp_path_factory):
    """The output folder of `ballaststudy calibrate` on the box target."""
    d, config, conditions, measured, specimens, planted = box_target
    out = tmp_path_factory.mktemp("box_calibration") / "cal"
    assert main(["calibrate", str(measured), "--conditions", str(conditions), "--specimens", *map(str, specimens),
                 "--config", str(config), "--quiet", "--out-dir", str(out), "--jobs", "2"]) == 0
    return out


@pytest.fixture(scope="module")
def triaxial_calibration(tmp_path_factory, small_library):
    """The output folder of `ballaststudy calibrate` on a planted triaxial test, at the least
    it runs: one small biaxial specimen given for both cases, 3 sets of 3 cycles (~6 s)."""
    from ballaststudy.measured.importer import import_test
    d = tmp_path_factory.mktemp("triaxial_calibration")
    def change(cfg):
        cfg["rig"]["biaxial"]["loading"].update(FAST_LOADING)
        cfg["calibration"].update(quantity="axial_strain", cases=2, cycles=3, initial_design=2, iterations=0,
                                  parameters={"mu": {"min": 0.4, "max": 1.2}}, posterior_samples=1024)
    config = shipped_config(d / "config.yaml", change)
    specimen = d / "s.nc"
    assert main(["case", "assemble", str(small_library), "--case", "0", "--rig", "biaxial", "--width-m", "0.12",
                 "--height-m", "0.24", "--config", str(config), "--out", str(specimen), "--quiet"]) == 0
    conditions = d / "t.yaml"
    conditions.write_text(yaml.safe_dump(dict(
        source="planted", rig="triaxial", confining_pressure_kPa=30.0, deviator_min_kPa=10.0, deviator_max_kPa=50.0,
        curves=[dict(file="t.dat", quantity="axial_strain", units="1", sign="compression_positive")])))
    (d / "t.dat").write_text("1, 0.001\n1.7, 0.0013\n2.5, 0.0015\n")
    import_test(conditions, d / "t.nc")
    out = d / "cal"
    assert main(["calibrate", str(d / "t.nc"), "--conditions", str(conditions), "--specimens", str(specimen),
                 str(specimen), "--config", str(config), "--quiet", "--out-dir", str(out), "--jobs", "2"]) == 0
    return out


def test_calibrate_a_box_test_end_to_end(box_calibration):
    """`ballaststudy calibrate` on box specimens: every output, settlement in metres, the
    case count; a strain quantity or a triaxial test with box specimens: one line, exit 2."""
    out = box_calibration
    doc = yaml.safe_load((out / "calibrated.yaml").read_text())
    assert doc["quantity"] == "settlement" and doc["dem_cases"] == 2 * 4     # 3 + the calibrated set
    assert 0.4 <= doc["parameters"]["mu"] <= 1.2 and np.isfinite(doc["rmse_after"])
    assert doc["stress_mapping"] == "none"              # a box test is loaded as measured
    with xr.open_dataset(out / "evaluations.nc") as ds:
        assert ds["settlement"].attrs["units"] == "m" and ds.sizes["case"] == 2
        assert ds["settlement"].shape == (4, 1, 2, CYCLES)
    for name in ("posterior.nc", "curves.png", "corner.png", "summary.md"):
        assert (out / name).is_file()
    with xr.open_dataset(out / "posterior.nc") as ds:
        assert ds.attrs["stress_mapping"] == "none"


def test_box_specimens_refuse_other_tests(box_target, tmp_path, capsys):
    """A strain curve of a box test, or a triaxial test, with box specimens: one line, exit
    2, nothing written."""
    from ballaststudy.measured.importer import import_test
    d, config, conditions, measured, specimens, planted = box_target
    (tmp_path / "s.dat").write_text((d / "s.dat").read_text())
    strain_cfg = tmp_path / "strain.yaml"
    cfg = yaml.safe_load(config.read_text())
    cfg["calibration"]["quantity"] = "axial_strain"
    strain_cfg.write_text(yaml.safe_dump(cfg))
    curve = dict(file="s.dat", units="1", sign="compression_positive", quantity="axial_strain")
    tests = {"box_strain": dict(source="planted", rig="box", load_max_kN=40.0, curves=[curve]),
             "triaxial": dict(source="planted", rig="triaxial", confining_pressure_kPa=30.0,
                              deviator_max_kPa=60.0, curves=[curve])}
    for name, doc in tests.items():
        (tmp_path / f"{name}.yaml").write_text(yaml.safe_dump(doc))
        import_test(tmp_path / f"{name}.yaml", tmp_path / f"{name}.nc")
    for name, key in (("box_strain", "calibration.quantity: axial_strain: the box rig does not record it"),
                      ("triaxial", "rig: triaxial: the specimens are box specimens")):
        out = tmp_path / "out"
        assert main(["calibrate", str(tmp_path / f"{name}.nc"), "--conditions", str(tmp_path / f"{name}.yaml"),
                     "--specimens", *map(str, specimens), "--config", str(strain_cfg), "--out-dir", str(out),
                     "--quiet"]) == 2
        line = capsys.readouterr().err.strip()
        assert "\n" not in line and key in line, line
        assert not out.exists() or not any(out.rglob("*"))


def test_documented_netcdf_evaluations(box_calibration, triaxial_calibration):
    for out in (box_calibration, triaxial_calibration):
        assert_documented(out / "evaluations.nc", "evaluations")


def test_documented_netcdf_posterior(box_calibration):
    assert_documented(box_calibration / "posterior.nc", "posterior")
