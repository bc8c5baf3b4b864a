"""`ballaststudy loop`: close the loop with measured data (issue 14).

    ballaststudy loop results/measured/<t1>.nc ... --conditions config/measured/<t1>.yaml ...
        --specimens S0.nc S1.nc ... --out-dir results/loop [--parameters calibrated.yaml]
        [--horizon results/horizon/horizon.nc] [--jobs 2] [--config config/config.yaml]

1. The plain model (Table 4.2's or calibrated parameters): K cases under every test; the
   residual per test in the DEM horizon (loop/residual.py) and its relation to the tests'
   covariates.
2. Every candidate effect (a modifier of role effect, scenario.modifiers): K cases under every test at a design of its
   parameter, refined `refine_rounds` times around its held-out posteriors (refined_design);
   held-out (leave one test out) predictive densities and the rule (loop/select.py) choose
   one effect or none. With specimen_share 0 (model-made data on
   these specimens) the plain cases run once more from perturbed velocities: the chaos
   probe, the noise model's scale.
3. The chosen effect at its parameter fitted on all tests, run again: the error after.
4. The long-term horizon: the accumulation law the measured curves chose (--horizon, from
   `ballaststudy horizon`) fitted to each ensemble carries it to the measured points beyond
   the simulated cycles, with that law's error on measured curves, reported apart.
Writes loop.nc, report.md, chosen.yaml and one figure per test into the folder; the cases
are cached by parameter hash under cases/ (an interrupted loop resumes)."""
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..calibration.bayes import initial_design
from ..calibration.cli import checked_targets, target_arguments
from ..calibration.evaluate import Evaluator
from ..config import ConfigError, job_seed, load_config
from ..inputs import open_netcdf, writable_dir
from ..measured.importer import load_conditions
from ..provenance import Recorder
from ..scenario.mapping import stage_mapping
from ..scenario.modifiers import EFFECTS, MODIFIERS, load_material_values
from ..cluster.pool import case_pool
from ..cluster.spec import executor_spec
from ..scenario.runner import check_backend
from ..scenario.scenario import check_stone_model, splitting_of
from ..stones import DEFAULT
from .discrepancy import make_discrepancy, source_name
from .horizon import chosen_for
from .outcome import LoopRun, PlainModel, Selection, Targets
from .report import write_outputs
from .select import (NoiseModel, candidate_covariances, choose, held_out_plain, judge_candidate, residual_covariances,
                     residual_dof, scatter_mse)

# the chaos probe's velocity perturbation (specimen_share 0): far below any physical speed
# of the test; the chaos it starts is saturated - runs perturbed by 1e-9, 1e-6 and 1e-4 m/s
# part from the unperturbed ones by the same amount (12 cycles, 24-stone specimens)
PROBE_M_S = 1e-9


def check_loop_targets(cfg, config_file, tests, tests_dir):
    """Every loop.effects entry an effect of the registry; every loop.targets entry a
    measured triaxial/biaxial test (names relative to
    measured.tests_dir) when there are any, each once; ConfigError naming the key."""
    for k, name in enumerate(cfg["loop"]["effects"]):
        if name not in EFFECTS:
            raise ConfigError(config_file, f"loop.effects[{k}]", f"{name!r} is not an effect; allowed: "
                              f"{', '.join(EFFECTS)}")
    targets = cfg["loop"]["targets"]
    for k, target in enumerate(targets):
        if tests and target not in tests:
            raise ConfigError(config_file, f"loop.targets[{k}]", f"{target!r} is not a measured test "
                              f"under {cfg['measured']['tests_dir']}; allowed: {', '.join(tests)}")
        if targets.index(target) != k:
            raise ConfigError(config_file, f"loop.targets[{k}]", f"{target!r} given twice; allowed: each test once")
        if tests and load_conditions(Path(tests_dir) / f"{target}.yaml")["rig"] not in ("triaxial", "biaxial"):
            raise ConfigError(config_file, f"loop.targets[{k}]", f"{target!r} is a box test; allowed: "
                              "triaxial or biaxial tests (the effects act on the biaxial rig)")


def _points(args, cfg):
    """[(N, values)] of every target within the simulated cycles, checked like calibrate's;
    biaxial specimens only."""
    measured, kind = checked_targets(args, cfg["loop"], "loop")
    if kind != "biaxial":
        raise ConfigError(args.specimens[0], "rig_kind", f"{kind}; allowed: biaxial specimens (the "
                          "effects act on the cyclic biaxial test)")
    return measured


def design(lower, upper, n, seed):
    """(n, d) design sets of a candidate: one parameter on an even grid from bound to bound
    (the surrogate never extrapolates, and an effect's bound where it is off - no wear, no
    fouling - is run: without it the posterior drifted to the unrun end, where the
    surrogate's width alone fitted the data); more parameters a Latin hypercube."""
    if len(lower) == 1:
        return np.linspace(lower[0], upper[0], n)[:, None]
    return initial_design(lower, upper, n, seed)


def refined_design(theta_means, lower, upper, spacing, n, seed):
    """(n, d) sets of one refinement round: spread over the box around the held-out
    posterior means (theta_means (T, d), one per left-out test) widened by 3/4 of
    ``spacing`` (d,) each side, within the bounds; one parameter the midpoints of n equal
    cells (never a bound: the grid has run those), more a Latin hypercube.
    Why a window and not draws from the posterior (calibration's next_batch): an effect
    that makes specimens give way at one end of its range responds with a cliff the
    surrogate cannot follow between two grid sets, and the posterior snaps onto one set
    (the end-restraint scenario: 0.30 +- 0.002 for a planted 0.20); draws from it would
    pile onto that set. The window reaches into the grid cells on both sides; halving
    ``spacing`` each round zooms in. Where the sets go depends on the tests (each fold's
    posterior leaves one out, their union does not); a held-out test is still predicted
    from the other tests' posterior only."""
    theta_means = np.atleast_2d(theta_means)
    lo = np.maximum(lower, theta_means.min(axis=0) - 0.75 * spacing)
    hi = np.minimum(upper, theta_means.max(axis=0) + 0.75 * spacing)
    if len(lo) == 1:
        return (lo + (np.arange(n) + 0.5) * (hi - lo) / n)[:, None]
    return initial_design(lo, hi, n, seed)


def _run_candidates(make, names, lp, seed):
    """{effect: (thetas (J, d), [(K, P)] per set, Evaluator)}: every design set under every test."""
    out = {}
    for name in names:
        eff = MODIFIERS[name]
        thetas = design(*_bounds(name), lp["design_sets"], job_seed(seed, f"loop/{name}"))
        evaluate = make([p.name for p in eff.parameters], name)
        out[name] = (thetas, evaluate(thetas), evaluate)
    return out


def _bounds(name):
    ps = MODIFIERS[name].parameters
    return np.array([p.low for p in ps]), np.array([p.high for p in ps])


@dataclass
class Candidate:
    """One candidate effect's runs and how it was judged."""
    thetas: np.ndarray       # (J, d) design sets
    at: list                 # J arrays (K, P): its cases at the measured points
    held: object             # select.HeldOut of the candidate
    fit: tuple               # select.fit_all: (mean (d,), interval90 (d, 2), ess)
    sampled: object          # select.Sampled: its surrogate over the prior sample, the posterior
    evaluate: object         # its calibration.evaluate.Evaluator (sets: every run, design first)


def _refine(runs, plain_at, probe_at, y, point_test, lp, seed, dof, disc):
    """_judge after ``refine_rounds`` rounds of refined_design sets added to every
    candidate's runs (in place; the grid's spacing halved each round)."""
    candidates, plain, noise = _judge(runs, plain_at, probe_at, y, point_test, lp, seed, dof, disc)
    for r in range(lp["refine_rounds"]):
        for name, (thetas, at, evaluate) in runs.items():
            lower, upper = _bounds(name)
            spacing = (upper - lower) / (lp["design_sets"] - 1) / 2 ** r
            new = refined_design(candidates[name].held.theta_mean, lower, upper, spacing, lp["refine_sets"],
                                 job_seed(seed, f"loop/{name}/refine{r}"))
            runs[name] = (np.vstack([thetas, new]), at + evaluate(new), evaluate)
        candidates, plain, noise = _judge(runs, plain_at, probe_at, y, point_test, lp, seed, dof, disc)
    return candidates, plain, noise


def _judge(runs, plain_at, probe_at, y, point_test, lp, seed, dof, disc):
    """({effect: Candidate}, the plain model's select.HeldOut, select.NoiseModel): every
    candidate and the plain model judged under one noise model, made from the plain runs
    (select.residual_covariances), each candidate's parameters fitted under its own sets'
    scatter (select.candidate_covariances), the t with ``dof`` degrees of freedom, and one
    discrepancy per source (discrepancy.Discrepancy ``disc``)."""
    measurement_var, share = lp["measurement_sd"] ** 2, lp["specimen_share"]
    covs, plain_covs = residual_covariances(plain_at, point_test, measurement_var, share, probe_at)
    plain = held_out_plain(plain_at, y, point_test, plain_covs, dof, disc)
    out, own, own_scatter = {}, {}, {}
    for name, (thetas, at, evaluate) in runs.items():
        own[name], yardstick = candidate_covariances(at, point_test, measurement_var, (covs, plain_covs), share)
        own_scatter[name] = scatter_mse(yardstick, point_test, disc)
        args = (thetas, at, y, point_test, *_bounds(name), covs, lp["posterior_samples"], seed, dof, disc, own[name])
        out[name] = Candidate(thetas, at, *judge_candidate(*args), evaluate)
    return out, plain, NoiseModel(covs, plain_covs, disc, dof, scatter_mse(plain_covs, point_test, disc), own,
                                  own_scatter)


def _long_term_law(path, lp):
    """The horizon table's law for this loop's cycles; the table must be of loop.quantity."""
    table = open_netcdf(path, "horizon")
    if table.attrs.get("quantity") != lp["quantity"]:
        raise ConfigError(path, "quantity", f"{table.attrs.get('quantity')!r}; allowed: the loop's "
                          f"{lp['quantity']!r} (ballaststudy horizon --quantity)")
    return chosen_for(table, lp["cycles"])


def _loop(args):
    check_backend(args.backend)
    cfg = load_config(args.config)
    lp = cfg["loop"]
    out = writable_dir(args.out_dir)
    measured = _points(args, cfg)
    base = load_material_values(args.parameters) if args.parameters else {}
    check_stone_model(cfg, args.config, args.backend, parameters=(args.parameters, base),
                      stages=("loop.effects",))
    long_term_law = _long_term_law(args.horizon, lp) if args.horizon else None
    targets = Targets(args.conditions, args.measured, measured)
    y, point_test = targets.y, targets.point_test
    recorder = Recorder("loop", inputs=(*args.measured, *args.conditions, args.config, *args.specimens,
                                        *([args.parameters] if args.parameters else []),
                                        *([args.horizon] if args.horizon else []),
                                        *([args.strength_envelope] if args.strength_envelope else [])),
                        params={"loop": lp, "base": base, "stress_mapping": cfg.get("stress_mapping"),
                                "stone_model": cfg.get("stone_model", DEFAULT), "splitting": splitting_of(cfg)},
                        seed=cfg["seed"])
    mapping = stage_mapping(cfg, args.config, args.strength_envelope, "biaxial")
    t0 = time.time()
    # the plain cases keep their first-loaded state only for a hook-only candidate (abrasion)
    share = any(MODIFIERS[e].hook_only for e in lp["effects"])

    spec = executor_spec(cfg, args.config, args.executor, args.scheduler_address)

    def make(names, effect=None, perturbation_m_s=0.0):
        return Evaluator(names, args.specimens, [(c, n) for c, (n, _) in zip(args.conditions, measured)],
                         cfg, lp["cycles"], lp["quantity"], out, jobs=args.jobs,
                         progress=not args.quiet, effect=effect, base=base, perturbation_m_s=perturbation_m_s,
                         backend=args.backend, mapping=mapping, share_first_loading=share, pool=pool)

    with case_pool(spec, args.jobs, out / "workers") as pool:
        plain_eval = make([])
        plain_at = plain_eval(np.zeros((1, 0)))[0]
        probe_eval = make([], perturbation_m_s=PROBE_M_S) if lp["specimen_share"] == 0 else None
        probe_at = probe_eval(np.zeros((1, 0)))[0] if probe_eval else None
        conditions = [load_conditions(c) for c in args.conditions]
        untestable = [e for e in lp["effects"] if not MODIFIERS[e].testable(conditions)]
        runs = _run_candidates(make, [e for e in lp["effects"] if e not in untestable], lp, cfg["seed"])
        dof = residual_dof(len(plain_at), lp["specimen_share"])      # the loop runs one chaos probe
        disc = make_discrepancy(y, targets.point_cycle, point_test, [source_name(c) for c in conditions],
                                lp["discrepancy_terms"], lp["discrepancy_prior_sd_share"], plain_at.mean(axis=0))
        candidates, plain, noise = _refine(runs, plain_at, probe_at, y, point_test, lp, cfg["seed"], dof, disc)
        chosen, evidence = choose({k: (c.held, plain) for k, c in candidates.items()}, y,
                                   {k: noise.scatter_of(k) for k in candidates})
        after = None
        if chosen:
            best = candidates[chosen]
            best.evaluate(best.fit[0][None])            # the chosen effect at its fitted value
            after = best.evaluate.sets[-1]
    probe_set = probe_eval.sets[0] if probe_eval else None
    files = write_outputs(out, LoopRun(
        lp, targets,
        PlainModel(plain_eval.sets[0], plain_at.mean(axis=0), plain, probe_set),
        Selection(candidates, evidence, chosen, after, untestable), base, minutes=(time.time() - t0) / 60,
        likelihood_dof=dof, long_term_law=long_term_law, mapping=plain_eval.mapping_records(), noise=noise))
    recorder.finish()
    sets = plain_eval.sets + (probe_eval.sets if probe_eval else []) + [st for c in candidates.values() for st in c.evaluate.sets]
    cases = [f for st in sets for per_test in st["cases"] for f in per_test]  # this run's sets
    # (the cache folder may hold older ones)
    recorder.write_beside(files[0], also=files[1:] + cases)
    if not args.quiet:
        print(f"wrote {out}: effect chosen: {chosen or 'none'}")


def register(subparsers):
    c = subparsers.add_parser("loop", help="residuals, candidate effects on held-out tests, the "
                              "long-term horizon")
    target_arguments(c, "K assembled biaxial specimens (case assemble --rig biaxial)")
    c.add_argument("--parameters", type=Path, help="a calibrated.yaml: the plain model's material "
                   "parameters (default Table 4.2's)")
    c.add_argument("--horizon", type=Path, help="a horizon.nc (ballaststudy horizon): the accumulation law "
                   "the long-term horizon extrapolates with, and its error on measured curves (default: none, "
                   "nothing extrapolated)")
    c.set_defaults(func=_loop)
    return c
