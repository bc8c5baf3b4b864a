"""The long-term horizon by measured error (loop/horizon.py): the hardening-log law's
formula and recovery; the table chooses the law that made planted curves, whichever it is
(hardening_log or Sato: the ranking is not wired to one law); a curve enters an N_fit
only with a point beyond it and enough points up to it; a law that cannot be fitted counts
as an infinite error; the loop's N_fit is the nearest at or beyond its horizon; and the
command writes horizon.nc/md/png from imported measured tests (N < 1 read as 1)."""
import numpy as np
import pytest
import xarray as xr

from ballaststudy.cli import main
from ballaststudy.loop.accumulation import LAWS, fit_law, hardening_log
from ballaststudy.loop.horizon import chosen_for, enters, horizon_table, measured_curve
from ..measured.test_import import write_test
from ..netcdf_documented import assert_documented

FAR = 5e5
GRID = np.geomspace(1.0, FAR, 40)            # a measured curve's cycle counts, log-spaced


def test_hardening_log_takes_its_documented_values():
    eps0, gamma, alpha, c = 0.01, 0.05, 0.02, 0.004
    law = (eps0, gamma, alpha, c)
    assert hardening_log(1.0, law) == pytest.approx(eps0)
    assert hardening_log(1.0 + 1.0 / alpha, law) == pytest.approx(
        eps0 + gamma * (1 - np.exp(-1)) + c * np.log(1.0 + 1.0 / alpha))
    assert hardening_log(1e6, law) - hardening_log(1e5, law) == pytest.approx(c * np.log(10.0))


def test_hardening_log_recovers_a_planted_curve_and_carries_it():
    planted = np.array([0.005, 0.06, 0.01, 0.003])
    seen = GRID[GRID <= 1e3]
    fit = fit_law("hardening_log", seen, hardening_log(seen, planted))
    np.testing.assert_allclose(fit.params, planted, rtol=1e-3)
    assert abs(hardening_log(FAR, fit.params) / hardening_log(FAR, planted) - 1) < 1e-3


def _curves(law, params, seed, noise=2e-4):
    rng = np.random.default_rng(seed)
    return {f"t{i}": (GRID, LAWS[law](GRID, p) + rng.normal(0.0, noise, GRID.size)) for i, p in enumerate(params)}


@pytest.mark.parametrize("truth, params", [
    ("hardening_log", [(0.005, 0.05 + 0.01 * i, 0.01, 0.002 + 0.001 * i) for i in range(6)]),
    ("sato", [(0.005, 0.05 + 0.01 * i, 0.01, 1e-6 * (1 + i)) for i in range(6)]),   # creep 5-30x noise by 1e3
])
def test_the_table_chooses_the_law_that_made_the_curves(truth, params):
    ds = horizon_table(_curves(truth, params, seed=3), [1e3, 1e4])
    assert list(ds["chosen_law"].values) == [truth, truth]
    assert (ds["curves_entered"].values == 6).all()
    median = ds["median_abs_error"]
    others = median.drop_sel(law=truth)
    assert (others > 2 * median.sel(law=truth)).all(), median.to_pandas()
    assert set(ds.data_vars) >= {"error", "predicted_last", "entered", "curves_fitted"}
    assert all("units" in ds[v].attrs for v in ds.data_vars if v != "chosen_law")


def test_which_curves_enter():
    short = GRID[GRID <= 800]                 # ends before N_fit 1e3
    assert not enters(short, 1e3) and enters(GRID, 1e3)
    # up to 1e3: 4 distinct points (as many as the 4-parameter laws have) do not enter, 5 do
    assert not enters(np.array([1.0, 1.0, 10.0, 100.0, 1e3, 1e5]), 1e3)
    assert enters(np.array([1.0, 5.0, 10.0, 100.0, 1e3, 1e5]), 1e3)
    ds = horizon_table({"short": (short, 0.01 + 0.001 * np.log(short)),
                        "long": (GRID, 0.01 + 0.001 * np.log(GRID))}, [1e3])
    assert ds["entered"].values[:, 0].tolist() == [0, 1]
    assert np.isnan(ds["error"].sel(test="short").values).all()
    assert ds["curves_entered"].values[0] == 1


def test_a_law_that_cannot_be_fitted_counts_as_infinite():
    """Strain 0 at N = 1 on 4 of 7 curves: the power law (a N^b) cannot pass through it, so its
    median |error| is infinite and it is not chosen, even though it made the other curves."""
    curves = {f"p{i}": (GRID, 0.01 * (1 + 0.1 * i) * GRID ** 0.1) for i in range(4)}
    for i in range(4):
        n, v = curves[f"p{i}"]
        curves[f"z{i}"] = (n, np.where(n == 1.0, 0.0, v))
    del curves["p3"]
    ds = horizon_table(curves, [1e3])
    power = ds.sel(law="power", fit_cycles=1e3)
    assert int(power["curves_fitted"]) == 3 and np.isinf(float(power["median_abs_error"]))
    assert ds["chosen_law"].values[0] != "power"


def test_the_loop_takes_the_nearest_n_fit_at_or_beyond_its_horizon():
    ds = horizon_table(_curves("hardening_log", [(0.005, 0.05, 0.01, 0.003)] * 2, seed=1), [1e3, 1e4])
    assert chosen_for(ds, 12).fit_cycles == 1e3 and chosen_for(ds, 1e3).fit_cycles == 1e3
    assert chosen_for(ds, 2e3).fit_cycles == 1e4 and chosen_for(ds, 1e5).fit_cycles == 1e4
    law = chosen_for(ds, 12)
    assert law.name == "hardening_log" and law.curves == 2
    assert law.stated_error == float(ds["stated_abs_error"].sel(law=law.name, fit_cycles=1e3))
    none = horizon_table({"short": (GRID[:5], GRID[:5] * 1e-3)}, [1e3])
    assert chosen_for(none, 12) is None


def _imported(tmp_path):
    """Two measured tests on a hardening-log law, imported: their files."""
    n = np.concatenate([[0.97], GRID[1:]])    # the first loading digitised left of N = 1
    v = hardening_log(np.maximum(n, 1.0), (0.005, 0.05, 0.01, 0.003))
    files = []
    for k in range(2):
        d = tmp_path / f"src{k}"
        d.mkdir()
        write_test(d, axial="".join(f"{a}, {b}\n" for a, b in zip(n, v * (1 + 0.1 * k))))
        files.append(tmp_path / "measured" / f"set{k}" / "t.nc")
        assert main(["measured", "import", str(d / "test.yaml"), "--out", str(files[-1]), "--quiet"]) == 0
    return files


def test_the_command_writes_the_table_from_measured_tests(tmp_path):
    files = _imported(tmp_path)
    n1, _ = measured_curve(files[0], "axial_strain")
    assert n1[0] == 1.0 and np.all(np.diff(n1) > 0)
    out = tmp_path / "horizon"
    assert main(["horizon", *map(str, files), "--out-dir", str(out), "--fit-cycles", "1000", "--quiet"]) == 0
    ds = xr.open_dataset(out / "horizon.nc")
    assert list(ds["test"].values) == ["set0/t", "set1/t"] and ds.attrs["Conventions"] == "CF-1.8"
    assert ds["chosen_law"].values[0] == "hardening_log"
    assert "hardening_log" in (out / "horizon.md").read_text() and (out / "horizon.png").stat().st_size > 0


def test_bad_fit_cycles_is_one_line(tmp_path, capsys):
    with pytest.raises(SystemExit) as stop:
        main(["horizon", str(tmp_path / "x.nc"), "--out-dir", str(tmp_path / "h"), "--fit-cycles", "0"])
    err = capsys.readouterr().err
    assert stop.value.code == 2
    assert "--fit-cycles" in err and len(err.strip().splitlines()) == 1


def test_documented_netcdf_horizon(tmp_path):
    out = tmp_path / "horizon"
    assert main(["horizon", *map(str, _imported(tmp_path)), "--out-dir", str(out), "--fit-cycles", "1000",
                 "--quiet"]) == 0
    assert_documented(out / "horizon.nc", "horizon")
