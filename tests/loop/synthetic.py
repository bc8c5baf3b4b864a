"""Data with an undeclared effect (issue 14): "measured" tests made by the model itself with
one candidate effect switched on - at a strength the data do not state - and digitised like
the shared measurements, so that the loop can be checked where the answer is known. A helper
of tests/loop and bench/loop_undeclared.py, not of the package: it drives the command line
with argument lists as a user would.

A planted test's curve is the ensemble mean of the given specimens under the effect (run
through the loop's own runner, so the truth's cases sit in the same cache), read off at
11-35 cycle counts uniform in ln N (digitised points crowd no decade) with Gaussian noise of
a share of the curve's final value (a digitiser's error scales with the plot's axis). The
files written are the ones a user writes for a real test: a conditions YAML (p, q bounds, f,
covariates; no effect, no strength) and the curve file, imported to the test's netCDF.

Given the loop's own specimens the truth is the model's ensemble with the effect (common
random numbers: the effect's signature without a new specimen's scatter, run the loop with
``specimen_share`` 0); given fresh specimens it carries their scatter too (share 1): one
set for every test (one offset shared by all tests), or a set per test, as a laboratory
builds a specimen for each test."""
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr
import yaml

from ballaststudy.calibration.bayes import rmse
from ballaststudy.calibration.evaluate import Evaluator
from ballaststudy.scenario.results import at_points
from ballaststudy.cli import main
from ballaststudy.dem.materials import ContactMaterial
from ballaststudy.loop.select import chaos_covariance
from ballaststudy.measured.importer import import_test
from ballaststudy.rig.library import synthetic_library

from ..biaxial_fast import FAST_LOADING

POINTS = (11, 35)           # digitised points per curve, as in the shared measured data
NOISE_SHARE = 0.01          # the digitiser's noise, sd as a share of the curve's final value


@dataclass(frozen=True)
class PlantedTest:
    """The conditions of one planted test (what its YAML declares)."""
    confining_pressure_kPa: float
    deviator_min_kPa: float
    deviator_max_kPa: float
    frequency_Hz: float
    VCI_percent: float = 0.0

    def conditions(self, curve_file):
        cov = {"VCI": {"value": float(self.VCI_percent), "units": "%"}} if self.VCI_percent else {}
        return dict(source="planted (model-made: an undeclared effect)", rig="triaxial",
                    confining_pressure_kPa=float(self.confining_pressure_kPa),
                    deviator_min_kPa=float(self.deviator_min_kPa),
                    deviator_max_kPa=float(self.deviator_max_kPa), frequency_Hz=float(self.frequency_Hz),
                    **({"covariates": cov} if cov else {}),
                    curves=[dict(file=curve_file, quantity="axial_strain", units="1",
                                 sign="compression_positive")])


def digitise(curve, rng, noise_share, points=POINTS):
    """(N, value) of a curve of cycles 1..len(curve) read at a random number of cycle counts
    (``points`` bounds) uniform in ln N, with noise of sd ``noise_share`` x |final value|."""
    m = int(rng.integers(points[0], points[1] + 1))
    n = np.sort(np.exp(rng.uniform(0.0, math.log(curve.size), m)))
    value = np.interp(np.log(n), np.log(np.arange(1, curve.size + 1)), curve)
    return n, value + rng.normal(0.0, noise_share * abs(curve[-1]), m)


def truth_runs(tests_yaml, specimens, config, cycles, out_dir, effect=None, values=None,
               base=None, jobs=1, perturbation_m_s=0.0, probe=0):
    """(T, K, cycles) axial strain of each of ``specimens`` under each test with ``effect``
    at ``values`` (None: the plain model), cases cached under out_dir/cases; from velocities
    perturbed by ``perturbation_m_s`` if > 0 (a chaos probe of the truth; probes 0, 1, ...
    perturb in independent directions)."""
    values = dict(values or {})
    evaluate = Evaluator(list(values), specimens, [(c, np.arange(1.0, cycles + 1)) for c in tests_yaml],
                         config, cycles, "axial_strain", out_dir, jobs=jobs, effect=effect, base=base,
                         perturbation_m_s=perturbation_m_s, perturbation_seed=probe * len(specimens))
    evaluate(np.array([list(values.values())]))
    return evaluate.sets[0]["curves"]


def truth_curves(tests_yaml, specimens, config, cycles, out_dir, effect=None, values=None,
                 base=None, jobs=1):
    """(T, cycles) ensemble-mean axial strain: truth_runs averaged over the specimens."""
    return truth_runs(tests_yaml, specimens, config, cycles, out_dir, effect, values, base, jobs).mean(axis=1)


def irreducible_rmse(runs, probes, cycles, point_test, noise_sd):
    """(per test (T,), pooled) RMSE that no prediction made from runs at other parameter
    values can beat on planted tests: the chaos the truth's ensemble mean carries
    (select.chaos_covariance / K) plus the digitiser's noise (sd per test), at the measured
    points (``cycles``, ``point_test``). runs (T, K, cycles): the truth's runs; probes
    (M, T, K, cycles): the same runs from velocities perturbed M times. The truth is one
    chaotic draw about the effect's smooth trend; a surrogate over other parameter values
    predicts at best that trend. Points grouped by test, 0 first, as the loop's."""
    cycles, point_test = np.asarray(cycles, float), np.asarray(point_test)
    tests = range(len(runs))

    def at(curves):                      # (T, K, cycles) -> (K, P) at the measured points
        return np.concatenate([[at_points(c, cycles[point_test == t]) for c in curves[t]] for t in tests], axis=1)
    runs_at, probes_at = at(runs), np.array([at(p) for p in probes])
    per_test = [np.diag(chaos_covariance(runs_at, probes_at, point_test, t)) / len(runs_at) + noise_sd[t] ** 2
                for t in tests]
    return np.sqrt([v.mean() for v in per_test]), math.sqrt(np.concatenate(per_test).mean())


def plant(folder, tests, specimens, config, cycles, effect=None, values=None, base=None,
          noise_share=NOISE_SHARE, seed=0, cache=None, jobs=1):
    """Write the planted tests t<j>.yaml / t<j>.dat / t<j>.nc into ``folder``; returns
    (measured netCDFs, conditions YAMLs). The truth's cases go to ``cache`` (default folder).
    ``specimens``: one list for every test, or a list per test (per_test_specimens)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    conditions = []
    for j, t in enumerate(tests):
        conditions.append(folder / f"t{j}.yaml")
        conditions[-1].write_text(yaml.safe_dump(t.conditions(f"t{j}.dat"), sort_keys=False))
    if isinstance(specimens[0], (list, tuple)):
        truth = np.concatenate([truth_curves([c], s, config, cycles, cache or folder, effect, values, base, jobs)
                                for c, s in zip(conditions, specimens)])
    else:
        truth = truth_curves(conditions, specimens, config, cycles, cache or folder, effect, values, base, jobs)
    rng = np.random.default_rng(seed)
    measured = []
    for j, curve in enumerate(truth):
        n, v = digitise(curve, rng, noise_share)
        (folder / f"t{j}.dat").write_text("".join(f"{a!r}, {b!r}\n" for a, b in zip(n.tolist(), v.tolist())))
        measured.append(folder / f"t{j}.nc")
        import_test(conditions[j], measured[-1])
    return measured, conditions


# The undeclared-effect scenarios (bench/loop_undeclared.py, tests/loop/test_undeclared.py):
# eight tests, so that every candidate's rule can pass (a one-sided signed-rank test over 8
# tests at 0.05 / 4 candidates needs 7 of them better), weak joints, so that wear can break
# them within a few cycles. Every test is a condition of its own for every candidate: the
# confining pressure differs from test to test (the quasi-static model sees neither f nor
# VCI, so tests that share p and q would be copies of one run for three of the four
# candidates: with p in {30, 40} the signed-rank test counted two conditions as eight), and
# f (rate acts through it) and VCI (fouling does) are not ordered alike, so that the two
# effects' patterns over the tests differ.
SCENARIO_TESTS = tuple(PlantedTest(p, 10.0, 50.0, f, vci) for p, f, vci in zip(
    (30, 45, 25, 50, 35, 60, 40, 55), (5, 10, 15, 20, 30, 40, 50, 60), (50, 10, 70, 30, 80, 20, 60, 40)))
SCENARIO_BASE = {"F_str_co": 1.0}
PLANTED = {"none": {}, "rate": {"contact_damping_ratio": 0.3}, "abrasion": {"wear_per_cycle": 0.12},
           "fouling": {"friction_loss": 0.6}, "end_restraint": {"platen_friction": 0.2}}
# A change no candidate makes (issue 34's out-of-library control): the stones' contact twice
# as stiff as Table 4.2's, planted as a material parameter the loop's plain model keeps.
OUT_OF_LIBRARY = {"stiffer_contact": {"E_star": 2 * ContactMaterial().E},
                  # issue 75's: the contact's normal-to-shear stiffness ratio 2.5 -> 6
                  "stiffness_ratio": {"kappa_star": 6.0}}


SCENARIO_LIBRARY = dict(n_stones=24, size=(0.035, 0.065), r0=0.008, seed=3, database="tiny")


def library_spec(library=None):
    """The scenarios' synthetic library (rig.library.synthetic_library arguments), with the
    entries of ``library`` in place of the defaults."""
    return {**SCENARIO_LIBRARY, **(library or {})}


def scenario_setup(folder, config_file, cases=3, cycles=24, design_sets=9, specimen_share=0.0,
                   library=None, size_m=(0.12, 0.24), refine_rounds=2, refine_sets=4, assemble=None):
    """A synthetic BPM library, a config for the loop at this scale and ``assemble`` (default
    ``cases``) assembled biaxial specimens in ``folder``; returns (specimens, config, base
    parameters YAML). The defaults are the slow test's scale (tests/loop/test_undeclared.py
    says why)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    lib = library_spec(library)
    if not (folder / "BPM.nc").exists():
        synthetic_library(**lib).to_netcdf(folder / "BPM.nc")
    cfg = yaml.safe_load(Path(config_file).read_text())
    cfg["databases_file"] = str(Path(config_file).parent / cfg["databases_file"])
    cfg["rig"]["biaxial"]["loading"].update(FAST_LOADING)
    sets = cfg["specimens"]
    sets[cfg["loop"]["specimens"]]["cases"] = max(cases, sets[cfg["loop"]["specimens"]]["cases"])
    cfg["loop"].update(cases=cases, cycles=cycles, design_sets=design_sets, refine_rounds=refine_rounds,
                       refine_sets=refine_sets, posterior_samples=4096, specimen_share=float(specimen_share))
    (folder / "config.yaml").write_text(yaml.safe_dump(cfg))
    (folder / "base.yaml").write_text(yaml.safe_dump({"parameters": SCENARIO_BASE}))
    specimens = [folder / f"s{k}.nc" for k in range(assemble or cases)]
    for k, s in enumerate(specimens):
        if not s.exists():
            main(["case", "assemble", str(folder / "BPM.nc"), "--case", str(k), "--rig", "biaxial", "--width-m",
                  str(size_m[0]), "--height-m", str(size_m[1]), "--config", str(folder / "config.yaml"),
                  "--out", str(s), "--quiet"])
    return specimens, folder / "config.yaml", folder / "base.yaml"


def declared_sd(measured, noise_share=NOISE_SHARE):
    """The measurement sd a user who digitised these curves would declare
    (``loop.measurement_sd``): the digitiser's noise, ``noise_share`` x a curve's final
    value, at the median of the tests' last measured values."""
    finals = []
    for path in measured:
        with xr.open_dataset(path) as ds:
            finals.append(abs(float(ds["axial_strain"].values[-1])))
    return noise_share * float(np.median(finals))


def run_loop(folder, out, measured, conditions, specimens, jobs=2):
    """`ballaststudy loop` on planted tests, in ``out``, with the scenario folder's config
    (``loop.measurement_sd`` declared from the measured curves, declared_sd: the loop is
    told the noise the curves carry), base parameters and case cache (shared by every loop
    run there); returns ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    if not (out / "cases").exists():
        (out / "cases").symlink_to((folder / "cases").resolve())
    cfg = yaml.safe_load((folder / "config.yaml").read_text())
    cfg["loop"]["measurement_sd"] = declared_sd(measured)
    (out / "config.yaml").write_text(yaml.safe_dump(cfg))
    if main(["loop", *map(str, measured), "--conditions", *map(str, conditions), "--specimens", *map(str, specimens),
             "--parameters", str(folder / "base.yaml"), "--out-dir", str(out), "--jobs", str(jobs), "--config",
             str(out / "config.yaml"), "--quiet"]):
        raise RuntimeError(f"ballaststudy loop refused the planted tests in {out} (its one line above)")
    return out


def run_scenario(folder, name, specimens, cycles, truth_specimens=None, jobs=2, seed=0, values=None):
    """Plant SCENARIO_TESTS with effect ``name`` (PLANTED, or at ``values``; "none": the
    plain model) or a material change (OUT_OF_LIBRARY) and run the loop on them, its cases
    cached in ``folder``/cases (shared by the scenarios), in ``folder``/<name> (or
    <name>_<value> with ``values``). Returns (chosen effect or None, the candidates'
    evidence, the plain model's RMSE)."""
    folder = Path(folder)
    if name in OUT_OF_LIBRARY:
        effect, planted, base = None, {}, {**SCENARIO_BASE, **OUT_OF_LIBRARY[name]}
    else:
        effect, planted, base = None if name == "none" else name, values or PLANTED[name], SCENARIO_BASE
    if values:
        name = name + "_" + "_".join(f"{v:g}" for v in values.values())
    measured, conditions = plant(folder / name / "tests", SCENARIO_TESTS, truth_specimens or specimens,
                                 folder / "config.yaml", cycles, effect, planted, base, seed=seed, cache=folder,
                                 jobs=jobs)
    out = run_loop(folder, folder / name / "loop", measured, conditions, specimens, jobs)
    chosen = yaml.safe_load((out / "chosen.yaml").read_text())["effect"]
    with xr.open_dataset(out / "loop.nc") as ds:
        candidates = json.loads(ds.attrs["candidates_json"])
        plain = rmse(ds["measured"].values, ds["plain_prediction"].values)
    return (None if chosen == "none" else chosen), candidates, plain
