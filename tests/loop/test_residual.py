"""Residuals and their attribution on planted data with known answers: the model's own
extra specimen is within its scatter (negative control), a planted offset and a planted
growth in ln N are recovered within 3 standard errors, a planted covariate relation is
significant and an absent one is not."""
import numpy as np
import pytest

from ballaststudy.loop.residual import covariate_tests, holm, residual, summary

N_SIM = 300
POINTS = np.unique(np.round(np.exp(np.linspace(0, np.log(N_SIM), 15)), 1))


def _base(n):
    return 0.01 + 0.004 * np.log(n)


def _cases(rng, k, sd=0.002):
    """k simulated specimens: the base curve with a specimen offset growing in ln N."""
    n = np.arange(1, N_SIM + 1)
    return np.array([_base(n) + rng.normal(0, sd) * (1 + 0.2 * np.log(n)) for _ in range(k)])


@pytest.mark.parametrize("seed", range(5))
def test_one_more_specimen_is_within_the_scatter(seed):
    rng = np.random.default_rng(seed)
    cases = _cases(rng, 10)
    extra = _cases(rng, 1)[0]
    measured = np.interp(np.log(POINTS), np.log(np.arange(1, N_SIM + 1)), extra)
    s = summary(residual(POINTS, measured, cases, 1e-4))
    # one specimen's offset runs along its whole curve: a pointwise test would reject it
    assert s["bias_p"] > 0.01 and s["slope_p"] > 0.01, s


def test_planted_offset_and_growth_are_recovered():
    rng = np.random.default_rng(1)
    cases = _cases(rng, 10, sd=0.0005)
    mean = cases.mean(axis=0)
    at = np.interp(np.log(POINTS), np.log(np.arange(1, N_SIM + 1)), mean)
    offset = summary(residual(POINTS, at + 0.01, cases, 1e-4))
    assert offset["bias"] == pytest.approx(0.01, abs=1e-9) and offset["bias_p"] < 1e-3
    assert abs(offset["slope_ln_n"]) < 1e-9 and offset["slope_p"] > 0.5
    growth = summary(residual(POINTS, at + 0.003 * np.log(POINTS), cases, 1e-4))
    assert growth["slope_ln_n"] == pytest.approx(0.003, rel=1e-6) and growth["slope_p"] < 1e-3


def test_no_point_beyond_the_simulated_cycles():
    cases = _cases(np.random.default_rng(2), 3)
    n = np.array([1.0, 10.0, 299.0, 301.0, 5e5])
    res = residual(n, _base(n), cases, 1e-3)
    assert res.n.tolist() == [1.0, 10.0, 299.0]


def test_one_case_has_only_the_measurement_sd():
    cases = _cases(np.random.default_rng(3), 1)
    res = residual(POINTS, _base(POINTS), cases, 2e-3)
    assert np.allclose(res.sd, 2e-3) and len(res.cases) == 1
    s = summary(res)
    assert not s["scatter_known"] and s["bias_se"] == pytest.approx(2e-3 / np.sqrt(len(POINTS)))


def test_holm_adjustment():
    assert holm([0.01, 0.04, 0.03]) == pytest.approx([0.03, 0.06, 0.06])


def _tests(rng, relation):
    """Two source studies; in each, frequencies and pressures, the bias planted by
    relation(f, p) plus noise; a per-study offset (the grouping factor)."""
    rows = []
    for source, offset in (("A", 0.0), ("B", 0.02)):
        for f in (5, 10, 20, 30, 40, 60):
            for p in (30, 60):
                rows.append(dict(source=source, frequency_Hz=f, confining_pressure_kPa=p,
                                 bias=offset + relation(f, p) + rng.normal(0, 0.002)))
    return rows


def test_a_planted_covariate_is_found_and_only_it():
    rows = _tests(np.random.default_rng(4), lambda f, p: 0.001 * f)
    out = {r["covariate"]: r for r in covariate_tests(rows, "bias", ["frequency_Hz", "confining_pressure_kPa"])}
    f = out["frequency_Hz"]
    assert f["significant"] and abs(f["slope"] - 0.001) < 3 * f["se"] and f["groups"] == 2
    assert not out["confining_pressure_kPa"]["significant"]


def test_no_relation_nothing_significant():
    rows = _tests(np.random.default_rng(5), lambda f, p: 0.0)
    out = covariate_tests(rows, "bias", ["frequency_Hz", "confining_pressure_kPa", "VCI"])
    assert not any(r.get("significant") for r in out)
    assert [r["tried"] for r in out] == [True, True, False]          # VCI declared nowhere


def test_one_test_alone_is_no_evidence():
    """Six tests share a pressure, one differs and is far off: its residual would be the
    whole evidence for a pressure relation, so pressure is not tried."""
    rng = np.random.default_rng(6)
    rows = [dict(source="A", confining_pressure_kPa=60, frequency_Hz=f, bias=rng.normal(0, 0.001))
            for f in (5, 10, 20, 30, 40, 60)]
    rows.append(dict(source="A", confining_pressure_kPa=30, frequency_Hz=20, bias=0.05))
    out = {r["covariate"]: r for r in covariate_tests(rows, "bias", ["confining_pressure_kPa", "frequency_Hz"])}
    assert not out["confining_pressure_kPa"]["tried"] and out["frequency_Hz"]["tried"]
