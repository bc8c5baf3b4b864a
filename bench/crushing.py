"""Single-stone crushing of a library's stones, bonded then rigid, and the Weibull laws
fitted to each (rig/crushing.py): the rigid stones' strength calibrated against the bonded
stones'.

    NUMBA_NUM_THREADS=1 python bench/crushing.py results/bpm/box_test.nc --stones 60 \
        [--F-str-co 3.5] [--d0 0.04] [--seed 1] [--criterion deviator] [--out crushing.csv]

Strengths are in the stress of the splitting criterion named (dem/crushing.py CRITERIA;
default largest_contact_force). The bonded stones are crushed first; their fit (sigma0, m at d0), one per stone material
(Table 4.2's hard and soft joints), is the rigid stones' Weibull; the same stones, turned
alike, are then crushed rigid and fitted again. Prints one line per stone and model, the
fits per model and material with the 90 % interval of m, per material a two-sample KS test
of the size-corrected strengths sigma_f (d/d0)^(2/m_bonded), and the core-seconds of each
model. Never a test."""
import argparse
import csv
import os
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

from scipy import stats  # noqa: E402

from ballaststudy.dem.crushing import CRITERIA  # noqa: E402
from ballaststudy.dem.materials import MATERIAL_NAMES, STONE_MATERIALS  # noqa: E402
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


def report(name, out, d0, seconds, materials):
    """{material: fit} of the crushes ``out`` (``materials``: each stone's)."""
    fits = {}
    for mat in sorted(set(materials.values())):
        sel = [c for c in out if materials[c.stone] == mat]
        fit = weibull_fit([c.stress for c in sel], [c.diameter for c in sel], [c.failed for c in sel], d0)
        print(f"{name} {MATERIAL_NAMES[mat]}: sigma0 {fit['sigma0']:.4g} Pa at d0 {d0} m, m {fit['m']:.3f} "
              f"[{fit['m_low']:.3f}, {fit['m_high']:.3f}] (90 %), {fit['n_failed']}/{fit['n']} failed",
              flush=True)
        fits[mat] = fit
    print(f"{name}: {seconds:.1f} core-s", flush=True)
    return fits


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("library")
    ap.add_argument("--stones", type=int, default=60)
    ap.add_argument("--F-str-co", type=float, default=3.5)
    ap.add_argument("--d0", type=float, default=0.04)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--criterion", choices=CRITERIA, default=CRITERIA[0])
    ap.add_argument("--out")
    a = ap.parse_args(argv)
    lib = load_library(a.library)
    stones = range(min(a.stones, len(lib)))
    params = CrushingParams(F_str_co=a.F_str_co, criterion=a.criterion)
    print(f"{a.library}: {len(stones)} of {len(lib)} stones, criterion {a.criterion}, F_str_co {a.F_str_co}, "
          f"platens {params.platen_speed_m_s} m/s each, seed {a.seed}")
    materials = {k: lib.stone(k).material for k in stones}
    bonded, tb = crush_all(lib, stones, "bonded", params, a.seed)
    fb = report("bonded", bonded, a.d0, tb, materials)
    law = [fb.get(mat, fb[min(fb)]) for mat in STONE_MATERIALS]     # a material not drawn: the other's
    rigid, tr = crush_all(lib, stones, "rigid", params, a.seed,
                          dict(sigma0=[f["sigma0"] for f in law], m=[f["m"] for f in law], d0=a.d0))
    fr = report("rigid", rigid, a.d0, tr, materials)
    for mat, f in fb.items():
        size = lambda out: [c.stress * (c.diameter / a.d0) ** (2 / f["m"]) for c in out  # noqa: E731
                            if c.failed and materials[c.stone] == mat]
        ks = stats.ks_2samp(size(bonded), size(rigid))
        print(f"{MATERIAL_NAMES[mat]}: size-corrected strengths, bonded vs rigid: KS D {ks.statistic:.3f}, "
              f"p {ks.pvalue:.3g}; rigid m within the bonded interval: {f['m_low'] <= fr[mat]['m'] <= f['m_high']}")
    print(f"core-s bonded/rigid {tb / max(tr, 1e-9):.1f}")
    if a.out:
        with open(a.out, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["model", "stone", "material", "criterion", "diameter_m", "force_N", "stress_Pa",
                        "failed", "steps"])
            for name, out in (("bonded", bonded), ("rigid", rigid)):
                for c in out:
                    w.writerow([name, c.stone, MATERIAL_NAMES[materials[c.stone]], a.criterion, c.diameter,
                                c.force, c.stress, int(c.failed), c.steps])


if __name__ == "__main__":
    main()
