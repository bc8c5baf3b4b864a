"""Data with an undeclared effect (issue 14): "measured" tests made by the model itself with one
candidate effect switched on at a strength the data do not state, digitised like the shared
data (11-19 points per curve, uneven in ln N, 1 % noise), each test on its own fresh
specimen(s); then `ballaststudy loop` on them. Prints, per scenario, the effect the loop chose
and each candidate's evidence (gain, tests better, Wilcoxon p, held-out RMSE vs the plain
model's). A measurement, not a test: at this tiny scale (a 0.12 x 0.24 m specimen of 24
synthetic stones) the specimen-to-specimen scatter may swamp an effect, and this prints how
far the loop gets; the scenarios' model runs are shared (one case cache).

    python bench/loop_undeclared.py OUT_DIR [none rate abrasion fouling end_restraint]
        [--truth-specimens M]   # "measured" = mean of M fresh specimens (a larger specimen's
                                # lower scatter; default 1)
        [--truth-from-model]    # "measured" = mean of the model's own K specimens with the
                                # effect (common random numbers: the effect's signature
                                # without a new specimen's scatter)
        [--specimen-share S]    # loop.specimen_share (default 1)
"""
import argparse
import json
import math
import shutil
from pathlib import Path

import numpy as np
import xarray as xr
import yaml

from ballaststudy.calibration.runner import case_curve, run_case
from ballaststudy.cli import main
from ballaststudy.config import load_config
from ballaststudy.measured.importer import import_test, load_conditions
from ballaststudy.rig.biaxial import BiaxialParams

ROOT = Path(__file__).resolve().parents[1]
CYCLES, K, TESTS = 20, 3, 7
P, F, VCI = [30, 30, 40, 30, 40, 30, 40], [5, 10, 20, 30, 40, 50, 60], [0, 10, 20, 40, 50, 70, 80]
BASE = {"F_str_co": 1.0}           # weak joints, so wear can break them within a few cycles
TRUTH = {"rate": {"contact_damping_ratio": 0.3}, "abrasion": {"wear_per_cycle": 0.15},
         "fouling": {"friction_loss": 0.6}, "end_restraint": {"platen_friction": 0.05}, "none": {}}


def setup(d, truth_specimens, specimen_share):
    from ballaststudy.rig.library import synthetic_library
    synthetic_library(24, size=(0.035, 0.065), r0=0.008, seed=3, database="tiny").to_netcdf(d / "BPM.nc")
    cfg = yaml.safe_load((ROOT / "config/config.yaml").read_text())
    cfg["databases_file"] = str(ROOT / cfg["databases_file"])
    cfg["rig"]["biaxial"]["loading"]["consolidation_window_steps"] = 1000
    cfg["loop"].update(cases=K, cycles=CYCLES, design_sets=3, measurement_sd=1e-5, posterior_samples=2048,
                       specimen_share=specimen_share)
    (d / "config.yaml").write_text(yaml.safe_dump(cfg))
    (d / "base.yaml").write_text(yaml.safe_dump({"parameters": BASE}))
    for k in list(range(K)) + [100 + i for i in range(TESTS * truth_specimens)]:      # model's K, then fresh
        if not (d / f"s{k}.nc").exists():
            main(["case", "assemble", str(d / "BPM.nc"), "--case", str(k), "--rig", "biaxial", "--width-m", "0.12",
                  "--height-m", "0.24", "--config", str(d / "config.yaml"), "--out", str(d / f"s{k}.nc"), "--quiet"])


def conditions(folder, j):
    path = folder / f"t{j}.yaml"
    path.write_text(yaml.safe_dump(dict(
        source="planted", rig="triaxial", confining_pressure_kPa=P[j], deviator_min_kPa=10.0,
        deviator_max_kPa=50.0, frequency_Hz=F[j], covariates={"VCI": {"value": VCI[j], "units": "%"}},
        curves=[dict(file=f"t{j}.dat", quantity="axial_strain", units="1", sign="compression_positive")])))
    return path


def planted_curve(d, name, j, cond, specimens):
    """The truth: the mean of ``specimens`` under the effect (failed: censored)."""
    from concurrent.futures import ProcessPoolExecutor
    p = BiaxialParams.from_config(load_config(d / "config.yaml")["rig"])
    p.take_conditions(load_conditions(cond))
    jobs = [dict(specimen=str(s), values=BASE, cycles=CYCLES, rig=p.to_dict(),
                 effect=None if name == "none" else name, effect_values=TRUTH[name], metrics=None,
                 conditions=str(cond), out=str(d / "planted" / name / f"t{j}_{Path(s).stem}.nc")) for s in specimens]
    with ProcessPoolExecutor(2) as pool:
        outs = list(pool.map(run_case, jobs))
    return np.mean([case_curve(o, "axial_strain", CYCLES)[0] for o in outs], axis=0)


def scenario(d, name, truth_specimens, from_model, seed=0):
    folder = d / name
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir()
    (d / "cache").mkdir(exist_ok=True)
    rng = np.random.default_rng(seed)
    for j in range(TESTS):
        cond = conditions(folder, j)
        fresh = [d / f"s{100 + j * truth_specimens + m}.nc" for m in range(truth_specimens)]
        curve = planted_curve(d, name, j, cond, [d / f"s{k}.nc" for k in range(K)] if from_model else fresh)
        m = int(rng.integers(11, 20))
        n = np.sort(np.exp(rng.uniform(0, math.log(CYCLES), m)))
        v = np.interp(np.log(n), np.log(np.arange(1, CYCLES + 1)), curve)
        v += rng.normal(0, 0.01 * abs(curve[-1]) + 1e-6, m)
        (folder / f"t{j}.dat").write_text("".join(f"{a!r}, {b!r}\n" for a, b in zip(n.tolist(), v.tolist())))
        import_test(cond, folder / f"t{j}.nc")
    out = folder / "loop"
    out.mkdir()
    (out / "cases").symlink_to(d / "cache")
    main(["loop", *[str(folder / f"t{j}.nc") for j in range(TESTS)], "--conditions",
          *[str(folder / f"t{j}.yaml") for j in range(TESTS)], "--specimens", *[str(d / f"s{k}.nc") for k in range(K)],
          "--parameters", str(d / "base.yaml"), "--out-dir", str(out), "--jobs", "2", "--config",
          str(d / "config.yaml"), "--quiet"])
    chosen = yaml.safe_load((out / "chosen.yaml").read_text())["effect"]
    with xr.open_dataset(out / "loop.nc") as ds:
        cands = json.loads(ds.attrs["candidates_json"])
        plain = float(np.sqrt(np.mean((ds["measured"].values - ds["plain_prediction"].values) ** 2)))
    evidence = ", ".join(f"{c['effect']}: gain {c['gain']:.3g}, {c['wins']}/{c['tests']} better, p {c['p']:.2g}, "
                         f"held-out RMSE {c['held_out_rmse']:.2e}" for c in cands)
    print(f"planted {name:13s} -> chosen {chosen:13s} | plain RMSE {plain:.2e} | {evidence}", flush=True)


def parse():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("scenarios", nargs="*", default=list(TRUTH))
    ap.add_argument("--truth-specimens", type=int, default=1)
    ap.add_argument("--truth-from-model", action="store_true")
    ap.add_argument("--specimen-share", type=float, default=1.0, help="loop.specimen_share (0 with "
                    "--truth-from-model: the data are the model's own specimens)")
    return ap.parse_args()


if __name__ == "__main__":
    args = parse()
    args.out.mkdir(parents=True, exist_ok=True)
    setup(args.out, args.truth_specimens, args.specimen_share)
    for s in args.scenarios:
        scenario(args.out, s, args.truth_specimens, args.truth_from_model)
