"""Coverage of the loop's 90 % intervals by simulation (issue 75; simulation-based
calibration, Talts et al. 2018): DEM truths made on specimens the loop never saw, run
through the unchanged loop, counted.

Each truth plants one candidate effect at a value drawn uniformly from its design range
(the loop's prior), or none, on the 8 planted tests of tests/loop/synthetic.py, and is
"measured" on fresh specimens of the same library: one specimen under every test (one lab
specimen: what all tests share is its offset) or one per test (as a laboratory builds one
for each test) - the loop's noise model says a measured curve scatters like one of its
specimens (specimen_share 1). The loop runs on its own K specimens at a grid of
`--design-sets` values per candidate, no refinement: those runs are made once and shared
by every truth (common random numbers); only the truths are new runs. Truths are run in
order and each is written as it ends, so an interrupted run resumes where it stopped.

Writes OUT/truths.csv (per truth and candidate: the interval, whether it holds the planted
value or, for a candidate of a truth with nothing planted, does not exclude its no-effect
value (an interval half the prior's width or wider excludes nothing: loop/trust.py), the choice, the
rule's pick were the curves like ours (`named`: not adopted where they stray), the verdict, the
smallest detectable effect, how far the truth's specimens stray from the loop's, `unlike`
beyond loop/trust.py's limit, `own_stray`: the candidate's held-out rms over the root of its
own specimens' scatter) and OUT/coverage.csv (per planted effect and in all: truths,
`coverage` of the 90 % intervals with its Clopper-Pearson 90 % interval, the same among the
truths whose specimens the report did not call unlike ours, `false_choices`, `named_wrong`
(a wrong pick named, not adopted),
the planted effect chosen and the smallest planted value chosen, the largest missed, the
intervals' width over the prior's), and prints the table. Each truth's rows also give the
candidate's effect size (rms of its fitted curve minus the plain model's).

    python bench/loop_coverage.py OUT [--truths 30] [--none-share 0.34] [--cases 3]
        [--cycles 24] [--design-sets 9] [--pool 24] [--own-share 0] [--effects rate abrasion ...] [--jobs 2]
        [--plan-seed 0]    # another seed: other truths on the same specimens (a held-out confirmation)
"""
import argparse
import csv
import json
import sys
import time
from pathlib import Path

import numpy as np
import xarray as xr
import yaml
from scipy.stats import binomtest

from ballaststudy.loop.select import ALPHA, STRAY_LIMIT, pick, stray as own_stray
from ballaststudy.scenario.modifiers import EFFECTS, MODIFIERS

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))        # the planted scenarios are a test helper (bench/loop_undeclared.py)
from tests.loop.synthetic import SCENARIO_BASE, SCENARIO_TESTS, plant, run_loop, scenario_setup  # noqa: E402

LEVEL = 0.9
DEFAULT_EFFECTS = yaml.safe_load((ROOT / "config/config.yaml").read_text())["loop"]["effects"]


def truth_plan(n, none_share, effects, pool, seed=0, own_share=0.0, cases=3):
    """[{truth, planted, value, specimens, source, pool}] of n truths in a shuffled order:
    round(n x none_share) with no effect, the rest cycling through ``effects`` at values
    uniform in their ranges; shared and per-test specimens alternating; fresh specimens
    taken from a pool of ``pool`` in turn (a specimen serves several truths once the pool
    is used up, never the loop); round(n x own_share) of them (source 'own') measured on
    the loop's own ``cases`` specimens instead, where its noise model holds (a positive
    control: its intervals should cover there)."""
    rng = np.random.default_rng(seed)
    nones = int(round(n * none_share))
    kinds = ["none"] * nones + [effects[i % len(effects)] for i in range(n - nones)]
    kinds = [kinds[i] for i in rng.permutation(n)]
    own = set(np.random.default_rng(seed + 1).permutation(n)[:int(round(n * own_share))].tolist())
    plan, taken = [], 0
    for i, planted in enumerate(kinds):
        p = MODIFIERS[planted].parameters[0] if planted != "none" else None
        value = float(rng.uniform(p.low, p.high)) if p else float("nan")
        shared = i % 2 == 0
        width = 1 if shared else len(SCENARIO_TESTS)
        source = "own" if i in own else "fresh"
        start, size = (i, cases) if source == "own" else (taken, pool)
        plan.append(dict(truth=i, planted=planted, value=value, specimens="shared" if shared else "per_test",
                         source=source, pool=[(start + j) % size for j in range(width)]))
        taken += width if source == "fresh" else 0
    return plan


def run_truth(out, t, specimens, fresh, cycles, jobs):
    """Plant truth ``t`` and run the loop on it; its loop.nc's path (reused if there)."""
    folder = out / f"truth{t['truth']:03d}"
    loop_dir = folder / "loop"
    if (loop_dir / "loop.nc").exists():
        return loop_dir / "loop.nc"
    mine = [(specimens if t.get("source") == "own" else fresh)[k] for k in t["pool"]]
    truth_specimens = mine if t["specimens"] == "shared" else [[s] for s in mine]
    effect = None if t["planted"] == "none" else t["planted"]
    values = {MODIFIERS[effect].parameters[0].name: t["value"]} if effect else {}
    measured, conditions = plant(folder / "tests", SCENARIO_TESTS, truth_specimens, out / "config.yaml", cycles,
                                 effect, values, SCENARIO_BASE, seed=t["truth"], cache=out, jobs=jobs)
    return run_loop(out, loop_dir, measured, conditions, specimens, jobs) / "loop.nc"


def truth_rows(t, loop_nc):
    """Per candidate of one truth: its interval and what it holds (module doc)."""
    with xr.open_dataset(loop_nc) as ds:
        candidates = json.loads(ds.attrs["candidates_json"])
        chosen, kind = ds.attrs["chosen"], ds.attrs["verdict_class"]
        named = pick({c["effect"]: c for c in candidates}, len(candidates), alike=False) or "none"
        detect = json.loads(ds.attrs["detectable_json"])
        stray = json.loads(ds.attrs.get("specimen_stray_json", "{}")).get("ratio", float("nan"))
        sizes = {name: e["effect_size"] for row in json.loads(ds.attrs["discrepancy_json"])
                 for name, e in row["candidates"].items()}
    rows = []
    for c in candidates:
        (lo, hi), note = c["interval90"][0], c["interval_notes"][0]
        planted = c["effect"] == t["planted"]
        # a candidate's no-effect value is the truth only where nothing is planted: under another
        # planted effect it may rightly move to mimic it
        target = t["value"] if planted else note["no_effect"] if t["planted"] == "none" else None
        rows.append(dict(truth=t["truth"], planted=t["planted"], value=t["value"], specimens=t["specimens"],
                         source=t["source"],
                         candidate=c["effect"], mean=c["mean"][0], lo=lo, hi=hi,
                         width_share=note["width_share"], at_edge=note["at_edge"],
                         against="planted" if planted else ("no_effect" if target is not None else ""),
                         holds="" if target is None else int(lo <= target <= hi if planted
                                                             else not note["excludes_no_effect"]),
                         chosen=chosen, named=named, verdict=kind, effect_size=sizes.get(c["effect"], float("nan")),
                         detectable=detect.get(c["effect"], {}).get("smallest", float("nan")),
                         stray=stray, unlike=int(stray > STRAY_LIMIT), own_stray=own_stray(c)))
    return rows


def _ci(k, n):
    if n == 0:
        return float("nan"), float("nan")
    ci = binomtest(k, n).proportion_ci(LEVEL, method="exact")
    return float(ci.low), float(ci.high)


def summary(rows):
    """Per planted effect (and 'all'): the coverage of the planted effect's interval, the
    no-effect coverage of the other candidates, false choices, the planted effect chosen."""
    truths = {r["truth"]: r for r in rows}
    out = []
    groups = sorted({r["planted"] for r in rows}) + ["all"]
    for g in groups:
        ts = [t for t in truths.values() if g == "all" or t["planted"] == g]
        own = [r for r in rows if (g == "all" or r["planted"] == g) and r["against"] == "planted"]
        off = [r for r in rows if (g == "all" or r["planted"] == g) and r["against"] == "no_effect"]
        false = sum(t["chosen"] not in ("none", t["planted"]) for t in ts)
        named_wrong = sum(t["chosen"] == "none" and t["named"] not in ("none", t["planted"]) for t in ts)
        right = sum(t["chosen"] == t["planted"] for t in ts if t["planted"] != "none")
        k = sum(r["holds"] for r in own)
        lo, hi = _ci(k, len(own))
        chosen_values = [t["value"] for t in ts if t["planted"] != "none" and t["chosen"] == t["planted"]]
        missed_values = [t["value"] for t in ts if t["planted"] != "none" and t["chosen"] != t["planted"]]
        alike = [r for r in own if not r["unlike"]]
        out.append(dict(planted=g, truths=len(ts), coverage=k / len(own) if own else float("nan"),
                        coverage_lo=lo, coverage_hi=hi, unlike=sum(t["unlike"] for t in ts),
                        coverage_alike=sum(r["holds"] for r in alike) / len(alike) if alike else float("nan"),
                        no_effect_coverage=sum(r["holds"] for r in off) / len(off) if off else float("nan"),
                        false_choices=false, false_choice_rate=false / len(ts) if ts else float("nan"),
                        chosen_right=right, named_wrong=named_wrong, width_share=float(np.mean([r["width_share"] for r in own]))
                        if own else float("nan"),
                        none_truths=sum(t["planted"] == "none" for t in ts),
                        smallest_value_chosen=min(chosen_values, default=float("nan")),
                        largest_value_missed=max(missed_values, default=float("nan"))))
    return out


def write_csv(path, rows):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


def parse():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("--truths", type=int, default=30)
    ap.add_argument("--none-share", type=float, default=0.34)
    ap.add_argument("--cases", type=int, default=3)
    ap.add_argument("--cycles", type=int, default=24)
    ap.add_argument("--design-sets", type=int, default=9)
    ap.add_argument("--pool", type=int, default=24, help="fresh specimens the truths take in turn")
    ap.add_argument("--own-share", type=float, default=0.0,
                    help="share of the truths measured on the loop's own specimens (a positive control)")
    ap.add_argument("--effects", nargs="+", default=DEFAULT_EFFECTS, choices=EFFECTS,
                    help="the candidates (default: the shipped config's loop.effects)")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--plan-seed", type=int, default=0, help="seed of the truths' plan (effects, values, order)")
    return ap.parse_args()


if __name__ == "__main__":
    args = parse()
    args.out.mkdir(parents=True, exist_ok=True)
    specimens, config, _ = scenario_setup(args.out, ROOT / "config/config.yaml", args.cases, args.cycles,
                                          args.design_sets, 1.0, refine_rounds=0)
    cfg = yaml.safe_load(config.read_text())
    cfg["loop"]["effects"] = list(args.effects)
    config.write_text(yaml.safe_dump(cfg))
    fresh, _, _ = scenario_setup(args.out / "fresh", ROOT / "config/config.yaml", args.cases, args.cycles,
                                 args.design_sets, 1.0, refine_rounds=0, assemble=args.cases + args.pool)
    fresh = fresh[args.cases:]                    # the loop's own are cases 0 .. K - 1
    plan = truth_plan(args.truths, args.none_share, list(args.effects), args.pool, seed=args.plan_seed,
                      own_share=args.own_share, cases=args.cases)
    rows = []
    t0 = time.time()
    for t in plan:
        start = time.time()
        loop_nc = run_truth(args.out, t, specimens, fresh, args.cycles, args.jobs)
        rows += truth_rows(t, loop_nc)
        write_csv(args.out / "truths.csv", rows)
        chosen = rows[-1]["chosen"]
        print(f"truth {t['truth']:3d} {t['planted']:13s} {t['value']:.3g} ({t['source']}, {t['specimens']}): "
              f"chosen {chosen}, "
              f"verdict {rows[-1]['verdict']} | {(time.time() - start) / 60:.1f} min", flush=True)
    table = summary(rows)
    write_csv(args.out / "coverage.csv", table)
    print(f"\n{len(plan)} truths, {(time.time() - t0) / 3600:.2f} h on {args.jobs} jobs this invocation; the rule's "
          f"nominal false-choice rate: at most {ALPHA:g} (Bonferroni over {len(args.effects)} candidates)")
    for r in table:
        print(f"{r['planted']:13s} truths {r['truths']:3d}  coverage {r['coverage']:.2f} [{r['coverage_lo']:.2f}, "
              f"{r['coverage_hi']:.2f}] (specimens alike: {r['coverage_alike']:.2f}, unlike: {r['unlike']})  no-effect coverage {r['no_effect_coverage']:.2f}  false choices "
              f"{r['false_choices']}/{r['truths']} (named, not adopted, wrong: {r['named_wrong']})  chosen right "
              f"{r['chosen_right']}  width/prior {r['width_share']:.2f}")
