"""The parametric study's statistics on planted cases where the answer is known: a planted
slope recovered within its 95 % interval, the thesis' finding marked holds / does not hold
/ not decidable as the planted relation says (a negative control without any relation), the
SRC of a noiseless line is +-1, far below the thesis' scale the mark says so; the design
runs' Sobol indices rank the parameter the planted output depends on."""
import json

import numpy as np
import pytest
import xarray as xr
import yaml

from ballaststudy.calibration.parametric import (design_sets, findings, parametric_dataset,
                                                 sensitivity_table, slope_table)
from ballaststudy.cli import main

from ..netcdf_documented import assert_documented


def _write(path, final, cycles, k, values):
    ds = xr.Dataset({"settlement": ("cycle", np.linspace(0, final, cycles)),
                     "breakage_rate": ("cycle", np.full(cycles, 0.01))},
                    coords={"cycle": np.arange(cycles)},
                    attrs={"seed": k, "material_parameters_json": json.dumps(values)})
    ds.to_netcdf(path)
    return path


def _plant(tmp_path, name, values, settle, cases=5, cycles=100, seed=0):
    """metrics.nc per (value, case): settlement rising linearly over the cycles to
    settle(value) + noise at the last cycle."""
    rng = np.random.default_rng(seed)
    return [_write(tmp_path / f"{name}_{v:g}_{k}.nc", settle(v) + rng.normal(0, 1e-4), cycles, k, {name: v})
            for v in values for k in range(cases)]


def _plant_design(tmp_path, settle, sets=8, cases=2, cycles=100, seed=0):
    """The sensitivity design's runs: settle(F, mu) + noise."""
    rng = np.random.default_rng(seed)
    sets_ = design_sets({"F_str_co": (2.0, 5.0), "mu": (0.5, 0.8)}, sets, seed)
    return [_write(tmp_path / f"design{j}_{k}.nc", settle(v["F_str_co"], v["mu"]) + rng.normal(0, 1e-5),
                   cycles, k, v) for j, v in enumerate(sets_) for k in range(cases)]


def _row(table, name, output="settlement"):
    return next(r for r in table if r["parameter"] == name and r["output"] == output)


def test_planted_slopes_and_findings(tmp_path):
    paths = (_plant(tmp_path, "F_str_co", [2.0, 2.75, 3.5, 4.25, 5.0], lambda f: 0.010 - 0.001 * f)
             + _plant(tmp_path, "mu", [0.5, 0.6, 0.7, 0.8], lambda m: 0.004, seed=1))
    ds = parametric_dataset(paths)
    table = slope_table(ds)
    f = _row(table, "F_str_co")
    assert f["ci_low"] <= -0.001 <= f["ci_high"] and f["ci_high"] < 0 and f["p_value"] < 1e-6
    assert f["src"] == pytest.approx(-1.0, abs=0.02)          # nearly noiseless line
    mu = _row(table, "mu")
    assert mu["ci_low"] < 0 < mu["ci_high"] and abs(mu["src"]) < 0.6        # nothing planted
    marks = {m["finding"].split(" (")[0]: m["mark"] for m in findings(table, cases=5, cycles=100)}
    assert marks == {"settlement rises as F_str-co falls": "holds",
                     "settlement rises as mu falls": "not decidable"}
    small = findings(table, cases=2, cycles=3)
    assert [m["mark"] for m in small] == ["not decidable at this scale", "not decidable"]
    assert small[0]["mark_by_rule"] == "holds"


def test_the_opposite_relation_does_not_hold(tmp_path):
    ds = parametric_dataset(_plant(tmp_path, "mu", [0.5, 0.6, 0.7, 0.8], lambda m: 0.001 + 0.01 * m))
    marks = findings(slope_table(ds), cases=5, cycles=100)
    assert [m["mark"] for m in marks] == ["does not hold"]


def test_design_ranks_the_planted_parameter(tmp_path):
    """Settlement planted on F_str_co alone: its Sobol index ~1, mu's ~0 (negative control);
    the one-at-a-time statistics ignore the design runs."""
    paths = (_plant(tmp_path, "F_str_co", [2.0, 3.5, 5.0], lambda f: 0.01 - 0.001 * f, cases=2)
             + _plant_design(tmp_path, lambda f, m: 0.01 - 0.001 * f))
    ds = parametric_dataset(paths)
    assert sorted(set(ds["parameter"].values)) == ["F_str_co", "design"]
    rows = {r["parameter"]: r for r in sensitivity_table(ds) if r["output"] == "settlement"}
    assert rows["F_str_co"]["S1"] > 0.9 and rows["mu"]["ST"] < 0.05 and rows["mu"]["sets"] == 8
    assert [r["parameter"] for r in slope_table(ds)] == ["F_str_co", "F_str_co"]


def test_setting_cli(tmp_path, capsys):
    out = tmp_path / "s.yaml"
    assert main(["parametric", "setting", "F_str_co", "2.5", "mu", "0.6", "--out", str(out)]) == 0
    assert yaml.safe_load(out.read_text()) == {"parameters": {"F_str_co": 2.5, "mu": 0.6}}
    for argv, key in ((["nu", "2"], "parameters: nu: unknown"), (["mu"], "NAME VALUE pairs"),
                      (["mu", "-1"], "parameters.mu: '-1' is not allowed; allowed: a number >= 0"),
                      (["mu_r", "2"], "parameters.mu_r: '2' is not allowed; allowed: a number >= 0 and <= 1"),
                      (["F_str_co", "x"], "parameters.F_str_co: 'x' is not allowed")):
        assert main(["parametric", "setting", *argv, "--out", str(tmp_path / "bad.yaml")]) == 2
        line = capsys.readouterr().err.strip()
        assert "\n" not in line and key in line, line
        assert not (tmp_path / "bad.yaml").exists()


def _report(tmp_path):
    """`parametric report` on small planted settings and design runs: its folder."""
    paths = (_plant(tmp_path, "F_str_co", [2.0, 3.5, 5.0], lambda f: 0.01 - 0.001 * f, cases=2, cycles=3)
             + _plant(tmp_path, "mu", [0.5, 0.7], lambda m: 0.004, cases=2, cycles=3)
             + _plant_design(tmp_path, lambda f, m: 0.01 - 0.001 * f + 0.01 * m, sets=4, cycles=3))
    out = tmp_path / "out"
    assert main(["parametric", "report", *map(str, paths), "--out-dir", str(out), "--quiet"]) == 0
    return out


def test_report_cli_writes_every_file(tmp_path):
    out = _report(tmp_path)
    for name in ("parametric.nc", "report.md", "F_str_co.png", "mu.png", "report.md.prov.json"):
        assert (out / name).is_file(), name
    text = (out / "report.md").read_text()
    assert "not decidable at this scale" in text and "| F_str_co | settlement |" in text
    assert "## Global sensitivity (Sobol indices)" in text and "| settlement | mu |" in text
    with xr.open_dataset(out / "parametric.nc") as ds:
        assert ds.sizes["run"] == 18 and ds["settlement"].attrs["units"] == "m"
        assert len(json.loads(ds.attrs["sobol_indices_json"])) == 4


def test_documented_netcdf_parametric(tmp_path):
    assert_documented(_report(tmp_path) / "parametric.nc", "parametric")
