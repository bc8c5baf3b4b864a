"""study.nc: dims, coordinates with hand values, units and long names everywhere, NaN
padding of short or missing cases, unit conversion, provenance, and clear errors."""

import argparse
import json

import numpy as np
import pytest
import xarray as xr

from ballaststudy.config import ConfigError
from ballaststudy.provenance import sha256_file
from ballaststudy.study import BEHAVIOURS, aggregate
from ballaststudy.study.cli import register

from ..netcdf_documented import assert_documented

# 8 stones, b in mm, mass in kg: percent passing at 80 ... 8 mm = 100 80 70 60 50 40 30 20
B_MM = [70, 55, 45, 35, 25, 20, 12, 5]
MASS = [2, 1, 1, 1, 1, 1, 1, 2]
PP = [100, 80, 70, 60, 50, 40, 30, 20]
SD = 50 + 30 + 20 + 10 + 0 + 10 + 20 + 30          # eq. 3.3 by hand: 170
MEAN_B_MM = (2 * 70 + 55 + 45 + 35 + 25 + 20 + 12 + 2 * 5) / 10   # 34.2 mm
# stone 0 is long (a = 105 mm >= 100, 2 kg of 10 -> LI 20 %); stone 2 is non-cubic (a/c = 4) and flat
A_MM = [105, 66, 54, 42, 30, 24, 14.4, 6]
C_MM = [56, 44, 13.5, 28, 20, 16, 9.6, 4]


def _series(n, start=0.0):
    t = np.arange(n, dtype=float)
    return {"settlement": 1e-4 * t + start, "ghost_particles": 5 + t, "void_ratio": 0.3 - 1e-3 * t,
            "fpa": 55 + 0 * t, "fpa_left": 54 + 0 * t, "fpa_right": 56 + 0 * t, "breakage_rate": 1e-4 * t,
            "mean_coordination": 3 + 0 * t}


@pytest.fixture
def inputs(tmp_path, synth):
    forms = {}
    for name in ("G_1-1", "box_test"):
        p = tmp_path / f"{name}.nc"
        synth.forms_dataset(name, B_MM, MASS, A_MM, C_MM).to_netcdf(p)
        forms[name] = p
    metrics = {}
    cycles = {("G_1-1", 0): 6, ("G_1-1", 1): 4, ("box_test", 0): 6}   # (box_test, 1) absent
    for (db, case), n in cycles.items():
        p = tmp_path / db / f"case_{case:02d}" / "metrics.nc"
        p.parent.mkdir(parents=True)
        synth.metrics_dataset(_series(n)).to_netcdf(p)
        metrics[(db, case)] = p
    return metrics, forms


def test_layout_coordinates_and_padding(tmp_path, inputs):
    metrics, forms = inputs
    out = aggregate(metrics, forms, tmp_path / "results" / "study.nc")
    with xr.open_dataset(out) as ds:
        ds = ds.load()
    assert dict(ds.sizes) == {"database": 2, "case": 2, "cycle": 6, "sieve": 8}
    assert list(ds.database.values) == ["G_1-1", "box_test"]
    for name in BEHAVIOURS:
        assert ds[name].dims == ("database", "case", "cycle")
    for name, v in ds.variables.items():
        if v.dtype.kind in "fiu" and name not in ("case",):
            assert v.attrs.get("units") is not None and v.attrs.get("long_name"), f"{name} lacks units/long_name"
        else:
            assert v.attrs.get("long_name"), f"{name} lacks long_name"
    g = ds.sel(database="G_1-1")
    np.testing.assert_allclose(g.percent_passing.values, PP)
    assert g.size_diversity.item() == pytest.approx(SD)
    assert g.percent_passing_22_4mm.item() == pytest.approx(40.0)
    assert g.mean_size.item() == pytest.approx(MEAN_B_MM * 1e-3)
    assert g.shape_index.item() == pytest.approx(10.0)
    assert g.particle_length_index.item() == pytest.approx(20.0)
    assert g.flakiness_index.item() == pytest.approx(10.0)
    assert g.group.item() == "1" and ds.sel(database="box_test").group.item() == "box_test"
    # short case: 4 cycles of data, NaN after; missing case: all NaN
    s = g.settlement.sel(case=1).values
    np.testing.assert_allclose(s[:4], 1e-4 * np.arange(4))
    assert np.isnan(s[4:]).all()
    assert np.isnan(ds.settlement.sel(database="box_test", case=1)).all()
    assert ds.cycles_run.sel(database="G_1-1").values.tolist() == [6, 4]
    assert ds.cycles_run.sel(database="box_test").values.tolist() == [6, 0]
    prov = json.loads(ds.attrs["provenance"])
    assert prov["inputs"][str(metrics[("G_1-1", 1)])] == sha256_file(metrics[("G_1-1", 1)])
    assert prov["inputs"][str(forms["box_test"])] == sha256_file(forms["box_test"])
    assert (out.parent / "study.nc.prov.json").is_file()


def test_assembly_stages_at_limit_are_counted_and_reported(tmp_path, synth, inputs):
    """The rig layout a case's metrics file carries says how many assembly stages stopped
    at their step limit; a file without the record (or no file) gives -1, and the
    report's extent line counts the cases that had one."""
    from ballaststudy.study.report import extent_line
    metrics, forms = inputs
    for key, limits in ((("G_1-1", 0), ["settle after tamping: ...", "plate: ..."]),
                        (("G_1-1", 1), [])):
        with xr.open_dataset(metrics[key]) as f:
            ds = f.load()
        ds.attrs["rig_layout_json"] = json.dumps({"seed": 1, "stages_at_limit": limits})
        ds.to_netcdf(metrics[key])
    ds = xr.open_dataset(aggregate(metrics, forms, tmp_path / "study.nc")).load()
    got = ds.assembly_stages_at_limit
    assert got.sel(database="G_1-1").values.tolist() == [2, 0]
    assert got.sel(database="box_test").values.tolist() == [-1, -1]
    assert "1 of 2 cases were assembled with a stage stopped at its step limit" in extent_line(ds)


def test_force_ratio_when_loading_began_is_kept_and_reported(tmp_path, synth, inputs):
    """The stones' force ratio at the end of the assembly (the layout's stage_end) per case;
    NaN where a file does not record it; the report counts the cases not at rest."""
    from ballaststudy.study.report import extent_line
    metrics, forms = inputs
    for key, ratio in ((("G_1-1", 0), 0.003), (("G_1-1", 1), 0.02)):
        with xr.open_dataset(metrics[key]) as f:
            ds = f.load()
        ds.attrs["rig_layout_json"] = json.dumps({"stages_at_limit": [], "stage_end": {"relax": {"force_ratio": ratio}}})
        ds.to_netcdf(metrics[key])
    ds = xr.open_dataset(aggregate(metrics, forms, tmp_path / "study.nc")).load()
    assert ds.assembly_force_ratio.sel(database="G_1-1").values.tolist() == [0.003, 0.02]
    assert np.isnan(ds.assembly_force_ratio.sel(database="box_test").values).all()
    assert "largest 0.02; 1 of 2 cases at or above the thesis' equilibrium limit 0.008" in extent_line(ds)


def test_the_seating_before_cycle_0_is_kept(tmp_path, synth, inputs):
    """The loading ball's descent from its first sample (static pre-loading) to cycle 0's
    settlement force; NaN for a file without the time series."""
    metrics, forms = inputs
    with xr.open_dataset(metrics[("G_1-1", 0)]) as f:
        ds = f.load()
    ds["y_at_level"] = ("cycle", 0.249 - 1e-5 * np.arange(ds.sizes["cycle"]), {"units": "m"})
    ds["sample_y"] = ("sample", np.array([0.2513, 0.2502, 0.249]), {"units": "m"})
    ds.to_netcdf(metrics[("G_1-1", 0)])
    ds = xr.open_dataset(aggregate(metrics, forms, tmp_path / "study.nc")).load()
    assert float(ds.seating.sel(database="G_1-1", case=0)) == pytest.approx(2.3e-3, rel=1e-9)
    assert np.isnan(ds.seating.sel(database="G_1-1", case=1))


def test_units_are_converted(tmp_path, synth, inputs):
    metrics, forms = inputs
    p = tmp_path / "mm.nc"
    series = _series(6)
    series["settlement"] = series["settlement"] * 1e3
    series["fpa"] = np.deg2rad(series["fpa"])
    synth.metrics_dataset(series, units={"settlement": "mm", "fpa": "rad", "void_ratio": "%"}).to_netcdf(p)
    metrics[("box_test", 1)] = p
    ds = xr.open_dataset(aggregate(metrics, forms, tmp_path / "study.nc")).load()
    got = ds.sel(database="box_test", case=1)
    np.testing.assert_allclose(got.settlement.values, 1e-4 * np.arange(6))
    np.testing.assert_allclose(got.fpa.values, 55.0)
    np.testing.assert_allclose(got.void_ratio.values, (0.3 - 1e-3 * np.arange(6)) / 100)


def _run(argv):
    p = argparse.ArgumentParser()
    register(p.add_subparsers(dest="stage", required=True))
    args = p.parse_args(argv)
    args.func(args)


def test_cli_aggregate_identifies_cases_from_paths(tmp_path, inputs, capsys):
    metrics, forms = inputs
    out = tmp_path / "study.nc"
    _run(["study", "aggregate", *map(str, metrics.values()), "--forms", *map(str, forms.values()),
          "--out", str(out), "--group", "box_test=4"])
    ds = xr.open_dataset(out).load()
    assert ds.case.values.tolist() == [0, 1]
    assert ds.sel(database="box_test").group.item() == "4"
    assert "wrote" in capsys.readouterr().out


@pytest.mark.parametrize("damage, key", [
    (lambda ds: ds.drop_vars("void_ratio"), "void_ratio"),
    (lambda ds: ds.assign(settlement=ds.settlement.assign_attrs(units="furlong")), "settlement.units"),
    (lambda ds: ds.rename({"cycle": "step"}), "cycle"),
])
def test_bad_metrics_give_clear_error_and_no_output(tmp_path, synth, inputs, damage, key):
    metrics, forms = inputs
    bad = tmp_path / "bad.nc"
    damage(synth.metrics_dataset(_series(5))).to_netcdf(bad)
    metrics[("box_test", 1)] = bad
    out = tmp_path / "out" / "study.nc"
    with pytest.raises(ConfigError) as err:
        aggregate(metrics, forms, out)
    assert "bad.nc" in str(err.value) and key in str(err.value)
    assert not out.exists()
    leftovers = list(out.parent.glob("*")) if out.parent.exists() else []
    assert not leftovers, f"partial output left behind: {leftovers}"


def test_missing_forms_database_is_an_error(tmp_path, inputs):
    metrics, forms = inputs
    del forms["box_test"]
    with pytest.raises(ConfigError, match="box_test"):
        aggregate(metrics, forms, tmp_path / "study.nc")
    assert not (tmp_path / "study.nc").exists()


def test_generated_form_database(tmp_path, synth, small_database):
    """A database made by the real generator: coordinates equal the generated numbers."""
    nc, forms_ds, _ = small_database
    metrics = tmp_path / "m.nc"
    synth.metrics_dataset(_series(3)).to_netcdf(metrics)
    ds = xr.open_dataset(aggregate({("small", 0): metrics}, {"small": nc}, tmp_path / "study.nc")).load()
    b, m = forms_ds.b.values, forms_ds.mass.values
    pp = np.array([100 * m[b * 1e3 < s].sum() / m.sum() for s in (80, 63, 50, 40, 31.5, 22.4, 16, 8)])
    got = ds.sel(database="small")
    np.testing.assert_allclose(got.percent_passing.values, pp)
    assert got.size_diversity.item() == pytest.approx(np.abs(pp - 50).sum())
    assert got.percent_passing_22_4mm.item() == pytest.approx(pp[5])
    assert got.mean_size.item() == pytest.approx((m * b).sum() / m.sum())
    assert got.shape_index.item() == pytest.approx(100 * m[forms_ds.is_non_cubic.values == 1].sum() / m.sum())
    assert got.group.item() == "small"


def test_the_stone_model_is_named_and_one_per_study(tmp_path, inputs):
    """study.nc names the cases' stone model (files from before the switch: bonded); cases
    of two models in one study are refused, naming the file and the key."""
    metrics, forms = inputs
    with xr.open_dataset(aggregate(metrics, forms, tmp_path / "a.nc")) as ds:
        assert ds.attrs["stone_model"] == "bonded"
    for key in metrics:
        with xr.open_dataset(metrics[key]) as f:
            ds = f.load()
        ds.attrs["stone_model"] = "rigid"
        ds.to_netcdf(metrics[key])
    with xr.open_dataset(aggregate(metrics, forms, tmp_path / "b.nc")) as ds:
        assert ds.attrs["stone_model"] == "rigid"
    with xr.open_dataset(metrics[("box_test", 0)]) as f:
        ds = f.load()
    ds.attrs["stone_model"] = "bonded"
    ds.to_netcdf(metrics[("box_test", 0)])
    with pytest.raises(ConfigError, match="stone_model.*one stone model in a study"):
        aggregate(metrics, forms, tmp_path / "c.nc")
    assert not (tmp_path / "c.nc").exists()


def test_documented_netcdf_study(tmp_path, inputs):
    metrics, forms = inputs
    assert_documented(aggregate(metrics, forms, tmp_path / "study.nc"), "study")
