"""Recovery on the DEM itself (issue 13's test): a "measured" curve made by the model with
known F_str_co and mu (not Table 4.2's) on a specimen the calibration never sees, plus a
digitisation noise, is calibrated back with the biaxial rig on two other specimens: the
true values lie inside the 90 % intervals, and the friction's interval is narrower than
its prior. Small scale (synthetic coarse stones, 5 cycles); slow: ~3 min on 2 cores.
Measured 2026-11-24: 24 DEM cases, mu 90 % [0.72, 1.17] (56 % of the prior; true 0.9),
F_str_co [1.39, 5.77] (88 %; true 2.0): at this scale the specimen-to-specimen scatter
(axial strain 0.006 vs 0.034 at the same parameters) leaves F_str_co, which acts only
through the few bonds that break, nearly unidentified - an honest limit, not a bug."""

import numpy as np
import pytest

from ballaststudy.calibration.bayes import calibrate, rmse
from ballaststudy.calibration.evaluate import Evaluator
from ballaststudy.rig.biaxial import BiaxialParams, assemble_biaxial
from ballaststudy.rig.library import load_library

TRUE = {"F_str_co": 2.0, "mu": 0.9}
LOWER, UPPER = np.array([1.0, 0.4]), np.array([6.0, 1.2])
CYCLES = 5
ASSEMBLY = dict(width_m=0.15, height_m=0.30, drop_max_steps=200000, relax_steps=2000, fill_area_ratio=0.9)


@pytest.fixture(scope="module")
def setting(small_library, tmp_path_factory, fast_config, planted_conditions):
    tmp = tmp_path_factory.mktemp("recovery")
    specimens = []
    for seed in (7, 8, 9):
        path = tmp / f"specimen{seed}.nc"
        assemble_biaxial(load_library(small_library), BiaxialParams(**ASSEMBLY), seed=seed).save(path)
        specimens.append(path)
    config = fast_config(tmp)
    conditions = planted_conditions(tmp / "test.yaml", 200.0, frequency_Hz=5.0)
    return specimens, config, conditions, tmp


@pytest.mark.slow
def test_calibration_recovers_known_parameters(setting):
    specimens, config, conditions, tmp = setting
    points = np.arange(1.0, CYCLES + 1)
    names = list(TRUE)
    truth = Evaluator(names, specimens[2:], [(conditions, points)], config, CYCLES, "axial_strain",
                      tmp / "truth", jobs=1)
    y = truth(np.array([list(TRUE.values())]))[0][0]
    y = y + np.random.default_rng(5).normal(0.0, 5e-4, y.size)     # digitised points
    evaluate = Evaluator(names, specimens[:2], [(conditions, points)], config, CYCLES, "axial_strain",
                         tmp / "cal", jobs=2)
    res = calibrate(evaluate, y, LOWER, UPPER, n_initial=6, iterations=2, batch=3, seed=11,
                    include=np.array([3.5, 0.7]), measurement_var=(5e-4) ** 2)
    post = res.posterior
    cases = len(evaluate.sets) * len(specimens[:2])
    before = rmse(np.mean(res.curves[0], axis=0), y)
    print(f"\nrecovery: {cases} DEM cases; true {TRUE}; posterior mean {post.mean.round(3)}; "
          f"90 % {post.interval90.round(3).tolist()}; ESS {post.ess:.0f}; RMSE Table 4.2 {before:.4g}")
    for k, name in enumerate(names):
        lo, hi = post.interval90[k]
        assert lo <= TRUE[name] <= hi, (name, lo, hi)
    mu_width = np.diff(post.interval90[1])[0]
    assert mu_width < 0.65 * (UPPER[1] - LOWER[1]), mu_width
