"""The long-term horizon's extrapolation error, measured on synthetic long runs (issue 14):
K biaxial cases run N_long cycles; each accumulation law (loop/accumulation.py: Sato's
hardening form, and the log and power laws for reference) is fitted to the ensemble over
N <= N_fit only, as the loop fits the DEM horizon, and its prediction at N_long compared
with the ensemble's own value there. Prints one line per law and N_fit.

    python bench/loop_extrapolation.py OUT_DIR [--cases 3] [--long 200] [--fit 12 25 50]
        [--size 0.12 0.24]

The specimens are the tests' tiny synthetic ones by default (24 stones, 0.12 x 0.24 m,
p = 60 kPa, q 10-60 kPa), a measurement of how far a law carries, not of ballast."""
import argparse
from pathlib import Path

import numpy as np
import yaml

from ballaststudy.calibration.runner import case_curve, run_case
from ballaststudy.cli import main
from ballaststudy.config import load_config
from ballaststudy.loop.accumulation import fit_ensemble, predict
from ballaststudy.measured.importer import load_conditions
from ballaststudy.rig.biaxial import BiaxialParams

ROOT = Path(__file__).resolve().parents[1]


def ensemble(d, cases, cycles, size):
    from ballaststudy.rig.library import synthetic_library
    synthetic_library(24, size=(0.035, 0.065), r0=0.008, seed=3, database="tiny").to_netcdf(d / "BPM.nc")
    cfg = yaml.safe_load((ROOT / "config/config.yaml").read_text())
    cfg["databases_file"] = str(ROOT / cfg["databases_file"])
    cfg["rig"]["biaxial"]["loading"].update(consolidation_window_steps=1000, checkpoint_every=1000)
    (d / "config.yaml").write_text(yaml.safe_dump(cfg))
    (d / "t.yaml").write_text(yaml.safe_dump(dict(
        source="synthetic", rig="triaxial", confining_pressure_kPa=60.0, deviator_min_kPa=10.0,
        deviator_max_kPa=60.0, curves=[dict(file="t.dat", quantity="axial_strain", units="1",
                                            sign="compression_positive")])))
    p = BiaxialParams.from_config(load_config(d / "config.yaml")["rig"])
    p.take_conditions(load_conditions(d / "t.yaml"))
    curves = []
    for k in range(cases):
        spec = d / f"s{k}.nc"
        if not spec.exists():
            main(["case", "assemble", str(d / "BPM.nc"), "--case", str(k), "--rig", "biaxial", "--width-m",
                  str(size[0]), "--height-m", str(size[1]), "--config", str(d / "config.yaml"), "--out", str(spec),
                  "--quiet"])
        out = d / f"case{k}.nc"
        run_case(dict(specimen=str(spec), values={}, cycles=cycles, rig=p.to_dict(), effect=None,
                      effect_values={}, metrics=None, conditions=str(d / "t.yaml"), out=str(out)))
        curves.append(case_curve(out, "axial_strain", cycles)[0])
    return np.array(curves)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("--cases", type=int, default=3)
    ap.add_argument("--long", type=int, default=200)
    ap.add_argument("--fit", type=int, nargs="+", default=[12, 25, 50])
    ap.add_argument("--size", type=float, nargs=2, default=[0.12, 0.24])
    a = ap.parse_args()
    a.out.mkdir(parents=True, exist_ok=True)
    curves = ensemble(a.out, a.cases, a.long, a.size)
    n = np.arange(1, a.long + 1, dtype=float)
    truth = curves.mean(axis=0)[-1]
    print(f"{a.cases} cases x {a.long} cycles: ensemble mean axial strain at N = {a.long}: {truth:.5f} "
          f"(at N = {a.fit[0]}: {curves.mean(axis=0)[a.fit[0] - 1]:.5f})")
    for n_fit in a.fit:
        for law in ("sato", "log", "power"):
            try:
                fit = fit_ensemble(law, n[:n_fit], curves[:, :n_fit])
                pred, sd = predict(fit, np.array([float(a.long)]))
                print(f"fit N <= {n_fit:4d}  {law:5s}: predicted {pred[0]:.5f} +- {sd[0]:.5f}, "
                      f"error {(pred[0] - truth) / truth:+.1%}")
            except (RuntimeError, ValueError) as err:
                print(f"fit N <= {n_fit:4d}  {law:5s}: no fit ({err})")
