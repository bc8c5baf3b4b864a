"""`ballaststudy calibrate`: the config's parameters (section ``calibration``) fitted to one
or more measured tests (thesis 4.3, automated) - triaxial/biaxial tests with the biaxial
rig, box tests with the box rig (the specimens' kind decides); the tests are fitted jointly,
each test's points one block of the likelihood (calibration.bayes). Box settlement is
relative to the first cycle (thesis 4.5.1): a measured box curve is compared as given, so
give it relative to its first cycle too.

    ballaststudy calibrate results/measured/<t1>.nc [<t2>.nc ...] --conditions
        config/measured/<t1>.yaml [...] --specimens S0.nc S1.nc ... --out-dir
        results/calibration/<name> [--jobs 2]

Every check (bounds, the measured points within the simulated cycles, K = the specimens)
before any case runs; finished cases are reused (scenario.runner), so an interrupted calibration
resumes. Writes evaluations.nc, posterior.nc, calibrated.yaml, curves.png, corner.png and
summary.md into the folder."""
import json
import math
import time
from pathlib import Path

import numpy as np
import yaml

from ..argtypes import add_config, add_quiet, integer
from ..atomic import atomic_path
from ..config import ConfigError, load_config
from ..inputs import input_file, open_netcdf, writable_dir, writable_file
from ..measured.importer import load_conditions, measured_test_name
from ..provenance import Recorder
from ..rig.kinds import RUNS_TESTS, kind_for_test, kind_of, rig_classes
from ..scenario.mapping import stage_mapping
from ..scenario.modifiers import MATERIAL, MODIFIERS, material_parameter
from ..cluster.pool import case_pool
from ..cluster.spec import KINDS, executor_spec
from ..scenario.runner import BACKENDS, check_backend
from ..scenario.scenario import check_stone_model, splitting_of
from ..stones import DEFAULT
from .bayes import calibrate, rmse
from .evaluate import Evaluator
from .parametric import (DESIGN, cases_per_value, findings, parametric_dataset, plot_parameter,
                         report_markdown, sensitivity_table, slope_table)
from .report import (calibrated_yaml, evaluations_dataset, plot_corner, plot_curves,
                     posterior_dataset, summary_markdown)

METHOD = ("Gaussian-process surrogate of the ensemble-mean curve (scikit-learn, BSD-3), "
          "uniform prior in the bounds; per measured test, a multivariate t likelihood (K - 1 "
          "degrees of freedom: the K specimens shared by every set) with scale the ensemble's "
          "pooled case-to-case covariance of the test's points (shrunk 10 % to its diagonal) "
          "x (1 + 1/K) + measurement_sd^2 + the surrogate's variance, tests independent; "
          "Latin-hypercube design, then rounds drawn from the posterior (space filling)")


RIG_QUANTITIES = {"biaxial": ("axial_strain", "volumetric_strain"), "box": ("settlement",)}


def specimens_kind(paths):
    """The rig kind of the K assembled specimens; ConfigError if they differ."""
    kinds = [kind_of(open_netcdf(p, "assembled")) for p in paths]
    if len(set(kinds)) > 1:
        raise ConfigError(paths[kinds.index(kinds[-1])], "rig_kind", f"{kinds[-1]}, but "
                          f"{paths[0]} is {kinds[0]}; allowed: specimens of one rig")
    return kinds[0]


def write_netcdf(ds, path):
    with atomic_path(path) as tmp:        # creates the folder; a partial file never stays
        ds.to_netcdf(tmp)


def check_targets(cfg, config_file, tests):
    """Every calibration.targets entry must be one of the measured tests (names relative to
    measured.tests_dir, without .yaml) when there are any; a name for the output folder
    when there is more than one. Returns that folder's name."""
    cal = cfg["calibration"]
    for k, target in enumerate(cal["targets"]):
        if tests and target not in tests:
            raise ConfigError(config_file, f"calibration.targets[{k}]", f"{target!r} is not a measured "
                              f"test under {cfg['measured']['tests_dir']}; allowed: {', '.join(tests)}")
    check_parameters(cal["parameters"], config_file)
    check_rolling_parameters(cfg, config_file)
    if len(cal["targets"]) > 1 and not cal.get("name"):
        raise ConfigError(config_file, "calibration.name", "missing; allowed: a folder name, required "
                          "with more than one target")
    return cal.get("name") or cal["targets"][0]


def check_parameters(parameters, config_file):
    """Each calibrated parameter a material modifier's, its prior bounds inside the
    modifier's physical range and min below max; ConfigError naming the key."""
    for name, bounds in parameters.items():
        key = f"calibration.parameters.{name}"
        if name not in MATERIAL:
            raise ConfigError(config_file, key, f"unknown key; allowed: {', '.join(MATERIAL)}")
        p = material_parameter(name)
        for end in ("min", "max"):
            if not p.admits(bounds[end]):
                raise ConfigError(config_file, f"{key}.{end}", f"{bounds[end]!r} is not allowed; "
                                  f"allowed: a number {p.range_text()}")
        if not bounds["min"] < bounds["max"]:
            raise ConfigError(config_file, f"{key}.min", f"{bounds['min']:g} must be below {key}.max "
                              f"({bounds['max']:g})")


def check_rolling_parameters(cfg, config_file):
    """A parameter setting a rolling coefficient (mu_r) needs specimens assembled with the
    law's rolling sub-model; ConfigError naming the key otherwise."""
    cal = cfg["calibration"]
    kind = ((cfg.get("specimens") or {}).get(cal["specimens"]) or {}).get("rig")
    assembly = ((cfg.get("rig") or {}).get(kind) or {}).get("assembly") or {}
    for name in cal["parameters"]:
        if MODIFIERS[name].needs_rolling and assembly.get("rolling_resistance", "none") == "none":
            raise ConfigError(config_file, f"calibration.parameters.{name}", f"needs rolling "
                              f"resistance in the specimens' contact law; allowed: with "
                              f"rig.{kind}.assembly.rolling_resistance epsd")


def targets_kind(cfg, config_file, tests_dir):
    """The rig kind that runs the calibration's targets (their conditions' ``rig``), checked
    to be one kind that records calibration.quantity."""
    cal = cfg["calibration"]
    kinds = [kind_for_test(load_conditions(Path(tests_dir) / f"{t}.yaml")["rig"]) for t in cal["targets"]]
    if len(set(kinds)) > 1:
        raise ConfigError(config_file, "calibration.targets", f"{', '.join(cal['targets'])} need "
                          f"the {' and '.join(sorted(set(kinds)))} rigs; allowed: tests of one rig")
    if cal["quantity"] not in RIG_QUANTITIES[kinds[0]]:
        raise ConfigError(config_file, "calibration.quantity", f"{cal['quantity']}: the {kinds[0]} "
                          f"rig (the targets') does not record it; allowed: {', '.join(RIG_QUANTITIES[kinds[0]])}")
    sets = cfg.get("specimens") or {}
    if cal["specimens"] in sets and sets[cal["specimens"]]["rig"] != kinds[0]:
        raise ConfigError(config_file, "calibration.specimens", f"{cal['specimens']!r} is a "
                          f"{sets[cal['specimens']]['rig']} set, the targets need the {kinds[0]} rig; "
                          f"allowed: a {kinds[0]} set")
    return kinds[0]


def check_rig(path, config, cal, kind, section="calibration"):
    """ConfigError unless specimens of rig ``kind`` run the measured test and record
    calibration.quantity."""
    rig = open_netcdf(path, "measured").attrs.get("rig")
    if rig not in RUNS_TESTS[kind]:
        raise ConfigError(path, "rig", f"{rig}: the specimens are {kind} specimens; "
                          f"allowed: {' or '.join(RUNS_TESTS[kind])} tests")
    if cal["quantity"] not in RIG_QUANTITIES[kind]:
        raise ConfigError(config, f"{section}.quantity", f"{cal['quantity']}: the {kind} rig does "
                          f"not record it; allowed: {', '.join(RIG_QUANTITIES[kind])}")


def measured_points(path, config, cal, section="calibration"):
    """(N, values) of a measured test's curve within the simulated cycles; ConfigError if
    fewer than two."""
    ds = open_netcdf(path, "measured")
    q = cal["quantity"]
    if q not in ds:
        raise ConfigError(path, q, f"the test has no {q} curve; allowed: "
                          f"{', '.join(v for v in ds.data_vars)}")
    n, y = ds["cycle"].values, ds[q].values
    keep = np.isfinite(y) & (n >= 1) & (n <= cal["cycles"])
    if keep.sum() < 2:
        second = np.sort(n[np.isfinite(y) & (n >= 1)])[1:2]
        raise ConfigError(config, f"{section}.cycles",
                          f"{cal['cycles']} cycles hold {int(keep.sum())} measured point(s) of "
                          f"{path}; allowed: at least the second point's N "
                          f"({second[0]:.0f})" if second.size else "the test has < 2 points")
    return n[keep], y[keep]


def checked_targets(args, section_cfg, section):
    """([(N, values)] of every target within the simulated cycles, the specimens' rig kind),
    after every check a run of K specimens under measured tests needs (calibrate, loop):
    ConfigError naming file and key, before any case runs."""
    if len(args.specimens) != section_cfg["cases"]:
        raise ConfigError(args.config, f"{section}.cases", f"{section_cfg['cases']} but "
                          f"{len(args.specimens)} specimens given; allowed: one specimen per case")
    if len(args.conditions) != len(args.measured):
        raise ConfigError(args.config, f"{section}.targets", f"{len(args.measured)} measured files "
                          f"but {len(args.conditions)} conditions YAMLs; allowed: one of each per target")
    for c in args.conditions:
        input_file(c, "expected the test's conditions YAML")
    measured = [measured_points(m, args.config, section_cfg, section) for m in args.measured]
    kind = specimens_kind(args.specimens)
    for m in args.measured:
        check_rig(m, args.config, section_cfg, kind, section)
    return measured, kind


def _calibrate(args):
    check_backend(args.backend)
    out = writable_dir(args.out_dir)
    cfg = load_config(args.config)
    check_stone_model(cfg, args.config, args.backend, stages=("calibration.parameters",))
    cal = cfg["calibration"]
    measured, kind = checked_targets(args, cal, "calibration")
    points = np.concatenate([n for n, _ in measured])
    y = np.concatenate([v for _, v in measured])
    point_test = np.concatenate([np.full(n.size, j) for j, (n, _) in enumerate(measured)])
    names = list(cal["parameters"])
    lower = np.array([cal["parameters"][k]["min"] for k in names], float)
    upper = np.array([cal["parameters"][k]["max"] for k in names], float)
    rig = rig_classes(kind)[0].from_dataset(open_netcdf(args.specimens[0], "assembled"), "engine_checkpoint")
    table = {k: MODIFIERS[k].current(rig)[k] for k in names}
    t_before = np.array([table[k] for k in names])
    inside = bool(np.all((t_before >= lower) & (t_before <= upper)))
    recorder = Recorder("calibrate", inputs=(*args.measured, *args.conditions, args.config, *args.specimens,
                                             *([args.strength_envelope] if args.strength_envelope else [])),
                        params={"calibration": cal, "stress_mapping": cfg.get("stress_mapping"),
                                "stone_model": cfg.get("stone_model", DEFAULT), "splitting": splitting_of(cfg)},
                        seed=cfg["seed"])
    mapping = stage_mapping(cfg, args.config, args.strength_envelope, kind)
    spec = executor_spec(cfg, args.config, args.executor, args.scheduler_address)
    targets = [str(m) for m in args.measured]
    t0 = time.time()
    with case_pool(spec, args.jobs, out / "workers") as pool:
        evaluate = Evaluator(names, args.specimens, [(c, n) for c, (n, _) in zip(args.conditions, measured)],
                             cfg, cal["cycles"], cal["quantity"], out, jobs=args.jobs,
                             progress=not args.quiet, backend=args.backend, mapping=mapping, pool=pool)
        res = calibrate(evaluate, y, lower, upper, cal["initial_design"], cal["iterations"],
                        cal["batch"], seed=cfg["seed"], include=t_before if inside else None,
                        measurement_var=cal["measurement_sd"] ** 2, n_samples=cal["posterior_samples"],
                        point_test=point_test)
        rounds = list(res.rounds)
        if not inside:                          # Table 4.2 outside the prior: evaluated apart
            evaluate(t_before[None])
            rounds.append(-2)
        evaluate(res.posterior.mean[None])      # the calibrated set, from DEM runs
        rounds.append(-1)
    before = 0 if inside else len(rounds) - 2
    mapped = evaluate.mapping_records()
    attrs = {"targets": ", ".join(targets), "method": METHOD, "stress_mapping": mapping.kind,
             "stress_mapping_json": json.dumps(mapped)}
    ds = evaluations_dataset(names, evaluate.sets, rounds, points, point_test, y, cal["cycles"],
                             cal["quantity"], attrs)
    at = ds[cal["quantity"] + "_at_points"].values
    summary = dict(
        targets=targets, quantity=cal["quantity"], cycles=cal["cycles"], cases=cal["cases"],
        points=int(points.size), method=METHOD, table_4_2=table,
        rmse_before=rmse(at[before].mean(axis=0), y), rmse_after=rmse(at[-1].mean(axis=0), y),
        dem_cases=len(evaluate.sets) * len(targets) * cal["cases"], sets=len(evaluate.sets),
        failed_cases=int(ds["failed"].sum()), ess=float(res.posterior.ess),
        minutes=round((time.time() - t0) / 60, 1), stress_mapping=mapping.kind,
        stress_mapping_tests=mapped)
    summary["prior_coverage"] = {k: float((b - a) / (hi - lo)) for k, (a, b), lo, hi
                                 in zip(names, res.posterior.interval90, lower, upper)}
    if len(targets) > 1:
        tests = [measured_test_name(m) for m in args.measured]
        summary["held_out"] = held_out_rmse(res.held_out(y, point_test), at[before].mean(axis=0),
                                            at[-1].mean(axis=0), y, point_test, tests)
    summary["correlation"] = {f"{a}~{b}": float(res.posterior.correlation[i, j])
                              for i, a in enumerate(names) for j, b in enumerate(names) if i < j}
    files = {k: out / k for k in ("evaluations.nc", "posterior.nc", "calibrated.yaml",
                                  "curves.png", "corner.png", "summary.md")}
    write_netcdf(ds, files["evaluations.nc"])
    write_netcdf(posterior_dataset(names, res.posterior, attrs),
                 files["posterior.nc"])
    calibrated_yaml(files["calibrated.yaml"], names, res.posterior,
                    {k: v for k, v in summary.items() if k != "correlation"})
    plot_curves(files["curves.png"], ds, cal["quantity"], before, len(rounds) - 1,
                f"Table 4.2 (RMSE {summary['rmse_before']:.4f}) vs calibrated (RMSE {summary['rmse_after']:.4f})")
    plot_corner(files["corner.png"], names, res.posterior, res.thetas, lower, upper)
    summary_markdown(files["summary.md"], ", ".join(Path(m).stem for m in args.measured), names,
                     res.posterior, summary)
    recorder.finish()
    cases = [f for st in evaluate.sets for per_test in st["cases"] for f in per_test]  # this run's
    # sets (the cache folder may hold older ones)
    recorder.write_beside(files["calibrated.yaml"],
                          also=[f for k, f in files.items() if k != "calibrated.yaml"] + cases)
    if not args.quiet:
        print(f"wrote {out}: {summary['dem_cases']} DEM cases, RMSE {summary['rmse_before']:.4g} -> "
              f"{summary['rmse_after']:.4g}")


def held_out_rmse(held, before, after, y, point_test, targets):
    """{target: {rmse_before, rmse_after, rmse_held_out}}: each test against the ensemble mean
    with Table 4.2 and with the posterior mean of all tests (DEM runs), and against the
    surrogate's prediction from the posterior of the other tests (leave one condition out;
    the surrogate, not DEM runs, so it carries the surrogate's error)."""
    return {t: {"rmse_before": rmse(before[point_test == j], y[point_test == j]),
                "rmse_after": rmse(after[point_test == j], y[point_test == j]),
                "rmse_held_out": held.rmse(y, point_test, [j])} for j, t in enumerate(targets)}


def _setting(args):
    """A calibrated.yaml of the parametric study's runs: NAME VALUE [NAME VALUE ...]."""
    out = writable_file(args.out)
    if len(args.pairs) % 2:
        raise ConfigError(args.out, "parameters", f"{' '.join(args.pairs)}: allowed: NAME VALUE pairs")
    values = {}
    for name, text in zip(args.pairs[::2], args.pairs[1::2]):
        if name not in MATERIAL:
            raise ConfigError(args.out, "parameters", f"{name}: unknown; allowed: {', '.join(MATERIAL)}")
        p = material_parameter(name)
        try:
            values[name] = float(text)
        except ValueError:
            values[name] = float("nan")
        if not (math.isfinite(values[name]) and p.admits(values[name])):
            raise ConfigError(args.out, f"parameters.{name}", f"{text!r} is not allowed; "
                              f"allowed: a number {p.range_text()}")
    with atomic_path(out) as tmp:
        tmp.write_text(yaml.safe_dump({"parameters": values}))


def _parametric_report(args):
    out = writable_dir(args.out_dir)
    recorder = Recorder("parametric report", inputs=[input_file(p, "expected a netCDF file") for p in args.cases])
    ds = parametric_dataset(args.cases)
    cases = cases_per_value(ds)
    cycles = ds.sizes["cycle"]
    table = slope_table(ds)
    marks = findings(table, cases, cycles)
    sobol = sensitivity_table(ds)
    ds.attrs["sobol_indices_json"] = json.dumps(sobol)
    files = [out / "parametric.nc", out / "report.md"]
    write_netcdf(ds, files[0])
    report_markdown(files[1], table, marks, cases, cycles, sobol)
    for name in sorted(set(ds["parameter"].values) - {DESIGN}):
        files.append(out / f"{name}.png")
        plot_parameter(files[-1], ds, name)
    recorder.finish()
    recorder.write_beside(files[1], also=[files[0], *files[2:]])
    if not args.quiet:
        print(f"wrote {out}: " + "; ".join(f"{m['finding']}: {m['mark']}" for m in marks))


def register(subparsers):
    p = subparsers.add_parser("parametric", help="the parametric study's settings and report (thesis 4.4)")
    ps = p.add_subparsers(dest="action", required=True)
    s = ps.add_parser("setting", help="a calibrated.yaml of the varied parameter(s)")
    s.add_argument("pairs", nargs="+", metavar="NAME VALUE", help="F_str_co and/or mu, each with its value")
    s.add_argument("--out", required=True, type=Path, help="the calibrated.yaml to write")
    s.set_defaults(func=_setting)
    r = ps.add_parser("report", help="slopes, sensitivity, the thesis' findings, figures")
    r.add_argument("cases", nargs="+", type=Path, help="metrics.nc of the parametric runs")
    r.add_argument("--out-dir", required=True, type=Path, help="folder for the report, its table and figures")
    add_quiet(r)
    r.set_defaults(func=_parametric_report)
    c = subparsers.add_parser("calibrate", help="fit the config's parameters to a measured test (thesis 4.3)")
    target_arguments(c, "K assembled specimens (case assemble; biaxial for triaxial tests, box for box tests)")
    c.set_defaults(func=_calibrate)
    return c


def target_arguments(c, specimens_help):
    """The arguments of a run of K specimens under measured tests (calibrate, loop)."""
    c.add_argument("measured", nargs="+", type=Path, help="the target tests' netCDFs (measured import)")
    c.add_argument("--conditions", required=True, nargs="+", type=Path,
                   help="their conditions YAMLs, in the same order")
    c.add_argument("--specimens", required=True, nargs="+", type=Path, help=specimens_help)
    c.add_argument("--out-dir", required=True, type=Path, help="folder for the run's cases, netCDF, report and figures")
    c.add_argument("--jobs", type=integer(1, 1024), default=1, help="cases run in parallel (executor local)")
    c.add_argument("--backend", choices=BACKENDS, default="cpu",
                   help="cpu: in the executor's pool; cuda: every case in one GPU batch")
    c.add_argument("--executor", choices=KINDS, help="where the cpu cases run (default: the config's "
                   "executor.kind): local processes, a running Dask scheduler, or workers submitted "
                   "to slurm, pbs, sge or lsf")
    c.add_argument("--scheduler-address", help="executor dask: the scheduler's address (default: the "
                   "config's executor.scheduler_address)")
    c.add_argument("--strength-envelope", type=Path, help="the specimens' strength envelope "
                   "(case envelope), for the config's stress_mapping strength_ratio")
    add_config(c)
    add_quiet(c)
