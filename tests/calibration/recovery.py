"""Calibration recovery on the DEM (the slow test and bench/calibration_recovery.py): "measured"
curves made by the model with known F_str_co and mu on fresh specimens, one per test
condition (each laboratory test is a specimen of its own), plus a digitisation noise,
calibrated back jointly on K other specimens.

The rig runs the tests' fast first loading (I = 1.35e-4) but the config's consolidation
windows (5000 steps), not the other tests' 1000: with windows of ~2 ms the at-rest check
(strain rate < 2e-3 /s over one window) reads the servo's jitter, and a low-friction
specimen (mu 0.40) never passed it in 200 windows; with the config's windows it
consolidated in 14 s (2026-11-27)."""
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from ballaststudy.calibration.bayes import CalibrationResult, calibrate
from ballaststudy.calibration.evaluate import Evaluator
from ballaststudy.rig.biaxial import BiaxialParams, assemble_biaxial
from ballaststudy.rig.library import load_library

from ..shipped import ROOT
from .conftest import _fast_config, _planted_conditions

TRUE = {"F_str_co": 2.0, "mu": 0.9}
LOWER, UPPER = np.array([1.0, 0.4]), np.array([6.0, 1.2])
ASSEMBLY = dict(width_m=0.15, height_m=0.30, drop_max_steps=200000, relax_steps=2000, fill_area_ratio=0.9)
MEASUREMENT_SD = 5e-4


@dataclass
class Recovery:
    result: CalibrationResult
    y: np.ndarray             # the "measured" points, test after test
    after: np.ndarray         # (K, P) the DEM ensemble at the posterior mean
    cases: int                # DEM cases run by the calibration (the truths apart)


def _specimens(library, seeds, folder):
    paths = []
    for seed in seeds:
        path = Path(folder) / f"specimen{seed}.nc"
        assemble_biaxial(load_library(library), BiaxialParams(**ASSEMBLY), seed=seed).save(path)
        paths.append(path)
    return paths


def _config(folder):
    path = _fast_config(folder)
    cfg = yaml.safe_load(path.read_text())
    shipped = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())["rig"]["biaxial"]["loading"]
    cfg["rig"]["biaxial"]["loading"]["consolidation_window_steps"] = shipped["consolidation_window_steps"]
    path.write_text(yaml.safe_dump(cfg))
    return path


def recover(library, folder, calibration_seeds, truth_seeds, conditions_kPa, cycles=5, jobs=2, seed=11,
            noise_seed=5):
    """Recovery with specimens of ``calibration_seeds`` (K) and one fresh truth specimen per
    condition (p, q_max) [kPa] (q_min 10 kPa, 5 Hz quasi-static), the digitisation noise
    drawn with ``noise_seed``. Specimens are kept as ``folder``/specimen<seed>.nc and cases
    under their content's key, so recoveries in one folder share what they have in common."""
    folder = Path(folder)
    config = _config(folder)
    conditions = [_planted_conditions(folder / f"test{j}.yaml", q, p_kPa=p, frequency_Hz=5.0)
                  for j, (p, q) in enumerate(conditions_kPa)]
    calibration = _specimens(library, calibration_seeds, folder)
    truths = _specimens(library, truth_seeds, folder)
    points = np.arange(1.0, cycles + 1)
    names = list(TRUE)
    y = []
    for j, (c, s) in enumerate(zip(conditions, truths)):
        truth = Evaluator(names, [s], [(c, points)], config, cycles, "axial_strain", folder / f"truth{j}")
        y.append(truth(np.array([list(TRUE.values())]))[0][0])
    y = np.concatenate(y) + np.random.default_rng(noise_seed).normal(0.0, MEASUREMENT_SD, len(points) * len(conditions))
    point_test = np.repeat(np.arange(len(conditions)), len(points))
    evaluate = Evaluator(names, calibration, [(c, points) for c in conditions], config, cycles, "axial_strain",
                         folder / "cal", jobs=jobs)
    res = calibrate(evaluate, y, LOWER, UPPER, n_initial=6, iterations=2, batch=3, seed=seed,
                    include=np.array([3.5, 0.7]), measurement_var=MEASUREMENT_SD ** 2, point_test=point_test)
    after = evaluate(res.posterior.mean[None])[0]
    return Recovery(res, y, after, len(evaluate.sets) * len(calibration) * len(conditions))


def replicates(library, folder, calibration_seeds, conditions_kPa, count, first_truth_seed=101, first_noise_seed=5,
               **kw):
    """``count`` recoveries that differ in their truths' specimens (fresh seeds from
    ``first_truth_seed`` on, one per condition) and digitisation noise (seeds from
    ``first_noise_seed`` on), on the same calibration specimens: what coverage is counted over.
    Their initial designs are the same sets, run once."""
    n = len(conditions_kPa)
    return [recover(library, folder, calibration_seeds,
                    range(first_truth_seed + n * r, first_truth_seed + n * (r + 1)), conditions_kPa,
                    noise_seed=first_noise_seed + r, **kw)
            for r in range(count)]


def covered(recoveries):
    """(R, d) bool: whether each recovery's 90 % interval holds each true value."""
    truth = np.array(list(TRUE.values()))
    iv = np.array([r.result.posterior.interval90 for r in recoveries])
    return (iv[:, :, 0] <= truth) & (truth <= iv[:, :, 1])
