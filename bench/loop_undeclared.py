"""Data with an undeclared effect (issue 14), measured: "measured" tests made by the model
itself with one candidate effect at a strength the data do not state (tests/loop/synthetic.py:
11-35 digitised points uneven in ln N, 1 % noise), then `ballaststudy loop` on them. Prints,
per scenario, the effect chosen and each candidate's evidence (gain, tests better, Wilcoxon
p, held-out RMSE against the plain model's) and, per test, the planted effect's held-out RMSE
over the plain model's, and the planted truth's irreducible RMSE: its own chaos (the truth
run again from perturbed velocities) and the digitiser's noise, which no surrogate over
other parameter values can beat - where it exceeds half the plain model's RMSE, the goal
of halving is out of reach at that scale. The scenarios' model runs share one case cache.
The slow test tests/loop/test_undeclared.py asserts the same scenarios at their defaults.

    python bench/loop_undeclared.py OUT_DIR [none rate abrasion fouling end_restraint stiffer_contact]
        [--cases K] [--cycles N] [--design-sets S] [--refine-rounds R] [--refine-sets S]
        [--stones M --stone-size LO HI --ball-radius R]   # the library (m)
        [--size-m W H]   # the specimens' width and height (m)
        [--fresh]    # the truth on K fresh specimens (their scatter too; specimen_share 1)
                     # instead of the loop's own (common random numbers; share 0)
        [--fresh-per-test]  # K fresh specimens per test, as a laboratory builds one per test
        [--probes M]  # chaos probes of each truth for its irreducible RMSE (default 3)
"""
import argparse
import sys
import time
from pathlib import Path

import numpy as np

from ballaststudy.calibration.bayes import rmse
from ballaststudy.loop.cli import PROBE_M_S

ROOT = Path(__file__).resolve().parents[1]
# the planted scenarios are a test helper (tests/loop/synthetic.py), not part of the package;
# it imports its sibling helpers relatively, so it is imported as tests.loop.synthetic
sys.path.insert(0, str(ROOT))
from tests.loop.synthetic import (NOISE_SHARE, OUT_OF_LIBRARY, PLANTED, SCENARIO_BASE,  # noqa: E402
                                  SCENARIO_TESTS, irreducible_rmse, run_scenario, scenario_setup, truth_runs)


def per_test_rmse(loop_nc, effect):
    """(plain, the effect's held-out) RMSE per test: the pooled RMSE is led by the test of
    the largest strain (one specimen of K giving way under the effect is one such test)."""
    import xarray as xr
    with xr.open_dataset(loop_nc) as ds:
        y, test = ds["measured"].values, ds["point_test"].values
        held = ds["held_out_prediction"].values[list(ds["effect"].values).index(effect)]
        plain = ds["plain_prediction"].values
    return np.array([[rmse(y[test == t], m[test == t]) for m in (plain, held)] for t in np.unique(test)])


def verdict_of(loop_nc):
    """The verdict and the discrepancy per source (plain model) a loop.nc reports."""
    import json
    import xarray as xr
    with xr.open_dataset(loop_nc) as ds:
        disc = json.loads(ds.attrs["discrepancy_json"])
        return ds.attrs["verdict"] + " | discrepancy (plain): " + "; ".join(
            f"{d['source'][:20]} {dict(zip(d['terms'], (round(m, 7) for m in d['plain']['mean'])))} "
            f"size {d['plain']['size']:.2e}" for d in disc)


def attainable(out, name, specimens, cycles, plain_per_test, plain, probes):
    """Print the planted scenario's irreducible RMSE (synthetic.irreducible_rmse: the truth
    run again from ``probes`` perturbations, K more cases each) against its plain model's:
    the goal - half the plain RMSE - is out of any surrogate's reach where it is above half."""
    import xarray as xr
    conditions = [out / name / "tests" / f"t{j}.yaml" for j in range(len(SCENARIO_TESTS))]
    run = [conditions, specimens, out / "config.yaml", cycles, out, name, PLANTED[name], SCENARIO_BASE, 2]
    runs = truth_runs(*run)
    probe = [truth_runs(*run, perturbation_m_s=PROBE_M_S, probe=m) for m in range(probes)]
    with xr.open_dataset(out / name / "loop" / "loop.nc") as ds:
        n, test = ds["measured_cycle"].values, ds["point_test"].values
    per_test, pooled = irreducible_rmse(runs, probe, n, test, NOISE_SHARE * np.abs(runs.mean(axis=1)[:, -1]))
    print(f"    irreducible RMSE (the truth's chaos + the digitiser's noise) {pooled:.2e} = {pooled / plain:.2f} x the "
          f"plain model's: halving {'within' if pooled <= 0.5 * plain else 'beyond'} reach; per test / plain: "
          + " ".join(f"{a / b:.2f}" for a, b in zip(per_test, plain_per_test)), flush=True)


def parse():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("scenarios", nargs="*", default=list(PLANTED), choices=[*PLANTED, *OUT_OF_LIBRARY])
    ap.add_argument("--cases", type=int, default=3)
    ap.add_argument("--cycles", type=int, default=24)
    ap.add_argument("--design-sets", type=int, default=9)
    ap.add_argument("--refine-rounds", type=int, default=2)
    ap.add_argument("--refine-sets", type=int, default=4)
    ap.add_argument("--stones", type=int, default=24, help="stones in the library")
    ap.add_argument("--stone-size", type=float, nargs=2, default=[0.035, 0.065], metavar=("LO", "HI"))
    ap.add_argument("--ball-radius", type=float, default=0.008)
    ap.add_argument("--size-m", type=float, nargs=2, default=None, metavar=("W", "H"))
    ap.add_argument("--fresh", action="store_true")
    ap.add_argument("--fresh-per-test", action="store_true")
    ap.add_argument("--probes", type=int, default=3, help="chaos probes of each truth (irreducible RMSE)")
    ap.add_argument("--value", type=float, default=None,
                    help="the planted effects' parameter value instead of PLANTED's (one-parameter effects)")
    return ap.parse_args()


if __name__ == "__main__":
    args = parse()
    setup = {"size_m": tuple(args.size_m)} if args.size_m else {}
    setup.update(refine_rounds=args.refine_rounds, refine_sets=args.refine_sets)
    library = dict(n_stones=args.stones, size=tuple(args.stone_size), r0=args.ball_radius)
    args.fresh = args.fresh or args.fresh_per_test
    specimens, config, _ = scenario_setup(args.out, ROOT / "config/config.yaml", args.cases, args.cycles,
                                          args.design_sets, 1.0 if args.fresh else 0.0, library, **setup)
    fresh = None
    if args.fresh:      # more specimens of the same library (cases K .. 2K-1, or K .. (T + 1) K - 1)
        sets = len(SCENARIO_TESTS) if args.fresh_per_test else 1
        fresh, _, _ = scenario_setup(args.out / "fresh", ROOT / "config/config.yaml", args.cases, args.cycles,
                                     args.design_sets, 1.0, library, assemble=(sets + 1) * args.cases, **setup)
        fresh = fresh[args.cases:]
        if args.fresh_per_test:
            fresh = [fresh[j * args.cases:(j + 1) * args.cases] for j in range(sets)]
    for name in args.scenarios:
        t0 = time.time()
        values = ({k: args.value for k in PLANTED[name]} if args.value is not None and PLANTED.get(name) else None)
        chosen, candidates, plain = run_scenario(args.out, name, specimens, args.cycles, fresh, values=values)
        print(f"planted {name} {values or PLANTED.get(name, OUT_OF_LIBRARY.get(name))} -> chosen {chosen} | "
              f"plain RMSE {plain:.2e} | "
              f"{(time.time() - t0) / 60:.1f} min", flush=True)
        for c in candidates:
            print(f"    {c['effect']:13s} gain {c['gain']:9.3g}  {c['wins']}/{c['tests']} better  p {c['p']:.2g}  "
                  f"cut/scatter {c['mse_cut'] / c['scatter_mse']:+.2f}  "
                  f"width/prior {c['interval_notes'][0]['width_share']:.2f}{' at ' + c['interval_notes'][0]['at_edge'] + ' edge' if c['interval_notes'][0]['at_edge'] else ''}  "
                  f"excludes no-effect {c['interval_notes'][0]['excludes_no_effect']}  "
                  f"held-out RMSE {c['held_out_rmse']:.2e}  fitted {np.round(c['mean'], 3).tolist()} "
                  f"(90 % {np.round(c['interval90'], 3).tolist()})", flush=True)
        folder = args.out / (name + ("_" + "_".join(f"{v:g}" for v in values.values()) if values else ""))
        print(f"    verdict: {verdict_of(folder / 'loop' / 'loop.nc')}", flush=True)
        if name in PLANTED and name != "none":
            r = per_test_rmse(folder / "loop" / "loop.nc", name)
            print(f"    per test, {name}'s held-out RMSE / the plain model's: "
                  + " ".join(f"{b / a:.2f}" for a, b in r) + "; plain RMSE " + " ".join(f"{a:.1e}" for a, _ in r),
                  flush=True)
            if not args.fresh and not values:      # fresh truths carry their specimens' offsets as well
                attainable(args.out, name, specimens, args.cycles, r[:, 0], plain, args.probes)
