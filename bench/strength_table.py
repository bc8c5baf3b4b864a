"""phi_peak of the biaxial specimen against rolling friction mu_r and contact friction mu.

    NUMBA_NUM_THREADS=1 python bench/strength_table.py [--seeds 1 2] [--p 30]
        [--mu-r 0 0.1 0.3] [--mu 0.5 0.7 0.9] [--width 0.15 --height 0.30]
        [--library BPM.nc] [--config config/config.yaml] [--strain 0.10]
        [--inertial-number 1e-3 1e-4] [--load-control applied_force servo]

Each seed's specimen is assembled once with the law's rolling sub-model at mu_r = 0 (the
law without rolling, tests/dem/test_rolling.py), then every (mu_r, mu) is set on it by the
modifiers (common random numbers: the rows differ by the values only) and the strength
test (rig/biaxial/strength.py, the config's strength section) runs at p, at each
--inertial-number (default the config's: is the strength rate-independent there?). Prints
one row per (I, mu_r, mu): phi_peak per seed, mean, q_peak, dilatancy angle, and how far the
sides let sigma_3 stray from p (its largest |sigma_3 - p| / p after seating, on the
curve's means over 0.002 axial strain). Uses box_test's library at the
config's resolution (bench/case_benchmark.py builds and caches it). Never a test."""
import argparse
import itertools
import os
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--p", type=float, default=30.0, help="confining pressure [kPa]")
    ap.add_argument("--mu-r", type=float, nargs="+", default=[0.0, 0.1, 0.3])
    ap.add_argument("--mu", type=float, nargs="+", default=[0.5, 0.7, 0.9])
    ap.add_argument("--width", type=float, default=0.15)
    ap.add_argument("--height", type=float, default=0.30)
    ap.add_argument("--strain", type=float, help="axial_strain_max (config's strength section)")
    ap.add_argument("--library", help="a BPM.nc (default: box_test's, built once)")
    ap.add_argument("--inertial-number", type=float, nargs="+", help="(config's strength one)")
    ap.add_argument("--load-control", nargs="+", choices=["applied_force", "servo"],
                    help="the sides' p while compressing (default: the config's)")
    ap.add_argument("--config", default="config/config.yaml")
    a = ap.parse_args(argv)
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from case_benchmark import box_test_library

    import numpy as np

    from ballaststudy.config import load_config
    from ballaststudy.rig.biaxial import BiaxialRig, assemble_biaxial
    from ballaststudy.rig.biaxial.strength import run_strength
    from ballaststudy.rig.kinds import params_from_config
    from ballaststudy.rig.library import load_library
    from ballaststudy.scenario.modifiers import MODIFIERS
    cfg = load_config(a.config)
    st = cfg["strength"]
    params = params_from_config("biaxial", cfg.get("rig", {}))
    params.width_m, params.height_m = a.width, a.height
    params.rolling_resistance, params.rolling_friction = "epsd", 0.0
    lib = load_library(a.library or box_test_library(a.config))
    folder = Path(tempfile.mkdtemp())
    for seed in a.seeds:
        t = time.perf_counter()
        assemble_biaxial(lib, params, seed=seed).save(folder / f"s{seed}.nc")
        print(f"seed {seed}: assembled in {time.perf_counter() - t:.0f} s", flush=True)
    print(f"p = {a.p:g} kPa, {a.width:g} x {a.height:g} m")
    print("| sides | I | mu_r | mu | phi_peak per seed [deg] | phi_peak mean | q_peak mean [kPa] | psi mean [deg] "
          "| sigma_3 error max | s per test |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    controls = a.load_control or [params.load_control]
    for control, inertial, mu_r, mu in itertools.product(controls, a.inertial_number or [st["inertial_number"]],
                                                         a.mu_r, a.mu):
        res, t = [], time.perf_counter()
        for seed in a.seeds:
            rig = BiaxialRig.load(folder / f"s{seed}.nc")
            rig.params = params_from_config("biaxial", cfg.get("rig", {}))
            rig.params.load_control = control
            MODIFIERS["mu_r"].apply(rig, {"mu_r": mu_r})
            MODIFIERS["mu"].apply(rig, {"mu": mu})
            res.append(run_strength(rig, a.p, inertial, a.strain or st["axial_strain_max"],
                                    st["side_servo_gain_m_s_per_kPa"], st["side_servo_integral_steps"]))
        phi = [r.phi_peak_deg for r in res]
        stray = max(float(np.max(np.abs(r.confining[r.axial_strain >= r.seating_strain] / (a.p * 1e3) - 1.0)))
                    for r in res)
        print(f"| {control} | {inertial:g} | {mu_r:g} | {mu:g} | {', '.join(f'{v:.1f}' for v in phi)} | {np.mean(phi):.1f} | "
              f"{np.mean([r.q_peak for r in res]) / 1e3:.0f} | "
              f"{np.mean([r.dilatancy_angle_deg for r in res]):.1f} | {stray:.3f} | "
              f"{(time.perf_counter() - t) / len(res):.0f} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
