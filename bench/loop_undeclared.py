"""Data with an undeclared effect (issue 14), measured: "measured" tests made by the model
itself with one candidate effect at a strength the data do not state (loop/synthetic.py:
11-35 digitised points uneven in ln N, 1 % noise), then `ballaststudy loop` on them. Prints,
per scenario, the effect chosen and each candidate's evidence (gain, tests better, Wilcoxon
p, held-out RMSE against the plain model's). The scenarios' model runs share one case cache.
The slow test tests/loop/test_undeclared.py runs the same scenarios at the default settings.

    python bench/loop_undeclared.py OUT_DIR [none rate abrasion fouling end_restraint]
        [--cases K] [--cycles N] [--design-sets S]
        [--stones M --stone-size LO HI --ball-radius R]   # the library (m)
        [--fresh]    # the truth on fresh specimens (their scatter too; specimen_share 1)
                     # instead of the loop's own (common random numbers; share 0)
"""
import argparse
import json
import time
from pathlib import Path

import numpy as np
import xarray as xr
import yaml

from ballaststudy.cli import main
from ballaststudy.loop.synthetic import PlantedTest, plant

ROOT = Path(__file__).resolve().parents[1]
# eight tests: every candidate's rule can pass (one-sided signed-rank over 8 tests at
# 0.05 / 4), each test declaring a VCI (fouling acts through it), p and f varied
TESTS = [PlantedTest(p, 10.0, 50.0, f, vci) for p, f, vci in zip(
    [30, 40, 30, 40, 30, 40, 30, 40], [5, 10, 15, 20, 30, 40, 50, 60], [10, 20, 30, 40, 50, 60, 70, 80])]
BASE = {"F_str_co": 1.0}           # weak joints, so wear can break them within a few cycles
TRUTH = {"none": {}, "rate": {"contact_damping_ratio": 0.3}, "abrasion": {"wear_per_cycle": 0.12},
         "fouling": {"friction_loss": 0.6}, "end_restraint": {"platen_friction": 0.2}}


def setup(d, args):
    from ballaststudy.rig.library import synthetic_library
    if not (d / "BPM.nc").exists():
        synthetic_library(args.stones, size=tuple(args.stone_size), r0=args.ball_radius, seed=3,
                          database="tiny").to_netcdf(d / "BPM.nc")
    cfg = yaml.safe_load((ROOT / "config/config.yaml").read_text())
    cfg["databases_file"] = str(ROOT / cfg["databases_file"])
    cfg["rig"]["biaxial"]["loading"]["consolidation_window_steps"] = 1000
    cfg["loop"].update(cases=args.cases, cycles=args.cycles, design_sets=args.design_sets,
                       measurement_sd=1e-5, posterior_samples=4096, specimen_share=1.0 if args.fresh else 0.0)
    (d / "config.yaml").write_text(yaml.safe_dump(cfg))
    (d / "base.yaml").write_text(yaml.safe_dump({"parameters": BASE}))
    names = [f"s{k}" for k in range(args.cases)] + [f"fresh{k}" for k in range(args.cases)] * args.fresh
    for k, name in enumerate(names):
        if not (d / f"{name}.nc").exists():
            main(["case", "assemble", str(d / "BPM.nc"), "--case", str(k), "--rig", "biaxial", "--width-m", "0.12",
                  "--height-m", "0.24", "--config", str(d / "config.yaml"), "--out", str(d / f"{name}.nc"), "--quiet"])
    return [d / f"s{k}.nc" for k in range(args.cases)], [d / f"{n}.nc" for n in names[args.cases:]]


def scenario(d, name, specimens, fresh, args):
    folder = d / name
    t0 = time.time()
    measured, conditions = plant(folder / "tests", TESTS, fresh or specimens, d / "config.yaml", args.cycles,
                                 None if name == "none" else name, TRUTH[name], BASE, cache=d, jobs=2)
    out = folder / "loop"
    out.mkdir(parents=True, exist_ok=True)
    if not (out / "cases").exists():
        (out / "cases").symlink_to(d / "cases")
    main(["loop", *map(str, measured), "--conditions", *map(str, conditions), "--specimens", *map(str, specimens),
          "--parameters", str(d / "base.yaml"), "--out-dir", str(out), "--jobs", "2", "--config",
          str(d / "config.yaml"), "--quiet"])
    chosen = yaml.safe_load((out / "chosen.yaml").read_text())["effect"]
    with xr.open_dataset(out / "loop.nc") as ds:
        cands = json.loads(ds.attrs["candidates_json"])
        plain = float(np.sqrt(np.mean((ds["measured"].values - ds["plain_prediction"].values) ** 2)))
    print(f"planted {name} {TRUTH[name]} -> chosen {chosen} | plain RMSE {plain:.2e} | "
          f"{(time.time() - t0) / 60:.1f} min", flush=True)
    for c in cands:
        print(f"    {c['effect']:13s} gain {c['gain']:9.3g}  {c['wins']}/{c['tests']} better  p {c['p']:.2g}  "
              f"held-out RMSE {c['held_out_rmse']:.2e}  fitted {np.round(c['mean'], 3).tolist()}", flush=True)


def parse():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("scenarios", nargs="*", default=list(TRUTH))
    ap.add_argument("--cases", type=int, default=3)
    ap.add_argument("--cycles", type=int, default=12)
    ap.add_argument("--design-sets", type=int, default=5)
    ap.add_argument("--stones", type=int, default=24, help="stones in the library")
    ap.add_argument("--stone-size", type=float, nargs=2, default=[0.035, 0.065], metavar=("LO", "HI"))
    ap.add_argument("--ball-radius", type=float, default=0.008)
    ap.add_argument("--fresh", action="store_true")
    return ap.parse_args()


if __name__ == "__main__":
    args = parse()
    args.out.mkdir(parents=True, exist_ok=True)
    specimens, fresh = setup(args.out, args)
    for s in args.scenarios:
        scenario(args.out, s, specimens, fresh, args)
