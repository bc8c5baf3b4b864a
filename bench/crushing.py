"""Single-stone crushing of a library's stones, bonded then rigid, and the Weibull laws
fitted to each (rig/crushing.py): the rigid stones' strength calibrated against the bonded
stones'.

    NUMBA_NUM_THREADS=1 python bench/crushing.py results/bpm/box_test.nc --stones 60 \
        [--F-str-co 3.5] [--d0 0.04] [--seed 1] [--out crushing.csv]

The bonded stones are crushed first; their fit (sigma0, m at d0) is the rigid stones'
Weibull; the same stones, turned alike, are then crushed rigid and fitted again. Prints one
line per stone and model, both fits with the 90 % interval of m, a two-sample KS test of
the size-corrected strengths sigma_f (d/d0)^(2/m_bonded), and the core-seconds of each
model. Never a test."""
import argparse
import csv
import os
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

from scipy import stats  # noqa: E402

from ballaststudy.rig.crushing import CrushingParams, crush, weibull_fit  # noqa: E402
from ballaststudy.rig.library import load_library  # noqa: E402


def crush_all(lib, stones, model, params, seed, splitting=None):
    out, t0 = [], time.process_time()
    for k in stones:
        c = crush(lib, k, model, params, seed=seed, splitting=splitting)
        out.append(c)
        print(f"  {model:6s} stone {k:3d} ({lib.ball_count(k):3d} balls): d {c.diameter * 1e3:.1f} mm, "
              f"F {c.force:.4g} N, sigma_f {c.stress:.4g} Pa, {'failed' if c.failed else 'CENSORED'}, "
              f"{c.steps} steps", flush=True)
    return out, time.process_time() - t0


def report(name, out, d0, seconds):
    fit = weibull_fit([c.stress for c in out], [c.diameter for c in out], [c.failed for c in out], d0)
    print(f"{name}: sigma0 {fit['sigma0']:.4g} Pa at d0 {d0} m, m {fit['m']:.3f} "
          f"[{fit['m_low']:.3f}, {fit['m_high']:.3f}] (90 %), {fit['n_failed']}/{fit['n']} failed, "
          f"{seconds:.1f} core-s", flush=True)
    return fit


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("library")
    ap.add_argument("--stones", type=int, default=60)
    ap.add_argument("--F-str-co", type=float, default=3.5)
    ap.add_argument("--d0", type=float, default=0.04)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--out")
    a = ap.parse_args(argv)
    lib = load_library(a.library)
    stones = range(min(a.stones, len(lib)))
    params = CrushingParams(F_str_co=a.F_str_co)
    print(f"{a.library}: {len(stones)} of {len(lib)} stones, F_str_co {a.F_str_co}, "
          f"platens {params.platen_speed_m_s} m/s each, seed {a.seed}")
    bonded, tb = crush_all(lib, stones, "bonded", params, a.seed)
    fb = report("bonded", bonded, a.d0, tb)
    rigid, tr = crush_all(lib, stones, "rigid", params, a.seed,
                          dict(sigma0=fb["sigma0"], m=fb["m"], d0=a.d0))
    fr = report("rigid", rigid, a.d0, tr)
    size = lambda out: [c.stress * (c.diameter / a.d0) ** (2 / fb["m"]) for c in out if c.failed]  # noqa: E731
    ks = stats.ks_2samp(size(bonded), size(rigid))
    print(f"size-corrected strengths, bonded vs rigid: KS D {ks.statistic:.3f}, p {ks.pvalue:.3g}; "
          f"rigid m within the bonded interval: {fb['m_low'] <= fr['m'] <= fb['m_high']}; "
          f"core-s bonded/rigid {tb / max(tr, 1e-9):.1f}")
    if a.out:
        with open(a.out, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["model", "stone", "diameter_m", "force_N", "stress_Pa", "failed", "steps"])
            for name, out in (("bonded", bonded), ("rigid", rigid)):
                for c in out:
                    w.writerow([name, c.stone, c.diameter, c.force, c.stress, int(c.failed), c.steps])


if __name__ == "__main__":
    main()
