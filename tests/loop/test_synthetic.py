"""Model-made measured tests (synthetic.py): digitised like the shared data - 11-35
points within the simulated cycles, spread uniformly in ln N, noise of the stated share of
the final value - and declared like a real test: conditions and covariates, nothing that
names the effect or its strength."""
import numpy as np
import pytest
import yaml

from ballaststudy.measured.importer import import_test, load_conditions

from .synthetic import (NOISE_SHARE, POINTS, SCENARIO_LIBRARY, SCENARIO_TESTS, PlantedTest, declared_sd, digitise,
                        irreducible_rmse, library_spec)


def test_digitised_points_uneven_in_ln_n_with_the_stated_noise():
    curve = 0.01 + 0.002 * np.log(np.arange(1, 21))          # linear in ln N: exact in between
    counts, residuals, logs = [], [], []
    for seed in range(400):
        n, v = digitise(curve, np.random.default_rng(seed), 0.01)
        assert np.all(np.diff(n) >= 0) and n[0] >= 1.0 and n[-1] <= 20.0
        counts.append(n.size)
        residuals.append(v - (0.01 + 0.002 * np.log(n)))
        logs.append(np.log(n) / np.log(20.0))
    assert min(counts) == POINTS[0] and max(counts) == POINTS[1]
    r = np.concatenate(residuals)
    np.testing.assert_allclose(r.std(), 0.01 * curve[-1], rtol=0.03)
    assert abs(r.mean()) < 3 * r.std() / np.sqrt(r.size)
    # uniform in ln N: each fifth of the log range holds a fifth of the points (not of N)
    share = np.histogram(np.concatenate(logs), bins=5, range=(0, 1))[0] / sum(counts)
    np.testing.assert_allclose(share, 0.2, atol=0.01)


def test_a_planted_test_declares_conditions_only(tmp_path):
    t = PlantedTest(30.0, 10.0, 50.0, 20.0, VCI_percent=40.0)
    (tmp_path / "t.yaml").write_text(yaml.safe_dump(t.conditions("t.dat")))
    (tmp_path / "t.dat").write_text("1.0, 0.001\n2.5, 0.0015\n")
    cfg = load_conditions(tmp_path / "t.yaml")
    assert (cfg["confining_pressure_kPa"], cfg["deviator_max_kPa"], cfg["frequency_Hz"]) == (30.0, 50.0, 20.0)
    assert cfg["covariates"] == {"VCI": {"value": 40.0, "units": "%"}}
    text = (tmp_path / "t.yaml").read_text()
    for word in ("rate", "abrasion", "fouling", "restraint", "friction", "wear", "damping"):
        assert word not in text
    import_test(tmp_path / "t.yaml", tmp_path / "t.nc")
    clean = PlantedTest(30.0, 10.0, 50.0, 20.0).conditions("t.dat")
    assert "covariates" not in clean


def test_library_entries_given_replace_the_scenario_defaults():
    """bench/loop_undeclared.py passes every library entry (it crashed on the duplicates)."""
    spec = library_spec(dict(n_stones=40, r0=0.006))
    assert spec == {**SCENARIO_LIBRARY, "n_stones": 40, "r0": 0.006}
    assert library_spec() == SCENARIO_LIBRARY and SCENARIO_LIBRARY["n_stones"] == 24


def test_every_scenario_test_is_a_condition_of_its_own():
    """p differs from test to test (the quasi-static model sees neither f nor VCI), and f and
    VCI are not ordered alike (rate and fouling must leave different patterns)."""
    p = [t.confining_pressure_kPa for t in SCENARIO_TESTS]
    f = [t.frequency_Hz for t in SCENARIO_TESTS]
    vci = [t.VCI_percent for t in SCENARIO_TESTS]
    assert len(set(p)) == len(SCENARIO_TESTS) >= 7
    assert abs(np.corrcoef(np.argsort(np.argsort(f)), np.argsort(np.argsort(vci)))[0, 1]) < 0.5


def test_irreducible_rmse_is_the_chaos_of_the_truths_mean_plus_the_noise():
    """Planted chaos of known size: every run is a smooth trend plus an independent draw
    of sd s per point, each probe another; the K-mean scatters by s / sqrt(K) about the
    trend, and with digitiser noise sd e the floor is sqrt(s^2 / K + e^2), per test and
    pooled (a factor of 2 in either term, or a probe's draw counted as the difference of
    two, would show)."""
    rng = np.random.default_rng(0)
    k, cycles = 400, 30
    trend = np.linspace(1e-4, 3e-4, cycles)
    sd = np.array([2e-5, 5e-5])                              # chaos per run, per test
    noise = np.array([1e-5, 0.0])
    runs, probes = (trend + sd[:, None, None] * rng.standard_normal((m, 2, k, cycles)) for m in (1, 3))
    n = np.concatenate([np.arange(1.0, cycles + 1)] * 2)
    test = np.repeat([0, 1], cycles)
    per_test, pooled = irreducible_rmse(runs[0], probes, n, test, noise)
    expect = np.sqrt(sd ** 2 / k + noise ** 2)
    np.testing.assert_allclose(per_test, expect, rtol=0.05)
    np.testing.assert_allclose(pooled, np.sqrt(np.mean(expect ** 2)), rtol=0.05)
    np.testing.assert_array_equal(irreducible_rmse(runs[0], runs, n, test, np.zeros(2))[0], 0.0)


def test_no_planted_strength_is_a_grid_set():
    """With the loop's own specimens (common random numbers) a grid set at the planted
    value would be the truth itself, run again: the scenarios would test nothing."""
    import inspect

    from ballaststudy.loop.cli import _bounds, design

    from .synthetic import PLANTED, scenario_setup
    sets = inspect.signature(scenario_setup).parameters["design_sets"].default     # the slow test's
    for name, values in PLANTED.items():
        if values:
            grid = design(*_bounds(name), sets, 0)[:, 0]
            assert np.min(np.abs(grid - next(iter(values.values())))) > 1e-3 * np.ptp(grid), name


def test_the_declared_measurement_sd_is_the_noise_the_curves_carry(tmp_path):
    """The loop is told the digitiser's noise of the planted curves: NOISE_SHARE x a curve's
    final value (median over tests), within 10 % of the sd of the noise digitise added."""
    rng = np.random.default_rng(5)
    measured, noise = [], []
    for j, final in enumerate((4e-5, 5e-5, 7e-5)):
        curve = final * np.log1p(np.arange(1, 25)) / np.log1p(24)
        n, v = digitise(curve, rng, NOISE_SHARE, points=(2000, 2000))
        noise.append(np.std(v - np.interp(np.log(n), np.log(np.arange(1, 25)), curve)))
        (tmp_path / f"t{j}.dat").write_text("".join(f"{a!r}, {b!r}\n" for a, b in zip(n.tolist(), v.tolist())))
        (tmp_path / f"t{j}.yaml").write_text(yaml.safe_dump(PlantedTest(30.0, 10.0, 50.0, 5.0).conditions(f"t{j}.dat")))
        measured.append(tmp_path / f"t{j}.nc")
        import_test(tmp_path / f"t{j}.yaml", measured[-1])
    sd = declared_sd(measured)
    assert sd == pytest.approx(np.median(noise), rel=0.1), (sd, noise)
    assert sd == pytest.approx(NOISE_SHARE * 5e-5, rel=0.1)
